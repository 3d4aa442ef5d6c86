//! The fusion designs of a video run behind one type: the face-anchored mesh with the
//! pose-compensated temporal term on MediaPipe's canonical face ([`MeshKind::Face`],
//! [`AnchoredFuser`]) or on the fitted morphable model's face ([`MeshKind::Model`], the same
//! fuser with the frame's fitted face as its template), and the paper's fixed image-plane mesh
//! ([`MeshKind::Image`], [`ImagePlaneFuser`] on a domain fixed by the first frame with a face,
//! see [`crate::image_domain`]).
//!
//! All give, per frame, the fused and the raw surface on their mesh (camera coordinates,
//! metres) and both surfaces at the 468 landmarks — face mesh: vertices `0..468` (domain
//! vertex `i < 468` is landmark `i`); model mesh: the landmarks' points on the model
//! ([`LandmarkAnchor`]); image mesh: each landmark pixel located in the planar mesh and the
//! surface interpolated barycentrically — so the designs are compared on the same points.

use faer::Mat;
use serde::Serialize;
use visage_camera::{DepthMap, Intrinsics, RigidTransform};
use visage_fem::{
    boundary_vertices, ClipOptions, ClipReport, FairingSystem, FusionSystem, Preconditioner,
    SurfaceMetrics, SurfaceQuality, Weights,
};

use crate::image_domain::{dilated_face_mask, dilation_radius};
use crate::point_locator::PointLocator;
use crate::{
    solve_clip_frames, AnchoredFrame, AnchoredFuser, ClipFrame, ClipState, FaceDomain, FrameDepth,
    FrameStatus, FusedFrame, FusionError, FusionSetup, ImagePlaneFuser, MeshingOptions,
    SurfaceFuser,
};

/// Which mesh carries the surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshKind {
    /// Face-anchored (the FaceMesh template, subdivided), pose-compensated temporal term.
    #[default]
    Face,
    /// The paper's fixed image-plane mesh.
    Image,
    /// Face-anchored on the morphable model's face region, each frame's fitted face as the
    /// template (this person's identity and the frame's expression).
    Model,
}

/// Fusion parameters of a video run.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FusionParams {
    pub mesh: MeshKind,
    /// λ (face mesh: mm⁴ of the canonical face; image mesh: reference pixels⁴) and μ.
    pub weights: Weights,
    /// Face mesh: subdivision factor of the FaceMesh template.
    pub subdivision: usize,
    /// Image mesh: meshing of the fixed domain.
    pub meshing: MeshingOptions,
    /// Depth beyond this (metres) counts as missing.
    pub max_depth_m: f64,
    /// Fair each fused surface with this γ (1/m⁴; paper §5), or not.
    pub fairing_gamma: Option<f64>,
}

/// The face template a face-anchored mesh is built on: the canonical FaceMesh's vertices
/// (head coordinates, metres; vertex `i` is landmark `i`) and triangles, or the morphable
/// model's neutral face with where the landmarks lie on it.
#[derive(Clone, Copy, Debug)]
pub struct FaceTemplate<'a> {
    pub vertices: &'a [[f64; 3]],
    pub triangles: &'a [[u32; 3]],
    /// Where each of the 468 landmarks lies on the template; `None`: vertex `i` is landmark
    /// `i`.
    pub landmarks: Option<&'a [LandmarkAnchor]>,
    /// Texture coordinates per template vertex (empty: none).
    pub uvs: &'a [[f64; 2]],
}

/// A landmark's point on a template: `Σ_j bary[j] · vertex[triangle[j]] + offset` (offset in
/// head coordinates, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LandmarkAnchor {
    pub triangle: [u32; 3],
    pub bary: [f64; 3],
    pub offset: [f64; 3],
}

