//! A step allocates nothing: every buffer is owned by the solver and the model.

mod support;

use perifrac_physics::{
    ChenModel, Curve, Explicit, ExplicitConfig, ForceModel, FractureParams, Implicit,
    ImplicitConfig, Loads, Simulation, TimeStep, XuMaterial, XuModel, XuModuli, XuOptions,
    YieldParams,
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

/// One test: the counting allocator sees every thread of the binary.
#[test]
fn steps_do_not_allocate_on_any_path() {
    chen_paths();
    xu_paths();
}

fn chen_paths() {
    let mut steel = support::steel();
    let mut paths = vec![steel.clone()];
    steel.plasticity = Some(YieldParams {
        psi0: 1e30,
        gamma_ratio: 0.05,
        from_strain: false,
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
        let s = Explicit::new(m, &x, delta, loads, cfg).unwrap();
        assert_eq!(steady_allocations(s), 0, "allocations in 20 explicit steps");
    }
}

/// Allocations in 20 steps of `s`, after 5 to warm up the thread pool and the buffers; the
/// particles start moving sideways at 0.3 m/s.
fn steady_allocations<M: ForceModel, I: perifrac_physics::Integrator<M>>(
    mut s: Simulation<M, I>,
) -> usize {
    for v in s.velocities_mut() {
        v[1] = 0.3;
    }
    let mut env = perifrac_physics::NoEnvironment;
    for _ in 0..5 {
        s.step_in(&mut env).unwrap();
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..20 {
        s.step_in(&mut env).unwrap();
    }
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

fn xu_paths() {
    let base = XuMaterial::from_young_poisson(
        1e6,
        0.3,
        1000.0,
        Curve::NeoHookean,
        Curve::Stvk,
        XuModuli::Consistent,
    )
    .unwrap();
    let brittle = XuMaterial {
        fracture: Some(FractureParams {
            s_crit: 1.0,
            alpha: 0.0,
        }),
        ..base.clone()
    };
    let guarded = XuOptions {
        inversion_guard: Some(1.0),
        ..XuOptions::default()
    };
    for (mat, opts) in [(base, XuOptions::default()), (brittle, guarded)] {
        let model = || {
            let (disc, _, _) = support::block([0.04; 3], [4, 4, 4], 1.5);
            XuModel::new(disc, std::slice::from_ref(&mat), opts).unwrap()
        };
        let x = model().discretization().rest_positions().to_vec();
        let delta = model().discretization().horizon();
        let mut loads = Loads::new(x.len()).with_gravity([0.0, 0.0, -9.81]);
        loads.anchor(&[0, 1, 2], [0.1, 0.0, 0.0]).unwrap();
        let cfg = ExplicitConfig {
            dt: TimeStep::Fixed(1e-6),
            guard_fraction: 0.5,
        };
        let s = Explicit::new(model(), &x, delta, loads.clone(), cfg).unwrap();
        assert_eq!(steady_allocations(s), 0, "explicit Xu");
        let s = Implicit::new(model(), &x, loads, ImplicitConfig::with_dt(1e-2)).unwrap();
        assert_eq!(steady_allocations(s), 0, "implicit Xu");
    }
}
