//! `perifrac info`: a summary of a tet mesh, for people (text) or scripts (`--json`).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use serde::Serialize;

use crate::load::load_tet_mesh;

/// Dihedral angles below this many degrees are reported as slivers (a quality problem).
const SLIVER_DEG: f64 = 5.0;
/// Relative mismatch between tet volume and boundary-enclosed volume that counts as a problem;
/// both are sums of the same exact terms up to rounding, so anything above rounding is a defect.
const VOLUME_MISMATCH: f64 = 1e-9;

/// Everything `info` reports; serialised as-is for `--json`.
#[derive(Serialize)]
pub struct MeshInfo {
    /// Vertex count.
    pub vertices: usize,
    /// Tetrahedron count (= particle count).
    pub tets: usize,
    /// Triangles on the mesh boundary.
    pub boundary_faces: usize,
    /// Total rest volume, in the mesh's units cubed.
    pub volume: f64,
    /// Volume enclosed by the extracted boundary (divergence theorem); equals `volume` for a sound mesh.
    pub boundary_volume: f64,
    /// Mean length of the distinct edges (the paper's lambda).
    pub mean_edge_length: f64,
    /// Axis-aligned bounds, `[min, max]`.
    pub bounds: [[f64; 3]; 2],
    /// Smallest and largest tet volume.
    pub min_tet_volume: f64,
    /// Largest tet volume.
    pub max_tet_volume: f64,
    /// Smallest dihedral angle in degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle in degrees.
    pub max_dihedral_deg: f64,
    /// Smallest radius ratio (3 inradius / circumradius; 1 for a regular tet).
    pub min_radius_ratio: f64,
    /// Mean radius ratio.
    pub mean_radius_ratio: f64,
    /// Counts of all dihedral angles in 10-degree bins from 0 to 180.
    pub dihedral_histogram: Vec<usize>,
    /// Connected pieces through shared faces.
    pub pieces: usize,
    /// Tets given with negative orientation and reoriented on load.
    pub inverted_fixed: usize,
    /// Tets per region label.
    pub labels: BTreeMap<i32, usize>,
    /// Element kinds the reader skipped, with counts.
    pub skipped: BTreeMap<String, usize>,
    /// Problems found, in words; empty for a clean mesh.
    pub problems: Vec<String>,
}

/// Loads `path` and measures it.
pub fn measure(path: &Path) -> Result<MeshInfo> {
    let loaded = load_tet_mesh(path)?;
    let mesh = &loaded.mesh;
    let quality = mesh.quality();
    let surface = mesh.surface();
    let volume = mesh.total_rest_volume();
    let boundary_volume = surface.signed_volume();
    let mut bounds = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for p in mesh.rest_positions() {
        for k in 0..3 {
            bounds[0][k] = bounds[0][k].min(p[k]);
            bounds[1][k] = bounds[1][k].max(p[k]);
        }
    }
    let mut labels = BTreeMap::new();
    for &l in &loaded.tet_labels {
        *labels.entry(l).or_insert(0) += 1;
    }
    let pieces = mesh.pieces().count;

    let mut problems = Vec::new();
    if loaded.report.inverted_fixed > 0 {
        problems.push(format!(
            "{} tets had negative orientation and were reoriented",
            loaded.report.inverted_fixed
        ));
    }
    if pieces > 1 {
        problems.push(format!("the mesh falls into {pieces} separate pieces"));
    }
    if (boundary_volume - volume).abs() > VOLUME_MISMATCH * volume.abs() {
        problems.push(format!(
            "boundary encloses {boundary_volume} but the tets sum to {volume}"
        ));
    }
    if quality.min_dihedral_deg < SLIVER_DEG {
        let slivers: usize = quality.dihedral_histogram[0];
        problems.push(format!(
            "sliver tets: smallest dihedral angle {:.2} deg ({slivers} angles under 10 deg)",
            quality.min_dihedral_deg
        ));
    }
    let listed = loaded.boundary_faces.len();
    let listed_on_boundary = count_on_boundary(&loaded.boundary_faces, &surface);
    if listed > 0 && listed_on_boundary < listed {
        problems.push(format!(
            "the file lists {listed} triangles but only {listed_on_boundary} lie on the tets' \
             boundary ({} faces): the rest are inside the mesh, e.g. a surface embedded in \
             tets that fill a larger region such as its convex hull",
            mesh.boundary_face_count()
        ));
    }

    Ok(MeshInfo {
        vertices: mesh.num_vertices(),
        tets: mesh.num_tets(),
        boundary_faces: mesh.boundary_face_count(),
        volume,
        boundary_volume,
        mean_edge_length: mesh.mean_edge_length(),
        bounds,
        min_tet_volume: quality.min_volume,
        max_tet_volume: quality.max_volume,
        min_dihedral_deg: quality.min_dihedral_deg,
        max_dihedral_deg: quality.max_dihedral_deg,
        min_radius_ratio: quality.min_radius_ratio,
        mean_radius_ratio: quality.mean_radius_ratio,
        dihedral_histogram: quality.dihedral_histogram.to_vec(),
        pieces,
        inverted_fixed: loaded.report.inverted_fixed,
        labels,
        skipped: loaded.skipped.into_iter().collect(),
        problems,
    })
}

