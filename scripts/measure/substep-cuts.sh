#!/usr/bin/env bash
# What cuts a landing pile's step into sub-steps (docs/performance.md, the section of that name).
# Applies substep-cuts.patch (an instrumentation of integrate::choose_substep and an example
# running the peers' landing pile of 100 blobs, 80 steps) to HEAD in a temporary worktree,
# builds it in target/substep-cuts, and summarises steps 60-80 with substep-cuts.py. With
# FAR=1 every leaf pair is searched to its exact distance (no cutoff), for comparison.
# Written at bd1effb, refreshed at fe4e877 (FAR also searches the pairs the hulls set apart, which
# the narrow phase no longer sends to the search); a patch that no longer applies fails here
# rather than measure wrong code.
# Not part of CI: a few minutes for the build, under a second for the run.
set -euo pipefail
source "$(dirname "$0")/revs.sh"
build_patched substep-cuts HEAD
CUTS=1 TOL=1e-7 "$bin" 100 80 2>"$work/cuts.txt"
python3 "$here/substep-cuts.py" "$work/cuts.txt"
