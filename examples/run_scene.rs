//! Run a scene from code: load a scene file, change it before it is set up (here: a slower
//! ball and a coarser slab, so it runs in seconds), watch the frames as they are written, and
//! read the summary. This is what `perifrac run` does, without the progress bar.
//!
//! Run: `cargo run --release --example run_scene -- [SCENE] [OUT_DIR]`
//! (default `data/scenes/wall.toml` into `out/run_scene`).

use std::path::PathBuf;

use perifrac_scene::{check_output_dir, run, Observer, Progress, Scene, Setup};

/// Prints one line per frame.
struct Frames;

impl Observer for Frames {
    fn frame(&mut self, p: &Progress) {
        println!(
            "frame {:>2}: t = {:.2e} s, {} bonds broken, {} fragment(s)",
            p.frames_written - 1,
            p.time,
            p.broken_bonds,
            p.fragments
        );
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "data/scenes/wall.toml".into()),
    );
    let out = PathBuf::from(args.next().unwrap_or_else(|| "out/run_scene".into()));
    check_output_dir(&out, true)?;

    let mut scene = Scene::load(&scene_path)?;
    // The parsed tables are plain data: edit them before the setup validates and builds.
    if scene.file.mesh.primitive.as_deref() == Some("box") {
        scene.file.mesh.cells = Some([16, 16, 2]);
    }
    for ball in &mut scene.file.ball {
        if let Some(v) = &mut ball.velocity {
            *v = v.map(|c| 0.5 * c);
        }
    }
    let setup = Setup::new(&scene, Some(8))?;
    println!(
        "{}: {} particles, {} bonds, dt {:.2e} s, {} steps per frame",
        scene_path.display(),
        setup.info.particles,
        setup.info.bonds,
        setup.info.dt,
        setup.steps_per_frame
    );
    let summary = run(setup, &out, &mut Frames)?;
    println!(
        "{} steps, {} bonds broken, {} fragments, kinetic energy {:.3e} J; frames in {}",
        summary.steps,
        summary.solid().map_or(0, |s| s.broken_bonds),
        summary.fragments,
        summary.kinetic_energy,
        out.join("frames").display()
    );
    Ok(())
}
