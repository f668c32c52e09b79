//! The peridynamic side of Xu's static cases ([`super::xu`]): the problem (material,
//! reference, loads and held layers of each shape), the implicit steps that bring the bar to
//! rest, and what is read off the answer.

use std::f64::consts::TAU;
use std::time::Instant;

use perifrac_fem::{
    large_bending, twist, NewtonOptions, Reference, BENDING_YOUNG, REFERENCE_DENSITY,
    REFERENCE_GRAVITY, REFERENCE_POISSON, TWIST_YOUNG,
};
use perifrac_physics::{
    AnchorMotion, Implicit, ImplicitConfig, Loads, PhysicsError, Solver, Vec3, XuMaterial, XuModel,
};
use perifrac_topology::primitives::bar_data;

use super::{Run, LENGTH, SIDE};
use crate::bar::{cells_across, held_bar, xu_neo_hookean, KUHN};
use crate::fit::affine_at;
use crate::{BenchError, Effort};

/// The implicit step (s): long against the bar's slowest period, so each step is nearly static.
pub(super) const DT: f64 = 1.0;
/// Mass damping (1/s), about critical for the bent bar's first mode (4.5 rad/s).
pub(super) const DAMPING: f64 = 10.0;

/// How hard the static state is sought.
#[derive(Debug, Clone, Copy)]
pub(super) struct Settings {
    /// Relative tolerance of each step (the decrease of `Phi` still to come over the step's).
    pub tolerance: f64,
    /// Iterations per step at most; a capped step goes on from where it stopped in the next.
    pub max_iterations: usize,
    /// The static state is reached when a step moves no particle by more than this (m). Near
    /// rest the motion per step falls 4 to 5 times a step (measured at 40 x 4 x 4 cells,
    /// k = 2: 1.8e-3, 7.1e-4, 1.8e-4, 3.9e-5, 8.9e-6 m), so what is left to go is a fraction
    /// of it: stopping there rather than one step later (1.4e-6 m) moved the deviation by
    /// 1.4e-6 of the diagonal, under 1e-4 of itself (1.808787% against 1.808926%). Below about
    /// 1e-6 m the decrease of `Phi` is under its rounding and a step only repeats the last
    /// one's motion, so a tighter bound would never be met.
    pub settled: f64,
    /// Steps at most after the load is in place.
    pub max_settle_steps: usize,
    /// Steps that turn the twist's end through its full turn.
    pub turn_steps: usize,
}

impl Settings {
    /// The measurement's settings, or loose ones that only check the harness (`Tiny`).
    pub(super) fn at(effort: Effort) -> Settings {
        match effort {
            Effort::Tiny => Settings {
                tolerance: 1e-6,
                max_iterations: 100,
                settled: 1e-4,
                max_settle_steps: 6,
                turn_steps: 8,
            },
            Effort::Full => Settings {
                tolerance: 1e-6,
                max_iterations: 200,
                settled: 1e-5,
                max_settle_steps: 60,
                turn_steps: 24,
            },
        }
    }
}

/// Which static case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Shape {
    /// Bent by its weight.
    Bend,
    /// Twisted through a full turn.
    Twist,
}

impl Shape {
    /// The case's name.
    pub(super) fn name(self) -> &'static str {
        match self {
            Shape::Bend => "xu_bend",
            Shape::Twist => "xu_twist",
        }
    }

    /// Young's modulus (Pa).
    pub(super) fn young(self) -> f64 {
        match self {
            Shape::Bend => BENDING_YOUNG,
            Shape::Twist => TWIST_YOUNG,
        }
    }

    /// Xu's neo-Hookean-like material of the case, by the consistent conversion.
    fn material(self, case: &str) -> Result<XuMaterial, BenchError> {
        xu_neo_hookean(case, self.young(), REFERENCE_POISSON, REFERENCE_DENSITY)
    }

    /// The P2 neo-Hookean reference on `nx` cells along and its wall time (s).
    pub(super) fn reference(self, nx: usize) -> Result<(Reference, f64), BenchError> {
        let started = Instant::now();
        let (v, t) = bar_data(LENGTH, [SIDE, SIDE], nx);
        let r = match self {
            Shape::Bend => large_bending(v, t, &NewtonOptions::default()),
            Shape::Twist => {
                let options = NewtonOptions {
                    load_steps: 16,
                    ..Default::default()
                };
                twist(v, t, 1.0, &options)
            }
        }
        .map_err(|cause| BenchError::Fem {
            case: format!("{} FEM P2 {nx} cells", self.name()),
            cause,
        })?;
        Ok((r, started.elapsed().as_secs_f64()))
    }
}

