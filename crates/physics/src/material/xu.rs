//! Xu's hyperelastic peridynamic model (docs/model.md section 5): normalised weights, dilatation
//! from stretch ratios, `W_i = lambda g(theta_i) + mu sum_j w_ij V_j G_ij h(tau_ij)`, forces as
//! the exact negative gradient of `E = sum_i V_i W_i`, bond breaking as in Chen's model, and an
//! optional inversion guard (`material/guard.rs`).

use super::basis::Curve;
use super::fit::Spread;
use super::guard::{Guard, RestStiffness};
use super::kernel::{AllAlive, Mask, NoPlastic};
use super::xu_fit::{FitInputs, XuFit};
use super::xu_kernel::{
    bond_energy_sum, dilatation_sum, fitted_dilatation_sum, force, force_and_energy, Fitted,
    LinearH, NeoHookeanH, Normalised, PerParticleH, Stored, StvkH, Unit, XuInputs,
};
use super::{same_features, ForceModel, QuasiNewtonModel, XuMaterial};
use crate::crack_energy::{
    material_means, opening_integral, sample, OpeningBond, OpeningParticle, ParticleShare,
};
use crate::error::PhysicsError;
use crate::fracture::Damage;
use crate::math::{sub, Vec3};
use crate::par::{map_particles, map_particles2};
use crate::particles::Discretization;
use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use rayon::prelude::*;

/// The influence function `wt(r / delta)` before normalisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum XuKernelShape {
    /// `wt = 1`: every bond of the family weighs the same.
    #[default]
    Constant,
    /// `wt = 1 / (1 + r / delta)`: the paper's Figure 9, left.
    Inverse,
    /// `wt = r / delta`: the paper's Figure 9, right.
    Linear,
}

impl XuKernelShape {
    /// `wt(rho)` at `rho = r / delta`.
    pub fn weight(self, rho: f64) -> f64 {
        match self {
            XuKernelShape::Constant => 1.0,
            XuKernelShape::Inverse => 1.0 / (1.0 + rho),
            XuKernelShape::Linear => rho,
        }
    }
}

/// Choices of Xu's model fixed at setup.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XuOptions {
    /// The influence function.
    pub kernel: XuKernelShape,
    /// The inversion guard's factor on the rest bond stiffness (docs/model.md section 5), `None`:
    /// no guard.
    pub inversion_guard: Option<f64>,
    /// Reads the dilatation through per-bond weights fitted so that every uniform small strain
    /// gives `theta - 1 = tr(eps) / 3` on every particle, surfaces, edges and corners included
    /// (`material/xu_fit.rs`; a particle that loses a bond goes back on the normalised
    /// weights); off, through the normalised weights, which read a shear on a family cut
    /// unevenly as a volume change. On by default.
    pub fitted_dilatation: bool,
}

impl Default for XuOptions {
    /// The constant kernel, no guard, the fitted dilatation.
    fn default() -> Self {
        XuOptions {
            kernel: XuKernelShape::Constant,
            inversion_guard: None,
            fitted_dilatation: true,
        }
    }
}

/// What is fixed at setup.
#[derive(Debug, Clone)]
struct Setup {
    disc: Discretization,
    mass: Vec<f64>,
    /// `lambda_i`, `mu_i` (Pa).
    lambda: Vec<f64>,
    mu: Vec<f64>,
    /// `g` and `h` of each material, and each particle's material.
    g: Vec<Curve>,
    h: Vec<Curve>,
    /// `wt(r / delta) / r` per directed bond (1/m).
    wr: Vec<f64>,
    /// `G_ij` with the owner's axes and with the neighbour's, when some material is anisotropic.
    kernel: Option<(Vec<f64>, Vec<f64>)>,
    /// Rest curvatures `(lambda_i g_i''(1), mu_i h_i''(1))` (Pa).
    curvature: Vec<[f64; 2]>,
    options: XuOptions,
}

impl Setup {
    fn inputs<'a>(&'a self, y: &'a [Vec3]) -> XuInputs<'a> {
        XuInputs {
            family: self.disc.family(),
            y,
            volumes: self.disc.volumes(),
            wr: &self.wr,
        }
    }
}

