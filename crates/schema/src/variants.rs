//! The choices a scene makes and the keys each choice owns: a material's force model (its keys
//! in `[[material]]` and in `[simulation]`) and the integrator. A key given to the wrong choice
//! is refused by serde (see [`super::choice`]).

use serde::Deserialize;
use std::collections::BTreeMap;

/// The force model of a solid scene: `model = "chen"` (the default) or `"xu"` in each
/// `[[material]]`. `C` and `X` are the keys each model takes in the table at hand.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum Model<C, X> {
    /// Chen et al. 2018: elastoplastic, state-based (docs/model.md section 2).
    Chen(C),
    /// Xu et al. 2018: hyperelastic (docs/model.md section 5).
    Xu(X),
}

impl<C, X> Model<C, X> {
    /// Which model this is.
    pub fn kind(&self) -> crate::ModelKind {
        match self {
            Model::Chen(_) => crate::ModelKind::Chen,
            Model::Xu(_) => crate::ModelKind::Xu,
        }
    }
}

impl<C: Default, X> Default for Model<C, X> {
    fn default() -> Self {
        Model::Chen(C::default())
    }
}

/// A material's model and the material keys only it takes.
pub type MaterialModel = Model<ChenKeys, XuKeys>;

/// The scene's model and the `[simulation]` keys only it takes.
pub type SimulationModel = Model<ChenSettings, XuSettings>;

/// Material keys of Chen's model: plasticity.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ChenKeys {
    /// Yield limit `Psi0` in the raw units of `A^2` (depends on the horizon); or `yield_strain`.
    pub yield_psi0: Option<f64>,
    /// Yield as a deviatoric bond strain (dimensionless), converted to `Psi0` for the horizon.
    pub yield_strain: Option<f64>,
    /// Plastic extension cap as a ratio of the rest bond length (default 0.2 when plastic).
    pub plastic_cap: Option<f64>,
}

/// Material keys of Xu's model: the energy's curves and how the moduli become its constants.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct XuKeys {
    /// The named energy for both curves (default neo-Hookean).
    pub energy: Option<Energy>,
    /// A custom dilatation curve `g`, basis names to coefficients (`{ A1 = 1.0 }`).
    pub g: Option<BTreeMap<String, f64>>,
    /// A custom bond curve `h`, basis names to coefficients (`{ B3 = 1.5, B1 = -0.5 }`).
    pub h: Option<BTreeMap<String, f64>>,
    /// How `young` and `poisson` become the model's `lambda` and `mu` (default consistent).
    pub moduli: Option<Moduli>,
}

/// A material preset: handbook constants for the keys a material does not give
/// (docs/scenes.md, "Material presets", has the values and their sources).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// Soda-lime glass.
    Glass,
    /// Alumina, 99.5%.
    Ceramic,
    /// Normal-strength concrete (C30).
    Concrete,
    /// Structural steel.
    Steel,
    /// Aluminium alloy 6061-T6.
    Aluminium,
    /// Natural rubber.
    Rubber,
    /// Acrylic glass (PMMA).
    Acrylic,
}

/// Xu's named energies.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Energy {
    /// Linear elasticity.
    Linear,
    /// Neo-Hookean (the default).
    NeoHookean,
    /// Saint Venant-Kirchhoff.
    Stvk,
}

/// How Xu's `lambda` and `mu` follow from `young` and `poisson`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Moduli {
    /// The small-strain moduli of a full family equal the given ones (the default).
    Consistent,
    /// The paper's conversion.
    Paper,
}

/// `[simulation]` keys of Chen's model.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ChenSettings {
    /// How the constants meet the discrete family (default fitted).
    pub correction: Option<ChenCorrection>,
    /// With `correction = "ghosts"`: how a ghost extrapolates its source's displacement
    /// (default quadratic).
    pub ghost_fit: Option<GhostFitKey>,
}

/// `[simulation]` keys of Xu's model.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct XuSettings {
    /// Whether the dilatation's weights are fitted per particle (default fitted).
    pub correction: Option<XuCorrection>,
    /// The influence function (default constant).
    pub influence: Option<Influence>,
}

/// How Chen's constants meet the discrete family.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ChenCorrection {
    /// The dilatation fitted per bond, `b` calibrated (the default).
    Fitted,
    /// Scalars per particle.
    Calibrated,
    /// docs/model.md's constants.
    None,
    /// The fitted correction over families completed by ghost particles.
    Ghosts,
}

/// Whether Xu's dilatation weights are fitted.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum XuCorrection {
    /// Fitted per particle, back on the normalised ones once it loses a bond (the default).
    Fitted,
    /// The normalised weights.
    None,
}

/// How a ghost extrapolates its source's displacement.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum GhostFitKey {
    /// A quadratic fit (the default).
    Quadratic,
    /// An affine fit.
    Affine,
}

/// Xu's influence function.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Influence {
    /// Constant (the default).
    Constant,
    /// Inverse of the bond length.
    Inverse,
    /// Linear decay to the horizon.
    Linear,
}

/// The integrator of a solid scene: `integrator = "explicit"` (the default) or `"implicit"` in
/// `[simulation]`, with the keys only it takes.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Velocity Verlet under the stable limit.
    Explicit(ExplicitKeys),
    /// Quasi-Newton (Xu's model).
    Implicit(ImplicitKeys),
}

impl Default for Integrator {
    fn default() -> Self {
        Integrator::Explicit(ExplicitKeys::default())
    }
}

/// `[simulation]` keys of the explicit integrator.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ExplicitKeys {
    /// Fraction of the stable limit used by `"auto"` (default 0.8).
    pub safety: Option<f64>,
    /// Cover each step by sub-steps of `dt 2^-k`, refined where forces jump or bonds break
    /// late (default false).
    pub event_search: Option<bool>,
    /// Event search: the finest level `k_max` (default 4).
    pub event_levels: Option<u32>,
    /// Event search: the largest force may grow by this factor in a sub-step (default 1.1).
    pub force_growth: Option<f64>,
    /// Event search: a bond may break this share past its threshold (default 0.1).
    pub overshoot: Option<f64>,
}

/// `[simulation]` keys of the implicit integrator.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ImplicitKeys {
    /// Steps per frame when `dt = "auto"` (default 1).
    pub steps_per_frame: Option<u64>,
    /// Iterations per step at most (default 100).
    pub iterations: Option<usize>,
    /// Relative decrease at which a step stops (default 1e-4).
    pub tolerance: Option<f64>,
    /// L-BFGS pairs kept (default 10; 0: the constant matrix alone).
    pub history: Option<usize>,
    /// Refactor the step matrix when this share of the bonds broke since the last
    /// factorisation (default 0.02).
    pub refactor_share: Option<f64>,
}

/// The integrator of a shell scene: `integrator = "explicit"` (the default) or `"newmark"`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum ShellIntegrator {
    /// Velocity Verlet under the stable limit.
    Explicit(NoKeys),
    /// The paper's implicit average-acceleration rule: any step, `dt` in seconds required.
    Newmark(NewmarkKeys),
}

impl Default for ShellIntegrator {
    fn default() -> Self {
        ShellIntegrator::Explicit(NoKeys {})
    }
}

/// A choice that takes no keys of its own.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct NoKeys {}

/// `[simulation]` keys of a shell's Newmark step.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct NewmarkKeys {
    /// L-BFGS iterations per step at most (default 200; under the search, a trial that needs
    /// more than 30 is undone and halved).
    pub iterations: Option<usize>,
    /// The residual force a step stops at, as a share of its force scale (default 1e-6).
    pub tolerance: Option<f64>,
}
