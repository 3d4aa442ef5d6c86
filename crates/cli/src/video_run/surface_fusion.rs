//! The two fusion designs of `visage run` behind one type: the face-anchored mesh with the
//! pose-compensated temporal term (`--mesh face`, [`visage_pipeline::AnchoredFuser`]) and the
//! paper's fixed image-plane mesh (`--mesh image`, [`visage_pipeline::Fuser`] on a domain fixed
//! by the first frame with a face, see [`super::image_domain`]).
//!
//! Both give, per frame, the fused and the raw surface on their mesh (camera coordinates,
//! metres) and both surfaces at the 468 landmarks — face mode: vertices `0..468` (domain vertex
//! `i < 468` is landmark `i`); image mode: each landmark pixel located in the planar mesh and
//! the surface interpolated barycentrically — so the designs are compared on the same points.

use anyhow::Context;
use faer::Mat;
use visage_camera::{DepthMap, Intrinsics, RigidTransform};
use visage_face::CanonicalMesh;
use visage_fem::{
    solve_clip, ClipOptions, ClipReport, FusionSystem, SurfaceMetrics, SurfaceQuality, Weights,
};
use visage_pipeline::{
    to_positions, AnchoredFrame, AnchoredFuser, FaceDomain, FrameDepth, FrameStatus, Fuser,
    FusionSetup, MeshingOptions,
};

use super::image_domain::{dilated_face_mask, dilation_radius};
use super::point_locator::PointLocator;

/// Which mesh carries the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshKind {
    /// Face-anchored (FaceMesh template, subdivided), pose-compensated temporal term.
    Face,
    /// The paper's fixed image-plane mesh.
    Image,
}

/// Fusion parameters of a run.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct FusionParams {
    pub mesh: MeshKind,
    /// λ (face: mm⁴ of the canonical face; image: reference pixels⁴) and μ.
    pub weights: Weights,
    /// Face mode: subdivision factor of the FaceMesh template.
    pub subdivision: usize,
    /// Image mode: meshing of the fixed domain.
    pub meshing: MeshingOptions,
    /// Depth beyond this (metres) counts as missing.
    pub max_depth_m: f64,
}

/// One frame's input to the fusion: the tracked face and its depth.
pub struct FaceFrame<'a> {
    /// The 468 landmark pixels.
    pub landmarks_px: &'a [[f64; 2]],
    /// Head pose (canonical face → camera).
    pub pose: RigidTransform,
    /// The metric landmarks of the face fit (the face CNN's surface).
    pub metric_landmarks: &'a [[f64; 3]],
    /// The frame's depth map: `--depth DIR`, or image mode's rendered face depth.
    pub depth_map: Option<&'a DepthMap>,
    /// The rendered face depth (its mask) and face box, needed by image mode's first frame.
    pub face_mask: Option<(&'a DepthMap, [f32; 4])>,
}

/// What fusing a frame gave.
#[derive(Clone, Copy, Debug)]
pub struct FusedFrame {
    pub status: FrameStatus,
    pub valid_fraction: f64,
    pub relative_residual: f64,
    pub raw_quality: SurfaceQuality,
    pub fused_quality: SurfaceQuality,
}

/// A frame kept for clip mode: its data right-hand side, streaming solution (initial guess),
/// pose, raw surface and landmark pixels.
pub struct ClipFrame {
    pub b: Mat<f64>,
    pub x: Mat<f64>,
    pub pose: RigidTransform,
    pub raw: Vec<[f64; 3]>,
    pub landmarks_px: Vec<[f64; 2]>,
}

struct ImagePlane {
    fuser: Fuser,
    locator: PointLocator,
}

enum Design {
    Face(Box<AnchoredFuser>),
    /// Built on the first frame with a face.
    Image(Option<Box<ImagePlane>>),
}

/// The fusion of a run (either design), its output buffers and quality evaluator.
pub struct SurfaceFusion {
    design: Design,
    params: FusionParams,
    k: Intrinsics,
    metrics: Option<SurfaceMetrics>,
    fused: Vec<[f64; 3]>,
    raw: Vec<[f64; 3]>,
}

