//! Edge → triangle adjacency of a triangle list.

use std::collections::HashMap;

/// Key of an undirected edge: its endpoints in increasing order.
#[inline]
pub fn edge_key(a: u32, b: u32) -> (u32, u32) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

/// For each undirected edge, the (up to two) triangles that contain it.
pub fn edge_triangles(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), Vec<usize>> {
    let mut map: HashMap<(u32, u32), Vec<usize>> =
        HashMap::with_capacity(triangles.len() * 3 / 2 + 8);
    for (t, tri) in triangles.iter().enumerate() {
        for e in 0..3 {
            map.entry(edge_key(tri[e], tri[(e + 1) % 3]))
                .or_default()
                .push(t);
        }
    }
    map
}