/// The morphable model fitted to a frame: what the model mesh fuses on, and the model depth.
#[derive(Clone, Copy, Debug)]
pub struct ModelFrame<'a> {
    /// Model (head) coordinates → camera.
    pub pose: RigidTransform,
    /// The fitted face (identity and expression), head coordinates, metres, one point per
    /// model vertex.
    pub shape: &'a [[f64; 3]],
    /// The same in camera coordinates.
    pub camera: &'a [[f64; 3]],
    /// Their projections, pixels.
    pub pixels: &'a [[f64; 2]],
}

/// One frame's input to the fusion: the tracked face and its depth.
pub struct FaceFrame<'a> {
    /// The 468 landmark pixels.
    pub landmarks_px: &'a [[f64; 2]],
    /// Head pose (canonical face → camera).
    pub pose: RigidTransform,
    /// The metric landmarks of the face fit (the face CNN's surface).
    pub metric_landmarks: &'a [[f64; 3]],
    /// The frame's depth map: a depth folder's, or the image mesh's rendered face depth.
    pub depth_map: Option<&'a DepthMap>,
    /// The rendered face depth (its mask) and face box `[x, y, w, h]` (pixels), needed by the
    /// image mesh's first frame.
    pub face_mask: Option<(&'a DepthMap, [f32; 4])>,
    /// The morphable model fitted to the frame (needed by the model mesh).
    pub model: Option<ModelFrame<'a>>,
}

/// What fusing a frame gave: the fuser's record and the raw and fused surfaces' quality.
#[derive(Clone, Copy, Debug)]
pub struct FusedSurfaces {
    pub frame: FusedFrame,
    pub raw_quality: SurfaceQuality,
    /// The result's: the faired surface's when fairing is on.
    pub fused_quality: SurfaceQuality,
    /// Conjugate-gradient iterations of the fairing, when on.
    pub fairing_iterations: Option<usize>,
}

/// Fairing after the fusion (paper §5): the system measured on a track's first fused surface
/// (a head's rigid motion leaves `L` and `A` unchanged) and factored once, then one solve per
/// frame from the previous result.
struct Fairing {
    gamma: f64,
    system: Option<FairingSystem>,
    metrics: Option<SurfaceMetrics>,
    /// The last faired surface (empty: none yet in this track).
    surface: Vec<[f64; 3]>,
}

/// Relative residual the per-frame fairing solves to.
const FAIRING_TOLERANCE: f64 = 1e-10;

struct ImagePlane {
    fuser: ImagePlaneFuser,
    locator: PointLocator,
}

enum Design {
    Face(Box<AnchoredFuser>),
    /// The anchored fuser on the model, and where the landmarks lie on it.
    Model(Box<AnchoredFuser>, Vec<LandmarkAnchor>),
    /// Built on the first frame with a face.
    Image(Option<Box<ImagePlane>>),
}

/// The fusion of a video run (either design).
pub struct SurfaceFusion {
    design: Design,
    params: FusionParams,
    k: Intrinsics,
    /// Texture coordinates per mesh vertex (empty: none).
    uvs: Vec<[f64; 2]>,
    fairing: Option<Fairing>,
}

/// Quality figures of a frame without a surface.
const NO_SURFACE: SurfaceQuality = SurfaceQuality {
    mean_abs_h: 0.0,
    roughness: 0.0,
};

