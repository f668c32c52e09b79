//! Surface checks before meshing: duplicate vertices merged by exact position, then counts of
//! open boundary edges, non-manifold edges, inconsistently oriented edges and zero-area faces.

use hashbrown::HashMap;

use super::bvh::{cross, norm, sub};

/// What the checks found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceProblems {
    /// Vertices merged into an earlier vertex at exactly the same position.
    pub merged_vertices: usize,
    /// Faces dropped because two of their corners became one vertex.
    pub collapsed_faces: usize,
    /// Faces with (near) zero area, kept but reported.
    pub zero_area_faces: usize,
    /// Edges used by one face only (holes in the surface).
    pub open_edges: usize,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Edges whose two faces traverse them the same way (one face flipped).
    pub flipped_edges: usize,
}

impl SurfaceProblems {
    /// Whether the surface is closed, manifold and consistently oriented.
    pub fn is_watertight(&self) -> bool {
        self.open_edges == 0 && self.non_manifold_edges == 0 && self.flipped_edges == 0
    }
}

/// A surface after merging duplicate vertices.
#[derive(Debug, Clone)]
pub struct CleanSurface {
    /// Distinct vertices.
    pub vertices: Vec<[f64; 3]>,
    /// Faces on them, without collapsed faces.
    pub faces: Vec<[u32; 3]>,
    /// What was found.
    pub problems: SurfaceProblems,
}

/// Merges vertices by exact position and checks the edges. Faces must index `vertices`.
pub fn check_surface(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> CleanSurface {
    let mut problems = SurfaceProblems::default();
    let mut by_position: HashMap<[u64; 3], u32> = HashMap::with_capacity(vertices.len());
    let mut remap = Vec::with_capacity(vertices.len());
    let mut merged = Vec::with_capacity(vertices.len());
    for p in vertices {
        // +0.0 and -0.0 are the same position.
        let key = p.map(|x| if x == 0.0 { 0 } else { x.to_bits() });
        let next = merged.len() as u32;
        let id = *by_position.entry(key).or_insert(next);
        if id == next {
            merged.push(*p);
        } else {
            problems.merged_vertices += 1;
        }
        remap.push(id);
    }
    let mut out_faces = Vec::with_capacity(faces.len());
    let mut diag2: f64 = 0.0;
    if let Some(first) = merged.first() {
        let (mut lo, mut hi) = (*first, *first);
        for p in &merged {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let d = norm(sub(hi, lo));
        diag2 = d * d;
    }
    for f in faces {
        let g = f.map(|v| remap[v as usize]);
        if g[0] == g[1] || g[1] == g[2] || g[0] == g[2] {
            problems.collapsed_faces += 1;
            continue;
        }
        let p = g.map(|v| merged[v as usize]);
        // Zero area relative to the model: below 1e-14 of the squared diagonal is rounding.
        if 0.5 * norm(cross(sub(p[1], p[0]), sub(p[2], p[0]))) <= 1e-14 * diag2 {
            problems.zero_area_faces += 1;
        }
        out_faces.push(g);
    }
    // Per undirected edge: number of uses and the sum of directions (+1 low->high, -1 back).
    let mut edges: HashMap<(u32, u32), (u32, i32)> = HashMap::with_capacity(3 * out_faces.len());
    for f in &out_faces {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            let (key, dir) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
            let entry = edges.entry(key).or_insert((0, 0));
            entry.0 += 1;
            entry.1 += dir;
        }
    }
    for &(uses, dirs) in edges.values() {
        match uses {
            1 => problems.open_edges += 1,
            2 if dirs != 0 => problems.flipped_edges += 1,
            2 => {}
            _ => problems.non_manifold_edges += 1,
        }
    }
    CleanSurface {
        vertices: merged,
        faces: out_faces,
        problems,
    }
}

/// Signed volume enclosed by the faces (divergence theorem); exact for a closed surface.
pub fn enclosed_volume(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> f64 {
    faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| vertices[v as usize]);
            super::bvh::dot(a, cross(b, c)) / 6.0
        })
        .sum()
}

/// Enclosed volume with every hole capped by a fan from the centroid of its boundary loop, so
/// that an open scan gets a volume that does not depend on the coordinate origin. Equal to
/// [`enclosed_volume`] for a closed surface.
pub fn capped_volume(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> f64 {
    let mut directed: HashMap<(u32, u32), i32> = HashMap::with_capacity(3 * faces.len());
    for f in faces {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            *directed.entry((a, b)).or_insert(0) += 1;
            *directed.entry((b, a)).or_insert(0) -= 1;
        }
    }
    // Open directed edges a -> b (used once more one way than the other); the cap runs b -> a.
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for (&(a, b), &n) in &directed {
        if n > 0 {
            next.entry(a).or_default().push(b);
        }
    }
    let mut volume = enclosed_volume(vertices, faces);
    let starts: Vec<u32> = next.keys().copied().collect();
    for start in starts {
        // Walk one loop, consuming its edges.
        let mut lp = Vec::new();
        let mut v = start;
        while let Some(b) = next.get_mut(&v).and_then(|outs| outs.pop()) {
            lp.push((v, b));
            v = b;
            if v == start {
                break;
            }
        }
        if lp.is_empty() {
            continue;
        }
        let mut o = [0.0; 3];
        for &(a, _) in &lp {
            for k in 0..3 {
                o[k] += vertices[a as usize][k] / lp.len() as f64;
            }
        }
        for &(a, b) in &lp {
            let (pa, pb) = (vertices[a as usize], vertices[b as usize]);
            volume += super::bvh::dot(o, cross(pb, pa)) / 6.0;
        }
    }
    volume
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_seams_and_counts_problems() {
        // Two triangles of a square, the shared edge's vertices duplicated (a texture seam).
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let f = [[0, 1, 2], [3, 4, 5]];
        let s = check_surface(&v, &f);
        assert_eq!(s.problems.merged_vertices, 2);
        assert_eq!(s.vertices.len(), 4);
        // A lone square: four open edges, none flipped.
        assert_eq!(s.problems.open_edges, 4);
        assert_eq!(s.problems.flipped_edges, 0);
        // Flip the second face: the diagonal is now traversed the same way twice.
        let s = check_surface(&v, &[[0, 1, 2], [3, 5, 4]]);
        assert_eq!(s.problems.flipped_edges, 1);
        // A face with a repeated corner collapses.
        let s = check_surface(&v, &[[0, 1, 3]]);
        assert_eq!(s.problems.collapsed_faces, 1);
        assert!(s.faces.is_empty());
    }

    #[test]
    fn capped_volume_closes_a_hole() {
        // Unit cube without its top (z = 1) face, shifted away from the origin.
        let (v, mut f) = crate::mesher::cube_surface([5.0, -3.0, 2.0], [6.0, -2.0, 3.0]);
        f.retain(|t| t.iter().any(|&i| i < 4)); // the top face uses corners 4..8 only
        assert_eq!(f.len(), 10);
        // The cap is the missing square exactly: the cube's volume, 1, to rounding.
        assert!((capped_volume(&v, &f) - 1.0).abs() < 1e-12);
        assert!((enclosed_volume(&v, &f) - 1.0).abs() > 0.1);
    }
}
