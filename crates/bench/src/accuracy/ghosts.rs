//! Ghost particles across the bars' faces (`perifrac_physics::ghost`, issue 18), on the
//! scenes' unstructured tets at k = 1.5: the cantilever of the `cantilever` case, held by its
//! layer of particles or clamped by its mirror image across x = 0, and the moduli of the
//! `moduli` case at 8 cells across. The faces are the bars' own planes (a scene finds its
//! mesh's: `correction = "ghosts"`).

use perifrac_physics::{FaceKind, GhostFit, GhostPlane, GhostReport};

use super::cantilever::{bar_planes, relax, Clamp};
use super::motion::{deviation, Motion, Reference};
use super::motion_runs::Method;
use super::waves::tension_of;
use super::{material, table_and_plot, CaseReport, POISSON, SIDE};
use crate::bar::{cells_across, Cut, GhostedChen, UNSTRUCTURED_SEED};
use crate::table::Table;
use crate::{BenchError, Effort};

/// The cantilever's converged tip (m): the `cantilever` case's quadratic tets at 80 cells
/// along (docs/bench/accuracy.md), which this case does not rerun.
const P2_TIP: f64 = 1.472777e-2;

/// How a series corrects the surface: the fitted default alone, or with ghosts fitted so.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fix {
    Fitted,
    Ghosts(GhostFit),
}

impl Fix {
    fn name(self) -> &'static str {
        match self {
            Fix::Fitted => "fitted",
            Fix::Ghosts(GhostFit::Affine) => "affine ghosts",
            Fix::Ghosts(GhostFit::Quadratic) => "quadratic ghosts",
        }
    }
}

/// The gain column: median and largest, or a dash without free ghosts.
fn gains(g: &Option<GhostReport>, fix: Fix) -> String {
    match (g, fix) {
        (Some(g), Fix::Ghosts(_)) => format!("{:.1} / {:.1}", g.gain.median, g.gain.max),
        _ => "-".into(),
    }
}