impl SurfaceFusion {
    /// The face mesh builds and factors its operators now; the image mesh on its first frame.
    pub fn new(
        params: FusionParams,
        template: FaceTemplate<'_>,
        k: Intrinsics,
    ) -> Result<SurfaceFusion, FusionError> {
        let design = match params.mesh {
            MeshKind::Face => {
                let domain = FaceDomain::subdivide(
                    template.vertices.len(),
                    template.triangles,
                    params.subdivision,
                )?;
                Design::Face(Box::new(AnchoredFuser::new(
                    domain,
                    template.vertices,
                    k,
                    params.weights,
                    params.max_depth_m,
                )?))
            }
            MeshKind::Model => {
                let landmarks = template.landmarks.ok_or(FusionError::MissingInput {
                    what: "the model mesh needs the landmarks' places on the model",
                })?;
                let domain = FaceDomain::subdivide(template.vertices.len(), template.triangles, 1)?;
                Design::Model(
                    Box::new(AnchoredFuser::new(
                        domain,
                        template.vertices,
                        k,
                        params.weights,
                        params.max_depth_m,
                    )?),
                    landmarks.to_vec(),
                )
            }
            MeshKind::Image => Design::Image(None),
        };
        let uvs = match &design {
            Design::Face(f) | Design::Model(f, _)
                if template.uvs.len() == template.vertices.len() =>
            {
                f.domain()
                    .anchors
                    .iter()
                    .map(|a| {
                        let t = f.domain().template_triangles[a.triangle as usize];
                        std::array::from_fn(|c| {
                            (0..3)
                                .map(|j| a.bary[j] * template.uvs[t[j] as usize][c])
                                .sum()
                        })
                    })
                    .collect()
            }
            _ => Vec::new(),
        };
        let fairing = params.fairing_gamma.map(|gamma| Fairing {
            gamma,
            system: None,
            metrics: None,
            surface: Vec::new(),
        });
        Ok(SurfaceFusion {
            design,
            params,
            k,
            uvs,
            fairing,
        })
    }

    /// Texture coordinates per mesh vertex, interpolated from the template's (empty for the
    /// image-plane mesh, or a template without them).
    pub fn uvs(&self) -> &[[f64; 2]] {
        &self.uvs
    }

    /// The built fuser, if any (the image mesh has none before its first face).
    fn fuser(&self) -> Option<&dyn SurfaceFuser> {
        match &self.design {
            Design::Face(f) | Design::Model(f, _) => Some(f.as_ref()),
            Design::Image(Some(p)) => Some(&p.fuser),
            Design::Image(None) => None,
        }
    }

    fn fuser_mut(&mut self) -> Option<&mut dyn SurfaceFuser> {
        match &mut self.design {
            Design::Face(f) | Design::Model(f, _) => Some(f.as_mut()),
            Design::Image(Some(p)) => Some(&mut p.fuser),
            Design::Image(None) => None,
        }
    }

    /// The mesh's triangles, once the mesh exists (image mesh: after the first face).
    pub fn triangles(&self) -> Option<&[[u32; 3]]> {
        self.fuser().map(|f| f.triangles())
    }

    /// Which design this is.
    pub fn mesh(&self) -> MeshKind {
        self.params.mesh
    }

    /// The fusion parameters.
    pub fn params(&self) -> &FusionParams {
        &self.params
    }

    /// Vertices of the mesh (0 before the image mesh's first face).
    pub fn vertex_count(&self) -> usize {
        self.fused().len()
    }

    /// Whether the next frame needs [`FaceFrame::face_mask`] (the image mesh's first face).
    pub fn needs_face_mask(&self) -> bool {
        matches!(self.design, Design::Image(None))
    }

    /// Forgets the temporal history (the face was lost).
    pub fn reset(&mut self) {
        if let Some(f) = self.fuser_mut() {
            f.reset();
        }
        if let Some(fairing) = &mut self.fairing {
            fairing.surface.clear();
        }
    }

    /// The last fused surface (#V, camera coordinates, metres): the faired one when fairing
    /// is on.
    pub fn fused(&self) -> &[[f64; 3]] {
        match &self.fairing {
            Some(f) if !f.surface.is_empty() => &f.surface,
            _ => self.fuser().map_or(&[], |f| f.solution()),
        }
    }

    /// The last raw surface on the same mesh (holes as the solver filled them).
    pub fn raw(&self) -> &[[f64; 3]] {
        self.fuser().map_or(&[], |f| f.raw())
    }

