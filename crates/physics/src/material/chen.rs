//! The Chen elastoplastic state-based model with fracture (docs/model.md section 2, with its
//! Decisions: `Lambda = 1`, `ed = e - theta r / 3`, return-map increment `/(4 omega b)`,
//! threshold-scaled fracture).

use super::fit::{
    anisotropic_target, dilatation_weights, fit_tensors, Correction, Spread, ISOTROPIC_TARGET,
};
use super::guard::{Guard, GuardInputs, RestStiffness};
use super::kernel::{
    dilatation, dilatation_breaking, dilatation_yield, dilatation_yield_breaking, energy_density,
    force, force_yield, with_row_buffer, yield_inside, Alive, AllAlive, Fitted, Inputs, Isotropic,
    Mask, NoPlastic, PerBond, Plastic, RowHint, WithPlastic, Yield,
};
use super::lanes::{self, theta_moment};
use super::same_features;
use super::{ChenMaterial, ForceModel};
use crate::error::PhysicsError;
use crate::fracture::Damage;
use crate::math::{mat_vec, norm, sub, Vec3, IDENTITY};
use crate::par::{for_rows_mut, map_particles, update_particles};
use crate::particles::Discretization;
use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use std::f64::consts::PI;

/// Choices of the Chen model fixed at setup.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChenOptions {
    /// Add the energy-consistent pressure term: `a_i theta_i` becomes
    /// `a_i theta_i - (b_i c_i / 3) S_i`, `S_i = sum_j omega_ij r_ij (ed_ij - ep_ij) V_j`, which
    /// makes the force exactly `-dE/dy` of the stored energy (docs/model.md's force is not a
    /// gradient: `theta` weights extensions by `omega` while `ed` removes `theta r / 3`). `S_i`
    /// vanishes for homogeneous deformations of the continuum, so the moduli are unchanged.
    pub energy_consistent: bool,
    /// Per-particle calibration from the discrete family (docs/model.md section 2 lists it as an
    /// option): `c_i = 3 / sum_j omega_ij r_ij V_j`, `a_i = kappa_i c_i / 2` and
    /// `b_i = 15 mu_i / (2 sum_j omega_ij r_ij^2 V_j)` instead of `9 / (4 pi delta^4)`,
    /// `9 kappa / (8 pi delta^4)` and `15 mu / (2 pi delta^5)`. A uniform dilatation `eps` then
    /// gives `theta = 3 eps` and `ed = 0` on every bond of every particle, surface ones
    /// included, which docs/model.md's pressure-free Decision needs on a discrete mesh (with the
    /// uniform constants interior Kuhn-lattice particles get `theta = 3.077 eps` and surface ones
    /// as little as a quarter of it, so pressure leaks into `A_dev` and yields), and the
    /// measured moduli of a bar come closer (see tests/moduli.rs). It stiffens cut families
    /// (corners most), which raises `omega_max`: 7.89e5 to 1.23e6 rad/s on a 3 x 3 x 3-cell
    /// steel block at k = 1.5, so the stable step shrinks by a third.
    pub calibrated: bool,
    /// Fitted dilatation weights (`fit.rs`; default on): each bond's dilatation weight becomes
    /// `omega_ij (n n : L_i)` with one symmetric tensor `L_i` per particle fitted so that every
    /// homogeneous small strain gives `theta_i = tr(eps)` on every particle, cut families
    /// included (the scalar `c_i` gets only the trace right: on unevenly cut families it reads
    /// shear as volume change). The deviatoric weights stay `omega_ij`, with `b_i` as
    /// `calibrated` says. Costs 16 bytes a bond (each bond's weight and its reverse's, stored
    /// in bond order), a force evaluation 1.15 times the scalar calibration's on 13.9 M bonds
    /// (one thread, the vector loops of `lanes.rs`; 1.06 on 1.8 M bonds before them), and a
    /// stable step 8% to 13% shorter (docs/DECISIONS.md).
    pub fitted_dilatation: bool,
}

/// Ridge of the dilatation fit, a share of the family moment's mean diagonal pulling `L_i`
/// towards the scalar calibration: a guard against families whose directions do not span the
/// six strain modes, small enough to leave spanning families fitted to round-off.
pub const FIT_RIDGE: f64 = 1e-9;

/// The fitted dilatation weight of a bond stays within this factor of the scalar calibration's
/// (`|d_ij| <= FIT_BOUND c_i omega_ij`): a particle whose fit needs more is blended towards the
/// scalar calibration until its largest factor is this. Every Kuhn-lattice block measured (2 to
/// 8 cells across, k = 1 to 2) needs at most 7.5 (on corner bonds), so lattice meshes are fitted
/// exactly; families whose directions nearly fail to span the six strain modes (a thin part one
/// tet across) asked for up to 1.6e5 on `octopus-low.mesh`.
pub const FIT_BOUND: f64 = 10.0;

impl Default for ChenOptions {
    fn default() -> Self {
        ChenOptions {
            energy_consistent: true,
            calibrated: true,
            fitted_dilatation: true,
        }
    }
}

/// What is fixed at setup: discretisation, constants, weights, yield parameters.
#[derive(Debug, Clone)]
struct Setup {
    disc: Discretization,
    mass: Vec<f64>,
    density: Vec<f64>,
    /// `a_i = kappa_i c_i / 2` (`9 kappa_i / (8 pi delta^4)` uncalibrated).
    coef_a: Vec<f64>,
    /// `b_i = 15 mu_i / (2 m_i)`, `m_i = pi delta^5` uncalibrated.
    coef_b: Vec<f64>,
    /// Per-particle `c_i` (`9 / (4 pi delta^4)` unless calibrated).
    c_theta: Vec<f64>,
    /// Per-bond `omega` when some material is anisotropic (`delta / r` otherwise).
    weights: Option<Vec<f64>>,
    /// Per-bond fitted dilatation weights `(d_ij, d_ji)` (each over its own particle's `c`),
    /// in bond order, when the dilatation is fitted.
    dil_weights: Option<Vec<[f64; 2]>>,
    /// Reverse-bond index, when anisotropic.
    reverse: Option<Vec<u32>>,
    /// What [`ChenModel::correction`] reports, made with the constants.
    correction: Correction,
    /// The particles before this one are active; those from it on are passive (no energy, no
    /// force state: their dilatation is never needed).
    active: usize,
    /// Per-particle `(Psi0, gamma_ratio)` when some material is plastic (infinite: elastic).
    yield_params: Option<Vec<(f64, f64)>>,
    /// Per particle `[r_min + r_max (m), 1 / (r_min r_max) (1/m^2), C (1 - margin)]` with
    /// `C = sqrt(2 Psi0) / (4 b)`, the constants of the test that lets a plastic first pass
    /// skip its return-map loop (`kernel::Yield::all_inside`), when some material is plastic.
    yield_inside: Option<Vec<[f64; 3]>>,
    options: ChenOptions,
}

