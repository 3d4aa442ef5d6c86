//! Every fuzz target on the stable toolchain: its committed seeds (`fuzz/seeds/TARGET/`), then
//! [`MUTANTS`] deterministic mutants of them, each under `catch_unwind`. A panic fails the test
//! naming the target and the mutant, and leaves the input in
//! `target/fuzz-replay/TARGET/mutant-N` to reproduce (`cargo +nightly fuzz run TARGET FILE`
//! in `fuzz/`). This is the short, fixed budget the test suite spends; `fuzz/run.sh` fuzzes
//! with coverage guidance for as long as one wants.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use visage_fuzz_targets::{mutation::mutant, TARGETS};

/// Mutants per target.
const MUTANTS: u64 = 20_000;

/// Longest mutant per target (bytes): as `fuzz/run.sh`'s `-max_len`.
fn max_len(target: &str) -> usize {
    match target {
        "exif" => 512,
        "intrinsics_json" | "rigid_transform_json" | "pc2" | "network_config" => 1024,
        "depth_png" | "tflite" | "image" => 8192,
        _ => 4096,
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn seeds(target: &str) -> Vec<Vec<u8>> {
    let dir = root().join("fuzz/seeds").join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().map(|f| std::fs::read(f).unwrap()).collect()
}

#[test]
fn every_target_survives_its_seeds_and_their_mutants() {
    let all_seeds: Vec<Vec<Vec<u8>>> = TARGETS.iter().map(|(name, _)| seeds(name)).collect();
    for ((name, _), seeds) in TARGETS.iter().zip(&all_seeds) {
        assert!(!seeds.is_empty(), "no seeds for {name}");
    }
    // Panics are caught and reported below, not printed as they happen.
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    for ((name, body), seeds) in TARGETS.into_iter().zip(&all_seeds) {
        let inputs = seeds
            .iter()
            .cloned()
            .enumerate()
            .map(|(i, s)| (format!("seed-{i}"), s))
            .chain((0..MUTANTS).map(|i| (format!("mutant-{i}"), mutant(seeds, i, max_len(name)))));
        for (label, input) in inputs {
            if catch_unwind(AssertUnwindSafe(|| body(&input))).is_err() {
                let dir = root().join("target/fuzz-replay").join(name);
                std::fs::create_dir_all(&dir).unwrap();
                std::fs::write(dir.join(&label), &input).unwrap();
                failures.push(format!("{name} {label} ({})", dir.join(&label).display()));
            }
        }
    }
    let _ = std::panic::take_hook();
    assert!(failures.is_empty(), "panics: {failures:#?}");
}
