//! Building a [`TetMesh`]: input validation, reorientation, rest-vertex stars, face adjacency.

use crate::error::TopologyError;
use crate::faces::{signed_volume, FACE_CORNERS};
use crate::mesh::{mean_distinct_edge, BuildReport, TetMesh, NO_TET};
use crate::split::SplitScratch;

/// Relative volume tolerance: a tet is rejected when `|volume| <= VOLUME_TOLERANCE * lambda^3`.
///
/// Why this value: a regular tet of edge `lambda` has volume `lambda^3 / (6 sqrt 2) ~ 0.12
/// lambda^3`, and the rounding error of the determinant is a few `1e-16 lambda^3`. A tet below
/// `1e-12 lambda^3` is eleven orders of magnitude flatter than a healthy one and only four above
/// rounding noise: its orientation, barycentre and particle volume cannot be trusted.
pub const VOLUME_TOLERANCE: f64 = 1e-12;

impl TetMesh {
    /// Builds a mesh from rest vertex positions (length) and tets (vertex indices).
    ///
    /// Validates that the mesh is non-empty, coordinates are finite, indices are in range, every
    /// tet has four distinct corners and `|volume| > 1e-12 * lambda^3` (`lambda` = mean distinct
    /// edge length, see [`VOLUME_TOLERANCE`]). Negatively oriented tets are reoriented by swapping
    /// corners 2 and 3 and counted in [`BuildReport::inverted_fixed`]. A face shared by three or
    /// more tets is a non-manifold error naming the tets.
    pub fn new(
        vertices: Vec<[f64; 3]>,
        mut tets: Vec<[u32; 4]>,
    ) -> Result<(TetMesh, BuildReport), TopologyError> {
        if tets.is_empty() {
            return Err(TopologyError::Empty);
        }
        if tets.len() >= NO_TET as usize {
            return Err(TopologyError::TetOutOfRange {
                tet: NO_TET,
                num_tets: tets.len(),
            });
        }
        for (v, p) in vertices.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(TopologyError::NonFiniteVertex {
                    vertex: v as u32,
                    coords: *p,
                });
            }
        }
        check_corners(vertices.len(), &tets)?;
        let mean_edge = mean_distinct_edge(&vertices, &tets);
        let report = orient(&vertices, &mut tets, mean_edge)?;
        let (star_offsets, star_tets) = build_star(vertices.len(), &tets);
        let (neighbours, boundary_faces) = build_adjacency(&tets)?;
        let n = vertices.len();
        let mesh = TetMesh {
            pos: vertices.clone(),
            rest: vertices,
            origin: (0..n as u32).collect(),
            crack: vec![0; tets.len()],
            tets,
            neighbours,
            star_offsets,
            star_tets,
            mean_edge,
            boundary_faces,
            scratch: SplitScratch::new(n),
            accum: Vec::new(),
        };
        Ok((mesh, report))
    }
}

/// Indices in range and four distinct corners.
fn check_corners(num_vertices: usize, tets: &[[u32; 4]]) -> Result<(), TopologyError> {
    for (t, tet) in tets.iter().enumerate() {
        for &v in tet {
            if v as usize >= num_vertices {
                return Err(TopologyError::VertexOutOfRange {
                    tet: t as u32,
                    vertex: v,
                    num_vertices,
                });
            }
        }
        for i in 0..4 {
            for j in i + 1..4 {
                if tet[i] == tet[j] {
                    return Err(TopologyError::RepeatedCorner {
                        tet: t as u32,
                        corners: *tet,
                    });
                }
            }
        }
    }
    Ok(())
}

/// Rejects flat tets and reorients negative ones.
fn orient(
    vertices: &[[f64; 3]],
    tets: &mut [[u32; 4]],
    mean_edge: f64,
) -> Result<BuildReport, TopologyError> {
    let tolerance = VOLUME_TOLERANCE * mean_edge.powi(3);
    let mut report = BuildReport::default();
    for (t, tet) in tets.iter_mut().enumerate() {
        let [a, b, c, d] = tet.map(|v| vertices[v as usize]);
        let volume = signed_volume(a, b, c, d);
        if volume.abs() <= tolerance || !volume.is_finite() {
            return Err(TopologyError::Degenerate {
                tet: t as u32,
                volume,
                tolerance,
            });
        }
        if volume < 0.0 {
            tet.swap(2, 3);
            report.inverted_fixed += 1;
        }
    }
    Ok(report)
}

/// Rest-vertex -> tets star in CSR form, tets ascending within each vertex.
pub(crate) fn build_star(num_vertices: usize, tets: &[[u32; 4]]) -> (Vec<usize>, Vec<u32>) {
    let mut offsets = vec![0usize; num_vertices + 1];
    for tet in tets {
        for &v in tet {
            offsets[v as usize + 1] += 1;
        }
    }
    for i in 0..num_vertices {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut star = vec![0u32; offsets[num_vertices]];
    for (t, tet) in tets.iter().enumerate() {
        for &v in tet {
            star[fill[v as usize]] = t as u32;
            fill[v as usize] += 1;
        }
    }
    (offsets, star)
}

/// Tet across each local face, and the number of boundary faces.
fn build_adjacency(tets: &[[u32; 4]]) -> Result<(Vec<[u32; 4]>, usize), TopologyError> {
    // Key: sorted vertex ids of a face. Value: the first (tet * 4 + face) slot seen, and the
    // second one or NO_TET.
    let mut faces: hashbrown::HashMap<[u32; 3], [u32; 2]> =
        hashbrown::HashMap::with_capacity(tets.len() * 2 + 4);
    let mut neighbours = vec![[NO_TET; 4]; tets.len()];
    for (t, tet) in tets.iter().enumerate() {
        for (f, corners) in FACE_CORNERS.iter().enumerate() {
            let mut key = corners.map(|k| tet[k]);
            key.sort_unstable();
            let slot = (t * 4 + f) as u32;
            let entry = faces.entry(key).or_insert([slot, NO_TET]);
            if entry[0] == slot {
                continue;
            }
            if entry[1] != NO_TET {
                return Err(TopologyError::NonManifoldFace {
                    face: key,
                    tets: [entry[0] / 4, entry[1] / 4, t as u32],
                });
            }
            entry[1] = slot;
            let (other_t, other_f) = ((entry[0] / 4) as usize, (entry[0] % 4) as usize);
            if neighbours[t].contains(&(other_t as u32)) {
                // Already adjacent through another face: only possible for a duplicated tet.
                return Err(TopologyError::DuplicateTet {
                    tet: t as u32,
                    other: other_t as u32,
                });
            }
            neighbours[t][f] = other_t as u32;
            neighbours[other_t][other_f] = t as u32;
        }
    }
    let boundary = faces.values().filter(|s| s[1] == NO_TET).count();
    Ok((neighbours, boundary))
}
