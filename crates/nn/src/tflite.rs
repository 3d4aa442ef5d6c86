//! A bounds-checked reader for the TFLite flatbuffer format (`schema.fbs` of TensorFlow Lite),
//! limited to the fields and operators the engine implements (those of MediaPipe's face
//! networks, and the custom operators of its attention face mesh, whose FlexBuffer options
//! become [`CustomOptions`]).
//!
//! Why by hand: the generated readers of the `flatbuffers` crate would add a build step and a
//! 5 000-line schema for the ten fields we read; every read here checks its bounds and turns a
//! malformed file into [`NnError::Tflite`] instead of a panic.
//!
//! Flatbuffer layout reminder: a table starts with an `i32` offset back to its vtable; the vtable
//! holds `u16` field offsets (0 = absent, use the default); references to tables, vectors and
//! strings are `u32` offsets relative to where they are stored; a vector is a `u32` length then the
//! elements.

use std::cell::Cell;

use crate::custom_options;
use crate::ops::{LandmarksToTransformMatrix, SliceMasks};
use crate::sparse::{DimFormat, Sparsity};
use crate::NnError;

/// Element type of a tensor (`TensorType` in the schema).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TensorType {
    Float32,
    Float16,
    Int32,
    /// Any other type code (unsupported by the engine, kept for error messages).
    Other(i8),
}

/// One tensor of the graph.
#[derive(Clone, Debug)]
pub struct Tensor {
    pub name: String,
    /// Shape, e.g. `[1, 192, 192, 3]` (NHWC).
    pub shape: Vec<usize>,
    pub dtype: TensorType,
    /// Index into [`TfliteModel::buffers`]; constant tensors have a non-empty buffer.
    pub buffer: usize,
    /// How a sparse constant is stored (its buffer then holds only the non-zeros); `None` for
    /// dense tensors.
    pub sparsity: Option<Sparsity>,
}

/// The operators the engine implements: built-in ones (`BuiltinOperator` codes in the schema)
/// and MediaPipe's custom ones of the attention face mesh (`CUSTOM` with a `custom_code`,
/// version 2 only: version 1 of each takes other shapes and options).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpCode {
    Add,
    Concatenation,
    Conv2d,
    Densify,
    DepthToSpace,
    DepthwiseConv2d,
    Dequantize,
    MaxPool2d,
    Mul,
    Relu,
    Reshape,
    ResizeBilinear,
    Pad,
    Prelu,
    StridedSlice,
    /// Custom `Landmarks2TransformMatrix` (version 2).
    Landmarks2TransformMatrix,
    /// Custom `TransformTensorBilinear` (version 2).
    TransformTensorBilinear,
    /// Custom `TransformLandmarks` (version 2).
    TransformLandmarks,
}

impl OpCode {
    fn from_builtin(code: i32) -> Option<OpCode> {
        Some(match code {
            0 => OpCode::Add,
            2 => OpCode::Concatenation,
            3 => OpCode::Conv2d,
            4 => OpCode::DepthwiseConv2d,
            5 => OpCode::DepthToSpace,
            6 => OpCode::Dequantize,
            17 => OpCode::MaxPool2d,
            18 => OpCode::Mul,
            19 => OpCode::Relu,
            22 => OpCode::Reshape,
            23 => OpCode::ResizeBilinear,
            34 => OpCode::Pad,
            45 => OpCode::StridedSlice,
            54 => OpCode::Prelu,
            124 => OpCode::Densify,
            _ => return None,
        })
    }

    /// The custom operator `name` of `version`, or why the engine does not run it.
    fn from_custom(name: &str, version: i32) -> Result<OpCode, String> {
        let code = match name {
            "Landmarks2TransformMatrix" => OpCode::Landmarks2TransformMatrix,
            "TransformTensorBilinear" => OpCode::TransformTensorBilinear,
            "TransformLandmarks" => OpCode::TransformLandmarks,
            _ => return Err(format!("custom operator {name:?} is not implemented")),
        };
        if version != 2 {
            return Err(format!(
                "custom operator {name} version {version} is not implemented (version 2 only)"
            ));
        }
        Ok(code)
    }
}

/// `BuiltinOperator_CUSTOM`: the operator is named by its `custom_code`.
const BUILTIN_CUSTOM: i32 = 32;

/// `SAME` or `VALID` padding of convolutions and pooling (TensorFlow semantics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Padding {
    Same,
    Valid,
}

/// Operator options the engine needs (only the fields these networks use).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OpOptions {
    pub padding: Padding,
    pub stride: [usize; 2],
    pub filter: [usize; 2],
    pub depth_multiplier: usize,
    pub dilation: [usize; 2],
    /// `fused_activation_function`: 0 = none, 1 = RELU (accepted on `CONV_2D` and `ADD`);
    /// the engine rejects the others.
    pub activation: i8,
    pub axis: i32,
    /// `DEPTH_TO_SPACE` block size.
    pub block_size: usize,
    /// `RESIZE_BILINEAR`: `align_corners`.
    pub align_corners: bool,
    /// `RESIZE_BILINEAR`: `half_pixel_centers`.
    pub half_pixel_centers: bool,
    /// `STRIDED_SLICE`: its masks and `offset`.
    pub slice: SliceMasks,
}

