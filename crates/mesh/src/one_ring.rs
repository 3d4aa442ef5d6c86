/// Vertex one-rings of a triangle mesh in compressed form: the neighbours of vertex `i` are
/// `neighbours[start[i]..start[i + 1]]` (each once, in order of first appearance).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OneRing {
    start: Vec<usize>,
    neighbours: Vec<u32>,
}

impl OneRing {
    /// One-rings of `vertex_count` vertices connected by `triangles`.
    pub fn new(vertex_count: usize, triangles: &[[u32; 3]]) -> Self {
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); vertex_count];
        for t in triangles {
            for a in 0..3 {
                for b in 0..3 {
                    let list = &mut lists[t[a] as usize];
                    if a != b && !list.contains(&t[b]) {
                        list.push(t[b]);
                    }
                }
            }
        }
        let mut start = Vec::with_capacity(vertex_count + 1);
        let mut neighbours = Vec::new();
        start.push(0);
        for list in &lists {
            neighbours.extend_from_slice(list);
            start.push(neighbours.len());
        }
        OneRing { start, neighbours }
    }

    /// The neighbours of vertex `i`.
    ///
    /// # Panics
    /// If `i` is not a vertex.
    #[inline]
    #[track_caller]
    pub fn of(&self, i: usize) -> &[u32] {
        &self.neighbours[self.start[i]..self.start[i + 1]]
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.start.len() - 1
    }

    /// Whether there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