impl SurfaceFusion {
    /// Face mode builds and factors its operators now; image mode on its first frame.
    pub fn new(
        params: FusionParams,
        canonical: &CanonicalMesh,
        k: Intrinsics,
    ) -> anyhow::Result<SurfaceFusion> {
        let design = match params.mesh {
            MeshKind::Face => {
                let domain = FaceDomain::subdivide(
                    canonical.vertices.len(),
                    &canonical.triangles,
                    params.subdivision,
                )?;
                Design::Face(Box::new(AnchoredFuser::new(
                    domain,
                    &canonical.vertices,
                    k,
                    params.weights,
                    params.max_depth_m,
                )?))
            }
            MeshKind::Image => Design::Image(None),
        };
        let mut fusion = SurfaceFusion {
            design,
            params,
            k,
            metrics: None,
            fused: Vec::new(),
            raw: Vec::new(),
        };
        if let Design::Face(f) = &fusion.design {
            let d = f.domain();
            fusion.metrics = Some(SurfaceMetrics::new(
                d.vertex_count(),
                &d.triangles,
                &d.boundary,
            ));
            fusion.fused = vec![[0.0; 3]; d.vertex_count()];
            fusion.raw = vec![[0.0; 3]; d.vertex_count()];
        }
        Ok(fusion)
    }

    /// The mesh's triangles, once the mesh exists (image mode: after the first face).
    pub fn triangles(&self) -> Option<&[[u32; 3]]> {
        match &self.design {
            Design::Face(f) => Some(&f.domain().triangles),
            Design::Image(Some(p)) => Some(&p.fuser.setup().mesh.triangles),
            Design::Image(None) => None,
        }
    }

    /// Which design this is.
    pub fn mesh(&self) -> MeshKind {
        self.params.mesh
    }

    /// Vertices of the mesh (0 before image mode's first face).
    pub fn vertex_count(&self) -> usize {
        self.fused.len()
    }

    /// Whether the image domain needs `FaceFrame::face_mask` on the next frame (image mode's
    /// first face).
    pub fn needs_face_mask(&self) -> bool {
        matches!(self.design, Design::Image(None))
    }

    /// Forgets the temporal history (the face was lost).
    pub fn reset(&mut self) {
        match &mut self.design {
            Design::Face(f) => f.reset(),
            Design::Image(Some(p)) => p.fuser.solver_mut().reset(),
            Design::Image(None) => {}
        }
    }

    /// The last fused surface (#V, camera coordinates, metres).
    pub fn fused(&self) -> &[[f64; 3]] {
        &self.fused
    }

    /// The last raw surface on the same mesh (holes as the solver filled them).
    pub fn raw(&self) -> &[[f64; 3]] {
        &self.raw
    }

    /// Fuses one frame. Allocation-free in face mode; image mode builds its mesh and factors
    /// its system on its first frame (counted in that frame's fusion time) and allocates when
    /// in-painting a frame without predecessor.
    pub fn process(&mut self, frame: &FaceFrame<'_>) -> anyhow::Result<FusedFrame> {
        if let Design::Image(None) = self.design {
            self.build_image_plane(frame)?;
        }
        let (status, valid_fraction, relative_residual) = match &mut self.design {
            Design::Face(f) => {
                let depth = match frame.depth_map {
                    Some(map) => FrameDepth::Map(map),
                    None => FrameDepth::Surface(frame.metric_landmarks),
                };
                let r = f.process(&AnchoredFrame {
                    landmarks_px: frame.landmarks_px,
                    pose: frame.pose,
                    depth,
                })?;
                self.fused.copy_from_slice(f.solution());
                self.raw.copy_from_slice(f.raw());
                (r.status, r.valid_fraction, r.relative_residual)
            }
            Design::Image(Some(p)) => {
                let depth = frame
                    .depth_map
                    .context("image mode needs a depth map per frame")?;
                let r = p.fuser.process(depth);
                to_positions(p.fuser.solution(), &mut self.fused);
                to_positions(p.fuser.raw(), &mut self.raw);
                (r.status, r.valid_fraction, r.relative_residual)
            }
            Design::Image(None) => unreachable!("built above"),
        };
        let (raw_quality, fused_quality) = if status == FrameStatus::NoData {
            let zero = SurfaceQuality {
                mean_abs_h: 0.0,
                roughness: 0.0,
            };
            (zero, zero)
        } else {
            self.quality()
        };
        Ok(FusedFrame {
            status,
            valid_fraction,
            relative_residual,
            raw_quality,
            fused_quality,
        })
    }

    /// Mean |H| and roughness (ERRATA 13) of the current raw and fused surfaces.
    fn quality(&mut self) -> (SurfaceQuality, SurfaceQuality) {
        match &mut self.metrics {
            Some(m) => (m.evaluate(&self.raw), m.evaluate(&self.fused)),
            None => unreachable!("metrics exist once a mesh does"),
        }
    }

