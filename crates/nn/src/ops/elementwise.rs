/// A fused activation (TFLite's `fused_activation_function`), of those the engine implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Activation {
    /// None (`NONE`).
    #[default]
    None,
    /// `max(x, 0)` (`RELU`).
    Relu,
}

/// `y = max(x, 0)` (TFLite `RELU`).
#[inline(always)]
pub fn relu(x: &[f32], y: &mut [f32]) {
    for (o, &v) in y.iter_mut().zip(x) {
        *o = v.max(0.0);
    }
}

/// Parametric ReLU with one slope per channel (TFLite `PRELU` with alpha `[1, 1, C]`):
/// `y = x` where `x ≥ 0`, else `α[c] · x`. `x`, `y` are `[…, C]`.
///
/// # Panics
/// If `x.len()` is not a multiple of `alpha.len()` or `y` has another length.
#[track_caller]
#[inline(always)]
pub fn prelu(x: &[f32], alpha: &[f32], y: &mut [f32]) {
    assert_eq!(x.len(), y.len(), "prelu sizes");
    assert_eq!(x.len() % alpha.len(), 0, "prelu channel count");
    for (yr, xr) in y
        .chunks_exact_mut(alpha.len())
        .zip(x.chunks_exact(alpha.len()))
    {
        for ((o, &v), &a) in yr.iter_mut().zip(xr).zip(alpha) {
            *o = if v >= 0.0 { v } else { a * v };
        }
    }
}

/// Element-wise sum of two tensors of the same shape (TFLite `ADD`, no broadcasting), with the
/// fused activation `act` applied to each sum.
///
/// # Panics
/// If the lengths differ.
#[track_caller]
#[inline(always)]
pub fn add(a: &[f32], b: &[f32], act: Activation, y: &mut [f32]) {
    assert!(a.len() == b.len() && a.len() == y.len(), "add sizes");
    if act == Activation::Relu {
        return add_relu(a, b, y);
    }
    for ((o, &u), &v) in y.iter_mut().zip(a).zip(b) {
        *o = u + v;
    }
}

/// `y = max(a + b, 0)`. Not inlined into the step loop (which keeps that loop's code as it was
/// for the networks without fused activations); SSE vectorises it.
#[inline(never)]
fn add_relu(a: &[f32], b: &[f32], y: &mut [f32]) {
    for ((o, &u), &v) in y.iter_mut().zip(a).zip(b) {
        *o = (u + v).max(0.0);
    }
}

/// Element-wise product (TFLite `MUL` without fused activation) of `a` with `b` of the same
/// length, or with `b`'s one value broadcast over `a`.
///
/// # Panics
/// If `b` has neither one value nor `a`'s length, or `y` has another length than `a`.
#[track_caller]
pub fn mul(a: &[f32], b: &[f32], y: &mut [f32]) {
    assert_eq!(a.len(), y.len(), "mul sizes");
    if let &[s] = b {
        for (o, &u) in y.iter_mut().zip(a) {
            *o = u * s;
        }
        return;
    }
    assert_eq!(a.len(), b.len(), "mul sizes");
    for ((o, &u), &v) in y.iter_mut().zip(a).zip(b) {
        *o = u * v;
    }
}

/// `prelu(a + b, α)` in one pass (an `ADD` whose only reader is a `PRELU`): the same values
/// as [`add`] then [`prelu`], without writing and reading the sum.
///
/// # Panics
/// If the lengths differ or are not a multiple of `alpha.len()`.
#[track_caller]
#[inline(always)]
pub fn add_prelu(a: &[f32], b: &[f32], alpha: &[f32], y: &mut [f32]) {
    assert!(a.len() == b.len() && a.len() == y.len(), "add sizes");
    assert_eq!(a.len() % alpha.len(), 0, "prelu channel count");
    let c = alpha.len();
    for ((yr, ar), br) in y
        .chunks_exact_mut(c)
        .zip(a.chunks_exact(c))
        .zip(b.chunks_exact(c))
    {
        for (((o, &u), &v), &s) in yr.iter_mut().zip(ar).zip(br).zip(alpha) {
            let x = u + v;
            *o = if x >= 0.0 { x } else { s * x };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prelu_relu_add() {
        let mut y = [0.0; 4];
        prelu(&[-1.0, 2.0, -3.0, -4.0], &[0.5, 0.25], &mut y);
        assert_eq!(y, [-0.5, 2.0, -1.5, -1.0]);
        relu(&[-1.0, 2.0, 0.0, -0.0], &mut y);
        assert_eq!(y, [0.0, 2.0, 0.0, 0.0]);
        add(&[1.0, 2.0, 3.0, 4.0], &[0.5; 4], Activation::None, &mut y);
        assert_eq!(y, [1.5, 2.5, 3.5, 4.5]);
        add(
            &[1.0, -2.0, 3.0, -0.25],
            &[0.5; 4],
            Activation::Relu,
            &mut y,
        );
        assert_eq!(y, [1.5, 0.0, 3.5, 0.25]);
        add(
            &[1.0, -2.0, 3.0, -0.25],
            &[0.5; 4],
            Activation::None,
            &mut y,
        );
        assert_eq!(y, [1.5, -1.5, 3.5, 0.25]);
        // The fused add + PReLU gives add's then prelu's values, bit for bit.
        let (a, b, alpha) = ([1.0, -2.0, 3.0, -0.3], [0.5, 0.7, -3.5, 0.1], [0.25, 0.1]);
        let (mut sum, mut two) = ([0.0; 4], [0.0; 4]);
        add(&a, &b, Activation::None, &mut sum);
        prelu(&sum, &alpha, &mut two);
        add_prelu(&a, &b, &alpha, &mut y);
        assert_eq!(y.map(f32::to_bits), two.map(f32::to_bits));
    }

    #[test]
    fn mul_by_a_scalar_or_elementwise() {
        let mut y = [0.0; 4];
        mul(&[1.0, -2.0, 3.0, 4.0], &[0.25], &mut y);
        assert_eq!(y, [0.25, -0.5, 0.75, 1.0]);
        mul(&[1.0, -2.0, 3.0, 4.0], &[2.0, 0.5, -1.0, 0.0], &mut y);
        assert_eq!(y, [2.0, -1.0, -3.0, 0.0]);
    }
}
