//! Colliders from the scene's `[[ground]]` and `[[ball]]` tables.

use std::f64::consts::PI;

use perifrac_contact::{BallDesc, BallMotion, Colliders, ContactParams, GroundDesc};

use perifrac_topology::TetMesh;

use crate::error::SceneError;
use crate::schema::{BallSpec, GroundSpec};

use super::check::{contact_coefficients, Ctx};
use super::material::Materials;

/// What the colliders add to the highest frequency of the system, for the stable step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct ContactStiffness {
    /// Largest `omega^2` (1/s^2) of a particle on the colliders: the sum of their penalty
    /// stiffnesses (a particle can touch every collider at once, squeezed between a ball and
    /// the ground say, never one twice) times the largest stiffness scale over mass.
    pub collider_omega2: f64,
    /// Largest `omega^2` (1/s^2) of a dynamic ball on the particles it can touch at once,
    /// `n k / M` with `n = 4 ((R + r) / r)^2` (as many contact spheres of radius `r` as fit
    /// around it): a light ball rings faster than the particles it hits.
    pub ball_omega2: f64,
    /// Largest `omega^2` (1/s^2) contact between particles adds
    /// (`perifrac_contact::SelfContact::max_omega2`); 0 without it.
    pub self_omega2: f64,
}

/// Per particle, the factor on the colliders' stiffness that makes it `factor E_i r_i` (its
/// material's Young's modulus `E_i`, Pa, and its contact radius `r_i`, m) when the colliders
/// are built at `young` (Pa) and `radius` (m): `E_i r_i / (young radius)`.
pub(super) fn stiffness_scale(
    materials: &Materials,
    ids: &[u16],
    radii: &[f64],
    young: f64,
    radius: f64,
) -> Vec<f64> {
    let reference = young * radius;
    ids.iter()
        .zip(radii)
        .map(|(&id, &r)| {
            let s = materials.young(id as usize) * r / reference;
            if s.is_finite() {
                s
            } else {
                1.0
            }
        })
        .collect()
}

/// The colliders and their stiffness, or `None` when the scene has none. `young` (Pa) and
/// `radius` (mean contact radius, m) scale the penalty stiffness of a reference particle;
/// particle `i` gets `scale[i]` times it, and has mass `masses[i]` (kg).
#[allow(clippy::too_many_arguments)] // the scene's two tables and the particles' scales
pub(crate) fn build_colliders(
    ctx: &Ctx,
    ground: &[GroundSpec],
    ball: &[BallSpec],
    young: f64,
    radius: f64,
    gravity: [f64; 3],
    scale: &[f64],
    masses: &[f64],
) -> Result<Option<(Colliders, ContactStiffness)>, SceneError> {
    if ground.is_empty() && ball.is_empty() {
        return Ok(None);
    }
    // The coefficients were checked with the rest of the settings (check::check_settings).
    let params = |factor, damping, friction| {
        let (k, d, mu) = contact_coefficients(factor, damping, friction);
        ContactParams::from_material(young, radius, k, d, mu)
    };
    let mut stiffness = ContactStiffness::default();
    let scale_max = scale.iter().cloned().fold(0.0, f64::max);
    let scale_over_mass = scale
        .iter()
        .zip(masses)
        .map(|(&s, &m)| if m > 0.0 { s / m } else { 0.0 })
        .fold(0.0, f64::max);
    let grounds: Vec<GroundDesc> = ground
        .iter()
        .map(|g| GroundDesc {
            point: g.point.unwrap_or([0.0; 3]),
            normal: g.normal.unwrap_or([0.0, 0.0, 1.0]),
            params: params(g.stiffness_factor, g.damping_ratio, g.friction),
        })
        .collect();
    let mut balls = Vec::new();
    for (i, b) in ball.iter().enumerate() {
        let velocity = b.velocity.unwrap_or([0.0; 3]);
        let mass = b
            .mass
            .or(b.density.map(|rho| rho * 4.0 / 3.0 * PI * b.radius.powi(3)));
        let motion = match mass {
            Some(mass) => BallMotion::Dynamic { mass, velocity },
            None => BallMotion::Kinematic { velocity },
        };
        let params = params(b.stiffness_factor, b.damping_ratio, b.friction);
        if let Some(m) = mass {
            let touching = 4.0 * ((b.radius + radius) / radius).powi(2);
            let omega2 = touching * scale_max * params.stiffness / m;
            if !omega2.is_finite() {
                return Err(ctx.err(
                    format!("ball[{i}].radius"),
                    format!(
                        "{} m against contact spheres of {:.3e} m: the contacts the ball can \
                         take at once, times their stiffness over its mass, overflow",
                        super::check::show(b.radius),
                        radius
                    ),
                ));
            }
            stiffness.ball_omega2 = stiffness.ball_omega2.max(omega2);
        }
        balls.push(BallDesc {
            center: b.center,
            radius: b.radius,
            motion,
            params,
        });
    }
    let sum: f64 = grounds
        .iter()
        .map(|g| g.params.stiffness)
        .chain(balls.iter().map(|b| b.params.stiffness))
        .sum();
    stiffness.collider_omega2 = sum * scale_over_mass;
    Colliders::new(grounds, balls, gravity)
        .map(|c| Some((c, stiffness)))
        .map_err(|e| ctx.err("ball/ground", e.to_string()))
}

/// Refuses colliders that start inside the object: a particle's contact sphere (centre
/// `rest`, radius `radii`, m) reaching below a ground or into a ball, or a ball centre inside
/// the mesh's closed boundary.
pub(super) fn check_placement(
    ctx: &Ctx,
    colliders: &Colliders,
    mesh: &TetMesh,
    rest: &[[f64; 3]],
    radii: &[f64],
) -> Result<(), SceneError> {
    colliders.check_clear(rest, radii).map_err(|e| {
        ctx.err(
            "ball/ground",
            format!("collider inside the object at the start: {e}"),
        )
    })?;
    let surface = mesh.surface();
    let inside = colliders
        .balls_inside_surface(&surface.vertices, &surface.faces)
        .map_err(|e| ctx.err("ball", e.to_string()))?;
    if let Some(&b) = inside.first() {
        return Err(ctx.err(
            format!("ball[{b}].center"),
            "collider inside the object at the start (the centre is inside the mesh)",
        ));
    }
    Ok(())
}
