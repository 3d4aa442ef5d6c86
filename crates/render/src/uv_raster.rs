//! A triangle of a mesh's UV layout rasterised onto a square texture: which texels it covers
//! and their barycentric coordinates, for what is painted or fused in texture space (the
//! export's fused texture, the expression benchmark's painted lids).

/// Calls `texel(x, y, barycentrics)` for every texel of a `size × size` texture whose centre
/// lies in the triangle with UVs `uv` (OBJ convention, v up: texel (x, y)'s centre is at
/// `u = (x + ½) / size`, `v = 1 − (y + ½) / size`). Edges are inclusive (a texel on a shared
/// edge is visited by both triangles); a degenerate triangle visits none.
pub fn rasterize_uv_triangle(
    uv: [[f64; 2]; 3],
    size: usize,
    mut texel: impl FnMut(usize, usize, [f64; 3]),
) {
    let s = size as f64;
    let q = uv.map(|p| [p[0] * s - 0.5, (1.0 - p[1]) * s - 0.5]);
    let area =
        (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]);
    if area.abs() < 1e-12 {
        return;
    }
    let lo = |c: usize| q.iter().map(|p| p[c]).fold(f64::INFINITY, f64::min);
    let hi = |c: usize| q.iter().map(|p| p[c]).fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1) = (lo(0).ceil().max(0.0) as usize, hi(0).floor().min(s - 1.0));
    let (y0, y1) = (lo(1).ceil().max(0.0) as usize, hi(1).floor().min(s - 1.0));
    if x1 < 0.0 || y1 < 0.0 {
        return;
    }
    for y in y0..=y1 as usize {
        for x in x0..=x1 as usize {
            let (px, py) = (x as f64, y as f64);
            let edge = |a: [f64; 2], b: [f64; 2]| {
                ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / area
            };
            let b = [edge(q[1], q[2]), edge(q[2], q[0]), edge(q[0], q[1])];
            if b.iter().all(|&w| w >= -1e-9) {
                texel(x, y, b);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles_of_a_square_cover_every_texel_with_barycentrics_that_place_it() {
        let size = 8;
        let mut seen = vec![0; size * size];
        let corners = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        for tri in [[0, 1, 2], [0, 2, 3]] {
            let uv = tri.map(|i| corners[i]);
            rasterize_uv_triangle(uv, size, |x, y, b| {
                seen[y * size + x] += 1;
                assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-9);
                // The barycentrics give back the texel centre's UV.
                let u: f64 = (0..3).map(|k| b[k] * uv[k][0]).sum();
                let v: f64 = (0..3).map(|k| b[k] * uv[k][1]).sum();
                assert!((u - (x as f64 + 0.5) / 8.0).abs() < 1e-9);
                assert!((v - (1.0 - (y as f64 + 0.5) / 8.0)).abs() < 1e-9);
            });
        }
        assert!(seen.iter().all(|&n| n >= 1), "{seen:?}");
        let mut none = true;
        rasterize_uv_triangle([[0.1, 0.1], [0.5, 0.5], [0.9, 0.9]], size, |_, _, _| {
            none = false
        });
        assert!(none);
    }
}
