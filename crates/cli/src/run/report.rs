//! What `perifrac run` prints: the setup line of each kind of body, and one summary for every
//! run, with the lines that only one kind has.

use std::path::Path;

use perifrac_physics::IntegratorKind;
use perifrac_scene::setup::defaults::{CORRECTION_WARNING, CORRECTION_WARNING_MAX};
use perifrac_scene::setup::ModelKind;
use perifrac_scene::{BodySummary, Setup, ShellSetup, ShellSummary, SolidSummary, Summary};

/// The setup line of a tet solid, with its correction factors and warnings.
pub(super) fn solid_setup(scene: &Path, setup: &Setup, on: &str) {
    let info = &setup.info;
    let t = &info.times;
    eprintln!(
        "{}: {} particles, {} bonds, {} model, {} integrator, horizon {:.3e} m, dt {:.3e} s \
         (explicit stable limit {:.3e} s{}), {}, {on} (mesh {:.2}, bond families {:.2}, \
         model {:.2}, stable step {:.2}{})",
        scene.display(),
        info.particles,
        info.bonds,
        info.model,
        info.integrator,
        info.horizon,
        info.dt,
        info.dt_limit,
        if info.travel_limit.is_finite() {
            format!(", contact travel limit {:.3e} s", info.travel_limit)
        } else {
            String::new()
        },
        info.estimate,
        t.mesh.as_secs_f64(),
        t.families.as_secs_f64(),
        t.model.as_secs_f64(),
        t.stable_step.as_secs_f64(),
        if t.stable_step_recalled {
            ", recalled from the cache"
        } else {
            ""
        },
    );
    for (k, young) in &info.too_soft {
        eprintln!(
            "warning: material {k} has a Young's modulus of {young:e} Pa, softer than any solid \
             (the scene's units are SI: young = 70e9 is 70 GPa)"
        );
    }
    for e in &info.from_energy {
        eprintln!(
            "material {}: fracture energy {} J/m^2 gives s_crit {:.4e} on these bonds",
            e.material, e.fracture_energy, e.s_crit
        );
    }
    let Some(c) = &info.correction else {
        return;
    };
    let d = c.dilatation;
    if info.model == ModelKind::Xu {
        eprintln!(
            "correction of Xu's normalised dilatation weights (fitted): x{:.3} to x{:.3} (median \
             {:.3}, 99% under {:.3} in magnitude)",
            d.min, d.max, d.median, d.p99
        );
        return;
    }
    let b = c.deviatoric;
    eprintln!(
        "correction of docs/model.md's constants: dilatation weights x{:.3} to x{:.3} (median \
         {:.3}, 99% under {:.3} in magnitude), b x{:.3} to x{:.3} (median {:.3}, 99% under \
         {:.3})",
        d.min, d.max, d.median, d.p99, b.min, b.max, b.median, b.p99
    );
    if let Some(g) = &info.ghosts {
        eprintln!(
            "ghost particles across the boundary: {} ({:.1} a particle; {} bonds, {:.2} a real \
             one), gain median {:.1}, 99% under {:.1}, largest {:.1} ({} quadratic fits fell \
             back to affine ones, {} bonds too short left out)",
            g.ghosts,
            g.ghosts as f64 / info.particles.max(1) as f64,
            g.bonds,
            g.bonds as f64 / info.bonds.max(1) as f64,
            g.gain.median,
            g.gain.p99,
            g.gain.max,
            g.affine_fallbacks,
            g.short
        );
    }
    // b_i / b0 is a full ball's moment over the family's: how much of it a particle lost
    if b.p99 > CORRECTION_WARNING || b.max > CORRECTION_WARNING_MAX {
        eprintln!(
            "warning: factors on b past {CORRECTION_WARNING} (1 in 100) or \
             {CORRECTION_WARNING_MAX} (any): some particles have lost most of their family \
             (tets much larger than the horizon, or parts one or two tets across); a finer or \
             more even mesh, or a larger horizon factor, gives them more bonds"
        );
    }
}

