/// Which elements a `STRIDED_SLICE` takes, resolved for one input shape (rank ≤ 4, padded in
/// front to four axes): along axis `d`, `count[d]` indices `start[d] + i·step[d]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StridedSlice {
    /// The input's shape, four axes.
    pub shape: [usize; 4],
    pub start: [usize; 4],
    pub step: [isize; 4],
    pub count: [usize; 4],
}

/// A `STRIDED_SLICE`'s masks (`StridedSliceOptions`): bit `d` of a mask is about axis `d`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SliceMasks {
    /// Axes whose `begin` is ignored: the slice starts at the first index in its direction.
    pub begin: u32,
    /// Axes whose `end` is ignored: the slice runs to the last index in its direction.
    pub end: u32,
    /// Unsupported (rejected by [`StridedSlice::new`]).
    pub ellipsis: u32,
    /// Unsupported (rejected by [`StridedSlice::new`]).
    pub new_axis: u32,
    /// Axes taken at `begin` only and dropped from the output's shape.
    pub shrink_axis: u32,
    /// `offset`: `end` counts from `begin` (`end ← begin + end`).
    pub offset: bool,
}

impl StridedSlice {
    /// TensorFlow's `StridedSlice` for `shape` with constant `begin`, `end`, `strides` (one
    /// per axis; negative indices count from the end, and are then clamped to the axis) and
    /// `masks`. Returns the plan and the output's shape (without the shrunk axes). Errors on a
    /// rank above 4, operand lengths other than the rank, a zero stride, an ellipsis or a new
    /// axis.
    pub fn new(
        shape: &[usize],
        begin: &[i32],
        end: &[i32],
        strides: &[i32],
        masks: SliceMasks,
    ) -> Result<(StridedSlice, Vec<usize>), String> {
        let rank = shape.len();
        if rank > 4 {
            return Err(format!("a slice of rank {rank} (at most 4)"));
        }
        if begin.len() != rank || end.len() != rank || strides.len() != rank {
            return Err(format!(
                "begin, end, strides of {}, {}, {} values for rank {rank}",
                begin.len(),
                end.len(),
                strides.len()
            ));
        }
        if masks.ellipsis != 0 || masks.new_axis != 0 {
            return Err("ellipsis and new-axis masks are not supported".into());
        }
        let pad = 4 - rank;
        let mut plan = StridedSlice {
            shape: [1; 4],
            start: [0; 4],
            step: [1; 4],
            count: [1; 4],
        };
        let mut out = Vec::with_capacity(rank);
        for d in 0..rank {
            let bit = |mask: u32| mask >> d & 1 == 1;
            let dim = shape[d] as i64;
            let stride = strides[d] as i64;
            if stride == 0 {
                return Err(format!("stride 0 on axis {d}"));
            }
            let resolve = |i: i64| if i < 0 { i + dim } else { i };
            let shrink = bit(masks.shrink_axis);
            let (lo, hi) = if stride > 0 { (0, dim) } else { (-1, dim - 1) };
            let b = if bit(masks.begin) {
                if stride > 0 {
                    0
                } else {
                    dim - 1
                }
            } else {
                resolve(begin[d] as i64).clamp(lo, hi)
            };
            let e = if shrink {
                b + 1
            } else if bit(masks.end) {
                if stride > 0 {
                    dim
                } else {
                    -1
                }
            } else if masks.offset {
                (b + end[d] as i64).clamp(lo, hi)
            } else {
                resolve(end[d] as i64).clamp(lo, hi)
            };
            if shrink && !(0..dim).contains(&b) {
                return Err(format!("index {} outside axis {d} of {dim}", begin[d]));
            }
            let stride = if shrink { 1 } else { stride };
            // Indices b, b + s, … strictly before e.
            let (span, step) = if stride > 0 {
                (e - b, stride)
            } else {
                (b - e, -stride)
            };
            let n = (span.max(0) as u64).div_ceil(step as u64);
            plan.shape[pad + d] = shape[d];
            plan.start[pad + d] = if n > 0 { b as usize } else { 0 };
            plan.step[pad + d] = stride as isize;
            plan.count[pad + d] = n as usize;
            if !shrink {
                out.push(n as usize);
            }
        }
        Ok((plan, out))
    }

    /// Number of values the slice takes.
    pub fn len(&self) -> usize {
        self.count.iter().product()
    }

