//! `perifrac mesh`: tet meshes from built-in primitives, or from a closed triangle surface
//! (`.obj`, `.ply`, `.off`) with the built-in mesher or, on request, TetGen.

use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};
use perifrac_io::TetFormat;
use perifrac_topology::mesher::{
    box_cut_data, estimated_tets, mesh_surface, BoxCut, MesherOptions, MesherReport,
};
use perifrac_topology::spec::{parse_primitive, parse_round};
use perifrac_topology::{primitives, TetMesh};

use crate::load::to_data;

/// Cell counts: explicit, or `resolution` cells across the longest side, others in proportion.
pub fn cell_counts(
    size: [f64; 3],
    resolution: usize,
    cells: Option<&[usize]>,
) -> Result<[usize; 3]> {
    if let Some(c) = cells {
        if c.len() != 3 || c.contains(&0) {
            bail!("--cells needs three positive counts, e.g. 40,8,40");
        }
        return Ok([c[0], c[1], c[2]]);
    }
    if resolution == 0 {
        bail!("--resolution must be at least 1");
    }
    Ok(primitives::cells_for_resolution(size, resolution))
}

/// How `perifrac mesh` was asked to size and build the mesh.
#[derive(Debug, Clone, Default)]
pub struct MeshArgs<'a> {
    /// Cells across the longest side.
    pub resolution: Option<usize>,
    /// Exact cell counts (primitives only).
    pub cells: Option<&'a [usize]>,
    /// Target edge length (surfaces only).
    pub edge_length: Option<f64>,
    /// Use TetGen instead of the built-in mesher (surfaces only).
    pub tetgen: bool,
    /// Boxes only: unstructured tets from points of this seed instead of the Kuhn lattice.
    pub unstructured: Option<u64>,
    /// Boxes only: the mirrored Kuhn lattice ([`primitives::Lattice::Mirrored`]).
    pub mirrored: bool,
    /// Go on when the estimated memory passes what is available.
    pub allow_large: bool,
}

/// Cells across the longest side of a primitive when none is given.
const DEFAULT_PRIMITIVE_RESOLUTION: usize = 20;

/// Meshes `input` (an existing surface file, or else a primitive spec) into `output`.
pub fn run(input: &str, output: &Path, args: &MeshArgs) -> Result<()> {
    let path = Path::new(input);
    if path.is_dir() {
        bail!("{input} is a directory, not a surface file (.obj, .ply, .off) or a primitive spec");
    }
    if path.is_file() {
        if args.cells.is_some() {
            bail!("--cells applies to primitives only; use --resolution or --edge-length");
        }
        if args.unstructured.is_some() || args.mirrored {
            bail!("--unstructured and --mirrored apply to box primitives only");
        }
        return if args.tetgen {
            run_tetgen(path, output)
        } else {
            run_surface(path, output, args)
        };
    }
    if let Some((vertices, faces)) = parse_round(input)? {
        if args.cells.is_some() || args.tetgen || args.unstructured.is_some() || args.mirrored {
            bail!("--cells, --tetgen, --unstructured and --mirrored do not apply to `{input}`");
        }
        return mesh_and_write(&vertices, &faces, input, output, args);
    }
    if args.edge_length.is_some() || args.tetgen {
        bail!("--edge-length and --tetgen apply to surface files, and `{input}` is not a file");
    }
    run_primitive(
        input,
        output,
        args.resolution.unwrap_or(DEFAULT_PRIMITIVE_RESOLUTION),
        args.cells,
        match (args.unstructured, args.mirrored) {
            (Some(seed), _) => BoxCut::Unstructured(seed),
            (None, true) => BoxCut::Lattice(primitives::Lattice::Mirrored),
            (None, false) => BoxCut::Lattice(primitives::Lattice::Kuhn),
        },
        args.allow_large,
    )
}

/// Refuses a mesh of `tets` tets on `vertices` vertices whose estimated memory
/// ([`perifrac_scene::budget::mesh_memory`]) passes what is available, unless `allow_large`.
fn check_memory(tets: u64, vertices: u64, allow_large: bool) -> Result<()> {
    use perifrac_scene::budget;
    let need = budget::mesh_memory(tets, vertices);
    let (have, source) = budget::available_memory();
    if need > have && !allow_large {
        bail!(
            "{} tets would need about {} of memory, more than the {} available ({source}); \
             use fewer cells, or pass --allow-large to mesh anyway",
            budget::count(tets),
            budget::bytes(need),
            budget::bytes(have)
        );
    }
    Ok(())
}

/// Meshes a surface file with the built-in mesher and prints its report.
fn run_surface(path: &Path, output: &Path, args: &MeshArgs) -> Result<()> {
    TetFormat::from_path(output)?;
    let surface = perifrac_io::read_surface(path)?;
    let what = path.display().to_string();
    mesh_and_write(&surface.vertices, &surface.faces, &what, output, args)
}

