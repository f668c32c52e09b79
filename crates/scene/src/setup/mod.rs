//! From a parsed scene to a ready [`Driver`]: validation with one clear message per problem, the
//! mesh, materials by region, initial cracks, the peridynamic model, colliders, loads and the
//! time step. Nothing is written to disk here, except by a memo of stable-step estimates the
//! caller passes ([`Setup::with_memo`]).

pub(crate) mod check;
pub use check::MAX_FPS;
pub(crate) mod colliders;
pub(crate) mod loads;
mod material;
pub use material::FromEnergy;
pub(crate) mod math;
mod mesh;
pub mod presets;
mod radii;
mod self_contact;
mod solver;
pub(crate) mod step;
mod xu_material;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use perifrac_physics::{
    Correction, Discretization, EstimateMemo, GhostReport, IntegratorKind, PhysicsError,
};

use crate::budget::{self, Limits, MeshShape, WorkEstimate};
use crate::driver::Driver;
use crate::error::SceneError;
use crate::load::Scene;
use crate::schema::{Integrator, SceneFile};

use check::Ctx;
pub(crate) use math::bounds;

/// Defaults the scene may override.
pub mod defaults {
    /// Horizon factor (the paper's 1.45).
    pub const HORIZON_FACTOR: f64 = 1.45;
    /// Fraction of the stable limit for `dt = "auto"`.
    pub const SAFETY: f64 = 0.8;
    /// Frames after the initial one.
    pub const FRAMES: usize = 24;
    /// Box cells across the longest side when neither `cells` nor `resolution` is given.
    pub const BOX_RESOLUTION: usize = 20;
    /// Seed of an unstructured box's points when the scene gives none.
    pub const MESH_SEED: u64 = 1;
    /// Plastic cap ratio when a yield limit is given without one.
    pub const PLASTIC_CAP: f64 = 0.2;
    /// Contact penalty factor on `E r_p`.
    pub const STIFFNESS_FACTOR: f64 = perifrac_contact::ContactParams::DEFAULT_STIFFNESS_FACTOR;
    /// Contact normal damping ratio.
    pub const DAMPING_RATIO: f64 = 0.1;
    /// Coulomb friction.
    pub const FRICTION: f64 = 0.5;
    /// Facets around the round primitives' surfaces before meshing.
    pub const ROUND_SEGMENTS: usize = 64;
    /// A fixed step may be at most this fraction of the estimated limit: the Lanczos estimate
    /// converges from below, so the estimate itself is not a safe step.
    pub const MAX_FIXED_FRACTION: f64 = 0.95;
    /// The blow-up guard: a step that moves a particle further than this fraction of the
    /// horizon stops the run.
    pub const GUARD_FRACTION: f64 = 0.5;
    /// `dt = "auto"` also keeps the fastest ball or particle at the start from moving more than
    /// this fraction of the mean contact radius per step, so that a contact builds up over
    /// several steps instead of appearing at full depth in one.
    pub const TRAVEL_FRACTION: f64 = 0.1;
    /// The implicit step's `dt = "auto"` keeps the fastest body at the start from moving more
    /// than this fraction of the mean contact radius per step: the contact potential is then
    /// seen within a step, never tunnelled through.
    pub const IMPLICIT_TRAVEL_FRACTION: f64 = 1.0;
    /// `perifrac run` warns when one particle in a hundred has a calibrated `b_i` over
    /// docs/model.md's `b` past this: `b_i / b` is a full ball's moment over the particle's
    /// family's, so such a particle has lost most of its neighbours (a tet far larger than the horizon,
    /// or a thin part one or two tets across) and its stiffness rests on a few bonds. Meshes of
    /// `perifrac mesh` stay under it (99th percentiles 2.8 to 6.2 on the shared surfaces at
    /// resolution 20), while their largest factors, on a few corner slivers, reach 12 to 31.
    pub const CORRECTION_WARNING: f64 = 10.0;
    /// ... or when any passes this: that particle rings at about the square root of it times
    /// the frequency of a full family, and sets the stable step alone.
    pub const CORRECTION_WARNING_MAX: f64 = 100.0;
    /// `perifrac run` warns on a material whose Young's modulus (Pa) is under this: the softest
    /// gels are about a kilopascal, so a smaller value is most likely a unit slip (`young = 70`
    /// for 70 GPa).
    pub const SOFTEST_SOLID: f64 = 1e3;
}

