//! Dynamic balls: momentum exchange with particles, Newton's third law, resting on a particle
//! layer and on the ground.

mod common;
use common::*;
use perifrac_contact::{BallDesc, BallMotion, Colliders, GroundDesc, Vec3};

fn dynamic_ball(center: Vec3, radius: f64, mass: f64, velocity: Vec3, p: (f64, f64)) -> BallDesc {
    BallDesc {
        center,
        radius,
        motion: BallMotion::Dynamic { mass, velocity },
        params: params(p.0, p.1),
    }
}

fn total_momentum(w: &World, col: &Colliders) -> Vec3 {
    let mut p = w.momentum();
    let b = col.ball(0);
    for (a, pa) in p.iter_mut().enumerate() {
        *pa += b.mass.unwrap() * b.velocity[a];
    }
    p
}

#[test]
fn particle_ball_collision_conserves_momentum() {
    // A 10 g ball moving +x at 2 m/s hits three 1 g particles off-axis, with damping and
    // friction (all force terms active); no ground, no gravity.
    let ball = dynamic_ball([-0.1, 0.0, 0.0], 0.03, 0.01, [2.0, 0.0, 0.0], (0.3, 0.4));
    let mut col = Colliders::new(vec![], vec![ball], [0.0; 3]).unwrap();
    let y = vec![[0.0, 0.01, 0.005], [0.05, -0.02, 0.0], [0.06, 0.0, 0.03]];
    let v = vec![[0.0, 0.5, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
    let mut w = World::new(y, v, vec![M; 3], vec![R; 3], [0.0; 3]);
    let p0 = total_momentum(&w, &col);
    let scale = 0.01 * 2.0;
    let mut worst: f64 = 0.0;
    let mut contacts = 0;
    for _ in 0..20_000 {
        contacts += w.step(&mut col, DT).contacts;
        let p = total_momentum(&w, &col);
        for a in 0..3 {
            worst = worst.max((p[a] - p0[a]).abs() / scale);
        }
    }
    println!("contacts {contacts}, worst momentum drift {worst:e} of the initial |p|");
    // Measured 93 pair-steps in contact (three hits of ~30 steps: pi / omega / dt = 31).
    assert!(contacts > 30, "the ball must hit something: {contacts}");
    // The ball lost speed to the particles.
    assert!(col.ball(0).velocity[0] < 1.9, "{:?}", col.ball(0).velocity);
    // Equal and opposite kicks: drift is rounding only. Measured 5.2e-16; bound 1e-13.
    assert!(worst < 1e-13, "{worst:e}");
}

#[test]
fn reaction_is_minus_the_sum_of_particle_forces() {
    // One step on a cluster pressed into a ball at rest, forces starting at zero.
    let ball = dynamic_ball([0.0; 3], 0.05, 1.0, [0.0; 3], (0.2, 0.5));
    let mut col = Colliders::new(vec![], vec![ball], [0.0; 3]).unwrap();
    let n = 200;
    let y: Vec<Vec3> = (0..n)
        .map(|i| {
            let t = i as f64 * 0.7;
            let z = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let rad = 0.055 + 0.001 * (i % 7) as f64;
            [rad * s * t.cos(), rad * s * t.sin(), rad * z]
        })
        .collect();
    let v: Vec<Vec3> = (0..n).map(|i| [0.1 * (i % 3) as f64, -0.2, 0.05]).collect();
    let mut f = vec![[0.0; 3]; n];
    let stats = col.step(DT, &y, &v, &vec![M; n], &vec![R; n], &mut f);
    assert!(stats.contacts > 50, "{stats:?}");
    let reaction = col.ball(0).reaction;
    let mut sum = [0.0; 3];
    for fi in &f {
        for a in 0..3 {
            sum[a] += fi[a];
        }
    }
    let mag = f
        .iter()
        .map(|fi| fi.iter().map(|x| x.abs()).sum::<f64>())
        .sum::<f64>();
    for a in 0..3 {
        // Only the summation order differs (per-chunk partials vs this loop): bound 1e-14 of the
        // summed magnitudes, about 50 roundings of 2e-16.
        assert!(
            (sum[a] + reaction[a]).abs() <= 1e-14 * mag,
            "{sum:?} vs {reaction:?}"
        );
    }
}

#[test]
fn heavy_ball_rests_on_a_particle_layer_on_the_ground() {
    // 4 x 4 particles (r = 1 cm, 1 g, spacing 2r) resting on the ground, a 1 kg ball of radius
    // 5 cm placed touching the central four; gravity on everything.
    let ground = GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params: params(0.5, 0.5),
    };
    let k = params(0.0, 0.0).stiffness;
    let mut y = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            y.push([
                (2 * i) as f64 * R - 3.0 * R,
                (2 * j) as f64 * R - 3.0 * R,
                R - M * 9.81 / k,
            ]);
        }
    }
    let n = y.len();
    // Touching the four particles at (+-r, +-r): |c - p| = R_b + r.
    let rb = 0.05;
    let cz = R + ((rb + R).powi(2) - 2.0 * R * R).sqrt();
    let big_m = 1.0;
    let ball = dynamic_ball([0.0, 0.0, cz], rb, big_m, [0.0; 3], (0.5, 0.5));
    let mut col = Colliders::new(vec![ground], vec![ball], G).unwrap();
    // Centres only: the particles rest on the ground with their static sag M g / k.
    col.check_clear(&y, &vec![0.0; n]).unwrap();
    let mut w = World::new(y, vec![[0.0; 3]; n], vec![M; n], vec![R; n], G);
    let steps = 50_000; // 0.5 s
    let window = 20_000; // average the reaction over the last 0.2 s
    let mut mean = [0.0; 3];
    let mut max_pen: f64 = 0.0;
    for s in 0..steps {
        let st = w.step(&mut col, DT);
        max_pen = max_pen.max(st.max_penetration);
        if s >= steps - window {
            let r = col.ball(0).reaction;
            for a in 0..3 {
                mean[a] += r[a] / window as f64;
            }
        }
    }
    let weight = big_m * 9.81;
    let b = col.ball(0);
    println!(
        "mean reaction {mean:?} (weight {weight}), last {:?}, ball {:?}, max penetration {max_pen:e}",
        b.reaction, b
    );
    // Equilibrium: the particles carry the weight. Measured mean 9.80998 N for 9.81 N (1.6e-6
    // relative; the ball still sinks slowly, 0.9 mm/s, as the squeezed particles creep
    // outwards under the velocity-capped friction); bound 1e-3. Horizontal mean measured
    // 5.5e-5 N (the instantaneous value rattles by a few N): bound 1e-3 of the weight.
    assert!((mean[2] - weight).abs() < 1e-3 * weight, "{mean:?}");
    assert!(
        mean[0].abs() < 1e-3 * weight && mean[1].abs() < 1e-3 * weight,
        "{mean:?}"
    );
    // The ball stays up: measured sink 4.4e-4 m in 0.5 s (compression 4.6e-5 m plus the
    // creep); bound R / 10 = 1e-3 m. Speed measured 8.7e-4 m/s; bound 5e-3.
    assert!(b.center[2] > cz - 0.1 * R, "{:?}", b.center);
    assert!(
        b.velocity.iter().all(|x| x.abs() < 5e-3),
        "{:?}",
        b.velocity
    );
    // Every particle is still on the ground and below the ball.
    assert!(w.y.iter().all(|p| p[2] > 0.0 && p[2] < R), "{:?}", w.y);
}