    /// Fuses one frame. Allocation-free with the face mesh; the image mesh builds its mesh and
    /// factors its system on its first frame and allocates when in-painting a frame without
    /// predecessor.
    ///
    /// # Errors
    /// The image mesh without a depth map (or, on its first frame, without the face mask),
    /// a domain that cannot be meshed, or a frame that does not fit the fuser.
    pub fn process(&mut self, frame: &FaceFrame<'_>) -> Result<FusedSurfaces, FusionError> {
        if let Design::Image(None) = self.design {
            self.build_image_plane(frame)?;
        }
        let fused = match &mut self.design {
            Design::Face(f) => {
                let depth = match frame.depth_map {
                    Some(map) => FrameDepth::Map(map),
                    None => FrameDepth::Surface(frame.metric_landmarks),
                };
                f.process(&AnchoredFrame {
                    landmarks_px: frame.landmarks_px,
                    pose: frame.pose,
                    depth,
                    template: None,
                })?
            }
            Design::Model(f, _) => {
                let model = frame.model.ok_or(FusionError::MissingInput {
                    what: "the model mesh needs the model fitted to every frame",
                })?;
                let depth = match frame.depth_map {
                    Some(map) => FrameDepth::Map(map),
                    None => FrameDepth::Surface(model.camera),
                };
                f.process(&AnchoredFrame {
                    landmarks_px: model.pixels,
                    pose: model.pose,
                    depth,
                    template: Some(model.shape),
                })?
            }
            Design::Image(Some(p)) => {
                let depth = frame.depth_map.ok_or(FusionError::MissingInput {
                    what: "the image-plane mesh needs a depth map per frame",
                })?;
                p.fuser.process(depth)?
            }
            Design::Image(None) => unreachable!("built above"),
        };
        let (raw_quality, mut fused_quality) = match self.fuser_mut() {
            Some(f) if fused.status != FrameStatus::NoData => f.frame_quality(),
            _ => (NO_SURFACE, NO_SURFACE),
        };
        let mut fairing_iterations = None;
        if fused.status != FrameStatus::NoData {
            if let Some((quality, iterations)) = self.fair()? {
                fused_quality = quality;
                fairing_iterations = Some(iterations);
            }
        }
        Ok(FusedSurfaces {
            frame: fused,
            raw_quality,
            fused_quality,
            fairing_iterations,
        })
    }

    /// Fairs the fuser's current solution (when fairing is on): its quality and iterations.
    fn fair(&mut self) -> Result<Option<(SurfaceQuality, usize)>, FusionError> {
        let Some(solution) = self.fuser().map(|f| f.solution().to_vec()) else {
            return Ok(None);
        };
        let triangles = match self.triangles() {
            Some(t) => t.to_vec(),
            None => return Ok(None),
        };
        let Some(fairing) = &mut self.fairing else {
            return Ok(None);
        };
        let weights = vec![1.0; solution.len()];
        if fairing.system.is_none() {
            fairing.system = Some(FairingSystem::new(
                &solution,
                &triangles,
                &weights,
                fairing.gamma,
                Preconditioner::Cholesky,
            )?);
            fairing.metrics = Some(SurfaceMetrics::new(
                solution.len(),
                &triangles,
                &boundary_vertices(solution.len(), &triangles),
            ));
        }
        let (Some(system), Some(metrics)) = (&mut fairing.system, &mut fairing.metrics) else {
            return Ok(None);
        };
        let warm = if fairing.surface.len() == solution.len() {
            std::mem::take(&mut fairing.surface)
        } else {
            solution.clone()
        };
        let (surface, iterations, _) = system.solve(&solution, &warm, FAIRING_TOLERANCE, 200);
        fairing.surface = surface;
        Ok(Some((metrics.evaluate(&fairing.surface), iterations)))
    }

