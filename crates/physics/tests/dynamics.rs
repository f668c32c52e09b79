//! Explicit integration: stable-step estimate, blow-up guard, energy and angular momentum.

mod support;

use perifrac_physics::energy::angular_momentum;
use perifrac_physics::math::{cross, norm, sub, Vec3};
use perifrac_physics::{
    lanczos_frequency, max_frequency, stable_frequency, stable_frequency_memo, ChenMaterial,
    ChenModel, Discretization, EstimateMemo, Explicit, ExplicitConfig, ForceModel, FractureParams,
    FrequencyEstimate, Loads, MemoKey, PhysicsError, TimeStep,
};
use perifrac_topology::mesher::unstructured_box_data;
use perifrac_topology::TetMesh;
use std::cell::RefCell;
use std::collections::HashMap;
use support::{elastic_block, nonuniform, scalar_block};

fn solver(cells: [usize; 3], dt: TimeStep) -> Explicit<ChenModel> {
    let m = elastic_block(cells, 1.5);
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let loads = Loads::new(x.len());
    let cfg = ExplicitConfig {
        dt,
        guard_fraction: 0.5,
    };
    Explicit::new(m, &x, delta, loads, cfg).unwrap()
}

/// Releases the block from a 0.1% non-uniform strain.
fn strain(s: &mut Explicit<ChenModel>, size: f64) {
    let x = s.model().discretization().rest_positions().to_vec();
    s.set_positions(&nonuniform(&x, 1e-3, size));
}

fn total_energy(s: &mut Explicit<ChenModel>) -> f64 {
    s.kinetic_energy() + s.elastic_energy()
}

#[test]
fn power_iteration_step_is_stable_at_0_9_and_caught_at_1_5() {
    let mut m = elastic_block([3, 3, 3], 1.5);
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let est = max_frequency(&mut m, &x, delta, 500, 1e-10);
    let sa = m.silling_askari_step();
    eprintln!(
        "omega_max {:.4e} rad/s after {} iterations (change {:.1e}); dt_crit {:.4e} s; Silling-Askari {:.4e} s = {:.3} of it",
        est.omega_max,
        est.iterations,
        est.last_change,
        est.critical_step(),
        sa,
        sa / est.critical_step()
    );
    // the limit 2 / omega_max of velocity Verlet, probed from a strained start with all modes
    for (factor, stable) in [(0.9, true), (1.5, false)] {
        let mut s = solver([3, 3, 3], TimeStep::Fixed(factor * est.critical_step()));
        strain(&mut s, 0.03);
        let e0 = total_energy(&mut s);
        let mut result = Ok(());
        let mut emax: f64 = e0;
        for step in 0..3000 {
            if let Err(e) = s.step() {
                result = Err(e);
                break;
            }
            if step % 100 == 0 {
                emax = emax.max(total_energy(&mut s));
            }
        }
        if stable {
            assert!(result.is_ok(), "{result:?}");
            eprintln!("factor {factor}: energy {e0:.4e}, largest {emax:.4e}");
            // Near the limit the measured energy of the top modes swings by 1 / (1 - (w dt)^2 / 4)
            // about Verlet's conserved shadow energy, but does not grow: measured largest 1.0 e0
            // (the strained start is the energy maximum); an unstable mode grows ~7x per step.
            assert!(emax < 1.5 * e0);
        } else {
            eprintln!("factor {factor}: {result:?} after {} steps", s.steps());
            assert!(matches!(result, Err(PhysicsError::Unstable { .. })));
            assert!(s.steps() < 200);
        }
    }
}

#[test]
fn auto_step_uses_the_lanczos_estimate() {
    let s = solver([2, 2, 2], TimeStep::Auto { safety: 0.8 });
    let est = s.estimate().unwrap();
    assert!((s.dt() - 0.8 * est.critical_step()).abs() < 1e-15 * s.dt());
    let mut m = elastic_block([2, 2, 2], 1.5);
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let (omega, lanczos) = stable_frequency(&mut m, &x, delta);
    assert_eq!(est, lanczos);
    assert_eq!(omega, est.omega_max);
}

/// A memo in memory that counts its stores.
#[derive(Default)]
struct Memo {
    kept: RefCell<HashMap<MemoKey, FrequencyEstimate>>,
    stores: RefCell<usize>,
}