/// Xu's model over one discretisation, with its state and buffers.
#[derive(Debug, Clone)]
pub struct XuModel {
    setup: Setup,
    damage: Option<Damage>,
    /// `1 / sum_j wt_ij V_j` over the intact bonds (1/m^3; 0 without bonds).
    inv_norm: Vec<f64>,
    theta: Vec<f64>,
    /// `[inv_norm lambda g'(theta), inv_norm mu]` per particle from the last dilatation pass.
    pq: Vec<[f64; 2]>,
    scratch: Vec<f64>,
    guard: Option<Guard>,
    /// The fitted dilatation's weights, with `XuOptions::fitted_dilatation`.
    fit: Option<XuFit>,
    /// A row of weights while a particle goes back on the normalised ones.
    fit_row: Vec<f64>,
}

/// Binds `$p` to the pressure weights (fitted or normalised), then as [`with_hgd`].
macro_rules! with_hgdp {
    ($s:expr, $fit:expr, $damage:expr, |$h:ident, $g:ident, $d:ident, $p:ident| $body:expr) => {
        match $fit {
            None => {
                let $p = Normalised;
                with_hgd!($s, $damage, |$h, $g, $d| $body)
            }
            Some(fit) => {
                let $p = Fitted { pairs: fit.pairs() };
                with_hgd!($s, $damage, |$h, $g, $d| $body)
            }
        }
    };
}

/// Binds `$h` (bond curve), `$g` (kernel) and `$d` (damage mask) to concrete types and expands
/// `$body` once per combination.
macro_rules! with_hgd {
    ($s:expr, $damage:expr, |$h:ident, $g:ident, $d:ident| $body:expr) => {
        match $damage {
            None => {
                let $d = AllAlive;
                with_hgd!(@g $s, $h, $g, $body)
            }
            Some(dm) => {
                let $d = Mask(dm.bond_state());
                with_hgd!(@g $s, $h, $g, $body)
            }
        }
    };
    (@g $s:expr, $h:ident, $g:ident, $body:expr) => {
        match &$s.kernel {
            None => {
                let $g = Unit;
                with_hgd!(@h $s, $h, $body)
            }
            Some((own, other)) => {
                let $g = Stored { own, other };
                with_hgd!(@h $s, $h, $body)
            }
        }
    };
    (@h $s:expr, $h:ident, $body:expr) => {{
        let uniform = $s.h.iter().all(|c| *c == $s.h[0]);
        match (&$s.h[0], uniform) {
            (Curve::Linear, true) => {
                let $h = LinearH;
                $body
            }
            (Curve::NeoHookean, true) => {
                let $h = NeoHookeanH;
                $body
            }
            (Curve::Stvk, true) => {
                let $h = StvkH;
                $body
            }
            _ => {
                let $h = PerParticleH {
                    curves: &$s.h,
                    material: $s.disc.materials(),
                    uniform,
                };
                $body
            }
        }
    }};
}

