//! Materials from the scene's `[[material]]` tables: Chen's (the default) or Xu's, one model
//! for the whole scene.

use std::f64::consts::PI;

use perifrac_physics::crack_energy::{chen_crack_energy, solve_thresholds};
use perifrac_physics::math::Mat3;
use perifrac_physics::{
    ChenMaterial, Discretization, FractureParams, XuMaterial, XuModel, YieldParams,
};

use crate::error::SceneError;
use crate::schema::{ChenCorrection, ChenKeys, ChenSettings, MaterialSpec, Model, SceneFile};

use super::check::Ctx;
use super::defaults;
use super::ModelKind;

/// The scene's materials, all of one model.
pub(super) enum Materials {
    /// Chen's elastoplastic model.
    Chen(Vec<ChenMaterial>),
    /// Xu's hyperelastic model.
    Xu(Vec<XuMaterial>),
}

impl Materials {
    /// Largest Young's modulus (Pa), which scales the contact stiffness.
    pub(super) fn max_young(&self) -> f64 {
        match self {
            Materials::Chen(m) => m.iter().map(|m| m.young()).fold(0.0, f64::max),
            Materials::Xu(m) => m
                .iter()
                .map(super::xu_material::young_of)
                .fold(0.0, f64::max),
        }
    }

    /// Young's modulus (Pa) of material `k` (0 for an index past the list).
    pub(super) fn young(&self, k: usize) -> f64 {
        match self {
            Materials::Chen(m) => m.get(k).map_or(0.0, |m| m.young()),
            Materials::Xu(m) => m.get(k).map_or(0.0, super::xu_material::young_of),
        }
    }

    /// Whether any material can break (has fracture parameters).
    pub(super) fn any_breaks(&self) -> bool {
        match self {
            Materials::Chen(m) => m.iter().any(|m| m.fracture.is_some()),
            Materials::Xu(m) => m.iter().any(|m| m.fracture.is_some()),
        }
    }

    /// The model's name in the scene file.
    pub(super) fn kind(&self) -> ModelKind {
        match self {
            Materials::Chen(_) => ModelKind::Chen,
            Materials::Xu(_) => ModelKind::Xu,
        }
    }
}

