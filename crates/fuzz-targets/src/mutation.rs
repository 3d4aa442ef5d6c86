//! Deterministic mutations of seed files, for replaying the fuzz targets on the stable
//! toolchain: what libFuzzer's default mutators do, simplified — flip bits, set bytes to
//! boundary values, insert, delete, duplicate or shuffle a run of bytes, splice two seeds,
//! truncate, and overwrite a run with a number in text — driven by a small seeded generator
//! (SplitMix64), so that a failure is reproduced by its target and index alone.

/// SplitMix64: a fast, well-mixed 64-bit generator, fully determined by its seed.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// Byte values at the edges of integer types and of ASCII classes.
const INTERESTING: [u8; 12] = [
    0, 1, 0x7f, 0x80, 0xff, b'0', b'9', b'-', b'.', b'"', b'{', b'\n',
];

/// Numbers in text that parsers meet at their limits.
const NUMBERS: [&str; 10] = [
    "0",
    "-1",
    "4294967295",
    "18446744073709551616",
    "1e308",
    "-1e-308",
    "NaN",
    "inf",
    "65536",
    "2147483648",
];

/// The `index`-th mutant of `seeds` (each a file's bytes; at least one): a seed chosen and
/// changed by one to four mutations, at most `max_len` bytes long.
pub fn mutant(seeds: &[Vec<u8>], index: u64, max_len: usize) -> Vec<u8> {
    let mut rng = SplitMix64::new(index.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x5eed);
    let mut data = seeds[rng.below(seeds.len())].clone();
    for _ in 0..1 + rng.below(4) {
        mutate(&mut data, seeds, &mut rng);
    }
    data.truncate(max_len);
    data
}

fn mutate(data: &mut Vec<u8>, seeds: &[Vec<u8>], rng: &mut SplitMix64) {
    let len = data.len();
    match rng.below(9) {
        0 if len > 0 => {
            let i = rng.below(len);
            data[i] ^= 1 << rng.below(8);
        }
        1 if len > 0 => {
            let i = rng.below(len);
            data[i] = INTERESTING[rng.below(INTERESTING.len())];
        }
        2 => {
            let i = rng.below(len + 1);
            let n = 1 + rng.below(8);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
            data.splice(i..i, bytes);
        }
        3 if len > 0 => {
            let i = rng.below(len);
            let n = 1 + rng.below((len - i).min(16));
            data.drain(i..i + n);
        }
        4 if len > 0 => {
            let i = rng.below(len);
            let n = 1 + rng.below((len - i).min(32));
            let run = data[i..i + n].to_vec();
            let at = rng.below(len + 1);
            data.splice(at..at, run);
        }
        5 if len > 1 => {
            let i = rng.below(len);
            let j = rng.below(len);
            data.swap(i, j);
        }
        6 => {
            let other = &seeds[rng.below(seeds.len())];
            let at = rng.below(len + 1);
            let from = rng.below(other.len() + 1);
            data.truncate(at);
            data.extend_from_slice(&other[from..]);
        }
        7 if len > 0 => data.truncate(rng.below(len)),
        _ => {
            let number = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
            let i = rng.below(len + 1);
            let end = (i + rng.below(4)).min(len);
            data.splice(i..end, number.iter().copied());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutants_are_reproducible_and_bounded() {
        let seeds = vec![b"{\"frames\": []}".to_vec(), b"ply\n".to_vec()];
        for i in 0..1000 {
            let m = mutant(&seeds, i, 64);
            assert_eq!(m, mutant(&seeds, i, 64));
            assert!(m.len() <= 64);
        }
        let distinct: std::collections::HashSet<_> =
            (0..1000).map(|i| mutant(&seeds, i, 64)).collect();
        assert!(distinct.len() > 500, "{} distinct mutants", distinct.len());
    }
}