/// The ghosts case.
pub fn ghosts(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<CaseReport, BenchError> {
    // cells along for the context series and for the candidates (the mirror-clamped ghosts,
    // run to the target's 60 x 6 x 6), the moduli bar's, and its Poisson's ratios
    let (context, candidates, across8, ratios): (&[usize], &[usize], usize, &[f64]) = match effort {
        Effort::Tiny => (&[20], &[20], 16, &[POISSON]),
        Effort::Full => (&[20, 30, 40], &[20, 30, 40, 60], 32, &[0.1, POISSON, 0.4]),
    };
    let cut = Cut::Unstructured(UNSTRUCTURED_SEED);
    let variants = [
        (Clamp::Held, Fix::Ghosts(GhostFit::Affine), context),
        (Clamp::Mirror, Fix::Fitted, context),
        (Clamp::Mirror, Fix::Ghosts(GhostFit::Affine), candidates),
        (Clamp::Mirror, Fix::Ghosts(GhostFit::Quadratic), candidates),
    ];
    let mut runs = Vec::new();
    let mut convergence = Table::new(&[
        "correction",
        "clamp",
        "cells",
        "error",
        "observed order",
        "sideways / vertical",
        "ghosts",
        "gain: median / largest",
        "steps",
    ]);
    for (clamp, fix, levels) in variants {
        let mut last: Option<(f64, f64)> = None;
        for &nx in levels {
            let n = cells_across(nx);
            progress(&format!(
                "ghosts: cantilever {nx}x{n}x{n}, {}, {} clamp",
                fix.name(),
                clamp_name(clamp)
            ));
            let m = material("ghosts", POISSON)?;
            let method = format!("PD {}, {} clamp", fix.name(), clamp_name(clamp));
            let planes = match fix {
                Fix::Ghosts(_) => bar_planes(clamp),
                // the mirror clamp alone: only the face x = 0
                Fix::Fitted => bar_planes(clamp)
                    .into_iter()
                    .filter(|p| p.kind == FaceKind::Clamped)
                    .collect(),
            };
            let fit = match fix {
                Fix::Ghosts(f) => f,
                Fix::Fitted => GhostFit::Affine,
            };
            let g = GhostedChen {
                material: m,
                planes,
                fit,
            };
            let (mut run, _, side, report) = relax(nx, 1.5, &g, cut, clamp, method)?;
            run.error = run.value / P2_TIP - 1.0;
            let order = match last {
                Some((e, c)) if e != 0.0 && run.error != 0.0 => format!(
                    "{:.2}",
                    (e.abs() / run.error.abs()).ln() / (nx as f64 / c).ln()
                ),
                _ => "-".into(),
            };
            last = Some((run.error, nx as f64));
            convergence.push(vec![
                fix.name().into(),
                clamp_name(clamp).into(),
                run.resolution.clone(),
                format!("{:+.2}%", 100.0 * run.error),
                order,
                format!("{:.2}%", 100.0 * side),
                report.as_ref().map_or("-".into(), |g| g.ghosts.to_string()),
                gains(&report, fix),
                run.steps.to_string(),
            ]);
            runs.push(run);
        }
    }
    let mut moduli = Table::new(&[
        "correction",
        "cells",
        "nu given",
        "E error",
        "nu measured",
        "nu - nu given",
        "gain: median / largest",
        "wall time (s)",
    ]);
    // the moduli bar, [0, 0.4] x [0, SIDE]^2: its four side faces free, its ends held
    let sides = GhostPlane::box_faces([0.0; 3], [0.4, SIDE, SIDE])[2..].to_vec();
    for fit in [GhostFit::Affine, GhostFit::Quadratic] {
        for &nu0 in ratios {
            let fix = Fix::Ghosts(fit);
            progress(&format!(
                "ghosts: moduli at {across8} cells along, nu = {nu0}, {}",
                fix.name()
            ));
            let g = GhostedChen {
                material: material("ghosts", nu0)?,
                planes: sides.clone(),
                fit,
            };
            let (e, nu, run, _, report) = tension_of(across8, 1.5, &g, nu0, cut)?;
            moduli.push(vec![
                fix.name().into(),
                run.resolution.clone(),
                format!("{nu0}"),
                format!("{:+.2}%", 100.0 * (e - 1.0)),
                format!("{nu:.4}"),
                format!("{:+.4}", nu - nu0),
                gains(&report, fix),
                format!("{:.1}", run.wall_s),
            ]);
        }
    }
    // the swinging and twisting bars of the motion cases (held by their clamp layer, the four
    // side faces ghosted), against those cases' finer reference
    let (motion_nx, fem_nx): (usize, [usize; 2]) = match effort {
        Effort::Tiny => (20, [10, 10]),
        Effort::Full => (40, [40, 80]),
    };
    let mut motions = Table::new(&[
        "motion",
        "correction",
        "cells",
        "deviation / diagonal",
        "steps",
        "wall time (s)",
    ]);
    for (motion, fem) in [(Motion::Swing, fem_nx[0]), (Motion::Twist, fem_nx[1])] {
        progress(&format!(
            "ghosts: {}, corotated P2 at {fem} cells along",
            motion.name()
        ));
        let reference = Reference::run(motion, fem, 0.5)?;
        for fit in [GhostFit::Affine, GhostFit::Quadratic] {
            let fix = Fix::Ghosts(fit);
            progress(&format!(
                "ghosts: {} at {motion_nx} cells along, {}",
                motion.name(),
                fix.name()
            ));
            let (run, points, pd) = Method::ChenGhosts(fit).run(motion, motion_nx, 1.5)?;
            let dev = deviation(&pd, &reference.at(&points)?);
            motions.push(vec![
                motion.name().into(),
                fix.name().into(),
                run.resolution.clone(),
                format!("{:.2}%", 100.0 * dev),
                run.steps.to_string(),
                format!("{:.1}", run.wall_s),
            ]);
        }
    }
    let (table, plot) = table_and_plot("Ghosts: cantilever under gravity", "m", &runs);
    let text = format!(
        "This case tests ghost particles (`perifrac_physics::ghost`) on the scenes' \
         unstructured tets (seed {UNSTRUCTURED_SEED}) at k = 1.5. The section \"Ghost \
         particles across the faces\" of docs/DECISIONS.md describes them. Every particle \
         within a horizon of a side face is mirrored across it. Near an edge or corner, it is \
         mirrored across both or all three faces. The image moves with its source by the \
         least-squares fit of the displacement over the source's family. The fit is affine, \
         or quadratic with the second derivatives. The image stores no energy. It completes \
         its neighbours' families. The correction's constants are fitted over the completed \
         families. The cantilever of the `cantilever` case is held in one of two ways. The \
         \"held\" clamp is its layer of held particles behind x = 0. The \"mirror\" clamp is \
         its own image across x = 0, moving as minus its source. This gives zero displacement \
         on the face to first order, with no layer. Errors are against the `cantilever` \
         case's quadratic tets at 80 cells along ({P2_TIP} m). A ghost's gain is the sum of \
         its combination's coefficients' magnitudes. A copy of its source has a gain of 1. \
         The moduli are the `moduli` case's at 8 cells across. The bar's four side faces are \
         ghosted. Its end layers are held as in that case. The swinging and twisting bars are \
         the `swing` and `twist` cases' at 4 cells across. They are held by their clamp layer, \
         and their four side faces are ghosted. They are measured against those cases' \
         reference: corotated quadratic tets at 40 and 80 cells along. The measure is the \
         same: the largest distance from the reference over particles and samples, over the \
         diagonal."
    );
    Ok(CaseReport {
        name: "ghosts".into(),
        title: "Ghost particles across the faces".into(),
        text,
        table,
        plot,
        runs,
        tables: vec![
            (
                "Cantilever: convergence, sideways deflection, ghosts".into(),
                convergence,
            ),
            (
                "Moduli with ghosts (8 cells across in the full run)".into(),
                moduli,
            ),
            ("Swinging and twisting bars with ghosts".into(), motions),
        ],
    })
}

/// The clamp's name in the tables.
fn clamp_name(c: Clamp) -> &'static str {
    match c {
        Clamp::Held => "held",
        Clamp::Mirror => "mirror",
    }
}