/// The scene's materials and the material id of every particle (rest barycentres `rest`, m):
/// material 0 everywhere, then each later material over the particles in its region.
pub(super) fn materials_by_region(
    ctx: &Ctx,
    f: &SceneFile,
    rest: &[[f64; 3]],
    horizon: f64,
) -> Result<(Materials, Vec<u16>), SceneError> {
    // the parser gives every material the first one's model
    let mixed = |i: usize| ctx.err(format!("material[{i}].model"), "one model per scene");
    let materials = match scene_model(f) {
        ModelKind::Chen => Materials::Chen(
            f.material
                .iter()
                .enumerate()
                .map(|(i, m)| match &m.model {
                    Model::Chen(keys) => chen_material(ctx, i, m, keys, horizon),
                    Model::Xu(_) => Err(mixed(i)),
                })
                .collect::<Result<Vec<_>, _>>()?,
        ),
        ModelKind::Xu => Materials::Xu(
            f.material
                .iter()
                .enumerate()
                .map(|(i, m)| match &m.model {
                    Model::Xu(keys) => super::xu_material::xu_material(ctx, i, m, keys),
                    Model::Chen(_) => Err(mixed(i)),
                })
                .collect::<Result<Vec<_>, _>>()?,
        ),
    };
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

/// The scene's model: the first material's (Chen's when there is none).
pub(super) fn scene_model(f: &SceneFile) -> ModelKind {
    f.material
        .first()
        .map_or(ModelKind::Chen, |m| m.model.kind())
}

/// The stiffest modulus a material may have (Pa): a thousand times diamond's Young's modulus
/// (about 1.1e12 Pa). Above it a value is a unit mistake, and products such as the contact
/// stiffness (a modulus times a length) or `9 kappa mu` overflow for values near `f64::MAX`.
pub(super) const MAX_MODULUS: f64 = 1e15;

/// A modulus (Pa) at `key`: positive, finite and at most [`MAX_MODULUS`].
fn modulus(ctx: &Ctx, key: &str, v: f64) -> Result<f64, SceneError> {
    ctx.positive(key, v, "Pa")?;
    if v > MAX_MODULUS {
        return Err(ctx.err(
            key,
            format!(
                "{} Pa is above {MAX_MODULUS:e} Pa, a thousand times diamond's stiffness (the \
                 scene's units are SI: Pa, not kPa)",
                super::check::show(v)
            ),
        ));
    }
    Ok(v)
}

/// `(kappa, mu)` (Pa) of `material[i]` from `young` + `poisson` or `bulk_modulus` +
/// `shear_modulus`, each at most [`MAX_MODULUS`].
pub(super) fn elasticity(ctx: &Ctx, i: usize, m: &MaterialSpec) -> Result<(f64, f64), SceneError> {
    let key = format!("material[{i}]");
    match (m.young, m.poisson, m.bulk_modulus, m.shear_modulus) {
        (Some(e), Some(nu), None, None) => {
            modulus(ctx, &format!("{key}.young"), e)?;
            if !(nu > -1.0 && nu < 0.5) {
                return Err(ctx.err(
                    format!("{key}.poisson"),
                    format!("{nu} must be in (-1, 0.5)"),
                ));
            }
            Ok((e / (3.0 * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu))))
        }
        (None, None, Some(k), Some(mu)) => {
            modulus(ctx, &format!("{key}.bulk_modulus"), k)?;
            modulus(ctx, &format!("{key}.shear_modulus"), mu)?;
            Ok((k, mu))
        }
        _ => Err(ctx.err(
            &key,
            "give the elasticity as young + poisson, or as bulk_modulus + shear_modulus",
        )),
    }
}

/// The density (kg/m^3) of `material[i]`, given or from its preset.
pub(super) fn density(ctx: &Ctx, i: usize, m: &MaterialSpec) -> Result<f64, SceneError> {
    let key = format!("material[{i}].density");
    match m.density {
        Some(d) => ctx.density(&key, d),
        None => Err(ctx.err(key, "missing: give the density (kg/m^3) or a preset")),
    }
}

/// The fracture criterion of `material[i]`, if it breaks. A threshold from `fracture_energy`
/// (J/m^2) is set once the families are built ([`thresholds_from_energy`]); until then its
/// `s_crit` is 1.
pub(super) fn fracture(
    ctx: &Ctx,
    i: usize,
    m: &MaterialSpec,
) -> Result<Option<FractureParams>, SceneError> {
    let key = format!("material[{i}]");
    let given = [m.s_crit, m.fracture_energy, m.tensile_strength]
        .iter()
        .filter(|v| v.is_some())
        .count();
    if given > 1 {
        return Err(ctx.err(
            &key,
            "give one of s_crit, fracture_energy (J/m^2) and tensile_strength (Pa): each sets \
             the same threshold",
        ));
    }
    let strength = match m.tensile_strength {
        Some(t) if t.is_nan() || t <= 0.0 => {
            return Err(ctx.err(
                format!("{key}.tensile_strength"),
                format!("{t} Pa must be positive (inf: no fracture)"),
            ))
        }
        // s_crit is the strain at which the longest bonds along a uniform tension break
        Some(t) => {
            let (k, mu) = elasticity(ctx, i, m)?;
            Some(t * (3.0 * k + mu) / (9.0 * k * mu))
        }
        None => None,
    };
    let s_crit = match (m.s_crit.or(strength), m.fracture_energy) {
        // two at once were refused above
        (Some(s), _) => {
            if s.is_nan() || s <= 0.0 {
                return Err(ctx.err(
                    format!("{key}.s_crit"),
                    format!("{s} must be positive (inf: no fracture)"),
                ));
            }
            s
        }
        (None, Some(g)) => {
            if g.is_nan() || g <= 0.0 {
                return Err(ctx.err(
                    format!("{key}.fracture_energy"),
                    format!("{g} J/m^2 must be positive (inf: no fracture)"),
                ));
            }
            if g.is_finite() {
                1.0
            } else {
                g
            }
        }
        (None, None) if m.alpha.is_some() => {
            return Err(ctx.err(
                format!("{key}.alpha"),
                "alpha scales the fracture threshold: give s_crit, fracture_energy or \
                 tensile_strength too",
            ))
        }
        (None, None) => return Ok(None),
    };
    let alpha = ctx.non_negative(&format!("{key}.alpha"), m.alpha.unwrap_or(0.0))?;
    Ok(s_crit
        .is_finite()
        .then_some(FractureParams { s_crit, alpha }))
}

