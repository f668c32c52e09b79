//! A steel strip clamped along one end sags under its own weight: the thin-shell model
//! (crates/shell) stepped with damping to rest, at three resolutions, beside the Kirchhoff
//! plate answer `q L^4 / (8 D)`. Explicitly at 0.8 of the stable step by default; with
//! `newmark`, by the implicit Newmark step at 0.1 ms, a hundred and more times the explicit
//! limit (the first bending mode's period is 12 ms).
//!
//! Run: `cargo run --release --example shell_cantilever [-- newmark]` (about 11 s explicit,
//! 1.4 s with Newmark's 500 steps, which give the same tips to 3 or 4 digits: 81.0, 90.2 and
//! 95.1% of Kirchhoff's).

use perifrac_shell::{
    generate, NewmarkConfig, ShellDynamics, ShellMaterial, ShellMesh, ShellModel,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let newmark = std::env::args().nth(1).as_deref() == Some("newmark");
    // 10 x 2 cm, 1 mm thick; nu = 0 so the strip and the wide plate agree.
    let (length, width, h): (f64, f64, f64) = (0.1, 0.02, 1e-3);
    let steel = ShellMaterial::new(200e9, 0.0, 7800.0, h)?;
    let d = steel.young * h.powi(3) / 12.0;
    let q = steel.areal_density() * 9.81;
    let expected = q * length.powi(4) / (8.0 * d);
    println!("Kirchhoff tip deflection {:.4e} m", expected);
    for (nx, ny) in [(10, 2), (20, 4), (40, 8)] {
        let s = generate::sheet(length, width, nx, ny)?;
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles.clone())?;
        let mut shell = ShellDynamics::new(ShellModel::new(mesh, steel)?)?;
        // Two rows of vertices held: their triangles stay flat, which clamps the slope.
        let dx = length / nx as f64;
        for (i, p) in s.vertices.iter().enumerate() {
            if p[0] < dx + 1e-9 {
                shell.pin(i);
            }
        }
        shell.set_gravity([0.0, 0.0, -9.81]);
        // About critical damping of the first bending mode (514 rad/s).
        shell.set_damping(500.0)?;
        let dt = if newmark {
            shell.set_newmark(Some(NewmarkConfig::default()))?;
            1e-4
        } else {
            0.8 * shell.stable_step()?
        };
        let steps = (0.05 / dt).ceil() as usize;
        let started = std::time::Instant::now();
        for _ in 0..steps {
            shell.step(dt)?;
        }
        let wall = started.elapsed().as_secs_f64();
        let tip: Vec<f64> = s
            .vertices
            .iter()
            .zip(shell.positions())
            .filter(|(p, _)| p[0] > length - 1e-9)
            .map(|(_, x)| -x[2])
            .collect();
        let mean = tip.iter().sum::<f64>() / tip.len() as f64;
        println!(
            "{nx:>3} x {ny:<2} quads: {steps:>6} steps of {dt:.2e} s in {wall:.2} s, tip {mean:.4e} m, \
             {:.1}% of Kirchhoff's",
            100.0 * mean / expected
        );
    }
    Ok(())
}
