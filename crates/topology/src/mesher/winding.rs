//! Generalised winding number (Jacobson et al. 2013) of a triangle surface, evaluated
//! hierarchically: far clusters of triangles contribute through their dipole term (the fast
//! winding number of Barill et al. 2018, first order), near ones exactly.
//!
//! The winding number is 1 inside a closed, outward-oriented surface and 0 outside; across a
//! small hole it falls smoothly instead of jumping, so thresholding at 1/2 still gives a
//! sensible inside for slightly open scans.

use super::bvh::TriangleBvh;

/// Accuracy parameter: a cluster is summarised once the query is `BETA` cluster radii away.
/// At 2 the dipole error is a few per cent of the cluster's own (already small) contribution,
/// far below the 1/2 threshold margin away from the surface.
const BETA: f64 = 2.0;

/// Inside test by generalised winding number.
#[derive(Debug, Clone)]
pub struct Winding {
    bvh: TriangleBvh,
}

impl Winding {
    /// Prepares the hierarchy for the surface's triangles.
    pub fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Self {
        let tris = faces
            .iter()
            .map(|f| f.map(|v| vertices[v as usize]))
            .collect();
        Self {
            bvh: TriangleBvh::new(tris),
        }
    }

    /// The winding number at `q` (1 inside, 0 outside for a closed outward surface).
    pub fn at(&self, q: [f64; 3]) -> f64 {
        self.bvh.solid_angle(q, BETA) / (4.0 * std::f64::consts::PI)
    }

    /// Whether `q` is inside (winding number above 1/2).
    pub fn inside(&self, q: [f64; 3]) -> bool {
        self.at(q) > 0.5
    }

    /// The triangle hierarchy, for closest-point queries.
    pub fn bvh(&self) -> &TriangleBvh {
        &self.bvh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit cube with outward faces.
    fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        crate::mesher::cube_surface([0.0; 3], [1.0; 3])
    }

    #[test]
    fn cube_inside_and_outside() {
        let (v, f) = cube();
        let w = Winding::new(&v, &f);
        // Exact for so few triangles (one leaf): 1 inside, 0 outside to rounding.
        assert!((w.at([0.5, 0.5, 0.5]) - 1.0).abs() < 1e-9);
        assert!(w.at([0.3, 0.8, 0.1]) > 0.99);
        assert!(w.at([1.5, 0.5, 0.5]).abs() < 1e-9);
        assert!(w.at([-3.0, 2.0, 9.0]).abs() < 1e-9);
    }

    #[test]
    fn open_cube_still_has_an_inside() {
        let (v, mut f) = cube();
        f.truncate(10); // drop the x = 1 face: a large hole
        let w = Winding::new(&v, &f);
        // Near the closed side the winding number stays close to 1.
        assert!(w.inside([0.2, 0.5, 0.5]));
        assert!(!w.inside([-0.5, 0.5, 0.5]));
    }
}
