#!/usr/bin/env bash
# Where a landing pile's narrow phase goes, by class of query and of leaf pair (docs/performance.md,
# "Where a landing pile's narrow phase goes"). Applies leaf-classes.patch (tallies of the
# narrow phase's queries and leaf pairs, timed by the time-stamp counter, and an example that
# runs the peers' landing pile) to REV (default HEAD) in a temporary worktree, builds it in
# target/leaf-classes, and prints steps 61-80 of the piles of SIZES blobs (default "100 500") on
# one thread, ROUNDS times (default 1). x86-64 only (rdtsc). The tallies' own time (two counter
# reads a leaf pair) is in the narrow phase's. Written at 35dbe32, refreshed at fe4e877; a patch
# that no longer applies fails here rather than measure wrong code. Not part of CI: a few
# minutes for the build.
#
#   scripts/measure/leaf-classes.sh [REV]
set -euo pipefail
source "$(dirname "$0")/revs.sh"
build_patched leaf-classes "${1:-HEAD}"
for round in $(seq 1 "${ROUNDS:-1}"); do
    for size in ${SIZES:-100 500}; do
        N=$size STEPS=80 FROM=60 "$bin"
    done
done