/// The Chen model over one discretisation, with its state and the per-step buffers it owns.
#[derive(Debug, Clone)]
pub struct ChenModel {
    setup: Setup,
    /// Plastic extensions `(ep_ij, ep_ji)` per directed bond `i -> j` (m), only when plastic:
    /// each bond's own and its reverse's, so the bond loops stream them instead of gathering
    /// the reverse's (`ep[k][1] == ep[rev k][0]` always, bit for bit).
    ep: Option<Vec<[f64; 2]>>,
    /// A lower bound on every plastic extension (m, at most 0): the least ever stored, which
    /// lets the damage check pass over bonds far from breaking without loading theirs.
    ep_floor: f64,
    /// Per particle `[theta_i, S_i, least extension changed, 1 if any changed]` of a plastic
    /// step's first pass, only when plastic.
    first_pass: Vec<[f64; 4]>,
    /// Per particle, whether the last first pass changed any of its own ends' extensions (the
    /// force pass maps the other end of a bond only then), only when plastic.
    changed: Vec<bool>,
    /// Per particle, which of its row's plastic extensions may be nonzero, only when plastic:
    /// [`OWN_SET`] its own ends (and every neighbour has been given [`ROW_SET`]), [`ROW_SET`]
    /// any of its pairs. A row without them holds `+0.0` only, so the passes skip its loads
    /// (most of a plastic body never yields). Set once and kept; recomputed from the values
    /// when they are set from outside.
    ep_rows: Vec<u8>,
    damage: Option<Damage>,
    /// Per particle `(theta_i, S_i)` from the last dilatation pass.
    ts: Vec<[f64; 2]>,
    pq: Vec<[f64; 2]>,
    scratch: Vec<f64>,
    /// The inversion guard, when asked for ([`ChenModel::with_inversion_guard`]).
    guard: Option<ChenGuard>,
    /// Per particle, what the lane loops read of a neighbour; empty where they cannot apply
    /// (per-bond weights, or a CPU without AVX2).
    packed: Vec<lanes::Packed>,
}

/// The inversion guard ([`super::guard`]) on Chen's bonds, with each bond's rest stiffness.
#[derive(Debug, Clone)]
struct ChenGuard {
    guard: Guard,
    /// `(k_ij, k_ji)` (N/m) per directed bond in bond order: [`Setup::micromoduli`] times
    /// `V_i V_j`.
    k: Vec<[f64; 2]>,
}

/// The guard's inputs at `y` (m) with the bond stiffnesses `k`.
fn guard_inputs<'a>(
    s: &'a Setup,
    damage: Option<&'a Damage>,
    k: &'a [[f64; 2]],
    y: &'a [Vec3],
) -> GuardInputs<'a, ChenStiffness<'a>> {
    GuardInputs {
        family: s.disc.family(),
        rest: s.disc.rest_positions(),
        y,
        stiffness: ChenStiffness(k),
        alive: damage.map(|d| d.bond_state()),
    }
}

/// [`ChenGuard::k`] as the guard reads it.
struct ChenStiffness<'a>(&'a [[f64; 2]]);

impl RestStiffness for ChenStiffness<'_> {
    #[inline(always)]
    fn pair(&self, _i: usize, k: usize) -> (f64, f64) {
        let [kij, kji] = self.0[k];
        (kij, kji)
    }
}

/// `f(i)` for the particles before `active`, `[0, 0]` for the passive ones after: their
/// dilatation meets only their zero constants, so it is not computed.
#[inline(always)]
fn active_only<F>(active: usize, f: F) -> impl Fn(usize) -> [f64; 2] + Sync
where
    F: Fn(usize) -> [f64; 2] + Sync,
{
    move |i| if i < active { f(i) } else { [0.0; 2] }
}

/// Particle `i`'s discrete family moments `(sum_j omega r V_j, sum_j omega r^2 V_j)` over its
/// rest bonds, with the per-bond weights `w` when given (`delta / r` otherwise).
fn family_moments(disc: &Discretization, w: Option<&[f64]>, i: usize) -> (f64, f64) {
    let fam = disc.family();
    let delta = disc.horizon();
    fam.range(i).fold((0.0, 0.0), |(m1, m2), k| {
        let r = fam.rest_lengths()[k];
        let wk = w.map_or(delta / r, |w| w[k]);
        let wv = wk * disc.volumes()[fam.neighbours()[k] as usize];
        (m1 + wv * r, m2 + wv * r * r)
    })
}

/// [`ChenModel::ep_rows`]' bit: the particle's own ends may be nonzero, and its neighbours
/// have [`ROW_SET`].
const OWN_SET: u8 = 1;
/// [`ChenModel::ep_rows`]' bit: some pair of the particle's row may be nonzero.
const ROW_SET: u8 = 2;

/// What the first pass knows of particle `i` from [`ChenModel::ep_rows`] and the last pass's
/// `changed` (a hint for speed: the results do not depend on it).
fn row_hint(rows: &[u8], changed: &[bool], i: usize) -> RowHint {
    RowHint {
        clean: rows[i] & OWN_SET == 0,
        pairs_clean: rows[i] & ROW_SET == 0,
        yielded: changed[i],
    }
}

/// Gives particle `i` [`OWN_SET`] (once) and its neighbours [`ROW_SET`]: its own ends are
/// about to hold values other than `+0.0`, and so are the mirrored ends of its neighbours' rows.
fn mark_own(fam: &crate::family::Family, rows: &mut [u8], i: usize) {
    if rows[i] & OWN_SET != 0 {
        return;
    }
    rows[i] |= OWN_SET | ROW_SET;
    for &j in &fam.neighbours()[fam.range(i)] {
        rows[j as usize] |= ROW_SET;
    }
}