pub use perifrac_schema::ModelKind;

/// What the run writes besides the surface PLY.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputOptions {
    /// POV-Ray `mesh2` includes.
    pub povray: bool,
    /// Particles with damage as PLY points.
    pub particles: bool,
    /// When to write checkpoints at frame boundaries.
    pub checkpoints: CheckpointPolicy,
    /// Write the run as a USD cache at its end, in this layout.
    pub usd: Option<crate::usd::UsdLayout>,
    /// Playback frames per second of caches.
    pub fps: f64,
    /// Relax each frame's crack faces towards their local crack plane, with these settings
    /// (`None`: as cut).
    pub smooth_cracks: Option<perifrac_topology::CrackSmoothing>,
    /// Pieces of at most this many tets are written as debris points, not surfaces (0: none).
    pub debris_tets: usize,
}

/// Pieces of at most this many tets are debris unless the scene says otherwise (`[output]
/// debris_tets`): chosen from the fragment sizes of `perifrac bench look` (BENCHMARKS.md, "The
/// look of the cut").
pub const DEFAULT_DEBRIS_TETS: usize = 3;

/// When a run writes a checkpoint at a frame boundary (an interrupted run always writes one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CheckpointPolicy {
    /// After every `n` frames.
    EveryFrames(usize),
    /// After the first frame that ends this many seconds of wall time or more after the last
    /// checkpoint (or the start).
    EverySeconds(u64),
    /// Only when interrupted.
    OnInterrupt,
}

impl CheckpointPolicy {
    /// The policy `[output] checkpoint_every` names: after every `n` frames, only when
    /// interrupted for 0, and every [`DEFAULT_CHECKPOINT_SECONDS`] when the key is left out.
    pub fn from_key(every: Option<usize>) -> CheckpointPolicy {
        match every {
            None => CheckpointPolicy::EverySeconds(DEFAULT_CHECKPOINT_SECONDS),
            Some(0) => CheckpointPolicy::OnInterrupt,
            Some(n) => CheckpointPolicy::EveryFrames(n),
        }
    }

    /// Whether a checkpoint is due once frame `frame` is written (the initial frame is 0),
    /// `since` the wall time since the last checkpoint (or the start).
    pub fn due(self, frame: usize, since: std::time::Duration) -> bool {
        match self {
            CheckpointPolicy::EveryFrames(n) => frame > 0 && frame.is_multiple_of(n),
            CheckpointPolicy::EverySeconds(s) => since.as_secs() >= s,
            CheckpointPolicy::OnInterrupt => false,
        }
    }
}

/// The wall time between checkpoints when the scene does not say (s).
pub const DEFAULT_CHECKPOINT_SECONDS: u64 = 300;

