//! A kinematic ball moving through a row of particles pushes them along its velocity.

mod common;
use common::*;
use perifrac_contact::{BallDesc, BallMotion, Colliders};

#[test]
fn kinematic_ball_pushes_a_row_of_particles() {
    let u = 1.0; // ball speed (m/s), along +x
    let ball = BallDesc {
        center: [-0.1, 0.0, 0.0],
        radius: 0.05,
        motion: BallMotion::Kinematic {
            velocity: [u, 0.0, 0.0],
        },
        params: params(0.0, 0.0),
    };
    let mut col = Colliders::new(vec![], vec![ball], [0.0, 0.0, -9.81]).unwrap();
    // Five particles on the ball's path, slightly off its axis (so the impacts are oblique),
    // spaced 5 cm; no gravity on them (a row in space).
    let n = 5;
    let y: Vec<_> = (0..n)
        .map(|i| [0.05 * i as f64, 0.004 * i as f64, 0.0])
        .collect();
    let mut w = World::new(y, vec![[0.0; 3]; n], vec![M; n], vec![R; n], [0.0; 3]);
    col.check_clear(&w.y, &vec![R; n]).unwrap();
    let mut reaction_x = 0.0;
    // 0.6 s: the ball travels 0.6 m, past the whole row (0.2 m long) and then some.
    let steps = 60_000;
    for _ in 0..steps {
        w.step(&mut col, DT);
        reaction_x += col.ball(0).reaction[0] * DT;
    }
    let b = col.ball(0);
    // Kinematic: the particles do not slow it down.
    assert_eq!(b.velocity, [u, 0.0, 0.0]);
    assert!(
        (b.center[0] - (-0.1 + 0.6 * u)).abs() < 1e-12,
        "{:?}",
        b.center
    );
    let p = w.momentum();
    println!("particle momentum {p:?}, velocities {:?}", w.v);
    for (i, v) in w.v.iter().enumerate() {
        // Each particle was hit and moves forward, at most at 2u (elastic rebound off a wall
        // moving at u); measured 2.0012u head-on (the penalty onset's O(dt) error, 6e-4),
        // 1.86u..1.99u for the oblique hits. Bound 2u (1 + 2e-3).
        assert!(
            v[0] > 0.5 * u && v[0] <= 2.0 * u * (1.0 + 2e-3),
            "particle {i}: {v:?}"
        );
    }
    assert!(p[0] > 0.0 && p[1].abs() < p[0] && p[2] == 0.0, "{p:?}");
    // The impulse the ball took is minus what the particles got (time-integrated reaction,
    // with the trapezoid of the kicks); all contacts are over, so it matches to rounding:
    // measured relative mismatch 0 (the same products summed); bound 1e-12.
    println!("impulse mismatch {:e}", (reaction_x + p[0]).abs() / p[0]);
    assert!(
        (reaction_x + p[0]).abs() < 1e-12 * p[0],
        "{reaction_x} vs {}",
        p[0]
    );
}
