use crate::tflite::Padding;

/// Sliding-window geometry of a convolution or pooling over an `[H, W, C]` input
/// (TensorFlow semantics: `SAME` pads `max((out−1)·s + k − in, 0)` in total, the smaller half
/// before, i.e. top/left).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub in_h: usize,
    pub in_w: usize,
    pub out_h: usize,
    pub out_w: usize,
    pub k_h: usize,
    pub k_w: usize,
    pub stride_h: usize,
    pub stride_w: usize,
    pub pad_top: usize,
    pub pad_left: usize,
}

impl Window {
    /// Output size and padding for an `in_h × in_w` input, a `k_h × k_w` window and strides.
    pub fn new(
        in_h: usize,
        in_w: usize,
        k: [usize; 2],
        stride: [usize; 2],
        padding: Padding,
    ) -> Window {
        let dim = |input: usize, k: usize, s: usize| -> (usize, usize) {
            match padding {
                Padding::Same => {
                    let out = input.div_ceil(s);
                    let total = ((out.saturating_sub(1)) * s + k).saturating_sub(input);
                    (out, total / 2)
                }
                Padding::Valid => ((input.saturating_sub(k)) / s + 1, 0),
            }
        };
        let (out_h, pad_top) = dim(in_h, k[0], stride[0]);
        let (out_w, pad_left) = dim(in_w, k[1], stride[1]);
        Window {
            in_h,
            in_w,
            out_h,
            out_w,
            k_h: k[0],
            k_w: k[1],
            stride_h: stride[0],
            stride_w: stride[1],
            pad_top,
            pad_left,
        }
    }

    /// Input row/column of window tap `k` for output index `o`, or `None` in the padding.
    #[inline(always)]
    pub fn tap(o: usize, stride: usize, k: usize, pad: usize, len: usize) -> Option<usize> {
        (o * stride + k).checked_sub(pad).filter(|&i| i < len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_and_valid_match_tensorflow() {
        let w = Window::new(96, 96, [3, 3], [2, 2], Padding::Same);
        assert_eq!((w.out_h, w.pad_top), (48, 0));
        let w = Window::new(192, 192, [3, 3], [2, 2], Padding::Same);
        assert_eq!((w.out_h, w.pad_top), (96, 0));
        let w = Window::new(64, 64, [3, 3], [1, 1], Padding::Same);
        assert_eq!((w.out_h, w.pad_top), (64, 1));
        let w = Window::new(128, 128, [5, 5], [2, 2], Padding::Same);
        assert_eq!((w.out_h, w.pad_top), (64, 1));
        let w = Window::new(3, 3, [3, 3], [3, 3], Padding::Valid);
        assert_eq!((w.out_h, w.pad_top), (1, 0));
    }
}
