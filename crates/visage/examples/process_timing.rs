//! The library's per-frame cost, frame in to results out: a clip's frames decoded first, then
//! `Reconstructor::process` on each, timed; prints the median and the mean in milliseconds.
//! The Python package's overhead is measured against it (`python/benchmarks/overhead.py`).
//!
//! ```sh
//! cargo run --release -p visage --example process_timing -- INPUT [MODELS] [PASSES]
//! ```

use std::path::PathBuf;
use std::time::Instant;

use visage::{Input, Reconstructor};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1);
    let Some(input) = args.next().map(PathBuf::from) else {
        return Err("usage: process_timing INPUT [MODELS] [PASSES]".into());
    };
    let models = args.next().map(PathBuf::from);
    let passes: usize = match args.next() {
        Some(p) => p.to_string_lossy().parse()?,
        None => 3,
    };
    let input = Input::open(&input)?;
    let builder = || {
        let b = Reconstructor::builder().latency(0);
        match &models {
            Some(dir) => b.models_dir(dir),
            None => b,
        }
    };
    let (width, height) = input.size();
    let frames = input.collect::<Result<Vec<_>, _>>()?;
    let mut ms = Vec::new();
    for _ in 0..passes {
        // A fresh reconstructor per pass: each pass is the clip from its start.
        let mut reconstructor = builder().build(width, height)?;
        for frame in &frames {
            let start = Instant::now();
            let result = reconstructor.process(frame)?;
            std::hint::black_box(result.mesh());
            ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let mean = ms.iter().sum::<f64>() / ms.len() as f64;
    ms.sort_by(f64::total_cmp);
    println!(
        "{} frames × {passes}: median {:.3} ms, mean {:.3} ms per frame",
        frames.len(),
        ms[ms.len() / 2],
        mean
    );
    Ok(())
}
