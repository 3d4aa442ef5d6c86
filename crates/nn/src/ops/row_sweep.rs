/// Where one depthwise 3×3 row sweep of the explicit vector kernels (AVX2, AVX-512) reads and
/// writes: input rows are `row` values apart, consecutive output columns read `step` values
/// apart; `x0` is the top-left tap of the first column at the first channel swept (the AVX2
/// kernel's block, the AVX-512 kernel's channel 0) and `y0` its output; `n` columns.
pub(super) struct Row3 {
    pub row: usize,
    pub step: usize,
    pub x0: usize,
    pub y0: usize,
    pub n: usize,
}
