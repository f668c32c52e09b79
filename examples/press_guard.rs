//! Press an elastic steel block to a fifth of its height between the ground and a plate, once
//! with Chen's model as it is and once with the inversion guard, and count where the block
//! folded through itself: pairs of particles within a horizon at rest whose separation now
//! points against the rest one. Linear bonds store no energy that blows up as a neighbourhood
//! turns inside out; the guard's springs towards each particle's affine deformation do.
//!
//! Run: `cargo run --release --example press_guard -- [CELLS] [FACTOR]` (default a block of
//! 6 cells a side, about a minute and three; factor 10).

use std::path::Path;
use std::time::Instant;

use perifrac_bench::stability::turned_over;
use perifrac_physics::math::dot;
use perifrac_scene::{Scene, Setup};

/// The press of `perifrac bench stability` on a block of `n` 1 cm cells a side: the plate (a
/// kinematic ball of radius 10 m) comes down at 10 m/s to 20% of the height, stops, and holds.
fn press(n: usize, guard: Option<f64>) -> String {
    let side = n as f64 * 0.01;
    let squeeze = 0.8 * side / 10.0;
    let guard = guard.map_or(String::new(), |f| format!("inversion_guard = {f:?}\n"));
    format!(
        "[mesh]\nprimitive = \"box\"\nsize = [{side}, {side}, {side}]\ncells = [{n}, {n}, {n}]\n\
         structure = \"lattice\"\n\n\
         [[material]]\nyoung = 200e9\npoisson = 0.25\ndensity = 7800.0\n\n\
         [simulation]\nduration = {}\ndamping = 0.0\nself_contact = true\n{guard}\n\
         [[ground]]\nstiffness_factor = 10.0\n\n\
         [[ball]]\ncenter = [{}, {}, {}]\nradius = 10.0\nvelocity = [0.0, 0.0, -10.0]\n\
         until = {squeeze}\nstiffness_factor = 10.0\n\n[output]\nframes = 4\n",
        2.0 * squeeze,
        side / 2.0,
        side / 2.0,
        side + 10.0,
    )
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(6), |a| a.parse())?;
    let factor: f64 = args.next().map_or(Ok(10.0), |a| a.parse())?;
    for guard in [None, Some(factor)] {
        let scene = Scene::parse(&press(n, guard), Path::new("press.toml"))?;
        let mut setup = Setup::new(&scene, None)?;
        let steps = setup.frames as u64 * setup.steps_per_frame;
        let x = setup.driver.mesh().rest_barycentres();
        let started = Instant::now();
        let mut fastest: f64 = 0.0;
        for _ in 0..steps {
            setup.driver.step()?;
            let v = setup.driver.solver().velocities();
            fastest = v.iter().map(|v| dot(*v, *v).sqrt()).fold(fastest, f64::max);
        }
        let y = setup.driver.solver().positions();
        println!(
            "{}: {} particles, {steps} steps in {:.1} s; fastest particle {fastest:.1} m/s; \
             {} pairs turned over",
            guard.map_or("no guard".into(), |f| format!("guard {f}")),
            x.len(),
            started.elapsed().as_secs_f64(),
            turned_over(&x, y, setup.info.horizon)
        );
    }
    Ok(())
}
