//! Thin-shell scenes (Gingold et al. 2004, crate `perifrac-shell`): a `[shell]` table names a
//! triangle surface (a generated sphere, ellipsoid, cylinder, sheet or bowl, or a file) and its
//! thickness in place of a tet scene's `[mesh]`; one `[[material]]` gives Young's modulus,
//! Poisson's ratio, density, and optionally yield and fracture strains; grounds, balls,
//! anchors, initial velocities and frame output read as in tet scenes. [`ShellScene::load`]
//! parses, [`ShellSetup::new`] validates and builds, [`crate::run()`] steps it and
//! writes frames that `perifrac render` reads.
//!
//! ```no_run
//! use perifrac_scene::{run, ShellScene, ShellSetup, Silent};
//! let scene = ShellScene::load("data/scenes/shell_egg.toml".as_ref())?;
//! let setup = ShellSetup::new(&scene, Some(4), false)?; // 4 frames after the initial one
//! let summary = run(setup, "out/egg".as_ref(), &mut Silent)?;
//! let broken = summary.shell().map_or(0, |s| s.broken_triangles);
//! println!("{broken} triangles broke, {} pieces", summary.fragments);
//! # Ok::<(), perifrac_scene::SceneError>(())
//! ```

mod loads;
mod setup;

pub use perifrac_schema::is_shell_scene;
pub use perifrac_schema::shell::{
    ShellMaterialSpec, ShellOutputSpec, ShellSceneFile, ShellSimulationSpec, ShellSpec,
};
pub use setup::{defaults, ShellScene, ShellSetup, ShellSetupInfo};
