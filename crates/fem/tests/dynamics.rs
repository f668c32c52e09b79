//! Explicit dynamics: free fall is exact, energy is conserved, halving the step moves a sampled
//! trajectory by a small, second-order amount, the step allocates nothing, and the critical
//! step estimate separates stable from unstable.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use common::{max_abs, rotation};
use perifrac_fem::{
    critical_time_step, Dynamic, Kinematics, Mesh, Parallelism, Problem, Sampler, Vec3,
};

/// Counts allocations made by the current thread.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A free (unconstrained) P2 bar, 0.5 x 0.1 x 0.1 m, 5x1x1 cells, cantilever material.
fn free_bar(gravity: Vec3) -> Problem {
    let (v, t) = perifrac_topology::primitives::bar_data(0.5, [0.1, 0.1], 5);
    Problem::new(
        Mesh::quadratic(v, t).unwrap(),
        common::cantilever_material(),
    )
    .unwrap()
    .with_gravity(gravity)
}

#[test]
fn free_body_falls_with_exactly_g() {
    let g = [0.3, -1.0, -9.81];
    let problem = free_bar(g);
    let dt = 0.5 * critical_time_step(&problem, 50);
    for kin in [Kinematics::Linear, Kinematics::Corotated] {
        let mut sim = Dynamic::new(&problem, kin, dt).unwrap();
        for _ in 0..200 {
            sim.step().unwrap();
        }
        let t = sim.time();
        let mut worst = 0.0f64;
        for ((x, v), rest) in sim
            .positions()
            .iter()
            .zip(sim.velocities())
            .zip(problem.mesh().nodes())
        {
            for d in 0..3 {
                worst = worst.max((x[d] - rest[d] - 0.5 * g[d] * t * t).abs());
                worst = worst.max((v[d] - g[d] * t).abs() * dt);
            }
        }
        eprintln!(
            "{kin:?}: free fall over {t:e} s, worst deviation {worst:e} m (fall {:e} m)",
            0.5 * 9.81 * t * t
        );
        // Measured 4e-17 m: velocity Verlet is exact for constant acceleration, and a uniform
        // translation has zero strain.
        assert!(worst < 1e-14, "{worst}");
    }
}

/// `problem` started with a spin about z through the bar's middle (`spin` rad/s) plus a
/// bending and a stretching velocity field of a few m/s.
fn spinning(problem: &Problem, kin: Kinematics, dt: f64, spin: f64) -> Dynamic<'_> {
    let mut sim = Dynamic::new(problem, kin, dt).unwrap();
    let rest = problem.mesh().nodes();
    for (v, x) in sim.velocities_mut().iter_mut().zip(rest) {
        let (dx, dy) = (x[0] - 0.25, x[1]);
        let phase = std::f64::consts::PI * x[0] / 0.5;
        *v = [
            -spin * dy + 2.0 * phase.cos(),
            spin * dx,
            3.0 * phase.sin() - 1.5,
        ];
    }
    sim
}

/// Largest relative deviation of kinetic + elastic energy from its start over a run to `end`.
fn energy_error(sim: &mut Dynamic, end: f64) -> f64 {
    let energy = |s: &Dynamic| s.kinetic_energy() + s.elastic_energy().unwrap();
    let e0 = energy(sim);
    let mut worst = 0.0f64;
    while sim.time() < end {
        sim.step().unwrap();
        worst = worst.max((energy(sim) - e0).abs() / e0);
    }
    worst
}

/// A spinning, vibrating free bar: energy is conserved to a small, bounded, second-order error.
#[test]
fn energy_is_conserved_without_damping() {
    let problem = free_bar([0.0; 3]);
    let dt_crit = critical_time_step(&problem, 100);
    // Corotated with a 20 rad/s spin (1.2 rad over the run); linear without spin (it cannot
    // rotate). 0.06 s is about 6 periods of the bar's first bending mode.
    for (kin, spin) in [(Kinematics::Corotated, 20.0), (Kinematics::Linear, 0.0)] {
        let mut errors = Vec::new();
        for factor in [0.5, 0.25] {
            let mut sim = spinning(&problem, kin, factor * dt_crit, spin);
            let err = energy_error(&mut sim, 0.06);
            eprintln!(
                "{kin:?}, dt = {factor} x {dt_crit:.3e} s: {} steps, max |E - E0| / E0 = {err:.3e}",
                sim.step_count()
            );
            errors.push(err);
        }
        // Measured: corotated 3.8e-4 then 9.5e-5, linear 1.5e-3 then 3.8e-4 (bounded
        // oscillation, no drift). Second order: halving the step divides the error by 4.
        assert!(errors[0] < 3e-3, "{errors:?}");
        let ratio = errors[0] / errors[1];
        assert!(ratio > 3.0 && ratio < 5.0, "{errors:?}");
    }
}

