#!/usr/bin/env bash
# Where a landing pile's narrow phase goes, by class of query and of leaf pair (docs/performance.md,
# "Where the landing pile's narrow phase goes"). Applies leaf-classes.patch (tallies of the
# narrow phase's queries and leaf pairs, timed by the time-stamp counter, and an example that
# runs the peers' landing pile) to REV (default HEAD) in a temporary worktree, builds it in
# target/leaf-classes, and prints steps 61-80 of the piles of SIZES blobs (default "100 500") on
# one thread, ROUNDS times (default 1). x86-64 only (rdtsc). The tallies' own time (two counter
# reads a leaf pair) is in the narrow phase's. Written at 35dbe32; a patch that no longer applies
# fails here rather than measure wrong code. Not part of CI: a few minutes for the build.
#
#   scripts/measure/leaf-classes.sh [REV]
set -euo pipefail
root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
here="$root/scripts/measure"
work=$(mktemp -d)
trap 'git -C "$root" worktree remove --force "$work/tree" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
git -C "$root" worktree add --detach "$work/tree" "${1:-HEAD}" >/dev/null
cd "$work/tree"
git apply "$here/leaf-classes.patch"
CARGO_TARGET_DIR="$root/target/leaf-classes" cargo build --release --example leaf_classes
for round in $(seq 1 "${ROUNDS:-1}"); do
    for size in ${SIZES:-100 500}; do
        N=$size STEPS=80 FROM=60 "$root/target/leaf-classes/release/examples/leaf_classes"
    done
done
