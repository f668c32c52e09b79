//! The scene's object as a tet mesh (primitive, tet file or meshed surface) and its initial
//! cracks.

use perifrac_physics::NO_NEIGHBOUR;
use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::mesher::{
    box_cut_data, cylinder_surface, estimated_tets, mesh_surface, sphere_surface, BoxCut,
    MesherOptions,
};
use perifrac_topology::{primitives, TetMesh, NO_TET};

use crate::budget::MeshShape;
use crate::error::SceneError;
use crate::load::Scene;
use crate::schema::{PrecrackSpec, SceneFile};

use super::check::Ctx;
use super::defaults;

/// What the scene's object is made from, read and checked but not yet built: a box's counts,
/// a surface to mesh, or a tet file's arrays.
enum Source {
    /// A box primitive from the origin (`size` in m, unscaled), of `cells` cuboids, cut as
    /// `cut` says.
    Box {
        size: [f64; 3],
        cells: [usize; 3],
        cut: BoxCut,
    },
    /// A closed surface for the built-in mesher (a round primitive's or a file's).
    Surface {
        vertices: Vec<[f64; 3]>,
        faces: Vec<[u32; 3]>,
    },
    /// A tet mesh file and its arrays.
    Tets {
        path: std::path::PathBuf,
        data: perifrac_io::TetMeshData,
    },
}

/// The scene's object before it is built, with what the work estimate needs.
pub(super) struct Planned {
    source: Source,
    /// Counts, mean edge and mean tet volume of the mesh it will be (estimated for a surface).
    pub(super) shape: MeshShape,
    scale: f64,
    translate: [f64; 3],
}

