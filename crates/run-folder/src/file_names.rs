//! The one table of what a run's output folder holds: every file and folder name that a run,
//! `visage export` and the batch worker write. Code that reads or writes one of them names it
//! from here; [`OUTPUT_FILES`] and [`OUTPUT_FOLDERS`] are what a run may replace or remove.

/// The point cache: the fused surface per frame (`visage run`).
pub const POINT_CACHE: &str = "sequence.pc2";
/// The point cache with every frame filled, while it is being written (the frames without a
/// mesh hold the nearest earlier one); renamed to [`POINT_CACHE`] when the run finishes.
pub const POINT_CACHE_FILLED: &str = "sequence.pc2.filled.tmp";
/// The point cache's mesh: the fixed topology with UVs.
pub const CACHE_MESH: &str = "mesh.obj";
/// The point cache's material.
pub const CACHE_MATERIAL_FILE: &str = "mesh.mtl";
/// Every frame's landmarks, head pose and fused landmarks.
pub const LANDMARKS: &str = "landmarks.json";
/// The run's status, parameters, per-frame and summary figures.
pub const METRICS: &str = "metrics.json";
/// The camera's intrinsics.
pub const CAMERA: &str = "camera.json";
/// The ARKit curves as a Live Link Face CSV.
pub const BLENDSHAPES_CSV: &str = "blendshapes.csv";
/// The ARKit curves as compact JSON.
pub const BLENDSHAPES_JSON: &str = "blendshapes.json";
/// The fitted neutral face.
pub const IDENTITY_MESH: &str = "identity.obj";
/// The identity's coefficients.
pub const IDENTITY: &str = "identity.json";
/// The face's texture fused from the frames (an export).
pub const TEXTURE: &str = "texture.png";
/// The animated glTF (an export).
pub const GLB: &str = "sequence.glb";
/// The HTML report (an export).
pub const REPORT: &str = "report.html";
/// The preview video (an export).
pub const PREVIEW: &str = "preview.mp4";
/// What the exports were made with and of.
pub const EXPORT: &str = "export.json";
/// The faces a run over every face found, one subfolder each.
pub const FACES: &str = "faces.json";

/// Per-frame meshes (`NNNNNN.ply`), with `--ply`.
pub const MESHES_FOLDER: &str = "meshes";
/// Per-frame raw (unfused) meshes, with `--ply raw`.
pub const RAW_FOLDER: &str = "raw";
/// Per-frame and per-shape plots (an export).
pub const PLOTS_FOLDER: &str = "plots";
/// Renders of chosen frames (an export).
pub const FRAMES_FOLDER: &str = "frames";

/// The prefix of the per-face subfolders of a run over every face (`face-1`, `face-2`, …).
pub const FACE_FOLDER_PREFIX: &str = "face-";

/// In a batch's clip folder: what was made from what, with checksums (a finished clip).
pub const BATCH_DONE: &str = "done.json";
/// In a batch's clip folder: why the clip failed.
pub const BATCH_ERROR: &str = "error.json";
/// In a batch folder: the batch's manifest, options and shard count.
pub const BATCH: &str = "batch.json";
/// In a batch folder: the clips being processed, each renamed to its id when done.
pub const BATCH_PARTIAL_FOLDER: &str = ".partial";

/// The lock file: held by the one process writing into the folder, naming it; it stays in
/// the folder, marking it as one visage wrote to (never removed by `--overwrite`).
pub const LOCK: &str = ".visage.lock";

/// The suffix of a file being written (renamed to its name once complete).
pub const TMP_SUFFIX: &str = ".tmp";

/// The files a run and `visage export` write at the top of an output folder.
pub const OUTPUT_FILES: [&str; 16] = [
    POINT_CACHE,
    CACHE_MESH,
    CACHE_MATERIAL_FILE,
    LANDMARKS,
    METRICS,
    CAMERA,
    BLENDSHAPES_CSV,
    BLENDSHAPES_JSON,
    IDENTITY_MESH,
    IDENTITY,
    TEXTURE,
    GLB,
    REPORT,
    PREVIEW,
    EXPORT,
    FACES,
];

/// The folders a run and `visage export` write in an output folder.
pub const OUTPUT_FOLDERS: [&str; 4] = [MESHES_FOLDER, RAW_FOLDER, PLOTS_FOLDER, FRAMES_FOLDER];
