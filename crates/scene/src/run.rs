//! Running a prepared scene of either kind: steps between frames, frames through the sinks
//! into a run directory (layout in [`crate::output`]), progress to an [`Observer`], a
//! [`Summary`] at the end. One loop serves every body (the crate's `Body` trait).

use std::path::Path;
use std::time::{Duration, Instant};

use crate::body::{AnySetup, Body, BodySummary, Plan, ShellSummary, SolidSummary};
use crate::checkpoint::{self, Checkpoint, Position, RunIdentity, CHECKPOINT_FILE};
use crate::error::SceneError;
use crate::output::{clear_output_dir, RunWriter};
use crate::sinks::{Finished, Sinks};

/// Where a run stands, handed to the [`Observer`] after every step and frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Simulated time (s).
    pub time: f64,
    /// Simulated duration of the whole run (s).
    pub duration: f64,
    /// Steps done.
    pub steps: u64,
    /// Steps the run will take.
    pub total_steps: u64,
    /// Bonds (solids) or triangles (shells) broken so far.
    pub broken_bonds: u64,
    /// Fragments at the last frame written.
    pub fragments: usize,
    /// Frames written so far, the initial one included.
    pub frames_written: usize,
}

/// Receives progress; the command line draws a progress bar from it.
pub trait Observer {
    /// After every step.
    fn step(&mut self, _progress: &Progress) {}
    /// After every frame is written.
    fn frame(&mut self, _progress: &Progress) {}
    /// Asked after every step and frame: true makes the run write a checkpoint and stop with
    /// [`SceneError::Interrupted`] (the command line answers true after SIGINT or SIGTERM).
    fn interrupted(&mut self) -> bool {
        false
    }
}

/// An observer that ignores everything.
pub struct Silent;
impl Observer for Silent {}

/// The end of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub time: f64,
    /// The step (s).
    pub dt: f64,
    /// Fragments (connected pieces) at the end.
    pub fragments: usize,
    /// Kinetic energy of the body at the end (J).
    pub kinetic_energy: f64,
    /// Elastic energy at the end (J).
    pub elastic_energy: f64,
    /// Frames written, the initial one included.
    pub frames_written: usize,
    /// The USD cache, when the scene asked for one, and the wall time it took to write.
    pub usd: Option<(crate::usd::UsdReport, Duration)>,
    /// What the body counted.
    pub body: BodySummary,
}

impl Summary {
    /// A tet solid's counts (`None` for a shell).
    pub fn solid(&self) -> Option<&SolidSummary> {
        match &self.body {
            BodySummary::Solid(s) => Some(s),
            BodySummary::Shell(_) => None,
        }
    }

    /// A thin shell's counts (`None` for a solid).
    pub fn shell(&self) -> Option<&ShellSummary> {
        match &self.body {
            BodySummary::Shell(s) => Some(s),
            BodySummary::Solid(_) => None,
        }
    }
}

/// Runs `setup` (a tet solid's [`crate::Setup`] or a shell's [`crate::ShellSetup`]) to the
/// end, writing frames into `dir` (cleared of an earlier run's files first). On an instability
/// the frames written so far stay, `run.json` records the error, and [`SceneError::Stopped`]
/// is returned; a failure to write a frame (a full disk, say) is recorded in `run.json` too
/// and returned. When the observer reports an interruption, a checkpoint is written and
/// [`SceneError::Interrupted`] returned; [`resume`] continues from it.
pub fn run(
    setup: impl Into<AnySetup>,
    dir: &Path,
    observer: &mut dyn Observer,
) -> Result<Summary, SceneError> {
    let (body, plan) = setup.into().split();
    let id = RunIdentity::of(&plan, body.as_ref());
    clear_output_dir(dir)?;
    let writer = start_writer(dir, &plan, body.as_ref(), Vec::new())?;
    let start = Position {
        frame: 0,
        step_in_frame: 0,
    };
    drive(body, &plan, &id, writer, dir, start, observer)
}

/// Continues the run in `dir` from `checkpoint` (read by [`Checkpoint::read`]); `setup` must be
/// built from [`Checkpoint::scene`] with [`Checkpoint::frames`]. A checkpoint of another scene,
/// mesh or step is refused. The files written are byte-identical to those of a run that was
/// never interrupted.
pub fn resume(
    setup: impl Into<AnySetup>,
    checkpoint: &Checkpoint,
    dir: &Path,
    observer: &mut dyn Observer,
) -> Result<Summary, SceneError> {
    let (mut body, plan) = setup.into().split();
    // the identity of the fresh setup, before the restore changes its mesh
    let id = RunIdentity::of(&plan, body.as_ref());
    checkpoint.restore(dir, &id, body.as_mut())?;
    let writer = start_writer(dir, &plan, body.as_ref(), checkpoint.recorded.clone())?;
    drive(body, &plan, &id, writer, dir, checkpoint.position, observer)
}

