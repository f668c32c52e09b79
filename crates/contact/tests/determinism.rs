//! Same inputs, 1 thread vs 2 threads: bit-identical forces and ball states.

use perifrac_contact::{BallDesc, BallMotion, Colliders, ContactParams, GroundDesc, Vec3};

fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn run(threads: usize) -> (Vec<Vec3>, Vec<perifrac_contact::BallState>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let p = ContactParams::from_material(1e7, 0.01, 1.0, 0.3, 0.4);
        let grounds = vec![
            GroundDesc {
                point: [0.0; 3],
                normal: [0.0, 0.0, 1.0],
                params: p,
            },
            GroundDesc {
                point: [0.5, 0.0, 0.0],
                normal: [-1.0, 0.0, 0.2],
                params: p,
            },
        ];
        let balls = vec![
            BallDesc {
                center: [0.2, 0.2, 0.1],
                radius: 0.1,
                motion: BallMotion::Dynamic {
                    mass: 2.0,
                    velocity: [0.1, 0.0, -0.5],
                },
                params: p,
            },
            BallDesc {
                center: [0.3, 0.4, 0.15],
                radius: 0.08,
                motion: BallMotion::Kinematic {
                    velocity: [0.0, -0.3, 0.0],
                },
                params: p,
            },
        ];
        let mut col = Colliders::new(grounds, balls, [0.0, 0.0, -9.81]).unwrap();
        // 20k particles (10 chunks) in a 0.5 m box above the ground, many touching colliders.
        let n = 20_000;
        let mut s = 7u64;
        let y: Vec<Vec3> = (0..n)
            .map(|_| [0.5 * lcg(&mut s), 0.5 * lcg(&mut s), 0.3 * lcg(&mut s)])
            .collect();
        let v: Vec<Vec3> = (0..n)
            .map(|_| [lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5])
            .collect();
        let m: Vec<f64> = (0..n).map(|_| 1e-3 * (0.5 + lcg(&mut s))).collect();
        let r = vec![0.01; n];
        let mut f = vec![[0.0; 3]; n];
        let mut contacts = 0;
        for _ in 0..5 {
            f.iter_mut().for_each(|fi| *fi = [0.0; 3]);
            contacts += col.step(1e-5, &y, &v, &m, &r, &mut f).contacts;
        }
        assert!(contacts > 1000, "{contacts}");
        (f, col.balls().collect())
    })
}

#[test]
fn one_and_two_threads_agree_bit_for_bit() {
    let (f1, b1) = run(1);
    let (f2, b2) = run(2);
    let bits = |f: &[Vec3]| {
        f.iter()
            .flat_map(|x| x.map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    assert!(bits(&f1) == bits(&f2), "forces differ");
    for (a, b) in b1.iter().zip(&b2) {
        assert_eq!(a.center.map(f64::to_bits), b.center.map(f64::to_bits));
        assert_eq!(a.velocity.map(f64::to_bits), b.velocity.map(f64::to_bits));
        assert_eq!(a.reaction.map(f64::to_bits), b.reaction.map(f64::to_bits));
    }
    assert!(
        b1[0].reaction.iter().any(|&x| x != 0.0),
        "the dynamic ball must be touched"
    );
}