/// [`ChenModel::ep_rows`] from the values of the pairs `ep`: [`OWN_SET`] where an own end's bits
/// are not those of `+0.0` (with [`ROW_SET`] for the neighbours), [`ROW_SET`] where any pair's are not.
fn mark_rows(fam: &crate::family::Family, ep: &[[f64; 2]], rows: &mut [u8]) {
    let zero = |x: f64| x.to_bits() == 0;
    for i in 0..fam.len() {
        let row = &ep[fam.range(i)];
        rows[i] = if row.iter().all(|p| zero(p[0]) && zero(p[1])) {
            0
        } else {
            ROW_SET
        };
    }
    for i in 0..fam.len() {
        if !ep[fam.range(i)].iter().all(|p| zero(p[0])) {
            mark_own(fam, rows, i);
        }
    }
}

/// `ep[k] = (own[k], own[rev k])` for every directed bond `k`.
fn fill_pairs(fam: &crate::family::Family, own: &[f64], ep: &mut [[f64; 2]]) {
    fam.for_each_reverse(|k, r| ep[k] = [own[k], own[r]]);
}

/// Binds `$w` (weights) and `$d` (damage mask) to concrete view types and expands `$body` once
/// per combination, so every bond loop is monomorphised.
macro_rules! with_wd {
    ($setup:expr, $damage:expr, |$w:ident, $d:ident| $body:expr) => {
        match $damage {
            None => {
                let $d = AllAlive;
                with_wd!(@w $setup, $w, $body)
            }
            Some(dm) => {
                let $d = Mask(dm.bond_state());
                with_wd!(@w $setup, $w, $body)
            }
        }
    };
    (@w $setup:expr, $w:ident, $body:expr) => {
        match ($setup.weights.as_deref(), $setup.dil_weights.as_deref()) {
            (None, None) => {
                let $w = Isotropic { delta: $setup.disc.horizon() };
                $body
            }
            (Some(wv), None) => {
                let $w = PerBond { w: wv, rev: $setup.reverse.as_deref().expect("reverse index") };
                $body
            }
            (None, Some(dw)) => {
                let $w = Fitted { base: Isotropic { delta: $setup.disc.horizon() }, dw };
                $body
            }
            (Some(wv), Some(dw)) => {
                let rev = $setup.reverse.as_deref().expect("reverse index");
                let $w = Fitted { base: PerBond { w: wv, rev }, dw };
                $body
            }
        }
    };
}

/// As `with_wd`, also binding `$p` to the plastic view.
macro_rules! with_wpd {
    ($setup:expr, $ep:expr, $damage:expr, |$w:ident, $p:ident, $d:ident| $body:expr) => {
        match $ep {
            None => {
                let $p = NoPlastic;
                with_wd!($setup, $damage, |$w, $d| $body)
            }
            Some(ep) => {
                let $p = WithPlastic { ep };
                with_wd!($setup, $damage, |$w, $d| $body)
            }
        }
    };
}

impl Setup {
    /// The direct micromoduli (N/m^7) of directed bond `k` of particle `i`: the pair force
    /// density `0.5 (A_ij + A_ji)` against the bond's extension, its own terms only, split by
    /// the end whose energy carries them and into deviatoric and dilatation parts:
    /// `[[2 omega_ij b_i, 2 c_i a_i d_ij^2 V_j], [2 omega_ji b_j, 2 c_j a_j d_ji^2 V_i]]`.
    fn micromoduli(&self, i: usize, k: usize) -> [[f64; 2]; 2] {
        let fam = self.disc.family();
        let vol = self.disc.volumes();
        let j = fam.neighbours()[k] as usize;
        let r = fam.rest_lengths()[k];
        let delta = self.disc.horizon();
        let (wij, wji) = match (&self.weights, &self.reverse) {
            (Some(w), Some(rev)) => (w[k], w[rev[k] as usize]),
            _ => (delta / r, delta / r),
        };
        let (dij, dji) = match &self.dil_weights {
            Some(d) => (d[k][0], d[k][1]),
            None => (wij, wji),
        };
        [
            [
                2.0 * (wij * self.coef_b[i]),
                2.0 * self.c_theta[i] * self.coef_a[i] * dij * dij * vol[j],
            ],
            [
                2.0 * (wji * self.coef_b[j]),
                2.0 * self.c_theta[j] * self.coef_a[j] * dji * dji * vol[i],
            ],
        ]
    }

    /// The bond loops' read-only inputs at positions `y` (m).
    fn inputs<'a>(&'a self, y: &'a [Vec3]) -> Inputs<'a> {
        Inputs {
            family: self.disc.family(),
            y,
            volumes: self.disc.volumes(),
            c_theta: &self.c_theta,
        }
    }

    /// The lane loops' inputs over `packed` ([`lanes`]) where they can run: a non-empty
    /// `packed` (allocated only with the isotropic weight) and a CPU with AVX2. The elastic
    /// passes take them only where nothing is plastic; a plastic one only on rows that hold no
    /// plastic extension.
    fn lane_row<'a>(&'a self, packed: &'a [lanes::Packed]) -> Option<lanes::Row<'a>> {
        if packed.is_empty() {
            return None;
        }
        let dw = self.dil_weights.as_deref();
        lanes::Row::new(self.disc.family(), packed, self.disc.horizon(), dw)
    }

    /// The return map's per-particle constants, when some material is plastic.
    fn yield_view(&self) -> Option<Yield<'_>> {
        let params = self.yield_params.as_deref()?;
        Some(Yield {
            coef_b: &self.coef_b,
            params,
            inside: self.yield_inside.as_deref()?,
        })
    }
}

impl ChenModel {
    /// Sets up the model with `materials[id]` for each particle's material id. Plastic and damage
    /// state are allocated only when some material asks for them.
    pub fn new(disc: Discretization, materials: &[ChenMaterial]) -> Result<Self, PhysicsError> {
        Self::with_options(disc, materials, ChenOptions::default())
    }

