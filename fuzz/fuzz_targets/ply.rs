//! `visage_mesh::io::parse_ply` (what `read_ply` reads a PLY file with), ASCII and binary: any
//! bytes give a consistent mesh (triangles index existing vertices, per-vertex attributes absent
//! or one per vertex) or an error, never a panic, hang or huge allocation.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_mesh::io::parse_ply;

fuzz_target!(|data: &[u8]| {
    match parse_ply(data, Path::new("fuzz.ply")) {
        Ok(m) => {
            let nv = m.vertices.len();
            assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < nv));
            for len in [m.uvs.len(), m.normals.len(), m.colors.len()] {
                assert!(len == 0 || len == nv, "{len} attributes for {nv} vertices");
            }
            assert!(m.vertices.iter().flatten().all(|c| c.is_finite()));
        }
        Err(e) => drop(e.to_string()),
    }
});
