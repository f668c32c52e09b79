//! A step allocates nothing: every buffer is owned by the solver and the model.

mod support;

use perifrac_physics::{
    ChenModel, Explicit, ExplicitConfig, FractureParams, Loads, TimeStep, YieldParams,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steps_do_not_allocate_on_any_path() {
    let mut steel = support::steel();
    let mut paths = vec![steel.clone()];
    steel.plasticity = Some(YieldParams {
        psi0: 1e30,
        gamma_ratio: 0.05,
    });
    steel.fracture = Some(FractureParams {
        s_crit: 1.0,
        alpha: 0.0,
    });
    paths.push(steel);
    for mat in paths {
        let (disc, _, _) = support::block([0.04; 3], [4, 4, 4], 1.5);
        let x = disc.rest_positions().to_vec();
        let delta = disc.horizon();
        let m = ChenModel::new(disc, &[mat]).unwrap();
        let cfg = ExplicitConfig {
            dt: TimeStep::Fixed(1e-7),
            guard_fraction: 0.5,
        };
        let mut loads = Loads::new(x.len()).with_damping(10.0).unwrap();
        loads.anchor(&[0, 1, 2], [0.1, 0.0, 0.0]).unwrap();
        let mut s = Explicit::new(m, &x, delta, loads, cfg).unwrap();
        for v in s.velocities_mut() {
            v[1] = 0.3;
        }
        for _ in 0..5 {
            s.step().unwrap(); // warm up the thread pool
        }
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        for _ in 0..20 {
            s.step().unwrap();
        }
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert_eq!(after - before, 0, "allocations in 20 steps");
    }
}
