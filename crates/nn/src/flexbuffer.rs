//! A bounds-checked reader of the FlexBuffers that hold the options of MediaPipe's custom
//! operators (a TFLite operator's `custom_options` in the `FLEXBUFFERS` format): one map from
//! keys to integers, floats and typed vectors of integers, read whole into a [`FlexMap`].
//!
//! Why by hand: the `flexbuffers` crate (25.12.19, the latest release) panics on some malformed
//! buffers (google/flatbuffers issue 8923, still open), and these options use five of the
//! format's types; every read here checks its bounds and a malformed buffer is an `Err`.
//!
//! Format reminder (FlexBuffers, the schema-less sibling of FlatBuffers, little-endian): the
//! buffer ends with the root's packed type and then the root's byte width, the root's slot
//! just before them. A packed type byte holds the type in its upper six bits and log2 of a byte
//! width (1, 2, 4, 8) in its lower two. Scalars sit inline in their parent's slot, at the
//! parent's width; other values are referenced by an unsigned offset back from the slot, the
//! packed type giving the width of their elements. A vector is preceded by its length; an
//! untyped vector's elements are followed by one packed type byte each; a map is an untyped
//! vector of values preceded by (offset back to its keys vector, that vector's byte width,
//! length); a key is a NUL-terminated string.

/// FlexBuffers type codes (`flexbuffers::Type`) of the values the reader decodes.
mod kind {
    pub const INT: u8 = 1;
    pub const UINT: u8 = 2;
    pub const FLOAT: u8 = 3;
    pub const INDIRECT_INT: u8 = 6;
    pub const INDIRECT_UINT: u8 = 7;
    pub const INDIRECT_FLOAT: u8 = 8;
    pub const MAP: u8 = 9;
    pub const VECTOR_INT: u8 = 11;
    pub const VECTOR_UINT: u8 = 12;
    pub const BOOL: u8 = 26;
}

/// One value of a [`FlexMap`].
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum FlexValue {
    Int(i64),
    UInt(u64),
    Float(f64),
    Bool(bool),
    /// A typed vector of signed or unsigned integers.
    Ints(Vec<i64>),
    /// A value of another type (its type code), kept so that asking for it names the type.
    Other(u8),
}

/// A FlexBuffer whose root is a map, read whole: its keys in stored order with their values.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FlexMap {
    entries: Vec<(String, FlexValue)>,
}

impl FlexMap {
    /// Reads a buffer whose root is a map. Errors (in words) on anything out of bounds, a root
    /// of another type, widths other than 1, 2, 4, 8, keys that are not NUL-terminated UTF-8,
    /// a keys vector whose length is not the map's, and a key given twice.
    pub(crate) fn parse(buf: &[u8]) -> Result<FlexMap, String> {
        let r = Reader { buf };
        let n = buf.len();
        if n < 3 {
            return Err(format!("{n} bytes are too few for a FlexBuffer"));
        }
        let root_width = width(buf[n - 1])?;
        let packed = buf[n - 2];
        let root = (n - 2)
            .checked_sub(root_width)
            .ok_or_else(|| format!("root of {root_width} bytes in a {n}-byte buffer"))?;
        if packed >> 2 != kind::MAP {
            return Err(format!("the root has type {}, not a map", packed >> 2));
        }
        let map = r.deref(root, root_width)?;
        r.map(map, 1 << (packed & 3))
    }

