#!/usr/bin/env bash
# Regenerates every committed report and picture that depends on the engine, one command after
# the other (never two heavy jobs at once on a 2-core machine), and prints each one's time.
# About 5 minutes on 2 cores (plus the viewer screenshot's build). Not part of `cargo test` or .ci/run.
#
#   docs/accuracy.md, accuracy.csv, img/accuracy.png   cargo run --release --example work_precision
#   docs/stability.md                                  cargo run --release --example stability_report
#   docs/img/fig8-*, fig10-*, fig11-*, fig12-frames/   cargo run --release --example figures
#   docs/performance.md (generated part)               cargo run --release --example performance_report
#   docs/performance.md (peers part), comparison.md,
#   docs/img/peers-*.png                               cargo run --release -p peers
#   docs/img/viewer.png                                scripts/viewer-screenshot.sh (installs Xvfb)
#   docs/manifest.ron                                  cargo run --release --example manifest (last)
#
# The list lives in tests/common/manifest.rs; tests/manifest.rs (in CI) fails when the engine's
# golden hash or an input of these reports changed since docs/manifest.ron was written.
#
# The hand-written paragraphs of docs/performance.md (optimisation log, the solver's
# before/after) quote numbers from these runs and must be updated by hand.
#
# Usage: scripts/regenerate-docs.sh [--no-viewer]
set -euo pipefail
cd "$(dirname "$0")/.."

run() {
    local started=$SECONDS
    echo "== $*" >&2
    "$@"
    echo "== $* took $((SECONDS - started)) s" >&2
}

run cargo run --release --example work_precision > /dev/null
run cargo run --release --example stability_report > /dev/null
run cargo run --release --example figures
run cargo run --release --example performance_report > /dev/null
run cargo run --release -p peers > /dev/null
if [ "${1:-}" != "--no-viewer" ]; then
    run scripts/viewer-screenshot.sh
fi
run cargo run --release --example manifest
git status --short docs
