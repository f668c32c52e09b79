//! Xu's hyperelastic model in large static deformation against compressible neo-Hookean
//! quadratic tets (`perifrac_fem::large_bending` and `perifrac_fem::twist`): the 1 x 0.1 x
//! 0.1 m bar clamped at x = 0 and bent about 45 degrees by its own weight (E = 2e6 Pa), and
//! the same bar with its end x = 1 turned through a full turn about its axis (E = 1e6 Pa).
//!
//! Peridynamics uses the neo-Hookean-like curves (`g = h = A_1`) with the consistent moduli,
//! a clamp layer one horizon thick behind x = 0 (for the twist also one beyond x = 1, turned
//! rigidly through 360 degrees and then held), and reaches its static state with implicit
//! steps of 1 s (each nearly a static solve: the bar's slowest mode has a period of about
//! 1.4 s), mass damping, a tight tolerance, and as many steps as it takes until a step moves
//! no particle by more than 1 micrometre. The error is the paper's: the largest distance
//! between a particle of the bar proper and the reference at its rest point, over the
//! bounding-box diagonal.

use super::motion::{deviation_at, diagonal};
use super::xu_static::{
    largest_distance, mean_rotation, mid_span, peridynamics, Reading, Settings, Shape, DAMPING, DT,
};
use super::{table_and_plot, CaseReport, HORIZON_FACTORS, LENGTH};
use crate::table::Table;
use crate::{BenchError, Effort};
use perifrac_fem::{REFERENCE_DENSITY, REFERENCE_POISSON};
use perifrac_physics::Vec3;

/// The case's sweeps at `effort`: peridynamic cells along, horizon factors and the two
/// reference meshes (coarse, fine).
fn sweep(effort: Effort) -> (&'static [usize], &'static [f64], [usize; 2]) {
    match effort {
        Effort::Tiny => (&[20], &[1.5], [10, 20]),
        Effort::Full => (&[20, 30, 40], &HORIZON_FACTORS, [20, 40]),
    }
}

