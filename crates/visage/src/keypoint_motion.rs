//! SIFT keypoints on the face as an independent check of the head's motion (paper §3,
//! "classical scale-space detectors"): each frame's keypoints inside the face, matched with the
//! previous frame's (Lowe's ratio test and a mutual check), lifted onto each frame's fitted face
//! surface, and the rigid motion between the frames by RANSAC — against the motion of the
//! landmark fit's pose.
//!
//! The 3-D points come from the fitted surface, so their depth follows the landmark fit; their
//! image positions do not. The check therefore sees the landmarks' motion in the image plane
//! (slides, in-plane turns, jitter) independently and their depth only partly.

use std::sync::Arc;
use std::time::Instant;

use image::RgbImage;
use visage_camera::{Intrinsics, RigidTransform};
use visage_face::CanonicalMesh;
use visage_keypoints::{
    estimate_rigid_motion, match_descriptors, Descriptor, GrayImage, MatchOptions, RansacOptions,
    Sift, SiftOptions,
};
use visage_morphable::fit::rigid_pose::mat3_mul;

use crate::stages::{Tracked, TrackedFace};
use visage_run_folder::KeypointMotionMetrics;

/// The face box is widened by this fraction of its size on each side before detection.
pub const FACE_MARGIN: f64 = 0.1;

/// Face crops wider than this are averaged down by a whole factor to at most this width
/// (pixels) before detection: the keypoints' scales are relative, and the cost stays that of
/// a small face however large the face is in the frame.
pub const MAX_FACE_CROP_PX: usize = 200;

/// At most this many keypoints per face (the strongest), which bounds the matching's cost.
pub const MAX_FACE_KEYPOINTS: usize = 400;

/// RANSAC inlier distance, metres: the fitted surface puts a skin point within a few
/// millimetres of where it was a frame before.
pub const INLIER_THRESHOLD_M: f64 = 0.003;

/// Fewer inliers than this give no motion estimate.
pub const MIN_INLIERS: usize = 8;

/// A frame's face keypoints on its fitted surface.
struct FaceKeypoints {
    /// Camera coordinates, metres.
    points: Vec<[f64; 3]>,
    descriptors: Vec<Descriptor>,
    /// The landmark fit's head pose (canonical face → camera).
    pose: RigidTransform,
    /// Centre of the fitted face, camera coordinates.
    centre: [f64; 3],
}

/// The per-frame keypoint check: the detector and the previous frame's face keypoints.
pub(crate) struct KeypointMotion {
    k: Intrinsics,
    canonical: Arc<CanonicalMesh>,
    sift: Sift,
    previous: Option<FaceKeypoints>,
    /// The fitted face's vertices projected into the frame, and its triangles bucketed by
    /// the cells their bounding boxes overlap.
    projected: Vec<[f64; 2]>,
    grid: TriangleGrid,
}

/// Pixels per side of a [`TriangleGrid`] cell.
const GRID_CELL_PX: f64 = 16.0;

/// The projected face's triangles by grid cell, rebuilt each frame, so a keypoint is tested
/// against the few triangles near it instead of all 898.
#[derive(Default)]
struct TriangleGrid {
    origin: [f64; 2],
    columns: usize,
    rows: usize,
    /// Per cell `c`: triangles `entries[starts[c]..starts[c + 1]]`.
    starts: Vec<usize>,
    entries: Vec<u32>,
}

impl TriangleGrid {
    fn build(&mut self, points: &[[f64; 2]], triangles: &[[u32; 3]]) {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        self.entries.clear();
        self.starts.clear();
        if !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite()) {
            (self.columns, self.rows) = (0, 0);
            return;
        }
        self.origin = lo;
        self.columns = ((hi[0] - lo[0]) / GRID_CELL_PX) as usize + 1;
        self.rows = ((hi[1] - lo[1]) / GRID_CELL_PX) as usize + 1;
        let cells = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            let cell = |v: f64, o: f64| ((v - o) / GRID_CELL_PX) as usize;
            let (c0, c1) = (
                cell(a[0].min(b[0]).min(c[0]), lo[0]),
                cell(a[0].max(b[0]).max(c[0]), lo[0]),
            );
            let (r0, r1) = (
                cell(a[1].min(b[1]).min(c[1]), lo[1]),
                cell(a[1].max(b[1]).max(c[1]), lo[1]),
            );
            (r0..=r1).flat_map(move |r| (c0..=c1).map(move |c| (r, c)))
        };
        // Counting pass, then filling (a compressed row layout).
        let n = self.columns * self.rows;
        self.starts.resize(n + 1, 0);
        for t in triangles {
            for (r, c) in cells(t) {
                self.starts[r * self.columns + c + 1] += 1;
            }
        }
        for i in 0..n {
            self.starts[i + 1] += self.starts[i];
        }
        self.entries.resize(self.starts[n], 0);
        let mut fill = self.starts.clone();
        for (k, t) in triangles.iter().enumerate() {
            for (r, c) in cells(t) {
                let cell = r * self.columns + c;
                self.entries[fill[cell]] = k as u32;
                fill[cell] += 1;
            }
        }
    }

    /// Triangles whose bounding boxes may hold `p`.
    fn near(&self, p: [f64; 2]) -> &[u32] {
        let c = (p[0] - self.origin[0]) / GRID_CELL_PX;
        let r = (p[1] - self.origin[1]) / GRID_CELL_PX;
        if !(c >= 0.0 && r >= 0.0 && (c as usize) < self.columns && (r as usize) < self.rows) {
            return &[];
        }
        let cell = r as usize * self.columns + c as usize;
        &self.entries[self.starts[cell]..self.starts[cell + 1]]
    }
}

