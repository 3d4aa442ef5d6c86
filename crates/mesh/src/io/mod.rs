//! Mesh readers and writers (PLY, OBJ) shared by every stage of visage.

mod ply;

pub use ply::{write_ply, MeshIoError};
