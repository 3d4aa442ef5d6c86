//! Which file of a run's folder goes into which tool: the table the report shows (for the
//! files a folder holds) and the README repeats (a test keeps the two together).

use crate::file_names::{
    BLENDSHAPES_CSV, BLENDSHAPES_JSON, CACHE_MESH, CAMERA, GLB, IDENTITY, IDENTITY_MESH, LANDMARKS,
    MESHES_FOLDER, METRICS, PLOTS_FOLDER, POINT_CACHE, PREVIEW, REPORT, TEXTURE,
};

/// One row of the guide: the file (or folder), what it holds, where it goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileUse {
    pub file: &'static str,
    pub holds: &'static str,
    pub goes_to: &'static str,
}

/// The guide, the files a user opens first at the top.
pub const FILE_GUIDE: [FileUse; 14] = [
    FileUse {
        file: GLB,
        holds: "the animated face: mesh, texture, head motion, the 52 ARKit shapes as morph targets with their keys",
        goes_to: "Blender (File › Import › glTF: shape keys and head animated; checked), three.js and the web (as in the report), other glTF importers (Unreal, Godot; not checked here)",
    },
    FileUse {
        file: BLENDSHAPES_CSV,
        holds: "per frame, the 52 ARKit weights and the head's and eyes' angles, in Live Link Face's take format (names, order, timecode)",
        goes_to: "a rig with ARKit-named shapes (Unreal, Maya, MotionBuilder, Blender: keys from the columns, by name), spreadsheets, pandas",
    },
    FileUse {
        file: POINT_CACHE,
        holds: "the fused surface of every frame, as a point cache over the vertices of mesh.obj",
        goes_to: "Blender (import mesh.obj, Mesh Cache modifier on sequence.pc2), Maya, 3ds Max, Houdini (PC2 caches)",
    },
    FileUse {
        file: CACHE_MESH,
        holds: "the mesh the point cache moves, with UVs (mesh.mtl names the texture)",
        goes_to: "any 3-D tool, with sequence.pc2",
    },
    FileUse {
        file: TEXTURE,
        holds: "the face's colour fused from the first frames, in the mesh's UVs",
        goes_to: "the material of mesh.obj (already in the glb)",
    },
    FileUse {
        file: PREVIEW,
        holds: "the input, the mesh over it and the mesh turning, side by side, with the input's sound",
        goes_to: "any video player: check the tracking and the lip sync",
    },
    FileUse {
        file: REPORT,
        holds: "this page: the take's moments, curves, warnings and the 3-D viewer; opens offline",
        goes_to: "a browser",
    },
    FileUse {
        file: BLENDSHAPES_JSON,
        holds: "the weights and angles of blendshapes.csv with frame indices and times",
        goes_to: "Python (visage.read_run), JavaScript",
    },
    FileUse {
        file: LANDMARKS,
        holds: "per frame, the 468 tracked and fused landmarks and the metric head pose",
        goes_to: "Python (visage.read_run), research on the landmarks",
    },
    FileUse {
        file: IDENTITY_MESH,
        holds: "the person's neutral face, metric (metres), fitted over the whole clip",
        goes_to: "measuring the face; a base mesh for a rig",
    },
    FileUse {
        file: IDENTITY,
        holds: "the identity's ICT-FaceKit coefficients and the frames it was fitted on",
        goes_to: "Python, to rebuild or compare faces",
    },
    FileUse {
        file: CAMERA,
        holds: "the camera's intrinsics (focal lengths and centre in pixels)",
        goes_to: "matching the camera in a 3-D tool; reprojecting the mesh onto the video",
    },
    FileUse {
        file: METRICS,
        holds: "per frame, status, timings and quality figures; the run's summary",
        goes_to: "Python, dashboards, checking a batch",
    },
    FileUse {
        file: PLOTS_FOLDER,
        holds: "the report's charts as SVG and PNG",
        goes_to: "documents and slides",
    },
];

/// `meshes/` is written on request (`--ply`) only; the guide names it too.
pub const PER_FRAME_MESHES: FileUse = FileUse {
    file: MESHES_FOLDER,
    holds: "one PLY per frame (with --ply)",
    goes_to: "MeshLab, CloudCompare, Open3D",
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_readme_lists_every_file_of_the_guide() {
        let readme = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"),
        )
        .unwrap();
        let table: Vec<&str> = readme
            .lines()
            .skip_while(|l| !l.starts_with("| file | holds | goes to |"))
            .take_while(|l| l.starts_with('|'))
            .collect();
        assert!(
            !table.is_empty(),
            "the README has no files-and-where-they-go table"
        );
        for row in FILE_GUIDE.iter().chain([&PER_FRAME_MESHES]) {
            assert!(
                table
                    .iter()
                    .any(|l| l.starts_with(&format!("| `{}` |", row.file))),
                "the README's table lacks {}",
                row.file
            );
        }
    }
}
