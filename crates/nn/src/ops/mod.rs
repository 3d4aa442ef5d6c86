//! Hand-written NHWC kernels for the engine's operator set (that of MediaPipe's face networks),
//! and those of MediaPipe's custom operators of the attention face mesh (its landmarks turned
//! into a crop's matrix, the crop, the cropped points mapped back).
//!
//! All image tensors have batch 1 and are stored row-major as `[H, W, C]` (channels fastest),
//! like TFLite; landmarks are `[N, D]`, matrices 4×4 row-major. Inner loops run over contiguous
//! channels so that the compiler vectorises them. Kernels write into caller-owned outputs and
//! never allocate.

#[cfg(target_arch = "x86_64")]
mod avx512;
mod conv2d;
mod depth_to_space;
mod depthwise_conv2d;
mod elementwise;
mod landmarks_to_transform_matrix;
mod madd;
mod max_pool2d;
mod pad;
mod resize_bilinear;
#[cfg(target_arch = "x86_64")]
mod row_sweep;
pub mod separately;
mod strided_slice;
mod transform_landmarks;
mod transform_tensor_bilinear;
mod window;

pub use conv2d::{conv2d, conv2d_scratch_len, Conv2dWeights};
pub use depth_to_space::depth_to_space;
pub use depthwise_conv2d::depthwise_conv2d;
pub use elementwise::{add, add_prelu, mul, prelu, relu, Activation};
pub use landmarks_to_transform_matrix::{
    landmarks_to_transform_matrix, LandmarksToTransformMatrix,
};
pub use madd::{Fused, Madd, Plain};
pub use max_pool2d::max_pool2d;
pub use pad::pad4;
pub use resize_bilinear::{resize_bilinear, ResizeAxis};
pub use strided_slice::{strided_slice, SliceMasks, StridedSlice};
pub use transform_landmarks::transform_landmarks;
pub use transform_tensor_bilinear::transform_tensor_bilinear;
pub use window::Window;

/// The convolution kernels this process runs: `"avx512"`, `"avx2+fma"` or `"portable"` (what
/// a benchmark reports beside its figures; set `VISAGE_NO_AVX512` to measure the AVX2 ones on
/// a CPU that has AVX-512).
pub fn kernels() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if avx512::available() {
            return "avx512";
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return "avx2+fma";
        }
    }
    "portable"
}

/// `n` deterministic test values in [−0.5, 0.5) from `seed` (a linear congruential generator).
#[cfg(test)]
pub(crate) fn test_values(n: usize, seed: u32) -> Vec<f32> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        })
        .collect()
}
