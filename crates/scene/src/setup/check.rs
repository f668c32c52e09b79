//! Checks of every scene value that does not need the mesh, with the key path in each message.

use std::path::Path;

use crate::error::SceneError;
use crate::schema::{
    BallSpec, ExplicitKeys, GroundSpec, Integrator, Region, SceneFile, VelocitySpec,
};

use super::defaults;
use perifrac_physics::math::norm;

/// Densest value a material or ball may have (kg/m^3): over 40 times osmium's 22,590, far
/// beyond any solid, so a larger one is a unit slip; it keeps masses and momenta far from
/// overflow.
pub(super) const MAX_DENSITY: f64 = 1e6;

/// `v` for a message: Rust's shortest digits that read back, with an exponent where the plain
/// form would be long (`1e300`, not a 1 and 300 zeros; `2200`, not `2.2e3`).
pub(crate) fn show(v: f64) -> String {
    let plain = format!("{v}");
    let exponent = format!("{v:e}");
    if plain.len() > exponent.len() + 3 {
        exponent
    } else {
        plain
    }
}

/// The scene file a message names.
pub(crate) struct Ctx<'a> {
    /// The scene file.
    pub(crate) file: &'a Path,
}

impl Ctx<'_> {
    /// The physics crate refused something; the message names the scene file.
    pub(crate) fn physics(&self, cause: perifrac_physics::PhysicsError) -> SceneError {
        SceneError::Physics {
            file: self.file.to_path_buf(),
            cause,
        }
    }
    pub(crate) fn err(&self, key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::invalid(self.file, key, message)
    }
    pub(crate) fn positive(&self, key: &str, v: f64, unit: &str) -> Result<f64, SceneError> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!(
                    "{}{}{unit} must be positive and finite",
                    show(v),
                    if unit.is_empty() { "" } else { " " }
                ),
            ))
        }
    }
    /// A density (kg/m^3) at `key`: positive, finite and at most [`MAX_DENSITY`].
    pub(crate) fn density(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        let v = self.positive(key, v, "kg/m^3")?;
        if v > MAX_DENSITY {
            return Err(self.err(
                key,
                format!(
                    "{} kg/m^3 is above {}, over 40 times osmium's, the densest element (the \
                     scene's units are SI)",
                    show(v),
                    show(MAX_DENSITY)
                ),
            ));
        }
        Ok(v)
    }
    pub(crate) fn non_negative(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(self.err(key, format!("{} must be finite and >= 0", show(v))))
        }
    }
    pub(crate) fn finite3(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(v)
        } else {
            Err(self.err(key, format!("{v:?} must be finite")))
        }
    }
    pub(crate) fn direction(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        let v = self.finite3(key, v)?;
        let n = norm(v);
        if n < 1e-12 {
            return Err(self.err(key, format!("{v:?} is not a direction (zero length)")));
        }
        Ok(v.map(|c| c / n))
    }
    pub(crate) fn region(&self, key: &str, r: &Region) -> Result<(), SceneError> {
        self.finite3(&format!("{key}.min"), r.min)?;
        self.finite3(&format!("{key}.max"), r.max)?;
        if (0..3).any(|k| r.min[k] > r.max[k]) {
            return Err(self.err(
                key,
                format!("min {:?} exceeds max {:?} on some axis", r.min, r.max),
            ));
        }
        Ok(())
    }
}

