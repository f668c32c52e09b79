//! Shell fracture energy: a slotted glass strip pulled apart slowly dissipates `G_c h` per unit
//! length of the cracks it opens, at every resolution.

use perifrac_physics::math::{dot, norm, sub};
use perifrac_shell::generate::{sheet, sheet_uniform};
use perifrac_shell::*;

/// The strip's side (m) and thickness (m).
const SIDE: f64 = 0.05;
const THICKNESS: f64 = 1e-3;

/// What a pulled strip dissipated (J) and the length of the cracks it opened (m, rest).
struct Pulled {
    dissipated: f64,
    crack: f64,
}

/// A 5 x 5 cm glass strip, 1 mm thick, `n` x `n` cells (checkerboard diagonals, or all alike
/// when `uniform`), with a slot one cell wide from its lower edge to a quarter of its width at
/// the middle, pulled along x at a strain rate of 0.5/s (every vertex starts on the uniform
/// stretch, so no wave starts at the ends) until it is in two, then held for four wave
/// transits. Breaks by `fracture_energy` `g_c` (J/m^2) alone; no damping.
fn pulled(n: usize, g_c: f64, uniform: bool) -> Pulled {
    let s = if uniform {
        sheet_uniform(SIDE, SIDE, n, n).unwrap()
    } else {
        sheet(SIDE, SIDE, n, n).unwrap()
    };
    let a = SIDE / n as f64;
    let in_slot = |t: &[u32; 3]| {
        let c: [f64; 2] =
            [0, 1].map(|k| t.iter().map(|&i| s.vertices[i as usize][k]).sum::<f64>() / 3.0);
        c[0] > 0.5 * SIDE && c[0] < 0.5 * SIDE + a && c[1] < 0.25 * SIDE
    };
    let tris: Vec<[u32; 3]> = s
        .triangles
        .iter()
        .filter(|t| !in_slot(t))
        .copied()
        .collect();
    let mesh = ShellMesh::new(s.vertices.clone(), tris).unwrap();
    let glass = ShellMaterial::new(70e9, 0.22, 2500.0, THICKNESS).unwrap();
    let fracture = ShellFracture::new(f64::MAX, f64::MAX, 0.25, 1.0)
        .unwrap()
        .with_energy(g_c)
        .unwrap();
    let model = ShellModel::new(mesh, glass)
        .unwrap()
        .with_fracture(fracture);
    let mut shell = ShellDynamics::new(model).unwrap();
    let speed = 0.5 * 0.5 * SIDE;
    let mut driven = Vec::new();
    for (i, p) in s.vertices.iter().enumerate() {
        let v = speed * (2.0 * p[0] / SIDE - 1.0);
        shell.velocities_mut()[i] = [v, 0.0, 0.0];
        if p[0] < 1e-9 || p[0] > SIDE - 1e-9 {
            shell.drive(i, [v, 0.0, 0.0]);
            driven.push(i);
        }
    }
    let start = shell.kinetic_energy();
    let mut dt = 0.5 * shell.stable_step().unwrap();
    // four transits of a 3,000 m/s wave across the strip, in steps of the first size
    let hold = (4.0 * SIDE / 3000.0 / dt) as u64;
    let mut work = 0.0;
    let mut apart = None;
    for step in 0u64.. {
        // The holders' work: minus the body's force on the held vertices, times their
        // velocity, averaged over the step.
        let before: Vec<[f64; 3]> = driven.iter().map(|&i| shell.forces()[i]).collect();
        shell.step(dt).unwrap();
        for (k, &i) in driven.iter().enumerate() {
            let v = shell.velocities()[i];
            work -= 0.5 * dt * (dot(before[k], v) + dot(shell.forces()[i], v));
        }
        let r = shell.fracture().unwrap();
        if !r.events.is_empty() {
            // splits make smaller triangles: the stable step follows
            dt = dt.min(0.5 * shell.stable_step().unwrap());
            if apart.is_none()
                && pieces(shell.model().mesh())
                    .iter()
                    .max()
                    .is_some_and(|&p| p >= 1)
            {
                apart = Some(step);
                for &i in &driven {
                    shell.drive(i, [0.0; 3]);
                }
            }
        }
        if apart.is_some_and(|a| step > a + hold) {
            break;
        }
        assert!(step < 2_000_000, "the strip did not part");
    }
    let left = shell.elastic_energy() + shell.kinetic_energy();
    let m = shell.model();
    let x = m.mesh().vertices();
    // each crack edge is flagged in the triangle on each side of it
    let mut crack = 0.0;
    for (t, c) in m.mesh().triangles().iter().zip(m.crack_edges()) {
        for k in 0..3 {
            if c[k] {
                crack += 0.5 * norm(sub(x[t[(k + 1) % 3] as usize], x[t[(k + 2) % 3] as usize]));
            }
        }
    }
    Pulled {
        dissipated: work + start - left,
        crack,
    }
}

#[test]
fn a_pulled_strip_dissipates_the_fracture_energy_of_its_cracks_at_three_resolutions() {
    let g_c = 20.0;
    let mut dissipated = Vec::new();
    for n in [10, 20, 40] {
        let p = pulled(n, g_c, false);
        let ratio = p.dissipated / (g_c * THICKNESS * p.crack);
        eprintln!(
            "{n} x {n}: dissipated {:.4e} J, cracks {:.1} mm, D / (G_c h L) = {ratio:.3}",
            p.dissipated,
            1e3 * p.crack
        );
        // Measured 0.950, 0.964, 0.950: the triangle beside the split one gives up a little
        // less than the threshold's energy. The issue accepts 10%.
        assert!((ratio - 1.0).abs() < 0.10, "{n}: {ratio}");
        dissipated.push(p.dissipated);
    }
    // The cracks branch and spur alike at every resolution: the energy the strip takes to part
    // is the same within 4% (measured 2.01e-3, 2.06e-3, 2.09e-3 J); 10% allows another path.
    let (lo, hi) = dissipated
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), &d| (l.min(d), h.max(d)));
    assert!(hi / lo < 1.10, "{dissipated:?}");
}

#[test]
#[ignore = "the all-alike diagonals at three resolutions: measured, not a bound (docs/DECISIONS.md)"]
fn uniform_diagonals() {
    let g_c = 20.0;
    for n in [10, 20, 40] {
        let p = pulled(n, g_c, true);
        eprintln!(
            "{n} x {n}, uniform: dissipated {:.4e} J, cracks {:.1} mm, D / (G_c h L) = {:.3}",
            p.dissipated,
            1e3 * p.crack,
            p.dissipated / (g_c * THICKNESS * p.crack)
        );
    }
}