    /// As [`ChenModel::new`], with explicit [`ChenOptions`].
    pub fn with_options(
        disc: Discretization,
        materials: &[ChenMaterial],
        options: ChenOptions,
    ) -> Result<Self, PhysicsError> {
        let n = disc.len();
        Self::with_passive(disc, materials, options, n)
    }

    /// As [`ChenModel::with_options`], with the particles from `active` on passive: they store
    /// no energy (`a_i = b_i = 0`) and carry no force state of their own, but sit in their
    /// neighbours' families, which read their positions (the ghosts of [`crate::ghost`]). The
    /// correction's spread is over the active particles. A passive particle never yields (its
    /// own ends' plastic extensions stay zero; an active particle's bonds to it yield as any
    /// other), and its bonds break by the same criterion as every bond, with the thresholds
    /// of its material.
    pub fn with_passive(
        disc: Discretization,
        materials: &[ChenMaterial],
        options: ChenOptions,
        active: usize,
    ) -> Result<Self, PhysicsError> {
        for (m, mat) in materials.iter().enumerate() {
            mat.validate(m)?;
        }
        let n = disc.len();
        if active > n {
            return Err(PhysicsError::BadSetting(format!(
                "{active} active particles asked of {n}"
            )));
        }
        disc.check_material_ids(materials.len())?;
        let delta = disc.horizon();
        let mat = |i: usize| &materials[disc.materials()[i] as usize];
        let fam = disc.family();
        let anisotropic = materials.iter().any(|m| m.anisotropy.is_some());
        let weights = anisotropic.then(|| {
            let x = disc.rest_positions();
            let mut w = vec![0.0; fam.num_bonds()];
            for i in 0..n {
                let g = mat(i).anisotropy.unwrap_or(IDENTITY);
                for k in fam.range(i) {
                    let xi = sub(x[fam.neighbours()[k] as usize], x[i]);
                    w[k] = delta / norm(mat_vec(&g, xi));
                }
            }
            w
        });
        let mut moments = vec![(0.0, 0.0); n];
        map_particles(&mut moments, |i| {
            family_moments(&disc, weights.as_deref(), i)
        });
        let c0 = 9.0 / (4.0 * PI * delta.powi(4));
        let c_theta: Vec<f64> = (0..n)
            .map(|i| match moments[i].0 {
                m1 if options.calibrated && m1 > 0.0 => 3.0 / m1,
                _ => c0,
            })
            .collect();
        // a_i = kappa c_i / 2 (= 9 kappa / (8 pi delta^4) uncalibrated): the energy density
        // a theta^2 / c_i is then exactly kappa (3 eps)^2 / 2 under a uniform dilatation
        let coef_a = (0..n)
            .map(|i| {
                if i < active {
                    mat(i).bulk_modulus * c_theta[i] / 2.0
                } else {
                    0.0
                }
            })
            .collect();
        let coef_b: Vec<f64> = (0..n)
            .map(|i| match moments[i].1 {
                _ if i >= active => 0.0,
                m2 if options.calibrated && m2 > 0.0 => 15.0 * mat(i).shear_modulus / (2.0 * m2),
                _ => 15.0 * mat(i).shear_modulus / (2.0 * PI * delta.powi(5)),
            })
            .collect();
        let density: Vec<f64> = (0..n).map(|i| mat(i).density).collect();
        let mass = (0..n).map(|i| density[i] * disc.volumes()[i]).collect();
        let plastic = materials.iter().any(|m| m.plasticity.is_some());
        let fractures = materials.iter().any(ChenMaterial::fractures);
        let reverse = anisotropic.then(|| fam.reverse_index());
        // per particle, the fit's factor of largest magnitude on its bonds (1 unfitted)
        let mut worst = vec![1.0; n];
        // d_ij / c_i, so that theta_i = c_i sum_j (d_ij / c_i) e_ij V_j keeps the kernel's form
        // (omega_ij times the fit's factor on the scalar calibration, bounded by FIT_BOUND)
        let dil_weights = options.fitted_dilatation.then(|| {
            let x = disc.rest_positions();
            // fitted around the calibrated scalar 3 / sum omega r V whether or not the
            // constants are calibrated, then over the particle's own c_i
            let s: Vec<f64> = (0..n)
                .map(|i| match moments[i].0 {
                    m1 if m1 > 0.0 => 3.0 / m1,
                    _ => c0,
                })
                .collect();
            // each material's target: I, or the dilatation its anisotropy reads
            let targets: Vec<[f64; 6]> = materials
                .iter()
                .map(|m| match m.anisotropy {
                    Some(g) if g != IDENTITY => anisotropic_target(&g),
                    _ => ISOTROPIC_TARGET,
                })
                .collect();
            let w = weights.as_deref();
            let target = (targets.as_slice(), disc.materials());
            let l = fit_tensors(fam, x, disc.volumes(), w, delta, &s, target, FIT_RIDGE);
            // each bond carries its reverse's weight too, so the force loop reads both in
            // one stream; both computed in one parallel pass over the rows (the reverse's as
            // its own row computes it), no other per-bond array is allocated
            let mut pairs = vec![[0.0; 2]; fam.num_bonds()];
            let wr = w.zip(reverse.as_deref());
            let (l, bound) = (&l, FIT_BOUND);
            dilatation_weights(
                fam, x, wr, delta, l, &s, bound, &c_theta, &mut pairs, &mut worst,
            );
            pairs
        });
        // the correction's spread over the particles: the dilatation weight's largest over
        // docs/model.md's (`c_i / c0` times the fit's), and `b_i / b0`
        let m0 = PI * delta.powi(5);
        let correction = Correction {
            dilatation: Spread::of((0..active).map(|i| worst[i] * c_theta[i] / c0).collect()),
            deviatoric: Spread::of(
                (0..active)
                    .map(|i| match moments[i].1 {
                        m2 if options.calibrated && m2 > 0.0 => m0 / m2,
                        _ => 1.0,
                    })
                    .collect(),
            ),
        };
        let yield_params = plastic.then(|| {
            (0..n)
                .map(|i| {
                    let plasticity = mat(i).plasticity.filter(|_| i < active);
                    plasticity.map_or((f64::INFINITY, f64::INFINITY), |p| {
                        // a yield strain's Psi0 scales with b_i^2 (A_dev = 4 omega b_i ed)
                        let b0 = 15.0 * mat(i).shear_modulus / (2.0 * PI * delta.powi(5));
                        let scale = if p.from_strain {
                            (coef_b[i] / b0).powi(2)
                        } else {
                            1.0
                        };
                        (p.psi0 * scale, p.gamma_ratio)
                    })
                })
                .collect()
        });
        let yield_inside = yield_params
            .as_deref()
            .map(|p| yield_inside(fam, &coef_b, p));
        let damage = fractures.then(|| {
            let s_crit = (0..n)
                .map(|i| mat(i).fracture.map_or(f64::INFINITY, |f| f.s_crit))
                .collect();
            let alpha = (0..n)
                .map(|i| mat(i).fracture.map_or(0.0, |f| f.alpha))
                .collect();
            Damage::with_counted(fam, s_crit, alpha, active)
        });
        let ep = plastic.then(|| vec![[0.0; 2]; fam.num_bonds()]);
        let (first_pass, changed, ep_rows) = if plastic {
            (vec![[0.0; 4]; n], vec![true; n], vec![0; n])
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        let lanes_run = weights.is_none() && lanes::available();
        let packed = vec![lanes::Packed::default(); if lanes_run { n } else { 0 }];
        Ok(ChenModel {
            setup: Setup {
                c_theta,
                mass,
                density,
                coef_a,
                coef_b,
                weights,
                dil_weights,
                reverse,
                correction,
                active,
                yield_params,
                yield_inside,
                options,
                disc,
            },
            ep,
            ep_floor: 0.0,
            first_pass,
            changed,
            ep_rows,
            damage,
            ts: vec![[0.0; 2]; n],
            pq: vec![[0.0; 2]; n],
            scratch: vec![0.0; n],
            guard: None,
            packed,
        })
    }

    /// Adds the inversion guard of factor `factor` (> 0, finite): a spring of `factor` times
    /// each bond's rest stiffness towards its particle's least-squares affine deformation,
    /// flipped where that is inverted (docs/model.md section 5; `material/guard.rs`). Chen's
    /// bonds are linear springs that store no more energy as a neighbourhood folds through
    /// itself; the guard resists the non-affine part of a deformation, where a fold starts, and
    /// carries nothing under a uniform one. It costs two walks over the bonds a step (with a
    /// 3 x 3 product a bond) and a shorter stable step (at factor 10, 2.8 times on a free steel
    /// block; 1.6 times in a press whose stiff plate already shortened it).
    pub fn with_inversion_guard(mut self, factor: f64) -> Result<Self, PhysicsError> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(PhysicsError::BadSetting(format!(
                "inversion guard factor {factor} must be positive and finite"
            )));
        }
        let s = &self.setup;
        let fam = s.disc.family();
        let vol = s.disc.volumes();
        let mut k = vec![[0.0; 2]; fam.num_bonds()];
        crate::par::for_each_row(fam.offsets(), &mut k, &|i, row: &mut [[f64; 2]]| {
            for (b, slot) in fam.range(i).zip(row) {
                let j = fam.neighbours()[b] as usize;
                let [[dev_ij, dil_ij], [dev_ji, dil_ji]] = s.micromoduli(i, b);
                let vv = vol[i] * vol[j];
                *slot = [(dev_ij + dil_ij) * vv, (dev_ji + dil_ji) * vv];
            }
        });
        self.guard = Some(ChenGuard {
            guard: Guard::new(s.disc.len(), factor),
            k,
        });
        Ok(self)
    }

    /// The inversion guard's factor, if any.
    pub fn inversion_guard(&self) -> Option<f64> {
        self.guard.as_ref().map(|g| g.guard.factor())
    }

    /// Fits the guard's lagged gradients at `y` (bonds as they stand).
    fn refit_guard(&mut self, y: &[Vec3]) {
        if let Some(g) = self.guard.as_mut() {
            let inp = guard_inputs(&self.setup, self.damage.as_ref(), &g.k, y);
            g.guard.update(&inp);
        }
    }

    /// Adds the guard's forces at `y` with the lagged gradients (N).
    fn add_guard_forces(&self, y: &[Vec3], forces: &mut [Vec3]) {
        if let Some(g) = &self.guard {
            let inp = guard_inputs(&self.setup, self.damage.as_ref(), &g.k, y);
            g.guard.add_forces(&inp, forces);
        }
    }

    /// The discretisation.
    pub fn discretization(&self) -> &Discretization {
        &self.setup.disc
    }

    /// Dilatation `theta_i` of each particle from the last force or energy evaluation
    /// (dimensionless; a copy).
    pub fn dilatations(&self) -> Vec<f64> {
        self.ts.iter().map(|t| t[0]).collect()
    }

    /// The options chosen at setup.
    pub fn options(&self) -> ChenOptions {
        self.setup.options
    }

    /// Plastic extension `ep_ij` of each directed bond `i -> j` in bond order (m; a copy), when
    /// some material is plastic.
    pub fn plastic_extensions(&self) -> Option<Vec<f64>> {
        self.ep.as_ref().map(|ep| ep.iter().map(|p| p[0]).collect())
    }

    /// The stored pairs `(ep_ij, ep_ji)` of each directed bond `i -> j` in bond order (m), when
    /// some material is plastic: each bond's own plastic extension and its reverse's.
    pub fn plastic_extension_pairs(&self) -> Option<&[[f64; 2]]> {
        self.ep.as_deref()
    }

    /// Sets the plastic extension of every directed bond (m, in bond order), both ends of each
    /// bond's stored pair. Errors when the model is not plastic or `own` is not one value a
    /// bond.
    pub fn set_plastic_extensions(&mut self, own: &[f64]) -> Result<(), PhysicsError> {
        let fam = self.setup.disc.family();
        let Some(ep) = self.ep.as_mut() else {
            return Err(PhysicsError::BadSetting(
                "plastic extensions given to a model with no plastic material".into(),
            ));
        };
        if own.len() != ep.len() {
            return Err(PhysicsError::LengthMismatch {
                what: "plastic extensions (one per directed bond)",
                expected: ep.len(),
                got: own.len(),
            });
        }
        fill_pairs(fam, own, ep);
        self.ep_floor = WithPlastic { ep }.floor();
        mark_rows(fam, ep, &mut self.ep_rows);
        Ok(())
    }

    /// Damage state, when some material fractures.
    pub fn damage(&self) -> Option<&Damage> {
        self.damage.as_ref()
    }

    /// Cuts the passive particles `newly`, none cut before, out of every family, as a ghost
    /// layer drops a ghost whose source's family broke: their bonds become broken, and count
    /// towards no `phi` ([`Damage::isolate`]); only their rows and their reverses are touched.
    /// Nothing happens without fracture (no bond can break, so no ghost is dropped).
    pub(crate) fn isolate(&mut self, newly: &[u32]) {
        if let Some(d) = self.damage.as_mut() {
            d.isolate(self.setup.disc.family(), newly);
        }
    }

    /// Constants `(a_i, b_i)` of particle `i` (N/m^6 per unit dilatation, N/m^7 per m).
    pub fn constants(&self, i: usize) -> (f64, f64) {
        (self.setup.coef_a[i], self.setup.coef_b[i])
    }

    /// How far the model's constants stray from docs/model.md's (`9 / (4 pi delta^4)` and
    /// `15 mu / (2 pi delta^5)`), per particle: the dilatation weight over docs/model.md's of
    /// largest magnitude among its bonds (`c_i d_ij / (c0 omega_ij)`: `c_i / c0` calibrated,
    /// `n n : L_i / c0` fitted, 1 with neither), and `b_i / b0`.
    pub fn correction(&self) -> Correction {
        self.setup.correction
    }

    /// Recomputes `theta` at `y` with the plastic extensions as they are, then `pq`.
    fn dilatation_pass(&mut self, y: &[Vec3]) {
        if self.ep.is_none() {
            // a plastic model's dilatation pass (a trial, the energy) keeps the scalar loops
            self.pack_positions(y);
        }
        let s = &self.setup;
        let inp = s.inputs(y);
        let active = s.active;
        if let Some(row) = s.lane_row(&self.packed).filter(|_| self.ep.is_none()) {
            let moment = s.options.energy_consistent;
            let (fam, c) = (s.disc.family(), &s.c_theta);
            let alive = self.damage.as_ref().map(Damage::bond_state);
            map_particles(
                &mut self.ts,
                active_only(active, |i| {
                    let (sums, _) = row.dilatation(i, alive.map(|a| &a[fam.range(i)]));
                    theta_moment(c[i], sums, moment).into()
                }),
            );
            self.pressure_pass();
            return;
        }
        with_wpd!(s, self.ep.as_deref(), self.damage.as_ref(), |w, p, d| {
            let ts = &mut self.ts;
            if s.options.energy_consistent {
                map_particles(
                    ts,
                    active_only(active, |i| {
                        dilatation::<_, _, _, true>(inp, w, p, d, i).into()
                    }),
                )
            } else {
                map_particles(
                    ts,
                    active_only(active, |i| {
                        dilatation::<_, _, _, false>(inp, w, p, d, i).into()
                    }),
                )
            }
        });
        self.pressure_pass();
    }

    /// The first pass of a plastic step: `theta` at `y`, the return map of each bond's own end
    /// and `S` (into `ts`), then `pq`. The other ends' return map is [`Self::force_yield_pass`]'s.
    fn yield_pass(&mut self, y: &[Vec3]) {
        self.pack_positions(y);
        let s = &self.setup;
        let (Some(ep), Some(yp)) = (self.ep.as_deref_mut(), s.yield_view()) else {
            return;
        };
        let inp = s.inputs(y);
        let offsets = inp.family.offsets();
        let (rows, last) = (&self.ep_rows, &self.changed);
        let lanes = s.lane_row(&self.packed);
        with_wd!(s, self.damage.as_ref(), |w, d| {
            let body = |first: usize, out: &mut [[f64; 4]], ep: &mut [[f64; 2]]| {
                let base = offsets[first] as usize;
                with_row_buffer(|buf| {
                    for (o, t) in out.iter_mut().enumerate() {
                        let i = first + o;
                        let r = inp.family.range(i);
                        let own = &mut ep[r.start - base..r.end - base];
                        let hint = row_hint(rows, last, i);
                        *t = dilatation_yield(inp, w, d, yp, i, hint, own, buf, lanes);
                    }
                })
            };
            for_rows_mut(offsets, &mut self.first_pass, ep, &body);
        });
        self.finish_first_pass();
    }

    /// `ts` and the floor from the first pass of a plastic step, then `pq`.
    fn finish_first_pass(&mut self) {
        let fam = self.setup.disc.family();
        for (i, ((t, c), &[theta, moment, least, changed])) in self
            .ts
            .iter_mut()
            .zip(&mut self.changed)
            .zip(&self.first_pass)
            .enumerate()
        {
            *t = [theta, moment];
            *c = changed != 0.0;
            if *c {
                mark_own(fam, &mut self.ep_rows, i);
            }
            self.ep_floor = self.ep_floor.min(least);
        }
        self.pressure_pass();
    }

    /// `pq` from the `(theta, S)` of the last dilatation pass.
    fn pressure_pass(&mut self) {
        let s = &self.setup;
        let (a, b, ts) = (&s.coef_a, &s.coef_b, &self.ts);
        let c = &s.c_theta;
        let k = if s.options.energy_consistent {
            1.0 / 3.0
        } else {
            0.0
        };
        map_particles(&mut self.pq, |i| {
            let [theta, m] = ts[i];
            [a[i] * theta - k * c[i] * b[i] * m, b[i] * theta / 3.0]
        });
        if s.lane_row(&self.packed).is_some() {
            let pq = &self.pq;
            update_particles(&mut self.packed, |i, p| {
                let [pi, qi] = pq[i];
                p.pq = [pi, qi, b[i], 0.0];
            });
        }
    }

    /// Stores `y` (m) and the volumes in the packed records where the lane loops can run.
    fn pack_positions(&mut self, y: &[Vec3]) {
        if self.setup.lane_row(&self.packed).is_none() {
            return;
        }
        let vol = self.setup.disc.volumes();
        update_particles(&mut self.packed, |i, p| {
            let [x, y, z] = y[i];
            p.at = [x, y, z, vol[i]];
        });
    }

    /// The damage check and the dilatation pass of an elastic breaking model in one walk over
    /// the bonds (each bond's extension computed once for both), then `pq`. The same results,
    /// bit for bit, as [`ForceModel::break_bonds`] followed by the dilatation pass.
    fn break_and_dilate(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        self.pack_positions(y);
        let s = &self.setup;
        let Some(damage) = self.damage.as_mut() else {
            return;
        };
        let inp = s.inputs(y);
        let delta = s.disc.horizon();
        let ts = &mut self.ts;
        let lanes = s.lane_row(&self.packed);
        // zero-sized: no storage
        let none = &mut vec![(); inp.family.num_bonds()][..];
        with_wd!(@w s, w, {
            if s.options.energy_consistent {
                damage.visit_check(inp.family, delta, (ts, none), &|i, row, _, brk| {
                    let ((theta, m), c, most) =
                        dilatation_breaking::<_, true>(inp, w, lanes, brk, i, row);
                    ([theta, m], c, most)
                })
            } else {
                damage.visit_check(inp.family, delta, (ts, none), &|i, row, _, brk| {
                    let ((theta, m), c, most) =
                        dilatation_breaking::<_, false>(inp, w, lanes, brk, i, row);
                    ([theta, m], c, most)
                })
            }
        });
        damage.finish_check(inp.family, y, delta, NoPlastic, broken);
        self.pressure_pass();
    }

    /// The damage check and the first pass of a plastic step ([`Self::yield_pass`]) in one walk
    /// over the bonds: the check reads the plastic extensions of the last step, as
    /// [`ForceModel::break_bonds`] before the step would, and the return map skips the bonds it
    /// broke. The same results, bit for bit.
    fn break_and_yield(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        self.pack_positions(y);
        let s = &self.setup;
        let (Some(damage), Some(ep), Some(yp)) =
            (self.damage.as_mut(), self.ep.as_deref_mut(), s.yield_view())
        else {
            return;
        };
        let inp = s.inputs(y);
        let delta = s.disc.horizon();
        let floor = self.ep_floor;
        let (rows, last) = (&self.ep_rows, &self.changed);
        let out = (&mut self.first_pass[..], &mut ep[..]);
        let lanes = s.lane_row(&self.packed);
        with_wd!(@w s, w, {
            damage.visit_check(inp.family, delta, out, &|i, row, own, brk| {
                let hint = row_hint(rows, last, i);
                with_row_buffer(|buf| {
                    dilatation_yield_breaking(inp, w, brk, floor, yp, i, hint, row, own, buf, lanes)
                })
            })
        });
        damage.finish_check(inp.family, y, delta, WithPlastic { ep }, broken);
        self.finish_first_pass();
    }

    /// Force pass: `forces[i]` (N) from the current `pq`.
    fn force_pass(&self, y: &[Vec3], forces: &mut [Vec3]) {
        let s = &self.setup;
        let inp = s.inputs(y);
        let (pq, b) = (&self.pq, &s.coef_b);
        if let Some(row) = s.lane_row(&self.packed).filter(|_| self.ep.is_none()) {
            let fam = s.disc.family();
            let alive = self.damage.as_ref().map(Damage::bond_state);
            map_particles(forces, |i| row.force(i, alive.map(|a| &a[fam.range(i)])));
            return;
        }
        with_wpd!(s, self.ep.as_deref(), self.damage.as_ref(), |w, p, d| {
            map_particles(forces, |i| force(inp, w, p, d, pq, b, i))
        })
    }

    /// Force pass of a plastic step after [`Self::yield_pass`]: the return map of each bond's
    /// other end, then `forces[i]` (N) with the new extensions.
    fn force_yield_pass(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        let s = &self.setup;
        let (Some(ep), Some(yp)) = (self.ep.as_deref_mut(), s.yield_view()) else {
            return;
        };
        let inp = s.inputs(y);
        let (pq, ts, changed, rows) = (&self.pq, &self.ts, &self.changed, &self.ep_rows);
        let offsets = inp.family.offsets();
        let lanes = s.lane_row(&self.packed);
        with_wd!(s, self.damage.as_ref(), |w, d| {
            let body = |first: usize, f: &mut [Vec3], ep: &mut [[f64; 2]]| {
                let base = offsets[first] as usize;
                for (o, slot) in f.iter_mut().enumerate() {
                    let i = first + o;
                    let r = inp.family.range(i);
                    let own = &mut ep[r.start - base..r.end - base];
                    // a row of +0.0 whose neighbours changed nothing (else it would have
                    // ROW_SET): the elastic loop, which reads no pair
                    *slot = if rows[i] & ROW_SET == 0 {
                        match lanes {
                            Some(l) => l.force(i, d.row(inp.family, i)),
                            None => force(inp, w, NoPlastic, d, pq, yp.coef_b, i),
                        }
                    } else {
                        force_yield(inp, w, d, pq, yp, ts, changed, i, own)
                    };
                }
            };
            for_rows_mut(offsets, forces, ep, &body);
        });
    }

    #[track_caller]
    fn check_len(&self, y: &[Vec3], forces: Option<&[Vec3]>) {
        self.setup.disc.check_slices(y, forces);
    }
}

