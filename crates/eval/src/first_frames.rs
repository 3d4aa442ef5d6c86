//! The shaded colour image of each benchmark sequence's first frame (`visage eval synthetic
//! --save-frames`), to look at what the methods were given.

use std::path::Path;

use visage_morphable::IctModel;

use crate::benchmark::SequenceInfo;
use crate::error::EvalError;
use crate::synthesis::{synthesize, SynthesisConfig};

/// Writes `dir/seqNN_frame000.png` (8-bit sRGB) for each of `sequences` (NN its index),
/// synthesised again from its seed with `synthesis` (two frames, the first rendered), and
/// creates `dir` first.
///
/// # Errors
/// [`EvalError::CreateDir`] when `dir` cannot be created; a sequence that cannot be
/// synthesised or rendered; [`EvalError::WriteImage`] when an image cannot be written.
pub fn write_first_frames(
    model: &IctModel,
    synthesis: &SynthesisConfig,
    sequences: &[SequenceInfo],
    dir: &Path,
) -> Result<(), EvalError> {
    std::fs::create_dir_all(dir).map_err(|source| EvalError::CreateDir {
        path: dir.to_owned(),
        source,
    })?;
    for (s, info) in sequences.iter().enumerate() {
        let seq = synthesize(
            model,
            &SynthesisConfig {
                frames: 2,
                ..synthesis.clone()
            },
            info.seed,
        )?;
        let rgb = seq.render_color(0)?;
        let path = dir.join(format!("seq{s:02}_frame000.png"));
        visage_render::write_srgb_png(&path, seq.k.width, seq.k.height, &rgb)
            .map_err(EvalError::WriteImage)?;
    }
    Ok(())
}
