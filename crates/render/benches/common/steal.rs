//! CPU time the hypervisor took from this machine ("steal", Linux's `/proc/stat`) while a
//! benchmark ran. On a shared virtual machine the renderer's frame time swings by tens of per
//! cent with the host's load; a benchmark that lost CPU time to steal says so next to its figure.

use criterion::{Bencher, Criterion};

/// All CPU ticks and stolen ticks since boot, summed over CPUs (`None` off Linux).
fn ticks() -> Option<(u64, u64)> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    // "cpu  user nice system idle iowait irq softirq steal guest guest_nice"
    let fields: Vec<u64> = stat
        .lines()
        .next()?
        .split_whitespace()
        .skip(1)
        .map(|f| f.parse().ok())
        .collect::<Option<_>>()?;
    // Guest time is already counted in user and nice time.
    let total = fields.iter().take(8).sum();
    Some((total, *fields.get(7)?))
}

/// A [`Criterion`] whose benchmarks each report the share of CPU time stolen while they ran.
pub struct Reporting<'a>(pub &'a mut Criterion);

impl Reporting<'_> {
    /// [`Criterion::bench_function`], then the steal report (standard error).
    pub fn bench_function(&mut self, id: &str, f: impl FnMut(&mut Bencher)) -> &mut Self {
        let before = ticks();
        self.0.bench_function(id, f);
        match before.zip(ticks()) {
            Some(((t0, s0), (t1, s1))) if t1 > t0 => eprintln!(
                "{id}: host CPU steal while it ran: {:.1}% of this machine's CPU time",
                100.0 * (s1 - s0) as f64 / (t1 - t0) as f64
            ),
            // Filtered out: it did not run.
            Some(_) => {}
            None => eprintln!("{id}: host CPU steal not available on this system"),
        }
        self
    }
}
