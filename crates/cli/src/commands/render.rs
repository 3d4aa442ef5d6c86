//! `visage render`: colour and depth images of a mesh (paper §6, Algorithm 3).
//!
//! Flags are parsed in two stages: [`RenderArgs`] (raw, clap) → [`RenderConfig`] (validated,
//! files loaded); the libraries do the work.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use visage_camera::{write_depth_png, DepthKind, Intrinsics};
use visage_mesh::TriMesh;
use visage_render::{
    projective_uvs, turntable, write_srgb_png, Albedo, Camera, CullMode, Frame, Mat4, Material,
    Renderer, Scene, Texture, UNLIT,
};

/// Depth PNG scale: stored value = metres × 1000 (millimetres), what `visage fuse --depth` reads.
const DEPTH_PNG_SCALE: f64 = 1000.0;

/// Colour output written when neither `--out` nor `--depth-out` is given.
const DEFAULT_OUT: &str = "render.png";

/// Render a mesh (OBJ or PLY) to a colour PNG and/or a 16-bit depth PNG.
///
/// Without `--pose` the camera sits at the origin looking down +z and mesh coordinates are
/// camera coordinates (metres, x right, y down), as `visage fuse` writes them.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The mesh to render (.obj or .ply), or a run's point cache (OUT/sequence.pc2, with the
    /// mesh.obj beside it) with --frame.
    pub mesh: PathBuf,
    /// With a point cache: the sample to render (the input frame index when the run kept
    /// every frame).
    #[arg(long)]
    pub frame: Option<usize>,
    /// Camera intrinsics JSON: {"width", "height", "fx", "fy", "cx", "cy"} (pixels).
    #[arg(long)]
    pub intrinsics: PathBuf,
    /// World → camera pose JSON: {"rotation": [[...], [...], [...]], "translation": [x, y, z]}.
    #[arg(long)]
    pub pose: Option<PathBuf>,
    /// Texture image (PNG/JPEG, sRGB). Sampled at the mesh's UVs, or projectively with
    /// `--projective`.
    #[arg(long)]
    pub texture: Option<PathBuf>,
    /// Texture coordinates = where each vertex projects in the texture image seen by this camera
    /// (colour a reconstruction from its own video frame).
    #[arg(long, requires = "texture")]
    pub projective: bool,
    /// Colour PNG (8-bit sRGB). Default: render.png when no --depth-out is given.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// 16-bit depth PNG in millimetres, 0 = background.
    #[arg(long)]
    pub depth_out: Option<PathBuf>,
    /// What the depth PNG stores: z coordinate or distance along the ray.
    #[arg(long, value_enum, default_value_t = DepthKindArg::Z)]
    pub depth_kind: DepthKindArg,
    /// Several views, e.g. `turntable:8` (spin about the vertical axis through the mesh centre);
    /// outputs get a `_NNN` suffix. The views discard triangles facing away from the camera (as
    /// --cull-back): a face mesh is an open mask, whose inside seen from behind would look like
    /// a face.
    #[arg(long)]
    pub views: Option<String>,
    /// Multiply mesh coordinates by this factor first (e.g. 0.01 for a mesh in centimetres).
    #[arg(long, default_value_t = 1.0)]
    pub mesh_scale: f64,
    /// Show the surface colour without lighting.
    #[arg(long)]
    pub unlit: bool,
    /// Discard triangles facing away from the camera.
    #[arg(long)]
    pub cull_back: bool,
}

/// `--depth-kind` values.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum DepthKindArg {
    /// The z coordinate (Kinect/RealSense convention).
    Z,
    /// Euclidean distance from the camera centre.
    Ray,
}

/// Validated configuration: every file read, every parameter checked.
pub struct RenderConfig {
    mesh: TriMesh,
    camera: Camera,
    texture: Option<Texture>,
    out: Option<PathBuf>,
    depth_out: Option<PathBuf>,
    kind: DepthKind,
    views: usize,
    unlit: bool,
    cull: CullMode,
}