    /// The value of `key`, if the map has it.
    pub(crate) fn get(&self, key: &str) -> Option<&FlexValue> {
        self.entries.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// The keys, in stored order (sorted, in a well-formed buffer).
    pub(crate) fn keys(&self) -> impl Iterator<Item = &str> {
        self.entries.iter().map(|(k, _)| k.as_str())
    }

    /// Integer `key` (`None` when absent); a value of another type is an error.
    pub(crate) fn int(&self, key: &str) -> Result<Option<i64>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(&FlexValue::Int(v)) => Ok(Some(v)),
            Some(&FlexValue::UInt(v)) => i64::try_from(v)
                .map(Some)
                .map_err(|_| format!("{key} = {v} is out of range")),
            Some(v) => Err(format!("{key} is {}, not an integer", v.type_name())),
        }
    }

    /// Float `key` (`None` when absent); an integer reads as a float, as FlexBuffers' own
    /// `AsFloat` does; another type is an error.
    pub(crate) fn float(&self, key: &str) -> Result<Option<f64>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(&FlexValue::Float(v)) => Ok(Some(v)),
            Some(&FlexValue::Int(v)) => Ok(Some(v as f64)),
            Some(&FlexValue::UInt(v)) => Ok(Some(v as f64)),
            Some(v) => Err(format!("{key} is {}, not a number", v.type_name())),
        }
    }

    /// Vector of integers `key` (`None` when absent); another type is an error.
    pub(crate) fn ints(&self, key: &str) -> Result<Option<&[i64]>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(FlexValue::Ints(v)) => Ok(Some(v)),
            Some(v) => Err(format!(
                "{key} is {}, not a vector of integers",
                v.type_name()
            )),
        }
    }
}

impl FlexValue {
    fn type_name(&self) -> String {
        match self {
            FlexValue::Int(_) => "an integer".into(),
            FlexValue::UInt(_) => "an unsigned integer".into(),
            FlexValue::Float(_) => "a float".into(),
            FlexValue::Bool(_) => "a boolean".into(),
            FlexValue::Ints(_) => "a vector of integers".into(),
            FlexValue::Other(t) => format!("of FlexBuffers type {t}"),
        }
    }
}

/// The byte width that the low two bits of `packed` (or a stored width) say.
fn width(stored: u8) -> Result<usize, String> {
    match stored {
        1 | 2 | 4 | 8 => Ok(stored as usize),
        w => Err(format!("byte width {w} (not 1, 2, 4 or 8)")),
    }
}

/// Bounds-checked reads over the whole buffer.
struct Reader<'a> {
    buf: &'a [u8],
}

