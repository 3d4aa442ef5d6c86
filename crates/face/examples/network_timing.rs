//! Median time of one run of each face network on this machine, without criterion: the
//! attention face mesh, the plain landmark network and one iris network run, on a constant
//! input; then where the attention network's time goes (`Network::profile`, summed by kernel
//! and by part: the mesh backbone up to its 468 points, then the attention crops, heads and
//! mapping back). Models from `$VISAGE_MODELS` or `./models`; the kernels in use are printed
//! (`VISAGE_NO_AVX512=1` measures the AVX2 ones on an AVX-512 CPU).
//!
//! ```text
//! cargo run --release -p visage-face --example network_timing [-- RUNS]
//! ```

use std::collections::BTreeMap;
use std::time::Instant;

use visage_face::{models_dir, AttentionNetwork, IrisNetwork, LandmarkNetwork, ModelFile};

/// Median of `runs` timed calls of `f` after a few untimed ones, milliseconds.
fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    for _ in 0..runs.min(10) {
        f();
    }
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let runs: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 200,
    };
    let dir = models_dir();
    let mut attention = AttentionNetwork::load(&dir)?;
    let mut landmarks = LandmarkNetwork::load(&dir)?;
    let mut iris = IrisNetwork::load(&dir)?;
    attention.input_mut().fill(0.5);
    landmarks.input_mut().fill(0.5);
    iris.input_mut().fill(0.5);
    println!(
        "kernels: {}; median of {runs} runs, one thread",
        visage_nn::ops::kernels()
    );
    let a = median_ms(runs, || drop(attention.run()));
    let l = median_ms(runs, || drop(landmarks.run()));
    let i = median_ms(runs, || drop(iris.run()));
    println!("attention face mesh  {a:6.2} ms");
    println!("landmark network     {l:6.2} ms");
    println!("iris network (1 eye) {i:6.2} ms");

    // Where the attention network's time goes: each step alone, median over the runs.
    let bytes = ModelFile::FaceLandmarkWithAttention.read(&dir)?;
    let mut net = visage_nn::Network::from_tflite(&bytes, "attention")?;
    net.input_mut().fill(0.5);
    let profile = net.profile(runs.clamp(1, 50));
    let first_custom = profile
        .iter()
        .position(|p| p.op == "landmarks-to-matrix")
        .unwrap_or(profile.len());
    let part = |steps: &[visage_nn::StepProfile]| steps.iter().map(|p| p.median_us).sum::<f64>();
    let (backbone, heads) = (
        part(&profile[..first_custom]),
        part(&profile[first_custom..]),
    );
    println!(
        "profile: {:.2} ms in all: mesh backbone {:.2} ms ({} steps), attention crops, heads \
         and mapping {:.2} ms ({} steps)",
        (backbone + heads) / 1e3,
        backbone / 1e3,
        first_custom,
        heads / 1e3,
        profile.len() - first_custom
    );
    let mut by_kernel: BTreeMap<&str, (f64, usize)> = BTreeMap::new();
    for p in &profile {
        let e = by_kernel.entry(p.op.as_str()).or_default();
        e.0 += p.median_us;
        e.1 += 1;
    }
    let mut by_kernel: Vec<_> = by_kernel.into_iter().collect();
    by_kernel.sort_by(|a, b| b.1 .0.total_cmp(&a.1 .0));
    for (op, (us, n)) in by_kernel {
        println!("  {op:22} {n:4} steps {:8.1} µs", us);
    }
    Ok(())
}
