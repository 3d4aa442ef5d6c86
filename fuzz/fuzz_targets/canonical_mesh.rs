//! `CanonicalMesh::parse`, the protobuf reader of MediaPipe's geometry pipeline metadata
//! (`geometry_pipeline_metadata_landmarks.binarypb`): any bytes give a complete canonical face
//! (468 vertices with UVs, 898 triangles over them, a Procrustes basis) or an error, never a
//! panic or huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use visage_face::canonical_mesh::{CanonicalMesh, NUM_TRIANGLES};
use visage_face::NUM_LANDMARKS;

fuzz_target!(|data: &[u8]| {
    match CanonicalMesh::parse(data) {
        Ok(m) => {
            assert_eq!(m.vertices.len(), NUM_LANDMARKS);
            assert_eq!(m.uvs.len(), NUM_LANDMARKS);
            assert_eq!(m.triangles.len(), NUM_TRIANGLES);
            assert!(m
                .triangles
                .iter()
                .flatten()
                .all(|&i| (i as usize) < NUM_LANDMARKS));
            assert!(!m.procrustes_basis.is_empty());
        }
        Err(e) => drop(e.to_string()),
    }
});
