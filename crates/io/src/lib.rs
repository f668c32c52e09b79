//! Readers and writers of mesh files for perifrac.
//!
//! Tet meshes: TetGen (`.node`/`.ele`/`.face`), Medit (`.mesh`), Gmsh (`.msh`, ASCII 2.2 and
//! 4.1) and legacy VTK (`.vtk`, ASCII unstructured grid). Surfaces: OBJ, PLY (ASCII and binary)
//! and OFF in; PLY, OBJ and POV-Ray `mesh2` includes out.
//!
//! The crate exchanges plain data only ([`TetMeshData`], [`SurfaceData`], [`SurfaceRef`]):
//! indices are 0-based `u32`, coordinates `f64`. ASCII writers print the shortest decimal that
//! reads back to the same bits, so tet meshes round-trip exactly. Readers never panic: every
//! problem is an [`IoError`] naming the file and, for text formats, the 1-based line.

mod atomic;
mod check;
mod data;
mod error;
mod format;
mod gmsh_read;
mod gmsh_write;
mod medit;
mod numfmt;
mod obj;
mod off;
mod ply_frame;
mod ply_points;
mod ply_read;
mod ply_write;
mod povray;
mod tetgen;
mod tokens;
pub mod usda;
mod vtk;

pub use atomic::atomic_write;
pub use data::{SurfaceData, SurfaceRef, TetMeshData};
pub use error::IoError;
pub use format::TetFormat;
pub use obj::write_obj;
pub use ply_frame::{parse_ply_frame, read_ply_frame, FrameSurface};
pub use ply_points::{parse_ply_points, read_ply_points, write_ply_points, PointCloud};
pub use ply_read::{parse_ply_crack, read_ply_crack};
pub use ply_write::{write_ply, PlyEncoding};
pub use povray::write_povray_mesh2;

use std::path::Path;

/// Extensions [`read_surface`] understands, for error messages.
const SURFACE_IN: &str = ".obj, .ply, .off";
/// Extensions [`write_surface`] understands, for error messages.
const SURFACE_OUT: &str = ".ply, .obj, .inc, .pov";

/// Reads a tet mesh, choosing the reader from the extension (see [`TetFormat::from_path`]).
/// For TetGen either the `.node` or the `.ele` path may be given.
pub fn read_tet_mesh(path: &Path) -> Result<TetMeshData, IoError> {
    match TetFormat::from_path(path)? {
        TetFormat::TetGen => tetgen::read(path),
        TetFormat::Medit => medit::read(path),
        TetFormat::Gmsh22 | TetFormat::Gmsh41 => gmsh_read::read(path),
        TetFormat::Vtk => vtk::read(path),
    }
}

/// Parses the bytes of a one-file tet mesh (Medit, Gmsh, VTK), choosing the reader from the
/// extension of `path`, which only names the file in errors. A TetGen mesh is several files:
/// see [`parse_tetgen`].
pub fn parse_tet_mesh(path: &Path, data: &[u8]) -> Result<TetMeshData, IoError> {
    match TetFormat::from_path(path)? {
        TetFormat::TetGen => Err(IoError::invalid(
            path,
            "a TetGen mesh is a .node and an .ele file (and an optional .face): parse them \
             with parse_tetgen",
        )),
        TetFormat::Medit => medit::parse(path, data),
        TetFormat::Gmsh22 | TetFormat::Gmsh41 => gmsh_read::parse(path, data),
        TetFormat::Vtk => vtk::parse(path, data),
    }
}

/// Parses the bytes of a TetGen mesh: its `.node`, `.ele` and optional `.face` files. `path`
/// (either file's name) names the files in errors, with the extension of the one at fault.
pub fn parse_tetgen(
    path: &Path,
    node: &[u8],
    ele: &[u8],
    face: Option<&[u8]>,
) -> Result<TetMeshData, IoError> {
    tetgen::parse_all(path, node, ele, face)
}

/// The file whose lines [`TetMeshData::tet_lines`] counts for a mesh read from `path`: the
/// `.ele` beside a TetGen `.node`, otherwise `path` itself.
pub fn tet_lines_file(path: &Path) -> std::path::PathBuf {
    match TetFormat::from_path(path) {
        Ok(TetFormat::TetGen) => path.with_extension("ele"),
        _ => path.to_path_buf(),
    }
}

/// Writes a tet mesh in `format`, atomically. For TetGen, `path` may name the `.node` or the
/// `.ele`; both (and a `.face` when there are boundary faces) are written beside each other.
pub fn write_tet_mesh(path: &Path, mesh: &TetMeshData, format: TetFormat) -> Result<(), IoError> {
    check::mesh_for_writing(path, mesh)?;
    match format {
        TetFormat::TetGen => tetgen::write(path, mesh),
        TetFormat::Medit => medit::write(path, mesh),
        TetFormat::Gmsh22 => gmsh_write::write_v22(path, mesh),
        TetFormat::Gmsh41 => gmsh_write::write_v41(path, mesh),
        TetFormat::Vtk => vtk::write(path, mesh),
    }
}

/// Reads a triangle surface by extension: `.obj` (tobj), `.ply` (ASCII or binary), `.off`.
/// Polygons are fan-triangulated. A file without vertices or without faces is an error: it is
/// no surface.
pub fn read_surface(path: &Path) -> Result<SurfaceData, IoError> {
    surface_extension(path)?;
    parse_surface(path, &error::read_all(path)?)
}

/// The surface reader's extension of `path`, refusing one it does not read.
fn surface_extension(path: &Path) -> Result<&'static str, IoError> {
    match format::extension(path).as_deref() {
        Some("obj") => Ok("obj"),
        Some("ply") => Ok("ply"),
        Some("off") => Ok("off"),
        _ => Err(IoError::UnknownExtension {
            file: path.to_path_buf(),
            known: SURFACE_IN,
        }),
    }
}

/// [`read_surface`] on the bytes of a surface file, the reader chosen from the extension of
/// `path`, which only names the file in errors.
pub fn parse_surface(path: &Path, data: &[u8]) -> Result<SurfaceData, IoError> {
    let surface = match surface_extension(path)? {
        "obj" => obj::parse(path, data),
        "ply" => parse_ply_crack(path, data).map(|(s, _)| s),
        _ => off::parse(path, data),
    }?;
    let empty = |what: &str| IoError::Format {
        file: path.to_path_buf(),
        message: format!("no {what}: the file holds no surface"),
    };
    if surface.vertices.is_empty() {
        return Err(empty("vertices"));
    }
    if surface.faces.is_empty() {
        return Err(empty("faces"));
    }
    Ok(surface)
}

/// Writes a surface by extension: `.ply` (binary little-endian), `.obj`, `.inc`/`.pov`
/// (POV-Ray `mesh2` declared as `perifrac_mesh`).
pub fn write_surface(path: &Path, surface: &SurfaceRef) -> Result<(), IoError> {
    match format::extension(path).as_deref() {
        Some("ply") => write_ply(path, surface, PlyEncoding::BinaryLittleEndian),
        Some("obj") => write_obj(path, surface),
        Some("inc") | Some("pov") => write_povray_mesh2(path, surface, "perifrac_mesh"),
        _ => Err(IoError::UnknownExtension {
            file: path.to_path_buf(),
            known: SURFACE_OUT,
        }),
    }
}
