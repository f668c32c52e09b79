//! Tet-mesh file formats and their extensions.

use crate::IoError;
use std::path::Path;

/// The tet-mesh formats this crate reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TetFormat {
    /// TetGen `.node` + `.ele` (+ `.face`).
    TetGen,
    /// Medit / INRIA `.mesh`, ASCII.
    Medit,
    /// Gmsh `.msh` version 2.2, ASCII.
    Gmsh22,
    /// Gmsh `.msh` version 4.1, ASCII.
    Gmsh41,
    /// Legacy VTK `.vtk` unstructured grid, ASCII.
    Vtk,
}

/// Extensions [`TetFormat::from_path`] understands, for error messages.
const KNOWN: &str = ".node, .ele (TetGen), .mesh (Medit), .msh (Gmsh), .vtk (VTK legacy)";

impl TetFormat {
    /// The format for a path's extension: `.node`/`.ele` TetGen, `.mesh` Medit, `.msh` Gmsh 4.1
    /// (the writer's default; the reader detects the version from `$MeshFormat`), `.vtk` VTK.
    pub fn from_path(path: &Path) -> Result<TetFormat, IoError> {
        match extension(path).as_deref() {
            Some("node") | Some("ele") => Ok(TetFormat::TetGen),
            Some("mesh") => Ok(TetFormat::Medit),
            Some("msh") => Ok(TetFormat::Gmsh41),
            Some("vtk") => Ok(TetFormat::Vtk),
            _ => Err(IoError::UnknownExtension {
                file: path.to_path_buf(),
                known: KNOWN,
            }),
        }
    }
}

/// The lower-cased extension of `path`, if any.
pub(crate) fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_extension() {
        assert_eq!(
            TetFormat::from_path(Path::new("a.NODE")).unwrap(),
            TetFormat::TetGen
        );
        assert_eq!(
            TetFormat::from_path(Path::new("a.ele")).unwrap(),
            TetFormat::TetGen
        );
        assert_eq!(
            TetFormat::from_path(Path::new("a.mesh")).unwrap(),
            TetFormat::Medit
        );
        assert_eq!(
            TetFormat::from_path(Path::new("a.msh")).unwrap(),
            TetFormat::Gmsh41
        );
        assert_eq!(
            TetFormat::from_path(Path::new("a.vtk")).unwrap(),
            TetFormat::Vtk
        );
        let e = TetFormat::from_path(Path::new("a.stl"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("a.stl") && e.contains(".mesh") && e.contains(".node"),
            "{e}"
        );
    }
}
