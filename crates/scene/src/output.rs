//! The run directory: `run.json` (written first, before anything else, then rewritten
//! atomically after every frame and when the run stops; see [`crate::manifest`]), `scene.toml`
//! (the scene as run) and `frames/`, where the sinks ([`crate::sinks`]) write each frame:
//! `surface_NNNN.ply` (binary PLY: vertices split where the surface shades sharp, with normals
//! `nx ny nz`, velocities `vx vy vz` (m/s), and for solids texture coordinates `s t` and the
//! `vertex_id` of the surface vertex they copy, so that welding by it gives every piece's closed
//! 2-manifold surface; faces with their `crack` flag and stable `fragment` id, see
//! [`crate::fragments`]), optionally `surface_NNNN.inc` (POV-Ray `mesh2` with normals, declaring
//! [`POVRAY_MESH_NAME`]), for solids `particles_NNNN.ply` (points with `damage`, `mass` and
//! `fragment`) and `debris_NNNN.ply` (pieces of at most `[output] debris_tets` tets, left out
//! of the surface: points at their centres of mass with `radius`, velocity, `mass` and
//! `fragment`, see [`crate::debris`]). Every file is written to a temporary name and renamed
//! into place, so a reader never sees half a frame.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::body::Head;
use crate::error::SceneError;
use crate::fragments::FragmentBirth;
use crate::manifest::{FrameJson, RunManifest, RUN_FORMAT};

pub use crate::sinks::povray::POVRAY_MESH_NAME;

/// Refuses a non-empty `dir` unless `force`; reads only, so it can run before the setup.
pub fn check_output_dir(dir: &Path, force: bool) -> Result<(), SceneError> {
    let err = |message: String| SceneError::Output {
        dir: dir.to_path_buf(),
        message,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(err("exists and is not a directory".into()));
    }
    if dir.is_dir() && !force {
        let mut entries = std::fs::read_dir(dir).map_err(|e| err(e.to_string()))?;
        if entries.next().is_some() {
            return Err(err(
                "is not empty; choose another directory or pass --force to overwrite".into(),
            ));
        }
    }
    Ok(())
}

/// Keeps `run.json` of a run directory.
pub(crate) struct RunWriter {
    dir: PathBuf,
    manifest: RunManifest,
}

impl RunWriter {
    /// Takes `dir` over: writes `run.json` (with the frames `recorded` before, for a resumed
    /// run), then `scene.toml` and `frames/`; a failure after `run.json` is recorded in it.
    pub(crate) fn start(
        dir: &Path,
        scene_path: &Path,
        scene_text: &str,
        fps: f64,
        head: Head,
        recorded: Vec<FrameJson>,
        births: Vec<FragmentBirth>,
    ) -> Result<RunWriter, SceneError> {
        let Head {
            up,
            rest_bounds,
            grounds,
            dt,
            dt_limit,
            mass,
            body,
        } = head;
        let manifest = RunManifest {
            format: RUN_FORMAT.into(),
            scene: scene_path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            up,
            rest_bounds,
            grounds,
            body,
            dt,
            dt_limit,
            mass,
            fps,
            frames: recorded,
            fragments: births,
            finished: false,
            error: None,
        };
        let writer = RunWriter {
            dir: dir.to_path_buf(),
            manifest,
        };
        // run.json first: whatever fails after it is recorded in it.
        writer.write_manifest()?;
        let rest = write_scene_and_frames_dir(dir, scene_text);
        if let Err(e) = rest {
            let mut writer = writer;
            // Best effort: the error itself is what the caller reports.
            let _ = writer.record_error(e.to_string());
            return Err(e);
        }
        Ok(writer)
    }

    /// Records `frame` with the fragments so far (`last` marks the run finished).
    pub(crate) fn record_frame(
        &mut self,
        frame: FrameJson,
        births: Vec<FragmentBirth>,
        last: bool,
    ) -> Result<(), SceneError> {
        self.manifest.frames.push(frame);
        self.manifest.fragments = births;
        self.manifest.finished = last;
        self.write_manifest()
    }

