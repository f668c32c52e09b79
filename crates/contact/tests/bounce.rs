//! Drops onto a ground plane: no energy gain, no rebound above the drop height, damping lowers it.

mod common;
use common::*;
use perifrac_contact::{Colliders, GroundDesc};

const H: f64 = 0.1;

fn ground(damping: f64, friction: f64) -> Colliders {
    let g = GroundDesc {
        point: [0.0, 0.0, 0.0],
        normal: [0.0, 0.0, 2.0], // not unit on purpose: new() normalises
        params: params(damping, friction),
    };
    Colliders::new(vec![g], vec![], G).unwrap()
}

struct Drop {
    /// Highest drop height above first touch, over the particles (m).
    rebound: f64,
    /// Largest (E - E0) / E0 over the run.
    max_gain: f64,
    contacts: usize,
}

/// Particles dropped from `H` above touching (centre at `R + H`), with horizontal speeds `vx`;
/// returns the highest rebound (over particles, after the first contact) above touching.
fn drop(damping: f64, friction: f64, vx: &[f64]) -> Drop {
    let n = vx.len();
    let mut col = ground(damping, friction);
    let mut w = World::new(
        (0..n).map(|i| [0.1 * i as f64, 0.0, R + H]).collect(),
        vx.iter().map(|&u| [u, 0.0, 0.0]).collect(),
        vec![M; n],
        vec![R; n],
        G,
    );
    let e0 = w.energy(&col);
    let mut touched = vec![false; n];
    let mut rebound: f64 = 0.0;
    let mut max_gain = f64::NEG_INFINITY;
    let mut contacts = 0;
    // Fall 0.143 s, contact 0.3 ms, rise 0.143 s: 0.3 s covers one full bounce.
    for _ in 0..(0.3 / DT) as usize {
        contacts += w.step(&mut col, DT).contacts;
        for (t, y) in touched.iter_mut().zip(&w.y) {
            if y[2] < R {
                *t = true;
            } else if *t {
                rebound = rebound.max(y[2] - R);
            }
        }
        max_gain = max_gain.max((w.energy(&col) - e0) / e0);
    }
    assert!(
        touched.iter().all(|&t| t),
        "every particle must hit the ground"
    );
    Drop {
        rebound,
        max_gain,
        contacts,
    }
}

// Measured (omega dt = 0.1): the undamped, frictionless drop rebounds to 0.99884 H (the O(dt)
// error of the penalty onset between steps, v dt = 1.4e-5 m per crossing, loses a little); the
// largest energy excursion above E0 is 4.3e-5 E0 (one particle) and 2.0e-5 (four), inside the
// contact: velocity Verlet's shadow-energy wobble on the stiff spring, bounded a priori by
// (omega dt)^2 / 8 = 1.25e-3. Bounds: the rebound may not exceed H by more than 1e-4 H (one
// onset error) and the energy gain is held to 2e-4, about 4x the measured worst case.
const HEIGHT_TOL: f64 = 1e-4;
const ENERGY_TOL: f64 = 2e-4;

#[test]
fn elastic_drop_does_not_gain_energy() {
    let d = drop(0.0, 0.0, &[0.0]);
    println!(
        "elastic: rebound/H = {}, max gain = {:e}",
        d.rebound / H,
        d.max_gain
    );
    assert!(d.contacts > 0);
    assert!(d.rebound <= H * (1.0 + HEIGHT_TOL), "{}", d.rebound);
    // It does bounce back (elastic): nearly all the way.
    assert!(d.rebound > 0.99 * H, "{}", d.rebound);
    assert!(d.max_gain <= ENERGY_TOL, "{}", d.max_gain);
}

#[test]
fn damping_lowers_the_rebound() {
    let elastic = drop(0.0, 0.0, &[0.0]);
    let damped = drop(0.2, 0.0, &[0.0]);
    println!("damped 0.2: rebound/H = {}", damped.rebound / H);
    // A linear spring-dashpot with zeta = 0.2 has restitution exp(-zeta pi / sqrt(1 - zeta^2))
    // = 0.526 (height 0.28 H); the no-attraction clamp ends the contact earlier and keeps more:
    // measured 0.3245 H. Bounds 0.25..0.40 H.
    assert!(damped.rebound < elastic.rebound);
    assert!(
        damped.rebound < 0.40 * H && damped.rebound > 0.25 * H,
        "{}",
        damped.rebound
    );
    assert!(damped.max_gain <= ENERGY_TOL, "{}", damped.max_gain);
}

#[test]
fn several_particles_with_friction_and_sliding_do_not_gain_energy() {
    for (damping, friction) in [(0.0, 0.5), (0.3, 0.5), (0.0, 0.0)] {
        let d = drop(damping, friction, &[0.0, 0.5, -1.0, 3.0]);
        println!(
            "zeta {damping} mu {friction}: rebound/H = {}, max gain = {:e}",
            d.rebound / H,
            d.max_gain
        );
        assert!(d.rebound <= H * (1.0 + HEIGHT_TOL), "{}", d.rebound);
        assert!(d.max_gain <= ENERGY_TOL, "{}", d.max_gain);
    }
}
