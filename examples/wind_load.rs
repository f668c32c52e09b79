//! A load of one's own: wind, as an `Influence` added to a scene's driver. Every particle is
//! pulled towards the wind's velocity with a drag of rate `RATE` (1/s) times its mass, so a
//! still body drifts and a broken one's small pieces are carried further than large ones.
//! The scene's colliders and contact still act first; the driver's code is not touched.
//!
//! Run: `cargo run --release --example wind_load -- [SCENE] [OUT_DIR]`
//! (default `data/scenes/wall.toml`, coarsened, into `out/wind_load`).

use std::any::Any;
use std::path::PathBuf;

use perifrac_physics::math::{add, scale, sub, Vec3};
use perifrac_physics::External;
use perifrac_scene::environment::Influence;
use perifrac_scene::{check_output_dir, run, Scene, Setup, Silent};

/// Drag rate towards the wind's velocity (1/s).
const RATE: f64 = 40.0;

/// A uniform wind (m/s).
struct Wind {
    velocity: Vec3,
}

impl Influence for Wind {
    fn name(&self) -> &'static str {
        "wind"
    }

    fn add_forces(&mut self, ext: &mut External<'_>) {
        let (v, m) = (ext.velocities, ext.masses);
        for (i, f) in ext.forces.iter_mut().enumerate() {
            // F = RATE m (w - v): N, with the half-step velocity of the explicit step
            *f = add(*f, scale(sub(self.velocity, v[i]), RATE * m[i]));
        }
    }

    fn begin(&mut self, _dt: f64, _y0: &[Vec3], _v0: &[Vec3], _m: &[f64]) -> Result<(), String> {
        Err("this wind acts in explicit steps only".into())
    }

    fn potential(&mut self, _: &[Vec3], _: &[Vec3], _: Option<(&mut [Vec3], &mut [Vec3])>) -> f64 {
        0.0
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "data/scenes/wall.toml".into()),
    );
    let out = PathBuf::from(args.next().unwrap_or_else(|| "out/wind_load".into()));
    check_output_dir(&out, true)?;
    let mut scene = Scene::load(&scene_path)?;
    if scene.file.mesh.primitive.as_deref() == Some("box") {
        scene.file.mesh.cells = Some([16, 16, 2]);
    }
    let mut setup = Setup::new(&scene, Some(6))?;
    setup.driver.add_influence(Box::new(Wind {
        velocity: [0.0, 5.0, 0.0],
    }));
    let summary = run(setup, &out, &mut Silent)?;
    println!(
        "{} steps in the wind, {} fragments, kinetic energy {:.3e} J; frames in {}",
        summary.steps,
        summary.fragments,
        summary.kinetic_energy,
        out.join("frames").display()
    );
    Ok(())
}
