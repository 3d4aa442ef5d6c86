//! Seeds for the benchmark's random streams.

/// SplitMix64 (Steele et al. 2014): decorrelated seeds from consecutive integers.
pub fn mix_seed(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d1_049b_1331_11eb);
    z ^ (z >> 31)
}
