//! Checkpoints of a run: `checkpoint.bin` in the run directory, written atomically at frame
//! boundaries (see [`crate::CheckpointPolicy`]) and when the run is interrupted, holding the
//! scene as run and everything the steps changed (the driver's state: mesh, solver, balls,
//! counters) with where the run stood and the frames recorded so far. A resumed run rebuilds
//! the setup from the stored scene, checks that it is the same one (a fingerprint of the scene
//! text, the mesh, the particle and bond counts and the step), restores the state and
//! continues; its files are byte-identical to an uninterrupted run's.

use std::io::Write;
use std::path::{Path, PathBuf};

use perifrac_checkpoint::{fnv1a, fnv1a_from, Header, Reader, Writer};

use crate::body::{AnyScene, Body, Plan};
use crate::error::SceneError;
use crate::manifest::FrameJson;

/// The checkpoint's file name in the run directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

/// The program line a checkpoint carries; another build is refused, since it may step
/// differently.
pub fn program() -> String {
    format!("perifrac {}", env!("CARGO_PKG_VERSION"))
}

/// Where a run stands between two steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Position {
    /// The frame being stepped towards (1-based; frame 0 is the rest state).
    pub frame: usize,
    /// Steps already taken towards it.
    pub step_in_frame: u64,
}

/// A checkpoint read back: the scene it belongs to and where its run stood; the state itself
/// goes to [`crate::resume`].
#[derive(Debug, Clone)]
pub struct Checkpoint {
    /// What the file says of itself.
    pub header: Header,
    /// The scene file the run was started with (absolute).
    pub scene_path: PathBuf,
    /// The scene text as run.
    pub scene_text: String,
    /// Frames of the run after the initial one.
    pub frames: usize,
    /// Steps per frame.
    pub steps_per_frame: u64,
    /// Where the run stood.
    pub position: Position,
    /// `run.json`'s frames up to then.
    pub(crate) recorded: Vec<FrameJson>,
    body: Vec<u8>,
    /// Offset of the driver's state in `body`.
    state_at: usize,
}

/// Writes `dir/checkpoint.bin` atomically for the run `run` identifies, standing at
/// `position`, with the frames recorded so far and what `body` saves of itself, under a header
/// that says where the run stood.
pub(crate) fn write(
    dir: &Path,
    run: &RunIdentity,
    position: Position,
    recorded: &[FrameJson],
    body: &dyn Body,
) -> Result<PathBuf, SceneError> {
    let summary = format!(
        "{} at step {} (t = {:.6e} s), stepping to frame {} of {}",
        run.scene_path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        body.steps(),
        body.time(),
        position.frame,
        run.frames
    );
    let mut w = Writer::new();
    w.tag("run");
    w.str(&run.scene_path.to_string_lossy());
    w.str(&run.scene_text);
    w.usize(run.frames);
    w.u64(run.steps_per_frame);
    w.usize(position.frame);
    w.u64(position.step_in_frame);
    let frames = serde_json::to_string(recorded).map_err(|e| SceneError::Output {
        dir: dir.to_path_buf(),
        message: format!("cannot encode the frames for the checkpoint: {e}"),
    })?;
    w.str(&frames);
    body.save(&mut w);
    let header = Header {
        program: program(),
        fingerprint: run.fingerprint,
        summary,
    };
    let bytes = perifrac_checkpoint::seal(&header, w.bytes());
    let path = dir.join(CHECKPOINT_FILE);
    perifrac_io::atomic_write(&path, |f| f.write_all(&bytes))?;
    Ok(path)
}

/// What identifies a run for its checkpoints: the scene, the frames and steps, and a
/// fingerprint of the freshly built body (the scene text, frames, steps per frame, the step
/// and what the body identifies itself by: its rest mesh and counts).
#[derive(Debug, Clone)]
pub(crate) struct RunIdentity {
    pub scene_path: PathBuf,
    pub scene_text: String,
    pub frames: usize,
    pub steps_per_frame: u64,
    pub fingerprint: u64,
}

impl RunIdentity {
    /// The identity of a run of `body` (freshly built) under `plan`.
    pub(crate) fn of(plan: &Plan, body: &dyn Body) -> RunIdentity {
        let mut w = Writer::new();
        w.str(&plan.scene_text);
        w.usize(plan.frames);
        w.u64(plan.steps_per_frame);
        w.f64(plan.dt);
        body.identify(&mut w);
        let path = &plan.scene_path;
        RunIdentity {
            scene_path: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
            scene_text: plan.scene_text.clone(),
            frames: plan.frames,
            steps_per_frame: plan.steps_per_frame,
            fingerprint: fnv1a_from(fnv1a(b"perifrac run"), w.bytes()),
        }
    }
}

