//! Shading data for a piece surface: vertices split where the surface must not look smooth
//! (along crack edges and sharp corners), with normals, texture coordinates and velocities,
//! ready for a renderer or a cache file.
//!
//! Around each vertex the faces are grouped: two outer (non-crack) faces that share an edge at
//! the vertex join when their normals differ by less than the sharp angle; every crack face is
//! a group of its own, so cracks shade flat. Each group becomes one output vertex with the
//! angle-weighted mean normal of its faces. Texture coordinates are a box projection of the
//! rest positions (the material's own coordinates, so a texture sticks to the material as it
//! moves and breaks): along the dominant axis of the group's rest normal, scaled so that the
//! object's rest bounding box spans 0 to 1.

use crate::faces::{cross, dot, norm, sub};
use crate::mesh::TetMesh;
use crate::surface::Surface;

/// The default angle between two outer faces above which their shared edge shades sharp
/// (radians): 60 degrees. A box's 90 degree edges are sharp; the built-in mesher's sphere at
/// 8 cells across has faces meeting at up to 56.4 degrees (median 10.5, 90th percentile 34;
/// `tests::the_sphere_shades_smooth`), so it shades smooth. Its snapped surface is bumpier at
/// finer lattices (up to 107 degrees at 16 cells, 1% of edges above 82), where a few creases
/// show.
pub const SHARP_ANGLE: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// How [`Surface::shade`] splits and maps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingOptions {
    /// Outer faces whose normals differ by this angle or more meet at a sharp edge (radians).
    pub sharp_angle: f64,
    /// The rest point that maps to texture coordinate 0 (length).
    pub uv_origin: [f64; 3],
    /// The rest length that spans one texture unit (length, > 0).
    pub uv_size: f64,
}

/// A surface with its vertices split for shading. Faces keep the order and orientation of the
/// [`Surface`] they came from; `source[k]` is the surface (compact) vertex that output vertex
/// `k` copies.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ShadedSurface {
    /// Current positions (length).
    pub vertices: Vec<[f64; 3]>,
    /// Unit normals, pointing out of the piece.
    pub normals: Vec<[f64; 3]>,
    /// Velocities (length/time), those of the surface vertices copied.
    pub velocities: Vec<[f64; 3]>,
    /// Texture coordinates (dimensionless).
    pub uv: Vec<[f64; 2]>,
    /// The surface vertex each output vertex copies.
    pub source: Vec<u32>,
    /// Triangles as output vertex indices, outward.
    pub faces: Vec<[u32; 3]>,
    /// 1 for a crack face, 0 for an original boundary face.
    pub crack: Vec<u8>,
    /// Piece id of each face.
    pub piece: Vec<u32>,
}