impl ForceModel for ChenModel {
    fn num_particles(&self) -> usize {
        self.setup.disc.len()
    }

    fn save_state(&self, w: &mut Writer) {
        w.tag("chen");
        w.array(&self.ts);
        w.bool(self.ep.is_some());
        if let Some(ep) = &self.ep {
            // each bond's own extension, as before the pairs: the reverse's follows from it
            let own: Vec<f64> = ep.iter().map(|p| p[0]).collect();
            w.array(&own);
        }
        w.bool(self.damage.is_some());
        if let Some(d) = &self.damage {
            d.save(w);
        }
        if let Some(g) = &self.guard {
            g.guard.save(w);
        }
    }

    fn restore_state(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("chen")?;
        r.array_into("dilatations", &mut self.ts)?;
        same_features("plastic extension", self.ep.is_some(), r.bool("plastic")?)?;
        if let Some(ep) = &mut self.ep {
            let mut own = vec![0.0; ep.len()];
            r.array_into("plastic extensions", &mut own)?;
            fill_pairs(self.setup.disc.family(), &own, ep);
            self.ep_floor = WithPlastic { ep }.floor();
            mark_rows(self.setup.disc.family(), ep, &mut self.ep_rows);
        }
        same_features("damage", self.damage.is_some(), r.bool("fracture")?)?;
        if let Some(d) = &mut self.damage {
            d.restore(self.setup.disc.family(), r)?;
        }
        // written only with a guard: a scene's checkpoint is read by the same scene's model
        if let Some(g) = &mut self.guard {
            g.guard.restore(r)?;
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
        if self.ep.is_some() {
            self.yield_pass(y);
            self.force_yield_pass(y, forces);
        } else {
            self.dilatation_pass(y);
            self.force_pass(y, forces);
        }
        self.refit_guard(y);
        self.add_guard_forces(y, forces);
    }

    fn break_bonds_and_update_forces(
        &mut self,
        y: &[Vec3],
        broken: &mut Vec<(u32, u32)>,
        forces: &mut [Vec3],
    ) {
        if self.damage.is_none() {
            self.update_forces(y, forces);
            return;
        }
        self.check_len(y, Some(forces));
        if self.ep.is_some() {
            self.break_and_yield(y, broken);
            self.force_yield_pass(y, forces);
        } else {
            self.break_and_dilate(y, broken);
            self.force_pass(y, forces);
        }
        self.refit_guard(y);
        self.add_guard_forces(y, forces);
    }

    fn trial_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.check_len(y, Some(forces));
        self.dilatation_pass(y);
        self.force_pass(y, forces);
        self.add_guard_forces(y, forces);
    }

