/// Zero padding of a 4-D tensor (TFLite `PAD`): `pads[d] = [before, after]` for each axis of
/// `shape` (the input shape). Used by MediaPipe's networks to pad channels for residual adds.
///
/// # Panics
/// If `x` or `y` does not have the implied size.
#[track_caller]
#[inline(always)]
pub fn pad4(x: &[f32], shape: [usize; 4], pads: [[usize; 2]; 4], y: &mut [f32]) {
    let out: [usize; 4] = std::array::from_fn(|d| shape[d] + pads[d][0] + pads[d][1]);
    assert_eq!(x.len(), shape.iter().product::<usize>(), "pad input size");
    assert_eq!(y.len(), out.iter().product::<usize>(), "pad output size");
    y.fill(0.0);
    let c = shape[3];
    for n in 0..shape[0] {
        for h in 0..shape[1] {
            for w in 0..shape[2] {
                let src = ((n * shape[1] + h) * shape[2] + w) * c;
                let dst = (((n + pads[0][0]) * out[1] + h + pads[1][0]) * out[2] + w + pads[2][0])
                    * out[3]
                    + pads[3][0];
                y[dst..dst + c].copy_from_slice(&x[src..src + c]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_padding() {
        let x = [1.0, 2.0, 3.0, 4.0];
        let mut y = [9.0; 8];
        pad4(&x, [1, 1, 2, 2], [[0, 0], [0, 0], [0, 0], [0, 2]], &mut y);
        assert_eq!(y, [1.0, 2.0, 0.0, 0.0, 3.0, 4.0, 0.0, 0.0]);
    }
}
