//! Chen materials from the scene's `[[material]]` tables.

use std::f64::consts::PI;

use perifrac_physics::{ChenMaterial, FractureParams, YieldParams};

use crate::error::SceneError;
use crate::schema::{MaterialSpec, SceneFile};

use super::check::Ctx;
use super::defaults;

/// The scene's materials and the material id of every particle (rest barycentres `rest`, m):
/// material 0 everywhere, then each later material over the particles in its region.
pub(super) fn materials_by_region(
    ctx: &Ctx,
    f: &SceneFile,
    rest: &[[f64; 3]],
    horizon: f64,
) -> Result<(Vec<ChenMaterial>, Vec<u16>), SceneError> {
    let materials = f
        .material
        .iter()
        .enumerate()
        .map(|(i, m)| chen_material(ctx, i, m, horizon))
        .collect::<Result<Vec<_>, _>>()?;
    let mut ids = vec![0u16; rest.len()];
    for (k, m) in f.material.iter().enumerate().skip(1) {
        let Some(r) = m.region else { continue };
        let mut hit = 0;
        for (id, x) in ids.iter_mut().zip(rest) {
            if r.contains(*x) {
                *id = k as u16;
                hit += 1;
            }
        }
        if hit == 0 {
            return Err(ctx.err(
                format!("material[{k}].region"),
                "selects no particle (no tet barycentre inside the box)",
            ));
        }
    }
    Ok((materials, ids))
}

/// The Chen material of `material[i]`; `horizon` converts a yield strain to `Psi0`.
fn chen_material(
    ctx: &Ctx,
    i: usize,
    m: &MaterialSpec,
    horizon: f64,
) -> Result<ChenMaterial, SceneError> {
    let key = format!("material[{i}]");
    let mut mat = match (m.young, m.poisson, m.bulk_modulus, m.shear_modulus) {
        (Some(e), Some(nu), None, None) => {
            ctx.positive(&format!("{key}.young"), e, "Pa")?;
            if !(nu > -1.0 && nu < 0.5) {
                return Err(ctx.err(
                    format!("{key}.poisson"),
                    format!("{nu} must be in (-1, 0.5)"),
                ));
            }
            ChenMaterial::from_young_poisson(e, nu, m.density)
                .map_err(|e| ctx.err(&key, e.to_string()))?
        }
        (None, None, Some(k), Some(mu)) => {
            ctx.positive(&format!("{key}.bulk_modulus"), k, "Pa")?;
            ctx.positive(&format!("{key}.shear_modulus"), mu, "Pa")?;
            ChenMaterial::elastic(k, mu, m.density)
        }
        _ => {
            return Err(ctx.err(
                &key,
                "give the elasticity as young + poisson, or as bulk_modulus + shear_modulus",
            ))
        }
    };
    if let Some(s) = m.s_crit {
        if s.is_nan() || s <= 0.0 {
            return Err(ctx.err(
                format!("{key}.s_crit"),
                format!("{s} must be positive (inf: no fracture)"),
            ));
        }
        let alpha = ctx.non_negative(&format!("{key}.alpha"), m.alpha.unwrap_or(0.0))?;
        if s.is_finite() {
            mat.fracture = Some(FractureParams { s_crit: s, alpha });
        }
    } else if m.alpha.is_some() {
        return Err(ctx.err(
            format!("{key}.alpha"),
            "alpha scales the fracture threshold: give s_crit too",
        ));
    }
    let psi0 = match (m.yield_psi0, m.yield_strain) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(&key, "give either yield_psi0 or yield_strain, not both"))
        }
        (Some(p), None) => Some(ctx.positive(&format!("{key}.yield_psi0"), p, "")?),
        (None, Some(eps)) => {
            let eps = ctx.positive(&format!("{key}.yield_strain"), eps, "")?;
            // A_dev = 4 omega b ed with omega = delta / r and ed = eps r: |A_dev| = 4 delta b eps.
            let b = 15.0 * mat.shear_modulus / (2.0 * PI * horizon.powi(5));
            let a = 4.0 * horizon * b * eps;
            Some(0.5 * a * a)
        }
        (None, None) => None,
    };
    match (psi0, m.plastic_cap) {
        (Some(psi0), cap) => {
            let cap = cap.unwrap_or(defaults::PLASTIC_CAP);
            ctx.positive(&format!("{key}.plastic_cap"), cap, "")?;
            mat.plasticity = Some(YieldParams {
                psi0,
                gamma_ratio: cap,
            });
        }
        (None, Some(_)) => {
            return Err(ctx.err(
                format!("{key}.plastic_cap"),
                "caps plastic flow: give yield_strain or yield_psi0 too",
            ))
        }
        (None, None) => {}
    }
    if let Some(g) = m.anisotropy {
        for (k, &s) in g.iter().enumerate() {
            ctx.positive(&format!("{key}.anisotropy[{k}]"), s, "")?;
        }
        mat.anisotropy = Some([[g[0], 0.0, 0.0], [0.0, g[1], 0.0], [0.0, 0.0, g[2]]]);
    }
    mat.validate(i).map_err(|e| ctx.err(&key, e.to_string()))?;
    Ok(mat)
}
