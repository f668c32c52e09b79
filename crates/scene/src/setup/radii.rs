//! Contact radii of the particles (docs/model.md section 7).

use std::f64::consts::PI;

use rayon::prelude::*;

use perifrac_physics::math::{cross, dot, norm, sub};
use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::{TetMesh, NO_TET};

/// Contact radius (m) of every particle: `factor` times the radius of the sphere of the tet's
/// volume, `(3 V / 4 pi)^(1/3)`, but for a tet that touches the boundary (a face, an edge or a
/// vertex on it) at most `factor` times the distance from its barycentre to the boundary faces
/// around its vertices. With the cap the particles' contact surface lies within the mesh
/// surface at rest, so an object set down touching the ground starts touching it, not sunk
/// into it: the volume sphere of a boundary tet of a lattice box sticks out by 9% of the cell
/// size, and in an unstructured box a tet with only an edge on the surface can have its
/// barycentre closer to it than its volume sphere's radius. Faces of initial cracks count as
/// boundary. (For a tet's own boundary face the distance is a quarter of its height over it,
/// `3 V / (4 A)`.)
pub(super) fn contact_radii(mesh: &TetMesh, volumes: &[f64], factor: f64) -> Vec<f64> {
    let x = mesh.rest_positions();
    let origin = mesh.vertex_origin();
    let rest = |v: u32| origin[v as usize] as usize;
    // Boundary faces (rest vertex ids) around each rest vertex, as CSR.
    let mut faces: Vec<[usize; 3]> = Vec::new();
    for (t, (tet, nb)) in mesh.tets().iter().zip(mesh.neighbours()).enumerate() {
        for (f, &other) in nb.iter().enumerate() {
            if other == NO_TET || mesh.is_cracked(t as u32, f as u8) {
                faces.push(FACE_CORNERS[f].map(|k| rest(tet[k])));
            }
        }
    }
    let n = x.len();
    let mut start = vec![0usize; n + 1];
    for f in &faces {
        for &v in f {
            start[v + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; start[n]];
    for (i, f) in faces.iter().enumerate() {
        for &v in f {
            around[fill[v]] = i as u32;
            fill[v] += 1;
        }
    }
    // each tet's radius on its own: in parallel, the same values for any thread count
    mesh.tets()
        .par_iter()
        .zip(mesh.neighbours())
        .zip(volumes)
        .enumerate()
        .map(|(t, ((tet, nb), &v))| {
            let mut r = (3.0 * v / (4.0 * PI)).cbrt();
            // Its own boundary faces: the distance to their planes.
            for (f, &other) in nb.iter().enumerate() {
                if other != NO_TET && !mesh.is_cracked(t as u32, f as u8) {
                    continue;
                }
                let [a, b, c] = FACE_CORNERS[f].map(|k| x[rest(tet[k])]);
                let area = 0.5 * norm(cross(sub(b, a), sub(c, a)));
                if area > 0.0 {
                    r = r.min(0.75 * v / area);
                }
            }
            // Every boundary face at one of its vertices: the distance to the triangle.
            let p = tet.iter().fold([0.0; 3], |acc, &k| {
                let q = x[rest(k)];
                [
                    acc[0] + q[0] / 4.0,
                    acc[1] + q[1] / 4.0,
                    acc[2] + q[2] / 4.0,
                ]
            });
            for &k in tet {
                let k = rest(k);
                for &f in &around[start[k]..start[k + 1]] {
                    let [a, b, c] = faces[f as usize].map(|i| x[i]);
                    r = r.min(point_triangle_distance(p, a, b, c));
                }
            }
            factor * r
        })
        .collect()
}

/// Distance (m) from `p` to the triangle `a b c` (a degenerate one: to its edges).
fn point_triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let n = cross(sub(b, a), sub(c, a));
    let area2 = dot(n, n);
    if area2 > 0.0 {
        // Inside the triangle's prism: the distance to its plane.
        let ap = sub(p, a);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, w)| dot(cross(sub(w, u), sub(p, u)), n) >= 0.0);
        if inside {
            return dot(ap, n).abs() / area2.sqrt();
        }
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(u, w)| {
            let e = sub(w, u);
            let ee = dot(e, e);
            let s = if ee > 0.0 {
                (dot(sub(p, u), e) / ee).clamp(0.0, 1.0)
            } else {
                0.0
            };
            norm(sub(p, [u[0] + s * e[0], u[1] + s * e[1], u[2] + s * e[2]]))
        })
        .fold(f64::INFINITY, f64::min)
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
        // On a lattice of cubic cells no tet's barycentre comes nearer a boundary face at one
        // of its vertices than its own faces or volume sphere allow: the radii are those of
        // the own-face cap alone (as before unstructured boxes needed the vertex faces).
        for (t, (nb, &vt)) in mesh.neighbours().iter().zip(&v).enumerate() {
            let tet = mesh.tets()[t];
            let x = mesh.rest_positions();
            let mut own = (3.0 * vt / (4.0 * PI)).cbrt();
            for (f, &o) in nb.iter().enumerate() {
                if o == NO_TET {
                    let [a, b, c] = FACE_CORNERS[f].map(|k| x[tet[k] as usize]);
                    own = own.min(0.75 * vt / (0.5 * norm(cross(sub(b, a), sub(c, a)))));
                }
            }
            assert_eq!(r[t], 2.0 * own, "tet {t}");
        }
    }

    #[test]
    fn unstructured_boundary_spheres_stay_inside() {
        // An unstructured box has tets with only an edge or a vertex on a side, whose
        // barycentre can lie closer to it than their volume sphere's radius: capped too.
        let (v, t) =
            perifrac_topology::mesher::unstructured_box_data([0.0; 3], [1.0; 3], [6, 6, 6], 3)
                .unwrap();
        let mesh = TetMesh::new(v, t).unwrap().0;
        let volumes = mesh.rest_volumes();
        let r = contact_radii(&mesh, &volumes, 1.0);
        let mut capped_not_by_own_face = 0;
        for (t, (&rt, x)) in r.iter().zip(mesh.rest_barycentres()).enumerate() {
            for k in 0..3 {
                assert!(
                    x[k] - rt >= -1e-12 && x[k] + rt <= 1.0 + 1e-12,
                    "tet {t}: {x:?} {rt}"
                );
            }
            let own = mesh.neighbours()[t].contains(&NO_TET);
            let sphere = (3.0 * volumes[t] / (4.0 * PI)).cbrt();
            capped_not_by_own_face += usize::from(!own && rt < sphere);
        }
        // The case the vertex faces are for occurs here.
        assert!(capped_not_by_own_face > 0);
    }
}
