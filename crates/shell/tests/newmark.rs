//! The implicit Newmark step against what it must do: free fall exactly, momentum to
//! round-off, the explicit step's motion at small steps, bounded energy far past the explicit
//! limit, and the event search over it.

use perifrac_physics::math::{dot, sub, Vec3};
use perifrac_shell::generate::sheet;
use perifrac_shell::*;

fn steel_sheet() -> (ShellDynamics, Vec<Vec3>) {
    // A 10 x 10 cm steel sheet, 1 mm thick, 10 x 10 quads.
    let s = sheet(0.1, 0.1, 10, 10).unwrap();
    let mesh = ShellMesh::new(s.vertices.clone(), s.triangles.clone()).unwrap();
    let steel = ShellMaterial::new(200e9, 0.3, 7800.0, 1e-3).unwrap();
    let shell = ShellDynamics::new(ShellModel::new(mesh, steel).unwrap()).unwrap();
    (shell, s.vertices)
}

/// The sheet set vibrating in and out of its plane by a smooth velocity field (the model
/// test's), free, no gravity.
fn vibrating_sheet() -> ShellDynamics {
    let (mut shell, x) = steel_sheet();
    for (v, p) in shell.velocities_mut().iter_mut().zip(&x) {
        let (x, y) = (p[0] / 0.1, p[1] / 0.1);
        *v = [
            0.5 * (std::f64::consts::PI * y).sin(),
            -0.3 * (std::f64::consts::PI * x).sin(),
            2.0 * (2.0 * std::f64::consts::PI * x).sin() * (std::f64::consts::PI * y).cos(),
        ];
    }
    shell
}

fn energy(s: &ShellDynamics) -> f64 {
    s.kinetic_energy() + s.elastic_energy()
}

fn momentum(s: &ShellDynamics) -> Vec3 {
    let mut p = [0.0; 3];
    for (v, m) in s.velocities().iter().zip(s.model().masses()) {
        for k in 0..3 {
            p[k] += m * v[k];
        }
    }
    p
}

#[test]
fn free_fall_is_exact_at_any_step() {
    // With no strain the potential's minimiser is the target itself and the average
    // acceleration is g: Newmark integrates a constant acceleration exactly. Steps of 10 ms,
    // 10^4 times the sheet's stable step.
    let (mut shell, x0) = steel_sheet();
    let (v0, g) = ([0.3, -0.2, 1.5], [0.0, 0.0, -9.81]);
    shell.velocities_mut().fill(v0);
    shell.set_gravity(g);
    shell.set_newmark(Some(NewmarkConfig::default())).unwrap();
    for _ in 0..20 {
        shell.step(0.01).unwrap();
    }
    let t = shell.time();
    let mut worst: f64 = 0.0;
    for (p, q) in shell.positions().iter().zip(&x0) {
        for k in 0..3 {
            let exact = q[k] + v0[k] * t + 0.5 * g[k] * t * t;
            worst = worst.max((p[k] - exact).abs());
        }
    }
    for v in shell.velocities() {
        for k in 0..3 {
            worst = worst.max((v[k] - (v0[k] + g[k] * t)).abs() * 1e-3);
        }
    }
    // What is left is round-off turned into force by the stiff sheet: edge vectors taken
    // from coordinates of order 1 m carry strains of about 1e-13, forces of about 1e-7 N on
    // vertices of 0.8 g, which move them by about 1e-9 m in 0.2 s. Measured 3.8e-10 m (and
    // velocities scaled by 1 ms); a wrong rule (backward Euler's, say) is off by g dt t / 2,
    // 1 mm.
    assert!(worst < 5e-9, "{worst:e}");
    assert_eq!(shell.newmark_stats().steps, 20);
}

#[test]
fn momentum_is_conserved_to_round_off() {
    // The internal forces sum to zero at any positions and the velocity update is a sum of
    // forces over masses, so momentum holds whether or not the solve converged fully.
    let mut shell = vibrating_sheet();
    let dt = 20.0 * shell.stable_step().unwrap();
    shell.set_newmark(Some(NewmarkConfig::default())).unwrap();
    let p0 = momentum(&shell);
    let scale = shell
        .velocities()
        .iter()
        .zip(shell.model().masses())
        .map(|(v, m)| m * dot(*v, *v).sqrt())
        .sum::<f64>();
    for _ in 0..50 {
        shell.step(dt).unwrap();
    }
    let p = momentum(&shell);
    let drift = dot(sub(p, p0), sub(p, p0)).sqrt() / scale;
    // Measured 2.1e-16 relative to the sum of |m v|.
    assert!(drift < 1e-12, "{drift:e}");
}

