//! What the run loop steps: a body. A tet solid (`solid.rs`: the [`crate::Driver`] over a
//! peridynamic solver) and a thin shell (`shell.rs`) both implement the crate's `Body` trait,
//! so one run loop, one checkpoint convention, one `run.json` and one summary serve both.

pub(crate) mod shell;
pub(crate) mod solid;

use std::path::{Path, PathBuf};
use std::time::Duration;

use perifrac_checkpoint::{Reader, Writer};
use perifrac_physics::EstimateMemo;

use crate::budget::Limits;
use crate::error::SceneError;
use crate::fragments::FragmentBirth;
use crate::load::Scene;
use crate::manifest::{BodyJson, Bounds, FrameJson, GroundJson};
use crate::setup::{CheckpointPolicy, Setup};
use crate::shell::{ShellScene, ShellSetup};
use crate::sinks::{SinkChoice, Sinks};

pub use shell::ShellSummary;
pub use solid::SolidSummary;

/// Why a step failed.
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    /// The peridynamic solver of a tet solid.
    #[error("{0}")]
    Solid(perifrac_physics::PhysicsError),
    /// A thin shell.
    #[error("{0}")]
    Shell(perifrac_shell::ShellError),
}

/// The fixed part of `run.json` a body gives at the start.
#[derive(Debug, Clone)]
pub(crate) struct Head {
    pub up: [f64; 3],
    pub rest_bounds: Bounds,
    pub grounds: Vec<GroundJson>,
    pub dt: f64,
    pub dt_limit: f64,
    pub mass: f64,
    pub body: BodyJson,
}

/// A body the run loop steps and writes.
pub(crate) trait Body {
    /// `run.json`'s fixed facts.
    fn head(&self) -> Head;
    /// Writes what identifies the freshly built body (its rest mesh, counts) for the
    /// checkpoint's fingerprint.
    fn identify(&self, w: &mut Writer);
    /// One step.
    fn step(&mut self) -> Result<(), StepError>;
    /// Simulated time (s).
    fn time(&self) -> f64;
    /// Steps taken.
    fn steps(&self) -> u64;
    /// Bonds (solids) or triangles (shells) broken so far.
    fn broken(&self) -> u64;
    /// Hands frame `index` to `sinks` in `dir` and returns its record.
    fn frame(&mut self, index: usize, sinks: &Sinks, dir: &Path) -> Result<FrameJson, SceneError>;
    /// Every fragment so far, in id order.
    fn births(&self) -> Vec<FragmentBirth>;
    /// Writes everything steps and frames changed.
    fn save(&self, w: &mut Writer);
    /// Reads what [`Body::save`] wrote into a body built by the same setup.
    fn restore(&mut self, r: &mut Reader) -> Result<(), String>;
    /// Adds wall time spent writing output.
    fn add_output_time(&mut self, d: Duration);
    /// The body's part of the summary.
    fn summary(&mut self) -> BodySummary;
}

/// The body's part of a run's [`crate::Summary`].
#[derive(Debug, Clone, PartialEq)]
pub enum BodySummary {
    /// A tet solid's.
    Solid(SolidSummary),
    /// A thin shell's.
    Shell(ShellSummary),
}

/// What the run loop needs besides the body.
pub(crate) struct Plan {
    pub scene_path: PathBuf,
    pub scene_text: String,
    pub frames: usize,
    pub steps_per_frame: u64,
    pub dt: f64,
    pub fps: f64,
    pub checkpoints: CheckpointPolicy,
    pub sinks: SinkChoice,
}

/// A scene file of either kind, parsed.
#[derive(Debug, Clone)]
pub enum AnyScene {
    /// A tet solid (`[mesh]`).
    Solid(Box<Scene>),
    /// A thin shell (`[shell]`).
    Shell(Box<ShellScene>),
}

impl AnyScene {
    /// Reads and parses `path`: a thin shell when it has a `[shell]` table, else a tet solid.
    pub fn load(path: &Path) -> Result<AnyScene, SceneError> {
        AnyScene::parse(&crate::load::read(path)?, path)
    }

    /// Parses `text` as if read from `path` (relative files resolve against its directory).
    pub fn parse(text: &str, path: &Path) -> Result<AnyScene, SceneError> {
        if crate::shell::is_shell_scene(text) {
            ShellScene::parse(text, path).map(|s| AnyScene::Shell(Box::new(s)))
        } else {
            Scene::parse(text, path).map(|s| AnyScene::Solid(Box::new(s)))
        }
    }

    /// The scene file.
    pub fn path(&self) -> &Path {
        match self {
            AnyScene::Solid(s) => &s.path,
            AnyScene::Shell(s) => &s.path,
        }
    }
}

/// A scene of either kind ready to run.
pub enum AnySetup {
    /// A tet solid.
    Solid(Box<Setup>),
    /// A thin shell.
    Shell(Box<ShellSetup>),
}

impl From<Setup> for AnySetup {
    fn from(s: Setup) -> AnySetup {
        AnySetup::Solid(Box::new(s))
    }
}

impl From<ShellSetup> for AnySetup {
    fn from(s: ShellSetup) -> AnySetup {
        AnySetup::Shell(Box::new(s))
    }
}

impl AnySetup {
    /// Validates and builds `scene`: `frames` overrides its frame count, `limits` bound the
    /// work (a shell checks its step count and `allow_large` only), `memo` recalls a solid's
    /// stable-step estimate.
    pub fn new(
        scene: &AnyScene,
        frames: Option<usize>,
        limits: &Limits,
        memo: Option<&dyn EstimateMemo>,
    ) -> Result<AnySetup, SceneError> {
        Ok(match scene {
            AnyScene::Solid(s) => Setup::with_memo(s, frames, limits, memo)?.into(),
            AnyScene::Shell(s) => ShellSetup::new(s, frames, limits.allow_large)?.into(),
        })
    }

    /// Frames after the initial one.
    pub fn frames(&self) -> usize {
        match self {
            AnySetup::Solid(s) => s.frames,
            AnySetup::Shell(s) => s.frames,
        }
    }

    /// Steps between frames.
    pub fn steps_per_frame(&self) -> u64 {
        match self {
            AnySetup::Solid(s) => s.steps_per_frame,
            AnySetup::Shell(s) => s.steps_per_frame,
        }
    }

    /// The body to step and the plan around it.
    pub(crate) fn split(self) -> (Box<dyn Body>, Plan) {
        match self {
            AnySetup::Solid(s) => solid::split(*s),
            AnySetup::Shell(s) => shell::split(*s),
        }
    }
}