#[test]
fn heavy_ball_rests_on_the_ground_with_small_sag() {
    // A 10 kg ball on the ground; one 1 g particle elsewhere sets the reference mass, so the
    // ball-ground spring has the particle's contact frequency (stable at DT) and the sag is
    // m_ref g / k_g = 1e-3 * 9.81 / 1e5 = 9.81e-8 m.
    let ground = GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params: params(0.5, 0.5),
    };
    let rb = 0.1;
    let ball = dynamic_ball([0.0, 0.0, rb + 1e-3], rb, 10.0, [0.3, 0.0, 0.0], (0.5, 0.5));
    let mut col = Colliders::new(vec![ground], vec![ball], G).unwrap();
    let mut w = World::new(
        vec![[1.0, 0.0, 0.5]],
        vec![[0.0; 3]],
        vec![M],
        vec![R],
        [0.0; 3],
    );
    for _ in 0..100_000 {
        w.step(&mut col, DT);
    }
    let k_bg = col.ball_ground_stiffness(0, 0).unwrap();
    assert_eq!(k_bg, 1e5 * 10.0 / M);
    let sag = rb - col.ball(0).center[2];
    let expect = M * 9.81 / 1e5;
    let b = col.ball(0);
    println!("sag {sag:e} (expect {expect:e}), ball {b:?}");
    // Dropped from 1 mm, bounced and settled: measured sag within 4e-10 relative; bound 1e-6.
    assert!((sag - expect).abs() < 1e-6 * expect, "{sag:e}");
    // The ground carries the weight, and friction stopped the sliding (it never reverses).
    // Measured 98.1 N to rounding; bound 1e-9 relative. Speed after sliding 9.7 mm: 0.
    assert!((b.ground_force[2] - 98.1).abs() < 1e-9 * 98.1, "{b:?}");
    assert!(b.velocity[0] == 0.0 && b.center[0] > 0.0, "{b:?}");
}