impl Default for OpOptions {
    fn default() -> Self {
        OpOptions {
            padding: Padding::Same,
            stride: [1, 1],
            filter: [1, 1],
            depth_multiplier: 1,
            dilation: [1, 1],
            activation: 0,
            axis: 0,
            block_size: 1,
            align_corners: false,
            half_pixel_centers: false,
            slice: SliceMasks::default(),
        }
    }
}

/// The options of a custom operator, read from its FlexBuffer (`custom_options`).
#[derive(Clone, Debug, PartialEq)]
pub enum CustomOptions {
    /// `Landmarks2TransformMatrix`'s.
    LandmarksToTransformMatrix(LandmarksToTransformMatrix),
    /// `TransformTensorBilinear`'s: the crop's `[output_height, output_width]`.
    TransformTensorBilinear { output_size: [usize; 2] },
}

/// One operator: code, input and output tensor indices (`-1` = optional input absent), options
/// (built-in operators' in `options`, custom operators' in `custom`; `TransformLandmarks` has
/// none).
#[derive(Clone, Debug)]
pub struct Operator {
    pub code: OpCode,
    pub inputs: Vec<i32>,
    pub outputs: Vec<usize>,
    pub options: OpOptions,
    pub custom: Option<CustomOptions>,
}

/// The first subgraph of a TFLite model, with its constant buffers.
#[derive(Clone, Debug)]
pub struct TfliteModel {
    pub tensors: Vec<Tensor>,
    pub operators: Vec<Operator>,
    pub inputs: Vec<usize>,
    pub outputs: Vec<usize>,
    /// Raw constant data, one entry per buffer of the file (empty for activations).
    pub buffers: Vec<Vec<u8>>,
}

/// Bounds-checked flatbuffer cursor over the whole file.
struct Fb<'a> {
    buf: &'a [u8],
    name: &'a str,
    /// Elements of the vectors read so far ([`Fb::vector`]), at most `buf.len()`.
    elements: Cell<usize>,
}

impl<'a> Fb<'a> {
    fn err(&self, reason: impl Into<String>) -> NnError {
        NnError::Tflite {
            name: self.name.to_owned(),
            reason: reason.into(),
        }
    }

