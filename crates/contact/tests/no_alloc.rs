//! `step` allocates nothing once its buffers fit the particle count.

use perifrac_contact::{BallDesc, BallMotion, Colliders, ContactParams, GroundDesc, Vec3};
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
