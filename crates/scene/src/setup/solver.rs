//! The force model and the integrator the scene names, built into one [`Solver`].

use perifrac_physics::integrate::event_search::MAX_LEVELS;
use perifrac_physics::math::Vec3;
use perifrac_physics::{
    ChenModel, ChenOptions, Correction, Discretization, EventSearchConfig, Explicit,
    ExplicitConfig, FaceKind, ForceModel, GhostFaces, GhostFit, GhostLayer, GhostPlane,
    GhostReport, Ghosted, Implicit, ImplicitConfig, Loads, PhysicsError, Searched, Solver, Spread,
    TimeStep, XuKernelShape, XuModel, XuOptions,
};
use perifrac_topology::{BoundaryPlanes, TetMesh};

use crate::error::SceneError;
use crate::schema::{
    ChenCorrection, ExplicitKeys, GhostFitKey, Influence, Integrator, Model, SimulationSpec,
    XuCorrection,
};

use super::check::Ctx;
use super::defaults;
use super::material::Materials;

/// Checks the keys of the integrator `[simulation]` names (no scene mesh needed, so a bad
/// value is refused before any setup work).
pub(super) fn check_integrator(ctx: &Ctx, sim: &SimulationSpec) -> Result<(), SceneError> {
    match &sim.integrator {
        Integrator::Explicit(e) => {
            let search = [
                ("event_levels", e.event_levels.is_some()),
                ("force_growth", e.force_growth.is_some()),
                ("overshoot", e.overshoot.is_some()),
            ];
            if e.event_search != Some(true) {
                if let Some((k, _)) = search.iter().find(|(_, given)| *given) {
                    return Err(ctx.err(
                        format!("simulation.{k}"),
                        "is a setting of the event search: add event_search = true",
                    ));
                }
            }
            Ok(())
        }
        Integrator::Implicit(i) => {
            if i.steps_per_frame == Some(0) {
                return Err(ctx.err("simulation.steps_per_frame", "must be at least 1"));
            }
            if i.iterations == Some(0) {
                return Err(ctx.err("simulation.iterations", "must be at least 1"));
            }
            if let Some(t) = i.tolerance {
                if !(t > 0.0 && t < 1.0) {
                    return Err(ctx.err("simulation.tolerance", format!("{t} must be in (0, 1)")));
                }
            }
            if let Some(r) = i.refactor_share {
                ctx.non_negative("simulation.refactor_share", r)?;
            }
            Ok(())
        }
    }
}

/// A force model of either kind, before an integrator owns it.
pub(super) enum AnyModel {
    /// Chen's (each variant boxed: the enum is moved whole, and the models differ in size).
    Chen(Box<ChenModel>),
    /// Chen's over families completed by ghost particles (`correction = "ghosts"`).
    ChenGhosts(Box<Ghosted<ChenModel>>),
    /// Xu's.
    Xu(Box<XuModel>),
}

impl AnyModel {
    /// The model as the physics crate's interface.
    pub(super) fn as_dyn(&mut self) -> &mut dyn ForceModel {
        match self {
            AnyModel::Chen(m) => m,
            AnyModel::ChenGhosts(m) => m.as_mut(),
            AnyModel::Xu(m) => m,
        }
    }

    /// How Chen's constants stray from docs/model.md's (`None` for Xu's).
    pub(super) fn correction(&self) -> Option<Correction> {
        match self {
            AnyModel::Chen(m) => Some(m.correction()),
            AnyModel::ChenGhosts(m) => Some(m.inner().correction()),
            // Xu's bond term keeps its normalised weights (factor 1)
            AnyModel::Xu(m) => m.correction().map(|dilatation| Correction {
                dilatation,
                deviatoric: Spread::of(Vec::new()),
            }),
        }
    }

    /// What the build of the ghosts found, with ghosts.
    pub(super) fn ghosts(&self) -> Option<GhostReport> {
        match self {
            AnyModel::ChenGhosts(m) => Some(m.layer().report().clone()),
            _ => None,
        }
    }

    /// Heap bytes of the ghost layer (0 without ghosts).
    pub(super) fn ghost_layer_bytes(&self) -> usize {
        match self {
            AnyModel::ChenGhosts(m) => m.layer().memory_bytes(),
            _ => 0,
        }
    }
}

/// A mesh's boundary as the faces ghosts are mirrored across (all free).
struct MeshFaces(BoundaryPlanes);

impl GhostFaces for MeshFaces {
    fn near(&self, x: Vec3, horizon: f64, out: &mut Vec<GhostPlane>) {
        let planes = self.0.near(x, horizon).into_iter();
        out.extend(planes.map(|(point, normal)| GhostPlane {
            point,
            normal,
            kind: FaceKind::Free,
        }));
    }

