#!/usr/bin/env bash
# Light scenes on one and two threads, with every step on the pool and with light steps on the
# caller's thread (docs/performance.md, "Light steps on the caller's thread").
# Copies light_steps.rs into a temporary worktree of REV (default HEAD), builds it in
# target/light-steps/<rev> and runs it: a markdown table of each scene's work a step and its
# step times (medians of ROUNDS rounds, default 9).
# Not part of CI: a few minutes for the build, about two minutes for the runs.
#
#   scripts/measure/light-steps.sh [REV]
set -euo pipefail
source "$(dirname "$0")/revs.sh"
build_at_revs light_steps "${1:-HEAD}"
"${bins[0]#*:}"