/// The benchmark's cantilever (10x1x1 P2 cells) released from rest under gravity: halving the
/// step moves the sampled tip trajectory by a small amount that shrinks by 4 per halving.
#[test]
fn halving_the_step_converges_the_trajectory() {
    let problem = common::cantilever(10, true);
    let dt_crit = critical_time_step(&problem, 100);
    let sampler = Sampler::new(problem.mesh(), &[[1.0, 0.0, 0.0]]).unwrap();
    // Tip z displacement (m) every 0.01 s up to 0.1 s (half the first bending period).
    let trajectory = |dt: f64| -> Vec<f64> {
        let mut sim = Dynamic::new(&problem, Kinematics::Corotated, dt).unwrap();
        (1..=10)
            .map(|k| {
                sim.advance_to(0.01 * k as f64).unwrap();
                assert!((sim.time() - 0.01 * k as f64).abs() < 1e-12);
                sampler.interpolate(sim.positions())[0][2]
            })
            .collect()
    };
    // Steps that divide 0.01 s exactly.
    let n = (0.01 / (0.5 * dt_crit)).ceil();
    let runs: Vec<Vec<f64>> = [1.0, 2.0, 4.0]
        .iter()
        .map(|k| trajectory(0.01 / (n * k)))
        .collect();
    let diff = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let d1 = diff(&runs[0], &runs[1]);
    let d2 = diff(&runs[1], &runs[2]);
    let amplitude = runs[2].iter().fold(0.0f64, |a, b| a.max(b.abs()));
    eprintln!(
        "cantilever tip, dt = {:.3e} s ({} x critical {dt_crit:.3e} s): max |z(dt) - z(dt/2)| = {d1:.3e} m, |z(dt/2) - z(dt/4)| = {d2:.3e} m, tip amplitude {amplitude:.4e} m",
        0.01 / n,
        0.01 / n / dt_crit
    );
    eprintln!("tip z (m) at 0.01 s steps (dt/4): {:?}", runs[2]);
    // The tip falls well past the static deflection (0.0144 m for this mesh).
    assert!(amplitude > 0.02, "{amplitude}");
    // Measured: d1 = 2.3e-8 m, d2 = 6.4e-9 m (ratio 3.65) against a 2.9e-2 m swing: the step is converged
    // far below any error the benchmark measures (parts per million).
    assert!(d1 < 1e-5 * amplitude, "{d1}");
    let ratio = d1 / d2;
    assert!(ratio > 3.0 && ratio < 5.0, "{ratio}");
}

/// A prescribed twist moves the end faces exactly as asked, and the clamped nodes stay put.
#[test]
fn prescribed_twist_is_followed() {
    let (v, t) = perifrac_topology::primitives::bar_data(1.0, [0.1, 0.1], 10);
    let mut problem = Problem::new(
        Mesh::quadratic(v, t).unwrap(),
        common::cantilever_material(),
    )
    .unwrap();
    problem.fix_where(|x| x[0] <= 1e-12);
    // 0.5 rad/s about the bar's axis at x = 1.
    let twist = |x: Vec3, t: f64| -> Vec3 { common::apply(&rotation([1.0, 0.0, 0.0], 0.5 * t), x) };
    let end = problem.prescribe_where(|x| x[0] >= 1.0 - 1e-12, twist);
    // One Kuhn cell across: 4 corners, 4 side midpoints and the face diagonal's midpoint.
    assert_eq!(end, 9);
    let dt = 0.5 * critical_time_step(&problem, 50);
    let mut sim = Dynamic::new(&problem, Kinematics::Corotated, dt).unwrap();
    sim.advance_to(0.02).unwrap();
    let t = sim.time();
    for (i, (&x, &rest)) in sim
        .positions()
        .iter()
        .zip(problem.mesh().nodes())
        .enumerate()
    {
        if rest[0] >= 1.0 - 1e-12 {
            assert_eq!(x, twist(rest, t), "node {i}");
        } else if rest[0] <= 1e-12 {
            assert_eq!(x, rest, "node {i}");
        }
    }
    assert!(max_abs(sim.velocities()) > 0.0);
}

/// Stepping allocates nothing (serial kernel, so all work is on this thread).
#[test]
fn step_allocates_nothing() {
    let problem = common::cantilever(5, true);
    let dt = 0.5 * critical_time_step(&problem, 20);
    for kin in [Kinematics::Linear, Kinematics::Corotated] {
        let mut sim = Dynamic::new(&problem, kin, dt)
            .unwrap()
            .with_parallelism(Parallelism::Serial);
        sim.step().unwrap();
        let before = ALLOCATIONS.with(Cell::get);
        for _ in 0..100 {
            sim.step().unwrap();
        }
        let after = ALLOCATIONS.with(Cell::get);
        assert_eq!(after - before, 0, "{kin:?}");
    }
}

/// Serial and rayon kernels give bit-identical trajectories (the scatter is deterministic).
#[test]
fn parallel_and_serial_agree_bit_for_bit() {
    // 20x2x2 cells: 480 elements, above the size that runs serially anyway.
    let problem = common::cantilever(20, true);
    assert!(problem.mesh().element_count() >= perifrac_fem::SERIAL_BELOW);
    let dt = 0.5 * critical_time_step(&problem, 20);
    let run = |p: Parallelism| {
        let mut sim = Dynamic::new(&problem, Kinematics::Corotated, dt)
            .unwrap()
            .with_parallelism(p);
        for _ in 0..50 {
            sim.step().unwrap();
        }
        sim.positions().to_vec()
    };
    assert_eq!(run(Parallelism::Serial), run(Parallelism::Rayon));
}

/// Just below the estimated critical step the energy stays bounded; well above it the run
/// blows up.
#[test]
fn critical_step_estimate_separates_stable_from_unstable() {
    let problem = free_bar([0.0; 3]);
    let dt_crit = critical_time_step(&problem, 200);
    let coarse = critical_time_step(&problem, 20);
    eprintln!("critical step: {dt_crit:.4e} s (200 iterations), {coarse:.4e} s (20 iterations)");
    let err = |factor: f64| {
        let mut sim = spinning(&problem, Kinematics::Linear, factor * dt_crit, 0.0);
        let end = 2000.0 * factor * dt_crit;
        energy_error(&mut sim, end)
    };
    let (below, above) = (err(0.95), err(1.1));
    eprintln!("2000 steps: energy error {below:.3e} at 0.95 x, {above:.3e} at 1.1 x");
    assert!(below < 0.2, "{below}");
    assert!(above > 1e3, "{above}");
}