/// Reads and checks the scene's `[mesh]` without building it: the primitive's sizes and cell
/// counts (checked arithmetic, cells a tet mesh can have), a file's contents. Nothing in
/// proportion to the mesh is allocated but a file's own arrays.
pub(super) fn plan(ctx: &Ctx, scene: &Scene) -> Result<Planned, SceneError> {
    let m = &scene.file.mesh;
    let mesh_err = |message: String| SceneError::Mesh {
        file: scene.path.clone(),
        message,
    };
    let translate = ctx.finite3("mesh.translate", m.translate.unwrap_or([0.0; 3]))?;
    let scale = ctx.positive("mesh.scale", m.scale.unwrap_or(1.0), "")?;
    if let Some(r) = m.resolution {
        if r == 0 {
            return Err(ctx.err("mesh.resolution", "must be at least 1"));
        }
    }
    if m.primitive.as_deref() != Some("box") {
        for (key, given) in [
            ("mesh.structure", m.structure.is_some()),
            ("mesh.seed", m.seed.is_some()),
        ] {
            if given {
                return Err(ctx.err(
                    key,
                    "only a box primitive takes it (other objects are meshed from their surface)",
                ));
            }
        }
    }
    let opts = MesherOptions {
        edge_length: None,
        resolution: m.resolution,
    };
    let surface = |vertices: Vec<[f64; 3]>, faces: Vec<[u32; 3]>| {
        let shape = MeshShape::of_bcc(estimated_tets(&vertices, &opts));
        (Source::Surface { vertices, faces }, shape)
    };
    let (source, shape) = match (m.primitive.as_deref(), &m.file) {
        (Some(_), Some(_)) => {
            return Err(ctx.err("mesh", "give either primitive or file, not both"))
        }
        (None, None) => {
            return Err(ctx.err(
                "mesh",
                "name a primitive (\"box\", \"sphere\", \"cylinder\") or a file",
            ))
        }
        (Some("box"), None) => {
            let size = m
                .size
                .ok_or_else(|| ctx.err("mesh.size", "a box needs size = [x, y, z]"))?;
            for (k, &s) in size.iter().enumerate() {
                ctx.positive(&format!("mesh.size[{k}]"), s, "m")?;
            }
            let (cells, cells_key) = match (m.cells, m.resolution) {
                (Some(_), Some(_)) => {
                    return Err(ctx.err("mesh", "give either cells or resolution, not both"))
                }
                (Some(c), None) => {
                    if c.contains(&0) {
                        return Err(ctx.err("mesh.cells", format!("{c:?}: counts must be >= 1")));
                    }
                    (c, "mesh.cells")
                }
                (None, r) => (
                    primitives::cells_for_resolution(size, r.unwrap_or(defaults::BOX_RESOLUTION)),
                    "mesh.resolution",
                ),
            };
            let counts =
                primitives::box_counts(cells).map_err(|e| ctx.err(cells_key, e.to_string()))?;
            // The box as it will stand, scaled: its cells must make tets with a volume.
            let scaled = size.map(|s| s * scale);
            primitives::check_box([0.0; 3], scaled, cells)
                .map_err(|e| ctx.err("mesh.size", format!("{size:?} m in {cells:?} cells: {e}")))?;
            let cell: [f64; 3] = std::array::from_fn(|k| scaled[k] / cells[k] as f64);
            let lattice = match m.structure.as_deref() {
                None | Some("unstructured") => None,
                Some("lattice") => Some(primitives::Lattice::Kuhn),
                Some("mirrored") => Some(primitives::Lattice::Mirrored),
                Some(other) => {
                    return Err(ctx.err(
                        "mesh.structure",
                        format!(
                            "unknown structure \"{other}\" (known: unstructured, lattice, mirrored)"
                        ),
                    ))
                }
            };
            let cut = match lattice {
                None => BoxCut::Unstructured(m.seed.unwrap_or(defaults::MESH_SEED)),
                Some(_) if m.seed.is_some() => {
                    return Err(ctx.err(
                        "mesh.seed",
                        "a lattice box has no random points: drop seed or set structure = \"unstructured\"",
                    ))
                }
                Some(l) => BoxCut::Lattice(l),
            };
            (
                Source::Box { size, cells, cut },
                MeshShape::of_box(cell, counts),
            )
        }
        (Some("sphere"), None) => {
            let r = ctx.positive(
                "mesh.radius",
                m.radius
                    .ok_or_else(|| ctx.err("mesh.radius", "a sphere needs a radius"))?,
                "m",
            )?;
            let (v, f) = sphere_surface(r, defaults::ROUND_SEGMENTS);
            surface(v, f)
        }
        (Some("cylinder"), None) => {
            let r = m
                .radius
                .ok_or_else(|| ctx.err("mesh.radius", "a cylinder needs a radius"))?;
            let h = m
                .height
                .ok_or_else(|| ctx.err("mesh.height", "a cylinder needs a height"))?;
            ctx.positive("mesh.radius", r, "m")?;
            ctx.positive("mesh.height", h, "m")?;
            let (v, f) = cylinder_surface(r, h, 2 * defaults::ROUND_SEGMENTS);
            surface(v, f)
        }
        (Some(other), None) => {
            return Err(ctx.err(
                "mesh.primitive",
                format!("unknown primitive \"{other}\" (known: box, sphere, cylinder)"),
            ))
        }
        (None, Some(file)) => {
            let path = scene.base_dir().join(file);
            if path.is_dir() {
                return Err(ctx.err(
                    "mesh.file",
                    format!("{} is a directory, not a mesh file", path.display()),
                ));
            }
            if !path.is_file() {
                return Err(ctx.err("mesh.file", format!("{} not found", path.display())));
            }
            let ext = path
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            if matches!(ext.as_str(), "obj" | "off" | "ply") {
                let s = perifrac_io::read_surface(&path).map_err(|e| mesh_err(e.to_string()))?;
                surface(s.vertices, s.faces)
            } else {
                let data =
                    perifrac_io::read_tet_mesh(&path).map_err(|e| mesh_err(e.to_string()))?;
                let shape = MeshShape::of_tets(&data.vertices, &data.tets);
                (Source::Tets { path, data }, shape)
            }
        }
    };
    Ok(Planned {
        source,
        shape,
        scale,
        translate,
    })
}