    /// The fused and raw surfaces at the 468 landmark pixels `landmarks_px` (NaN where a
    /// landmark falls outside image mode's mesh).
    pub fn landmark_points(
        &self,
        landmarks_px: &[[f64; 2]],
        fused: &mut Vec<[f64; 3]>,
        raw: &mut Vec<[f64; 3]>,
    ) {
        fused.clear();
        raw.clear();
        match &self.design {
            Design::Face(_) => {
                fused.extend_from_slice(&self.fused[..landmarks_px.len()]);
                raw.extend_from_slice(&self.raw[..landmarks_px.len()]);
            }
            Design::Image(Some(p)) => {
                for &px in landmarks_px {
                    let missing = [f64::NAN; 3];
                    fused.push(p.locator.interpolate(&self.fused, px).unwrap_or(missing));
                    raw.push(p.locator.interpolate(&self.raw, px).unwrap_or(missing));
                }
            }
            Design::Image(None) => {}
        }
    }

    /// The state clip mode keeps for the current (just fused) frame.
    pub fn clip_frame(&self, landmarks_px: &[[f64; 2]]) -> ClipFrame {
        let (b, x, pose) = match &self.design {
            Design::Face(f) => (f.rhs().to_owned(), f.solution_head().to_owned(), *f.pose()),
            Design::Image(Some(p)) => (
                p.fuser.rhs().to_owned(),
                p.fuser.solution().to_owned(),
                RigidTransform::IDENTITY,
            ),
            Design::Image(None) => (Mat::zeros(0, 3), Mat::zeros(0, 3), RigidTransform::IDENTITY),
        };
        ClipFrame {
            b,
            x,
            pose,
            raw: self.raw.clone(),
            landmarks_px: landmarks_px.to_vec(),
        }
    }

    /// Solves the clip system (ERRATA 1) over `frames` — consecutive frames of one track — on
    /// the streaming factorisation; their `x` hold the solutions afterwards (face mode: head
    /// coordinates).
    pub fn solve_clip(&mut self, frames: &mut [ClipFrame], options: &ClipOptions) -> ClipReport {
        let take = |m: &mut Mat<f64>| std::mem::replace(m, Mat::new());
        let b: Vec<Mat<f64>> = frames.iter_mut().map(|f| take(&mut f.b)).collect();
        let mut x: Vec<Mat<f64>> = frames.iter_mut().map(|f| take(&mut f.x)).collect();
        let system: &mut FusionSystem = match &mut self.design {
            Design::Face(f) => f.solver_mut().system_mut(),
            Design::Image(Some(p)) => p.fuser.solver_mut().system_mut(),
            Design::Image(None) => {
                return ClipReport {
                    iterations: 0,
                    relative_residual: 0.0,
                    converged: true,
                }
            }
        };
        let report = solve_clip(system, &b, &mut x, options);
        for (f, x) in frames.iter_mut().zip(x) {
            f.x = x;
        }
        report
    }

    /// Loads a clip-solved frame as the current surface (fused = the clip solution in camera
    /// coordinates, raw = the frame's raw surface) and returns its quality.
    pub fn load_clip_frame(&mut self, frame: &ClipFrame) -> (SurfaceQuality, SurfaceQuality) {
        match &mut self.design {
            Design::Face(f) => {
                f.set_solution_head(&frame.x, frame.pose);
                self.fused.copy_from_slice(f.solution());
            }
            Design::Image(Some(_)) => to_positions(frame.x.as_ref(), &mut self.fused),
            Design::Image(None) => {}
        }
        self.raw.copy_from_slice(&frame.raw);
        self.quality()
    }

    fn build_image_plane(&mut self, frame: &FaceFrame<'_>) -> anyhow::Result<()> {
        let (face_depth, face_box) = frame
            .face_mask
            .context("image mode's first frame needs the face mask")?;
        let reference = frame.depth_map.unwrap_or(face_depth);
        let domain = dilated_face_mask(face_depth, dilation_radius(face_box));
        let setup = FusionSetup::new(&self.k, &domain, reference, &self.params.meshing)
            .context("cannot mesh the image-plane domain of the first face")?;
        let system = FusionSystem::new(setup.ops.clone(), self.params.weights)?;
        let locator = PointLocator::new(
            &setup.mesh.points,
            &setup.mesh.triangles,
            2.0 * self.params.meshing.spacing as f64,
        );
        let n = setup.vertex_count();
        self.metrics = Some(SurfaceMetrics::new(
            n,
            &setup.mesh.triangles,
            &setup.boundary,
        ));
        let fuser = Fuser::new(setup, system, self.params.max_depth_m);
        self.fused = vec![[0.0; 3]; n];
        self.raw = vec![[0.0; 3]; n];
        self.design = Design::Image(Some(Box::new(ImagePlane { fuser, locator })));
        Ok(())
    }
}
