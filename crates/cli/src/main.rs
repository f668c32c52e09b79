//! `perifrac`: the command line of the perifrac fracture toolkit.
//!
//! Each subcommand lives in its own module; this file only parses arguments and reports
//! errors with their context and a non-zero exit.

mod bench;
mod convert;
mod export;
mod info;
mod load;
mod mesh;
mod render;
mod run;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Peridynamic fracture animation: tet meshes in, crack surfaces out.
#[derive(Parser)]
#[command(name = "perifrac", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Convert a mesh between formats, chosen by extension.
    ///
    /// Tet meshes: .node/.ele (TetGen), .mesh (Medit), .msh (Gmsh 2.2/4.1 read, 4.1 written
    /// unless --gmsh22), .vtk (legacy ASCII). Surfaces: .obj, .off, .ply in; .ply, .obj,
    /// .inc (POV-Ray mesh2) out. Inverted tets are reoriented; degenerate ones are refused.
    Convert {
        /// Input mesh file.
        input: PathBuf,
        /// Output mesh file; written atomically.
        output: PathBuf,
        /// Write Gmsh files in the older 2.2 format instead of 4.1.
        #[arg(long)]
        gmsh22: bool,
    },
    /// Build a tet mesh from a closed surface (built-in mesher or TetGen) or a built-in primitive.
    Mesh {
        /// Closed surface (`.obj`, `.ply`, `.off`) for the built-in mesher, or a primitive spec
        /// `box:LXxLYxLZ` (a box from the origin), `bar:LxWxH`, `sphere:R` or `cylinder:RxH`
        /// (the round ones through the built-in mesher).
        input: String,
        /// Output tet mesh (any tet format by extension).
        #[arg(short, long)]
        output: PathBuf,
        /// Cells across the longest side (primitives: 6 tets per cell, default 20; surfaces: BCC
        /// lattice cells, default about 50k tets).
        #[arg(long, conflicts_with_all = ["cells", "edge_length"])]
        resolution: Option<usize>,
        /// Target edge length for surfaces (the BCC lattice spacing).
        #[arg(long)]
        edge_length: Option<f64>,
        /// Mesh the surface with `tetgen -pq1.414` (must be on the PATH) instead of the built-in
        /// mesher.
        #[arg(long)]
        tetgen: bool,
        /// Exact cell counts along x, y, z, e.g. `40,8,40`.
        #[arg(long, value_delimiter = ',')]
        cells: Option<Vec<usize>>,
        /// Boxes: a Delaunay mesh of well-spaced random points (as many tets as the cells
        /// would give, no direction preferred, as scenes use by default) instead of the Kuhn
        /// lattice.
        #[arg(long, conflicts_with = "mirrored")]
        unstructured: bool,
        /// Boxes: the Kuhn tets mirrored in every other cell along each axis (a box of even
        /// counts is mirror-symmetric) instead of the same six tets in every cell.
        #[arg(long)]
        mirrored: bool,
        /// Seed of `--unstructured`'s points.
        #[arg(long, requires = "unstructured", default_value_t = 1)]
        seed: u64,
        /// Go on when the mesh would need more memory than is available.
        #[arg(long)]
        allow_large: bool,
    },
    /// Simulate a scene file and write crack-surface frames (PLY, POV-Ray) into a directory.
    Run(run::RunArgs),
    /// Write a POV-Ray scene per frame of a run directory, and PNGs when povray is installed.
    Render(render::RenderArgs),
    /// Write a run directory's frames as one animated cache file (USD) for Blender, Houdini,
    /// Maya or any USD reader.
    Export(export::ExportArgs),
    /// Measure accuracy against references, stability on hard cases, and speed.
    Bench(bench::BenchArgs),
    /// Summarise a tet mesh: counts, volume, edge length, quality, pieces, problems.
    Info {
        /// Tet mesh file.
        mesh: PathBuf,
        /// Print one JSON object instead of the human summary.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Convert {
            input,
            output,
            gmsh22,
        } => convert::run(&input, &output, gmsh22),
        Command::Mesh {
            input,
            output,
            resolution,
            cells,
            edge_length,
            tetgen,
            unstructured,
            mirrored,
            seed,
            allow_large,
        } => mesh::run(
            &input,
            &output,
            &mesh::MeshArgs {
                resolution,
                cells: cells.as_deref(),
                edge_length,
                tetgen,
                unstructured: unstructured.then_some(seed),
                mirrored,
                allow_large,
            },
        ),
        Command::Info { mesh, json } => info::run(&mesh, json),
        Command::Run(args) => run::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Bench(args) => bench::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // Library errors quote what they wrap and do not also chain it, so the chain
            // (anyhow's contexts over one library error) repeats nothing.
            eprintln!("error: {err:#}");
            match err.downcast_ref::<perifrac_scene::SceneError>() {
                Some(perifrac_scene::SceneError::Interrupted { .. }) => {
                    ExitCode::from(run::INTERRUPTED_EXIT)
                }
                _ => ExitCode::FAILURE,
            }
        }
    }
}