    fn bytes(&self, pos: usize, n: usize) -> Result<&'a [u8], NnError> {
        pos.checked_add(n)
            .and_then(|end| self.buf.get(pos..end))
            .ok_or_else(|| {
                self.err(format!(
                    "read of {n} bytes at offset {pos} past the end ({} bytes)",
                    self.buf.len()
                ))
            })
    }

    fn u16(&self, pos: usize) -> Result<u16, NnError> {
        let b = self.bytes(pos, 2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&self, pos: usize) -> Result<u32, NnError> {
        let b = self.bytes(pos, 4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn i32(&self, pos: usize) -> Result<i32, NnError> {
        Ok(self.u32(pos)? as i32)
    }

    /// Follows a `u32` forward reference stored at `pos`.
    fn deref(&self, pos: usize) -> Result<usize, NnError> {
        let off = self.u32(pos)? as usize;
        pos.checked_add(off)
            .filter(|&p| p < self.buf.len())
            .ok_or_else(|| self.err(format!("reference at {pos} points outside the file")))
    }

    /// Position of field `index` of the table at `table`, or `None` when absent.
    fn field(&self, table: usize, index: usize) -> Result<Option<usize>, NnError> {
        let soff = self.i32(table)? as i64;
        let vtable = table as i64 - soff;
        if vtable < 0 || vtable as usize >= self.buf.len() {
            return Err(self.err(format!("vtable of table at {table} outside the file")));
        }
        let vtable = vtable as usize;
        let vsize = self.u16(vtable)? as usize;
        let slot = 4 + 2 * index;
        if slot + 2 > vsize {
            return Ok(None);
        }
        let off = self.u16(vtable + slot)? as usize;
        Ok((off != 0).then_some(table + off))
    }

    fn table_field(&self, table: usize, index: usize) -> Result<Option<usize>, NnError> {
        match self.field(table, index)? {
            Some(p) => Ok(Some(self.deref(p)?)),
            None => Ok(None),
        }
    }

    /// `(start, len)` of a vector field.
    ///
    /// In a well-formed file vectors do not overlap and every element takes at least a byte, so
    /// all the vectors read add up to at most as many elements as the file has bytes. A file
    /// whose references point at one vector many times breaks that bound, and would make the
    /// reader copy the same data over and over (a 300 kB file, 3 GB of buffers): it is an error
    /// here. A vector longer than the rest of the file fails its bounds check where it is read.
    fn vector(&self, table: usize, index: usize) -> Result<(usize, usize), NnError> {
        let Some(v) = self.table_field(table, index)? else {
            return Ok((0, 0));
        };
        let (start, len) = (v + 4, self.u32(v)? as usize);
        if len <= self.buf.len().saturating_sub(start) {
            let elements = self.elements.get() + len;
            if elements > self.buf.len() {
                return Err(self.err(format!(
                    "its vectors add up to more elements than the file has bytes ({}): \
                     references point at the same data more than once",
                    self.buf.len()
                )));
            }
            self.elements.set(elements);
        }
        Ok((start, len))
    }

    fn i32_vector(&self, table: usize, index: usize) -> Result<Vec<i32>, NnError> {
        let (start, len) = self.vector(table, index)?;
        self.bytes(start, len.saturating_mul(4))?;
        (0..len).map(|i| self.i32(start + 4 * i)).collect()
    }

    /// A vector of unsigned integers of `width` bytes (1, 2 or 4), widened.
    fn uint_vector(&self, table: usize, index: usize, width: usize) -> Result<Vec<u32>, NnError> {
        let (start, len) = self.vector(table, index)?;
        let b = self.bytes(start, len.saturating_mul(width))?;
        Ok(match width {
            1 => b.iter().map(|&v| v as u32).collect(),
            2 => b
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]) as u32)
                .collect(),
            _ => b
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        })
    }

    fn tables(&self, table: usize, index: usize) -> Result<Vec<usize>, NnError> {
        let (start, len) = self.vector(table, index)?;
        self.bytes(start, len.saturating_mul(4))?;
        (0..len).map(|i| self.deref(start + 4 * i)).collect()
    }

    fn string(&self, table: usize, index: usize) -> Result<String, NnError> {
        let (start, len) = self.vector(table, index)?;
        Ok(String::from_utf8_lossy(self.bytes(start, len)?).into_owned())
    }

    fn scalar_i32(&self, table: usize, index: usize, default: i32) -> Result<i32, NnError> {
        match self.field(table, index)? {
            Some(p) => self.i32(p),
            None => Ok(default),
        }
    }

    fn scalar_i8(&self, table: usize, index: usize, default: i8) -> Result<i8, NnError> {
        match self.field(table, index)? {
            Some(p) => Ok(self.bytes(p, 1)?[0] as i8),
            None => Ok(default),
        }
    }
}

fn usize_of(fb: &Fb, v: i32, what: &str) -> Result<usize, NnError> {
    usize::try_from(v).map_err(|_| fb.err(format!("{what} = {v} is negative")))
}

