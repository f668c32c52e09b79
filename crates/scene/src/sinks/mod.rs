//! Frame outputs as a list of sinks chosen from `[output]`: each writes its files for a frame
//! and says what it wrote, and may write something once the run ends (the USD cache). A new
//! format is one new file here and one line in [`Sinks::from_output`].

mod debris;
mod particles;
pub(crate) mod povray;
mod surface;
mod usd;

use std::path::Path;

use perifrac_io::SurfaceRef;

use crate::debris::Debris;
use crate::error::SceneError;
use crate::manifest::DebrisJson;

pub use debris::DebrisSink;
pub use particles::ParticlesSink;
pub use povray::PovraySink;
pub use surface::SurfacePlySink;
pub use usd::UsdSink;

/// The particles of a frame, for sinks that write points.
#[derive(Debug, Clone, Copy)]
pub struct ParticlesView<'a> {
    /// Positions (m).
    pub positions: &'a [[f64; 3]],
    /// Damage: the share of each particle's bonds broken.
    pub damage: &'a [f64],
    /// Masses (kg).
    pub mass: &'a [f64],
    /// Stable fragment ids, as numbers.
    pub fragment: &'a [f64],
}

/// One frame as a body hands it to the sinks.
pub struct FrameView<'a> {
    /// The frame's index (0 is the rest state).
    pub index: usize,
    /// The surface, with whatever per-vertex and per-face data the body has.
    pub surface: SurfaceRef<'a>,
    /// The particles, when the body has them and a sink asked ([`Sinks::wants_particles`]).
    pub particles: Option<ParticlesView<'a>>,
    /// Small pieces written as points instead of surfaces, when the body made any.
    pub debris: Option<&'a Debris>,
}

/// The files a frame's sinks wrote, relative to the run directory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameFiles {
    /// The surface PLY.
    pub surface: String,
    /// The POV-Ray include.
    pub povray: Option<String>,
    /// The particle PLY.
    pub particles: Option<String>,
    /// The debris PLY and the pieces in it.
    pub debris: Option<DebrisJson>,
}

/// What a sink wrote once the run ended.
#[derive(Debug, Clone)]
pub enum Finished {
    /// The USD cache.
    Usd(crate::usd::UsdReport),
}

/// What a sink's write returns.
pub type Written = Result<(), SceneError>;

/// A frame output.
pub trait FrameSink {
    /// Writes `frame` into the run directory `dir` and records the files in `files`.
    fn write(&self, dir: &Path, frame: &FrameView, files: &mut FrameFiles) -> Written;

    /// Whether this sink needs the frame's particles.
    fn wants_particles(&self) -> bool {
        false
    }

    /// Called once the last frame is written.
    fn finish(&self, _dir: &Path) -> Result<Option<Finished>, SceneError> {
        Ok(None)
    }
}

/// The sinks of a run, in the order they write.
pub struct Sinks {
    sinks: Vec<Box<dyn FrameSink>>,
}

/// What `[output]` asks for, in the terms the sinks need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SinkChoice {
    /// POV-Ray `mesh2` includes.
    pub povray: bool,
    /// Particles as PLY points.
    pub particles: bool,
    /// Debris as PLY points (when a body makes any).
    pub debris: bool,
    /// The USD cache at the end, in this layout.
    pub usd: Option<crate::usd::UsdLayout>,
}

impl Sinks {
    /// The sinks `choice` names; the surface PLY always.
    pub fn from_output(choice: SinkChoice) -> Sinks {
        let mut sinks: Vec<Box<dyn FrameSink>> = vec![Box::new(SurfacePlySink)];
        if choice.povray {
            sinks.push(Box::new(PovraySink));
        }
        if choice.particles {
            sinks.push(Box::new(ParticlesSink));
        }
        if choice.debris {
            sinks.push(Box::new(DebrisSink));
        }
        if let Some(layout) = choice.usd {
            sinks.push(Box::new(UsdSink { layout }));
        }
        Sinks { sinks }
    }

    /// Whether any sink needs the particles.
    pub fn wants_particles(&self) -> bool {
        self.sinks.iter().any(|s| s.wants_particles())
    }

    /// Writes `frame` through every sink.
    pub fn write(&self, dir: &Path, frame: &FrameView) -> Result<FrameFiles, SceneError> {
        let mut files = FrameFiles::default();
        for sink in &self.sinks {
            sink.write(dir, frame, &mut files)?;
        }
        Ok(files)
    }

    /// Ends every sink, returning what they wrote.
    pub fn finish(&self, dir: &Path) -> Result<Vec<Finished>, SceneError> {
        let mut done = Vec::new();
        for sink in &self.sinks {
            done.extend(sink.finish(dir)?);
        }
        Ok(done)
    }
}