impl XuModel {
    /// Sets up the model with `materials[id]` for each particle's material id.
    pub fn new(
        disc: Discretization,
        materials: &[XuMaterial],
        options: XuOptions,
    ) -> Result<Self, PhysicsError> {
        for (m, mat) in materials.iter().enumerate() {
            mat.validate(m)?;
        }
        if let Some(f) = options.inversion_guard {
            if !(f.is_finite() && f > 0.0) {
                return Err(PhysicsError::BadSetting(format!(
                    "inversion guard factor {f} must be positive and finite"
                )));
            }
        }
        let n = disc.len();
        disc.check_material_ids(materials.len())?;
        let mat = |i: usize| &materials[disc.materials()[i] as usize];
        let fam = disc.family();
        let delta = disc.horizon();
        let wr: Vec<f64> = (0..n)
            .flat_map(|i| fam.range(i))
            .map(|k| {
                let r = fam.rest_lengths()[k];
                options.kernel.weight(r / delta) / r
            })
            .collect();
        let anisotropic = materials.iter().any(|m| m.anisotropy.is_some());
        let kernel = anisotropic.then(|| {
            let x = disc.rest_positions();
            let mut own = vec![1.0; fam.num_bonds()];
            let mut other = vec![1.0; fam.num_bonds()];
            for i in 0..n {
                for k in fam.range(i) {
                    let j = fam.neighbours()[k] as usize;
                    let xi = sub(x[j], x[i]);
                    own[k] = mat(i).anisotropy.map_or(1.0, |a| a.factor(xi));
                    other[k] = mat(j).anisotropy.map_or(1.0, |a| a.factor(xi));
                }
            }
            (own, other)
        });
        let fractures = materials.iter().any(XuMaterial::fractures);
        let damage = fractures.then(|| {
            let s_crit = (0..n)
                .map(|i| mat(i).fracture.map_or(f64::INFINITY, |f| f.s_crit))
                .collect();
            let alpha = (0..n)
                .map(|i| mat(i).fracture.map_or(0.0, |f| f.alpha))
                .collect();
            Damage::new(fam, s_crit, alpha)
        });
        let setup = Setup {
            mass: (0..n).map(|i| mat(i).density * disc.volumes()[i]).collect(),
            lambda: (0..n).map(|i| mat(i).lambda).collect(),
            mu: (0..n).map(|i| mat(i).mu).collect(),
            g: materials.iter().map(|m| m.g.clone()).collect(),
            h: materials.iter().map(|m| m.h.clone()).collect(),
            curvature: (0..n)
                .map(|i| {
                    let m = mat(i);
                    [m.lambda * m.g.rest_curvature(), m.mu * m.h.rest_curvature()]
                })
                .collect(),
            wr,
            kernel,
            options,
            disc,
        };
        let mut model = XuModel {
            inv_norm: vec![0.0; n],
            theta: vec![1.0; n],
            pq: vec![[0.0; 2]; n],
            scratch: vec![0.0; n],
            guard: options.inversion_guard.map(|f| Guard::new(n, f)),
            damage,
            setup,
            fit: None,
            fit_row: Vec::new(),
        };
        model.normalise(None);
        if options.fitted_dilatation {
            model.fit = Some(XuFit::new(model.fit_inputs()));
        }
        Ok(model)
    }

