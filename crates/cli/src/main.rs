//! `perifrac`: the command line of the perifrac fracture toolkit.
//!
//! Each subcommand lives in its own module; this file only parses arguments and reports
//! errors with their context and a non-zero exit.

mod convert;
mod info;
mod load;
mod mesh;

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
    /// Build a tet mesh from a built-in primitive, e.g. `box:1x0.2x1` or `bar:1x0.1x0.1`.
    Mesh {
        /// Primitive spec `box:LXxLYxLZ` (a box from the origin) or `bar:LxWxH`.
        input: String,
        /// Output tet mesh (any tet format by extension).
        #[arg(short, long)]
        output: PathBuf,
        /// Cells across the longest side (each cell is cut into 6 tets).
        #[arg(long, default_value_t = 20, conflicts_with = "cells")]
        resolution: usize,
        /// Exact cell counts along x, y, z, e.g. `40,8,40`.
        #[arg(long, value_delimiter = ',')]
        cells: Option<Vec<usize>>,
    },
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
        } => mesh::run(&input, &output, resolution, cells.as_deref()),
        Command::Info { mesh, json } => info::run(&mesh, json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
