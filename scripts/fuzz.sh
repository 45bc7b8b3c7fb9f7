#!/usr/bin/env bash
# Fuzzes the scene loader and the step (fuzz/fuzz_targets/scene.rs: load → build → 20 steps →
# validate) with libFuzzer through cargo-fuzz, one job (the machine has 2 cores), seeded from
# assets/scenes. Installs cargo-fuzz if it is missing. The machine has only a stable toolchain:
# RUSTC_BOOTSTRAP lets it take cargo-fuzz's nightly flags, and the sanitizer is off (address
# sanitizing needs a nightly runtime); a panic, abort, timeout or leak of memory beyond
# -rss_limit_mb is still a crash. Not part of .ci/run.
# An input times out after TIMEOUT seconds (default 60) of its 20 steps. The instrumented build
# runs about 12 times slower than a release build: the slowest inputs found (a static body given
# spikes of metres and metre-wide bands, which bring every leaf pair of the bodies near it
# within their bands) take about 50 ms a step in release, 1 s for the 20 steps, and took 18–21 s
# in the fuzzer beside other work, so a 20 s limit stopped a run on a slow input, not a hang.
#
# The corpus (fuzz/corpus/$CORPUS, default `scene`; untracked) keeps every unit the runs found
# and grows slow: at 1,329 units, several of 20-30 s each under instrumentation, a 10 min run
# at ef029b9 spent all its time replaying it. CORPUS=<name> starts a corpus of that name from
# the seed scenes alone (or goes on with it).
#
#   scripts/fuzz.sh [SECONDS]      default 60; the issue's full run is 1800
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz
corpus=fuzz/corpus/${CORPUS:-scene}
mkdir -p "$corpus"
cp assets/scenes/*.ron "$corpus/"
cd fuzz
RUSTC_BOOTSTRAP=1 cargo fuzz run scene --sanitizer none --jobs 1 "../$corpus" -- \
    -max_total_time="$seconds" -timeout="${TIMEOUT:-60}" -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1