impl TfliteModel {
    /// Parses a `.tflite` flatbuffer; `name` is used in error messages (the file name).
    pub fn parse(bytes: &[u8], name: &str) -> Result<TfliteModel, NnError> {
        let fb = Fb {
            buf: bytes,
            name,
            elements: Cell::new(0),
        };
        if bytes.len() < 8 || &bytes[4..8] != b"TFL3" {
            return Err(
                fb.err("missing the TFL3 file identifier (not a TFLite model, or truncated)")
            );
        }
        let root = fb.deref(0)?;
        // Model: version 0, operator_codes 1, subgraphs 2, description 3, buffers 4.
        // OperatorCode: deprecated_builtin_code 0, custom_code 1, version 2, builtin_code 3.
        let mut codes = Vec::new();
        for oc in fb.tables(root, 1)? {
            let deprecated = fb.scalar_i8(oc, 0, 0)? as i32;
            let builtin = fb.scalar_i32(oc, 3, 0)?;
            let code = match deprecated.max(builtin) {
                BUILTIN_CUSTOM => OpCode::from_custom(&fb.string(oc, 1)?, fb.scalar_i32(oc, 2, 1)?),
                builtin => OpCode::from_builtin(builtin)
                    .ok_or_else(|| format!("builtin operator {builtin} is not implemented")),
            };
            codes.push(code);
        }
        let mut buffers = Vec::new();
        for b in fb.tables(root, 4)? {
            let (start, len) = fb.vector(b, 0)?;
            buffers.push(fb.bytes(start, len)?.to_vec());
        }
        let subgraphs = fb.tables(root, 2)?;
        let Some(&sg) = subgraphs.first() else {
            return Err(fb.err("no subgraph"));
        };
        let mut tensors = Vec::new();
        for t in fb.tables(sg, 0)? {
            let shape = fb
                .i32_vector(t, 0)?
                .into_iter()
                .map(|d| usize_of(&fb, d, "tensor dimension"))
                .collect::<Result<Vec<_>, _>>()?;
            let dtype = match fb.scalar_i8(t, 1, 0)? {
                0 => TensorType::Float32,
                1 => TensorType::Float16,
                2 => TensorType::Int32,
                other => TensorType::Other(other),
            };
            let buffer = fb.scalar_i32(t, 2, 0)?;
            let buffer = usize_of(&fb, buffer, "tensor buffer index")?;
            if buffer >= buffers.len() {
                return Err(fb.err(format!(
                    "tensor buffer index {buffer} ≥ {} buffers",
                    buffers.len()
                )));
            }
            // Tensor field 6: `sparsity`.
            let sparsity = match fb.table_field(t, 6)? {
                Some(s) => Some(read_sparsity(&fb, s)?),
                None => None,
            };
            tensors.push(Tensor {
                name: fb.string(t, 3)?,
                shape,
                dtype,
                buffer,
                sparsity,
            });
        }
        let check_tensor = |i: i32| -> Result<usize, NnError> {
            usize::try_from(i)
                .ok()
                .filter(|&i| i < tensors.len())
                .ok_or_else(|| fb.err(format!("tensor index {i} outside 0..{}", tensors.len())))
        };
        let inputs = fb
            .i32_vector(sg, 1)?
            .into_iter()
            .map(check_tensor)
            .collect::<Result<_, _>>()?;
        let outputs = fb
            .i32_vector(sg, 2)?
            .into_iter()
            .map(check_tensor)
            .collect::<Result<_, _>>()?;
        // Operator: opcode_index 0, inputs 1, outputs 2, builtin_options 4 (its type is 3),
        // custom_options 5, custom_options_format 6.
        let mut operators = Vec::new();
        for (k, op) in fb.tables(sg, 3)?.into_iter().enumerate() {
            let idx = fb.scalar_i32(op, 0, 0)?;
            let code = usize::try_from(idx)
                .ok()
                .and_then(|i| codes.get(i))
                .ok_or_else(|| {
                    fb.err(format!(
                        "operator code index {idx} outside 0..{}",
                        codes.len()
                    ))
                })?
                .clone()
                .map_err(|reason| fb.err(reason))?;
            let op_inputs = fb.i32_vector(op, 1)?;
            for &i in &op_inputs {
                if i >= 0 {
                    check_tensor(i)?;
                }
            }
            let op_outputs = fb
                .i32_vector(op, 2)?
                .into_iter()
                .map(check_tensor)
                .collect::<Result<_, _>>()?;
            let options = match fb.table_field(op, 4)? {
                Some(o) => read_options(&fb, code, o)?,
                None => OpOptions::default(),
            };
            let custom = read_custom_options(&fb, k, code, op)?;
            operators.push(Operator {
                code,
                inputs: op_inputs,
                outputs: op_outputs,
                options,
                custom,
            });
        }
        Ok(TfliteModel {
            tensors,
            operators,
            inputs,
            outputs,
            buffers,
        })
    }
}

fn padding(fb: &Fb, table: usize, index: usize) -> Result<Padding, NnError> {
    match fb.scalar_i8(table, index, 0)? {
        0 => Ok(Padding::Same),
        1 => Ok(Padding::Valid),
        p => Err(fb.err(format!("unknown padding {p}"))),
    }
}

fn positive(fb: &Fb, v: i32, what: &str) -> Result<usize, NnError> {
    if v >= 1 {
        Ok(v as usize)
    } else {
        Err(fb.err(format!("{what} = {v} must be ≥ 1")))
    }
}

fn read_options(fb: &Fb, code: OpCode, o: usize) -> Result<OpOptions, NnError> {
    let mut opt = OpOptions::default();
    match code {
        OpCode::Conv2d => {
            opt.padding = padding(fb, o, 0)?;
            opt.stride = [
                positive(fb, fb.scalar_i32(o, 2, 1)?, "stride_h")?,
                positive(fb, fb.scalar_i32(o, 1, 1)?, "stride_w")?,
            ];
            opt.activation = fb.scalar_i8(o, 3, 0)?;
            opt.dilation = [
                positive(fb, fb.scalar_i32(o, 5, 1)?, "dilation_h")?,
                positive(fb, fb.scalar_i32(o, 4, 1)?, "dilation_w")?,
            ];
        }
        OpCode::DepthwiseConv2d => {
            opt.padding = padding(fb, o, 0)?;
            opt.stride = [
                positive(fb, fb.scalar_i32(o, 2, 1)?, "stride_h")?,
                positive(fb, fb.scalar_i32(o, 1, 1)?, "stride_w")?,
            ];
            opt.depth_multiplier = positive(fb, fb.scalar_i32(o, 3, 1)?, "depth_multiplier")?;
            opt.activation = fb.scalar_i8(o, 4, 0)?;
            opt.dilation = [
                positive(fb, fb.scalar_i32(o, 6, 1)?, "dilation_h")?,
                positive(fb, fb.scalar_i32(o, 5, 1)?, "dilation_w")?,
            ];
        }
        OpCode::MaxPool2d => {
            opt.padding = padding(fb, o, 0)?;
            opt.stride = [
                positive(fb, fb.scalar_i32(o, 2, 1)?, "stride_h")?,
                positive(fb, fb.scalar_i32(o, 1, 1)?, "stride_w")?,
            ];
            opt.filter = [
                positive(fb, fb.scalar_i32(o, 4, 1)?, "filter_h")?,
                positive(fb, fb.scalar_i32(o, 3, 1)?, "filter_w")?,
            ];
            opt.activation = fb.scalar_i8(o, 5, 0)?;
        }
        OpCode::Add | OpCode::Mul => opt.activation = fb.scalar_i8(o, 0, 0)?,
        OpCode::StridedSlice => {
            let mask =
                |index: usize| -> Result<u32, NnError> { Ok(fb.scalar_i32(o, index, 0)? as u32) };
            opt.slice = SliceMasks {
                begin: mask(0)?,
                end: mask(1)?,
                ellipsis: mask(2)?,
                new_axis: mask(3)?,
                shrink_axis: mask(4)?,
                offset: fb.scalar_i8(o, 5, 0)? != 0,
            };
        }
        OpCode::Concatenation => {
            opt.axis = fb.scalar_i32(o, 0, 0)?;
            opt.activation = fb.scalar_i8(o, 1, 0)?;
        }
        OpCode::DepthToSpace => {
            opt.block_size = positive(fb, fb.scalar_i32(o, 0, 0)?, "block_size")?;
        }
        OpCode::ResizeBilinear => {
            // Fields 0 and 1 (new_height, new_width) are deprecated: the size is an input.
            opt.align_corners = fb.scalar_i8(o, 2, 0)? != 0;
            opt.half_pixel_centers = fb.scalar_i8(o, 3, 0)? != 0;
        }
        _ => {}
    }
    Ok(opt)
}