impl RenderConfig {
    /// Reads and checks everything `args` names.
    pub fn from_args(args: RenderArgs) -> anyhow::Result<RenderConfig> {
        let mut mesh = visage::run_folder::read_mesh_or_cache(&args.mesh, args.frame)?;
        if mesh.vertices.is_empty() || mesh.triangles.is_empty() {
            bail!(
                "{}: the mesh is empty ({} vertices, {} triangles): nothing to render",
                args.mesh.display(),
                mesh.vertices.len(),
                mesh.triangles.len()
            );
        }
        if !(args.mesh_scale.is_finite() && args.mesh_scale > 0.0) {
            bail!(
                "--mesh-scale {} must be positive and finite",
                args.mesh_scale
            );
        }
        if args.mesh_scale != 1.0 {
            mesh.vertices
                .iter_mut()
                .for_each(|p| *p = p.map(|c| c * args.mesh_scale));
        }
        let k = Intrinsics::load_json(&args.intrinsics)
            .with_context(|| format!("{}", args.intrinsics.display()))?;
        let mut camera =
            Camera::new(k).with_context(|| format!("{}", args.intrinsics.display()))?;
        if let Some(path) = &args.pose {
            camera = camera
                .with_pose(visage_camera::RigidTransform::load_json(path)?)
                .with_context(|| format!("{}", path.display()))?;
        }
        let texture = match &args.texture {
            Some(path) => {
                let t = Texture::load(path)?;
                if args.projective {
                    if (t.width(), t.height()) != (k.width, k.height) {
                        bail!(
                            "{}: projective texturing needs the frame the intrinsics describe ({}×{}), the image is {}×{}",
                            path.display(),
                            k.width,
                            k.height,
                            t.width(),
                            t.height()
                        );
                    }
                    mesh.uvs = projective_uvs(&mesh.vertices, &k, &Mat4::from_rigid(&camera.pose));
                } else if mesh.uvs.is_empty() {
                    bail!(
                        "{}: the mesh has no texture coordinates; add --projective to take them from the camera",
                        args.mesh.display()
                    );
                }
                Some(t)
            }
            None => None,
        };
        let views = match args.views.as_deref() {
            None => 1,
            Some(spec) => parse_views(spec)?,
        };
        let out = match (&args.out, &args.depth_out) {
            (None, None) => Some(PathBuf::from(DEFAULT_OUT)),
            (out, _) => out.clone(),
        };
        Ok(RenderConfig {
            mesh,
            camera,
            texture,
            out,
            depth_out: args.depth_out,
            kind: match args.depth_kind {
                DepthKindArg::Z => DepthKind::Z,
                DepthKindArg::Ray => DepthKind::Ray,
            },
            views,
            unlit: args.unlit,
            // A reconstructed face is an open mask: from behind, its lit inside reads as a face.
            cull: if args.cull_back || args.views.is_some() {
                CullMode::Back
            } else {
                CullMode::None
            },
        })
    }
}

/// `turntable:N` with `1 ≤ N ≤ 3600`.
fn parse_views(spec: &str) -> anyhow::Result<usize> {
    let n = spec
        .strip_prefix("turntable:")
        .and_then(|n| n.parse::<usize>().ok())
        .filter(|n| (1..=3600).contains(n));
    n.with_context(|| format!("--views {spec:?}: expected turntable:N with N between 1 and 3600"))
}

/// `color.png` → `color_007.png` when there are several views.
fn numbered(path: &Path, view: usize, views: usize) -> PathBuf {
    if views == 1 {
        return path.to_owned();
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match path.extension() {
        Some(ext) => format!("{stem}_{view:03}.{}", ext.to_string_lossy()),
        None => format!("{stem}_{view:03}"),
    };
    path.with_file_name(name)
}

/// Runs `visage render`.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let cfg = RenderConfig::from_args(args)?;
    let k = cfg.camera.intrinsics;
    let scene = Scene {
        material: if cfg.unlit {
            UNLIT
        } else {
            Material::default()
        },
        albedo: Albedo::for_mesh(&cfg.mesh, cfg.texture.as_ref()),
        cull: cfg.cull,
        ..Scene::default()
    };
    let models = if cfg.views == 1 {
        vec![Mat4::IDENTITY]
    } else {
        turntable(&cfg.mesh.vertices, cfg.views)
    };
    let mut renderer = Renderer::new();
    let mut frame = Frame::new(k.width, k.height, cfg.kind);
    for (view, model) in models.iter().enumerate() {
        renderer.render(&cfg.mesh, &cfg.camera, model, &scene, &mut frame)?;
        if let Some(out) = &cfg.out {
            write_srgb_png(
                &numbered(out, view, cfg.views),
                k.width,
                k.height,
                &frame.color,
            )?;
        }
        if let Some(out) = &cfg.depth_out {
            write_depth_png(
                &numbered(out, view, cfg.views),
                &frame.depth,
                DEPTH_PNG_SCALE,
            )?;
        }
        if frame.depth.valid_count() == 0 {
            eprintln!(
                "warning: view {view}: the mesh is not visible from this camera (empty image)"
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_specs_and_numbered_outputs() {
        assert_eq!(parse_views("turntable:12").unwrap(), 12);
        assert!(parse_views("turntable:0").is_err());
        assert!(parse_views("orbit:3").is_err());
        assert_eq!(
            numbered(Path::new("a/c.png"), 3, 8),
            PathBuf::from("a/c_003.png")
        );
        assert_eq!(
            numbered(Path::new("a/c.png"), 0, 1),
            PathBuf::from("a/c.png")
        );
    }
}