impl KeypointMotion {
    pub fn new(k: Intrinsics, canonical: Arc<CanonicalMesh>) -> Self {
        KeypointMotion {
            k,
            canonical,
            sift: Sift::new(SiftOptions {
                // The face region is large enough; the upsampled octave costs 4× for
                // keypoints smaller than skin texture resolves.
                upsample: false,
                max_keypoints: Some(MAX_FACE_KEYPOINTS),
                ..SiftOptions::default()
            }),
            previous: None,
            projected: Vec::new(),
            grid: TriangleGrid::default(),
        }
    }

    /// Checks `tracked`'s head motion since the previous frame with the keypoints of `image`
    /// (its frame) and records it; a cut or a frame without a face starts over.
    pub fn observe(&mut self, image: &RgbImage, tracked: &mut Tracked) {
        let start = Instant::now();
        if tracked.cut {
            self.previous = None;
        }
        let Some(face) = &tracked.face else {
            self.previous = None;
            return;
        };
        let current = self.face_keypoints(image, face);
        if let Some(previous) = &self.previous {
            tracked.metrics.keypoint_motion = Some(compare(previous, &current));
        }
        self.previous = Some(current);
        tracked.metrics.ms.keypoints = start.elapsed().as_secs_f64() * 1e3;
    }

    fn face_keypoints(&mut self, image: &RgbImage, face: &TrackedFace) -> FaceKeypoints {
        let (w, h) = (image.width() as usize, image.height() as usize);
        let [bx, by, bw, bh] = face.face_box.map(f64::from);
        let (mx, my) = (FACE_MARGIN * bw, FACE_MARGIN * bh);
        let x0 = (bx - mx).floor().clamp(0.0, w as f64) as usize;
        let y0 = (by - my).floor().clamp(0.0, h as f64) as usize;
        let x1 = (bx + bw + mx).ceil().clamp(0.0, w as f64) as usize;
        let y1 = (by + bh + my).ceil().clamp(0.0, h as f64) as usize;
        let geometry = &face.geometry;
        let mut out = FaceKeypoints {
            points: Vec::new(),
            descriptors: Vec::new(),
            pose: geometry.pose,
            centre: centroid(&geometry.fitted_vertices),
        };
        let region = [x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0)];
        let bin = region[2].div_ceil(MAX_FACE_CROP_PX).max(1);
        let Some(gray) = GrayImage::from_rgb8_region(w, h, image.as_raw(), region, bin) else {
            return out;
        };
        self.projected.clear();
        self.projected
            .extend(geometry.fitted_vertices.iter().map(|&p| self.k.project(p)));
        self.grid.build(&self.projected, &self.canonical.triangles);
        // A binned pixel's centre is (bin − 1)/2 past its block's first input pixel.
        let to_frame = |kp: &visage_keypoints::Keypoint| {
            let at = |v: f32, origin: usize| {
                origin as f64 + bin as f64 * f64::from(v) + (bin as f64 - 1.0) / 2.0
            };
            [at(kp.x, x0), at(kp.y, y0)]
        };
        let surface = FaceSurface {
            triangles: &self.canonical.triangles,
            projected: &self.projected,
            grid: &self.grid,
            vertices: &geometry.fitted_vertices,
        };
        // Only keypoints on the fitted face are described.
        let features = self
            .sift
            .detect_and_compute_where(&gray, |kp| surface.lift(to_frame(kp)).is_some());
        for (kp, d) in features.keypoints.iter().zip(&features.descriptors) {
            if let Some(p) = surface.lift(to_frame(kp)) {
                out.points.push(p);
                out.descriptors.push(*d);
            }
        }
        out
    }
}