    fn forces_vanish_at(&self, y: &[Vec3]) -> bool {
        // Every bond's extension is `|y_j - y_i| - r` with `r` computed from these very
        // positions, so exactly zero, and so is each dilatation; every force term carries one
        // of them unless a plastic extension is stored (`ep_rows` marks any that is not +0.0)
        // or the guard pulls towards its fitted gradients. An evaluation here would break no
        // bond, yield none, and leave only the plastic passes' hints, which results never
        // depend on.
        self.guard.is_none()
            && self.ep_rows.iter().all(|r| r & OWN_SET == 0)
            && y == self.setup.disc.rest_positions()
    }

    fn elastic_energy(&mut self, y: &[Vec3]) -> f64 {
        self.check_len(y, None);
        self.dilatation_pass(y);
        let s = &self.setup;
        let inp = s.inputs(y);
        let ts = &self.ts;
        with_wpd!(s, self.ep.as_deref(), self.damage.as_ref(), |w, p, d| {
            map_particles(&mut self.scratch, |i| {
                let (a, b) = (s.coef_a[i], s.coef_b[i]);
                inp.volumes[i] * energy_density(inp, w, p, d, i, ts[i][0], a, b)
            })
        });
        let guard = self.guard.as_ref().map_or(0.0, |g| {
            g.guard
                .energy(&guard_inputs(&self.setup, self.damage.as_ref(), &g.k, y))
        });
        self.scratch.iter().sum::<f64>() + guard
    }

