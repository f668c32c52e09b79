//! Reading a scene file: TOML parsing with line and column in every syntax or schema error.

use crate::error::SceneError;
use crate::schema::{SceneFile, Schema};
use std::path::{Path, PathBuf};

/// A parsed scene: the file's contents and where it came from (relative mesh paths resolve
/// against its directory).
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene file (for messages and relative paths).
    pub path: PathBuf,
    /// The TOML text as read.
    pub text: String,
    /// The parsed tables.
    pub file: SceneFile,
}

impl Scene {
    /// Reads and parses `path`.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::parse(&read(path)?, path)
    }

    /// Parses `text` as if read from `path`.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        if perifrac_schema::is_shell_scene(text) {
            return Err(SceneError::invalid(
                path,
                "shell",
                "a thin-shell scene: `perifrac run` runs it; this command takes tet scenes \
                 ([mesh])",
            ));
        }
        let file: SceneFile = Scene::parse_as(text, path)?;
        Ok(Scene {
            path: path.to_path_buf(),
            text: text.to_string(),
            file,
        })
    }

    /// Parses `text` (read from `path`) into the tables `T`, with line and column in every
    /// syntax or schema error; a key refused for belonging to another choice says which.
    pub(crate) fn parse_as<T: Schema>(text: &str, path: &Path) -> Result<T, SceneError> {
        perifrac_schema::parse(text).map_err(|e| SceneError::Parse {
            file: path.to_path_buf(),
            line: e.line,
            column: e.column,
            message: e.message,
        })
    }

    /// The directory relative paths in the scene resolve against.
    pub fn base_dir(&self) -> PathBuf {
        match self.path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }
}

/// The text of the scene file `path`.
pub(crate) fn read(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|cause| SceneError::Read {
        file: path.to_path_buf(),
        cause,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str =
        "[mesh]\nprimitive = \"box\"\nsize = [1.0, 0.1, 0.2]\nresolution = 10\n\n\
        [[material]]\nyoung = 1e9\npoisson = 0.25\ndensity = 1000.0\n\n\
        [simulation]\nduration = 0.001\n";

    #[test]
    fn minimal_scene_parses() {
        let s = Scene::parse(MINIMAL, Path::new("s.toml")).unwrap();
        assert_eq!(s.file.material.len(), 1);
        assert_eq!(s.file.mesh.size, Some([1.0, 0.1, 0.2]));
    }

    #[test]
    fn unknown_key_has_line_and_column() {
        let text = MINIMAL.replace("poisson = 0.25", "poison = 0.25");
        let err = Scene::parse(&text, Path::new("s.toml")).unwrap_err();
        let msg = err.to_string();
        // `poison` is on line 8, column 1
        assert!(msg.starts_with("s.toml:8:1: "), "{msg}");
        assert!(msg.contains("poison"), "{msg}");
    }

    #[test]
    fn wrong_type_has_line_and_column() {
        let text = MINIMAL.replace("density = 1000.0", "density = \"heavy\"");
        let msg = Scene::parse(&text, Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert!(msg.starts_with("s.toml:9:11: "), "{msg}");
    }
}