impl Checkpoint {
    /// Reads `dir/checkpoint.bin`, refusing a file that is not a checkpoint, is damaged, or was
    /// written by another version of perifrac.
    pub fn read(dir: &Path) -> Result<Checkpoint, SceneError> {
        let path = dir.join(CHECKPOINT_FILE);
        let bad = |message: String| SceneError::Checkpoint {
            path: path.clone(),
            message,
        };
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let Ok(manifest) = std::fs::read_to_string(dir.join("run.json")) else {
                    return Err(bad(
                        "not found, nor run.json: this is not a run directory".into()
                    ));
                };
                let finished = serde_json::from_str::<serde_json::Value>(&manifest)
                    .is_ok_and(|m| m["finished"] == serde_json::Value::Bool(true));
                return Err(bad(if finished {
                    "not found: the run in this directory finished, there is nothing to resume"
                        .into()
                } else {
                    "not found: the run was not interrupted by a signal and wrote no \
                     checkpoint at a frame ([output] checkpoint_every)"
                        .into()
                }));
            }
            Err(e) => return Err(bad(format!("cannot read: {e}"))),
        };
        let (header, body) = perifrac_checkpoint::open(&bytes).map_err(|e| bad(e.to_string()))?;
        if header.program != program() {
            return Err(bad(format!(
                "written by {}; this is {}, which may step differently: rerun the scene",
                header.program,
                program()
            )));
        }
        let mut r = Reader::new(body);
        let mut head = || -> Result<_, perifrac_checkpoint::CheckpointError> {
            r.tag("run")?;
            Ok((
                r.str("scene path")?,
                r.str("scene text")?,
                r.usize("frames")?,
                r.u64("steps per frame")?,
                Position {
                    frame: r.usize("frame")?,
                    step_in_frame: r.u64("step in frame")?,
                },
                r.str("frames recorded")?,
            ))
        };
        let (scene_path, scene_text, frames, steps_per_frame, position, recorded) =
            head().map_err(|e| bad(e.to_string()))?;
        let recorded: Vec<FrameJson> =
            serde_json::from_str(&recorded).map_err(|e| bad(format!("frames recorded: {e}")))?;
        if position.frame == 0
            || position.frame > frames
            || position.step_in_frame > steps_per_frame
        {
            return Err(bad(format!(
                "frame {} step {} is outside a run of {frames} frames of {steps_per_frame} steps",
                position.frame, position.step_in_frame
            )));
        }
        let state_at = body.len() - r.remaining();
        Ok(Checkpoint {
            header,
            scene_path: PathBuf::from(scene_path),
            scene_text,
            frames,
            steps_per_frame,
            position,
            recorded,
            body: body.to_vec(),
            state_at,
        })
    }

    /// Refuses the checkpoint in `dir` unless it was written for the run `id` identifies
    /// (built afresh from the scene): the same scene text and fingerprint.
    fn check_identity(&self, dir: &Path, id: &RunIdentity) -> Result<(), SceneError> {
        let bad = |message: String| SceneError::Checkpoint {
            path: dir.join(CHECKPOINT_FILE),
            message,
        };
        if id.scene_text != self.scene_text {
            return Err(bad(format!(
                "it belongs to another scene than {} (the scene text differs)",
                id.scene_path.display()
            )));
        }
        if id.fingerprint != self.header.fingerprint {
            return Err(bad(format!(
                "the setup of {} is no longer the one the checkpoint was written for (its mesh or \
                 surface file, frames or step changed); rerun the scene",
                id.scene_path.display()
            )));
        }
        Ok(())
    }

    /// The scene as run, parsed again (relative mesh paths resolve against the original
    /// scene file's directory).
    pub fn scene(&self) -> Result<AnyScene, SceneError> {
        AnyScene::parse(&self.scene_text, &self.scene_path)
    }

    /// Checks that `id` (of a body built from [`Checkpoint::scene`] with
    /// [`Checkpoint::frames`]) is the run the checkpoint was written for, then restores `body`
    /// to the saved state.
    pub(crate) fn restore(
        &self,
        dir: &Path,
        id: &RunIdentity,
        body: &mut dyn Body,
    ) -> Result<(), SceneError> {
        self.check_identity(dir, id)?;
        let bad = |message: String| SceneError::Checkpoint {
            path: dir.join(CHECKPOINT_FILE),
            message,
        };
        let mut r = Reader::new(&self.body[self.state_at..]);
        body.restore(&mut r).map_err(bad)?;
        r.finish().map_err(|e| bad(e.to_string()))
    }
}
