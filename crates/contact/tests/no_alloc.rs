//! `step`, the implicit-step methods and contact between particles (its force pass, its
//! energy, and a rebuild of its pair list) allocate nothing once their buffers fit the
//! particles and pairs. One test: the counting allocator sees every thread of the binary.

use perifrac_contact::{
    BallDesc, BallMotion, Colliders, ContactParams, GroundDesc, SelfContact, SelfContactParams,
    Vec3,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static A: Counting = Counting;

#[test]
fn steps_after_the_first_do_not_allocate() {
    explicit_steps();
    implicit_steps();
    self_contact_steps();
}

fn self_contact_steps() {
    // A 20 x 20 x 20 lattice of spacing 1 cm, every other particle bonded to its neighbours,
    // squeezed so neighbours overlap.
    let side = 20;
    let h = 0.01;
    let rest: Vec<Vec3> = (0..side * side * side)
        .map(|i| {
            let (x, y, z) = (i % side, (i / side) % side, i / (side * side));
            [x as f64 * h, y as f64 * h, z as f64 * h]
        })
        .collect();
    let n = rest.len();
    let mut sc = SelfContact::new(
        rest.clone(),
        vec![0.5 * h; n],
        vec![1e4; n],
        SelfContactParams::default(),
    )
    .unwrap();
    let x: Vec<Vec3> = rest.iter().map(|p| p.map(|c| 0.8 * c)).collect();
    let v = vec![[0.01, 0.0, -0.02]; n];
    let m = vec![1e-3; n];
    let mut f = vec![[0.0; 3]; n];
    let mut grad = vec![[0.0; 3]; n];
    let bonded = |i: u32, j: u32| (i + j).is_multiple_of(2);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let allocs = pool.install(|| {
        // Warm-up: the first build sizes the buffers.
        sc.prepare(&x, &v, 1e-5, &bonded);
        let before = ALLOCS.load(Ordering::Relaxed);
        let mut pairs = 0;
        for _ in 0..3 {
            sc.invalidate();
            assert!(sc.prepare(&x, &v, 1e-5, &bonded));
            pairs += sc.add_forces(1e-5, &x, &v, &m, &mut f).pairs;
            assert!(sc.potential(&x, Some(&mut grad)) > 0.0);
            sc.unbond(&[(0, 2), (1, 3)]);
        }
        assert!(pairs > 0);
        ALLOCS.load(Ordering::Relaxed) - before
    });
    assert_eq!(sc.rebuilds(), 4);
    assert_eq!(allocs, 0);
}

fn explicit_steps() {
    let p = ContactParams::from_material(1e7, 0.01, 1.0, 0.3, 0.4);
    let grounds = vec![GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params: p,
    }];
    let balls = vec![BallDesc {
        center: [0.0, 0.0, 0.1],
        radius: 0.1,
        motion: BallMotion::Dynamic {
            mass: 1.0,
            velocity: [0.0; 3],
        },
        params: p,
    }];
    let mut col = Colliders::new(grounds, balls, [0.0, 0.0, -9.81]).unwrap();
    let n = 10_000;
    let y: Vec<Vec3> = (0..n)
        .map(|i| [1e-5 * i as f64, 0.0, 0.005 + 1e-6 * i as f64])
        .collect();
    let v = vec![[0.1, 0.0, -0.1]; n];
    let m = vec![1e-3; n];
    let r = vec![0.01; n];
    let mut f = vec![[0.0; 3]; n];
    // A one-thread pool, entered once: the parallel loop then runs on this worker without
    // injecting jobs into a shared queue (whose blocks the allocator would count).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let allocs = pool.install(|| {
        col.step(1e-5, &y, &v, &m, &r, &mut f);
        let before = ALLOCS.load(Ordering::Relaxed);
        let mut contacts = 0;
        for _ in 0..10 {
            contacts += col.step(1e-5, &y, &v, &m, &r, &mut f).contacts;
        }
        assert!(contacts > 0);
        ALLOCS.load(Ordering::Relaxed) - before
    });
    assert_eq!(allocs, 0);
}

fn implicit_steps() {
    let p = ContactParams::from_material(1e7, 0.01, 1.0, 0.3, 0.4);
    let grounds = vec![GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params: p,
    }];
    let balls = vec![
        BallDesc {
            center: [0.0, 0.0, 0.1],
            radius: 0.1,
            motion: BallMotion::Dynamic {
                mass: 1.0,
                velocity: [0.0; 3],
            },
            params: p,
        },
        BallDesc {
            center: [0.05, 0.0, 0.1],
            radius: 0.05,
            motion: BallMotion::Kinematic {
                velocity: [0.1, 0.0, 0.0],
            },
            params: p,
        },
    ];
    let mut col = Colliders::new(grounds, balls, [0.0, 0.0, -9.81]).unwrap();
    // 10k particles (5 chunks) in a row through the ground and both balls.
    let n = 10_000;
    let y: Vec<Vec3> = (0..n)
        .map(|i| [1e-5 * i as f64, 0.0, 0.005 + 1e-6 * i as f64])
        .collect();
    let v = vec![[0.1, 0.0, -0.1]; n];
    let m = vec![1e-3; n];
    let r = vec![0.01; n];
    let dt = 1e-3;
    let q: Vec<Vec3> = y.iter().map(|p| [p[0] + 1e-4, p[1], p[2] - 1e-4]).collect();
    let mut gq = vec![[0.0; 3]; n];
    let mut gc = vec![[0.0; 3]; 1];
    let mut hint = vec![0.0; n];
    // A one-thread pool, entered once (see explicit_steps).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut step = |col: &mut Colliders| {
        col.begin_implicit(dt, &y, &v, &m, &r).unwrap();
        let c = [col.implicit_body_targets()[0]];
        let mut e = 0.0;
        for _ in 0..3 {
            e += col.implicit_potential(&q, &c, Some((&mut gq, &mut gc)));
            e += col.implicit_potential(&q, &c, None);
        }
        col.implicit_stiffness_hint(&q, &c, &mut hint);
        let stats = col.end_implicit(&q, &c, &v);
        (e, stats.contacts)
    };
    let allocs = pool.install(|| {
        // Warm-up: the first step sizes the buffers; the lagged-pair lists of a chunk grow
        // (by doubling) while its number of pairs in contact grows, here once more in the
        // second step as the balls move.
        step(&mut col);
        step(&mut col);
        let before = ALLOCS.load(Ordering::Relaxed);
        let mut contacts = 0;
        for _ in 0..5 {
            let (e, k) = step(&mut col);
            assert!(e > 0.0);
            contacts += k;
        }
        assert!(contacts > 0);
        ALLOCS.load(Ordering::Relaxed) - before
    });
    assert_eq!(allocs, 0);
}
