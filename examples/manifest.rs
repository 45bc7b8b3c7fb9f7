//! Writes `docs/manifest.ron`: the engine (golden determinism hash) and the inputs the
//! committed reports were generated from (see `tests/common/manifest.rs`). Run last by
//! `scripts/regenerate-docs.sh`, after every report is regenerated.
//!
//! Run: `cargo run --release --example manifest`.

#[path = "../tests/common/manifest.rs"]
mod manifest;

use std::path::Path;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let current = manifest::current(root);
    let text = ron::ser::to_string_pretty(&current, ron::ser::PrettyConfig::default()).expect("serialize the manifest");
    let header = "// Written by `cargo run --release --example manifest` (last step of scripts/regenerate-docs.sh).\n\
                  // tests/manifest.rs checks it against the working tree: regenerate the reports when it fails.\n";
    std::fs::write(root.join("docs/manifest.ron"), format!("{header}{text}\n")).expect("write docs/manifest.ron");
    eprintln!("wrote docs/manifest.ron ({} inputs)", current.inputs.len());
}
