//! Setup checks: validation, overlap detection, ball inside a closed surface, coincident centres.

use perifrac_contact::{
    BallDesc, BallMotion, Colliders, ContactError, ContactParams, GroundDesc, Vec3,
};

fn p() -> ContactParams {
    ContactParams::from_material(1e7, 0.01, 1.0, 0.1, 0.3)
}

fn ground(z: f64) -> GroundDesc {
    GroundDesc {
        point: [0.0, 0.0, z],
        normal: [0.0, 0.0, 1.0],
        params: p(),
    }
}

fn ball(center: Vec3, radius: f64, motion: BallMotion) -> BallDesc {
    BallDesc {
        center,
        radius,
        motion,
        params: p(),
    }
}

const STILL: BallMotion = BallMotion::Kinematic { velocity: [0.0; 3] };

#[test]
fn validation_names_the_collider_and_value() {
    let e = Colliders::new(vec![], vec![ball([0.0; 3], -1.0, STILL)], [0.0; 3]).unwrap_err();
    assert_eq!(e.to_string(), "ball 0: radius must be > 0, got -1");
    let heavy = BallMotion::Dynamic {
        mass: 0.0,
        velocity: [0.0; 3],
    };
    let e = Colliders::new(vec![], vec![ball([0.0, 0.0, 1.0], 0.1, heavy)], [0.0; 3]);
    assert!(
        matches!(e, Err(ContactError::NotPositive { what: "mass", .. })),
        "{e:?}"
    );
    let mut g = ground(0.0);
    g.normal = [0.0; 3];
    let e = Colliders::new(vec![ground(0.0), g], vec![], [0.0; 3]).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("ground 1: normal must be nonzero"),
        "{e}"
    );
    let mut g = ground(0.0);
    g.params.damping_ratio = -0.5;
    let e = Colliders::new(vec![g], vec![], [0.0; 3]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "ground 0: damping_ratio must be >= 0, got -0.5"
    );
    let e = Colliders::new(vec![], vec![], [0.0, f64::NAN, 0.0]).unwrap_err();
    assert!(matches!(e, ContactError::NonFinite { .. }), "{e:?}");
    // A dynamic ball reaching 0.12 m into the ground (its centre 0.02 m below it).
    let sunk = BallMotion::Dynamic {
        mass: 1.0,
        velocity: [0.0; 3],
    };
    let e = Colliders::new(
        vec![ground(0.0)],
        vec![ball([0.0, 0.0, -0.02], 0.1, sunk)],
        [0.0; 3],
    )
    .unwrap_err();
    assert_eq!(
        e,
        ContactError::BallInGround {
            ball: "ball 0".into(),
            ground: "ground 0".into(),
            depth: 0.12000000000000001
        }
    );
    // Touching the ground is fine.
    Colliders::new(
        vec![ground(0.0)],
        vec![ball([0.0, 0.0, 0.1], 0.1, sunk)],
        [0.0; 3],
    )
    .unwrap();
}

#[test]
fn ground_normal_is_normalised_and_state_is_reported() {
    let mut g = ground(1.0);
    g.normal = [0.0, 3.0, 4.0];
    let col = Colliders::new(vec![g], vec![ball([0.0, 5.0, 5.0], 0.5, STILL)], [0.0; 3]).unwrap();
    let gs: Vec<_> = col.grounds().collect();
    assert_eq!(gs[0].normal, [0.0, 0.6, 0.8]);
    assert_eq!(gs[0].point, [0.0, 0.0, 1.0]);
    let b = col.ball(0);
    assert_eq!((b.center, b.radius, b.mass), ([0.0, 5.0, 5.0], 0.5, None));
    assert!(!col.is_empty());
    assert!(Colliders::new(vec![], vec![], [0.0; 3]).unwrap().is_empty());
}

#[test]
fn check_clear_catches_contact_spheres_inside() {
    let col = Colliders::new(
        vec![ground(0.0), ground(-1.0)],
        vec![ball([0.0, 0.0, 1.0], 0.5, STILL)],
        [0.0; 3],
    )
    .unwrap();
    let r = [0.1; 3];
    // Touching the surfaces (sphere tangent to the plane / to the ball) is allowed.
    col.check_clear(&[[0.0, 0.0, 0.1], [0.0, 0.0, 1.6], [3.0, 0.0, 0.2]], &r)
        .unwrap();
    let e = col
        .check_clear(&[[3.0, 0.0, 0.2], [0.1, 0.0, 1.0], [0.0, 0.0, -0.25]], &r)
        .unwrap_err();
    // Particle 1: its centre 0.4 m inside the ball, its sphere 0.1 m further.
    assert_eq!(
        e,
        ContactError::Overlap {
            collider: "ball 0".into(),
            particle: 1,
            depth: 0.5
        }
    );
    assert_eq!(
        e.to_string(),
        "particle 1 starts 5.000e-1 m inside ball 0 (its contact sphere); move them at least \
         that far apart"
    );
    // A sphere whose centre is above the ground but which reaches 0.05 m below it.
    let e = col
        .check_clear(&[[3.0, 0.0, 0.2], [0.0, 0.0, 0.05]], &r[..2])
        .unwrap_err();
    assert_eq!(
        e,
        ContactError::Overlap {
            collider: "ground 0".into(),
            particle: 1,
            depth: 0.05
        }
    );
    // Issue 17: the deepest overlap is reported, not the lowest index (particle 0 reaches
    // 1 mm below the ground, particle 1 sits 3 cm inside the ball).
    let e = col
        .check_clear(
            &[[3.0, 0.0, 0.099], [0.0, 0.0, 0.53], [0.0, 0.0, 0.099]],
            &r,
        )
        .unwrap_err();
    match e {
        ContactError::Overlap {
            collider,
            particle,
            depth,
        } => {
            assert_eq!((collider.as_str(), particle), ("ball 0", 1));
            // Centre 0.03 m inside the ball's surface, plus the 0.1 m contact radius.
            assert!((depth - 0.13).abs() < 1e-12, "{depth}");
        }
        other => panic!("{other:?}"),
    }
    // Equal depths: the lowest particle index.
    let e = col
        .check_clear(&[[3.0, 0.0, 0.2], [5.0, 0.0, 0.05], [4.0, 0.0, 0.05]], &r)
        .unwrap_err();
    assert!(
        matches!(e, ContactError::Overlap { particle: 1, .. }),
        "{e:?}"
    );
    // The exact ball centre (where parry's projection is undefined) is caught too.
    let e = col.check_clear(&[[0.0, 0.0, 1.0]], &[0.0]).unwrap_err();
    assert!(
        matches!(e, ContactError::Overlap { depth, .. } if depth == 0.5),
        "{e:?}"
    );
}

