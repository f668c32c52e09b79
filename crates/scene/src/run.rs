//! Running a prepared scene: steps between frames, frames into a run directory (layout in
//! [`crate::output`]), progress to an [`Observer`], a [`Summary`] at the end.

use std::path::Path;
use std::time::Instant;

use crate::checkpoint::{self, Checkpoint, Position, RunIdentity, CHECKPOINT_FILE};

use crate::driver::StageTimes;
use crate::error::SceneError;
use crate::output::FrameWriter;
use crate::setup::Setup;

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
    /// Bonds broken so far (pairs).
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
    /// Bonds broken (pairs).
    pub broken_bonds: u64,
    /// Fragments (connected pieces of the cut mesh) at the end.
    pub fragments: usize,
    /// Crack triangles in the last surface (both sides counted).
    pub crack_triangles: usize,
    /// Kinetic energy of the particles at the end (J).
    pub kinetic_energy: f64,
    /// Elastic energy at the end (J).
    pub elastic_energy: f64,
    /// Kinetic energy of the dynamic balls at the end (J).
    pub ball_kinetic_energy: f64,
    /// Frames written, the initial one included.
    pub frames_written: usize,
    /// Wall time per stage (s).
    pub stage_times: StageTimes,
    /// The integrator's counters (iterations, factorisations and their wall times for the
    /// implicit one; zeros for the explicit one).
    pub solver: perifrac_physics::SolverStats,
    /// The integrator's name.
    pub integrator: &'static str,
    /// Self contact, when the scene has it: pair-list builds, and the most pairs in contact
    /// in a step with the deepest overlap (m, and as a share of the contact distance).
    pub self_contact: Option<(u64, perifrac_contact::SelfContactStats)>,
    /// The USD cache, when the scene asked for one, and the wall time it took to write.
    pub usd: Option<(crate::usd::UsdReport, std::time::Duration)>,
}

/// Runs `setup` to the end, writing frames into `dir`. On an instability the frames written
/// so far stay, `run.json` records the error, and [`SceneError::Stopped`] is returned; a
/// failure to write a frame (a full disk, say) is recorded in `run.json` too and returned.
/// When the observer reports an interruption, a checkpoint is written and
/// [`SceneError::Interrupted`] returned; [`resume`] continues from it.
pub fn run(setup: Setup, dir: &Path, observer: &mut dyn Observer) -> Result<Summary, SceneError> {
    let id = RunIdentity::of(&setup);
    let writer = FrameWriter::create(dir, &setup)?;
    let start = Position {
        frame: 0,
        step_in_frame: 0,
    };
    drive(setup, &id, writer, dir, start, observer)
}

/// Continues the run in `dir` from `checkpoint` (read by [`Checkpoint::read`]); `setup` must be
/// built from [`Checkpoint::scene`] with [`Checkpoint::frames`]. A checkpoint of another scene,
/// mesh or step is refused. The files written are byte-identical to those of a run that was
/// never interrupted.
pub fn resume(
    mut setup: Setup,
    checkpoint: &Checkpoint,
    dir: &Path,
    observer: &mut dyn Observer,
) -> Result<Summary, SceneError> {
    // the identity of the fresh setup, before the restore cuts its mesh
    let id = RunIdentity::of(&setup);
    checkpoint.restore(dir, &mut setup)?;
    let writer = FrameWriter::resume(dir, &setup, checkpoint.recorded.clone())?;
    drive(setup, &id, writer, dir, checkpoint.position, observer)
}