/// Checks the settings that need neither the mesh nor the built materials, so that a typo fails
/// before meshing; the material moduli, fracture and anisotropy settings are checked when the
/// materials are built (`material.rs`), the time step once the stable limit is known.
pub(super) fn check_settings(ctx: &Ctx, f: &SceneFile) -> Result<(), SceneError> {
    let sim = &f.simulation;
    ctx.positive("simulation.duration", sim.duration, "s")?;
    if let Some(k) = sim.horizon_factor {
        ctx.positive("simulation.horizon_factor", k, "")?;
        if k > 6.0 {
            return Err(ctx.err(
                "simulation.horizon_factor",
                format!("{} is far above the usual 1.0 to 2.0 (at most 6)", show(k)),
            ));
        }
    }
    if let Integrator::Explicit(ExplicitKeys {
        safety: Some(s), ..
    }) = sim.integrator
    {
        if !(s > 0.0 && s <= 1.0) {
            return Err(ctx.err(
                "simulation.safety",
                format!("{} must be in (0, 1]", show(s)),
            ));
        }
    }
    // A word other than "auto" is refused here, before the mesh and the stable step are made.
    super::step::fixed_step(ctx, sim)?;
    if let Some(g) = sim.gravity {
        ctx.finite3("simulation.gravity", g)?;
    }
    if let Some(d) = sim.damping {
        ctx.non_negative("simulation.damping", d)?;
    }
    if let Some(c) = sim.contact_radius {
        ctx.positive("simulation.contact_radius", c, "")?;
    }
    if f.material.is_empty() {
        return Err(ctx.err("material", "at least one [[material]] is needed"));
    }
    for (i, m) in f.material.iter().enumerate() {
        let key = format!("material[{i}]");
        match (i, &m.region) {
            (0, Some(_)) => {
                return Err(ctx.err(
                    "material[0].region",
                    "the first material is the default everywhere; give regions to later ones",
                ))
            }
            (i, None) if i > 0 => {
                return Err(ctx.err(
                    format!("{key}.region"),
                    "materials after the first need a region",
                ))
            }
            (_, Some(r)) => ctx.region(&format!("{key}.region"), r)?,
            _ => {}
        }
        super::material::density(ctx, i, m)?;
    }
    check_colliders(ctx, &f.ground, &f.ball)?;
    for (i, a) in f.anchor.iter().enumerate() {
        ctx.region(&format!("anchor[{i}].region"), &a.region)?;
        if let Some(v) = a.velocity {
            ctx.finite3(&format!("anchor[{i}].velocity"), v)?;
        }
        if let Some(w) = a.angular {
            ctx.finite3(&format!("anchor[{i}].angular"), w)?;
        }
        match (a.center, a.angular) {
            (Some(c), Some(_)) => {
                ctx.finite3(&format!("anchor[{i}].center"), c)?;
            }
            (Some(_), None) => {
                return Err(ctx.err(
                    format!("anchor[{i}].center"),
                    "is the centre of a rotation: give angular too",
                ))
            }
            _ => {}
        }
        if let Some(t) = a.until {
            ctx.non_negative(&format!("anchor[{i}].until"), t)?;
        }
    }
    check_velocities(ctx, &f.velocity)?;
    for (i, p) in f.precrack.iter().enumerate() {
        let key = format!("precrack[{i}]");
        ctx.finite3(&format!("{key}.point"), p.point)?;
        ctx.direction(&format!("{key}.normal"), p.normal)?;
        ctx.region(&format!("{key}.region"), &p.region)?;
    }
    if f.output.frames == Some(0) {
        return Err(ctx.err("output.frames", "must be at least 1"));
    }
    check_cache(ctx, f.output.usd, f.output.usd_pieces, f.output.fps)
}

/// Checks the USD cache's `[output]` keys: `fps` positive and at most [`MAX_FPS`],
/// `usd_pieces` only with `usd`.
pub(crate) fn check_cache(
    ctx: &Ctx,
    usd: Option<bool>,
    usd_pieces: Option<bool>,
    fps: Option<f64>,
) -> Result<(), SceneError> {
    if let Some(fps) = fps {
        ctx.positive("output.fps", fps, "")?;
        if fps > MAX_FPS {
            return Err(ctx.err(
                "output.fps",
                format!("{fps} frames per second is more than {MAX_FPS}"),
            ));
        }
    }
    if usd_pieces == Some(true) && usd != Some(true) {
        return Err(ctx.err(
            "output.usd_pieces",
            "lays out the USD cache, which is written only with usd = true",
        ));
    }
    Ok(())
}