/// Builds the mesh `plan` read: meshes a surface, makes a box, scales and translates, and
/// validates the tets (a problem in a tet file names its line, tets counted from 1).
pub(super) fn build(scene: &Scene, planned: Planned) -> Result<TetMesh, SceneError> {
    let mesh_err = |message: String| SceneError::Mesh {
        file: scene.path.clone(),
        message,
    };
    let Planned {
        source,
        scale,
        translate,
        ..
    } = planned;
    let mut lines = None;
    let (mut vertices, tets) = match source {
        Source::Box { size, cells, cut } => {
            box_cut_data([0.0; 3], size, cells, cut).map_err(|e| mesh_err(e.to_string()))?
        }
        Source::Surface { vertices, faces } => {
            let opts = MesherOptions {
                edge_length: None,
                resolution: scene.file.mesh.resolution,
            };
            mesh_surface(&vertices, &faces, &opts)
                .map(|o| (o.vertices, o.tets))
                .map_err(|e| mesh_err(e.to_string()))?
        }
        Source::Tets { path, data } => {
            lines = Some((perifrac_io::tet_lines_file(&path), data.tet_lines));
            (data.vertices, data.tets)
        }
    };
    for v in &mut vertices {
        for k in 0..3 {
            v[k] = v[k] * scale + translate[k];
        }
    }
    TetMesh::new(vertices, tets)
        .map(|(mesh, _)| mesh)
        .map_err(|e| match &lines {
            Some((file, lines)) => mesh_err(e.located(file, lines)),
            None => mesh_err(e.to_string()),
        })
}

/// Cuts the scene's initial cracks into `mesh` (and splits its vertices). Returns the face
/// adjacency for the family walk, with the cut faces hidden so that no bond crosses them, and
/// the number of faces cut.
pub(super) fn precracks(
    ctx: &Ctx,
    f: &SceneFile,
    mesh: &mut TetMesh,
    rest: &[[f64; 3]],
) -> Result<(Vec<[u32; 4]>, usize), SceneError> {
    let mut faces = 0;
    for (k, pc) in f.precrack.iter().enumerate() {
        faces += precrack(ctx, k, pc, mesh, rest)?;
    }
    // A cracked face is marked on both sides, so hiding it per side hides the pair.
    let adjacency = (0..mesh.num_tets())
        .map(|t| {
            let mut adj = mesh.neighbours()[t];
            for (face, u) in adj.iter_mut().enumerate() {
                if mesh.is_cracked(t as u32, face as u8) {
                    *u = NO_NEIGHBOUR;
                }
            }
            adj
        })
        .collect();
    if faces > 0 {
        mesh.split();
    }
    Ok((adjacency, faces))
}

/// Cuts the faces of `precrack[k]`; returns how many.
fn precrack(
    ctx: &Ctx,
    k: usize,
    pc: &PrecrackSpec,
    mesh: &mut TetMesh,
    rest: &[[f64; 3]],
) -> Result<usize, SceneError> {
    let n = ctx.direction(&format!("precrack[{k}].normal"), pc.normal)?;
    let side = |x: [f64; 3]| {
        (x[0] - pc.point[0]) * n[0] + (x[1] - pc.point[1]) * n[1] + (x[2] - pc.point[2]) * n[2]
    };
    let mut cut = Vec::new();
    for (t, adj) in mesh.neighbours().iter().enumerate() {
        for (face, &u) in adj.iter().enumerate() {
            if u == NO_TET || (u as usize) < t {
                continue;
            }
            let (a, b) = (side(rest[t]), side(rest[u as usize]));
            if (a < 0.0) == (b < 0.0) {
                continue;
            }
            let tet = mesh.tets()[t];
            let mut c = [0.0; 3];
            for &corner in &FACE_CORNERS[face] {
                let p = mesh.rest_positions()[tet[corner] as usize];
                for d in 0..3 {
                    c[d] += p[d] / 3.0;
                }
            }
            if pc.region.contains(c) {
                cut.push((t as u32, face as u8));
            }
        }
    }
    if cut.is_empty() {
        return Err(ctx.err(
            format!("precrack[{k}]"),
            "cuts no face (the plane does not pass between tets inside the region)",
        ));
    }
    for &(t, face) in &cut {
        mesh.crack_face(t, face)
            .map_err(|e| ctx.err(format!("precrack[{k}]"), e.to_string()))?;
    }
    Ok(cut.len())
}