impl EstimateMemo for Memo {
    fn recall(&self, key: MemoKey) -> Option<FrequencyEstimate> {
        self.kept.borrow().get(&key).copied()
    }
    fn store(&self, key: MemoKey, estimate: &FrequencyEstimate) {
        *self.stores.borrow_mut() += 1;
        self.kept.borrow_mut().insert(key, *estimate);
    }
}

#[test]
fn a_memo_gives_back_the_iterated_estimate_bit_for_bit_after_one_evaluation() {
    let estimate = |m: &mut ChenModel, memo: Option<&dyn EstimateMemo>| {
        let x = m.discretization().rest_positions().to_vec();
        let delta = m.discretization().horizon();
        stable_frequency_memo(m, &x, delta, memo)
    };
    let memo = Memo::default();
    let mut m = elastic_block([3, 3, 2], 1.5);
    let (_, plain) = estimate(&mut m, None);
    let (omega, cold) = estimate(&mut m, Some(&memo));
    // keeping it changes nothing about the iteration
    assert_eq!(cold, plain);
    assert!(!cold.recalled && cold.evaluations > 10, "{cold:?}");
    let (again, warm) = estimate(&mut m, Some(&memo));
    assert_eq!(again.to_bits(), omega.to_bits());
    // the forces at rest are zero without an evaluation (`forces_vanish_at`): the probe's
    // alone makes the key
    assert!(warm.recalled && warm.evaluations == 1, "{warm:?}");
    assert_eq!(
        (warm.iterations, warm.last_change),
        (cold.iterations, cold.last_change)
    );
    // the same mesh and material built again, with fracture on: the same operator at rest
    let (disc, _, _) = support::block([0.03, 0.03, 0.02], [3, 3, 2], 1.5);
    let brittle = ChenMaterial {
        fracture: Some(FractureParams {
            s_crit: 0.01,
            alpha: 0.0,
        }),
        ..support::steel()
    };
    let mut b = ChenModel::new(disc, &[brittle]).unwrap();
    let (_, recalled) = estimate(&mut b, Some(&memo));
    assert!(
        recalled.recalled && recalled.omega_max == omega,
        "{recalled:?}"
    );
    // another operator on the same particles (the scalar calibration), or a stiffer steel:
    // new keys, iterated and kept
    let (disc, _, _) = support::block([0.03, 0.03, 0.02], [3, 3, 2], 1.5);
    let stiffer = ChenMaterial::from_young_poisson(200e9 * (1.0 + 1e-9), 0.25, 7800.0).unwrap();
    for mut other in [
        support::scalar_block([3, 3, 2], 1.5),
        ChenModel::new(disc, &[stiffer]).unwrap(),
    ] {
        let (_, miss) = estimate(&mut other, Some(&memo));
        let (_, plain) = estimate(&mut other, None);
        assert_eq!(miss, plain);
    }
    assert_eq!(*memo.stores.borrow(), 3);

    // a memo that offers less than the iteration's own first Ritz value (a damaged or foreign
    // file; a tenth of the true frequency, where the first Ritz value of a random start is
    // about 0.6 of it here) is not believed: the step it implies could be unstable
    struct Low(f64);
    impl EstimateMemo for Low {
        fn recall(&self, _: MemoKey) -> Option<FrequencyEstimate> {
            Some(FrequencyEstimate {
                omega_max: self.0,
                iterations: 1,
                evaluations: 1,
                last_change: 0.0,
                recalled: false,
            })
        }
        fn store(&self, _: MemoKey, _: &FrequencyEstimate) {}
    }
    let (_, low) = estimate(&mut m, Some(&Low(0.1 * omega)));
    assert_eq!(low, plain);
    // one above it is taken as stored (the Ritz values only rise from there)
    let (_, high) = estimate(&mut m, Some(&Low(1.5 * omega)));
    assert!(high.recalled && high.omega_max == 1.5 * omega, "{high:?}");
}

/// Steel on a 6 x 6 x 4 unstructured box (seed 3), horizon 1.45 of the mean edge.
fn unstructured_block() -> ChenModel {
    let (v, t) = unstructured_box_data([0.0; 3], [0.06, 0.06, 0.04], [6, 6, 4], 3).unwrap();
    let (mesh, _) = TetMesh::new(v, t).unwrap();
    let (disc, _) = Discretization::from_tets(
        &mesh.rest_barycentres(),
        &mesh.rest_volumes(),
        mesh.neighbours(),
        1.45 * mesh.mean_edge_length(),
    )
    .unwrap();
    ChenModel::with_options(disc, &[support::steel()], support::SCALAR).unwrap()
}

