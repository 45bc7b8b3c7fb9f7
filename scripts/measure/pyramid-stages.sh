#!/usr/bin/env bash
# The stage times of the peers' pyramid while it settles, at several commits side by side
# (docs/performance.md, "Two threads for the stages between the narrow phase and the solve").
# Copies pyramid_stages.rs into a temporary worktree of each REV (default: 1821cfc and HEAD),
# builds it in target/pyramid-stages/<rev>, then runs steps 61–80 of the base-40 pyramid on one
# and two threads, ROUNDS times (default 3) with the builds alternating, printing each run's
# step and stage times (ms a step). With CALLGRIND=1 it instead counts the instructions a step of
# steps 61–70 of the base-40 and base-20 pyramids on one thread (valgrind's callgrind).
# Not part of CI: a few minutes for each build, about a minute a round.
#
#   scripts/measure/pyramid-stages.sh [REV ...]
set -euo pipefail
revs=("$@")
[ ${#revs[@]} -gt 0 ] || revs=(1821cfc HEAD)
source "$(dirname "$0")/revs.sh"
build_at_revs pyramid_stages "${revs[@]}"
if [ "${CALLGRIND:-0}" = 1 ]; then
    for base in 40 20; do
        for entry in "${bins[@]}"; do
            out="$work/callgrind.out"
            BASE=$base STEPS=70 FROM=60 EVERY=10 valgrind --tool=callgrind --toggle-collect='*measure_steps*' \
                --callgrind-out-file="$out" "${entry#*:}" >/dev/null 2>&1
            echo "base $base, ${entry%%:*}: $(instructions_per_step "$out" 10) M instructions a step (steps 61-70)"
        done
    done
    exit 0
fi
for round in $(seq 1 "${ROUNDS:-3}"); do
    for entry in "${bins[@]}"; do
        for threads in 1 2; do
            echo "== round $round, ${entry%%:*}, $threads thread(s)"
            BASE=40 STEPS=80 FROM=60 EVERY=20 THREADS=$threads "${entry#*:}" | tail -2
        done
    done
done