    fn inside(&self, x: Vec3) -> bool {
        self.0.inside(x)
    }

    fn has_clamped(&self) -> bool {
        false
    }
}

/// A check of the memory a run with a ghost layer needs, given the layer's report and bytes,
/// made before the model over it is built.
pub(super) type GhostCheck<'a> = &'a dyn Fn(&GhostReport, usize) -> Result<(), SceneError>;

/// The model of `materials` over `disc` (the particles of `mesh`), with the options of `sim`;
/// `check` refuses a ghost layer whose run would not fit in memory.
pub(super) fn model(
    ctx: &Ctx,
    sim: &SimulationSpec,
    disc: Discretization,
    mesh: &TetMesh,
    materials: &Materials,
    check: GhostCheck,
) -> Result<AnyModel, SceneError> {
    let physics = |cause: PhysicsError| ctx.physics(cause);
    // the parser names the materials' model in `sim.model`
    let mixed = || ctx.err("simulation", "the materials' model and its settings differ");
    match materials {
        Materials::Chen(m) => {
            let keys = match &sim.model {
                Model::Chen(k) => k,
                Model::Xu(_) => return Err(mixed()),
            };
            let base = ChenOptions::default();
            let ghosts = keys.correction == Some(ChenCorrection::Ghosts);
            if keys.ghost_fit.is_some() && !ghosts {
                return Err(ctx.err(
                    "simulation.ghost_fit",
                    "is a setting of the ghost particles: add correction = \"ghosts\"",
                ));
            }
            let options = match keys.correction {
                None | Some(ChenCorrection::Fitted) | Some(ChenCorrection::Ghosts) => base,
                Some(ChenCorrection::Calibrated) => ChenOptions {
                    fitted_dilatation: false,
                    ..base
                },
                Some(ChenCorrection::None) => ChenOptions {
                    calibrated: false,
                    fitted_dilatation: false,
                    ..base
                },
            };
            if ghosts {
                let fit = match keys.ghost_fit {
                    None | Some(GhostFitKey::Quadratic) => GhostFit::Quadratic,
                    Some(GhostFitKey::Affine) => GhostFit::Affine,
                };
                return ghosted(ctx, sim, disc, mesh, m.as_slice(), options, fit, check);
            }
            let model = ChenModel::with_options(disc, m, options).map_err(physics)?;
            let model = match guard_factor(ctx, sim)? {
                None => model,
                Some(f) => model.with_inversion_guard(f).map_err(physics)?,
            };
            Ok(AnyModel::Chen(Box::new(model)))
        }
        Materials::Xu(m) => {
            let keys = match &sim.model {
                Model::Xu(k) => k,
                Model::Chen(_) => return Err(mixed()),
            };
            let fitted_dilatation = match keys.correction {
                None => XuOptions::default().fitted_dilatation,
                Some(XuCorrection::Fitted) => true,
                Some(XuCorrection::None) => false,
            };
            let kernel = match keys.influence {
                None | Some(Influence::Constant) => XuKernelShape::Constant,
                Some(Influence::Inverse) => XuKernelShape::Inverse,
                Some(Influence::Linear) => XuKernelShape::Linear,
            };
            let inversion_guard = guard_factor(ctx, sim)?;
            let options = XuOptions {
                kernel,
                inversion_guard,
                fitted_dilatation,
            };
            Ok(AnyModel::Xu(Box::new(
                XuModel::new(disc, m, options).map_err(physics)?,
            )))
        }
    }
}

/// Chen's model of `materials` over `disc` with ghosts across the boundary of `mesh`
/// (`correction = "ghosts"`, each ghost extrapolated by `fit`), with the inversion guard when
/// asked for (its springs on the ghosts' bonds too).
#[allow(clippy::too_many_arguments)]
fn ghosted(
    ctx: &Ctx,
    sim: &SimulationSpec,
    disc: Discretization,
    mesh: &TetMesh,
    materials: &[perifrac_physics::ChenMaterial],
    options: ChenOptions,
    fit: GhostFit,
    check: GhostCheck,
) -> Result<AnyModel, SceneError> {
    let guard = guard_factor(ctx, sim)?;
    let physics = |cause: PhysicsError| ctx.physics(cause);
    let faces = MeshFaces(BoundaryPlanes::new(mesh, disc.horizon()));
    let layer = GhostLayer::build_with(&disc, &faces, fit).map_err(physics)?;
    check(layer.report(), layer.memory_bytes())?;
    let real = disc.len();
    let inner = ChenModel::with_passive(layer.extended().clone(), materials, options, real)
        .map_err(physics)?;
    let inner = match guard {
        None => inner,
        Some(f) => inner.with_inversion_guard(f).map_err(physics)?,
    };
    let model = Ghosted::new(disc, layer, inner).map_err(physics)?;
    Ok(AnyModel::ChenGhosts(Box::new(model)))
}