fn static_case(
    shape: Shape,
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    let (levels, factors, [coarse_nx, fine_nx]) = sweep(effort);
    let set = Settings::at(effort);
    let fem = |cause| BenchError::Fem {
        case: format!("{} reference", shape.name()),
        cause,
    };
    progress(&format!(
        "{}: P2 neo-Hookean at {coarse_nx} cells along",
        shape.name()
    ));
    let (coarse, _) = shape.reference(coarse_nx)?;
    progress(&format!(
        "{}: the reference, at {fine_nx} cells along",
        shape.name()
    ));
    let (reference, ref_wall) = shape.reference(fine_nx)?;
    let mut runs = Vec::new();
    let mut readings = Table::new(&match shape {
        Shape::Bend => [
            "cells",
            "k",
            "free-end centre, PD (m)",
            "reference (m)",
            "distance / diagonal",
            "steps",
            "iterations",
            "capped steps",
            "last step's motion (m)",
        ],
        Shape::Twist => [
            "cells",
            "k",
            "mid-span rotation, PD (deg)",
            "reference (deg)",
            "difference (deg)",
            "steps",
            "iterations",
            "capped steps",
            "last step's motion (m)",
        ],
    });
    let mut by_mesh: f64 = 0.0;
    for &k in factors {
        for &nx in levels {
            progress(&format!(
                "{}: peridynamics at {nx} cells along, k = {k}",
                shape.name()
            ));
            let mut solved = peridynamics(shape, nx, k, &set)?;
            let at = reference.positions_at(&solved.rest).map_err(fem)?;
            let at_coarse = coarse.positions_at(&solved.rest).map_err(fem)?;
            by_mesh = by_mesh.max(deviation_at(&at, &at_coarse));
            let dev = deviation_at(&solved.current, &at);
            solved.run.value = dev;
            solved.run.error = dev;
            let stats = solved.run.implicit.unwrap_or_default();
            let (pd, want, diff) = match solved.reading {
                Reading::Tip(tip) => {
                    let want = reference.positions_at(&[[LENGTH, 0.0, 0.0]]).map_err(fem)?[0];
                    (
                        format!("({:.4}, {:.4}, {:.4})", tip[0], tip[1], tip[2]),
                        format!("({:.4}, {:.4}, {:.4})", want[0], want[1], want[2]),
                        format!(
                            "{:.2}%",
                            100.0 * largest_distance(&[tip], &[want]) / diagonal()
                        ),
                    )
                }
                Reading::Rotation(pd) => {
                    let h = LENGTH / nx as f64;
                    let mid = mid_span(&solved.rest, h);
                    let r: Vec<Vec3> = mid.iter().map(|&i| solved.rest[i]).collect();
                    let c: Vec<Vec3> = mid.iter().map(|&i| at[i]).collect();
                    let want = mean_rotation(&r, &c);
                    (
                        format!("{pd:.2}"),
                        format!("{want:.2}"),
                        format!("{:+.2}", pd - want),
                    )
                }
            };
            readings.push(vec![
                solved.run.resolution.clone(),
                format!("{k:.1}"),
                pd,
                want,
                diff,
                solved.run.steps.to_string(),
                stats.iterations.to_string(),
                stats.capped_steps.to_string(),
                format!(
                    "{:.1e}{}",
                    solved.settled.motion,
                    if solved.settled.stalled {
                        " (then a stall at rounding)"
                    } else {
                        ""
                    }
                ),
            ]);
            runs.push(solved.run);
        }
    }
    let (table, plot) = table_and_plot(
        &format!("{} against neo-Hookean P2", shape.title()),
        "deviation / diagonal",
        &runs,
    );
    let resolved = runs.iter().filter(|r| by_mesh < 0.1 * r.error).count();
    let text = format!(
        "{} Peridynamics uses Xu's model with the neo-Hookean-like curves (g = h = A1) and the \
         consistent moduli. These are E = {:e} Pa, nu = {REFERENCE_POISSON} and \
         rho = {REFERENCE_DENSITY} kg/m^3. There is a clamp layer one horizon thick behind \
         x = 0.{} The bar is brought to rest by implicit steps of {DT} s. The implicit solve \
         has a tolerance of {:e} and at most {} iterations a step. Mass damping is {DAMPING} \
         1/s. The steps go on until a step moves no particle by more than {:e} m, with at \
         most {} steps. The error is the paper's. It is the largest distance between a \
         particle of the bar proper (0 < x < 1) and the reference at its rest point. It is \
         divided by the diagonal of the bounding box ({:.4} m). The reference is compressible \
         neo-Hookean quadratic tets at {fine_nx} cells along. It is solved by Newton with load \
         stepping in {:.1} s. At {coarse_nx} cells along, the reference differs from that by \
         at most {:.3}% of the diagonal at the same points. This is under a tenth of \
         {resolved} of the {} peridynamic deviations.",
        match shape {
            Shape::Bend =>
                "A 1 x 0.1 x 0.1 m bar clamped at x = 0 bends under its own weight, with \
                 g = 9.81 m/s^2 along -z. Its free end turns about 45 degrees.",
            Shape::Twist =>
                "A 1 x 0.1 x 0.1 m bar is clamped at x = 0. Its end x = 1 is turned through \
                 360 degrees about its axis and held axially. There is no gravity.",
        },
        shape.young(),
        match shape {
            Shape::Bend => String::new(),
            Shape::Twist => format!(
                " A second clamp layer one horizon thick, beyond x = 1, turns rigidly through \
                 the full turn in {} steps. It is then held.",
                set.turn_steps
            ),
        },
        set.tolerance,
        set.max_iterations,
        set.settled,
        set.max_settle_steps,
        diagonal(),
        ref_wall,
        100.0 * by_mesh,
        runs.len(),
    );
    let reading_title = match shape {
        Shape::Bend => "The free end's centre (PD: an affine fit over the last two cells)",
        Shape::Twist => {
            "Mid-span rotation (particles within a cell of x = 0.5, over 0.02 m from the axis)"
        }
    };
    Ok(CaseReport {
        name: shape.name().into(),
        title: shape.title().into(),
        text,
        table,
        plot,
        runs,
        tables: vec![(reading_title.into(), readings)],
    })
}

impl Shape {
    fn title(self) -> &'static str {
        match self {
            Shape::Bend => "Xu's model: a bar bent far by its weight",
            Shape::Twist => "Xu's model: a bar twisted through a full turn",
        }
    }
}

/// Xu's model against the neo-Hookean bar bent about 45 degrees by its weight.
pub fn xu_bend(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<CaseReport, BenchError> {
    static_case(Shape::Bend, effort, progress)
}

/// Xu's model against the neo-Hookean bar twisted through a full turn.
pub fn xu_twist(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<CaseReport, BenchError> {
    static_case(Shape::Twist, effort, progress)
}
