/// Errors of the engine. Every variant names the model (as given to
/// [`crate::Network::from_tflite`] or [`crate::TfliteModel::parse`]).
#[derive(Debug, thiserror::Error)]
pub enum NnError {
    /// A TFLite flatbuffer is malformed, or its graph uses something this engine does not
    /// implement (an operator, an operator variant or a tensor type).
    #[error("{name}: invalid or unsupported TFLite model: {reason}")]
    Tflite { name: String, reason: String },
}

/// An [`NnError::Tflite`] for the model called `name`.
pub(crate) fn err(name: &str, reason: String) -> NnError {
    NnError::Tflite {
        name: name.to_owned(),
        reason,
    }
}