/// Checks the `[[ground]]` and `[[ball]]` tables: finite points and centres, unit-able normals,
/// positive radii, one of mass or density, usable contact coefficients.
pub(crate) fn check_colliders(
    ctx: &Ctx,
    grounds: &[GroundSpec],
    balls: &[BallSpec],
) -> Result<(), SceneError> {
    for (i, gr) in grounds.iter().enumerate() {
        let key = format!("ground[{i}]");
        if let Some(p) = gr.point {
            ctx.finite3(&format!("{key}.point"), p)?;
        }
        if let Some(nrm) = gr.normal {
            ctx.direction(&format!("{key}.normal"), nrm)?;
        }
        check_contact(
            ctx,
            &key,
            gr.stiffness_factor,
            gr.damping_ratio,
            gr.friction,
        )?;
    }
    for (i, b) in balls.iter().enumerate() {
        let key = format!("ball[{i}]");
        ctx.finite3(&format!("{key}.center"), b.center)?;
        ctx.positive(&format!("{key}.radius"), b.radius, "m")?;
        if let Some(v) = b.velocity {
            ctx.finite3(&format!("{key}.velocity"), v)?;
        }
        if b.mass.is_some() && b.density.is_some() {
            return Err(ctx.err(&key, "give either mass or density, not both"));
        }
        if let Some(t) = b.until {
            ctx.non_negative(&format!("{key}.until"), t)?;
            if b.mass.is_some() || b.density.is_some() {
                return Err(ctx.err(
                    format!("{key}.until"),
                    "a ball with a mass moves under its forces: only a kinematic ball (no mass \
                     or density) can be stopped",
                ));
            }
        }
        if let Some(m) = b.mass {
            ctx.positive(&format!("{key}.mass"), m, "kg")?;
        }
        if let Some(d) = b.density {
            ctx.density(&format!("{key}.density"), d)?;
            // The mass is density times volume: name the value that makes it overflow.
            let volume = 4.0 / 3.0 * std::f64::consts::PI * b.radius.powi(3);
            if !volume.is_finite() {
                return Err(ctx.err(
                    format!("{key}.radius"),
                    format!(
                        "{} m is too large: the ball's volume overflows",
                        show(b.radius)
                    ),
                ));
            }
            if !(d * volume).is_finite() {
                return Err(ctx.err(
                    format!("{key}.density"),
                    format!(
                        "{} kg/m^3 over a ball of radius {} m gives a mass that overflows",
                        show(d),
                        show(b.radius)
                    ),
                ));
            }
        }
        check_contact(ctx, &key, b.stiffness_factor, b.damping_ratio, b.friction)?;
    }
    Ok(())
}

/// Checks the `[[velocity]]` tables: regions and finite vectors.
pub(crate) fn check_velocities(ctx: &Ctx, velocities: &[VelocitySpec]) -> Result<(), SceneError> {
    for (i, v) in velocities.iter().enumerate() {
        let key = format!("velocity[{i}]");
        if let Some(r) = &v.region {
            ctx.region(&format!("{key}.region"), r)?;
        }
        for (name, x) in [
            ("linear", v.linear),
            ("angular", v.angular),
            ("center", v.center),
        ] {
            if let Some(x) = x {
                ctx.finite3(&format!("{key}.{name}"), x)?;
            }
        }
    }
    Ok(())
}

/// The highest playback rate a scene may ask for (frames per second): far above any film or
/// game rate, low enough that a frame is never shorter than a millisecond.
pub const MAX_FPS: f64 = 1000.0;

/// A collider's contact coefficients with the defaults filled in: `(stiffness factor, damping
/// ratio, friction)`, all dimensionless.
pub(crate) fn contact_coefficients(
    stiffness: Option<f64>,
    damping: Option<f64>,
    friction: Option<f64>,
) -> (f64, f64, f64) {
    (
        stiffness.unwrap_or(defaults::STIFFNESS_FACTOR),
        damping.unwrap_or(defaults::DAMPING_RATIO),
        friction.unwrap_or(defaults::FRICTION),
    )
}

/// Refuses a collider's contact coefficients (see [`contact_coefficients`]) that are not
/// usable: a stiffness factor that is not positive, a negative damping ratio or friction.
fn check_contact(
    ctx: &Ctx,
    key: &str,
    stiffness: Option<f64>,
    damping: Option<f64>,
    friction: Option<f64>,
) -> Result<(), SceneError> {
    let (k, d, mu) = contact_coefficients(stiffness, damping, friction);
    ctx.positive(&format!("{key}.stiffness_factor"), k, "")?;
    ctx.non_negative(&format!("{key}.damping_ratio"), d)?;
    ctx.non_negative(&format!("{key}.friction"), mu)?;
    Ok(())
}
