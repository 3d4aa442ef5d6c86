//! A streaming quantile over a fixed range: a histogram of [`BINS`] bins, so memory does not
//! grow with the clip.

/// Bins per histogram.
pub const BINS: usize = 200;

/// A streaming quantile over a fixed range.
#[derive(Clone, Debug)]
pub(crate) struct Histogram {
    lo: f64,
    hi: f64,
    counts: Vec<u32>,
    total: u32,
}

impl Histogram {
    pub(crate) fn new(lo: f64, hi: f64) -> Histogram {
        Histogram {
            lo,
            hi,
            counts: vec![0; BINS],
            total: 0,
        }
    }

    pub(crate) fn push(&mut self, v: f64) {
        let t = ((v - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0);
        let bin = ((t * BINS as f64) as usize).min(BINS - 1);
        self.counts[bin] += 1;
        self.total += 1;
    }

    /// Samples so far.
    pub(crate) fn total(&self) -> u32 {
        self.total
    }

    /// The value below which a fraction `q` of the samples lie (bin centre).
    pub(crate) fn quantile(&self, q: f64) -> f64 {
        let target = (q * self.total as f64).ceil().max(1.0) as u32;
        let mut seen = 0;
        for (bin, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= target {
                return self.lo + (bin as f64 + 0.5) / BINS as f64 * (self.hi - self.lo);
            }
        }
        self.hi
    }
}
