//! The time step: the stable limit of material and contact, the scene's request, and the fit
//! to whole steps per frame.

use perifrac_contact::Colliders;
use perifrac_physics::math::norm;
use perifrac_physics::{stable_frequency_memo, EstimateMemo, ForceModel};

use crate::error::SceneError;
use crate::schema::{DtSpec, SimulationSpec};

use super::check::Ctx;
use super::colliders::ContactStiffness;
use super::defaults;

/// Estimated stable step (s), `2 / omega`: `omega^2` adds the material's highest frequency
/// (Lanczos on the linearised forces at `rest`, Silling-Askari when it fails), all
/// collider springs on the particle that rings fastest on them, the fastest dynamic ball on
/// the particles it touches and contact between particles (see [`ContactStiffness`]). The
/// material's estimate is recalled from `memo` when it holds it; the flag says so.
pub(super) fn stable_limit(
    model: &mut dyn ForceModel,
    rest: &[[f64; 3]],
    horizon: f64,
    contact: ContactStiffness,
    memo: Option<&dyn EstimateMemo>,
) -> (f64, bool) {
    let (omega, est) = stable_frequency_memo(model, rest, horizon, memo);
    let dt = 2.0
        / (omega * omega + contact.collider_omega2 + contact.ball_omega2 + contact.self_omega2)
            .sqrt();
    (dt, est.recalled)
}

/// The longest step (s) in which the fastest ball (by its initial velocity) or particle (by
/// `velocities`, m/s) moves `fraction` of the mean contact radius (`r_mean`, m; the mean,
/// because a few slivers at the surface must not set the pace for all); infinite when nothing
/// moves.
pub(super) fn travel_limit(
    colliders: &Colliders,
    r_mean: f64,
    velocities: &[[f64; 3]],
    fraction: f64,
) -> f64 {
    let v_max = colliders
        .balls()
        .map(|b| norm(b.velocity))
        .chain(velocities.iter().map(|&v| norm(v)))
        .fold(0.0, f64::max);
    if v_max > 0.0 {
        fraction * r_mean / v_max
    } else {
        f64::INFINITY
    }
}

/// The scene's `dt`: `None` for `"auto"` (or no `dt`), a positive number of seconds, or an
/// error for anything else.
pub(super) fn fixed_step(ctx: &Ctx, sim: &SimulationSpec) -> Result<Option<f64>, SceneError> {
    match &sim.dt {
        None => Ok(None),
        Some(DtSpec::Word(w)) if w == "auto" => Ok(None),
        Some(DtSpec::Word(w)) => Err(ctx.err(
            "simulation.dt",
            format!("\"{w}\": expected \"auto\" or a step in seconds"),
        )),
        Some(DtSpec::Seconds(dt)) => ctx.positive("simulation.dt", *dt, "s").map(Some),
    }
}

/// The explicit step the scene asks for (s): `"auto"` is `safety` (default
/// [`defaults::SAFETY`]) times the stable limit, and at most `travel_limit`; a fixed step above
/// [`defaults::MAX_FIXED_FRACTION`] of the stable limit is refused.
pub(super) fn requested_step(
    ctx: &Ctx,
    sim: &SimulationSpec,
    safety: Option<f64>,
    dt_limit: f64,
    travel_limit: f64,
) -> Result<f64, SceneError> {
    let Some(dt) = fixed_step(ctx, sim)? else {
        return Ok((safety.unwrap_or(defaults::SAFETY) * dt_limit).min(travel_limit));
    };
    let most = defaults::MAX_FIXED_FRACTION * dt_limit;
    if dt > most {
        return Err(ctx.err(
            "simulation.dt",
            format!(
                "{dt:e} s is above the stable limit: the estimate is {dt_limit:.3e} s \
                 (keep dt <= {most:.3e} s, or write dt = \"auto\")"
            ),
        ));
    }
    Ok(dt)
}

/// The implicit step the scene asks for (s): `dt` in seconds, or `"auto"`: the frame
/// (`duration / frames`) over `steps_per_frame` (default 1), and at most `travel_limit` (the
/// step in which the fastest body moves [`defaults::IMPLICIT_TRAVEL_FRACTION`] of a contact
/// radius). No stability limit applies.
pub(super) fn implicit_step(
    ctx: &Ctx,
    sim: &SimulationSpec,
    steps_per_frame: Option<u64>,
    frames: usize,
    travel_limit: f64,
) -> Result<f64, SceneError> {
    match fixed_step(ctx, sim)? {
        None => {
            let frame_dt = sim.duration / frames as f64;
            let per_frame = steps_per_frame.unwrap_or(1).max(1) as f64;
            Ok((frame_dt / per_frame).min(travel_limit))
        }
        Some(_) if steps_per_frame.is_some() => Err(ctx.err(
            "simulation.steps_per_frame",
            "give either dt in seconds or steps_per_frame, not both",
        )),
        Some(dt) => Ok(dt),
    }
}

/// The step (s) and steps per frame: frames fall exactly on steps, and the step is at most
/// `wanted` (s).
///
/// `steps_per_frame` saturates at `u64::MAX` for a step far below the frame (or a zero one);
/// the step budget refuses such a run.
pub(crate) fn fit_to_frames(duration: f64, frames: usize, wanted: f64) -> (f64, u64) {
    let frame_dt = duration / frames as f64;
    // `as` saturates, and takes NaN to 0 (then 1).
    let steps_per_frame = ((frame_dt / wanted).ceil() as u64).max(1);
    (frame_dt / steps_per_frame as f64, steps_per_frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_fall_on_steps_and_the_step_never_grows() {
        let (dt, n) = fit_to_frames(1.0, 10, 0.03);
        // 0.1 s per frame at most 0.03 s per step: 4 steps of 0.025 s.
        assert_eq!(n, 4);
        assert!((dt - 0.025).abs() < 1e-15);
        let (dt, n) = fit_to_frames(1.0, 10, 1.0);
        assert_eq!((dt, n), (0.1, 1));
    }
}