/// A threshold that `fracture_energy` set: the material, its fracture energy (J/m^2) and the
/// `s_crit` (1) it gives on the scene's families.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FromEnergy {
    /// The material's index.
    pub material: usize,
    /// Its fracture energy `G_c` (J/m^2).
    pub fracture_energy: f64,
    /// The threshold that costs `G_c` a unit area of crack on these families (1).
    pub s_crit: f64,
}

/// The finite fracture energies (J/m^2) of `f`'s materials, `None` where a material gives none.
fn energies(f: &SceneFile) -> Vec<Option<f64>> {
    f.material
        .iter()
        .map(|m| m.fracture_energy.filter(|g| g.is_finite()))
        .collect()
}

/// Sets the threshold of every Chen material of `f` that gives a finite `fracture_energy`:
/// `s_crit = sqrt(G_c / G_1)`, where `G_1` is the crack energy at `s_crit = 1` on `disc`'s
/// families (physics' `crack_energy`), with the scalar correction of the constants unless the
/// scene asks for none. Xu's thresholds are set on the built model ([`xu_thresholds_from_energy`]).
pub(super) fn thresholds_from_energy(
    f: &SceneFile,
    materials: &mut Materials,
    disc: &Discretization,
) -> Vec<FromEnergy> {
    let Materials::Chen(mats) = materials else {
        return Vec::new();
    };
    let energies = energies(f);
    if energies.iter().all(Option::is_none) {
        return Vec::new();
    }
    let calibrated = !matches!(
        f.simulation.model,
        Model::Chen(ChenSettings {
            correction: Some(ChenCorrection::None),
            ..
        })
    );
    let moduli: Vec<(f64, f64)> = mats
        .iter()
        .map(|m| (m.bulk_modulus, m.shear_modulus))
        .collect();
    let unit = chen_crack_energy(disc, &moduli, calibrated);
    let mut set = Vec::new();
    for (k, (mat, energy)) in mats.iter_mut().zip(&energies).enumerate() {
        let (Some(g), Some(fracture)) = (energy, mat.fracture.as_mut()) else {
            continue;
        };
        let g1 = unit.get(k).copied().unwrap_or(0.0);
        // a material with no particle never breaks: its threshold does not matter
        fracture.s_crit = if g1 > 0.0 {
            (g / g1).sqrt()
        } else {
            f64::INFINITY
        };
        set.push(FromEnergy {
            material: k,
            fracture_energy: *g,
            s_crit: fracture.s_crit,
        });
    }
    set
}

/// Sets the threshold of every Xu material of `f` that gives a finite `fracture_energy`, on the
/// built `model`: the `s_crit` at which its crack energy (`XuModel::crack_energy`, exact in the
/// model's curves) equals `G_c`.
pub(super) fn xu_thresholds_from_energy(f: &SceneFile, model: &mut XuModel) -> Vec<FromEnergy> {
    let energies = energies(f);
    if energies.iter().all(Option::is_none) {
        return Vec::new();
    }
    let target: Vec<f64> = energies.iter().map(|g| g.unwrap_or(0.0)).collect();
    let s_crit = solve_thresholds(&target, |s| model.crack_energy(s));
    let mut set = Vec::new();
    for (k, energy) in energies.iter().enumerate() {
        let Some(g) = energy else { continue };
        model.set_s_crit(k, s_crit[k]);
        set.push(FromEnergy {
            material: k,
            fracture_energy: *g,
            s_crit: s_crit[k],
        });
    }
    set
}

