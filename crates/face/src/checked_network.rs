//! A model file compiled and checked against what its wrapper reads: the input's shape and the
//! size of each named output, so a wrong or altered file is an error at load time.

use visage_nn::Network;

use crate::{FaceError, ModelFile};

/// Compiles `bytes` as `file` and checks that its input is one `side × side` RGB image and that
/// each `(name, len)` of `outputs` is an output of `len` values.
pub(crate) fn compile_checked(
    file: ModelFile,
    bytes: &[u8],
    side: usize,
    outputs: &[(&str, usize)],
) -> Result<Network, FaceError> {
    let name = file.file_name();
    let net = Network::from_tflite(bytes, name)?;
    let invalid = |reason: String| FaceError::Tflite {
        name: name.into(),
        reason,
    };
    let expected = [1, side, side, 3];
    if net.input_shape() != expected {
        return Err(invalid(format!(
            "input shape {:?}, expected {expected:?}",
            net.input_shape()
        )));
    }
    for &(output, len) in outputs {
        match net.output_named(output) {
            Some(v) if v.len() == len => {}
            Some(v) => {
                return Err(invalid(format!(
                    "output {output} has {} values, expected {len}",
                    v.len()
                )))
            }
            None => return Err(invalid(format!("no output named {output}"))),
        }
    }
    Ok(net)
}
