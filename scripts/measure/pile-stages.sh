#!/usr/bin/env bash
# The stage times of the peers' landing pile of blobs at several commits side by side
# (docs/performance.md, "Cells set aside by the slab of a seeded search's minimum").
# Copies pile_stages.rs into a temporary worktree of each REV (default: HEAD~1 and HEAD),
# builds it in target/pile-stages/<rev>, then runs steps 61–80 of the piles of 100 and 500
# blobs (built from the start) on one and two threads, ROUNDS times (default 3) with the builds
# alternating, printing each run's mean step, counters, stage times (ms a step) and state hash.
# With CALLGRIND=1 it instead counts the instructions a step of steps 61–70 of both piles on
# one thread (valgrind's callgrind), keeping each profile as
# target/pile-stages/callgrind.pile-<size>.<commit> for `callgrind_annotate`. SIZES overrides the
# pile sizes ("100 500").
# Not part of CI: a few minutes for each build, a few minutes a round.
#
#   scripts/measure/pile-stages.sh [REV ...]
set -euo pipefail
revs=("$@")
[ ${#revs[@]} -gt 0 ] || revs=(HEAD~1 HEAD)
source "$(dirname "$0")/revs.sh"
build_at_revs pile_stages "${revs[@]}"
sizes=(${SIZES:-100 500})
if [ "${CALLGRIND:-0}" = 1 ]; then
    for size in "${sizes[@]}"; do
        for entry in "${bins[@]}"; do
            out="$kept/callgrind.pile-$size.${entry%%:*}"
            N=$size STEPS=70 FROM=60 valgrind --tool=callgrind --toggle-collect='*measure_steps*' \
                --callgrind-out-file="$out" "${entry#*:}" >/dev/null 2>&1
            echo "pile $size, ${entry%%:*}: $(instructions_per_step "$out" 10) M instructions a step (steps 61-70)"
        done
    done
    exit 0
fi
for round in $(seq 1 "${ROUNDS:-3}"); do
    for size in "${sizes[@]}"; do
        for entry in "${bins[@]}"; do
            for threads in 1 2; do
                echo "== round $round, ${entry%%:*}, $threads thread(s)"
                N=$size STEPS=80 FROM=60 THREADS=$threads "${entry#*:}"
            done
        done
    done
done