/// Runs the built-in mesher on a surface, prints its report and writes the mesh.
fn mesh_and_write(
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    what: &str,
    output: &Path,
    args: &MeshArgs,
) -> Result<()> {
    let format = TetFormat::from_path(output)?;
    let opts = MesherOptions {
        edge_length: args.edge_length,
        resolution: args.resolution,
    };
    // A BCC lattice has about one vertex per six tets.
    let tets = estimated_tets(vertices, &opts).ceil() as u64;
    check_memory(tets, tets / 6 + 1, args.allow_large)?;
    let out =
        mesh_surface(vertices, faces, &opts).with_context(|| format!("cannot mesh {what}"))?;
    print_report(&out.report);
    write_mesh(output, out.vertices, out.tets, format)
}

/// Builds the topology (which checks orientation), writes the mesh and prints the summary.
fn write_mesh(
    output: &Path,
    vertices: Vec<[f64; 3]>,
    tets: Vec<[u32; 4]>,
    format: TetFormat,
) -> Result<()> {
    let (mesh, build) = TetMesh::new(vertices, tets)?;
    let q = mesh.quality();
    let data = to_data(&mesh, vec![0; mesh.num_tets()], Vec::new());
    perifrac_io::write_tet_mesh(output, &data, format)?;
    eprintln!(
        "wrote {} ({} vertices, {} tets, volume {:.6e}, min dihedral {:.2} deg, \
         {} inverted tets fixed)",
        output.display(),
        mesh.num_vertices(),
        mesh.num_tets(),
        mesh.total_rest_volume(),
        q.min_dihedral_deg,
        build.inverted_fixed
    );
    eprintln!(
        "dihedral histogram (10-degree bins): {:?}",
        q.dihedral_histogram
    );
    Ok(())
}

/// Prints what the built-in mesher found and did.
fn print_report(r: &MesherReport) {
    let p = &r.problems;
    eprintln!(
        "surface: {} duplicate vertices merged, {} collapsed faces dropped, {} zero-area faces, \
         {} open edges, {} non-manifold edges, {} flipped edges",
        p.merged_vertices,
        p.collapsed_faces,
        p.zero_area_faces,
        p.open_edges,
        p.non_manifold_edges,
        p.flipped_edges
    );
    if r.reoriented {
        eprintln!("surface faces pointed inwards; reversed them");
    }
    if r.used_winding_on_open_surface {
        eprintln!("surface is not watertight; inside decided by generalised winding number");
    }
    if r.fragments.dropped_pieces > 0 {
        eprintln!(
            "dropped {} loose fragments ({} tets) left by features thinner than the lattice",
            r.fragments.dropped_pieces, r.fragments.dropped_tets
        );
    }
    if r.manifold.removed_tets + r.manifold.added_tets > 0 {
        eprintln!(
            "boundary made manifold where it pinched at a lattice vertex or edge: {} tets \
             removed, {} added",
            r.manifold.removed_tets, r.manifold.added_tets
        );
    }
    eprintln!(
        "lattice spacing {:.4e}; snapped {} of {} boundary vertices onto the surface \
         ({} part way, {} left for quality)",
        r.edge_length, r.snap.snapped, r.snap.boundary_vertices, r.snap.partial, r.snap.kept
    );
    eprintln!(
        "{} tets, volume {:.6e} vs surface {:.6e} ({:+.2}%), dihedral angles {:.2}..{:.2} deg",
        r.tets,
        r.mesh_volume,
        r.surface_volume,
        100.0 * (r.mesh_volume / r.surface_volume - 1.0),
        r.min_dihedral_deg,
        r.max_dihedral_deg
    );
}

