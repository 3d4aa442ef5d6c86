//! The limits that keep a corrupt model from allocating without bound: the size of one tensor,
//! checked before anything else, and the values a compiled network holds in all, counted as
//! compilation goes ([`Budget`]).

use crate::error::err;
use crate::network::dims::dims;
use crate::tflite::TfliteModel;
use crate::NnError;

/// Most values one tensor may have (2^26, 256 MiB of f32): a guard against corrupt shapes,
/// checked before anything is allocated. MediaPipe's face networks have under a million.
pub const MAX_TENSOR_VALUES: usize = 1 << 26;

/// Most values a compiled network may hold, its weights and activations together (2^28,
/// 1 GiB of f32): a corrupt model that reuses one large constant many times, or describes huge
/// activations, is an error rather than an allocation that takes all memory.
pub const MAX_NETWORK_VALUES: usize = 1 << 28;

/// Checks that every shape is within [`MAX_TENSOR_VALUES`] (zero dimensions counted as one),
/// so that no product of dimensions while compiling can overflow and no tensor is unreasonably
/// large.
pub(super) fn check_tensor_sizes(model: &TfliteModel, name: &str) -> Result<(), NnError> {
    for t in &model.tensors {
        let size = t
            .shape
            .iter()
            .try_fold(1usize, |size, &d| size.checked_mul(d.max(1)));
        if size.is_none_or(|size| size > MAX_TENSOR_VALUES) {
            return Err(err(
                name,
                format!(
                    "tensor {} of shape {} is too large: its dimensions multiply to more \
                     than {MAX_TENSOR_VALUES}",
                    t.name,
                    dims(&t.shape)
                ),
            ));
        }
    }
    Ok(())
}

/// The values allocated so far while compiling, against [`MAX_NETWORK_VALUES`].
pub(super) struct Budget<'a> {
    name: &'a str,
    spent: std::cell::Cell<usize>,
}

impl<'a> Budget<'a> {
    /// Nothing spent yet; `name` is the model's, for the error.
    pub(super) fn new(name: &'a str) -> Budget<'a> {
        Budget {
            name,
            spent: std::cell::Cell::new(0),
        }
    }

    /// Counts `values` more, before they are allocated.
    pub(super) fn charge(&self, values: usize) -> Result<(), NnError> {
        let spent = self.spent.get().saturating_add(values);
        if spent > MAX_NETWORK_VALUES {
            return Err(err(
                self.name,
                format!(
                    "its weights and activations need more than {MAX_NETWORK_VALUES} values \
                     (1 GiB), far more than a face network"
                ),
            ));
        }
        self.spent.set(spent);
        Ok(())
    }
}