/// Facts about the prepared scene, for the summary and `run.json`.
#[derive(Debug, Clone, PartialEq)]
pub struct SetupInfo {
    /// Particles (= tets).
    pub particles: usize,
    /// Directed bonds.
    pub bonds: usize,
    /// Horizon (m).
    pub horizon: f64,
    /// Mean tet edge length (m).
    pub edge_length: f64,
    /// Stable step estimate of the explicit integrator (s), contact stiffness included (for
    /// an implicit scene: how far its step is beyond it).
    pub dt_limit: f64,
    /// Longest step (s) in which the fastest ball or particle at the start moves
    /// [`defaults::TRAVEL_FRACTION`] of the mean contact radius; infinite without colliders.
    pub travel_limit: f64,
    /// The step used (s): the requested one, shortened so that frames fall on steps.
    pub dt: f64,
    /// Total particle mass (kg).
    pub mass: f64,
    /// World up: opposite gravity, +z without gravity.
    pub up: [f64; 3],
    /// Rest bounding box (m).
    pub rest_bounds: ([f64; 3], [f64; 3]),
    /// Crack faces cut at the start.
    pub precrack_faces: usize,
    /// The thresholds set from a material's `fracture_energy`.
    pub from_energy: Vec<FromEnergy>,
    /// Materials softer than any solid: index and Young's modulus (Pa) under
    /// [`defaults::SOFTEST_SOLID`].
    pub too_soft: Vec<(usize, f64)>,
    /// The force model.
    pub model: ModelKind,
    /// The integrator.
    pub integrator: IntegratorKind,
    /// How far the constants stray from docs/model.md's: per particle, the largest factor on its
    /// dilatation weights and Chen's factor on `b` (Xu's: the fitted dilatation's factors on
    /// the normalised weights, its bond term's all 1; `None` with Xu's normalised weights).
    pub correction: Option<Correction>,
    /// What the build of the ghost particles found (`correction = "ghosts"`).
    pub ghosts: Option<GhostReport>,
    /// The work estimate the run was checked against: memory from the counted bonds, steps,
    /// output and wall time.
    pub estimate: WorkEstimate,
    /// Wall time of the setup's stages.
    pub times: SetupTimes,
}

/// Wall time of the setup's stages (not written to `run.json`: two runs of one scene write
/// identical files).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SetupTimes {
    /// The mesh: built or read, materials assigned by region, precracks cut.
    pub mesh: Duration,
    /// The bond families (neighbour walk, symmetrisation, rest lengths).
    pub families: Duration,
    /// The force model: per-bond state, weights, shape tensors.
    pub model: Duration,
    /// The stable-step estimate.
    pub stable_step: Duration,
    /// Whether the material's stable-step estimate was recalled from a memo
    /// ([`Setup::with_memo`]) rather than iterated.
    pub stable_step_recalled: bool,
    /// The whole setup, the stages above included.
    pub total: Duration,
}

/// A scene ready to run.
pub struct Setup {
    /// The scene file.
    pub scene_path: PathBuf,
    /// Its text (copied into the output directory).
    pub scene_text: String,
    /// The simulation state.
    pub driver: Driver,
    /// Frames after the initial one.
    pub frames: usize,
    /// Steps between frames.
    pub steps_per_frame: u64,
    /// What to write.
    pub output: OutputOptions,
    /// Facts for the summary.
    pub info: SetupInfo,
}

impl Setup {
    /// Validates and builds everything `scene` asks for; `frames` overrides the scene's frame
    /// count. Refuses a run past the default budgets on this machine
    /// ([`Limits::for_this_machine`]); see [`Setup::with_limits`].
    pub fn new(scene: &Scene, frames: Option<usize>) -> Result<Setup, SceneError> {
        Setup::with_limits(scene, frames, &Limits::for_this_machine())
    }

    /// [`Setup::new`] against `limits`: the memory a run needs is estimated before the mesh
    /// and again before the bond families are built, its steps, output and wall time once the
    /// step is known (and earlier where the frame count or the contact travel limit alone
    /// pass the budget), and a run past a budget is refused with [`SceneError::TooLarge`]
    /// quoting the estimate, unless `limits.allow_large`. The estimate is kept in
    /// [`SetupInfo::estimate`].
    pub fn with_limits(
        scene: &Scene,
        frames: Option<usize>,
        limits: &Limits,
    ) -> Result<Setup, SceneError> {
        Setup::with_memo(scene, frames, limits, None)
    }