/// The orthonormal axes of `material[i]` as the columns of a matrix (identity by default).
pub(super) fn axes(ctx: &Ctx, i: usize, m: &MaterialSpec) -> Result<Mat3, SceneError> {
    let Some(a) = m.axes else {
        return Ok(perifrac_physics::math::IDENTITY);
    };
    let key = format!("material[{i}].axes");
    if m.anisotropy.is_none() {
        return Err(ctx.err(&key, "orient an anisotropy: give anisotropy too"));
    }
    let mut unit = [[0.0; 3]; 3];
    for (k, v) in a.iter().enumerate() {
        unit[k] = ctx.direction(&format!("{key}[{k}]"), *v)?;
    }
    let dot = perifrac_physics::math::dot;
    for (p, q) in [(0, 1), (0, 2), (1, 2)] {
        let c = dot(unit[p], unit[q]);
        if c.abs() > 1e-6 {
            return Err(ctx.err(
                &key,
                format!("axes {p} and {q} are not perpendicular (cosine {c:.3e})"),
            ));
        }
    }
    Ok([0, 1, 2].map(|r| [unit[0][r], unit[1][r], unit[2][r]]))
}

/// The Chen material of `material[i]` with Chen's `keys`; `horizon` converts a yield strain to `Psi0`.
fn chen_material(
    ctx: &Ctx,
    i: usize,
    m: &MaterialSpec,
    keys: &ChenKeys,
    horizon: f64,
) -> Result<ChenMaterial, SceneError> {
    let key = format!("material[{i}]");
    let mut mat = match (m.young, m.poisson) {
        (Some(e), Some(nu)) => {
            elasticity(ctx, i, m)?;
            ChenMaterial::from_young_poisson(e, nu, density(ctx, i, m)?)
                .map_err(|e| ctx.err(&key, e.to_string()))?
        }
        _ => {
            let (k, mu) = elasticity(ctx, i, m)?;
            ChenMaterial::elastic(k, mu, density(ctx, i, m)?)
        }
    };
    mat.fracture = fracture(ctx, i, m)?;
    let psi0 = match (keys.yield_psi0, keys.yield_strain) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(&key, "give either yield_psi0 or yield_strain, not both"))
        }
        (Some(p), None) => Some((ctx.positive(&format!("{key}.yield_psi0"), p, "")?, false)),
        (None, Some(eps)) => {
            let eps = ctx.positive(&format!("{key}.yield_strain"), eps, "")?;
            // A_dev = 4 omega b ed with omega = delta / r and ed = eps r: |A_dev| = 4 delta b eps,
            // with docs/model.md's b here; each particle rescales it to its own b_i (from_strain).
            let b = 15.0 * mat.shear_modulus / (2.0 * PI * horizon.powi(5));
            let a = 4.0 * horizon * b * eps;
            Some((0.5 * a * a, true))
        }
        (None, None) => None,
    };
    match (psi0, keys.plastic_cap) {
        (Some((psi0, from_strain)), cap) => {
            let cap = cap.unwrap_or(defaults::PLASTIC_CAP);
            ctx.positive(&format!("{key}.plastic_cap"), cap, "")?;
            mat.plasticity = Some(YieldParams {
                psi0,
                gamma_ratio: cap,
                from_strain,
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
        // G = A diag(g) A^T with the axes as the columns of A
        let a = axes(ctx, i, m)?;
        let mut big_g = [[0.0; 3]; 3];
        for (r, row) in big_g.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|k| a[r][k] * g[k] * a[c][k]).sum();
            }
        }
        mat.anisotropy = Some(big_g);
    } else {
        axes(ctx, i, m)?;
    }
    mat.validate(i).map_err(|e| ctx.err(&key, e.to_string()))?;
    Ok(mat)
}