#[test]
fn lanczos_matches_converged_power_iteration_in_a_fraction_of_the_evaluations() {
    // Both are lower bounds that rise to the largest eigenvalue of M^-1 K; power iteration run
    // to a 1e-12 change is the reference. Measured: Lanczos (the setup's, stopping at a 1e-6
    // change of omega^2) 3.3e-7 low on the lattice block and 2.8e-7 on the unstructured one, in
    // 27 and 21 force evaluations (the forces at rest taken as zero, not evaluated) against the
    // reference's 1,850 and 472. The bound is the
    // stopping tolerance itself; power iteration at its old setting (a 1e-5 change) was 5e-5
    // low on the default wall, and 0.67% low on the jello after its 100 iterations. (Measured
    // on the scalar calibration; with the fitted dilatation the lattice block's Lanczos stops
    // 1.3e-6 low in 20 evaluations: the stopping test bounds the change, not the error.)
    for (name, mut m) in [
        ("lattice", scalar_block([6, 6, 4], 1.45)),
        ("unstructured", unstructured_block()),
    ] {
        let x = m.discretization().rest_positions().to_vec();
        let delta = m.discretization().horizon();
        let reference = max_frequency(&mut m, &x, delta, 5000, 1e-12);
        let (_, est) = stable_frequency(&mut m, &x, delta);
        let rel = est.omega_max / reference.omega_max - 1.0;
        eprintln!(
            "{name}: Lanczos {:.10e} rad/s in {} evaluations, power {:.10e} in {}: {rel:+.2e}",
            est.omega_max, est.evaluations, reference.omega_max, reference.evaluations
        );
        assert!(rel.abs() < 1e-6, "{name}: {rel:e}");
        assert!(4 * est.evaluations < reference.evaluations, "{name}");
        // a looser tolerance stops earlier and lower, never above the reference
        let rough = lanczos_frequency(&mut m, &x, delta, 100, 1e-2);
        assert!(rough.evaluations < est.evaluations, "{name}");
        assert!(rough.omega_max <= est.omega_max * (1.0 + 1e-12), "{name}");
    }
}

#[test]
fn undamped_free_vibration_conserves_energy() {
    // A free bar 0.24 x 0.02 x 0.02 m started in its fundamental axial mode. Velocity Verlet's
    // measured energy oscillates about its conserved shadow energy with relative amplitude
    // ~(omega dt)^2 / 4 per mode: the bar is long enough that omega_1 dt ~ 0.08 at half the limit.
    let (disc, _, _) = support::block([0.24, 0.02, 0.02], [24, 2, 2], 1.5);
    let m = ChenModel::new(disc, &[support::steel()]).unwrap();
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let cfg = ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.5 },
        guard_fraction: 0.5,
    };
    let mut s = Explicit::new(m, &x, delta, Loads::new(x.len()), cfg).unwrap();
    for (v, p) in s.velocities_mut().iter_mut().zip(&x) {
        v[0] = 0.1 * (std::f64::consts::PI * p[0] / 0.24).cos();
    }
    let e0 = total_energy(&mut s);
    let mut worst: f64 = 0.0;
    for step in 0..10_000 {
        s.step().unwrap();
        if step % 50 == 0 {
            worst = worst.max((total_energy(&mut s) - e0).abs() / e0);
        }
    }
    eprintln!("10,000 steps at half the limit: max relative energy error {worst:.3e}");
    // requirement of issue 3: 0.5 %; measured 1.2e-3, bounded (no drift)
    assert!(worst < 5e-3);
}

#[test]
fn spinning_free_block_conserves_angular_momentum() {
    let mut s = solver([3, 3, 2], TimeStep::Auto { safety: 0.5 });
    strain(&mut s, 0.03);
    let y: Vec<Vec3> = s.positions().to_vec();
    let c = [0.015, 0.015, 0.01];
    let omega = [3.0, -20.0, 50.0]; // rad/s: rim speed ~1 m/s, far below the wave speed
    for (v, p) in s.velocities_mut().iter_mut().zip(&y) {
        *v = cross(omega, sub(*p, c));
    }
    let mass = s.model().masses().to_vec();
    let l0 = angular_momentum(&mass, s.positions(), s.velocities());
    for _ in 0..2000 {
        s.step().unwrap();
    }
    let l1 = angular_momentum(&mass, s.positions(), s.velocities());
    let err = norm(sub(l1, l0)) / norm(l0);
    eprintln!("angular momentum after 2000 steps: relative change {err:.3e}");
    // central pair forces equal and opposite bond by bond: velocity Verlet conserves L exactly up
    // to the rounding of ~1e5 additions per particle
    assert!(err < 1e-12);
}

