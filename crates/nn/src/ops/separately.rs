//! The memory-bound passes — PReLU, add, add + PReLU, max-pool — as functions of their own,
//! compiled for AVX2 where the CPU has it, for the network's step loop to call.
//!
//! Inlined into that loop, the compiler could not tell a pass's output from its inputs (all
//! are slices of the network's buffers) and left the loops scalar or behind run-time overlap
//! checks: the 2×2 max-pool of the landmark network's 96×96×16 tensor took 53 µs there and
//! 33 µs as a function of its own. The values are the same: these passes round each value once.
#![allow(unsafe_code)]

use super::{Activation, Window};

/// `pub fn $name(args)`: `$pass(args)`, through a copy of it compiled for AVX2 on its own
/// where the CPU has AVX2, else through the caller's.
macro_rules! separately {
    ($(#[$doc:meta])* $name:ident => $pass:path, ($($arg:ident: $ty:ty),*)) => {
        $(#[$doc])*
        #[inline(always)]
        pub fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                #[target_feature(enable = "avx2")]
                #[inline(never)]
                fn avx2($($arg: $ty),*) {
                    $pass($($arg),*)
                }
                // SAFETY: the CPU has AVX2 (tested just above).
                unsafe { avx2($($arg),*) };
                return;
            }
            $pass($($arg),*)
        }
    };
}

separately!(
    /// [`super::prelu`].
    prelu => super::prelu, (x: &[f32], alpha: &[f32], y: &mut [f32])
);
separately!(
    /// [`super::add`].
    add => super::add, (a: &[f32], b: &[f32], act: Activation, y: &mut [f32])
);
separately!(
    /// [`super::add_prelu`].
    add_prelu => super::add_prelu, (a: &[f32], b: &[f32], alpha: &[f32], y: &mut [f32])
);
separately!(
    /// [`super::max_pool2d`].
    max_pool2d => super::max_pool2d, (x: &[f32], win: &Window, c: usize, y: &mut [f32])
);