/// A custom operator's options from its `custom_options` bytes (field 5) in its
/// `custom_options_format` (field 6); `None` for built-in operators and for
/// `TransformLandmarks`, which reads none.
fn read_custom_options(
    fb: &Fb,
    k: usize,
    code: OpCode,
    op: usize,
) -> Result<Option<CustomOptions>, NnError> {
    let bytes = || -> Result<(&[u8], i8), NnError> {
        let (start, len) = fb.vector(op, 5)?;
        Ok((fb.bytes(start, len)?, fb.scalar_i8(op, 6, 0)?))
    };
    let invalid = |r: String| fb.err(format!("operator {k} ({code:?}): custom options: {r}"));
    Ok(Some(match code {
        OpCode::Landmarks2TransformMatrix => {
            let (b, format) = bytes()?;
            CustomOptions::LandmarksToTransformMatrix(
                custom_options::landmarks_to_transform_matrix(b, format).map_err(invalid)?,
            )
        }
        OpCode::TransformTensorBilinear => {
            let (b, format) = bytes()?;
            CustomOptions::TransformTensorBilinear {
                output_size: custom_options::transform_tensor_bilinear(b, format)
                    .map_err(invalid)?,
            }
        }
        _ => return Ok(None),
    }))
}

/// `SparsityParameters`: traversal_order 0, block_map 1, dim_metadata 2. Each
/// `DimensionMetadata`: format 0, dense_size 1, array_segments (union type 2, value 3),
/// array_indices (union type 4, value 5); the union members `Int32Vector`, `Uint16Vector`,
/// `Uint8Vector` (types 1, 2, 3) hold their values in field 0. Only the layout is checked here;
/// [`crate::sparse::densify`] checks that the indices fit the tensor.
fn read_sparsity(fb: &Fb, s: usize) -> Result<Sparsity, NnError> {
    let dims = |index: usize, what: &str| -> Result<Vec<usize>, NnError> {
        fb.i32_vector(s, index)?
            .into_iter()
            .map(|d| usize_of(fb, d, what))
            .collect()
    };
    let traversal_order = dims(0, "sparsity traversal order")?;
    let block_map = dims(1, "sparsity block map")?;
    let index_vector = |meta: usize, field: usize, what: &str| -> Result<Vec<usize>, NnError> {
        let width = match fb.scalar_i8(meta, field, 0)? {
            1 => 4,
            2 => 2,
            3 => 1,
            t => {
                return Err(fb.err(format!(
                    "sparse dimension {what}: unknown index vector type {t}"
                )))
            }
        };
        let table = fb
            .table_field(meta, field + 1)?
            .ok_or_else(|| fb.err(format!("sparse dimension without {what}")))?;
        Ok(fb
            .uint_vector(table, 0, width)?
            .into_iter()
            .map(|v| v as usize)
            .collect())
    };
    let mut dim_metadata = Vec::new();
    for meta in fb.tables(s, 2)? {
        dim_metadata.push(match fb.scalar_i8(meta, 0, 0)? {
            0 => DimFormat::Dense {
                size: usize_of(fb, fb.scalar_i32(meta, 1, 0)?, "dense_size")?,
            },
            1 => DimFormat::SparseCsr {
                segments: index_vector(meta, 2, "array_segments")?,
                indices: index_vector(meta, 4, "array_indices")?,
            },
            f => return Err(fb.err(format!("unknown sparse dimension format {f}"))),
        });
    }
    Ok(Sparsity {
        traversal_order,
        block_map,
        dim_metadata,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_garbage_without_panicking() {
        assert!(TfliteModel::parse(b"", "empty").is_err());
        assert!(TfliteModel::parse(b"\x00\x00\x00\x00TFL3", "tiny").is_err());
        let mut junk = vec![0xffu8; 64];
        junk[4..8].copy_from_slice(b"TFL3");
        let err = TfliteModel::parse(&junk, "junk.tflite")
            .unwrap_err()
            .to_string();
        assert!(err.contains("junk.tflite"), "{err}");
        // Every truncation of a minimal valid header must fail cleanly.
        for n in 0..junk.len() {
            let _ = TfliteModel::parse(&junk[..n], "cut");
        }
    }

    /// A flatbuffer value for [`build`]: scalars inline, the rest by reference.
    enum V {
        I8(i8),
        I32(i32),
        /// A table; `None` = field absent.
        Table(Vec<Option<V>>),
        /// A vector of tables.
        Tables(Vec<V>),
        /// A vector of scalars: the length it declares and its raw bytes.
        Scalars(u32, Vec<u8>),
        Str(&'static str),
    }

    fn i32s(v: &[i32]) -> V {
        V::Scalars(
            v.len() as u32,
            v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        )
    }

    /// Writes `v` (not a scalar) at the end of `buf`, children after their parent (references
    /// point forward); returns its position.
    fn put(buf: &mut Vec<u8>, v: &V) -> usize {
        fn slot(buf: &mut Vec<u8>) -> usize {
            buf.extend([0; 4]);
            buf.len() - 4
        }
        fn patch(buf: &mut [u8], at: usize, target: usize) {
            buf[at..at + 4].copy_from_slice(&((target - at) as u32).to_le_bytes());
        }
        let start = buf.len();
        match v {
            V::Table(fields) => {
                let n = fields.len();
                buf.extend((4 + 2 * n as u16).to_le_bytes());
                buf.extend((4 + 4 * n as u16).to_le_bytes());
                for (i, f) in fields.iter().enumerate() {
                    let off = if f.is_some() { 4 + 4 * i as u16 } else { 0 };
                    buf.extend(off.to_le_bytes());
                }
                let table = buf.len();
                buf.extend(((table - start) as i32).to_le_bytes());
                let mut children = Vec::new();
                for f in fields {
                    match f {
                        None => buf.extend([0; 4]),
                        Some(V::I8(x)) => buf.extend([*x as u8, 0, 0, 0]),
                        Some(V::I32(x)) => buf.extend(x.to_le_bytes()),
                        Some(child) => children.push((slot(buf), child)),
                    }
                }
                for (at, child) in children {
                    let c = put(buf, child);
                    patch(buf, at, c);
                }
                table
            }
            V::Tables(items) => {
                buf.extend((items.len() as u32).to_le_bytes());
                let slots: Vec<usize> = items.iter().map(|_| slot(buf)).collect();
                for (at, child) in slots.into_iter().zip(items) {
                    let c = put(buf, child);
                    patch(buf, at, c);
                }
                start
            }
            V::Scalars(n, bytes) => {
                buf.extend(n.to_le_bytes());
                buf.extend(bytes);
                start
            }
            V::Str(s) => {
                buf.extend((s.len() as u32).to_le_bytes());
                buf.extend(s.as_bytes());
                buf.push(0);
                start
            }
            V::I8(_) | V::I32(_) => unreachable!("scalars are stored inline"),
        }
    }

    /// A `.tflite` file whose root table is `model`.
    fn build(model: &V) -> Vec<u8> {
        let mut buf = vec![0, 0, 0, 0];
        buf.extend(b"TFL3");
        let root = put(&mut buf, model);
        buf[0..4].copy_from_slice(&(root as u32).to_le_bytes());
        buf
    }

    /// A model with one float16 tensor `w` of shape [2, 4] stored sparse (row dense, columns
    /// CSR), rows [1, 0, 0, 2] and [0, 0, 3, 0]; `segments` and `indices` are the CSR level's
    /// `(union type, vector)` (`None`: the union's table is absent); `format` is that level's
    /// format (1 = CSR).
    fn sparse_model(format: i8, segments: (i8, Option<V>), indices: (i8, Option<V>)) -> Vec<u8> {
        let index_vector = |v: Option<V>| v.map(|v| V::Table(vec![Some(v)]));
        let sparsity = V::Table(vec![
            Some(i32s(&[0, 1])),
            None,
            Some(V::Tables(vec![
                V::Table(vec![Some(V::I8(0)), Some(V::I32(2))]),
                V::Table(vec![
                    Some(V::I8(format)),
                    None,
                    Some(V::I8(segments.0)),
                    index_vector(segments.1),
                    Some(V::I8(indices.0)),
                    index_vector(indices.1),
                ]),
            ])),
        ]);
        let tensor = V::Table(vec![
            Some(i32s(&[2, 4])),
            Some(V::I8(1)),
            Some(V::I32(1)),
            Some(V::Str("w")),
            None,
            None,
            Some(sparsity),
        ]);
        let subgraph = V::Table(vec![
            Some(V::Tables(vec![tensor])),
            Some(i32s(&[])),
            Some(i32s(&[])),
            Some(V::Tables(Vec::new())),
        ]);
        let values: Vec<u8> = [0x3c00u16, 0x4000, 0x4200] // 1, 2, 3
            .iter()
            .flat_map(|h| h.to_le_bytes())
            .collect();
        build(&V::Table(vec![
            Some(V::I32(3)),
            Some(V::Tables(Vec::new())),
            Some(V::Tables(vec![subgraph])),
            None,
            Some(V::Tables(vec![
                V::Table(Vec::new()),
                V::Table(vec![Some(V::Scalars(6, values))]),
            ])),
        ]))
    }

    #[test]
    fn reads_a_sparse_tensor() {
        let bytes = sparse_model(
            1,
            (3, Some(V::Scalars(3, vec![0, 2, 3]))),
            (2, Some(i16s(&[0, 3, 2]))),
        );
        let m = TfliteModel::parse(&bytes, "sparse.tflite").unwrap();
        let t = &m.tensors[0];
        assert_eq!(
            (t.name.as_str(), t.dtype, t.buffer),
            ("w", TensorType::Float16, 1)
        );
        let s = t.sparsity.as_ref().unwrap();
        assert_eq!(s.traversal_order, [0, 1]);
        assert!(s.block_map.is_empty());
        assert_eq!(
            s.dim_metadata,
            [
                DimFormat::Dense { size: 2 },
                DimFormat::SparseCsr {
                    segments: vec![0, 2, 3],
                    indices: vec![0, 3, 2],
                },
            ]
        );
        let values = crate::float16::f16_slice_to_f32(&m.buffers[1]);
        let dense = crate::sparse::densify(s, &t.shape, &values).unwrap();
        assert_eq!(dense, [1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 3.0, 0.0]);
    }

    fn i16s(v: &[u16]) -> V {
        V::Scalars(
            v.len() as u32,
            v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        )
    }

    #[test]
    fn rejects_a_malformed_sparsity_block_without_panicking() {
        let ok = || (3, Some(V::Scalars(3, vec![0, 2, 3])));
        let cases = [
            // An index vector type outside the union.
            (
                sparse_model(1, ok(), (7, Some(V::Scalars(3, vec![0, 3, 2])))),
                "index vector type 7",
            ),
            // Vectors that claim more elements than the file holds.
            (
                sparse_model(1, (3, Some(V::Scalars(1000, vec![0, 2, 3]))), ok()),
                "past the end",
            ),
            (
                sparse_model(1, ok(), (1, Some(V::Scalars(1 << 30, vec![0; 12])))),
                "past the end",
            ),
            // A CSR level without its segments, and an unknown level format.
            (sparse_model(1, (3, None), ok()), "without array_segments"),
            (sparse_model(2, ok(), ok()), "format 2"),
        ];
        for (bytes, reason) in &cases {
            let e = TfliteModel::parse(bytes, "bad_sparsity.tflite")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("bad_sparsity.tflite") && e.contains(reason),
                "{e}"
            );
        }
        let good = sparse_model(1, ok(), ok());
        assert!(TfliteModel::parse(&good, "good").is_ok());
        // Any byte set to 0xff gives a model or an error, never a panic.
        let mut bytes = good.clone();
        for i in 8..bytes.len() {
            let keep = bytes[i];
            bytes[i] = 0xff;
            let _ = TfliteModel::parse(&bytes, "flipped");
            bytes[i] = keep;
        }
        // Every truncation fails cleanly.
        for n in 0..good.len() {
            assert!(TfliteModel::parse(&good[..n], "cut").is_err());
        }
    }

    /// A model of one custom operator `name` of `version` from `x` (`[1, 4, 3]`) to `y`,
    /// with `options` as its `custom_options` (FlexBuffers).
    fn custom_model(name: &'static str, version: i32, options: &[u8]) -> Vec<u8> {
        let tensor = |name: &'static str, shape: &[i32]| {
            V::Table(vec![
                Some(i32s(shape)),
                Some(V::I8(0)),
                Some(V::I32(0)),
                Some(V::Str(name)),
            ])
        };
        let operator = V::Table(vec![
            Some(V::I32(0)),
            Some(i32s(&[0])),
            Some(i32s(&[1])),
            None,
            None,
            Some(V::Scalars(options.len() as u32, options.to_vec())),
            Some(V::I8(0)),
        ]);
        let subgraph = V::Table(vec![
            Some(V::Tables(vec![
                tensor("x", &[1, 4, 3]),
                tensor("y", &[1, 4, 4]),
            ])),
            Some(i32s(&[0])),
            Some(i32s(&[1])),
            Some(V::Tables(vec![operator])),
        ]);
        let code = V::Table(vec![
            Some(V::I8(32)),
            Some(V::Str(name)),
            Some(V::I32(version)),
            Some(V::I32(32)),
        ]);
        build(&V::Table(vec![
            Some(V::I32(3)),
            Some(V::Tables(vec![code])),
            Some(V::Tables(vec![subgraph])),
            None,
            Some(V::Tables(vec![V::Table(Vec::new())])),
        ]))
    }

    #[test]
    fn reads_custom_operators_and_their_options() {
        // `{output_height: 16, output_width: 16}`, as in MediaPipe's attention mesh.
        let crop =
            b"output_height\0output_width\0\x02\x1c\x0f\x02\x01\x02\x10\x10\x04\x04\x04\x24\x01";
        let m = TfliteModel::parse(&custom_model("TransformTensorBilinear", 2, crop), "c").unwrap();
        assert_eq!(m.operators[0].code, OpCode::TransformTensorBilinear);
        assert_eq!(
            m.operators[0].custom,
            Some(CustomOptions::TransformTensorBilinear {
                output_size: [16, 16]
            })
        );
        let m = TfliteModel::parse(&custom_model("TransformLandmarks", 2, &[]), "c").unwrap();
        assert_eq!(
            (m.operators[0].code, &m.operators[0].custom),
            (OpCode::TransformLandmarks, &None)
        );
        let reason = |bytes: Vec<u8>| {
            TfliteModel::parse(&bytes, "custom.tflite")
                .unwrap_err()
                .to_string()
        };
        let e = reason(custom_model("TransformTensorBilinear", 1, crop));
        assert!(
            e.contains("TransformTensorBilinear version 1 is not implemented"),
            "{e}"
        );
        let e = reason(custom_model("MaxPoolingWithArgmax2D", 1, &[]));
        assert!(
            e.contains("\"MaxPoolingWithArgmax2D\" is not implemented"),
            "{e}"
        );
        let e = reason(custom_model(
            "Landmarks2TransformMatrix",
            2,
            b"\x00\x00\x01",
        ));
        assert!(
            e.contains("custom.tflite") && e.contains("operator 0 (Landmarks2TransformMatrix)"),
            "{e}"
        );
        // Any byte set to 0xff gives a model or an error, never a panic.
        let mut bytes = custom_model("TransformTensorBilinear", 2, crop);
        for i in 8..bytes.len() {
            let keep = bytes[i];
            bytes[i] = 0xff;
            let _ = TfliteModel::parse(&bytes, "flipped");
            bytes[i] = keep;
        }
    }

    #[test]
    fn a_vector_shared_by_many_references_is_rejected() {
        // A model whose 1000 buffers all reference one Buffer table of 1000 bytes: read as is,
        // a 5 kB file would become 1 MB of buffers (a 300 kB one, 3 GB).
        let (n, len) = (1000usize, 1000usize);
        let mut b = vec![0u8; 4];
        b.extend(b"TFL3");
        let patch = |b: &mut Vec<u8>, at: usize, target: usize| {
            b[at..at + 4].copy_from_slice(&((target - at) as u32).to_le_bytes());
        };
        // Root: a vtable of five fields of which only `buffers` (4) is present, then the table.
        let vtable = b.len();
        for v in [14u16, 8, 0, 0, 0, 0, 4] {
            b.extend(v.to_le_bytes());
        }
        let root = b.len();
        b.extend(((root - vtable) as i32).to_le_bytes());
        let buffers_ref = b.len();
        b.extend([0; 4]);
        let buffers = b.len();
        patch(&mut b, buffers_ref, buffers);
        b.extend((n as u32).to_le_bytes());
        let slots: Vec<usize> = (0..n).map(|i| buffers + 4 + 4 * i).collect();
        b.resize(buffers + 4 + 4 * n, 0);
        // The one Buffer table: `data` (field 0) holds `len` bytes.
        let buffer_vtable = b.len();
        for v in [6u16, 8, 4] {
            b.extend(v.to_le_bytes());
        }
        let buffer = b.len();
        b.extend(((buffer - buffer_vtable) as i32).to_le_bytes());
        let data_ref = b.len();
        b.extend([0; 4]);
        let data = b.len();
        patch(&mut b, data_ref, data);
        b.extend((len as u32).to_le_bytes());
        b.resize(b.len() + len, 1);
        for at in slots {
            patch(&mut b, at, buffer);
        }
        b[0..4].copy_from_slice(&(root as u32).to_le_bytes());
        let err = TfliteModel::parse(&b, "shared.tflite")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("shared.tflite") && err.contains("same data more than once"),
            "{err}"
        );
    }
}