/// The step loop from `start` to the end.
fn drive(
    setup: Setup,
    id: &RunIdentity,
    mut writer: FrameWriter,
    dir: &Path,
    start: Position,
    observer: &mut dyn Observer,
) -> Result<Summary, SceneError> {
    let Setup {
        mut driver,
        frames,
        steps_per_frame,
        output,
        info,
        ..
    } = setup;
    let total_steps = (frames as u64).saturating_mul(steps_per_frame);
    let mut progress = Progress {
        time: driver.solver().time(),
        duration: info.dt * total_steps as f64,
        steps: driver.solver().steps(),
        total_steps,
        broken_bonds: driver.broken_bonds(),
        fragments: writer.manifest().frames.last().map_or(1, |f| f.fragments),
        frames_written: writer.frames_written(),
    };
    let mut last_checkpoint = Instant::now();
    // stops with the error recorded in run.json (best effort: the error is what is reported)
    let stop = |writer: &mut FrameWriter, e: SceneError| {
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
            for k in first..steps_per_frame {
                if let Err(cause) = driver.step() {
                    let stopped = SceneError::Stopped {
                        time: driver.solver().time(),
                        step: driver.solver().steps(),
                        frames: writer.frames_written(),
                        cause,
                    };
                    return stop(&mut writer, stopped);
                }
                progress.steps += 1;
                progress.time = driver.solver().time();
                progress.broken_bonds = driver.broken_bonds();
                observer.step(&progress);
                if observer.interrupted() {
                    let at = Position {
                        frame,
                        step_in_frame: k + 1,
                    };
                    return interrupt(&mut writer, dir, id, at, &driver);
                }
            }
        }
        let written = writer
            .write_frame(frame, &mut driver, frame == frames)
            .map(|w| w.fragments);
        let fragments = match written {
            Ok(fragments) => fragments,
            Err(e) => return stop(&mut writer, e),
        };
        progress.fragments = fragments;
        progress.frames_written = writer.frames_written();
        observer.frame(&progress);
        if frame < frames {
            let next = Position {
                frame: frame + 1,
                step_in_frame: 0,
            };
            if observer.interrupted() {
                return interrupt(&mut writer, dir, id, next, &driver);
            }
            if output.checkpoints.due(frame, last_checkpoint.elapsed()) {
                let t = Instant::now();
                let saved = checkpoint::write(dir, id, next, &writer.manifest().frames, &driver);
                driver.add_output_time(t.elapsed());
                if let Err(e) = saved {
                    return stop(&mut writer, e);
                }
                last_checkpoint = Instant::now();
            }
        }
    }
    let usd = match output.usd {
        Some(layout) => {
            let t = Instant::now();
            match crate::usd::export_usd(dir, None, layout, None) {
                Ok(report) => {
                    let took = t.elapsed();
                    driver.add_output_time(took);
                    Some((report, took))
                }
                Err(e) => return stop(&mut writer, e),
            }
        }
        None => None,
    };
    // finished: a checkpoint left from before would only resume what is done
    let _ = std::fs::remove_file(dir.join(CHECKPOINT_FILE));
    let last = writer
        .manifest()
        .frames
        .last()
        .expect("the initial frame is always written");
    Ok(Summary {
        steps: driver.solver().steps(),
        time: driver.solver().time(),
        dt: info.dt,
        broken_bonds: driver.broken_bonds(),
        fragments: last.fragments,
        crack_triangles: last.crack_triangles,
        kinetic_energy: last.kinetic_energy,
        elastic_energy: last.elastic_energy,
        ball_kinetic_energy: driver.colliders().map_or(0.0, |c| c.kinetic_energy()),
        frames_written: writer.frames_written(),
        stage_times: driver.stage_times(),
        solver: driver.solver().stats(),
        self_contact: driver
            .self_contact()
            .map(|c| (c.rebuilds(), driver.self_contact_deepest())),
        integrator: driver.solver().integrator_name(),
        usd,
    })
}

/// Writes a checkpoint at `at`, records the interruption in `run.json` and returns it as the
/// error.
fn interrupt(
    writer: &mut FrameWriter,
    dir: &Path,
    id: &RunIdentity,
    at: Position,
    driver: &crate::driver::Driver,
) -> Result<Summary, SceneError> {
    let e = match checkpoint::write(dir, id, at, &writer.manifest().frames, driver) {
        Ok(path) => SceneError::Interrupted {
            time: driver.solver().time(),
            step: driver.solver().steps(),
            frames: writer.frames_written(),
            checkpoint: path,
        },
        Err(e) => e,
    };
    let _ = writer.record_error(e.to_string());
    Err(e)
}
