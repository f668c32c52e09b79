//! Contact radii of the particles (MODEL.md section 7).

use std::f64::consts::PI;

use perifrac_physics::math::{cross, norm, sub};
use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::{TetMesh, NO_TET};

/// Contact radius (m) of every particle: `factor` times the radius of the sphere of the tet's
/// volume, `(3 V / 4 pi)^(1/3)`, but for a tet on the boundary at most `factor` times the
/// distance from its barycentre to its boundary faces (a quarter of the tet's height over
/// them, `3 V / (4 A)`). With the cap the particles' contact surface lies on the mesh surface
/// at rest, so an object set down touching the ground starts touching it, not sunk into it
/// (the volume sphere of a boundary tet of a box sticks out by 9% of the cell size). Faces of
/// initial cracks count as boundary.
pub(super) fn contact_radii(mesh: &TetMesh, volumes: &[f64], factor: f64) -> Vec<f64> {
    let x = mesh.rest_positions();
    let origin = mesh.vertex_origin();
    mesh.tets()
        .iter()
        .zip(mesh.neighbours())
        .zip(volumes)
        .enumerate()
        .map(|(t, ((tet, nb), &v))| {
            let mut r = (3.0 * v / (4.0 * PI)).cbrt();
            for (f, &other) in nb.iter().enumerate() {
                if other != NO_TET && !mesh.is_cracked(t as u32, f as u8) {
                    continue;
                }
                let [a, b, c] = FACE_CORNERS[f].map(|k| x[origin[tet[k] as usize] as usize]);
                let area = 0.5 * norm(cross(sub(b, a), sub(c, a)));
                if area > 0.0 {
                    r = r.min(0.75 * v / area);
                }
            }
            factor * r
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use perifrac_topology::primitives;

    #[test]
    fn boundary_spheres_stop_at_the_surface() {
        // One cell of 6 Kuhn tets, h = 1: every tet has a boundary face; volume 1/6.
        let mesh = primitives::box_mesh([0.0; 3], [1.0; 3], [1, 1, 1]);
        let v = mesh.rest_volumes();
        let r = contact_radii(&mesh, &v, 1.0);
        let bary = mesh.rest_barycentres();
        let volume_sphere = (3.0 / (4.0 * PI * 6.0f64)).cbrt();
        for (t, (&rt, x)) in r.iter().zip(&bary).enumerate() {
            assert!(rt <= volume_sphere + 1e-15, "tet {t}");
            // No sphere reaches out of the unit cube by more than rounding.
            for k in 0..3 {
                assert!(
                    x[k] - rt >= -1e-12 && x[k] + rt <= 1.0 + 1e-12,
                    "tet {t}: {x:?} {rt}"
                );
            }
        }
        // Interior tets keep the volume sphere: in a 3^3 block the middle cell's tets have no
        // boundary face.
        let mesh = primitives::box_mesh([0.0; 3], [3.0; 3], [3, 3, 3]);
        let v = mesh.rest_volumes();
        let r = contact_radii(&mesh, &v, 2.0);
        let inner = mesh
            .neighbours()
            .iter()
            .position(|nb| nb.iter().all(|&o| o != NO_TET))
            .unwrap();
        assert!((r[inner] - 2.0 * volume_sphere).abs() < 1e-12);
    }
}
