//! Contact between the particles of the body that share no intact bond (`[simulation]
//! self_contact`), with each particle's stiffness from its own material.

use perifrac_contact::{SelfContact, SelfContactParams};

use crate::error::SceneError;
use crate::schema::SimulationSpec;

use super::check::Ctx;
use super::material::Materials;

/// Default penalty stiffness factor on `E r_p`, a quarter of the colliders': a particle may
/// touch twelve others at once, so the stable step makes room for twelve springs. On the
/// default wall a factor of 1 halves the step (the deepest overlap is 2.0% of a contact
/// distance), 0.25 shortens it to 0.76 of the step without self contact (5.8%).
const STIFFNESS_FACTOR: f64 = 0.25;

/// Self contact when the scene asks for it, or by default when any material can break:
/// particles at `rest` (m) with contact `radii` (m) and material ids `ids` into `materials`;
/// `None` when it is off.
pub(super) fn build(
    ctx: &Ctx,
    sim: &SimulationSpec,
    materials: &Materials,
    ids: &[u16],
    rest: &[[f64; 3]],
    radii: &[f64],
) -> Result<Option<SelfContact>, SceneError> {
    let keys = [
        ("self_contact_stiffness", sim.self_contact_stiffness),
        ("self_contact_distance", sim.self_contact_distance),
        ("self_contact_damping", sim.self_contact_damping),
        ("self_contact_friction", sim.self_contact_friction),
    ];
    // On by default when something can break: fragments and crack faces then meet.
    if !sim.self_contact.unwrap_or(materials.any_breaks()) {
        if let Some((key, _)) = keys.iter().find(|(_, v)| v.is_some()) {
            let why = match sim.self_contact {
                Some(false) => "applies to self contact, which self_contact = false turns off",
                _ => "applies to self contact, off where no material can break: set self_contact = true",
            };
            return Err(ctx.err(format!("simulation.{key}"), why));
        }
        return Ok(None);
    }
    let base = SelfContactParams::default();
    let factor = match sim.self_contact_stiffness {
        // 0 measures how deep unbonded particles pass through each other without pushing.
        Some(k) => ctx.non_negative("simulation.self_contact_stiffness", k)?,
        None => STIFFNESS_FACTOR,
    };
    let distance_factor = match sim.self_contact_distance {
        Some(d) => ctx.positive("simulation.self_contact_distance", d, "")?,
        None => base.distance_factor,
    };
    let damping_ratio = match sim.self_contact_damping {
        Some(d) => ctx.non_negative("simulation.self_contact_damping", d)?,
        None => base.damping_ratio,
    };
    let friction = match sim.self_contact_friction {
        Some(mu) => ctx.non_negative("simulation.self_contact_friction", mu)?,
        None => base.friction,
    };
    let stiffness = ids
        .iter()
        .zip(radii)
        .map(|(&id, &r)| factor * materials.young(id as usize) * r)
        .collect();
    let params = SelfContactParams {
        distance_factor,
        damping_ratio,
        friction,
        ..base
    };
    SelfContact::new(rest.to_vec(), radii.to_vec(), stiffness, params)
        .map(Some)
        .map_err(|e| ctx.err("simulation.self_contact", e.to_string()))
}
