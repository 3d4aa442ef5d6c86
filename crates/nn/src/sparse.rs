//! Sparse constant tensors (TFLite's `SparsityParameters`) and their expansion to dense values,
//! which the compiler does once at load time for the tensors behind `DENSIFY` (MediaPipe's
//! full-range face detector stores 46 of its 1×1 convolution kernels this way).
//!
//! The format, as TensorFlow Lite's `FormatConverter` reads it: the tensor's dimensions are
//! visited in `traversal_order`; each visited level is either dense (every index
//! `0..dense_size`) or compressed sparse row (`SPARSE_CSR`): the indices present below parent
//! position `p` are `array_indices[array_segments[p] .. array_segments[p + 1]]`, and the position
//! handed to the next level is the index into `array_indices`. The stored values are the
//! non-zeros in that visiting order. Block sparsity (`block_map`) is not implemented.

/// How one level of a sparse tensor is stored (`DimensionMetadata`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DimFormat {
    /// Every index `0..size` is present.
    Dense { size: usize },
    /// Compressed sparse row: `segments` has one entry per parent position plus one, `indices`
    /// the present indices of this level.
    SparseCsr {
        segments: Vec<usize>,
        indices: Vec<usize>,
    },
}

/// The sparsity of a constant tensor (`SparsityParameters` in the schema).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sparsity {
    /// The order in which the dimensions are visited (a permutation of `0..rank`).
    pub traversal_order: Vec<usize>,
    /// Block dimensions (block sparsity); must be empty for [`densify`].
    pub block_map: Vec<usize>,
    /// One entry per visited level.
    pub dim_metadata: Vec<DimFormat>,
}

