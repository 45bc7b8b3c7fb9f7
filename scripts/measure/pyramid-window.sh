#!/usr/bin/env bash
# What the peers' pyramid of base 40 costs while it settles (docs/performance.md, "A pyramid of
# 40 levels in the peers' window"). Applies pyramid-window.patch (an example that builds the
# peers' pyramid through the public API and prints its counters every EVERY steps; a count of
# why pairs are not carried, CARRYDBG=1; the contacts deeper than the rest depth at each
# position correction, EXCESS=1; and a prototype of the nonsmooth nonlinear conjugate
# gradient momentum on the resting solve, NNCG=1, one thread only) to HEAD in a temporary
# worktree, builds it in target/pyramid-window and runs the cases of that section, one thread.
# Written at 6f4d3fa, whose code the section measured; it runs at 2b648f2 (the same code) unless
# REV names another commit, where a patch that no longer applies fails rather than measure
# wrong code (the contact solver's rows of 34806ed changed the lines the prototype touches).
# Not part of CI: a few minutes for the build, about a minute for the runs.
set -euo pipefail
source "$(dirname "$0")/revs.sh"
build_patched pyramid-window "${REV:-2b648f2}"
run() {
    echo "== $*"
    env "$@" "$bin"
}
run STEPS=100 EVERY=20 MOVERS=1
run STEPS=100 EVERY=20 CARRYDBG=1 2>&1 | grep -E '^==|^step' -B1 | grep -v '^--'
for posit in 4 6 8 12; do run STEPS=80 EVERY=20 POSIT=$posit | tail -1; done
run STEPS=200 EVERY=20 NNCG=1
run STEPS=200 EVERY=20 NNCG=1 TOL=1e-6
run STEPS=120 EVERY=20 GAP=0.005
run STEPS=300 EVERY=50 EXCESS=1 2>&1 | awk '/^excess/ { if (++n % 25 == 0) print; next } { print }'
