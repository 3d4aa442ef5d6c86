//! The faces a run over every face follows: those of the first frame that shows any, found
//! by both detectors (near and far faces), left to right.

use std::path::Path;

use visage_face::{DetectorUse, FaceMesh};

use crate::{Error, Input};

/// The faces of `input`'s first frame that shows any, left to right: that frame's input index
/// and each face's box (`[x, y, width, height]`, pixels). Empty when no frame shows a face.
/// `models` is the folder of the model files.
///
/// # Errors
/// Missing model files, a frame that cannot be decoded, a detector failure.
pub fn first_faces(input: Input, models: &Path) -> Result<Vec<(usize, [f32; 4])>, Error> {
    let mut mesh = FaceMesh::load(models)?;
    mesh.detectors = DetectorUse::Both;
    for frame in input {
        let frame = frame?;
        let mut boxes: Vec<[f32; 4]> = mesh
            .process(&frame.image)
            .map_err(|e| Error::on_frame(&frame.source, "face detection", e))?
            .iter()
            .map(|f| f.bbox)
            .collect();
        if !boxes.is_empty() {
            boxes.sort_by(|a, b| a[0].total_cmp(&b[0]));
            return Ok(boxes.into_iter().map(|b| (frame.index, b)).collect());
        }
    }
    Ok(Vec::new())
}
