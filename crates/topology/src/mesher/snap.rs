//! Snapping the boundary of a clipped lattice onto the surface, under a quality guard.
//!
//! Each boundary vertex moves towards its closest surface point (if one lies within a lattice
//! spacing). The move is tried in full, then at 3/4, 1/2 and 1/4 of the way; the first one that
//! leaves every tet around the vertex positively oriented with all dihedral angles at least
//! [`MIN_DIHEDRAL_DEG`] is taken, otherwise the vertex stays. The lattice tets start at 60 and
//! 90 degrees, so the guard is what bounds the final angles.

use hashbrown::HashMap;

use super::bvh::TriangleBvh;
use crate::faces::{signed_volume, FACE_CORNERS};
use crate::quality::dihedral_angles_deg;

/// Smallest dihedral angle a snap may leave, in degrees.
pub const MIN_DIHEDRAL_DEG: f64 = 10.0;

/// Fractions of the way to the surface tried in turn.
const STEPS: [f64; 4] = [1.0, 0.75, 0.5, 0.25];

/// What snapping did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SnapReport {
    /// Boundary vertices of the clipped lattice.
    pub boundary_vertices: usize,
    /// Moved all the way onto the surface.
    pub snapped: usize,
    /// Moved part of the way (a full move would have spoilt a tet).
    pub partial: usize,
    /// Left where they were.
    pub kept: usize,
}

/// Vertices on faces used by one tet only.
pub fn boundary_vertices(tets: &[[u32; 4]], num_vertices: usize) -> Vec<bool> {
    let mut faces: HashMap<[u32; 3], u32> = HashMap::with_capacity(2 * tets.len());
    for t in tets {
        for corners in FACE_CORNERS {
            let mut f = corners.map(|c| t[c]);
            f.sort_unstable();
            *faces.entry(f).or_insert(0) += 1;
        }
    }
    let mut on = vec![false; num_vertices];
    for (f, &n) in &faces {
        if n == 1 {
            for &v in f {
                on[v as usize] = true;
            }
        }
    }
    on
}

/// Moves boundary vertices onto the surface where the guard allows; `h` is the lattice spacing.
pub fn snap_to_surface(
    vertices: &mut [[f64; 3]],
    tets: &[[u32; 4]],
    bvh: &TriangleBvh,
    h: f64,
) -> SnapReport {
    let on = boundary_vertices(tets, vertices.len());
    // Vertex -> tets, compressed rows.
    let mut start = vec![0u32; vertices.len() + 1];
    for t in tets {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..vertices.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut incident = vec![0u32; start[vertices.len()] as usize];
    for (ti, t) in tets.iter().enumerate() {
        for &v in t {
            incident[fill[v as usize] as usize] = ti as u32;
            fill[v as usize] += 1;
        }
    }
    let mut report = SnapReport::default();
    for v in 0..vertices.len() {
        if !on[v] {
            continue;
        }
        report.boundary_vertices += 1;
        let from = vertices[v];
        let Some((target, _)) = bvh.closest_point(from, h) else {
            report.kept += 1;
            continue;
        };
        let around = &incident[start[v] as usize..start[v + 1] as usize];
        let mut moved = None;
        for (step, &s) in STEPS.iter().enumerate() {
            let p = [0, 1, 2].map(|k| from[k] + s * (target[k] - from[k]));
            vertices[v] = p;
            if around.iter().all(|&t| good(vertices, tets[t as usize])) {
                moved = Some(step);
                break;
            }
        }
        match moved {
            Some(0) => report.snapped += 1,
            Some(_) => report.partial += 1,
            None => {
                vertices[v] = from;
                report.kept += 1;
            }
        }
    }
    report
}

/// Positively oriented with every dihedral angle at least [`MIN_DIHEDRAL_DEG`].
fn good(vertices: &[[f64; 3]], t: [u32; 4]) -> bool {
    let p = t.map(|v| vertices[v as usize]);
    signed_volume(p[0], p[1], p[2], p[3]) > 0.0
        && dihedral_angles_deg(p)
            .iter()
            .all(|a| (MIN_DIHEDRAL_DEG..=180.0 - MIN_DIHEDRAL_DEG).contains(a))
}
