//! The event search (docs/model.md section 6): with no levels it is the plain explicit step bit for
//! bit; with levels, its sub-steps add up to the outer step exactly, rejected trials are
//! counted, and on a bar pulled apart the bonds it breaks are less far past their threshold
//! than the plain step's. That an undone trial leaves nothing behind rests on the snapshot
//! being the checkpoint's save and restore, which `tests/resume.rs` shows complete.

mod support;

use perifrac_physics::{
    ChenModel, EventSearchConfig, Explicit, ExplicitConfig, ForceModel, FractureParams, Loads,
    Searched, Solver, TimeStep,
};
use support::{block, steel};

const L: f64 = 0.2;

fn bar() -> (ChenModel, Vec<[f64; 3]>, f64) {
    let (disc, _, _) = block([L, 0.02, 0.02], [20, 2, 2], 1.5);
    let x = disc.rest_positions().to_vec();
    let delta = disc.horizon();
    let mut glass = steel();
    glass.fracture = Some(FractureParams {
        s_crit: 2e-3,
        alpha: 0.0,
    });
    (ChenModel::new(disc, &[glass]).unwrap(), x, delta)
}

fn config() -> ExplicitConfig {
    ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.8 },
        guard_fraction: 0.5,
    }
}

/// The halves of the bar moving apart at 30 m/s each: a strain of about 6e-3 arrives at the
/// middle, three times `s_crit`.
fn pull(sim: &mut dyn Solver, x: &[[f64; 3]]) {
    for (v, p) in sim.velocities_mut().iter_mut().zip(x) {
        v[0] = if p[0] < 0.5 * L { -30.0 } else { 30.0 };
    }
}

fn searched(search: EventSearchConfig) -> (Searched<ChenModel>, Vec<[f64; 3]>) {
    let (m, x, delta) = bar();
    let n = x.len();
    let sim = Searched::new(m, &x, delta, Loads::new(n), config(), search).unwrap();
    (sim, x)
}

fn plain() -> (Explicit<ChenModel>, Vec<[f64; 3]>) {
    let (m, x, delta) = bar();
    let n = x.len();
    (
        Explicit::new(m, &x, delta, Loads::new(n), config()).unwrap(),
        x,
    )
}

#[test]
fn with_no_levels_the_search_is_the_plain_step() {
    let (mut a, x) = searched(EventSearchConfig {
        levels: 0,
        ..EventSearchConfig::default()
    });
    let (mut b, _) = plain();
    pull(&mut a, &x);
    pull(&mut b, &x);
    for _ in 0..60 {
        let ka = Solver::step(&mut a, &mut perifrac_physics::NoEnvironment)
            .unwrap()
            .to_vec();
        let kb = Solver::step(&mut b, &mut perifrac_physics::NoEnvironment)
            .unwrap()
            .to_vec();
        assert_eq!(ka, kb);
    }
    assert_eq!(a.positions(), b.positions());
    assert_eq!(a.velocities(), b.velocities());
    assert_eq!(a.time().to_bits(), b.time().to_bits());
    assert_eq!(Solver::stats(&a).rejected, 0);
}

#[test]
fn sub_steps_add_up_to_the_step_and_breaking_is_seen_sooner() {
    let (mut a, x) = searched(EventSearchConfig::default());
    let (mut b, _) = plain();
    pull(&mut a, &x);
    pull(&mut b, &x);
    let steps = 60;
    let (mut worst_a, mut worst_b) = (0.0f64, 0.0f64);
    let (mut broken_a, mut broken_b) = (0, 0);
    for _ in 0..steps {
        broken_a += Solver::step(&mut a, &mut perifrac_physics::NoEnvironment)
            .unwrap()
            .len();
        worst_a = worst_a.max(a.model().break_overshoot());
        broken_b += Solver::step(&mut b, &mut perifrac_physics::NoEnvironment)
            .unwrap()
            .len();
        worst_b = worst_b.max(b.model().break_overshoot());
    }
    // the outer clock is the plain step's, to the bit
    assert_eq!(a.time().to_bits(), b.time().to_bits());
    assert_eq!(a.steps(), steps);
    let s = Solver::stats(&a);
    assert!(s.substeps > steps && s.rejected > 0, "{s:?}");
    assert!(broken_a > 0 && broken_b > 0, "the bar breaks in both");
    // the search refines until a breaking bond is at most 10% past its threshold, or the
    // finest level is reached; the plain step lets bonds run further past
    assert!(
        worst_a < worst_b,
        "overshoot {worst_a} with the search, {worst_b} without"
    );
}

#[test]
fn settings_out_of_range_are_refused() {
    let (m, x, delta) = bar();
    let n = x.len();
    for bad in [
        EventSearchConfig {
            levels: 21,
            ..Default::default()
        },
        EventSearchConfig {
            force_growth: 1.0,
            ..Default::default()
        },
        EventSearchConfig {
            force_growth: f64::NAN,
            ..Default::default()
        },
        EventSearchConfig {
            overshoot: -0.1,
            ..Default::default()
        },
        EventSearchConfig {
            force_floor: 1.0,
            ..Default::default()
        },
    ] {
        let r = Searched::new(m.clone(), &x, delta, Loads::new(n), config(), bad);
        assert!(r.is_err(), "{bad:?} accepted");
    }
}
