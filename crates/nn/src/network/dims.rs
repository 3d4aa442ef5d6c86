//! Shapes in words, for error messages and profiles.

/// A shape in words, e.g. `1×192×192×3` (`scalar` for rank 0).
pub(super) fn dims(shape: &[usize]) -> String {
    if shape.is_empty() {
        return "scalar".into();
    }
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    dims.join("×")
}