    /// What the fit reads.
    fn fit_inputs(&self) -> FitInputs<'_> {
        let s = &self.setup;
        FitInputs {
            family: s.disc.family(),
            x: s.disc.rest_positions(),
            volumes: s.disc.volumes(),
            wr: &s.wr,
            inv_norm: &self.inv_norm,
            alive: self.damage.as_ref().map(|d| d.bond_state()),
        }
    }

    /// The crack energy per unit area (J/m^2) of each material whose bonds break at the measure
    /// `s_crit[m]` (1): the energy a slow, rigid opening of a plane dissipates, bond by bond and
    /// with the weights normalised again at each break as the model does, integrated over the
    /// plane's offset and averaged over whole families (`crack_energy.rs`), at most
    /// [`SAMPLE_PER_MATERIAL`](crate::crack_energy::SAMPLE_PER_MATERIAL) of them a material. It uses the model's own curves, so it holds
    /// at any stretch; a material with no particle gets 0.
    pub fn crack_energy(&self, s_crit: &[f64]) -> Vec<f64> {
        let s = &self.setup;
        let disc = &s.disc;
        let (fam, x, volumes) = (disc.family(), disc.rest_positions(), disc.volumes());
        let delta = disc.horizon();
        let ids = disc.materials();
        let per: Vec<ParticleShare> = sample(disc, s.g.len())
            .into_par_iter()
            .map(|(i, whole)| {
                let m = ids[i] as usize;
                let bonds: Vec<OpeningBond> = fam
                    .range(i)
                    .map(|k| {
                        let j = fam.neighbours()[k] as usize;
                        let r = fam.rest_lengths()[k];
                        let v = volumes[j];
                        let kernel = s.kernel.as_ref().map_or(1.0, |(own, _)| own[k]);
                        // theta - 1 = inv_norm sum f V e with the fit, as without it with wr
                        let fit_v = self.fit.as_ref().map_or(s.wr[k], |f| f.pairs()[k][0]) * v;
                        OpeningBond {
                            x: sub(x[j], x[i]),
                            r,
                            wt_v: s.wr[k] * r * v,
                            energy_v: s.wr[k] * r * v * kernel,
                            wr_v: s.wr[k] * v,
                            fit_v,
                        }
                    })
                    .collect();
                let particle = OpeningParticle {
                    lambda: s.lambda[i],
                    mu: s.mu[i],
                    g: &s.g[m],
                    h: &s.h[m],
                    e_c: s_crit.get(m).copied().unwrap_or(0.0) * delta,
                };
                ParticleShare {
                    material: m,
                    volume: volumes[i],
                    energy: opening_integral(&bonds, particle),
                    whole,
                }
            })
            .collect();
        material_means(&per, s.g.len())
    }

    /// Sets the fracture threshold `s_crit` (1) of every particle of material `material`; a
    /// model built without fracture has no threshold to set and is left as it is.
    pub fn set_s_crit(&mut self, material: usize, s_crit: f64) {
        let Some(damage) = self.damage.as_mut() else {
            return;
        };
        for (i, &m) in self.setup.disc.materials().iter().enumerate() {
            if m as usize == material {
                damage.set_s_crit(i, s_crit);
            }
        }
    }

    /// With the fitted dilatation, per particle its fitted weight over the normalised one of
    /// largest magnitude on its bonds at setup (1: Xu's normalised weights).
    pub fn correction(&self) -> Option<Spread> {
        self.fit.as_ref().map(XuFit::correction)
    }

    /// The options chosen at setup.
    pub fn options(&self) -> XuOptions {
        self.setup.options
    }

    /// Dilatation `theta_i` of each particle from the last force or energy evaluation (1 at
    /// rest).
    pub fn dilatations(&self) -> &[f64] {
        &self.theta
    }

    /// Recomputes `1 / sum_j wt_ij V_j` over intact bonds, for the particles in `touched` (all
    /// when `None`), so `sum_j w_ij V_j = 1` stays true as bonds break and a broken body at rest
    /// feels no force.
    fn normalise(&mut self, touched: Option<&[(u32, u32)]>) {
        let s = &self.setup;
        let fam = s.disc.family();
        let vol = s.disc.volumes();
        let alive = self.damage.as_ref().map(|d| d.bond_state());
        let one = |i: usize| {
            let sum: f64 = fam
                .range(i)
                .filter(|&k| alive.is_none_or(|a| a[k] != 0))
                .map(|k| s.wr[k] * fam.rest_lengths()[k] * vol[fam.neighbours()[k] as usize])
                .sum();
            if sum > 0.0 {
                1.0 / sum
            } else {
                0.0
            }
        };
        match touched {
            None => map_particles(&mut self.inv_norm, one),
            Some(pairs) => {
                for &(i, j) in pairs {
                    self.inv_norm[i as usize] = one(i as usize);
                    self.inv_norm[j as usize] = one(j as usize);
                }
            }
        }
    }

    /// `theta` and `pq` at `y`.
    fn dilatation_pass(&mut self, y: &[Vec3]) {
        let inp = self.setup.inputs(y);
        let inv = &self.inv_norm;
        match (self.damage.as_ref(), &self.fit) {
            // theta = 1 + inv sum f V (l - r): 1 at rest and without intact bonds
            (None, Some(fit)) => map_particles(&mut self.theta, |i| {
                1.0 + inv[i] * fitted_dilatation_sum(inp, fit.pairs(), AllAlive, i)
            }),
            (Some(dm), Some(fit)) => {
                let d = Mask(dm.bond_state());
                map_particles(&mut self.theta, |i| {
                    1.0 + inv[i] * fitted_dilatation_sum(inp, fit.pairs(), d, i)
                })
            }
            (None, None) => map_particles(&mut self.theta, |i| {
                theta_of(inv[i], dilatation_sum(inp, AllAlive, i))
            }),
            (Some(dm), None) => {
                let d = Mask(dm.bond_state());
                map_particles(&mut self.theta, |i| {
                    theta_of(inv[i], dilatation_sum(inp, d, i))
                })
            }
        }
        let s = &self.setup;
        let (theta, ids) = (&self.theta, s.disc.materials());
        map_particles(&mut self.pq, |i| {
            let g = &s.g[ids[i] as usize];
            [inv[i] * s.lambda[i] * g.slope(theta[i]), inv[i] * s.mu[i]]
        });
    }

    fn force_pass(&self, y: &[Vec3], forces: &mut [Vec3]) {
        let inp = self.setup.inputs(y);
        let pq = &self.pq;
        let s = &self.setup;
        with_hgdp!(s, &self.fit, self.damage.as_ref(), |h, g, d, p| {
            map_particles(forces, |i| force(inp, (h, g, d, p), pq, i))
        });
        if let Some(guard) = &self.guard {
            guard.add_forces(&self.guard_inputs(y), forces);
        }
    }

    fn guard_inputs<'a>(
        &'a self,
        y: &'a [Vec3],
    ) -> super::guard::GuardInputs<'a, BondStiffness<'a>> {
        super::guard::GuardInputs {
            family: self.setup.disc.family(),
            rest: self.setup.disc.rest_positions(),
            y,
            stiffness: BondStiffness { model: self },
            alive: self.damage.as_ref().map(|d| d.bond_state()),
        }
    }

    /// Rest stiffness `k_ij = V_i V_j (w_ij / r^2)(lambda_i g_i''(1) + mu_i G_ij h_i''(1))`
    /// (N/m) of directed bond `k` of particle `i` (intact or not), from the normalised weights
    /// `w` whether or not the dilatation is fitted: the step matrix's springs (with the fit
    /// they no longer bound its corner families' Hessian; docs/DECISIONS.md, "The fitted
    /// dilatation in Xu's model").
    #[inline]
    pub fn rest_bond_stiffness(&self, i: usize, k: usize) -> f64 {
        self.pair_stiffness(i, k, false)[0]
    }

    /// `k_ji` (N/m) of the reverse of directed bond `k` of particle `i`.
    #[inline]
    pub fn reverse_bond_stiffness(&self, i: usize, k: usize) -> f64 {
        self.pair_stiffness(i, k, false)[1]
    }

    /// `[k_ij, k_ji]` (N/m) of directed bond `k` of particle `i`; with `bound` and the fitted
    /// dilatation, the dilatation term's spring `V_i V_j lambda_i g_i''(1) S_i |d_ij| / r^2`
    /// that bounds its Hessian by Cauchy-Schwarz (`material/xu_fit.rs`).
    #[inline(always)]
    fn pair_stiffness(&self, i: usize, k: usize, bound: bool) -> [f64; 2] {
        let s = &self.setup;
        let j = s.disc.family().neighbours()[k] as usize;
        let (gij, gji) = s.kernel.as_ref().map_or((1.0, 1.0), |(a, b)| (a[k], b[k]));
        let fit = self.fit.as_ref().filter(|_| bound);
        [
            self.stiffness_from((i, j), k, gij, fit.map(|f| (f, 0))),
            self.stiffness_from((j, i), k, gji, fit.map(|f| (f, 1))),
        ]
    }

    /// `k` seen from `owner` across bond `k` (whose rest length and `wr` both ends share),
    /// with the fitted weight of `end` (0: the owner's own bond, 1: its reverse) when bounding.
    #[inline(always)]
    fn stiffness_from(
        &self,
        (owner, other): (usize, usize),
        k: usize,
        g: f64,
        fitted: Option<(&XuFit, usize)>,
    ) -> f64 {
        let s = &self.setup;
        let r = s.disc.family().rest_lengths()[k];
        let [lg, mh] = s.curvature[owner];
        let vol = s.disc.volumes();
        match fitted {
            // d_ij = inv_i r f_ij
            Some((fit, end)) => {
                let dil = fit.spread(owner) * fit.pairs()[k][end].abs();
                vol[owner] * vol[other] * self.inv_norm[owner] / r * (s.wr[k] * mh * g + lg * dil)
            }
            None => vol[owner] * vol[other] * (s.wr[k] * self.inv_norm[owner] / r) * (lg + mh * g),
        }
    }

    #[track_caller]
    fn check_len(&self, y: &[Vec3], forces: Option<&[Vec3]>) {
        self.setup.disc.check_slices(y, forces);
    }
}