impl TetMesh {
    /// [`ShadingOptions`] with the default sharp angle and texture coordinates that span the
    /// rest bounding box's longest side from its lower corner.
    pub fn shading_options(&self) -> ShadingOptions {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.rest {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        ShadingOptions {
            sharp_angle: SHARP_ANGLE,
            uv_origin: if lo[0].is_finite() { lo } else { [0.0; 3] },
            uv_size: if size > 0.0 { size } else { 1.0 },
        }
    }

    /// Splits `surface` (extracted from this mesh) for shading, with `vertex_velocities` given
    /// per mesh vertex (see [`TetMesh::vertex_velocities`]).
    ///
    /// Panics if `vertex_velocities` does not have one entry per mesh vertex.
    #[track_caller]
    pub fn shade(
        &self,
        surface: &Surface,
        vertex_velocities: &[[f64; 3]],
        options: &ShadingOptions,
    ) -> ShadedSurface {
        assert_eq!(
            vertex_velocities.len(),
            self.pos.len(),
            "one velocity per mesh vertex"
        );
        let mut rest: Vec<[f64; 3]> = surface
            .vertex_ids
            .iter()
            .map(|&v| self.rest[self.origin[v as usize] as usize])
            .collect();
        let mut velocities: Vec<[f64; 3]> = surface
            .vertex_ids
            .iter()
            .map(|&v| vertex_velocities[v as usize])
            .collect();
        // A vertex added at an edge's middle takes the mean of the ends.
        for &(m, a, b) in &surface.midpoints {
            let mean = |x: &[[f64; 3]]| -> [f64; 3] {
                std::array::from_fn(|k| 0.5 * (x[a as usize][k] + x[b as usize][k]))
            };
            rest[m as usize] = mean(&rest);
            velocities[m as usize] = mean(&velocities);
        }
        surface.shade(&rest, &velocities, options)
    }
}

impl Surface {
    /// Splits the vertices for shading (see the module documentation); `rest` and `velocities`
    /// are given per surface vertex.
    ///
    /// Panics if `rest` or `velocities` does not have one entry per vertex.
    #[track_caller]
    pub fn shade(
        &self,
        rest: &[[f64; 3]],
        velocities: &[[f64; 3]],
        options: &ShadingOptions,
    ) -> ShadedSurface {
        let n = self.vertices.len();
        assert_eq!(rest.len(), n, "one rest position per surface vertex");
        assert_eq!(velocities.len(), n, "one velocity per surface vertex");
        let unit = |p: &[[f64; 3]], f: &[u32; 3]| {
            let [a, b, c] = f.map(|k| p[k as usize]);
            let m = cross(sub(b, a), sub(c, a));
            let l = norm(m);
            if l > 0.0 {
                [m[0] / l, m[1] / l, m[2] / l]
            } else {
                [0.0; 3]
            }
        };
        let normal: Vec<[f64; 3]> = self.faces.iter().map(|f| unit(&self.vertices, f)).collect();
        let rest_normal: Vec<[f64; 3]> = self.faces.iter().map(|f| unit(rest, f)).collect();
        let (start, around) = self.faces_around_vertices();
        let cos_sharp = options.sharp_angle.cos();
        let mut out = ShadedSurface {
            faces: vec![[0; 3]; self.faces.len()],
            crack: self.crack.clone(),
            piece: self.piece.clone(),
            ..ShadedSurface::default()
        };
        let mut group: Vec<usize> = Vec::new();
        for v in 0..n {
            let ring = &around[start[v]..start[v + 1]];
            // Union-find over the faces around v; roots are the lowest ring position.
            group.clear();
            group.extend(0..ring.len());
            for i in 0..ring.len() {
                for j in i + 1..ring.len() {
                    let (fi, fj) = (ring[i].0 as usize, ring[j].0 as usize);
                    if self.crack[fi] != 0 || self.crack[fj] != 0 {
                        continue;
                    }
                    let shares_edge = self.faces[fi]
                        .iter()
                        .any(|&w| w as usize != v && self.faces[fj].contains(&w));
                    if shares_edge && dot(normal[fi], normal[fj]) > cos_sharp {
                        let (a, b) = (root(&mut group, i), root(&mut group, j));
                        group[a.max(b)] = a.min(b);
                    }
                }
            }
            for i in 0..ring.len() {
                if root(&mut group, i) != i {
                    continue;
                }
                // A new output vertex for the group rooted at i.
                let id = out.vertices.len() as u32;
                let mut sum = [0.0; 3];
                let mut rest_sum = [0.0; 3];
                for (j, &(f, c)) in ring.iter().enumerate().skip(i) {
                    if root(&mut group, j) != i {
                        continue;
                    }
                    let (f, c) = (f as usize, c as usize);
                    out.faces[f][c] = id;
                    let w = corner_angle(&self.vertices, &self.faces[f], c);
                    let wr = corner_angle(rest, &self.faces[f], c);
                    for k in 0..3 {
                        sum[k] += w * normal[f][k];
                        rest_sum[k] += wr * rest_normal[f][k];
                    }
                }
                let fallback = normal[ring[i].0 as usize];
                let nv = normalized(sum)
                    .or(normalized(fallback))
                    .unwrap_or([0.0, 0.0, 1.0]);
                out.vertices.push(self.vertices[v]);
                out.normals.push(nv);
                out.velocities.push(velocities[v]);
                out.uv.push(project(rest[v], rest_sum, options));
                out.source.push(v as u32);
            }
        }
        out
    }
}

/// Root of `i` in the local union-find.
fn root(group: &mut [usize], mut i: usize) -> usize {
    while group[i] != i {
        group[i] = group[group[i]];
        i = group[i];
    }
    i
}

/// The interior angle (radians) of triangle `face` at its corner `c`.
fn corner_angle(p: &[[f64; 3]], face: &[u32; 3], c: usize) -> f64 {
    let a = p[face[c] as usize];
    let b = p[face[(c + 1) % 3] as usize];
    let d = p[face[(c + 2) % 3] as usize];
    let (u, w) = (sub(b, a), sub(d, a));
    norm(cross(u, w)).atan2(dot(u, w))
}

fn normalized(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = norm(a);
    (l > 0.0 && l.is_finite()).then(|| [a[0] / l, a[1] / l, a[2] / l])
}

/// Box projection of the rest point `x` along the dominant axis of `axis` (x when it is zero).
fn project(x: [f64; 3], axis: [f64; 3], options: &ShadingOptions) -> [f64; 2] {
    let a = axis.map(f64::abs);
    let (u, v) = if a[0] >= a[1] && a[0] >= a[2] {
        (1, 2)
    } else if a[1] >= a[2] {
        (0, 2)
    } else {
        (0, 1)
    };
    let s = 1.0 / options.uv_size;
    [
        (x[u] - options.uv_origin[u]) * s,
        (x[v] - options.uv_origin[v]) * s,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives;

    fn options() -> ShadingOptions {
        ShadingOptions {
            sharp_angle: SHARP_ANGLE,
            uv_origin: [0.0; 3],
            uv_size: 1.0,
        }
    }

    fn still(s: &Surface) -> Vec<[f64; 3]> {
        vec![[0.0; 3]; s.vertices.len()]
    }

    #[test]
    fn a_box_splits_at_its_edges_and_corners() {
        let mesh = primitives::box_mesh([0.0; 3], [1.0, 2.0, 3.0], [2, 2, 2]);
        let s = mesh.surface();
        let shaded = s.shade(&s.vertices, &still(&s), &options());
        // Every normal is exactly one of the six axis directions, the face's own.
        for (f, face) in shaded.faces.iter().enumerate() {
            let [a, b, c] = face.map(|k| shaded.vertices[k as usize]);
            let fnormal = cross(sub(b, a), sub(c, a));
            for &k in face {
                let nv = shaded.normals[k as usize];
                assert_eq!(
                    nv.iter().filter(|x| x.abs() == 1.0).count(),
                    1,
                    "face {f}: {nv:?}"
                );
                assert!(dot(nv, fnormal) > 0.0);
            }
        }
        // A corner vertex of the box has three copies, an edge vertex two, a side vertex one:
        // (8 corners * 3 + 12 edges * 1 middle vertex * 2 + 6 sides * 1) for 2x2x2 cells.
        assert_eq!(shaded.vertices.len(), 8 * 3 + 12 * 2 + 6);
        assert!(shaded
            .source
            .iter()
            .all(|&v| (v as usize) < s.vertices.len()));
    }

    #[test]
    fn the_sphere_shades_smooth() {
        let (v, f) = crate::mesher::sphere_surface(1.0, 24);
        let out = crate::mesher::mesh_surface(
            &v,
            &f,
            &crate::mesher::MesherOptions {
                resolution: Some(8),
                ..Default::default()
            },
        )
        .unwrap();
        let mesh = TetMesh::new(out.vertices, out.tets).unwrap().0;
        let s = mesh.surface();
        // The largest angle between two faces sharing an edge: under the sharp angle.
        let mut largest: f64 = 0.0;
        let unit = |f: &[u32; 3]| {
            let [a, b, c] = f.map(|k| s.vertices[k as usize]);
            normalized(cross(sub(b, a), sub(c, a))).unwrap()
        };
        for (i, f) in s.faces.iter().enumerate() {
            for g in &s.faces[i + 1..] {
                if f.iter().filter(|v| g.contains(v)).count() == 2 {
                    largest = largest.max(dot(unit(f), unit(g)).clamp(-1.0, 1.0).acos());
                }
            }
        }
        assert!(largest < SHARP_ANGLE, "{}", largest.to_degrees());
        let shaded = s.shade(&s.vertices, &still(&s), &options());
        assert_eq!(shaded.vertices.len(), s.vertices.len());
        // The normals point outward, within the facets' own deviation from the sphere.
        for (p, nv) in shaded.vertices.iter().zip(&shaded.normals) {
            let radial = normalized(*p).unwrap();
            assert!(dot(radial, *nv) > largest.cos(), "{p:?} {nv:?}");
        }
    }

    #[test]
    fn crack_faces_shade_flat_on_their_own_vertices() {
        let mut mesh = primitives::box_mesh([0.0; 3], [2.0, 1.0, 1.0], [2, 1, 1]);
        // Cut the bonds across x = 1 and move the right half away.
        let centres = mesh.rest_barycentres();
        let mut broken = Vec::new();
        for (t, nb) in mesh.neighbours().iter().enumerate() {
            for &o in nb {
                if o != crate::NO_TET && (centres[t][0] < 1.0) != (centres[o as usize][0] < 1.0) {
                    broken.push((t as u32, o));
                }
            }
        }
        mesh.crack_bonds(&broken);
        mesh.split();
        let s = mesh.surface();
        assert!(s.crack.contains(&1));
        let velocity: Vec<[f64; 3]> = (0..s.vertices.len())
            .map(|k| [k as f64, 0.0, 0.0])
            .collect();
        let shaded = s.shade(&s.vertices, &velocity, &options());
        let mut seen = vec![0; shaded.vertices.len()];
        for (f, face) in shaded.faces.iter().enumerate() {
            if shaded.crack[f] == 1 {
                for &k in face {
                    seen[k as usize] += 1;
                    // Flat: the face's own normal, +x or -x on the cut.
                    assert_eq!(shaded.normals[k as usize][0].abs(), 1.0);
                }
            }
        }
        // No crack corner shares its vertex with any other face.
        for (f, face) in shaded.faces.iter().enumerate() {
            if shaded.crack[f] == 0 {
                assert!(face.iter().all(|&k| seen[k as usize] == 0));
            }
        }
        assert!(seen.iter().all(|&c| c <= 1));
        // Positions and velocities are those of the vertex copied; crack faces are projected
        // along x: their texture coordinates are (y, z).
        for (k, &seen_k) in seen.iter().enumerate() {
            let v = shaded.source[k] as usize;
            assert_eq!(shaded.vertices[k], s.vertices[v]);
            assert_eq!(shaded.velocities[k], velocity[v]);
            if seen_k == 1 {
                assert_eq!(shaded.uv[k], [s.vertices[v][1], s.vertices[v][2]]);
            }
        }
    }

    #[test]
    fn a_degenerate_face_gets_a_finite_normal() {
        let s = Surface {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vertex_ids: vec![0, 1, 2],
            faces: vec![[0, 1, 2]],
            crack: vec![0],
            piece: vec![0],
            midpoints: Vec::new(),
        };
        let shaded = s.shade(&s.vertices, &still(&s), &options());
        assert!(shaded.normals.iter().flatten().all(|x| x.is_finite()));
        assert!(shaded.uv.iter().flatten().all(|x| x.is_finite()));
    }
}