    /// Whether the slice takes nothing.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Copies the elements of `x` that `slice` takes into `y`, in order (TFLite `STRIDED_SLICE`).
/// Allocation-free.
///
/// # Panics
/// If `x` does not have `slice.shape`'s size or `y` not the slice's.
#[track_caller]
pub fn strided_slice(x: &[f32], slice: &StridedSlice, y: &mut [f32]) {
    let s = &slice.shape;
    assert_eq!(
        x.len(),
        s.iter().product::<usize>(),
        "strided_slice input size"
    );
    assert_eq!(y.len(), slice.len(), "strided_slice output size");
    let pitch = [s[1] * s[2] * s[3], s[2] * s[3], s[3], 1];
    // Offset of index i along axis d (non-negative by construction of the plan).
    let at = |d: usize, i: usize| {
        (slice.start[d] as isize + i as isize * slice.step[d]) as usize * pitch[d]
    };
    let mut k = 0;
    for i0 in 0..slice.count[0] {
        let o0 = at(0, i0);
        for i1 in 0..slice.count[1] {
            let o1 = o0 + at(1, i1);
            for i2 in 0..slice.count[2] {
                let o2 = o1 + at(2, i2);
                for i3 in 0..slice.count[3] {
                    y[k] = x[o2 + at(3, i3)];
                    k += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice(
        shape: &[usize],
        begin: &[i32],
        end: &[i32],
        strides: &[i32],
        masks: SliceMasks,
    ) -> (Vec<f32>, Vec<usize>) {
        let x: Vec<f32> = (0..shape.iter().product::<usize>())
            .map(|v| v as f32)
            .collect();
        let (plan, out) = StridedSlice::new(shape, begin, end, strides, masks).unwrap();
        let mut y = vec![-1.0; plan.len()];
        strided_slice(&x, &plan, &mut y);
        (y, out)
    }

    #[test]
    fn identity_steps_negative_indices_and_masks() {
        // The attention mesh's identity slice of [1, 1, 1, 6].
        let none = SliceMasks::default();
        let (y, out) = slice(&[1, 1, 1, 6], &[0; 4], &[1, 1, 1, 6], &[1; 4], none);
        assert_eq!(
            (y, out),
            (vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0], vec![1, 1, 1, 6])
        );
        // Every other column of rows 1.. of a 3 × 4 matrix.
        let (y, out) = slice(&[3, 4], &[1, 0], &[3, 4], &[1, 2], none);
        assert_eq!((y, out), (vec![4.0, 6.0, 8.0, 10.0], vec![2, 2]));
        // Negative: the last row, backwards, begin/end from the masks.
        let masks = SliceMasks {
            begin: 0b10,
            end: 0b10,
            ..none
        };
        let (y, out) = slice(&[3, 4], &[-1, 0], &[3, 0], &[1, -1], masks);
        assert_eq!((y, out), (vec![11.0, 10.0, 9.0, 8.0], vec![1, 4]));
        // Shrinking axis 0 to row 1; an end past the axis is clamped; offset ends.
        let masks = SliceMasks {
            shrink_axis: 0b01,
            ..none
        };
        let (y, out) = slice(&[3, 4], &[1, 2], &[0, 99], &[1, 1], masks);
        assert_eq!((y, out), (vec![6.0, 7.0], vec![2]));
        let masks = SliceMasks {
            offset: true,
            ..none
        };
        let (y, out) = slice(&[3, 4], &[1, 1], &[1, 2], &[1, 1], masks);
        assert_eq!((y, out), (vec![5.0, 6.0], vec![1, 2]));
        // An empty range.
        let (y, out) = slice(&[3, 4], &[2, 0], &[1, 4], &[1, 1], none);
        assert_eq!((y, out), (vec![], vec![0, 4]));
    }

    #[test]
    fn rejects_what_it_does_not_implement() {
        let e = |masks, strides: &[i32]| {
            StridedSlice::new(&[2, 2], &[0, 0], &[2, 2], strides, masks).unwrap_err()
        };
        let ellipsis = SliceMasks {
            ellipsis: 1,
            ..SliceMasks::default()
        };
        assert!(e(ellipsis, &[1, 1]).contains("ellipsis"));
        assert!(e(SliceMasks::default(), &[1, 0]).contains("stride 0"));
        let shrink = SliceMasks {
            shrink_axis: 1,
            ..SliceMasks::default()
        };
        assert!(
            StridedSlice::new(&[2, 2], &[5, 0], &[6, 2], &[1, 1], shrink)
                .unwrap_err()
                .contains("outside")
        );
        assert!(
            StridedSlice::new(&[1; 5], &[0; 5], &[1; 5], &[1; 5], shrink)
                .unwrap_err()
                .contains("rank 5")
        );
    }
}