/// Expands `values` (the stored non-zeros, in visiting order) to the dense row-major tensor of
/// `shape`. Every index and segment is checked: a malformed description is an `Err` with the
/// reason, never a panic or an out-of-bounds write.
pub fn densify(sparsity: &Sparsity, shape: &[usize], values: &[f32]) -> Result<Vec<f32>, String> {
    let rank = shape.len();
    if !sparsity.block_map.is_empty() {
        return Err(format!(
            "block sparsity (block map {:?}) is not supported",
            sparsity.block_map
        ));
    }
    let order = &sparsity.traversal_order;
    let mut seen = vec![false; rank];
    if order.len() != rank
        || order
            .iter()
            .any(|&d| d >= rank || std::mem::replace(&mut seen[d], true))
    {
        return Err(format!(
            "traversal order {order:?} is not a permutation of the {rank} dimensions"
        ));
    }
    if sparsity.dim_metadata.len() != rank {
        return Err(format!(
            "{} dimension metadata entries for rank {rank}",
            sparsity.dim_metadata.len()
        ));
    }
    let total = shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .filter(|&t| t <= 1 << 28)
        .ok_or_else(|| format!("dense shape {shape:?} is too large"))?;
    // Row-major strides of the dense tensor, per visited level.
    let mut strides = vec![1usize; rank];
    for d in (0..rank.saturating_sub(1)).rev() {
        strides[d] = strides[d + 1] * shape[d + 1];
    }
    let level_stride: Vec<usize> = order.iter().map(|&d| strides[d]).collect();
    let level_size: Vec<usize> = order.iter().map(|&d| shape[d]).collect();
    for (level, meta) in sparsity.dim_metadata.iter().enumerate() {
        match meta {
            DimFormat::Dense { size } if *size != level_size[level] => {
                return Err(format!(
                    "dense level {level} has size {size}, the dimension has {}",
                    level_size[level]
                ));
            }
            DimFormat::Dense { .. } => {}
            DimFormat::SparseCsr { segments, indices } => {
                if segments.windows(2).any(|w| w[0] > w[1])
                    || segments.last().is_some_and(|&s| s > indices.len())
                {
                    return Err(format!(
                        "sparse level {level}: segments not increasing or past the {} indices",
                        indices.len()
                    ));
                }
                if let Some(&i) = indices.iter().find(|&&i| i >= level_size[level]) {
                    return Err(format!(
                        "sparse level {level}: index {i} outside the dimension of {}",
                        level_size[level]
                    ));
                }
            }
        }
    }
    let mut out = vec![0.0f32; total];
    let mut next = 0usize;
    // Depth-first walk: (level, parent position, dense offset so far).
    let mut stack = vec![(0usize, 0usize, 0usize)];
    // Children are pushed in reverse so that they pop in order.
    while let Some((level, pos, offset)) = stack.pop() {
        if level == rank {
            let v = values.get(next).ok_or_else(|| {
                format!(
                    "the sparsity describes more than the {} stored values",
                    values.len()
                )
            })?;
            out[offset] = *v;
            next += 1;
            continue;
        }
        match &sparsity.dim_metadata[level] {
            DimFormat::Dense { size } => {
                for i in (0..*size).rev() {
                    let child = pos
                        .checked_mul(*size)
                        .and_then(|p| p.checked_add(i))
                        .ok_or_else(|| "position overflow".to_string())?;
                    stack.push((level + 1, child, offset + i * level_stride[level]));
                }
            }
            DimFormat::SparseCsr { segments, indices } => {
                let (Some(&lo), Some(&hi)) = (segments.get(pos), segments.get(pos + 1)) else {
                    return Err(format!(
                        "sparse level {level}: no segment for parent position {pos} ({} \
                         segment bounds)",
                        segments.len()
                    ));
                };
                for k in (lo..hi).rev() {
                    stack.push((level + 1, k, offset + indices[k] * level_stride[level]));
                }
            }
        }
        if stack.len() > total + rank + 1 {
            return Err("the sparsity describes more entries than the dense tensor".into());
        }
    }
    if next != values.len() {
        return Err(format!(
            "the sparsity places {next} values, the buffer holds {}",
            values.len()
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×4 matrix with rows `[1, 0, 0, 2]` and `[0, 0, 3, 0]`: row dense, column CSR.
    fn csr() -> Sparsity {
        Sparsity {
            traversal_order: vec![0, 1],
            block_map: Vec::new(),
            dim_metadata: vec![
                DimFormat::Dense { size: 2 },
                DimFormat::SparseCsr {
                    segments: vec![0, 2, 3],
                    indices: vec![0, 3, 2],
                },
            ],
        }
    }

    #[test]
    fn expands_a_csr_matrix() {
        let dense = densify(&csr(), &[2, 4], &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!(dense, [1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 3.0, 0.0]);
    }

    #[test]
    fn expands_the_detector_layout_and_a_transposed_order() {
        // [C_out = 2, 1, 1, C_in = 3], dims 0–2 dense, dim 3 CSR (as in the full-range model).
        let s = Sparsity {
            traversal_order: vec![0, 1, 2, 3],
            block_map: Vec::new(),
            dim_metadata: vec![
                DimFormat::Dense { size: 2 },
                DimFormat::Dense { size: 1 },
                DimFormat::Dense { size: 1 },
                DimFormat::SparseCsr {
                    segments: vec![0, 1, 3],
                    indices: vec![1, 0, 2],
                },
            ],
        };
        let d = densify(&s, &[2, 1, 1, 3], &[5.0, 6.0, 7.0]).unwrap();
        assert_eq!(d, [0.0, 5.0, 0.0, 6.0, 0.0, 7.0]);
        // Column-major traversal of a 2×2: values visited (0,0), (1,0), (0,1), (1,1).
        let t = Sparsity {
            traversal_order: vec![1, 0],
            block_map: Vec::new(),
            dim_metadata: vec![DimFormat::Dense { size: 2 }, DimFormat::Dense { size: 2 }],
        };
        let d = densify(&t, &[2, 2], &[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(d, [1.0, 3.0, 2.0, 4.0]);
    }

    #[test]
    fn rejects_malformed_descriptions() {
        let bad =
            |s: &Sparsity, shape: &[usize], n: usize| densify(s, shape, &vec![1.0; n]).unwrap_err();
        assert!(bad(&csr(), &[2, 4], 2).contains("more than the 2 stored"));
        assert!(bad(&csr(), &[2, 4], 4).contains("places 3 values"));
        assert!(bad(&csr(), &[2, 3], 3).contains("index 3 outside"));
        assert!(bad(&csr(), &[3, 4], 3).contains("dense level 0"));
        let mut s = csr();
        s.dim_metadata[1] = DimFormat::SparseCsr {
            segments: vec![0, 2, 9],
            indices: vec![0, 3, 2],
        };
        assert!(bad(&s, &[2, 4], 3).contains("segments"));
        s.dim_metadata[1] = DimFormat::SparseCsr {
            segments: vec![0, 2],
            indices: vec![0, 3, 2],
        };
        assert!(bad(&s, &[2, 4], 3).contains("no segment"));
        let mut s = csr();
        s.traversal_order = vec![0, 0];
        assert!(bad(&s, &[2, 4], 3).contains("permutation"));
        s.traversal_order = vec![0, 1];
        s.block_map = vec![1];
        assert!(bad(&s, &[2, 4], 3).contains("block"));
        s.block_map.clear();
        s.dim_metadata.pop();
        assert!(bad(&s, &[2, 4], 3).contains("metadata"));
    }
}