/// A static peridynamic answer: the run, the rest and final positions of the bar proper's
/// particles, what the case reads off it (the free-end centre, or the mid-span rotation in
/// degrees) and the last step's largest motion (m).
pub(super) struct Solved {
    /// The run (its value and error for the caller to set).
    pub run: Run,
    /// Rest positions of the bar proper's particles (m).
    pub rest: Vec<Vec3>,
    /// Their final positions (m).
    pub current: Vec<Vec3>,
    /// What the shape reads off.
    pub reading: Reading,
    /// How the stepping ended.
    pub settled: Settled,
}

/// What a case reads off a static answer.
#[derive(Debug, Clone, Copy)]
pub(super) enum Reading {
    /// Position (m) of the centre of the free end, `(1, 0, 0)` at rest.
    Tip(Vec3),
    /// Mean rotation (degrees) about x of the particles near mid-span away from the axis.
    Rotation(f64),
}

/// How the static state was reached: the last step's largest motion (m), and whether the
/// stepping ended on a line-search stall at the rounding floor of `Phi`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Settled {
    /// The last step's largest motion (m).
    pub motion: f64,
    /// Whether a stall at the rounding floor ended the stepping.
    pub stalled: bool,
}

/// A stall whose predicted decrease is below this share of `Phi` is at the rounding floor: the
/// line search cannot see it (with 1 s steps under gravity `Phi` holds the inertial term of a
/// free fall, about 490 J for these bars).
const ROUNDING_FLOOR: f64 = 1e-9;

/// Steps `s` until a step moves no particle by more than `settled`, at most
/// `max_settle_steps`. (Whether the step reached its tolerance does not matter: near rest a
/// step's whole decrease of `Phi` is so small that a relative tolerance asks for less than its
/// rounding, and the line search then halves many times per iteration.) A step that stalls at the rounding floor (see
/// [`ROUNDING_FLOOR`]) ends the stepping with the state of the step before it.
fn settle(s: &mut Implicit<XuModel>, case: &str, set: &Settings) -> Result<Settled, BenchError> {
    let mut motion = f64::INFINITY;
    for _ in 0..set.max_settle_steps {
        let before = s.positions().to_vec();
        match s.step() {
            Ok(_) => {}
            Err(PhysicsError::Stalled { predicted, phi, .. })
                if predicted <= ROUNDING_FLOOR * phi.abs() =>
            {
                return Ok(Settled {
                    motion,
                    stalled: true,
                })
            }
            Err(cause) => {
                return Err(BenchError::Physics {
                    case: case.into(),
                    cause,
                })
            }
        }
        motion = largest_distance(&before, s.positions());
        if motion <= set.settled {
            break;
        }
    }
    Ok(Settled {
        motion,
        stalled: false,
    })
}

/// Largest distance (m) between corresponding points.
pub(super) fn largest_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Mean rotation (degrees, in [0, 360)) about the x axis from `rest` to `current`.
pub(super) fn mean_rotation(rest: &[Vec3], current: &[Vec3]) -> f64 {
    let angles: Vec<f64> = rest
        .iter()
        .zip(current)
        .map(|(x, y)| {
            (y[2].atan2(y[1]) - x[2].atan2(x[1]))
                .to_degrees()
                .rem_euclid(360.0)
        })
        .collect();
    angles.iter().sum::<f64>() / angles.len().max(1) as f64
}

