//! `visage_mesh::io::parse_obj` (what `read_obj` / `read_obj_with` read an OBJ file with). The
//! first byte picks the `ObjReadOptions` (attributes and faces on or off), the rest is the file.
//! A mesh that is read must be consistent: triangles index existing vertices, per-vertex
//! attributes are absent or one per vertex, one source face per triangle.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_mesh::io::{parse_obj, ObjReadOptions};

fuzz_target!(|data: &[u8]| {
    let Some((&flags, file)) = data.split_first() else {
        return;
    };
    let options = ObjReadOptions {
        attributes: flags & 1 == 0,
        faces: flags & 2 == 0,
    };
    match parse_obj(file, Path::new("fuzz.obj"), &options) {
        Ok(obj) => {
            let m = &obj.mesh;
            let nv = m.vertices.len();
            assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < nv));
            for len in [m.uvs.len(), m.normals.len(), m.colors.len()] {
                assert!(len == 0 || len == nv, "{len} attributes for {nv} vertices");
            }
            assert_eq!(obj.triangle_face.len(), m.triangles.len());
            assert!(m.vertices.iter().flatten().all(|c| c.is_finite()));
        }
        Err(e) => drop(e.to_string()),
    }
});