#[test]
fn results_are_bit_identical_for_any_thread_count() {
    // every particle sums its own bonds sequentially, so the thread count cannot change a bit
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut s = solver([6, 5, 5], TimeStep::Auto { safety: 0.8 });
            strain(&mut s, 0.05);
            for _ in 0..50 {
                s.step().unwrap();
            }
            s.positions().to_vec()
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn bad_settings_are_errors_and_nan_is_caught_even_without_the_distance_guard() {
    let m = elastic_block([2, 2, 2], 1.5);
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let n = x.len();
    let cfg = |dt, guard_fraction| ExplicitConfig { dt, guard_fraction };
    for bad in [
        cfg(TimeStep::Fixed(f64::NAN), 0.5),
        cfg(TimeStep::Fixed(-1.0), 0.5),
        cfg(TimeStep::Auto { safety: 0.0 }, 0.5),
        cfg(TimeStep::Fixed(1e-7), f64::NAN),
        cfg(TimeStep::Fixed(1e-7), 0.0),
    ] {
        assert!(Explicit::new(m.clone(), &x, delta, Loads::new(n), bad).is_err());
    }
    assert!(Loads::new(n).with_damping(-1.0).is_err());
    assert!(Loads::new(n).anchor(&[n as u32], [0.0; 3]).is_err());
    assert!(Explicit::new(
        m.clone(),
        &x[1..],
        delta,
        Loads::new(n),
        cfg(TimeStep::Fixed(1e-7), 0.5)
    )
    .is_err());
    // a NaN velocity is reported as an error with the guard disabled
    let mut s = Explicit::new(
        m,
        &x,
        delta,
        Loads::new(n),
        cfg(TimeStep::Fixed(1e-7), f64::INFINITY),
    )
    .unwrap();
    s.velocities_mut()[3][1] = f64::NAN;
    assert!(matches!(
        s.step(),
        Err(PhysicsError::Unstable { particle: 3, .. })
    ));
}

/// A rotating anchor holds its particles on their circles over many steps: the end of a bar
/// turned at 20 rad/s about the bar's axis through a quarter turn.
#[test]
fn rotating_anchor_turns_its_particles_on_exact_circles() {
    use perifrac_physics::AnchorMotion;
    let m = elastic_block([8, 2, 2], 1.5);
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let end: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize][0] < 0.01)
        .collect();
    let motion = AnchorMotion {
        velocity: [0.0; 3],
        angular: [20.0, 0.0, 0.0],
        center: [0.0, 0.01, 0.01],
    };
    let mut loads = Loads::new(x.len());
    loads.anchor_motion(&end, motion).unwrap();
    let cfg = ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.8 },
        guard_fraction: 0.5,
    };
    let mut s = Explicit::new(m, &x, delta, loads, cfg).unwrap();
    let steps = (std::f64::consts::FRAC_PI_2 / 20.0 / s.dt()).ceil() as usize;
    for _ in 0..steps {
        s.step().unwrap();
    }
    let angle = 20.0 * s.time();
    for &i in &end {
        let (r0, y) = (sub(x[i as usize], motion.center), s.positions()[i as usize]);
        let r = sub(y, motion.center);
        // each step composes one exact rotation: rounding grows ~1e-16 per step over a few
        // hundred steps
        let (c, sn) = (angle.cos(), angle.sin());
        let want = [r0[0], c * r0[1] - sn * r0[2], sn * r0[1] + c * r0[2]];
        assert!(
            norm(sub(r, want)) < 1e-13,
            "particle {i}: {r:?} vs {want:?}"
        );
    }
    // the velocity is the rigid one at the end of the step
    let i = end[0] as usize;
    let v = s.velocities()[i];
    let want = cross([20.0, 0.0, 0.0], sub(s.positions()[i], motion.center));
    assert!(
        norm(sub(v, want)) < 1e-12 * norm(want).max(1.0),
        "{v:?} vs {want:?}"
    );
}
