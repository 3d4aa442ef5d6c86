/// Multiply-add `a·b + c` as the kernels' inner operation: fused (one rounding, `vfmadd` on CPUs
/// with FMA) or plain (two roundings). Kernels are generic over it so that the same source is
/// compiled once per instruction set; see [`crate::network::Network::run`].
pub trait Madd {
    /// Whether `madd` rounds once; kernels with explicit vector code use it only then, so that
    /// both paths keep their rounding.
    const FUSED: bool;

    /// `a · b + c`.
    fn madd(a: f32, b: f32, c: f32) -> f32;
}

/// Separate multiply and add (portable; what the compiler vectorises without FMA).
pub struct Plain;

/// Fused multiply-add; only fast where the caller is compiled with the `fma` target feature.
pub struct Fused;

impl Madd for Plain {
    const FUSED: bool = false;

    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a * b + c
    }
}

impl Madd for Fused {
    const FUSED: bool = true;

    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a.mul_add(b, c)
    }
}