/// The fitted face in a frame: its triangles, vertices (camera coordinates) and their
/// projections, bucketed.
struct FaceSurface<'a> {
    triangles: &'a [[u32; 3]],
    projected: &'a [[f64; 2]],
    grid: &'a TriangleGrid,
    vertices: &'a [[f64; 3]],
}

impl FaceSurface<'_> {
    /// The nearest point of the fitted face seen at `pixel`: in each projected triangle that
    /// holds the pixel, the perspective-correct interpolation of its corners (where the pixel's
    /// ray meets the triangle's plane); the smallest depth wins. `None` off the face.
    fn lift(&self, pixel: [f64; 2]) -> Option<[f64; 3]> {
        let mut best: Option<[f64; 3]> = None;
        for &t in self.grid.near(pixel) {
            let t = self.triangles[t as usize];
            let [a, b, c] = t.map(|i| self.projected[i as usize]);
            let Some(bary) = barycentric(a, b, c, pixel) else {
                continue;
            };
            let corners = t.map(|i| self.vertices[i as usize]);
            let w: [f64; 3] = std::array::from_fn(|j| bary[j] / corners[j][2]);
            let sum = w[0] + w[1] + w[2];
            let point: [f64; 3] =
                std::array::from_fn(|k| (0..3).map(|j| w[j] * corners[j][k]).sum::<f64>() / sum);
            if best.is_none_or(|p| point[2] < p[2]) {
                best = Some(point);
            }
        }
        best
    }
}

/// Barycentric coordinates of `p` in triangle `(a, b, c)` when it lies inside (`None` outside
/// or for a degenerate triangle).
fn barycentric(a: [f64; 2], b: [f64; 2], c: [f64; 2], p: [f64; 2]) -> Option<[f64; 3]> {
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if det.abs() < 1e-12 {
        return None;
    }
    let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
    let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
    let l0 = 1.0 - l1 - l2;
    (l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0).then_some([l0, l1, l2])
}

/// The keypoint motion from `previous` to `current` against the landmark pose's.
fn compare(previous: &FaceKeypoints, current: &FaceKeypoints) -> KeypointMotionMetrics {
    let matches = match_descriptors(
        &previous.descriptors,
        &current.descriptors,
        &MatchOptions::default(),
    );
    let mut record = KeypointMotionMetrics {
        keypoints: current.points.len(),
        matches: matches.len(),
        inliers: 0,
        rotation_deg: None,
        rotation_disagreement_deg: None,
        translation_disagreement_mm: None,
    };
    let source: Vec<[f64; 3]> = matches.iter().map(|m| previous.points[m.query]).collect();
    let target: Vec<[f64; 3]> = matches.iter().map(|m| current.points[m.train]).collect();
    let options = RansacOptions {
        inlier_threshold: INLIER_THRESHOLD_M,
        min_inliers: MIN_INLIERS,
        ..RansacOptions::default()
    };
    let Some(estimate) = estimate_rigid_motion(&source, &target, &options) else {
        return record;
    };
    // The landmark fit's motion: X_k = T_k T_{k−1}⁻¹ X_{k−1}.
    let landmarks = |x: [f64; 3]| current.pose.apply(previous.pose.apply_inverse(x));
    let sift = &estimate.transform;
    let r_landmarks = mat3_mul(&current.pose.rotation, &transpose(&previous.pose.rotation));
    let disagreement = mat3_mul(&transpose(&sift.rotation), &r_landmarks);
    let c = previous.centre;
    record.inliers = estimate.inliers.len();
    record.rotation_deg = Some(rotation_angle_deg(&sift.rotation));
    record.rotation_disagreement_deg = Some(rotation_angle_deg(&disagreement));
    record.translation_disagreement_mm = Some(1e3 * distance(sift.apply(c), landmarks(c)));
    record
}

fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in points {
        for k in 0..3 {
            c[k] += p[k] / n;
        }
    }
    c
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn transpose(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

/// The angle of rotation `m`, degrees in `[0, 180]`.
fn rotation_angle_deg(m: &[[f64; 3]; 3]) -> f64 {
    let trace = m[0][0] + m[1][1] + m[2][2];
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_surface_is_lifted_where_the_ray_meets_the_nearest_triangle() {
        let k = Intrinsics::new(200, 200, 100.0, 100.0, 100.0, 100.0).unwrap();
        // A tilted square (z = 0.5 + 0.2 x) and, behind part of it, a farther one.
        let vertices: Vec<[f64; 3]> = [[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]]
            .iter()
            .map(|&[x, y]| [x, y, 0.5 + 0.2 * x])
            .chain([[-0.1, -0.1, 0.9], [0.3, -0.1, 0.9], [-0.1, 0.3, 0.9]])
            .collect();
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]];
        let projected: Vec<[f64; 2]> = vertices.iter().map(|&p| k.project(p)).collect();
        let mut grid = TriangleGrid::default();
        grid.build(&projected, &triangles);
        let surface = FaceSurface {
            triangles: &triangles,
            projected: &projected,
            grid: &grid,
            vertices: &vertices,
        };
        for pixel in [[100.0, 100.0], [120.0, 90.0], [85.0, 112.0]] {
            let p = surface.lift(pixel).unwrap();
            // On the near plane and on the pixel's ray.
            assert!((p[2] - (0.5 + 0.2 * p[0])).abs() < 1e-12, "{p:?}");
            let back = k.project(p);
            assert!((back[0] - pixel[0]).abs() < 1e-9 && (back[1] - pixel[1]).abs() < 1e-9);
        }
        assert!(surface.lift([5.0, 5.0]).is_none());
    }

    #[test]
    fn barycentric_inside_and_outside() {
        let (a, b, c) = ([0.0, 0.0], [4.0, 0.0], [0.0, 4.0]);
        let l = barycentric(a, b, c, [1.0, 1.0]).unwrap();
        assert!((l[0] - 0.5).abs() < 1e-12 && (l[1] - 0.25).abs() < 1e-12);
        assert!(barycentric(a, b, c, [3.0, 3.0]).is_none());
        assert!(barycentric(a, a, c, [0.0, 1.0]).is_none());
    }

    fn rotation_z(deg: f64) -> [[f64; 3]; 3] {
        let a = deg.to_radians();
        [
            [a.cos(), -a.sin(), 0.0],
            [a.sin(), a.cos(), 0.0],
            [0.0, 0.0, 1.0],
        ]
    }

    /// Keypoints on a face-sized patch 0.5 m away, with distinct descriptors.
    fn patch(pose: RigidTransform) -> FaceKeypoints {
        let points: Vec<[f64; 3]> = (0..60)
            .map(|i| {
                let (u, v) = ((i % 8) as f64 / 7.0 - 0.5, (i / 8) as f64 / 7.0 - 0.5);
                [0.12 * u, 0.15 * v, 0.5 + 0.02 * (3.0 * u * v).sin()]
            })
            .collect();
        let descriptors = (0..60)
            .map(|i| std::array::from_fn(|j| ((i * 131 + j * 17 + (i * j) % 7) % 200) as u8))
            .collect();
        FaceKeypoints {
            centre: centroid(&points),
            points,
            descriptors,
            pose,
        }
    }

    #[test]
    fn the_check_measures_how_far_the_pose_is_from_the_keypoints_motion() {
        let motion = RigidTransform {
            rotation: rotation_z(3.0),
            translation: [0.002, -0.001, 0.0],
        };
        let previous = patch(RigidTransform {
            rotation: rotation_z(0.0),
            translation: [0.0, 0.0, 0.5],
        });
        let mut current = patch(previous.pose);
        current.points = previous.points.iter().map(|&p| motion.apply(p)).collect();
        // The landmark pose moved as the keypoints did: no disagreement.
        current.pose = RigidTransform {
            rotation: mat3_mul(&motion.rotation, &previous.pose.rotation),
            translation: motion.apply(previous.pose.translation),
        };
        let agree = compare(&previous, &current);
        assert_eq!((agree.matches, agree.inliers), (60, 60));
        assert!((agree.rotation_deg.unwrap() - 3.0).abs() < 1e-6);
        assert!(agree.rotation_disagreement_deg.unwrap() < 1e-6);
        assert!(agree.translation_disagreement_mm.unwrap() < 1e-6);
        // A pose that turned one degree further and slid 2 mm: both seen.
        current.pose.rotation = mat3_mul(&rotation_z(1.0), &current.pose.rotation);
        current.pose.translation[0] += 0.002;
        let off = compare(&previous, &current);
        assert!((off.rotation_disagreement_deg.unwrap() - 1.0).abs() < 1e-6);
        assert!(off.translation_disagreement_mm.unwrap() > 2.0);
    }

    #[test]
    fn rotation_angles() {
        let a = 0.3f64;
        let rz = [
            [a.cos(), -a.sin(), 0.0],
            [a.sin(), a.cos(), 0.0],
            [0.0, 0.0, 1.0],
        ];
        assert!((rotation_angle_deg(&rz) - a.to_degrees()).abs() < 1e-9);
        let back = mat3_mul(&transpose(&rz), &rz);
        assert!(rotation_angle_deg(&back) < 1e-6);
    }
}