#[test]
fn small_steps_follow_the_explicit_motion() {
    // Both rules are second order: at a quarter of the stable step over 400 steps (0.29 ms)
    // the two trajectories differ by O(dt^2); measured 0.045% of the largest displacement.
    let mut explicit = vibrating_sheet();
    let dt = 0.25 * explicit.stable_step().unwrap();
    let mut implicit = explicit.clone();
    implicit
        .set_newmark(Some(NewmarkConfig::default()))
        .unwrap();
    let x0 = explicit.positions().to_vec();
    let mut worst: f64 = 0.0;
    let mut largest: f64 = 0.0;
    for _ in 0..400 {
        explicit.step(dt).unwrap();
        implicit.step(dt).unwrap();
        for ((a, b), r) in explicit
            .positions()
            .iter()
            .zip(implicit.positions())
            .zip(&x0)
        {
            let d = sub(*a, *b);
            worst = worst.max(dot(d, d).sqrt());
            let u = sub(*a, *r);
            largest = largest.max(dot(u, u).sqrt());
        }
    }
    eprintln!("dt {dt:.3e}: worst {worst:.3e} m of {largest:.3e} m");
    assert!(worst < 0.005 * largest, "{worst:e} of {largest:e}");
}

#[test]
fn energy_stays_bounded_far_past_the_explicit_limit() {
    // The average-acceleration rule has no numerical damping and no stability limit: at 50
    // times the explicit limit the total energy stays within 0.2% over 100 steps (measured
    // 1.2e-3; the motion is far from linear in the model's bending), where the explicit step
    // runs away.
    let mut shell = vibrating_sheet();
    let dt = 50.0 * shell.stable_step().unwrap();
    let mut explicit = shell.clone();
    shell.set_newmark(Some(NewmarkConfig::default())).unwrap();
    let e0 = energy(&shell);
    let mut worst: f64 = 0.0;
    for _ in 0..100 {
        shell.step(dt).unwrap();
        worst = worst.max((energy(&shell) - e0).abs() / e0);
    }
    let st = shell.newmark_stats();
    eprintln!("worst {worst:.3e}, {st:?}");
    assert!(worst < 2e-3, "{worst:e}");
    assert_eq!(st.capped, 0);
    let mut ran_away = false;
    for _ in 0..100 {
        match explicit.step(dt) {
            Err(ShellError::RanAway { .. }) => {
                ran_away = true;
                break;
            }
            other => other.unwrap(),
        }
        let e = energy(&explicit);
        if e.is_nan() || e >= 10.0 * e0 {
            ran_away = true;
            break;
        }
    }
    assert!(ran_away);
}

#[test]
fn bad_settings_are_refused() {
    let (mut shell, _) = steel_sheet();
    for c in [
        NewmarkConfig {
            beta: 0.0,
            ..NewmarkConfig::default()
        },
        NewmarkConfig {
            gamma: 0.4,
            ..NewmarkConfig::default()
        },
        NewmarkConfig {
            tolerance: 0.0,
            ..NewmarkConfig::default()
        },
        NewmarkConfig {
            max_iterations: 0,
            ..NewmarkConfig::default()
        },
    ] {
        assert!(matches!(
            shell.set_newmark(Some(c)),
            Err(ShellError::BadSetting { .. })
        ));
    }
    assert!(shell.newmark().is_none());
}

#[test]
fn the_search_undoes_a_trial_whose_solve_reached_its_cap() {
    // Steps of 50 times the explicit limit need about 26 iterations (the energy test): with
    // trials capped at 4 the search halves them until the solves converge, and force growth
    // (off here) plays no part. The motion it takes stays bounded in energy.
    let mut shell = vibrating_sheet();
    let dt = 50.0 * shell.stable_step().unwrap();
    shell.set_newmark(Some(NewmarkConfig::default())).unwrap();
    let e0 = energy(&shell);
    let config = ShellSearch {
        levels: 8,
        force_growth: f64::INFINITY,
        trial_iterations: 4,
        ..ShellSearch::default()
    };
    let mut s = SearchedShell::new(shell, config).unwrap();
    for _ in 0..10 {
        s.advance(dt).unwrap();
    }
    let st = s.stats().clone();
    let nm = s.shell().newmark_stats();
    eprintln!("{st:?} {nm:?}");
    assert!(st.rejected_solve > 0, "{st:?}");
    assert_eq!(st.rejected, st.rejected_solve);
    // Every solve the search kept converged, except at the finest level, where it must take
    // what it has.
    assert!(st.substeps > 10);
    assert!(nm.capped >= st.rejected_solve);
    let worst = (energy(s.shell()) - e0).abs() / e0;
    assert!(worst < 2e-3, "{worst:e}");
}