/// How many of the file's listed triangles are faces of the tets' boundary (any orientation).
fn count_on_boundary(listed: &[[u32; 3]], surface: &perifrac_topology::Surface) -> usize {
    let key = |mut f: [u32; 3]| {
        f.sort_unstable();
        f
    };
    let boundary: std::collections::HashSet<[u32; 3]> = surface
        .faces
        .iter()
        .map(|f| key(f.map(|v| surface.vertex_ids[v as usize])))
        .collect();
    listed
        .iter()
        .filter(|f| boundary.contains(&key(**f)))
        .count()
}

/// Prints the summary of `path` as text or JSON.
pub fn run(path: &Path, json: bool) -> Result<()> {
    let info = measure(path)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print_human(path, &info);
    }
    Ok(())
}

fn print_human(path: &Path, i: &MeshInfo) {
    let [lo, hi] = i.bounds;
    println!("{}", path.display());
    println!(
        "  {} vertices, {} tets, {} boundary faces, {} piece(s)",
        i.vertices, i.tets, i.boundary_faces, i.pieces
    );
    println!(
        "  volume {:.6e} (boundary encloses {:.6e})",
        i.volume, i.boundary_volume
    );
    println!(
        "  bounds [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    println!("  mean edge length {:.6e}", i.mean_edge_length);
    println!(
        "  tet volume {:.3e} .. {:.3e}; dihedral {:.2} .. {:.2} deg; radius ratio min {:.3}, mean {:.3}",
        i.min_tet_volume,
        i.max_tet_volume,
        i.min_dihedral_deg,
        i.max_dihedral_deg,
        i.min_radius_ratio,
        i.mean_radius_ratio
    );
    println!("  dihedral angles (deg):");
    let peak = i
        .dihedral_histogram
        .iter()
        .copied()
        .max()
        .unwrap_or(0)
        .max(1);
    for (bin, &n) in i.dihedral_histogram.iter().enumerate() {
        if n == 0 {
            continue;
        }
        let bar = "#".repeat((40 * n).div_ceil(peak));
        println!("    {:>3}-{:<3} {:>9} {bar}", bin * 10, bin * 10 + 10, n);
    }
    if i.labels.len() > 1 {
        let parts: Vec<String> = i.labels.iter().map(|(l, n)| format!("{l}: {n}")).collect();
        println!("  regions (label: tets) {}", parts.join(", "));
    }
    for (kind, n) in &i.skipped {
        println!("  skipped {n} {kind}");
    }
    if i.problems.is_empty() {
        println!("  no problems found");
    } else {
        for p in &i.problems {
            println!("  problem: {p}");
        }
    }
}