/// The rest bond stiffness as the guard sees it.
#[derive(Clone, Copy)]
pub(crate) struct BondStiffness<'a> {
    model: &'a XuModel,
}

impl RestStiffness for BondStiffness<'_> {
    /// `(k_ij, k_ji)` of directed bond `k` of particle `i` (N/m).
    #[inline]
    fn pair(&self, i: usize, k: usize) -> (f64, f64) {
        (
            self.model.rest_bond_stiffness(i, k),
            self.model.reverse_bond_stiffness(i, k),
        )
    }
}

/// `theta = inv_norm * sum`, and the rest value 1 for a particle without intact bonds (its
/// energy is then zero whatever `g`).
#[inline(always)]
fn theta_of(inv_norm: f64, sum: f64) -> f64 {
    if inv_norm > 0.0 {
        inv_norm * sum
    } else {
        1.0
    }
}

impl ForceModel for XuModel {
    fn num_particles(&self) -> usize {
        self.setup.disc.len()
    }

    fn save_state(&self, w: &mut Writer) {
        w.tag("xu");
        w.array(&self.inv_norm);
        w.array(&self.theta);
        w.bool(self.damage.is_some());
        if let Some(d) = &self.damage {
            d.save(w);
        }
        w.bool(self.guard.is_some());
        if let Some(g) = &self.guard {
            g.save(w);
        }
    }

