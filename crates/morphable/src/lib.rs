//! Morphable face models (paper §3): the importer of the ICT-FaceKit model (ICT-VGL/ICT-FaceKit,
//! MIT licence), shared by the ground-truth benchmark (`visage-eval`) and the 3-DMM fitter.
//!
//! A model is a neutral mesh S̄ plus linear modes: `S(p, e) = S̄ + Σ_i p_i U_i + Σ_j e_j B_j`,
//! with identity modes `U_i = identity_i − S̄` (weights drawn from N(0, 1)) and expression
//! blendshape modes `B_j = expression_j − S̄` (weights in [0, 1]).
//!
//! # Conventions
//! - **Units**: metres (the OBJ files are in centimetres; [`CM_TO_M`] is applied on import).
//! - **Model frame**: the ICT frame — x to the subject's left as seen from the front (image
//!   right), y up, the face looking along +z.
//! - **Vertex numbering**: vertex `i` is the `i`-th `v` line of the OBJ files (no UV-seam
//!   copies: the files are read with `visage_mesh::io::read_obj_with` and
//!   `ObjReadOptions::POSITIONS_AND_FACES`), so landmark indices and region ranges index
//!   positions directly.
//! - **Triangles**: every polygon `(v0, …, vn)` becomes the fan `(v0, vi, vi+1)`; quads give
//!   two triangles with the file's orientation.

#![forbid(unsafe_code)]

pub mod binary_reader;
mod error;
mod face_model;
pub mod fit;
mod ict_model;
mod landmark_correspondence;
mod regions;

pub use error::MorphableError;
pub use face_model::FaceModel;
pub use fit::{FaceFit, FaceFitter, FitOptions};
pub use ict_model::{IctModel, ImportOptions, LANDMARK_COUNT};
pub use landmark_correspondence::{
    CanonicalCorrespondence, SurfacePoint, LANDMARK_PAIRS, LEFT_LOWER_LID, LEFT_UPPER_LID,
    LOWER_LIP, RIGHT_LOWER_LID, RIGHT_UPPER_LID, UPPER_LIP,
};
pub use regions::{Region, CM_TO_M, SOLID_SURFACE_END};
