//! Running a prepared scene: steps between frames, frames into a run directory (layout in
//! [`crate::output`]), progress to an [`Observer`], a [`Summary`] at the end.

use std::path::Path;

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
}

/// Runs `setup` to the end, writing frames into `dir`. On an instability the frames written
/// so far stay, `run.json` records the error, and [`SceneError::Stopped`] is returned; a
/// failure to write a frame (a full disk, say) is recorded in `run.json` too and returned.
pub fn run(setup: Setup, dir: &Path, observer: &mut dyn Observer) -> Result<Summary, SceneError> {
    let Setup {
        scene_path,
        scene_text,
        mut driver,
        frames,
        steps_per_frame,
        output,
        info,
    } = setup;
    let mut writer = FrameWriter::create(dir, &scene_path, &scene_text, &info, &driver, output)?;
    let total_steps = (frames as u64).saturating_mul(steps_per_frame);
    let mut progress = Progress {
        time: 0.0,
        duration: info.dt * total_steps as f64,
        steps: 0,
        total_steps,
        broken_bonds: 0,
        fragments: 1,
        frames_written: 0,
    };
    for frame in 0..=frames {
        if frame > 0 {
            for _ in 0..steps_per_frame {
                if let Err(cause) = driver.step() {
                    let stopped = SceneError::Stopped {
                        time: driver.solver().time(),
                        step: driver.solver().steps(),
                        frames: writer.frames_written(),
                        cause,
                    };
                    // Best effort: the stop is the error to report, recorded or not.
                    let _ = writer.record_error(stopped.to_string());
                    return Err(stopped);
                }
                progress.steps += 1;
                progress.time = driver.solver().time();
                progress.broken_bonds = driver.broken_bonds();
                observer.step(&progress);
            }
        }
        let written = writer
            .write_frame(frame, &mut driver, frame == frames)
            .map(|w| w.fragments);
        let fragments = match written {
            Ok(fragments) => fragments,
            Err(e) => {
                // Best effort, as above: the write error is what the caller reports.
                let _ = writer.record_error(e.to_string());
                return Err(e);
            }
        };
        progress.fragments = fragments;
        progress.frames_written = frame + 1;
        observer.frame(&progress);
    }
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
        integrator: driver.solver().integrator_name(),
    })
}
