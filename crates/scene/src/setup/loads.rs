//! Gravity, damping, anchors (with release times) and initial velocities.

use perifrac_physics::{AnchorMotion, Loads};

use crate::driver::Releases;
use crate::error::SceneError;
use crate::schema::{LoadSpec, Region, SceneFile, VelocitySpec};

use super::check::Ctx;
use crate::environment::RegionLoad;
use perifrac_physics::math::{add, cross, norm, scale, sub};
use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::{TetMesh, NO_TET};

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

/// A `[[load]]` table's ramp (s, 0 when absent) and end time (s, infinity when absent),
/// checked; `key` names the table.
pub(crate) fn timing(ctx: &Ctx, key: &str, l: &LoadSpec) -> Result<(f64, f64), SceneError> {
    let ramp = match l.ramp {
        Some(t) => ctx.non_negative(&format!("{key}.ramp"), t)?,
        None => 0.0,
    };
    let until = match l.until {
        Some(t) if t.is_nan() || t <= 0.0 => {
            return Err(ctx.err(
                format!("{key}.until"),
                format!("{t} s must be positive (inf: never)"),
            ))
        }
        Some(t) => t,
        None => f64::INFINITY,
    };
    Ok((ramp, until))
}

/// The `[[load]]` tables as forces (N) on particles at full strength, from the rest mesh
/// (before any initial crack): a traction or pressure on the boundary faces whose centroid lies
/// in the region, summed into each face's tet; a body force on the particles in it, times each
/// one's volume (m^3).
pub(super) fn region_loads(
    ctx: &Ctx,
    f: &SceneFile,
    mesh: &TetMesh,
    rest: &[[f64; 3]],
    volumes: &[f64],
) -> Result<Vec<RegionLoad>, SceneError> {
    let mut out = Vec::with_capacity(f.load.len());
    for (k, l) in f.load.iter().enumerate() {
        let key = format!("load[{k}]");
        if let Some(r) = &l.region {
            ctx.region(&format!("{key}.region"), r)?;
        }
        let (ramp, until) = timing(ctx, &key, l)?;
        let (particles, forces) = match (l.traction, l.pressure, l.body_force) {
            (Some(t), None, None) => {
                let t = ctx.finite3(&format!("{key}.traction"), t)?;
                on_faces(ctx, &key, mesh, l.region.as_ref(), |area| {
                    scale(t, norm(area))
                })?
            }
            (None, Some(p), None) => {
                if !p.is_finite() {
                    return Err(ctx.err(format!("{key}.pressure"), format!("{p} must be finite")));
                }
                on_faces(ctx, &key, mesh, l.region.as_ref(), |area| scale(area, -p))?
            }
            (None, None, Some(b)) => {
                let b = ctx.finite3(&format!("{key}.body_force"), b)?;
                let picked = select(ctx, &format!("{key}.region"), rest, l.region.as_ref())?;
                let forces = picked
                    .iter()
                    .map(|&i| scale(b, volumes[i as usize]))
                    .collect();
                (picked, forces)
            }
            _ => {
                return Err(ctx.err(
                    &key,
                    "give exactly one of traction (Pa), pressure (Pa) and body_force (N/m^3)",
                ))
            }
        };
        out.push(RegionLoad {
            particles,
            forces,
            ramp,
            until,
        });
    }
    Ok(out)
}

/// The particles of the tets with rest boundary faces whose centroid lies in `region`, each
/// with the sum of `force(area)` over those faces, `area` the face's outward area vector
/// (m^2); none selected is an error naming `key`.
fn on_faces(
    ctx: &Ctx,
    key: &str,
    mesh: &TetMesh,
    region: Option<&Region>,
    force: impl Fn([f64; 3]) -> [f64; 3],
) -> Result<(Vec<u32>, Vec<[f64; 3]>), SceneError> {
    let x = mesh.positions();
    let (mut particles, mut forces) = (Vec::new(), Vec::new());
    for (t, (corners, across)) in mesh.tets().iter().zip(mesh.neighbours()).enumerate() {
        let mut sum = [0.0; 3];
        let mut any = false;
        for (face, &other) in FACE_CORNERS.iter().zip(across) {
            if other != NO_TET {
                continue;
            }
            let [a, b, c] = face.map(|k| x[corners[k] as usize]);
            let centroid = [0, 1, 2].map(|d| (a[d] + b[d] + c[d]) / 3.0);
            if region.is_some_and(|r| !r.contains(centroid)) {
                continue;
            }
            // FACE_CORNERS winds each face outward of a positively oriented tet
            let area = scale(cross(sub(b, a), sub(c, a)), 0.5);
            sum = add(sum, force(area));
            any = true;
        }
        if any {
            particles.push(t as u32);
            forces.push(sum);
        }
    }
    if particles.is_empty() {
        return Err(ctx.err(
            format!("{key}.region"),
            "selects no boundary face: no face of the surface has its centroid in the box",
        ));
    }
    Ok((particles, forces))
}
