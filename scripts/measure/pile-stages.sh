#!/usr/bin/env bash
# The stage times of the peers' landing pile of blobs at several commits side by side
# (docs/performance.md, "Cells set aside by the slab of a seeded search's minimum").
# Copies pile_stages.rs into a temporary worktree of each REV (default: HEAD~1 and HEAD),
# builds it in target/pile-stages/<rev>, then runs steps 61–80 of the piles of 100 and 500
# blobs (built from the start) on one and two threads, ROUNDS times (default 3) with the builds
# alternating, printing each run's mean step, counters, stage times (ms a step) and state hash.
# With CALLGRIND=1 it instead counts the instructions a step of steps 61–70 of both piles on
# one thread (valgrind's callgrind). SIZES overrides the pile sizes ("100 500").
# Not part of CI: a few minutes for each build, a few minutes a round.
#
#   scripts/measure/pile-stages.sh [REV ...]
set -euo pipefail
root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
here="$root/scripts/measure"
revs=("$@")
[ ${#revs[@]} -gt 0 ] || revs=(HEAD~1 HEAD)
work=$(mktemp -d)
cleanup() {
    for tree in "$work"/tree-*; do git -C "$root" worktree remove --force "$tree" >/dev/null 2>&1 || true; done
    rm -rf "$work"
}
trap cleanup EXIT
bins=()
for rev in "${revs[@]}"; do
    commit=$(git -C "$root" rev-parse --short "$rev")
    tree="$work/tree-$commit"
    git -C "$root" worktree add --detach "$tree" "$commit" >/dev/null
    cp "$here/pile_stages.rs" "$tree/examples/pile_stages.rs"
    (cd "$tree" && CARGO_TARGET_DIR="$root/target/pile-stages/$commit" cargo build --release --example pile_stages)
    bins+=("$commit:$root/target/pile-stages/$commit/release/examples/pile_stages")
done
sizes=(${SIZES:-100 500})
if [ "${CALLGRIND:-0}" = 1 ]; then
    for size in "${sizes[@]}"; do
        for entry in "${bins[@]}"; do
            out="$work/callgrind.out"
            N=$size STEPS=70 FROM=60 valgrind --tool=callgrind --toggle-collect='*measure_steps*' \
                --callgrind-out-file="$out" "${entry#*:}" >/dev/null 2>&1
            total=$(callgrind_annotate "$out" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }')
            echo "pile $size, ${entry%%:*}: $(awk -v t="$total" 'BEGIN { printf "%.2f", t / 10 / 1e6 }') M instructions a step (steps 61-70)"
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