    fn break_bonds(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        let Some(damage) = self.damage.as_mut() else {
            return;
        };
        let s = &self.setup;
        let delta = s.disc.horizon();
        match self.ep.as_deref() {
            None => damage.check(s.disc.family(), y, delta, (NoPlastic, 0.0), broken),
            Some(ep) => {
                let p = (WithPlastic { ep }, self.ep_floor);
                damage.check(s.disc.family(), y, delta, p, broken)
            }
        }
    }

    fn silling_askari_step(&self) -> f64 {
        // Micromodulus of the pair force density 0.5 (A_ij + A_ji) against the bond extension,
        // direct terms only (`Setup::micromoduli`), summed over both ends (N/m^7).
        let s = &self.setup;
        let fam = s.disc.family();
        let vol = s.disc.volumes();
        let mut dt = f64::INFINITY;
        for i in 0..fam.len() {
            let mut sum = 0.0;
            for k in fam.range(i) {
                let j = fam.neighbours()[k] as usize;
                // the order of the sums as before the split (doubling is exact)
                let [[dev_ij, dil_ij], [dev_ji, dil_ji]] = s.micromoduli(i, k);
                sum += (dev_ij + dev_ji + dil_ij + dil_ji) * vol[j];
            }
            if sum > 0.0 {
                dt = dt.min((2.0 * s.density[i] / sum).sqrt());
            }
        }
        // the guard's lagged springs add `f` times each bond's direct stiffness
        dt / (1.0 + self.inversion_guard().unwrap_or(0.0)).sqrt()
    }

