//! The manifest of the generated reports, `docs/manifest.ron`: which command writes which
//! committed file, the engine they were generated with (the golden determinism hash, which
//! changes exactly when the dynamics change) and a hash of every input file (scenes and the
//! reporting code). `scripts/regenerate-docs.sh` rewrites it last (`cargo run --release
//! --example manifest`); `tests/manifest.rs` fails in CI when the engine or an input no longer
//! matches, so a stale report cannot land. Not a pixel comparison: timings differ run to run.
#![allow(dead_code)]

use std::path::Path;

use serde::{Deserialize, Serialize};

/// What `docs/manifest.ron` records.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The golden determinism hash (`assets/golden/determinism.ron`) at generation time.
    pub engine: u64,
    /// Every input file with its FNV-1a hash (hex), in path order.
    pub inputs: Vec<(String, String)>,
    /// Every generated file or directory with the command that writes it.
    pub outputs: Vec<(String, String)>,
}

/// The generated files and their commands (the table at the top of
/// `scripts/regenerate-docs.sh`).
pub const OUTPUTS: [(&str, &str); 16] = [
    ("docs/accuracy.md", "cargo run --release --example work_precision"),
    ("docs/accuracy.csv", "cargo run --release --example work_precision"),
    ("docs/img/accuracy.png", "cargo run --release --example work_precision"),
    ("docs/stability.md", "cargo run --release --example stability_report"),
    ("docs/img/fig12-frames", "cargo run --release --example figures"),
    ("docs/img/fig8-type3-type3-friction.png", "cargo run --release --example figures"),
    ("docs/performance.md", "cargo run --release --example performance_report; cargo run --release -p peers"),
    ("docs/comparison.md", "cargo run --release -p peers"),
    ("docs/img/peers-incline.png", "cargo run --release -p peers"),
    ("docs/img/peers-bowl.png", "cargo run --release -p peers"),
    ("docs/img/peers-ellipse.png", "cargo run --release -p peers"),
    ("docs/img/peers-slide.png", "cargo run --release -p peers"),
    ("docs/img/peers-bounce.png", "cargo run --release -p peers"),
    ("docs/img/peers-piles.png", "cargo run --release -p peers"),
    ("docs/img/viewer.png", "scripts/viewer-screenshot.sh"),
    ("docs/manifest.ron", "cargo run --release --example manifest"),
];

/// Files and directories (every file below, recursively) the reports are computed from,
/// besides the engine itself.
pub const INPUTS: [&str; 10] = [
    "assets/scenes",
    "assets/bench",
    "examples/work_precision",
    "examples/stability_report.rs",
    "examples/figures.rs",
    "examples/performance_report.rs",
    "examples/viewer.rs",
    "tests/common",
    "benches/peers/src",
    "scripts/regenerate-docs.sh",
];

/// The manifest of the working tree at `root` as it is now.
///
/// # Panics
/// If an input cannot be read (a missing input is a bug in [`INPUTS`]).
#[must_use]
pub fn current(root: &Path) -> Manifest {
    let golden = std::fs::read_to_string(root.join("assets/golden/determinism.ron")).expect("read the golden hash");
    let engine = golden
        .split(|c: char| !c.is_ascii_digit())
        .find(|s| !s.is_empty())
        .and_then(|s| s.parse().ok())
        .expect("a state_hash in assets/golden/determinism.ron");
    let mut files = Vec::new();
    for input in INPUTS {
        collect(root, &root.join(input), &mut files);
    }
    files.sort();
    let inputs = files
        .into_iter()
        .map(|path| {
            let bytes = std::fs::read(root.join(&path)).expect("read an input");
            (path, format!("{:016x}", fnv1a(&bytes)))
        })
        .collect();
    let outputs = OUTPUTS.iter().map(|&(path, command)| (path.to_owned(), command.to_owned())).collect();
    Manifest { engine, inputs, outputs }
}

/// Every file at or below `path`, relative to `root` with `/` separators.
fn collect(root: &Path, path: &Path, files: &mut Vec<String>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).expect("read an input directory") {
            collect(root, &entry.expect("a directory entry").path(), files);
        }
    } else {
        let relative = path.strip_prefix(root).expect("an input below the root");
        files.push(relative.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/"));
    }
}

/// FNV-1a, 64 bits: a fingerprint of a file's bytes (not for security).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, &byte| (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3))
}