    /// Records why the run stopped in `run.json` (and that it did not finish); the frames
    /// written stay. When the atomic rewrite fails (on a full disk it needs room for a second
    /// copy), `run.json` is overwritten in place, which needs little more room than it had; the
    /// first error is returned when that fails too.
    pub(crate) fn record_error(&mut self, message: String) -> Result<(), SceneError> {
        self.manifest.error = Some(message);
        self.manifest.finished = false;
        match self.write_manifest() {
            Ok(()) => Ok(()),
            Err(first) => {
                let text = self.manifest_text()?;
                std::fs::write(self.dir.join("run.json"), text).map_err(|_| first)
            }
        }
    }

    /// Frames written so far, the initial one included.
    pub(crate) fn frames_written(&self) -> usize {
        self.manifest.frames.len()
    }

    /// What `run.json` holds now.
    pub(crate) fn manifest(&self) -> &RunManifest {
        &self.manifest
    }

    /// `run.json`'s text, with its final newline.
    fn manifest_text(&self) -> Result<String, SceneError> {
        let mut text =
            serde_json::to_string_pretty(&self.manifest).map_err(|e| SceneError::Output {
                dir: self.dir.clone(),
                message: format!("cannot encode run.json: {e}"),
            })?;
        text.push('\n');
        Ok(text)
    }

    fn write_manifest(&self) -> Result<(), SceneError> {
        let text = self.manifest_text()?;
        perifrac_io::atomic_write(&self.dir.join("run.json"), |w| w.write_all(text.as_bytes()))?;
        Ok(())
    }
}

/// Writes `scene.toml` (the scene as run) into the run directory `dir` and creates `frames/`.
fn write_scene_and_frames_dir(dir: &Path, scene_text: &str) -> Result<(), SceneError> {
    perifrac_io::atomic_write(&dir.join("scene.toml"), |w| {
        w.write_all(scene_text.as_bytes())
    })?;
    std::fs::create_dir_all(dir.join("frames")).map_err(|e| SceneError::Output {
        dir: dir.to_path_buf(),
        message: format!("cannot create frames/: {e}"),
    })
}

/// Removes an earlier run's files from `dir` (`run.json`, `scene.toml`, `checkpoint.bin`,
/// `frames/`, `render/`, the USD cache named after its scene) and nothing else, creating `dir`
/// if needed.
pub(crate) fn clear_output_dir(dir: &Path) -> Result<(), SceneError> {
    let err = |message: String| SceneError::Output {
        dir: dir.to_path_buf(),
        message,
    };
    for name in ["frames", "render"] {
        let p = dir.join(name);
        if p.is_dir() {
            std::fs::remove_dir_all(&p).map_err(|e| err(format!("cannot clear {name}/: {e}")))?;
        }
    }
    // The USD cache an earlier run wrote under its scene's name (`[output] usd`).
    if let Ok(text) = std::fs::read_to_string(dir.join("run.json")) {
        let scene = serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|m| m["scene"].as_str().map(str::to_owned));
        if let Some(stem) = scene.as_deref().and_then(|s| Path::new(s).file_stem()) {
            let p = dir.join(format!("{}.usda", stem.to_string_lossy()));
            if p.is_file() {
                std::fs::remove_file(&p)
                    .map_err(|e| err(format!("cannot remove {}: {e}", p.display())))?;
            }
        }
    }
    for name in ["run.json", "scene.toml", crate::checkpoint::CHECKPOINT_FILE] {
        let p = dir.join(name);
        if p.is_file() {
            std::fs::remove_file(&p).map_err(|e| err(format!("cannot remove {name}: {e}")))?;
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| err(format!("cannot create: {e}")))?;
    Ok(())
}