fn start_writer(
    dir: &Path,
    plan: &Plan,
    body: &dyn Body,
    recorded: Vec<crate::manifest::FrameJson>,
) -> Result<RunWriter, SceneError> {
    RunWriter::start(
        dir,
        &plan.scene_path,
        &plan.scene_text,
        plan.fps,
        body.head(),
        recorded,
        body.births(),
    )
}

/// The step loop from `start` to the end.
fn drive(
    mut body: Box<dyn Body>,
    plan: &Plan,
    id: &RunIdentity,
    mut writer: RunWriter,
    dir: &Path,
    start: Position,
    observer: &mut dyn Observer,
) -> Result<Summary, SceneError> {
    let frames = plan.frames;
    let sinks = Sinks::from_output(plan.sinks);
    let total_steps = (frames as u64).saturating_mul(plan.steps_per_frame);
    let mut progress = Progress {
        time: body.time(),
        duration: plan.dt * total_steps as f64,
        steps: body.steps(),
        total_steps,
        broken_bonds: body.broken(),
        fragments: writer.manifest().frames.last().map_or(1, |f| f.fragments),
        frames_written: writer.frames_written(),
    };
    let mut last_checkpoint = Instant::now();
    // stops with the error recorded in run.json (best effort: the error is what is reported)
    let stop = |writer: &mut RunWriter, e: SceneError| {
        let _ = writer.record_error(e.to_string());
        Err(e)
    };
    for frame in start.frame..=frames {
        if frame > 0 {
            let first = if frame == start.frame {
                start.step_in_frame
            } else {
                0
            };
            for k in first..plan.steps_per_frame {
                if let Err(cause) = body.step() {
                    let stopped = SceneError::Stopped {
                        time: body.time(),
                        step: body.steps(),
                        frames: writer.frames_written(),
                        cause,
                    };
                    return stop(&mut writer, stopped);
                }
                progress.steps = body.steps();
                progress.time = body.time();
                progress.broken_bonds = body.broken();
                observer.step(&progress);
                if observer.interrupted() {
                    let at = Position {
                        frame,
                        step_in_frame: k + 1,
                    };
                    return interrupt(&mut writer, dir, id, at, body.as_ref());
                }
            }
        }
        let written = body.frame(frame, &sinks, dir).and_then(|record| {
            let fragments = record.fragments;
            writer.record_frame(record, body.births(), frame == frames)?;
            Ok(fragments)
        });
        progress.fragments = match written {
            Ok(fragments) => fragments,
            Err(e) => return stop(&mut writer, e),
        };
        progress.frames_written = writer.frames_written();
        observer.frame(&progress);
        if frame < frames {
            let next = Position {
                frame: frame + 1,
                step_in_frame: 0,
            };
            if observer.interrupted() {
                return interrupt(&mut writer, dir, id, next, body.as_ref());
            }
            if plan.checkpoints.due(frame, last_checkpoint.elapsed()) {
                let t = Instant::now();
                let recorded = &writer.manifest().frames;
                let saved = checkpoint::write(dir, id, next, recorded, body.as_ref());
                body.add_output_time(t.elapsed());
                if let Err(e) = saved {
                    return stop(&mut writer, e);
                }
                last_checkpoint = Instant::now();
            }
        }
    }
    let t = Instant::now();
    let finished = match sinks.finish(dir) {
        Ok(f) => f,
        Err(e) => return stop(&mut writer, e),
    };
    let took = t.elapsed();
    body.add_output_time(took);
    let usd = finished
        .into_iter()
        .map(|Finished::Usd(report)| (report, took))
        .next();
    // finished: a checkpoint left from before would only resume what is done
    let _ = std::fs::remove_file(dir.join(CHECKPOINT_FILE));
    let last = writer
        .manifest()
        .frames
        .last()
        .expect("the initial frame is always written");
    Ok(Summary {
        steps: body.steps(),
        time: body.time(),
        dt: plan.dt,
        fragments: last.fragments,
        kinetic_energy: last.kinetic_energy,
        elastic_energy: last.elastic_energy,
        frames_written: writer.frames_written(),
        usd,
        body: body.summary(),
    })
}

/// Writes a checkpoint at `at`, records the interruption in `run.json` and returns it as the
/// error.
fn interrupt(
    writer: &mut RunWriter,
    dir: &Path,
    id: &RunIdentity,
    at: Position,
    body: &dyn Body,
) -> Result<Summary, SceneError> {
    let e = match checkpoint::write(dir, id, at, &writer.manifest().frames, body) {
        Ok(path) => SceneError::Interrupted {
            time: body.time(),
            step: body.steps(),
            frames: writer.frames_written(),
            checkpoint: path,
        },
        Err(e) => e,
    };
    let _ = writer.record_error(e.to_string());
    Err(e)
}