    /// [`Setup::with_limits`], recalling the material's stable-step estimate from `memo` (a
    /// [`crate::memo::MemoDir`], say) when a run before built the same model, and storing it
    /// there otherwise: the recalled estimate is the iterated one bit for bit, after one force
    /// evaluation in place of the whole iteration (two for a model that cannot vouch for its
    /// forces at rest; [`SetupTimes::stable_step_recalled`]).
    pub fn with_memo(
        scene: &Scene,
        frames: Option<usize>,
        limits: &Limits,
        memo: Option<&dyn EstimateMemo>,
    ) -> Result<Setup, SceneError> {
        let started = Instant::now();
        let mut times = SetupTimes::default();
        let ctx = Ctx { file: &scene.path };
        let too_large = |message: String| SceneError::TooLarge {
            file: scene.path.clone(),
            message,
        };
        let resolved = presets::resolve(&scene.file);
        let f = &resolved;
        check::check_settings(&ctx, f)?;
        solver::check_integrator(&ctx, &f.simulation)?;
        let implicit = matches!(f.simulation.integrator, Integrator::Implicit(_));
        if implicit && material::scene_model(f) == ModelKind::Chen {
            return Err(ctx.err(
                "simulation.integrator",
                "\"implicit\" needs an energy with a rest stiffness: give the materials \
                 model = \"xu\" (Chen's elastoplastic model steps explicitly)",
            ));
        }
        let physics = |cause: PhysicsError| ctx.physics(cause);
        let sim = &f.simulation;
        let frames = frames
            .or(f.output.frames)
            .unwrap_or(defaults::FRAMES)
            .max(1);
        // Every frame takes at least one step: refused before any mesh is made.
        limits
            .check_steps(
                frames as u64,
                &format!("{frames} frames of at least one step"),
            )
            .map_err(too_large)?;
        let horizon_factor = sim.horizon_factor.unwrap_or(defaults::HORIZON_FACTOR);

        // Memory, from the mesh spec, before the mesh is built.
        let extra = budget::extra_per_bond(implicit, sim.inversion_guard.is_some());
        let planned = mesh::plan(&ctx, scene)?;
        let planned_shape = planned.shape;
        limits
            .check_memory(&WorkEstimate::of_mesh(planned_shape, horizon_factor, extra))
            .map_err(too_large)?;
        let stage = Instant::now();
        let mut mesh = mesh::build(scene, planned)?;
        let rest = mesh.rest_barycentres();
        let volumes = mesh.rest_volumes();
        let edge = mesh.mean_edge_length();
        let horizon = horizon_factor * edge;
        // Memory again, from the built mesh, before the bond families are.
        let built = MeshShape {
            tets: rest.len() as u64,
            vertices: mesh.num_vertices() as u64,
            mean_edge: edge,
            mean_volume: volumes.iter().sum::<f64>() / volumes.len().max(1) as f64,
        };
        let estimate = WorkEstimate::of_mesh(built, horizon_factor, extra);
        limits.check_memory(&estimate).map_err(too_large)?;

        let (mut materials, ids) = material::materials_by_region(&ctx, f, &rest, horizon)?;
        // on the rest boundary, before any initial crack adds faces
        let region_loads = loads::region_loads(&ctx, f, &mesh, &rest, &volumes)?;
        let (adjacency, precrack_faces) = mesh::precracks(&ctx, f, &mut mesh, &rest)?;
        times.mesh = stage.elapsed();
        let stage = Instant::now();
        let (mut disc, report) =
            Discretization::from_tets(&rest, &volumes, &adjacency, horizon).map_err(physics)?;
        disc.set_materials(&ids).map_err(physics)?;
        let mut from_energy = material::thresholds_from_energy(f, &mut materials, &disc);
        times.families = stage.elapsed();
        let stage = Instant::now();
        let counted = estimate.with_bonds(report.bonds as u64, extra);
        // with ghosts, the memory again once the layer is built, before the model over it
        let with_ghosts = |g: &GhostReport, layer_bytes: usize| {
            counted.with_ghosts(g.ghosts as u64, g.bonds as u64, layer_bytes as u64, extra)
        };
        let check_ghosts = |g: &GhostReport, layer_bytes: usize| {
            limits
                .check_memory(&with_ghosts(g, layer_bytes))
                .map_err(too_large)
        };
        let mut model = solver::model(&ctx, sim, disc, &mesh, &materials, &check_ghosts)?;
        if let solver::AnyModel::Xu(xu) = &mut model {
            from_energy = material::xu_thresholds_from_energy(f, xu);
        }
        times.model = stage.elapsed();
        let correction = model.correction();
        let ghosts = model.ghosts();
        let mut estimate = match &ghosts {
            Some(g) => with_ghosts(g, model.ghost_layer_bytes()),
            None => counted,
        };

        let radii = radii::contact_radii(&mesh, &volumes, sim.contact_radius.unwrap_or(1.0));
        let mean_radius = radii.iter().sum::<f64>() / radii.len() as f64;
        let young = materials.max_young();
        let gravity = sim.gravity.unwrap_or([0.0; 3]);
        // Each particle's collider stiffness from its own material and size: `E_i r_i` over
        // the reference `E_max r_mean` the colliders are built with.
        let stiffness_scale =
            colliders::stiffness_scale(&materials, &ids, &radii, young, mean_radius);
        let mut colliders = colliders::build_colliders(
            &ctx,
            &f.ground,
            &f.ball,
            young,
            mean_radius,
            gravity,
            &stiffness_scale,
            model.as_dyn().masses(),
        )?;
        if let Some((col, _)) = &mut colliders {
            colliders::check_placement(&ctx, col, &mesh, &rest, &radii)?;
            col.set_stiffness_scale(stiffness_scale)
                .map_err(|e| ctx.err("ball/ground", e.to_string()))?;
        }
        let mut contact = colliders.as_ref().map(|(_, k)| *k).unwrap_or_default();
        let self_contact = self_contact::build(&ctx, sim, &materials, &ids, &rest, &radii)?;
        if let Some(sc) = &self_contact {
            contact.self_omega2 = sc.max_omega2(model.as_dyn().masses());
        }

        let velocities = loads::initial_velocities(&ctx, &f.velocity, &rest)?;
        let travel = |fraction| {
            colliders.as_ref().map_or(f64::INFINITY, |(c, _)| {
                step::travel_limit(c, mean_radius, &velocities, fraction)
            })
        };
        let travel_fraction = match implicit {
            false => defaults::TRAVEL_FRACTION,
            true => defaults::IMPLICIT_TRAVEL_FRACTION,
        };
        let travel_limit = travel(travel_fraction);
        // A fixed step, or "auto"'s bound by the travel limit, already gives a least step
        // count: refused before the stable step's estimate when that passes the budget.
        let (early_dt, why) = match step::fixed_step(&ctx, sim)? {
            Some(dt) => (dt, format!("dt = {} s", check::show(dt))),
            None => (
                travel_limit,
                format!(
                    "the contact travel limit allows {travel_limit:.3e} s per step, the \
                     fastest ball or particle moving {travel_fraction} of a contact radius"
                ),
            ),
        };
        let at_least = step::fit_to_frames(sim.duration, frames, early_dt).1;
        limits
            .check_steps(
                (frames as u64).saturating_mul(at_least),
                &format!("{frames} frame(s) of at least {at_least} steps: {why}"),
            )
            .map_err(too_large)?;
        let stage = Instant::now();
        let (dt_limit, recalled) =
            step::stable_limit(model.as_dyn(), &rest, horizon, contact, memo);
        times.stable_step = stage.elapsed();
        times.stable_step_recalled = recalled;
        let dt_wanted = match &sim.integrator {
            Integrator::Explicit(e) => {
                step::requested_step(&ctx, sim, e.safety, dt_limit, travel_limit)?
            }
            Integrator::Implicit(i) => {
                step::implicit_step(&ctx, sim, i.steps_per_frame, frames, travel_limit)?
            }
        };
        let (dt, steps_per_frame) = step::fit_to_frames(sim.duration, frames, dt_wanted);

        // Steps, output and wall time, now that the step is known.
        let output = output_options(f);
        estimate.steps = (frames as u64).saturating_mul(steps_per_frame);
        limits
            .check_steps(
                estimate.steps,
                &format!(
                    "{frames} frame(s) of {steps_per_frame} steps of {dt:.3e} s over {} s; the \
                     stable limit is {dt_limit:.3e} s{}",
                    check::show(sim.duration),
                    if travel_limit.is_finite() {
                        format!(", the contact travel limit {travel_limit:.3e} s")
                    } else {
                        String::new()
                    }
                ),
            )
            .map_err(too_large)?;
        let per_frame = budget::frame_bytes(
            mesh.boundary_face_count() as u64,
            rest.len() as u64,
            output.povray,
            output.particles,
        );
        estimate.output_bytes = per_frame.saturating_mul(frames as u64 + 1);
        limits
            .check_output(
                estimate.output_bytes,
                &format!(
                    "{} frames of at least {} each",
                    frames + 1,
                    budget::bytes(per_frame)
                ),
            )
            .map_err(too_large)?;
        estimate.seconds =
            budget::run_seconds(estimate.steps, estimate.bonds, limits.threads, implicit);
        limits
            .check_time(
                estimate.seconds,
                &format!(
                    "{} steps over {} bonds at {:.0} ns per bond update on one core, {} \
                     thread(s)",
                    budget::count(estimate.steps),
                    budget::count(estimate.bonds),
                    budget::SECONDS_PER_BOND_UPDATE * 1e9,
                    limits.threads
                ),
            )
            .map_err(too_large)?;

        let (loads, releases) = loads::loads(&ctx, f, &rest, gravity)?;
        let start = solver::Start {
            rest: &rest,
            horizon,
            loads,
            dt,
        };
        let mut solver = solver::build(&ctx, sim, model, start)?;
        solver.velocities_mut().copy_from_slice(&velocities);

        times.total = started.elapsed();
        let info = SetupInfo {
            particles: rest.len(),
            bonds: report.bonds,
            horizon,
            edge_length: edge,
            dt_limit,
            travel_limit,
            dt,
            mass: solver.model().masses().iter().sum(),
            model: materials.kind(),
            integrator: solver.integrator(),
            up: math::up_from_gravity(gravity),
            rest_bounds: bounds(mesh.rest_positions()),
            precrack_faces,
            from_energy,
            too_soft: (0..f.material.len())
                .map(|k| (k, materials.young(k)))
                .filter(|&(_, e)| e < defaults::SOFTEST_SOLID)
                .collect(),
            correction,
            ghosts,
            estimate,
            times,
        };
        let mut driver = Driver::new(
            mesh,
            solver,
            colliders.map(|(c, _)| c),
            self_contact,
            radii,
            releases,
        )
        .with_ball_stops(
            f.ball
                .iter()
                .enumerate()
                .filter_map(|(i, b)| b.until.map(|t| (t, i)))
                .collect(),
        );
        if !region_loads.is_empty() {
            driver.add_influence(Box::new(crate::environment::Loads::new(
                region_loads,
                &rest,
            )));
        }
        Ok(Setup {
            scene_path: scene.path.clone(),
            scene_text: scene.text.clone(),
            driver,
            frames,
            steps_per_frame,
            output,
            info,
        })
    }
}

fn output_options(f: &SceneFile) -> OutputOptions {
    OutputOptions {
        povray: f.output.povray.unwrap_or(true),
        particles: f.output.particles.unwrap_or(true),
        checkpoints: CheckpointPolicy::from_key(f.output.checkpoint_every),
        usd: crate::usd::UsdLayout::from_keys(f.output.usd, f.output.usd_pieces),
        fps: f.output.fps.unwrap_or(crate::usd::DEFAULT_FPS),
        smooth_cracks: f
            .output
            .smooth_cracks
            .unwrap_or(true)
            .then(perifrac_topology::CrackSmoothing::default),
        debris_tets: f.output.debris_tets.unwrap_or(DEFAULT_DEBRIS_TETS),
    }
}