    /// The fused and raw surfaces at the 468 landmark pixels `landmarks_px` (NaN where a
    /// landmark falls outside the image mesh).
    pub fn landmark_points(
        &self,
        landmarks_px: &[[f64; 2]],
        fused: &mut Vec<[f64; 3]>,
        raw: &mut Vec<[f64; 3]>,
    ) {
        fused.clear();
        raw.clear();
        match &self.design {
            Design::Face(f) => {
                fused.extend_from_slice(&self.fused()[..landmarks_px.len()]);
                raw.extend_from_slice(&f.raw()[..landmarks_px.len()]);
            }
            Design::Model(f, landmarks) => {
                let pose = f.pose();
                for a in landmarks {
                    let offset = pose.rotate(a.offset.map(|c| c * f.scale()));
                    let at = |s: &[[f64; 3]]| -> [f64; 3] {
                        std::array::from_fn(|c| {
                            (0..3)
                                .map(|j| a.bary[j] * s[a.triangle[j] as usize][c])
                                .sum::<f64>()
                                + offset[c]
                        })
                    };
                    fused.push(at(self.fused()));
                    raw.push(at(f.raw()));
                }
            }
            Design::Image(Some(p)) => {
                let missing = [f64::NAN; 3];
                for &px in landmarks_px {
                    let locate = |s: &[[f64; 3]]| p.locator.interpolate(s, px).unwrap_or(missing);
                    fused.push(locate(self.fused()));
                    raw.push(locate(p.fuser.raw()));
                }
            }
            Design::Image(None) => {}
        }
    }

    /// The state the clip solve keeps for the current (just fused) frame.
    pub fn clip_frame(&self, landmarks_px: &[[f64; 2]]) -> ClipFrame {
        let state = match self.fuser() {
            Some(f) => f.clip_state(),
            None => ClipState {
                b: Mat::zeros(0, 3),
                x: Mat::zeros(0, 3),
                pose: RigidTransform::IDENTITY,
                offset: Mat::zeros(0, 3),
            },
        };
        ClipFrame {
            state,
            raw: self.raw().to_vec(),
            landmarks_px: landmarks_px.to_vec(),
        }
    }

    /// Solves the clip system (ERRATA 1, 17) over `frames` — consecutive frames of one track —
    /// on the streaming factorisation; their states' `x` hold the solutions afterwards.
    pub fn solve_clip(&mut self, frames: &mut [ClipFrame], options: &ClipOptions) -> ClipReport {
        match self.fuser_mut() {
            Some(fuser) => solve_clip_frames(fuser, frames, options),
            None => ClipReport {
                iterations: 0,
                relative_residual: 0.0,
                converged: true,
            },
        }
    }

    /// Makes a clip-solved frame the current surface (fused = its clip solution in camera
    /// coordinates, raw = its raw surface) and returns the raw and fused quality.
    pub fn load_clip_frame(&mut self, frame: &ClipFrame) -> (SurfaceQuality, SurfaceQuality) {
        let (raw, fused) = match self.fuser_mut() {
            Some(f) => {
                f.load_clip_solution(&frame.state, &frame.raw);
                f.frame_quality()
            }
            None => return (NO_SURFACE, NO_SURFACE),
        };
        // The clip frames come in order: the previous faired surface is the warm start.
        match self.fair() {
            Ok(Some((faired, _))) => (raw, faired),
            _ => (raw, fused),
        }
    }

    fn build_image_plane(&mut self, frame: &FaceFrame<'_>) -> Result<(), FusionError> {
        let (face_depth, face_box) = frame.face_mask.ok_or(FusionError::MissingInput {
            what: "the image-plane mesh's first frame needs the face mask",
        })?;
        let reference = frame.depth_map.unwrap_or(face_depth);
        let domain = dilated_face_mask(face_depth, dilation_radius(face_box));
        let setup = FusionSetup::new(&self.k, &domain, reference, &self.params.meshing)?;
        let system = FusionSystem::new(setup.ops.clone(), self.params.weights)?;
        let locator = PointLocator::new(
            &setup.mesh.points,
            &setup.mesh.triangles,
            2.0 * self.params.meshing.spacing as f64,
        );
        let fuser = ImagePlaneFuser::new(setup, system, self.params.max_depth_m);
        self.design = Design::Image(Some(Box::new(ImagePlane { fuser, locator })));
        Ok(())
    }
}