    fn restore_state(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("xu")?;
        r.array_into("normalisations", &mut self.inv_norm)?;
        r.array_into("dilatations", &mut self.theta)?;
        same_features("damage", self.damage.is_some(), r.bool("fracture")?)?;
        if let Some(d) = &mut self.damage {
            d.restore(self.setup.disc.family(), r)?;
        }
        same_features("inversion guard", self.guard.is_some(), r.bool("guard")?)?;
        if let Some(g) = &mut self.guard {
            g.restore(r)?;
        }
        if let Some(mut fit) = self.fit.take() {
            // each particle's weights are a function of its intact bonds alone: fitted with all
            // of them, normalised over them once one is broken
            fit.set_all(self.fit_inputs());
            self.fit = Some(fit);
        }
        Ok(())
    }

    fn discretization(&self) -> &Discretization {
        &self.setup.disc
    }

    fn masses(&self) -> &[f64] {
        &self.setup.mass
    }

    fn update_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.check_len(y, Some(forces));
        if self.guard.is_some() {
            let mut guard = self.guard.take().expect("checked");
            guard.update(&self.guard_inputs(y));
            self.guard = Some(guard);
        }
        self.dilatation_pass(y);
        self.force_pass(y, forces);
    }

    fn trial_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.check_len(y, Some(forces));
        self.dilatation_pass(y);
        self.force_pass(y, forces);
    }

    fn elastic_energy(&mut self, y: &[Vec3]) -> f64 {
        self.check_len(y, None);
        self.dilatation_pass(y);
        let s = &self.setup;
        let inp = s.inputs(y);
        let (theta, inv) = (&self.theta, &self.inv_norm);
        let ids = s.disc.materials();
        with_hgd!(s, self.damage.as_ref(), |h, g, d| {
            map_particles(&mut self.scratch, |i| {
                if inv[i] == 0.0 {
                    return 0.0;
                }
                let dil = s.lambda[i] * s.g[ids[i] as usize].eval(theta[i]).0;
                let bonds = s.mu[i] * inv[i] * bond_energy_sum(inp, h, g, d, i);
                inp.volumes[i] * (dil + bonds)
            })
        });
        let guard = self
            .guard
            .as_ref()
            .map_or(0.0, |gd| gd.energy(&self.guard_inputs(y)));
        self.scratch.iter().sum::<f64>() + guard
    }

    fn break_bonds(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        let Some(damage) = self.damage.as_mut() else {
            return;
        };
        let start = broken.len();
        let s = &self.setup;
        damage.check(
            s.disc.family(),
            y,
            s.disc.horizon(),
            (NoPlastic, 0.0),
            broken,
        );
        if broken.len() > start {
            self.normalise(Some(&broken[start..]));
            if let Some(mut fit) = self.fit.take() {
                // both ends back on the normalised weights, over the intact bonds left
                let mut buf = std::mem::take(&mut self.fit_row);
                let inp = self.fit_inputs();
                for &(i, j) in &broken[start..] {
                    fit.unfit(inp, i as usize, &mut buf);
                    fit.unfit(inp, j as usize, &mut buf);
                }
                self.fit = Some(fit);
                self.fit_row = buf;
            }
        }
    }

    fn silling_askari_step(&self) -> f64 {
        // sqrt(2 m_i / sum_j (k_ij + k_ji)) with the rest bond stiffness (N/m) of both ends,
        // the fitted dilatation's bounding springs with the fit
        let fam = self.setup.disc.family();
        let mut dt = f64::INFINITY;
        for i in 0..fam.len() {
            let sum: f64 = fam
                .range(i)
                .map(|k| self.pair_stiffness(i, k, true).iter().sum::<f64>())
                .sum();
            if sum > 0.0 {
                dt = dt.min((2.0 * self.setup.mass[i] / sum).sqrt());
            }
        }
        // the guard's lagged springs add `f` times each bond's rest stiffness
        dt / (1.0 + self.setup.options.inversion_guard.unwrap_or(0.0)).sqrt()
    }

    fn memory_bytes(&self) -> usize {
        let XuModel {
            setup,
            damage,
            inv_norm,
            theta,
            pq,
            scratch,
            guard,
            fit,
            fit_row,
        } = self;
        let Setup {
            disc,
            mass,
            lambda,
            mu,
            g: _,
            h: _,
            wr,
            kernel,
            curvature,
            options: _,
        } = setup;
        disc.memory_bytes()
            + 8 * (mass.len() + lambda.len() + mu.len() + wr.len())
            + kernel.as_ref().map_or(0, |(a, b)| 8 * (a.len() + b.len()))
            + 16 * curvature.len()
            + damage.as_ref().map_or(0, Damage::memory_bytes)
            + 8 * (inv_norm.len() + theta.len() + scratch.len())
            + 16 * pq.len()
            + guard.as_ref().map_or(0, Guard::memory_bytes)
            + fit.as_ref().map_or(0, XuFit::memory_bytes)
            + 8 * fit_row.capacity()
    }

    fn damage(&self) -> Option<&Damage> {
        self.damage.as_ref()
    }
}