impl<'a> Reader<'a> {
    fn bytes(&self, pos: usize, n: usize) -> Result<&'a [u8], String> {
        pos.checked_add(n)
            .and_then(|end| self.buf.get(pos..end))
            .ok_or_else(|| {
                format!(
                    "read of {n} bytes at {pos} past the end ({} bytes)",
                    self.buf.len()
                )
            })
    }

    /// An unsigned integer of `w` bytes (1, 2, 4 or 8) at `pos`.
    fn uint(&self, pos: usize, w: usize) -> Result<u64, String> {
        let mut le = [0u8; 8];
        le[..w].copy_from_slice(self.bytes(pos, w)?);
        Ok(u64::from_le_bytes(le))
    }

    /// A signed integer of `w` bytes at `pos`, sign-extended.
    fn int(&self, pos: usize, w: usize) -> Result<i64, String> {
        let shift = 64 - 8 * w as u32;
        Ok(((self.uint(pos, w)? << shift) as i64) >> shift)
    }

    /// A float of `w` bytes (4 or 8) at `pos`.
    fn float(&self, pos: usize, w: usize) -> Result<f64, String> {
        let bits = self.uint(pos, w)?;
        match w {
            4 => Ok(f32::from_bits(bits as u32) as f64),
            8 => Ok(f64::from_bits(bits)),
            _ => Err(format!("a float of {w} bytes")),
        }
    }

    /// A length or count of `w` bytes at `pos`, at most the buffer's size (every element takes
    /// at least a byte).
    fn count(&self, pos: usize, w: usize) -> Result<usize, String> {
        let n = self.uint(pos, w)?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n <= self.buf.len())
            .ok_or_else(|| format!("length {n} at {pos} exceeds the buffer"))
    }

    /// The position an offset of `w` bytes at `pos` points back to.
    fn deref(&self, pos: usize, w: usize) -> Result<usize, String> {
        let off = self.uint(pos, w)?;
        usize::try_from(off)
            .ok()
            .and_then(|off| pos.checked_sub(off))
            .ok_or_else(|| format!("offset {off} at {pos} points before the buffer"))
    }

    /// `pos - k·w`, the fields stored before a vector.
    fn before(&self, pos: usize, k: usize, w: usize) -> Result<usize, String> {
        pos.checked_sub(k * w)
            .ok_or_else(|| format!("vector at {pos} has no room for its prefix"))
    }

    /// The NUL-terminated UTF-8 key at `pos`.
    fn key(&self, pos: usize) -> Result<String, String> {
        let rest = self
            .buf
            .get(pos..)
            .ok_or_else(|| format!("key at {pos} past the end"))?;
        let len = rest
            .iter()
            .position(|&b| b == 0)
            .ok_or_else(|| format!("key at {pos} is not NUL-terminated"))?;
        String::from_utf8(rest[..len].to_vec()).map_err(|_| format!("key at {pos} is not UTF-8"))
    }

    /// The map at `pos` whose values are `w` bytes wide.
    fn map(&self, pos: usize, w: usize) -> Result<FlexMap, String> {
        let len = self.count(self.before(pos, 1, w)?, w)?;
        let keys_width = width(self.uint(self.before(pos, 2, w)?, w)? as u8)?;
        let keys = self.deref(self.before(pos, 3, w)?, w)?;
        let keys_len = self.count(self.before(keys, 1, keys_width)?, keys_width)?;
        if keys_len != len {
            return Err(format!("a map of {len} values has {keys_len} keys"));
        }
        // The values, then one packed type byte each.
        let types = self.bytes(pos + len * w, len)?;
        self.bytes(keys, len * keys_width)?;
        let mut entries: Vec<(String, FlexValue)> = Vec::with_capacity(len);
        for (i, &packed) in types.iter().enumerate() {
            let key = self.key(self.deref(keys + i * keys_width, keys_width)?)?;
            if entries.iter().any(|(k, _)| *k == key) {
                return Err(format!("key {key} given twice"));
            }
            let value = self.value(pos + i * w, w, packed)?;
            entries.push((key, value));
        }
        Ok(FlexMap { entries })
    }

    /// The value in the slot at `slot` of a parent `w` bytes wide, of packed type `packed`.
    fn value(&self, slot: usize, w: usize, packed: u8) -> Result<FlexValue, String> {
        let child = 1usize << (packed & 3);
        Ok(match packed >> 2 {
            kind::INT => FlexValue::Int(self.int(slot, w)?),
            kind::UINT => FlexValue::UInt(self.uint(slot, w)?),
            kind::FLOAT => FlexValue::Float(self.float(slot, w)?),
            kind::BOOL => FlexValue::Bool(self.uint(slot, w)? != 0),
            kind::INDIRECT_INT => FlexValue::Int(self.int(self.deref(slot, w)?, child)?),
            kind::INDIRECT_UINT => FlexValue::UInt(self.uint(self.deref(slot, w)?, child)?),
            kind::INDIRECT_FLOAT => FlexValue::Float(self.float(self.deref(slot, w)?, child)?),
            t @ (kind::VECTOR_INT | kind::VECTOR_UINT) => {
                let v = self.deref(slot, w)?;
                let n = self.count(self.before(v, 1, child)?, child)?;
                self.bytes(v, n * child)?;
                let ints = (0..n)
                    .map(|k| {
                        if t == kind::VECTOR_INT {
                            self.int(v + k * child, child)
                        } else {
                            let u = self.uint(v + k * child, child)?;
                            i64::try_from(u).map_err(|_| format!("element {u} is out of range"))
                        }
                    })
                    .collect::<Result<_, _>>()?;
                FlexValue::Ints(ints)
            }
            t => FlexValue::Other(t),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `TransformTensorBilinear`'s options in MediaPipe's `face_landmark_with_attention.tflite`:
    /// `{output_height: 16, output_width: 16}`, everything one byte wide.
    const CROP_OPTIONS: &[u8] = b"output_height\0output_width\0\
        \x02\x1c\x0f\x02\x01\x02\x10\x10\x04\x04\x04\x24\x01";

    /// A map of four-byte values `{f: 1.5, i: -3, v: [7, -1, 300]}` (the vector's elements two
    /// bytes wide), as FlexBuffers' builder lays it out.
    fn wide_map() -> Vec<u8> {
        let mut b = b"f\0i\0v\0".to_vec(); // keys at 0, 2, 4
        b.extend([3, 0]); // v: length 3, two-byte elements, at 8
        let v = b.len();
        for x in [7i16, -1, 300] {
            b.extend(x.to_le_bytes());
        }
        b.push(3); // keys vector: length, then offsets back, one byte each
        let keys = b.len();
        for (k, at) in [0usize, 2, 4].into_iter().enumerate() {
            b.push((keys + k - at) as u8);
        }
        // Map prefix (four bytes each): keys offset, keys width, length.
        let prefix = b.len();
        b.extend(((prefix - keys) as u32).to_le_bytes());
        b.extend(1u32.to_le_bytes());
        b.extend(3u32.to_le_bytes());
        let map = b.len();
        b.extend(1.5f32.to_le_bytes());
        b.extend((-3i32).to_le_bytes());
        let slot = b.len();
        b.extend(((slot - v) as u32).to_le_bytes());
        b.extend([3 << 2 | 2, 1 << 2 | 2, 11 << 2 | 1]); // float, int, int vector of 2 bytes
        let root = b.len();
        b.push((root - map) as u8);
        b.extend([9 << 2 | 2, 1]); // a map of four-byte values; root one byte wide
        b
    }

    #[test]
    fn reads_mediapipes_crop_options() {
        let m = FlexMap::parse(CROP_OPTIONS).unwrap();
        assert_eq!(
            m.keys().collect::<Vec<_>>(),
            ["output_height", "output_width"]
        );
        assert_eq!(m.int("output_height"), Ok(Some(16)));
        assert_eq!(m.int("output_width"), Ok(Some(16)));
        assert_eq!(m.float("output_width"), Ok(Some(16.0)));
        assert_eq!(m.int("scale"), Ok(None));
        assert!(m.ints("output_width").unwrap_err().contains("not a vector"));
    }

    #[test]
    fn reads_wide_values_and_typed_vectors() {
        let m = FlexMap::parse(&wide_map()).unwrap();
        assert_eq!(m.float("f"), Ok(Some(1.5)));
        assert_eq!(m.int("i"), Ok(Some(-3)));
        assert_eq!(m.ints("v"), Ok(Some(&[7, -1, 300][..])));
        assert!(m.int("f").unwrap_err().contains("f is a float"));
    }

    #[test]
    fn malformed_buffers_are_errors_not_panics() {
        for good in [CROP_OPTIONS.to_vec(), wide_map()] {
            for n in 0..good.len() {
                assert!(FlexMap::parse(&good[..n]).is_err(), "{n} bytes");
            }
            let mut bytes = good.clone();
            for i in 0..bytes.len() {
                for flip in [0x00, 0x7f, 0xff] {
                    let keep = bytes[i];
                    bytes[i] = flip;
                    let _ = FlexMap::parse(&bytes);
                    bytes[i] = keep;
                }
            }
        }
        let mut not_a_map = CROP_OPTIONS.to_vec();
        let n = not_a_map.len();
        not_a_map[n - 2] = 1 << 2; // an integer root
        assert!(FlexMap::parse(&not_a_map)
            .unwrap_err()
            .contains("not a map"));
        let mut twice = CROP_OPTIONS.to_vec();
        twice[29] = 0x1d; // the second key also points at "output_height"
        assert!(FlexMap::parse(&twice).unwrap_err().contains("twice"));
    }
}
