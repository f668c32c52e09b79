//! Scene files and the simulation driver of perifrac.
//!
//! A scene (TOML, [`schema`], crate `perifrac-schema`) names the object (a built-in primitive or a mesh file), materials
//! by region, the horizon, the time step (`"auto"` allowed), the duration, colliders (ground
//! planes and balls), anchors, initial velocities, initial cracks and the frame output. A
//! thin-shell scene ([`shell`]) names a triangle surface instead.
//!
//! - [`Scene::load`] parses a tet scene with line and column in every error; [`AnyScene::load`]
//!   reads either kind.
//! - [`Setup::new`] validates it and builds the mesh, the peridynamic model, the colliders and
//!   the solver without writing anything; [`AnySetup::new`] builds either kind.
//! - [`run()`] steps the body (a solid's [`Driver`], or a shell) in one loop for both, and writes
//!   frames through the sinks ([`sinks`]) into a run directory (layout in [`output`]),
//!   reporting progress to an [`Observer`].
//! - An interrupted run leaves a [`Checkpoint`] that [`resume`] continues from, byte for byte.
//!
//! ```no_run
//! use perifrac_scene::{run, Scene, Setup, Silent};
//! let scene = Scene::load("data/scenes/wall.toml".as_ref())?;
//! let setup = Setup::new(&scene, Some(4))?; // 4 frames after the initial one
//! let summary = run(setup, "out/wall".as_ref(), &mut Silent)?;
//! println!("{} fragments", summary.fragments);
//! # Ok::<(), perifrac_scene::SceneError>(())
//! ```

#![warn(missing_docs)]

pub mod body;
pub mod budget;
pub mod checkpoint;
pub mod debris;
pub mod driver;
pub mod environment;
pub mod error;
pub mod fragments;
pub mod load;
pub mod manifest;
pub mod memo;
pub mod output;
pub mod run;
pub mod setup;
pub mod shell;
pub mod sinks;
pub mod usd;

/// The scene file's tables (the `perifrac-schema` crate).
pub use perifrac_schema as schema;

pub use body::{AnyScene, AnySetup, BodySummary, ShellSummary, SolidSummary, StepError};
pub use budget::{Limits, WorkEstimate};
pub use checkpoint::{Checkpoint, Position, CHECKPOINT_FILE};
pub use driver::{Driver, StageTimes, StepReport};
pub use error::SceneError;
pub use fragments::{FragmentBirth, FragmentIds};
pub use load::Scene;
pub use manifest::{FrameJson, RunManifest, RUN_FORMAT};
pub use memo::MemoDir;
pub use output::{check_output_dir, POVRAY_MESH_NAME};
pub use run::{resume, run, Observer, Progress, Silent, Summary};
pub use setup::{CheckpointPolicy, OutputOptions, Setup, SetupInfo, SetupTimes};
pub use shell::{is_shell_scene, ShellScene, ShellSetup, ShellSetupInfo};
pub use usd::{export_usd, UsdLayout, UsdReport, DEFAULT_FPS};