impl QuasiNewtonModel for XuModel {
    /// `k_ij`, times `1 + f` with the inversion guard of factor `f`: the guard's energy
    /// `f/2 k |eta - F xi|^2` (lagged `F`) has exactly the Hessian `f k (e_i - e_j)(e_i - e_j)^T`.
    fn bond_stiffness(&self, out: &mut [f64]) {
        let scale = 1.0 + self.setup.options.inversion_guard.unwrap_or(0.0);
        let fam = self.setup.disc.family();
        assert_eq!(
            out.len(),
            fam.num_bonds(),
            "one stiffness per directed bond"
        );
        let alive = self.damage.as_ref().map(|d| d.bond_state());
        crate::par::for_each_row(fam.offsets(), out, &|i, row: &mut [f64]| {
            for (k, slot) in fam.range(i).zip(row) {
                *slot = if alive.is_none_or(|a| a[k] != 0) {
                    scale * self.rest_bond_stiffness(i, k)
                } else {
                    0.0
                };
            }
        });
    }

    /// One dilatation pass and one fused force-and-energy pass (three bond loops become two).
    fn energy_and_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) -> f64 {
        self.check_len(y, Some(forces));
        self.dilatation_pass(y);
        let s = &self.setup;
        let inp = s.inputs(y);
        let (theta, inv, pq) = (&self.theta, &self.inv_norm, &self.pq);
        let ids = s.disc.materials();
        with_hgdp!(s, &self.fit, self.damage.as_ref(), |h, g, d, p| {
            map_particles2(forces, &mut self.scratch, |i| {
                let (f, bonds) = force_and_energy(inp, (h, g, d, p), pq, i);
                if inv[i] == 0.0 {
                    return (f, 0.0);
                }
                let dil = s.lambda[i] * s.g[ids[i] as usize].eval(theta[i]).0;
                (f, inp.volumes[i] * (dil + s.mu[i] * inv[i] * bonds))
            })
        });
        let mut energy = self.scratch.iter().sum::<f64>();
        if let Some(guard) = &self.guard {
            let gi = self.guard_inputs(y);
            guard.add_forces(&gi, forces);
            energy += guard.energy(&gi);
        }
        energy
    }
}