/// Meshes a surface with Debian's `tetgen -pq1.414` and imports its `.node`/`.ele`.
fn run_tetgen(path: &Path, output: &Path) -> Result<()> {
    let format = TetFormat::from_path(output)?;
    let available = Command::new("tetgen")
        .arg("-h")
        .output()
        .map(|_| true)
        .unwrap_or(false);
    if !available {
        bail!("--tetgen: `tetgen` is not on the PATH (Debian: apt install tetgen); leave out --tetgen to use the built-in mesher");
    }
    let surface = perifrac_io::read_surface(path)?;
    let dir = std::env::temp_dir().join(format!("perifrac-tetgen-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let result = (|| -> Result<()> {
        let off = dir.join("surface.off");
        write_off(&off, &surface.vertices, &surface.faces)?;
        let run = Command::new("tetgen")
            .arg("-pq1.414Q")
            .arg(&off)
            .output()
            .context("running tetgen")?;
        let ele = dir.join("surface.1.ele");
        if !run.status.success() || !ele.exists() {
            let said = String::from_utf8_lossy(&run.stdout) + String::from_utf8_lossy(&run.stderr);
            let tail: Vec<&str> = said.lines().rev().take(4).collect();
            bail!(
                "tetgen could not mesh {} ({}); it said: {}. TetGen needs a closed, \
                 non-self-intersecting solid; the built-in mesher (without --tetgen) copes with \
                 small holes",
                path.display(),
                run.status,
                tail.into_iter().rev().collect::<Vec<_>>().join(" / ")
            );
        }
        let data = perifrac_io::read_tet_mesh(&ele)?;
        eprintln!("tetgen -pq1.414 meshed {}", path.display());
        write_mesh(output, data.vertices, data.tets, format)
    })();
    // Best effort: the temporary files are ours alone.
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// Writes an ASCII OFF surface for TetGen (Rust's `{}` for f64 round-trips exactly).
fn write_off(path: &Path, vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<()> {
    use std::fmt::Write as _;
    let mut text = format!("OFF\n{} {} 0\n", vertices.len(), faces.len());
    for p in vertices {
        let _ = writeln!(text, "{} {} {}", p[0], p[1], p[2]);
    }
    for f in faces {
        let _ = writeln!(text, "3 {} {} {}", f[0], f[1], f[2]);
    }
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

/// Builds the primitive and writes it to `output`.
fn run_primitive(
    spec: &str,
    output: &Path,
    resolution: usize,
    cells: Option<&[usize]>,
    cut: BoxCut,
    allow_large: bool,
) -> Result<()> {
    let prim = parse_primitive(spec)?;
    let counts = cell_counts(prim.size, resolution, cells)?;
    let [nx, ny, nz] = counts;
    let what = || format!("`{spec}` in {nx}x{ny}x{nz} cells");
    // Checked counts, sizes within range and cells with a volume, before anything is allocated.
    let (vertices, tets) = primitives::box_counts(counts).with_context(what)?;
    primitives::check_box([0.0; 3], prim.size, counts).with_context(what)?;
    check_memory(tets as u64, vertices as u64, allow_large)?;
    let format = TetFormat::from_path(output)?;
    let (v, t) = box_cut_data([0.0; 3], prim.size, counts, cut).with_context(what)?;
    let mesh = TetMesh::new(v, t).with_context(what)?.0;
    let data = to_data(&mesh, vec![0; mesh.num_tets()], Vec::new());
    perifrac_io::write_tet_mesh(output, &data, format)?;
    eprintln!(
        "wrote {} ({} vertices, {} tets, {}x{}x{} cells)",
        output.display(),
        mesh.num_vertices(),
        mesh.num_tets(),
        counts[0],
        counts[1],
        counts[2]
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_spreads_cells_in_proportion() {
        // 1 x 0.2 x 0.5 at 20 across the longest side: cell size 0.05 -> 20, 4, 10.
        assert_eq!(cell_counts([1.0, 0.2, 0.5], 20, None).unwrap(), [20, 4, 10]);
        // A side much thinner than a cell still gets one cell.
        assert_eq!(
            cell_counts([1.0, 0.001, 1.0], 10, None).unwrap(),
            [10, 1, 10]
        );
        assert!(cell_counts([1.0; 3], 0, None).is_err());
        assert!(cell_counts([1.0; 3], 5, Some(&[1, 0, 1])).is_err());
    }

    #[test]
    fn primitives_that_cannot_be_meshed_are_errors_not_panics() {
        let dir = std::env::temp_dir().join(format!("perifrac-mesh-test-{}", std::process::id()));
        let out = dir.join("o.mesh");
        // The reproducers of issue 17 (each panicked or aborted before).
        for (spec, cells, expect) in [
            ("box:1e8x1x1", None, "too flat"),
            ("box:1e-30x1x1", None, "too flat"),
            ("box:1e308x1x1", None, "beyond 1e50"),
            ("bar:1e308x1x1", None, "beyond 1e50"),
            (
                "box:1x1x1",
                Some(vec![4_294_967_296, 4_294_967_296, 1]),
                "more than a mesh can index",
            ),
            (
                "box:1x1x1",
                Some(vec![9_223_372_036_854_775_808, 2, 1]),
                "more than a mesh can index",
            ),
        ] {
            let e = run_primitive(
                spec,
                &out,
                20,
                cells.as_deref(),
                BoxCut::Lattice(primitives::Lattice::Kuhn),
                false,
            )
            .unwrap_err();
            let msg = format!("{e:#}");
            assert!(msg.contains(spec) && msg.contains(expect), "{spec}: {msg}");
            assert!(!out.exists());
        }
    }
}
