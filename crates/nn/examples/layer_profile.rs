//! Where a network's time goes, layer by layer, against this CPU's roofline.
//!
//! `cargo run --release -p visage-nn --example layer_profile -- MODEL.tflite [RUNS]`
//!
//! Each compiled step is timed alone (median of RUNS runs, default 200, one thread) and printed
//! with its multiply-adds, the bytes it must move, its rate, and the time the roofline allows:
//! `max(MACs / peak, bytes / bandwidth)`, with the peak (FMA at the widest vectors the kernels
//! use here, AVX-512 or AVX2, registers only) and the
//! bandwidth (a copy within the L2 cache) measured here first. The last lines sum the steps per
//! kind of kernel.

use std::collections::BTreeMap;
use std::time::Instant;

use visage_nn::Network;

/// Independent accumulators: enough to cover the FMA latency on two pipes.
const CHAINS: usize = 12;

/// Multiply-adds per second with every value in registers, and the instruction set.
fn peak_macs_per_s() -> (f64, &'static str) {
    let reps = 20_000_000usize;
    let start = Instant::now();
    let (v, lanes, isa) = fma_loop(reps);
    let s = start.elapsed().as_secs_f64();
    std::hint::black_box(v);
    ((reps * CHAINS * lanes) as f64 / s, isa)
}

fn fma_loop(reps: usize) -> (f32, usize, &'static str) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU has AVX-512F (checked just above).
        return (unsafe { fma_loop_avx512(reps) }, 16, "AVX-512 FMA");
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return (unsafe { fma_loop_avx2(reps) }, 8, "AVX2 FMA");
    }
    (fma_chains(reps), 8, "scalar")
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn fma_loop_avx2(reps: usize) -> f32 {
    fma_chains(reps)
}

/// With explicit 512-bit vectors: the compiler keeps arrays of 16 lanes out of registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn fma_loop_avx512(reps: usize) -> f32 {
    use std::arch::x86_64::{_mm512_fmadd_ps, _mm512_reduce_add_ps, _mm512_set1_ps};
    let mut acc = [_mm512_set1_ps(1.0); CHAINS];
    let (a, b) = (
        _mm512_set1_ps(std::hint::black_box(0.999_f32)),
        _mm512_set1_ps(std::hint::black_box(1e-4_f32)),
    );
    for _ in 0..reps {
        for v in acc.iter_mut() {
            *v = _mm512_fmadd_ps(*v, a, b);
        }
    }
    acc.iter().map(|&v| _mm512_reduce_add_ps(v)).sum()
}

#[inline(always)]
fn fma_chains(reps: usize) -> f32 {
    let mut acc = [[1.0f32; 8]; CHAINS];
    let (a, b) = (
        std::hint::black_box(0.999_f32),
        std::hint::black_box(1e-4_f32),
    );
    for _ in 0..reps {
        for chain in acc.iter_mut() {
            for v in chain.iter_mut() {
                *v = v.mul_add(a, b);
            }
        }
    }
    acc.iter().flatten().sum()
}

/// Bytes per second (read + write) copying a buffer of `bytes` that stays in the L2 cache.
fn l2_bytes_per_s(bytes: usize) -> f64 {
    let n = bytes / 8;
    let src = vec![1.0f32; n];
    let mut dst = vec![0.0f32; n];
    let reps = 4000;
    let start = Instant::now();
    for r in 0..reps {
        dst.copy_from_slice(&src);
        dst[r % n] += 1.0;
        std::hint::black_box(&mut dst);
    }
    (2 * n * 4 * reps) as f64 / start.elapsed().as_secs_f64()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: layer_profile MODEL.tflite [RUNS]")?;
    let runs: usize = args.next().map(|r| r.parse()).transpose()?.unwrap_or(200);
    let bytes = std::fs::read(&path).map_err(|e| format!("{path}: {e}"))?;
    let mut net = Network::from_tflite(&bytes, &path)?;
    for (i, v) in net.input_mut().iter_mut().enumerate() {
        *v = ((i * 7919) % 256) as f32 / 255.0;
    }
    let (peak, isa) = peak_macs_per_s();
    let bandwidth = l2_bytes_per_s(256 << 10);
    println!(
        "{path}: peak {:.1} GMAC/s ({isa}, registers), L2 copy {:.1} GB/s; {runs} runs",
        peak / 1e9,
        bandwidth / 1e9
    );
    for _ in 0..20 {
        net.run();
    }
    let steps = net.profile(runs);
    println!(
        "{:>4} {:<22} {:<14} {:>9} {:>9} {:>8} {:>8} {:>6} {:>6}",
        "step", "kernel", "output", "MMAC", "KB", "µs", "bound µs", "GMAC/s", "×bound"
    );
    let mut kinds: BTreeMap<String, [f64; 3]> = BTreeMap::new();
    let (mut total, mut total_bound) = (0.0, 0.0);
    for (i, s) in steps.iter().enumerate() {
        let bound = (s.macs as f64 / peak).max(s.bytes as f64 / bandwidth) * 1e6;
        println!(
            "{i:>4} {:<22} {:<14} {:>9.3} {:>9.1} {:>8.1} {:>8.1} {:>6.1} {:>6.1}",
            s.op,
            s.output,
            s.macs as f64 / 1e6,
            s.bytes as f64 / 1e3,
            s.median_us,
            bound,
            s.macs as f64 / s.median_us / 1e3,
            s.median_us / bound.max(1e-3),
        );
        let kind = s.op.split(['+', ' ']).next().unwrap_or("").to_owned();
        let k = kinds.entry(kind).or_default();
        k[0] += s.median_us;
        k[1] += bound;
        k[2] += s.macs as f64;
        total += s.median_us;
        total_bound += bound;
    }
    println!("by kernel:");
    for (kind, [us, bound, macs]) in &kinds {
        println!(
            "  {kind:<16} {us:>8.1} µs ({:>4.1} %), bound {bound:>7.1} µs, {:>6.1} MMAC",
            100.0 * us / total,
            macs / 1e6
        );
    }
    println!("total {total:.1} µs (sum of steps alone), roofline {total_bound:.1} µs");
    Ok(())
}
