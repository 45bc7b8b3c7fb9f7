# Sourced by the scripts of scripts/measure: build_at_revs builds one measuring program at
# several commits side by side; build_patched builds an instrumentation patch's example.
#
# build_at_revs NAME REV...: copies scripts/measure/NAME.rs into examples/ of a temporary
# worktree of each REV and builds it there in target/<NAME with - for _>/<commit>; sets `work`
# (a temporary directory, removed with the worktrees on exit), `kept` (that target directory,
# for what a script keeps after it) and `bins` ("commit:path" for each REV).
build_at_revs() {
    local name=$1 root here commit tree
    shift
    root=$(git -C "$(dirname "${BASH_SOURCE[0]}")" rev-parse --show-toplevel)
    here="$root/scripts/measure"
    kept="$root/target/${name//_/-}"
    work=$(mktemp -d)
    trap 'for tree in "$work"/tree-*; do git -C "'"$root"'" worktree remove --force "$tree" >/dev/null 2>&1 || true; done; rm -rf "$work"' EXIT
    bins=()
    for rev in "$@"; do
        commit=$(git -C "$root" rev-parse --short "$rev")
        tree="$work/tree-$commit"
        git -C "$root" worktree add --detach "$tree" "$commit" >/dev/null
        cp "$here/$name.rs" "$tree/examples/$name.rs"
        (cd "$tree" && CARGO_TARGET_DIR="$kept/$commit" cargo build --release --example "$name")
        bins+=("$commit:$kept/$commit/release/examples/$name")
    done
}

# instructions_per_step FILE STEPS: callgrind's total in FILE over STEPS steps, in millions.
instructions_per_step() {
    local total
    total=$(callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }')
    awk -v t="$total" -v n="$2" 'BEGIN { printf "%.2f", t / n / 1e6 }'
}

# build_patched NAME REV: applies scripts/measure/NAME.patch (NAME with dashes) to a temporary
# worktree of REV and builds its example (NAME with underscores) there in target/NAME; sets
# `root`, `here` (this directory), `work` (a temporary directory, removed with the worktree on
# exit) and `bin` (the example). A patch that no longer applies fails here rather than measure
# wrong code.
build_patched() {
    local name=$1 rev=$2
    root=$(git -C "$(dirname "${BASH_SOURCE[0]}")" rev-parse --show-toplevel)
    here="$root/scripts/measure"
    work=$(mktemp -d)
    trap 'git -C "'"$root"'" worktree remove --force "$work/tree" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
    git -C "$root" worktree add --detach "$work/tree" "$rev" >/dev/null
    (cd "$work/tree" && git apply "$here/$name.patch" &&
        CARGO_TARGET_DIR="$root/target/$name" cargo build --release --example "${name//-/_}")
    bin="$root/target/$name/release/examples/${name//-/_}"
}