/// The setup line of a thin shell.
pub(super) fn shell_setup(scene: &Path, setup: &ShellSetup, on: &str) {
    let info = &setup.info;
    eprintln!(
        "{}: thin shell, {} vertices, {} triangles ({} free edges), thickness {:.3e} m, \
         mass {:.4e} kg, dt {:.3e} s (stable limit {:.3e} s), {}, {on}",
        scene.display(),
        info.vertices,
        info.triangles,
        info.boundary_edges,
        info.thickness,
        info.mass,
        info.dt,
        info.dt_limit,
        match (info.event_levels, info.newmark.is_some()) {
            (0, false) => "explicit, no event search".to_string(),
            (0, true) => "implicit Newmark, no event search".to_string(),
            (k, false) => format!("explicit, event search to level {k}"),
            (k, true) => format!("implicit Newmark, event search to level {k}"),
        },
    );
}

/// The summary of a finished run: `wall` seconds in this process, which resumed at step
/// `resumed_at` (0 for a fresh run).
pub(super) fn summary(s: &Summary, wall: f64, resumed_at: u64, threads: usize, dir: &Path) {
    let stepped = s.steps.saturating_sub(resumed_at);
    let broken = match &s.body {
        BodySummary::Solid(b) => format!(
            "{} bonds broken, {} fragments, {} crack triangles",
            b.broken_bonds, s.fragments, b.crack_triangles
        ),
        BodySummary::Shell(b) => format!(
            "{} triangles broken, {} fragments, {} triangles yielded",
            b.broken_triangles, s.fragments, b.yielded
        ),
    };
    eprintln!(
        "done in {wall:.2} s: {} steps ({}{:.0} steps/s), t = {:.4e} s, {broken}",
        s.steps,
        if resumed_at > 0 {
            format!("{stepped} after resuming, ")
        } else {
            String::new()
        },
        stepped as f64 / wall.max(1e-9),
        s.time,
    );
    let balls = s.solid().map_or(0.0, |b| b.ball_kinetic_energy);
    let loads = match &s.body {
        BodySummary::Solid(b) => b.load_work,
        BodySummary::Shell(b) => b.load_work,
    };
    eprintln!(
        "energy at the end: kinetic {:.4e} J, elastic {:.4e} J{}{}",
        s.kinetic_energy,
        s.elastic_energy,
        if balls > 0.0 {
            format!(", balls {balls:.4e} J")
        } else {
            String::new()
        },
        loads.map_or(String::new(), |w| format!(
            "; the loads did {w:.4e} J of work"
        ))
    );
    match &s.body {
        BodySummary::Solid(b) => solid_lines(b, s.steps),
        BodySummary::Shell(b) => shell_lines(b, s.steps, threads),
    }
    eprintln!(
        "{} frames in {}",
        s.frames_written,
        dir.join("frames").display()
    );
    if let Some((usd, took)) = &s.usd {
        eprintln!("{}", crate::export::describe(usd, *took));
    }
}

/// A tet solid's self contact, event search, implicit iterations and time per stage.
fn solid_lines(s: &SolidSummary, steps: u64) {
    if let Some(line) = why_little_broke(s) {
        eprintln!("{line}");
    }
    if let Some((builds, deepest)) = s.self_contact {
        eprintln!(
            "self contact: up to {} pairs touching, deepest overlap {:.3e} m ({:.1}% of a \
             contact distance), pair list built {builds} times",
            deepest.pairs,
            deepest.max_overlap,
            100.0 * deepest.max_overlap_share
        );
    }
    let it = s.solver;
    if s.integrator == IntegratorKind::EventSearch {
        eprintln!(
            "event search: {} sub-steps ({:.2} per step), {} trial sub-steps undone",
            it.substeps,
            it.substeps as f64 / steps.max(1) as f64,
            it.rejected
        );
    }
    if s.integrator == IntegratorKind::Implicit {
        eprintln!(
            "implicit: {} iterations ({:.1} per step, {} evaluations), {} steps at the \
             iteration cap, {} factorisations ({:.2} s), solves {:.2} s, factor {:.1} MB",
            it.iterations,
            it.iterations as f64 / steps.max(1) as f64,
            it.evaluations,
            it.capped_steps,
            it.factorizations,
            it.factor_seconds,
            it.solve_seconds,
            it.factor_bytes as f64 / 1e6
        );
    }
    let t = s.stage_times;
    let share =
        |d: std::time::Duration| 100.0 * d.as_secs_f64() / t.total().as_secs_f64().max(1e-12);
    eprintln!(
        "time per stage: physics {:.0}% (contact {:.0}%), topology {:.0}%, advection {:.0}%, \
         output {:.0}% ({:.2} s)",
        share(t.physics),
        share(t.contact),
        share(t.topology),
        share(t.advect),
        share(t.output),
        t.output.as_secs_f64()
    );
}

