//! Xu materials from the scene's `[[material]]` tables (`model = "xu"`).

use std::collections::BTreeMap;

use perifrac_physics::{Basis, Curve, XuAnisotropy, XuMaterial, XuModuli};

use crate::error::SceneError;
use crate::schema::{Energy, MaterialSpec, Moduli, XuKeys};

use super::check::Ctx;
use super::material::{axes, density, elasticity, fracture};

/// The Xu material of `material[i]` with Xu's `keys`.
pub(super) fn xu_material(
    ctx: &Ctx,
    i: usize,
    m: &MaterialSpec,
    keys: &XuKeys,
) -> Result<XuMaterial, SceneError> {
    let key = format!("material[{i}]");
    let named = match keys.energy {
        None | Some(Energy::NeoHookean) => Curve::NeoHookean,
        Some(Energy::Linear) => Curve::Linear,
        Some(Energy::Stvk) => Curve::Stvk,
    };
    let g = custom(ctx, &format!("{key}.g"), keys.g.as_ref())?.unwrap_or_else(|| named.clone());
    let h = custom(ctx, &format!("{key}.h"), keys.h.as_ref())?.unwrap_or(named);
    let rule = match keys.moduli {
        None | Some(Moduli::Consistent) => XuModuli::Consistent,
        Some(Moduli::Paper) => XuModuli::Paper,
    };
    let (kappa, mu) = elasticity(ctx, i, m)?;
    let young = 9.0 * kappa * mu / (3.0 * kappa + mu);
    let poisson = (3.0 * kappa - 2.0 * mu) / (2.0 * (3.0 * kappa + mu));
    let mut mat = XuMaterial::from_young_poisson(young, poisson, density(ctx, i, m)?, g, h, rule)
        .map_err(|e| ctx.err(&key, e.to_string()))?;
    mat.fracture = fracture(ctx, i, m)?;
    let frame = axes(ctx, i, m)?;
    if let Some(s) = m.anisotropy {
        for (k, &v) in s.iter().enumerate() {
            ctx.positive(&format!("{key}.anisotropy[{k}]"), v, "")?;
        }
        mat.anisotropy = Some(XuAnisotropy {
            axes: frame,
            stretch: s,
        });
    }
    mat.validate(i).map_err(|e| ctx.err(&key, e.to_string()))?;
    Ok(mat)
}

/// A custom curve from `{ basis = coefficient }`, `None` when not given.
fn custom(
    ctx: &Ctx,
    key: &str,
    terms: Option<&BTreeMap<String, f64>>,
) -> Result<Option<Curve>, SceneError> {
    let Some(terms) = terms else { return Ok(None) };
    let mut out = Vec::with_capacity(terms.len());
    for (name, &c) in terms {
        let b = Basis::parse(name).ok_or_else(|| {
            ctx.err(
                format!("{key}.{name}"),
                "not a basis: expected A1 .. A12 or B1 .. B12",
            )
        })?;
        if !c.is_finite() {
            return Err(ctx.err(format!("{key}.{name}"), format!("{c} must be finite")));
        }
        out.push((b, c));
    }
    let curve = Curve::Custom(out);
    curve
        .validate(key)
        .map_err(|e| ctx.err(key, e.to_string()))?;
    Ok(Some(curve))
}

/// Young's modulus (Pa) an Xu material has in the small-strain limit of a full family (see
/// [`XuModuli::Consistent`]): used to scale contact stiffness, as Chen's `E` is.
pub(super) fn young_of(m: &XuMaterial) -> f64 {
    // small-strain shear G = mu h''(1) / 15 and Lame lambda_L = lambda g''(1) / 9 + G
    let shear = m.mu * m.h.rest_curvature() / 15.0;
    let lame = m.lambda * m.g.rest_curvature() / 9.0 + shear;
    shear * (3.0 * lame + 2.0 * shear) / (lame + shear)
}
