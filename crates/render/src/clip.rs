//! Clipping of triangles against the near and far planes in homogeneous clip space (the step
//! between Eq. (6.1) and the perspective divide).
//!
//! Only the near and far planes are clipped geometrically: the near plane keeps `w > 0` so the
//! perspective divide is defined, the far plane bounds depth. The four side planes are handled by
//! trivial rejection plus scissoring in the rasteriser, which is exact and cheaper.

/// Most vertices a triangle can have after clipping against two planes.
pub const MAX_CLIPPED_VERTICES: usize = 5;

/// A vertex during clipping: OpenGL clip coordinates `(x, y, z, w)` and its barycentric
/// coordinates in the original triangle (clip space is an affine image of object space, so
/// barycentrics interpolate linearly here).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVertex {
    /// Clip-space position.
    pub clip: [f64; 4],
    /// Barycentric coordinates in the original triangle.
    pub bary: [f64; 3],
}

/// A convex polygon of at most [`MAX_CLIPPED_VERTICES`] vertices, without allocation.
#[derive(Clone, Copy, Debug)]
pub struct ClippedPolygon {
    vertices: [ClipVertex; MAX_CLIPPED_VERTICES + 1],
    len: usize,
}

impl ClippedPolygon {
    /// The polygon's vertices, in order.
    pub fn vertices(&self) -> &[ClipVertex] {
        &self.vertices[..self.len]
    }

    fn push(&mut self, v: ClipVertex) {
        if self.len < self.vertices.len() {
            self.vertices[self.len] = v;
            self.len += 1;
        }
    }
}

/// Signed distance-like value of a clip vertex to the near plane (`z + w ≥ 0` inside, i.e. camera
/// `z ≥ near`).
#[inline]
pub fn near_distance(c: [f64; 4]) -> f64 {
    c[2] + c[3]
}

/// Same for the far plane (`w − z ≥ 0` inside, i.e. camera `z ≤ far`).
#[inline]
pub fn far_distance(c: [f64; 4]) -> f64 {
    c[3] - c[2]
}

/// The point where segment `inside → outside` crosses a plane with distances `di ≥ 0 > do_`.
///
/// Always parameterised from the inside end, so the two triangles sharing an edge compute
/// bit-identical crossing points (no crack along a clipped shared edge).
#[inline]
fn crossing(inside: &ClipVertex, outside: &ClipVertex, di: f64, do_: f64) -> ClipVertex {
    let t = di / (di - do_);
    let lerp = |a: f64, b: f64| a + t * (b - a);
    ClipVertex {
        clip: std::array::from_fn(|k| lerp(inside.clip[k], outside.clip[k])),
        bary: std::array::from_fn(|k| lerp(inside.bary[k], outside.bary[k])),
    }
}

/// One Sutherland–Hodgman pass against the plane `distance(v) ≥ 0`.
fn clip_against(poly: &ClippedPolygon, distance: fn([f64; 4]) -> f64) -> ClippedPolygon {
    let mut out = ClippedPolygon {
        vertices: poly.vertices,
        len: 0,
    };
    let vs = poly.vertices();
    for (i, cur) in vs.iter().enumerate() {
        let next = &vs[(i + 1) % vs.len()];
        let (dc, dn) = (distance(cur.clip), distance(next.clip));
        if dc >= 0.0 {
            out.push(*cur);
            if dn < 0.0 {
                out.push(crossing(cur, next, dc, dn));
            }
        } else if dn >= 0.0 {
            out.push(crossing(next, cur, dn, dc));
        }
    }
    out
}

/// Clips triangle `v` against the near and far planes. Returns an empty polygon when nothing is
/// left, the triangle itself when it lies between the planes.
pub fn clip_triangle(v: [ClipVertex; 3]) -> ClippedPolygon {
    let mut poly = ClippedPolygon {
        vertices: [v[0]; MAX_CLIPPED_VERTICES + 1],
        len: 0,
    };
    v.iter().for_each(|&x| poly.push(x));
    if v.iter()
        .all(|x| near_distance(x.clip) >= 0.0 && far_distance(x.clip) >= 0.0)
    {
        return poly;
    }
    let poly = clip_against(&poly, near_distance);
    if poly.len < 3 {
        return ClippedPolygon { len: 0, ..poly };
    }
    let poly = clip_against(&poly, far_distance);
    if poly.len < 3 {
        return ClippedPolygon { len: 0, ..poly };
    }
    poly
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(z: f64, bary: usize) -> ClipVertex {
        // A camera with near = 1, far = 10: z_clip = (11 z − 20)/9, w = z.
        let (n, f) = (1.0, 10.0);
        let zc = ((f + n) * z - 2.0 * f * n) / (f - n);
        let mut b = [0.0; 3];
        b[bary] = 1.0;
        ClipVertex {
            clip: [z, 0.5 * z * bary as f64, zc, z],
            bary: b,
        }
    }

    #[test]
    fn triangle_crossing_the_near_plane_becomes_a_quad_on_it() {
        let poly = clip_triangle([vertex(0.5, 0), vertex(2.0, 1), vertex(3.0, 2)]);
        assert_eq!(poly.vertices().len(), 4);
        for v in poly.vertices() {
            assert!(v.clip[3] >= 1.0 - 1e-12, "w = z ≥ near: {v:?}");
            assert!((v.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        assert!(
            poly.vertices()
                .iter()
                .filter(|v| (v.clip[3] - 1.0).abs() < 1e-12)
                .count()
                == 2
        );
    }

    #[test]
    fn fully_outside_triangles_vanish_and_inside_ones_pass_unchanged() {
        assert!(
            clip_triangle([vertex(0.5, 0), vertex(0.2, 1), vertex(0.9, 2)])
                .vertices()
                .is_empty()
        );
        assert!(
            clip_triangle([vertex(11.0, 0), vertex(12.0, 1), vertex(20.0, 2)])
                .vertices()
                .is_empty()
        );
        let tri = [vertex(2.0, 0), vertex(3.0, 1), vertex(4.0, 2)];
        assert_eq!(clip_triangle(tri).vertices(), &tri);
        let both = clip_triangle([vertex(0.5, 0), vertex(5.0, 1), vertex(20.0, 2)]);
        assert_eq!(both.vertices().len(), 5, "cut by both planes");
    }

    #[test]
    fn shared_edge_crossing_is_bit_identical_in_both_directions() {
        let (a, b) = (vertex(0.5, 0), vertex(4.0, 1));
        let p = crossing(&b, &a, near_distance(b.clip), near_distance(a.clip));
        let c1 = clip_triangle([a, b, vertex(3.0, 2)]);
        let c2 = clip_triangle([b, a, vertex(5.0, 2)]);
        let has = |poly: &ClippedPolygon| poly.vertices().iter().any(|v| v.clip == p.clip);
        assert!(has(&c1) && has(&c2));
    }
}
