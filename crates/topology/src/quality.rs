//! Element quality measures of the current mesh.

use crate::faces::{cross, dot, norm, signed_volume, sub, EDGES, FACE_CORNERS};
use crate::mesh::TetMesh;

/// Quality summary of the tets in current positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Quality {
    /// Smallest signed tet volume (length^3); negative means an inverted tet.
    pub min_volume: f64,
    /// Largest signed tet volume (length^3).
    pub max_volume: f64,
    /// Smallest dihedral angle over all tets (degrees).
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle over all tets (degrees).
    pub max_dihedral_deg: f64,
    /// Smallest radius ratio `3 r_in / r_circ` (1 for a regular tet, 0 for a flat one).
    pub min_radius_ratio: f64,
    /// Mean radius ratio over the tets.
    pub mean_radius_ratio: f64,
    /// Counts of all dihedral angles in 10-degree bins, `[0, 10)` .. `[170, 180]`.
    pub dihedral_histogram: [usize; 18],
}

/// The six dihedral angles of a tet (degrees), in the order of [`EDGES`].
pub fn dihedral_angles_deg(p: [[f64; 3]; 4]) -> [f64; 6] {
    let normals = FACE_CORNERS.map(|[a, b, c]| cross(sub(p[b], p[a]), sub(p[c], p[a])));
    EDGES.map(|[i, j]| {
        // The two faces meeting at edge (i, j) are those opposite the other two corners.
        let mut others = (0..4).filter(|&k| k != i && k != j);
        let (k, l) = (others.next().unwrap_or(0), others.next().unwrap_or(0));
        let (nk, nl) = (normals[k], normals[l]);
        let c = -dot(nk, nl) / (norm(nk) * norm(nl));
        c.clamp(-1.0, 1.0).acos().to_degrees()
    })
}

/// Radius ratio `3 r_in / r_circ` of a tet: 1 for a regular tet, 0 for a flat one.
pub fn radius_ratio(p: [[f64; 3]; 4]) -> f64 {
    let volume = signed_volume(p[0], p[1], p[2], p[3]);
    let area: f64 = FACE_CORNERS
        .iter()
        .map(|&[a, b, c]| 0.5 * norm(cross(sub(p[b], p[a]), sub(p[c], p[a]))))
        .sum();
    let r_in = 3.0 * volume.abs() / area;
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    // Circumcentre offset from p0 is (|a|^2 b x c + |b|^2 c x a + |c|^2 a x b) / (12 V).
    let (bc, ca, ab) = (cross(b, c), cross(c, a), cross(a, b));
    let (aa, bb, cc) = (dot(a, a), dot(b, b), dot(c, c));
    let num = [0, 1, 2].map(|i| aa * bc[i] + bb * ca[i] + cc * ab[i]);
    let r_circ = norm(num) / (12.0 * volume.abs());
    if r_circ.is_finite() && r_circ > 0.0 {
        3.0 * r_in / r_circ
    } else {
        0.0
    }
}

impl TetMesh {
    /// Volume, dihedral angle and radius ratio statistics of the current mesh.
    pub fn quality(&self) -> Quality {
        let mut q = Quality {
            min_volume: f64::INFINITY,
            max_volume: f64::NEG_INFINITY,
            min_dihedral_deg: f64::INFINITY,
            max_dihedral_deg: f64::NEG_INFINITY,
            min_radius_ratio: f64::INFINITY,
            mean_radius_ratio: 0.0,
            dihedral_histogram: [0; 18],
        };
        for t in 0..self.tets.len() {
            let p = self.current_corners(t);
            let v = signed_volume(p[0], p[1], p[2], p[3]);
            q.min_volume = q.min_volume.min(v);
            q.max_volume = q.max_volume.max(v);
            for angle in dihedral_angles_deg(p) {
                q.min_dihedral_deg = q.min_dihedral_deg.min(angle);
                q.max_dihedral_deg = q.max_dihedral_deg.max(angle);
                // Angles on a bin edge to 1e-8 degrees (45, 60, 90 in lattice meshes, computed with
                // rounding either side) count in the upper bin, so regular meshes bin stably.
                let bin = ((angle / 10.0 + 1e-9) as usize).min(17);
                q.dihedral_histogram[bin] += 1;
            }
            let rr = radius_ratio(p);
            q.min_radius_ratio = q.min_radius_ratio.min(rr);
            q.mean_radius_ratio += rr;
        }
        q.mean_radius_ratio /= self.tets.len().max(1) as f64;
        q
    }
}