    fn damage(&self) -> Option<&Damage> {
        self.damage.as_ref()
    }

    fn memory_bytes(&self) -> usize {
        let ChenModel {
            setup,
            ep,
            ep_floor: _,
            first_pass,
            changed,
            ep_rows,
            damage,
            ts,
            pq,
            scratch,
            guard,
            packed,
        } = self;
        let Setup {
            disc,
            mass,
            density,
            coef_a,
            coef_b,
            c_theta,
            weights,
            dil_weights,
            reverse,
            correction: _,
            active: _,
            yield_params,
            yield_inside,
            options: _,
        } = setup;
        disc.memory_bytes()
            + 8 * (mass.len() + density.len() + coef_a.len() + coef_b.len() + c_theta.len())
            + weights.as_ref().map_or(0, |w| 8 * w.len())
            + dil_weights.as_ref().map_or(0, |w| 16 * w.len())
            + reverse.as_ref().map_or(0, |r| 4 * r.len())
            + yield_params.as_ref().map_or(0, |y| 16 * y.len())
            + yield_inside.as_ref().map_or(0, |y| 24 * y.len())
            + ep.as_ref().map_or(0, |e| 16 * e.len())
            + 32 * first_pass.len()
            + changed.len()
            + ep_rows.len()
            + damage.as_ref().map_or(0, Damage::memory_bytes)
            + 8 * scratch.len()
            + std::mem::size_of_val(&packed[..])
            + 16 * (pq.len() + ts.len())
            + guard
                .as_ref()
                .map_or(0, |g| g.guard.memory_bytes() + 16 * g.k.len())
    }
}

#[cfg(test)]
#[path = "lanes_tests.rs"]
mod lanes_tests;