/// `simulation.inversion_guard`, the factor on each bond's rest stiffness, checked positive
/// (absent: no guard).
fn guard_factor(ctx: &Ctx, sim: &SimulationSpec) -> Result<Option<f64>, SceneError> {
    sim.inversion_guard
        .map(|f| ctx.positive("simulation.inversion_guard", f, ""))
        .transpose()
}

/// The event search's settings from the explicit integrator's keys, each checked.
fn search_config(ctx: &Ctx, sim: &ExplicitKeys) -> Result<EventSearchConfig, SceneError> {
    let base = EventSearchConfig::default();
    let levels = sim.event_levels.unwrap_or(base.levels);
    if levels > MAX_LEVELS {
        return Err(ctx.err(
            "simulation.event_levels",
            format!("{levels} is more than {MAX_LEVELS} (2^{MAX_LEVELS} sub-steps per step)"),
        ));
    }
    let force_growth = sim.force_growth.unwrap_or(base.force_growth);
    // inf turns the force test off
    if force_growth.is_nan() || force_growth <= 1.0 {
        return Err(ctx.err(
            "simulation.force_growth",
            format!("{force_growth} must be a factor above 1 (inf: no force test)"),
        ));
    }
    let overshoot = match sim.overshoot {
        Some(o) => ctx.non_negative("simulation.overshoot", o)?,
        None => base.overshoot,
    };
    Ok(EventSearchConfig {
        levels,
        force_growth,
        overshoot,
        ..base
    })
}

/// Where a solver starts: at rest at `rest` (m), with `loads`, stepping `dt` (s); `horizon`
/// (m) scales the explicit blow-up guard.
pub(super) struct Start<'a> {
    pub rest: &'a [[f64; 3]],
    pub horizon: f64,
    pub loads: Loads,
    pub dt: f64,
}

/// The solver: `model` stepped by the scene's integrator from `start`.
pub(super) fn build(
    ctx: &Ctx,
    sim: &SimulationSpec,
    model: AnyModel,
    start: Start,
) -> Result<Box<dyn Solver>, SceneError> {
    let Start {
        rest,
        horizon,
        loads,
        dt,
    } = start;
    let physics = |cause: PhysicsError| ctx.physics(cause);
    let explicit = ExplicitConfig {
        dt: TimeStep::Fixed(dt),
        guard_fraction: defaults::GUARD_FRACTION,
    };
    if let Integrator::Explicit(
        e @ ExplicitKeys {
            event_search: Some(true),
            ..
        },
    ) = &sim.integrator
    {
        let search = search_config(ctx, e)?;
        return Ok(match model {
            AnyModel::Chen(m) => Box::new(
                Searched::new(*m, rest, horizon, loads, explicit, search).map_err(physics)?,
            ),
            AnyModel::ChenGhosts(m) => Box::new(
                Searched::new(*m, rest, horizon, loads, explicit, search).map_err(physics)?,
            ),
            AnyModel::Xu(m) => Box::new(
                Searched::new(*m, rest, horizon, loads, explicit, search).map_err(physics)?,
            ),
        });
    }
    Ok(match (&sim.integrator, model) {
        (Integrator::Explicit(_), AnyModel::Chen(m)) => {
            Box::new(Explicit::new(*m, rest, horizon, loads, explicit).map_err(physics)?)
        }
        (Integrator::Explicit(_), AnyModel::ChenGhosts(m)) => {
            Box::new(Explicit::new(*m, rest, horizon, loads, explicit).map_err(physics)?)
        }
        (Integrator::Explicit(_), AnyModel::Xu(m)) => {
            Box::new(Explicit::new(*m, rest, horizon, loads, explicit).map_err(physics)?)
        }
        (Integrator::Implicit(keys), AnyModel::Xu(m)) => {
            let base = ImplicitConfig::with_dt(dt);
            let config = ImplicitConfig {
                max_iterations: keys.iterations.unwrap_or(base.max_iterations),
                tolerance: keys.tolerance.unwrap_or(base.tolerance),
                history: keys.history.unwrap_or(base.history),
                refactor_share: keys.refactor_share.unwrap_or(base.refactor_share),
                ..base
            };
            Box::new(Implicit::new(*m, rest, loads, config).map_err(physics)?)
        }
        (Integrator::Implicit(_), AnyModel::Chen(_) | AnyModel::ChenGhosts(_)) => {
            return Err(ctx.err(
                "simulation.integrator",
                "\"implicit\" needs an energy with a rest stiffness: give the materials \
                 model = \"xu\" (Chen's elastoplastic model steps explicitly)",
            ))
        }
    })
}