/// Particles of `rest` near mid-span (within one cell of x = L/2) and more than 0.02 m from
/// the axis, where the twist's rotation is read.
pub(super) fn mid_span(rest: &[Vec3], h: f64) -> Vec<usize> {
    (0..rest.len())
        .filter(|&i| {
            let x = rest[i];
            (x[0] - 0.5 * LENGTH).abs() < h && x[1].hypot(x[2]) > 0.02
        })
        .collect()
}

/// The static answer of peridynamics on `nx` cells along with horizon factor `k`.
pub(super) fn peridynamics(
    shape: Shape,
    nx: usize,
    k: f64,
    set: &Settings,
) -> Result<Solved, BenchError> {
    let started = Instant::now();
    let n = cells_across(nx);
    let h = LENGTH / nx as f64;
    let case = format!("{} PD {nx}x{n}x{n} k={k}", shape.name());
    let physics = |cause| BenchError::Physics {
        case: case.clone(),
        cause,
    };
    let material = shape.material(&case)?;
    let bar = held_bar(
        &case,
        LENGTH,
        SIDE,
        nx,
        k,
        &material,
        shape == Shape::Twist,
        KUHN,
    )?;
    let bonds = bar.body.bonds();
    let tracked = bar.body.select(|x| x[0] > 0.0 && x[0] < LENGTH);
    let free_end = bar
        .body
        .select(|x| x[0] > LENGTH - 2.0 * h && x[0] < LENGTH);
    let rest_all = bar.body.rest().to_vec();
    let gravity = match shape {
        Shape::Bend => REFERENCE_GRAVITY,
        Shape::Twist => [0.0; 3],
    };
    let mut loads = Loads::new(rest_all.len())
        .with_gravity(gravity)
        .with_damping(DAMPING)
        .map_err(physics)?;
    loads.anchor(&bar.clamp, [0.0; 3]).map_err(physics)?;
    if shape == Shape::Twist {
        let turn = AnchorMotion {
            velocity: [0.0; 3],
            angular: [TAU / (set.turn_steps as f64 * DT), 0.0, 0.0],
            center: [0.0; 3],
        };
        loads.anchor_motion(&bar.end, turn).map_err(physics)?;
    }
    let config = ImplicitConfig {
        tolerance: set.tolerance,
        max_iterations: set.max_iterations,
        ..ImplicitConfig::with_dt(DT)
    };
    let mut s = bar.body.implicit(&case, loads, config)?;
    if shape == Shape::Twist {
        for _ in 0..set.turn_steps {
            s.step().map_err(physics)?;
        }
        // a full turn brings the end back to its rest place: hold it there
        s.loads_mut().anchor(&bar.end, [0.0; 3]).map_err(physics)?;
    }
    let settled = settle(&mut s, &case, set)?;
    let y = s.positions();
    let rest: Vec<Vec3> = tracked.iter().map(|&i| rest_all[i as usize]).collect();
    let current: Vec<Vec3> = tracked.iter().map(|&i| y[i as usize]).collect();
    let reading = match shape {
        Shape::Bend => {
            let tip = affine_at(&rest_all, y, &free_end, [LENGTH, 0.0, 0.0]).ok_or_else(|| {
                BenchError::Mesh {
                    case: case.clone(),
                    message: "the free end's particles do not span three dimensions".into(),
                }
            })?;
            Reading::Tip(tip)
        }
        Shape::Twist => {
            let mid = mid_span(&rest, h);
            let r: Vec<Vec3> = mid.iter().map(|&i| rest[i]).collect();
            let c: Vec<Vec3> = mid.iter().map(|&i| current[i]).collect();
            Reading::Rotation(mean_rotation(&r, &c))
        }
    };
    let steps = s.steps();
    let run = Run {
        method: "PD Xu implicit (static)".into(),
        implicit: Some(Solver::stats(&s)),
        ..Run::peridynamics([nx, n, n], k, started, steps, bonds)
    };
    Ok(Solved {
        run,
        rest,
        current,
        reading,
        settled,
    })
}
