//! A bounds-checked reader for the TFLite flatbuffer format (`schema.fbs` of TensorFlow Lite),
//! limited to the fields and operators the engine implements (those of MediaPipe's face
//! networks).
//!
//! Why by hand: the generated readers of the `flatbuffers` crate would add a build step and a
//! 5 000-line schema for the ten fields we read; every read here checks its bounds and turns a
//! malformed file into [`NnError::Tflite`] instead of a panic.
//!
//! Flatbuffer layout reminder: a table starts with an `i32` offset back to its vtable; the vtable
//! holds `u16` field offsets (0 = absent, use the default); references to tables, vectors and
//! strings are `u32` offsets relative to where they are stored; a vector is a `u32` length then the
//! elements.

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
}

/// The built-in operators the engine implements (`BuiltinOperator` codes in the schema).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpCode {
    Add,
    Concatenation,
    Conv2d,
    DepthwiseConv2d,
    Dequantize,
    MaxPool2d,
    Relu,
    Reshape,
    Pad,
    Prelu,
}

impl OpCode {
    fn from_builtin(code: i32) -> Option<OpCode> {
        Some(match code {
            0 => OpCode::Add,
            2 => OpCode::Concatenation,
            3 => OpCode::Conv2d,
            4 => OpCode::DepthwiseConv2d,
            6 => OpCode::Dequantize,
            17 => OpCode::MaxPool2d,
            19 => OpCode::Relu,
            22 => OpCode::Reshape,
            34 => OpCode::Pad,
            54 => OpCode::Prelu,
            _ => return None,
        })
    }
}

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
    /// `fused_activation_function`: 0 = none (the only value the engine accepts).
    pub activation: i8,
    pub axis: i32,
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
        }
    }
}

/// One operator: code, input and output tensor indices (`-1` = optional input absent), options.
#[derive(Clone, Debug)]
pub struct Operator {
    pub code: OpCode,
    pub inputs: Vec<i32>,
    pub outputs: Vec<usize>,
    pub options: OpOptions,
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
    fn vector(&self, table: usize, index: usize) -> Result<(usize, usize), NnError> {
        match self.table_field(table, index)? {
            Some(v) => Ok((v + 4, self.u32(v)? as usize)),
            None => Ok((0, 0)),
        }
    }

    fn i32_vector(&self, table: usize, index: usize) -> Result<Vec<i32>, NnError> {
        let (start, len) = self.vector(table, index)?;
        self.bytes(start, len.saturating_mul(4))?;
        (0..len).map(|i| self.i32(start + 4 * i)).collect()
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
        let fb = Fb { buf: bytes, name };
        if bytes.len() < 8 || &bytes[4..8] != b"TFL3" {
            return Err(
                fb.err("missing the TFL3 file identifier (not a TFLite model, or truncated)")
            );
        }
        let root = fb.deref(0)?;
        // Model: version 0, operator_codes 1, subgraphs 2, description 3, buffers 4.
        let mut codes = Vec::new();
        for oc in fb.tables(root, 1)? {
            let deprecated = fb.scalar_i8(oc, 0, 0)? as i32;
            let builtin = fb.scalar_i32(oc, 3, 0)?;
            codes.push(deprecated.max(builtin));
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
            tensors.push(Tensor {
                name: fb.string(t, 3)?,
                shape,
                dtype,
                buffer,
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
        let mut operators = Vec::new();
        for op in fb.tables(sg, 3)? {
            let idx = fb.scalar_i32(op, 0, 0)?;
            let builtin = usize::try_from(idx)
                .ok()
                .and_then(|i| codes.get(i))
                .copied()
                .ok_or_else(|| {
                    fb.err(format!(
                        "operator code index {idx} outside 0..{}",
                        codes.len()
                    ))
                })?;
            let code = OpCode::from_builtin(builtin)
                .ok_or_else(|| fb.err(format!("builtin operator {builtin} is not implemented")))?;
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
            operators.push(Operator {
                code,
                inputs: op_inputs,
                outputs: op_outputs,
                options,
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
        OpCode::Add => opt.activation = fb.scalar_i8(o, 0, 0)?,
        OpCode::Concatenation => {
            opt.axis = fb.scalar_i32(o, 0, 0)?;
            opt.activation = fb.scalar_i8(o, 1, 0)?;
        }
        _ => {}
    }
    Ok(opt)
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
}
