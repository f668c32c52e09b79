//! The scene's object as a tet mesh (primitive, tet file or meshed surface) and its initial
//! cracks.

use perifrac_physics::NO_NEIGHBOUR;
use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::mesher::{cylinder_surface, mesh_surface, sphere_surface, MesherOptions};
use perifrac_topology::{primitives, TetMesh, NO_TET};

use crate::error::SceneError;
use crate::load::Scene;
use crate::schema::{PrecrackSpec, SceneFile};

use super::check::Ctx;
use super::defaults;

/// The tet mesh the scene names, scaled and translated.
pub(super) fn build_mesh(ctx: &Ctx, scene: &Scene) -> Result<TetMesh, SceneError> {
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
    let round = |vertices: Vec<[f64; 3]>, faces: Vec<[u32; 3]>| {
        let opts = MesherOptions {
            edge_length: None,
            resolution: m.resolution,
        };
        mesh_surface(&vertices, &faces, &opts)
            .map(|o| (o.vertices, o.tets))
            .map_err(|e| mesh_err(e.to_string()))
    };
    let (mut vertices, tets) = match (m.primitive.as_deref(), &m.file) {
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
            let cells = match (m.cells, m.resolution) {
                (Some(_), Some(_)) => {
                    return Err(ctx.err("mesh", "give either cells or resolution, not both"))
                }
                (Some(c), None) => {
                    if c.contains(&0) {
                        return Err(ctx.err("mesh.cells", format!("{c:?}: counts must be >= 1")));
                    }
                    c
                }
                (None, r) => {
                    primitives::cells_for_resolution(size, r.unwrap_or(defaults::BOX_RESOLUTION))
                }
            };
            if cells.iter().product::<usize>() > 20_000_000 {
                return Err(ctx.err("mesh.cells", format!("{cells:?} is too many cells")));
            }
            primitives::box_data([0.0; 3], size, cells)
        }
        (Some("sphere"), None) => {
            let r = ctx.positive(
                "mesh.radius",
                m.radius
                    .ok_or_else(|| ctx.err("mesh.radius", "a sphere needs a radius"))?,
                "m",
            )?;
            let (v, f) = sphere_surface(r, defaults::ROUND_SEGMENTS);
            round(v, f)?
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
            round(v, f)?
        }
        (Some(other), None) => {
            return Err(ctx.err(
                "mesh.primitive",
                format!("unknown primitive \"{other}\" (known: box, sphere, cylinder)"),
            ))
        }
        (None, Some(file)) => {
            let path = scene.base_dir().join(file);
            if !path.is_file() {
                return Err(ctx.err("mesh.file", format!("{} not found", path.display())));
            }
            let ext = path
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            if matches!(ext.as_str(), "obj" | "off" | "ply") {
                let s = perifrac_io::read_surface(&path).map_err(|e| mesh_err(e.to_string()))?;
                round(s.vertices, s.faces)?
            } else {
                let d = perifrac_io::read_tet_mesh(&path).map_err(|e| mesh_err(e.to_string()))?;
                (d.vertices, d.tets)
            }
        }
    };
    for v in &mut vertices {
        for k in 0..3 {
            v[k] = v[k] * scale + translate[k];
        }
    }
    TetMesh::new(vertices, tets)
        .map(|(mesh, _)| mesh)
        .map_err(|e| mesh_err(e.to_string()))
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