#[test]
fn coincident_centre_gives_a_finite_force_along_z() {
    let mut col =
        Colliders::new(vec![], vec![ball([1.0, 2.0, 3.0], 0.1, STILL)], [0.0; 3]).unwrap();
    let mut f = vec![[0.0; 3]];
    let stats = col.step(
        1e-5,
        &[[1.0, 2.0, 3.0]],
        &[[0.5, 0.0, 0.0]],
        &[1e-3],
        &[0.01],
        &mut f,
    );
    assert_eq!(stats.contacts, 1);
    assert_eq!(stats.max_penetration, 0.11);
    assert!(f[0].iter().all(|x| x.is_finite()), "{f:?}");
    // Normal along +z: k d = 1e5 * 0.11 minus damping of zero normal velocity.
    assert!((f[0][2] - 1e5 * 0.11).abs() < 1e-6, "{f:?}");
    // Friction against the +x sliding, capped by m |v_t| / dt = 1e-3 * 0.5 / 1e-5 = 50 N.
    assert!((f[0][0] + 50.0).abs() < 1e-9, "{f:?}");
    assert_eq!(col.ball(0).reaction, [-f[0][0], -f[0][1], -f[0][2]]);
}

/// Unit cube [0, 1]^3, triangles counter-clockwise seen from outside.
fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v: Vec<Vec3> = (0..8)
        .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
        .collect();
    let quads = [
        [0, 2, 3, 1], // z = 0, normal -z
        [4, 5, 7, 6], // z = 1, +z
        [0, 1, 5, 4], // y = 0, -y
        [2, 6, 7, 3], // y = 1, +y
        [0, 4, 6, 2], // x = 0, -x
        [1, 3, 7, 5], // x = 1, +x
    ];
    let t = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    (v, t)
}

#[test]
fn balls_inside_a_closed_cube_surface() {
    let (v, t) = cube();
    let balls = vec![
        ball([0.5, 0.5, 0.5], 0.1, STILL),    // inside, centre
        ball([1.5, 0.5, 0.5], 0.1, STILL),    // outside, beside a face
        ball([0.99, 0.01, 0.5], 2.0, STILL),  // inside, near an edge (radius does not matter)
        ball([1.01, 1.01, 1.01], 0.1, STILL), // outside, beyond a corner
        ball([0.5, 0.5, -0.01], 0.1, STILL),  // just below the bottom face
    ];
    let col = Colliders::new(vec![], balls, [0.0; 3]).unwrap();
    assert_eq!(col.balls_inside_surface(&v, &t).unwrap(), vec![0, 2]);
    let e = col.balls_inside_surface(&v, &[[0, 1, 8]]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "surface: triangle 0 uses vertex 8, but there are only 8 vertices"
    );
    assert!(col.balls_inside_surface(&v, &[]).is_err());
}

/// `penetration` is the deepest overlap of a sphere with any collider, `push_out` moves the
/// sphere along each collider's normal until it overlaps by no more than the depth allowed,
/// and the stiffnesses sum over every collider.
#[test]
fn penetration_push_out_and_stiffness_sum() {
    let c = Colliders::new(
        vec![ground(0.0)],
        vec![ball([0.0, 0.0, 2.0], 1.0, STILL)],
        [0.0; 3],
    )
    .unwrap();
    // 0.05 above the ground with radius 0.1: 0.05 into it, clear of the ball.
    let low = [0.3, 0.0, 0.05];
    assert!((c.penetration(low, 0.1) - 0.05).abs() < 1e-15);
    let out = c.push_out(low, 0.1, 0.0);
    assert!((out[2] - 0.1).abs() < 1e-15 && out[0] == 0.3, "{out:?}");
    assert!(c.penetration(out, 0.1).abs() < 1e-15);
    // Half a radius inside the ball, along x from its centre: 0.6 deep; allowed 0.2.
    let inside = [0.5, 0.0, 2.0];
    assert!((c.penetration(inside, 0.1) - 0.6).abs() < 1e-15);
    let out = c.push_out(inside, 0.1, 0.2);
    assert!((out[0] - 0.9).abs() < 1e-15 && out[2] == 2.0, "{out:?}");
    assert!((c.penetration(out, 0.1) - 0.2).abs() < 1e-15);
    // Within the allowance nothing moves; clear points stay.
    assert_eq!(c.push_out(inside, 0.1, 0.7), inside);
    assert_eq!(c.push_out([5.0, 5.0, 5.0], 0.1, 0.0), [5.0, 5.0, 5.0]);
    assert_eq!(c.penetration([5.0, 5.0, 5.0], 0.1), 0.0);
    assert!((c.stiffness_sum() - 2.0 * p().stiffness).abs() <= 1e-9 * p().stiffness);
}