/// A thin shell's sub-steps, Newmark solves, speed and contact time.
fn shell_lines(s: &ShellSummary, steps: u64, threads: usize) {
    let per_step = s.substeps as f64 / steps.max(1) as f64;
    if s.event_levels > 0 {
        eprintln!(
            "event search: {} sub-steps ({per_step:.2} per step), {} trial sub-steps undone",
            s.substeps, s.rejected
        );
    } else if s.substeps != steps {
        eprintln!(
            "{} sub-steps ({per_step:.2} per step): steps were cut where fracture lowered the \
             stable step",
            s.substeps
        );
    }
    if let Some(nm) = s.newmark {
        eprintln!(
            "Newmark: {} solves, {:.1} L-BFGS iterations each, {} at the cap, {} \
             factorisations ({:.2} s)",
            nm.steps,
            nm.iterations as f64 / nm.steps.max(1) as f64,
            nm.capped,
            nm.factorizations,
            nm.factor_seconds
        );
    }
    let stepping = s.physics_time.as_secs_f64().max(1e-9);
    let updates = s.triangle_updates as f64 / stepping;
    eprintln!(
        "speed: {updates:.3e} triangle updates/s ({:.3e} per thread){}",
        updates / threads as f64,
        match s.self_contact {
            Some((secs, builds)) => format!(
                ", self contact {secs:.2} s ({:.1}% of stepping, {builds} list builds)",
                100.0 * secs / stepping
            ),
            None => String::new(),
        }
    );
    if s.collider_seconds > 0.0 {
        eprintln!(
            "contact with grounds and balls: {:.2} s ({:.1}% of stepping)",
            s.collider_seconds,
            100.0 * s.collider_seconds / stepping
        );
    }
    eprintln!(
        "stepping {:.2} s, output {:.2} s",
        s.physics_time.as_secs_f64(),
        s.output_time.as_secs_f64()
    );
}

/// The share of the bonds under which a run says how close its materials came to breaking.
const FEW_BROKEN: f64 = 0.01;

/// When fewer than [`FEW_BROKEN`] of the bonds broke in a run that can break: how close each
/// breaking material came, as the largest share of its threshold a bond reached.
fn why_little_broke(s: &SolidSummary) -> Option<String> {
    let shares = s.peak_threshold_shares.as_ref()?;
    if s.broken_bonds as f64 >= FEW_BROKEN * s.bonds as f64 {
        return None;
    }
    let parts: Vec<String> = shares
        .iter()
        .enumerate()
        .filter_map(|(m, p)| p.map(|p| format!("material {m} {:.0}%", 100.0 * p)))
        .collect();
    if parts.is_empty() {
        return None;
    }
    let most = shares.iter().flatten().cloned().fold(0.0, f64::max);
    let hint = if most < 1.0 {
        "; to break, lower the threshold (fracture_energy or s_crit) or load harder"
    } else {
        ""
    };
    Some(format!(
        "{} of {} bonds broke (under {:.0}%); the largest bond stretch reached, as a share of \
         its threshold: {}{hint}",
        s.broken_bonds,
        s.bonds,
        100.0 * FEW_BROKEN,
        parts.join(", ")
    ))
}
