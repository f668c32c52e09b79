//! Gravity, damping, anchors (with release times) and initial velocities.

use perifrac_physics::{AnchorMotion, Loads};

use crate::driver::Releases;
use crate::error::SceneError;
use crate::schema::{Region, SceneFile, VelocitySpec};

use super::check::Ctx;
use perifrac_physics::math::cross;

use super::math::bounds;

/// Loads of the scene and the anchor releases as (time in s, particles).
pub(super) fn loads(
    ctx: &Ctx,
    f: &SceneFile,
    rest: &[[f64; 3]],
    gravity: [f64; 3],
) -> Result<(Loads, Releases), SceneError> {
    let sim = &f.simulation;
    let mut loads = Loads::new(rest.len())
        .with_gravity(gravity)
        .with_damping(sim.damping.unwrap_or(0.0))
        .map_err(|e| ctx.physics(e))?;
    let mut releases = Vec::new();
    for (k, a) in f.anchor.iter().enumerate() {
        let picked = select(ctx, &format!("anchor[{k}].region"), rest, Some(&a.region))?;
        let velocity = a.velocity.unwrap_or([0.0; 3]);
        let motion = match a.angular {
            None => AnchorMotion::translation(velocity),
            Some(angular) => AnchorMotion {
                velocity,
                angular,
                center: a.center.unwrap_or_else(|| centroid(rest, &picked)),
            },
        };
        loads
            .anchor_motion(&picked, motion)
            .map_err(|e| ctx.physics(e))?;
        if let Some(t) = a.until {
            releases.push((t, picked));
        }
    }
    Ok((loads, releases))
}

/// The `[[velocity]]` tables' initial velocities (m/s) per particle:
/// `linear + angular x (X - center)`, later tables overriding earlier ones where their regions
/// overlap, zero elsewhere.
pub(crate) fn initial_velocities(
    ctx: &Ctx,
    velocities: &[VelocitySpec],
    rest: &[[f64; 3]],
) -> Result<Vec<[f64; 3]>, SceneError> {
    let mut v = vec![[0.0; 3]; rest.len()];
    let (lo, hi) = bounds(rest);
    let centre = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    for (k, vs) in velocities.iter().enumerate() {
        let picked = select(
            ctx,
            &format!("velocity[{k}].region"),
            rest,
            vs.region.as_ref(),
        )?;
        let lin = vs.linear.unwrap_or([0.0; 3]);
        let ang = vs.angular.unwrap_or([0.0; 3]);
        let c = vs.center.unwrap_or(centre);
        for &p in &picked {
            let x = rest[p as usize];
            let w = cross(ang, [x[0] - c[0], x[1] - c[1], x[2] - c[2]]);
            v[p as usize] = [lin[0] + w[0], lin[1] + w[1], lin[2] + w[2]];
        }
    }
    Ok(v)
}

/// Mean rest position (m) of the particles `picked` (not empty).
fn centroid(rest: &[[f64; 3]], picked: &[u32]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &p in picked {
        for k in 0..3 {
            c[k] += rest[p as usize][k];
        }
    }
    c.map(|v| v / picked.len() as f64)
}

/// Particles (or a shell's vertices) whose rest position lies in `region` (all when `None`);
/// an empty selection is an error naming `key`.
pub(crate) fn select(
    ctx: &Ctx,
    key: &str,
    rest: &[[f64; 3]],
    region: Option<&Region>,
) -> Result<Vec<u32>, SceneError> {
    let picked: Vec<u32> = rest
        .iter()
        .enumerate()
        .filter(|(_, x)| region.is_none_or(|r| r.contains(**x)))
        .map(|(i, _)| i as u32)
        .collect();
    if picked.is_empty() {
        return Err(ctx.err(
            key,
            "selects nothing: no rest point (a tet's barycentre, a shell's vertex) lies inside the \
             box",
        ));
    }
    Ok(picked)
}
