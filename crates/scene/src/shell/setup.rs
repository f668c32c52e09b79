//! From a thin-shell scene file to a shell ready to step: the surface (generated or read),
//! its material, anchors, initial velocities, colliders and the time step, each problem
//! reported with the scene file and the key.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use perifrac_shell::{
    generate, NewmarkConfig, SearchedShell, ShellDynamics, ShellError, ShellFracture,
    ShellMaterial, ShellMesh, ShellModel, ShellSearch, ShellSelfContact, ShellYield, Vec3,
};

use crate::error::SceneError;
use crate::schema::{DtSpec, ShellIntegrator};
use crate::setup::check::{check_colliders, check_velocities, show, Ctx};
use crate::setup::colliders::build_colliders;
use crate::setup::loads::{initial_velocities, select};
use crate::setup::math::{bounds, up_from_gravity};
use crate::setup::step::fit_to_frames;
use crate::setup::CheckpointPolicy;

use perifrac_schema::shell::{ShellSceneFile, ShellSpec};

/// Defaults of shell scenes.
pub mod defaults {
    /// Fraction of the stable limit `dt = "auto"` takes. Lower than the solids' 0.8: the limit
    /// is measured at rest, and bending stiffens as a shell folds.
    pub const SAFETY: f64 = 0.5;
    /// A fixed step may be at most this fraction of the measured limit.
    pub const MAX_FIXED_FRACTION: f64 = 0.95;
    /// The event search's finest level (the paper's `k_max`).
    pub const EVENT_LEVELS: u32 = 10;
    /// Icosphere subdivisions of a sphere or ellipsoid.
    pub const SUBDIVISIONS: u32 = 3;
    /// A bowl's opening half-angle (degrees).
    pub const OPENING: f64 = 90.0;
    /// Vertex budging share.
    pub const BUDGE: f64 = 0.25;
    /// Share of the stress across a new crack released.
    pub const RELEASE: f64 = 1.0;
    /// Steps a run may take without `--allow-large`.
    pub const MAX_STEPS: u64 = 100_000_000;
}

/// A parsed thin-shell scene.
#[derive(Debug, Clone)]
pub struct ShellScene {
    /// The scene file.
    pub path: PathBuf,
    /// The TOML text as read.
    pub text: String,
    /// The parsed tables.
    pub file: ShellSceneFile,
}

impl ShellScene {
    /// Reads and parses `path`.
    pub fn load(path: &Path) -> Result<ShellScene, SceneError> {
        ShellScene::parse(&crate::load::read(path)?, path)
    }

    /// Parses `text` as if read from `path`.
    pub fn parse(text: &str, path: &Path) -> Result<ShellScene, SceneError> {
        let scene = crate::load::Scene::parse_as::<ShellSceneFile>(text, path)?;
        Ok(ShellScene {
            path: path.to_path_buf(),
            text: text.to_string(),
            file: scene,
        })
    }
}

/// What the setup found and chose, for the command line and `run.json`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellSetupInfo {
    /// Vertices at the start.
    pub vertices: usize,
    /// Triangles at the start.
    pub triangles: usize,
    /// Boundary (free) edges at the start.
    pub boundary_edges: usize,
    /// Rest thickness (m).
    pub thickness: f64,
    /// Total mass (kg).
    pub mass: f64,
    /// The step (s).
    pub dt: f64,
    /// The measured stable limit (s): elastic forces with the colliders' stiffness.
    pub dt_limit: f64,
    /// What the dynamic balls add to the squared highest frequency (1/s^2): the vertices a
    /// ball can hold at once, times their stiffness, over its mass. (What contact adds to a
    /// vertex's frequency is in the shell's own stable step, which follows the masses fracture
    /// changes.)
    pub ball_omega2: f64,
    /// The share of the stable limit steps keep to (`simulation.safety`); without the event
    /// search, steps are cut into parts when fracture lowers the limit.
    pub safety: f64,
    /// The event search's finest level (0: plain steps).
    pub event_levels: u32,
    /// The implicit Newmark step's settings (`None`: explicit steps).
    pub newmark: Option<NewmarkConfig>,
    /// World up.
    pub up: [f64; 3],
    /// Rest bounding box (m).
    pub rest_bounds: ([f64; 3], [f64; 3]),
    /// Whether the material yields, and whether it breaks.
    pub plastic: bool,
    /// Whether the material breaks.
    pub breaks: bool,
    /// Whether the shell's pieces repel each other.
    pub self_contact: bool,
    /// Whether the scene has `[[load]]` tables.
    pub loads: bool,
    /// Wall time of the setup.
    pub time: Duration,
}

/// A shell scene ready to run.
pub struct ShellSetup {
    /// The scene file.
    pub scene_path: PathBuf,
    /// Its text, copied into the run directory.
    pub scene_text: String,
    /// The shell, stepped with the event search (level 0 when the scene has none).
    pub shell: SearchedShell,
    /// Frames after the initial one.
    pub frames: usize,
    /// Steps per frame.
    pub steps_per_frame: u64,
    /// Whether frames get POV-Ray includes.
    pub povray: bool,
    /// Thickness (m) given to each piece in the frames (0: the mid-surface).
    pub frame_thickness: f64,
    /// The USD cache the run ends by writing, in its layout (none without `[output] usd`).
    pub usd: Option<crate::usd::UsdLayout>,
    /// Playback frames per second of that cache.
    pub fps: f64,
    /// When the run writes a checkpoint at a frame boundary (an interrupted run always writes
    /// one).
    pub checkpoints: crate::setup::CheckpointPolicy,
    /// What was found and chosen.
    pub info: ShellSetupInfo,
}

impl ShellSetup {
    /// Validates and builds what `scene` asks for; `frames` overrides the scene's frame count;
    /// a run of more than [`defaults::MAX_STEPS`] steps is refused unless `allow_large`.
    pub fn new(
        scene: &ShellScene,
        frames: Option<usize>,
        allow_large: bool,
    ) -> Result<ShellSetup, SceneError> {
        let started = Instant::now();
        let ctx = Ctx { file: &scene.path };
        let f = &scene.file;
        let sim = &f.simulation;
        // settings first, so a typo fails before the surface is built
        ctx.positive("simulation.duration", sim.duration, "s")?;
        let safety = sim.safety.unwrap_or(defaults::SAFETY);
        if !(safety > 0.0 && safety <= 1.0) {
            return Err(ctx.err(
                "simulation.safety",
                format!("{} must be in (0, 1]", show(safety)),
            ));
        }
        let fixed = match &sim.dt {
            None => None,
            Some(DtSpec::Word(w)) if w == "auto" => None,
            Some(DtSpec::Word(w)) => {
                return Err(ctx.err(
                    "simulation.dt",
                    format!("\"{w}\": expected \"auto\" or a step in seconds"),
                ))
            }
            Some(DtSpec::Seconds(dt)) => Some(ctx.positive("simulation.dt", *dt, "s")?),
        };
        let gravity = match sim.gravity {
            Some(g) => ctx.finite3("simulation.gravity", g)?,
            None => [0.0; 3],
        };
        let damping = match sim.damping {
            Some(d) => ctx.non_negative("simulation.damping", d)?,
            None => 0.0,
        };
        let search = sim.event_search.unwrap_or(false);
        if !search && (sim.event_levels.is_some() || sim.force_growth.is_some()) {
            let key = if sim.event_levels.is_some() {
                "simulation.event_levels"
            } else {
                "simulation.force_growth"
            };
            return Err(ctx.err(key, "sets the event search: give event_search = true too"));
        }
        let config = ShellSearch {
            levels: if search {
                sim.event_levels.unwrap_or(defaults::EVENT_LEVELS)
            } else {
                0
            },
            force_growth: sim
                .force_growth
                .unwrap_or(ShellSearch::default().force_growth),
            ..ShellSearch::default()
        };
        config.check().map_err(|e| {
            let key = if config.levels > 20 {
                "simulation.event_levels"
            } else {
                "simulation.force_growth"
            };
            ctx.err(key, e.to_string())
        })?;
        let newmark = match &sim.integrator {
            ShellIntegrator::Explicit(_) => None,
            ShellIntegrator::Newmark(keys) => {
                let defaults = NewmarkConfig::default();
                let c = NewmarkConfig {
                    max_iterations: keys.iterations.unwrap_or(defaults.max_iterations),
                    tolerance: keys.tolerance.unwrap_or(defaults.tolerance),
                    ..defaults
                };
                c.check().map_err(|e| {
                    let key = if c.max_iterations == 0 {
                        "simulation.iterations"
                    } else {
                        "simulation.tolerance"
                    };
                    ctx.err(key, e.to_string())
                })?;
                if fixed.is_none() {
                    return Err(ctx.err(
                        "simulation.dt",
                        "the Newmark step has no stable limit to take a share of: give dt in \
                         seconds",
                    ));
                }
                Some(c)
            }
        };
        let frames = frames
            .or(f.output.frames)
            .unwrap_or(crate::setup::defaults::FRAMES);
        if frames == 0 {
            return Err(ctx.err("output.frames", "must be at least 1"));
        }
        check_colliders(&ctx, &f.ground, &f.ball)?;
        if let Some(i) = f.ball.iter().position(|b| b.until.is_some()) {
            return Err(ctx.err(
                format!("ball[{i}].until"),
                "shell scenes do not stop balls yet: drop until (the ball keeps its velocity)",
            ));
        }
        check_velocities(&ctx, &f.velocity)?;
        for (i, a) in f.anchor.iter().enumerate() {
            ctx.region(&format!("anchor[{i}].region"), &a.region)?;
            for (k, set) in [
                ("angular", a.angular.is_some()),
                ("center", a.center.is_some()),
                ("until", a.until.is_some()),
            ] {
                if set {
                    return Err(ctx.err(
                        format!("anchor[{i}].{k}"),
                        "shell anchors hold vertices still or move them at a constant \
                         velocity: give region and velocity only",
                    ));
                }
            }
            if let Some(v) = a.velocity {
                ctx.finite3(&format!("anchor[{i}].velocity"), v)?;
            }
        }
        let material = shell_material(&ctx, f)?;
        let thickness = material.thickness;
        let checkpoints = CheckpointPolicy::from_key(f.output.checkpoint_every);
        let frame_thickness = match f.output.thickness {
            Some(t) => ctx.non_negative("output.thickness", t)?,
            None => thickness,
        };
        let o = &f.output;
        crate::setup::check::check_cache(&ctx, o.usd, o.usd_pieces, o.fps)?;

        let (vertices, triangles) = surface(&ctx, scene, &f.shell)?;
        let mesh =
            ShellMesh::new(vertices, triangles).map_err(|e| mesh_error(&ctx, &f.shell, e))?;
        let boundary_edges = mesh.num_boundary_edges();
        let rest: Vec<Vec3> = mesh.vertices().to_vec();
        let m = &f.material[0];
        let mut model =
            ShellModel::new(mesh, material).map_err(|e| mesh_error(&ctx, &f.shell, e))?;
        if let Some(y) = m.yield_strain {
            let params = ShellYield::new(y, m.hardening.unwrap_or(0.0)).map_err(|e| {
                let key = if y.is_finite() && y > 0.0 {
                    "hardening"
                } else {
                    "yield_strain"
                };
                ctx.err(format!("material[0].{key}"), e.to_string())
            })?;
            model = model.with_yield(params);
        } else if m.hardening.is_some() {
            return Err(ctx.err(
                "material[0].hardening",
                "hardens a yielding material: give yield_strain too",
            ));
        }
        let fracture = fracture(&ctx, f)?;
        let breaks = fracture.is_some();
        if let Some(params) = fracture {
            model = model.with_fracture(params);
        }
        let mass: f64 = model.masses().iter().sum();
        let mut shell = ShellDynamics::new(model).map_err(|e| ctx.err("shell", e.to_string()))?;
        shell.set_gravity(gravity);
        shell
            .set_damping(damping)
            .map_err(|e| ctx.err("simulation.damping", e.to_string()))?;
        let velocities = initial_velocities(&ctx, &f.velocity, &rest)?;
        shell.velocities_mut().copy_from_slice(&velocities);
        for (i, a) in f.anchor.iter().enumerate() {
            let picked = select(&ctx, &format!("anchor[{i}].region"), &rest, Some(&a.region))?;
            let v = a.velocity.unwrap_or([0.0; 3]);
            for p in picked {
                if v == [0.0; 3] {
                    shell.pin(p as usize);
                } else {
                    shell.drive(p as usize, v);
                }
            }
        }
        let loads = super::loads::shell_loads(
            &ctx,
            &f.load,
            shell.model().mesh(),
            thickness,
            shell.model().masses(),
            m.density,
        )?;
        let loaded = !loads.is_empty();
        shell
            .set_loads(loads)
            .map_err(|e| ctx.err("load", e.to_string()))?;
        // Colliders: each vertex a sphere of half the thickness, stiffness factor E h / 2.
        let radius = 0.5 * thickness;
        let masses = shell.model().masses().to_vec();
        let scale = vec![1.0; masses.len()];
        let ball_omega2 = match build_colliders(
            &ctx,
            &f.ground,
            &f.ball,
            material.young,
            radius,
            gravity,
            &scale,
            &masses,
        )? {
            Some((colliders, stiffness)) => {
                colliders
                    .check_clear(&rest, &vec![radius; rest.len()])
                    .map_err(|e| {
                        ctx.err(
                            "ball/ground",
                            format!("collider inside the shell at the start: {e}"),
                        )
                    })?;
                shell
                    .set_colliders(colliders, radius)
                    .map_err(|e| ctx.err("ball/ground", e.to_string()))?;
                stiffness.ball_omega2
            }
            None => 0.0,
        };
        match (
            sim.self_contact.unwrap_or(false),
            sim.self_contact_stiffness,
        ) {
            (false, Some(_)) => {
                return Err(ctx.err(
                    "simulation.self_contact_stiffness",
                    "sets self contact: give self_contact = true too",
                ))
            }
            (false, None) => {}
            (true, k) => {
                let params = ShellSelfContact {
                    stiffness: match k {
                        Some(k) => ctx.positive("simulation.self_contact_stiffness", k, "")?,
                        None => ShellSelfContact::default().stiffness,
                    },
                    ..ShellSelfContact::default()
                };
                shell
                    .set_self_contact(Some(params))
                    .map_err(|e| ctx.err("simulation.self_contact", e.to_string()))?;
            }
        }
        let shell_limit = shell
            .stable_step()
            .map_err(|e| ctx.err("shell", format!("no stable step: {e}")))?;
        let omega = 2.0 / shell_limit;
        let dt_limit = 2.0 / (omega * omega + ball_omega2).sqrt();
        let wanted = match fixed {
            Some(dt) if newmark.is_none() && dt > defaults::MAX_FIXED_FRACTION * dt_limit => {
                return Err(ctx.err(
                    "simulation.dt",
                    format!(
                        "{} s is above {} of the stable limit {:.3e} s (measured on the \
                         surface, with the colliders' stiffness); use \"auto\" or a smaller step",
                        show(dt),
                        defaults::MAX_FIXED_FRACTION,
                        dt_limit
                    ),
                ))
            }
            Some(dt) => dt,
            None => safety * dt_limit,
        };
        let (dt, steps_per_frame) = fit_to_frames(sim.duration, frames, wanted);
        let total = steps_per_frame.saturating_mul(frames as u64);
        if total > defaults::MAX_STEPS && !allow_large {
            return Err(SceneError::TooLarge {
                file: scene.path.clone(),
                message: format!(
                    "{total} steps of {dt:.3e} s (more than {}) to cover {} s",
                    defaults::MAX_STEPS,
                    show(sim.duration)
                ),
            });
        }
        shell
            .set_newmark(newmark)
            .map_err(|e| ctx.err("simulation.integrator", e.to_string()))?;
        let info = ShellSetupInfo {
            vertices: rest.len(),
            triangles: shell.model().mesh().triangles().len(),
            boundary_edges,
            thickness,
            mass,
            dt,
            dt_limit,
            safety,
            ball_omega2,
            event_levels: config.levels,
            newmark,
            up: up_from_gravity(gravity),
            rest_bounds: bounds(&rest),
            plastic: m.yield_strain.is_some(),
            breaks,
            self_contact: sim.self_contact.unwrap_or(false),
            loads: loaded,
            time: started.elapsed(),
        };
        let shell =
            SearchedShell::new(shell, config).map_err(|e| ctx.err("simulation", e.to_string()))?;
        Ok(ShellSetup {
            scene_path: scene.path.clone(),
            scene_text: scene.text.clone(),
            shell,
            frames,
            steps_per_frame,
            povray: f.output.povray.unwrap_or(true),
            frame_thickness,
            usd: crate::usd::UsdLayout::from_keys(f.output.usd, f.output.usd_pieces),
            fps: f.output.fps.unwrap_or(crate::usd::DEFAULT_FPS),
            checkpoints,
            info,
        })
    }
}

/// The material from the one `[[material]]` table, its constants checked with their keys.
fn shell_material(ctx: &Ctx, f: &ShellSceneFile) -> Result<ShellMaterial, SceneError> {
    let m = match f.material.as_slice() {
        [m] => m,
        [] => return Err(ctx.err("material", "a shell scene needs one [[material]]")),
        _ => {
            return Err(ctx.err(
                "material[1]",
                "a shell has one material: give one [[material]] table",
            ))
        }
    };
    ctx.positive("shell.thickness", f.shell.thickness, "m")?;
    ctx.positive("material[0].young", m.young, "Pa")?;
    ctx.density("material[0].density", m.density)?;
    if !(m.poisson > -1.0 && m.poisson <= 0.5) {
        return Err(ctx.err(
            "material[0].poisson",
            format!("{} must be in (-1, 0.5]", show(m.poisson)),
        ));
    }
    ShellMaterial::new(m.young, m.poisson, m.density, f.shell.thickness)
        .map_err(|e| ctx.err("material[0]", e.to_string()))
}

/// The fracture settings, `None` when no threshold is given.
fn fracture(ctx: &Ctx, f: &ShellSceneFile) -> Result<Option<ShellFracture>, SceneError> {
    let m = &f.material[0];
    let both = m.fracture_strain;
    let energy = match (m.fracture_energy, both) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                "material[0].fracture_energy",
                "give fracture_energy (J/m^2) or fracture_strain, not both",
            ))
        }
        (Some(g), None) if !(g.is_finite() && g > 0.0) => {
            return Err(ctx.err(
                "material[0].fracture_energy",
                format!("{} J/m^2 must be positive and finite", show(g)),
            ))
        }
        (g, _) => g,
    };
    let (tensile, compressive) = match (m.tensile_strain.or(both), m.compressive_strain.or(both)) {
        (None, None) if energy.is_none() => {
            for (k, set) in [
                ("budge", m.budge.is_some()),
                ("release", m.release.is_some()),
            ] {
                if set {
                    return Err(ctx.err(
                        format!("material[0].{k}"),
                        "a fracture setting: give fracture_energy or fracture_strain (or \
                         tensile_strain and compressive_strain) too",
                    ));
                }
            }
            return Ok(None);
        }
        // One threshold alone: the other side never breaks (or breaks by the energy alone).
        (t, c) => (t.unwrap_or(f64::INFINITY), c.unwrap_or(f64::INFINITY)),
    };
    for (key, v, given) in [
        ("tensile_strain", tensile, m.tensile_strain.is_some()),
        (
            "compressive_strain",
            compressive,
            m.compressive_strain.is_some(),
        ),
    ] {
        let key = if given { key } else { "fracture_strain" };
        if v.is_nan() || v <= 0.0 {
            return Err(ctx.err(
                format!("material[0].{key}"),
                format!("{} must be positive", show(v)),
            ));
        }
    }
    let budge = m.budge.unwrap_or(defaults::BUDGE);
    if !(0.0..0.5).contains(&budge) {
        return Err(ctx.err(
            "material[0].budge",
            format!("{} must be in [0, 0.5)", show(budge)),
        ));
    }
    let release = m.release.unwrap_or(defaults::RELEASE);
    if !(0.0..=1.0).contains(&release) {
        return Err(ctx.err(
            "material[0].release",
            format!("{} must be in [0, 1]", show(release)),
        ));
    }
    if energy.is_some() && release == 0.0 {
        return Err(ctx.err(
            "material[0].release",
            "0 releases no energy at a crack, so fracture_energy could never be spent: give a \
             release above 0",
        ));
    }
    // An infinite threshold stands for "never": the largest finite one does the same.
    let cap = |v: f64| if v.is_finite() { v } else { f64::MAX };
    let params = ShellFracture::new(cap(tensile), cap(compressive), budge, release)
        .map_err(|e| ctx.err("material[0]", e.to_string()))?;
    match energy {
        Some(g) => params
            .with_energy(g)
            .map(Some)
            .map_err(|e| ctx.err("material[0].fracture_energy", e.to_string())),
        None => Ok(Some(params)),
    }
}

/// A surface error, named after its file when the surface is read from one.
fn mesh_error(ctx: &Ctx, spec: &ShellSpec, e: ShellError) -> SceneError {
    match &spec.file {
        Some(file) => SceneError::Mesh {
            file: ctx.file.to_path_buf(),
            message: format!("{}: {e}", file.display()),
        },
        None => SceneError::Mesh {
            file: ctx.file.to_path_buf(),
            message: format!(
                "the generated {} : {e}",
                spec.surface.as_deref().unwrap_or("surface")
            ),
        },
    }
}

/// The surface's vertices (m) and triangles: generated or read, then scaled, rotated and
/// moved.
fn surface(
    ctx: &Ctx,
    scene: &ShellScene,
    s: &ShellSpec,
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), SceneError> {
    let need = |v: Option<f64>, key: &str, unit: &str| -> Result<f64, SceneError> {
        match v {
            Some(v) => ctx.positive(&format!("shell.{key}"), v, unit),
            None => Err(ctx.err(
                format!("shell.{key}"),
                format!("a {} needs it", s.surface.as_deref().unwrap_or("surface")),
            )),
        }
    };
    let cells = |default: [usize; 2], least: [usize; 2]| -> Result<[usize; 2], SceneError> {
        let c = s.cells.unwrap_or(default);
        if c[0] < least[0] || c[1] < least[1] {
            return Err(ctx.err(
                "shell.cells",
                format!(
                    "{c:?}: at least {least:?} for a {}",
                    s.surface.as_deref().unwrap_or("")
                ),
            ));
        }
        Ok(c)
    };
    let subdivisions = || -> Result<u32, SceneError> {
        let n = s.subdivisions.unwrap_or(defaults::SUBDIVISIONS);
        if n > 7 {
            return Err(ctx.err(
                "shell.subdivisions",
                format!("{n}: at most 7 ({} triangles)", 20u64 << 14),
            ));
        }
        Ok(n)
    };
    // keys a surface does not use are refused, so a misplaced one is not silently ignored
    let set = [
        ("radius", s.radius.is_some()),
        ("radii", s.radii.is_some()),
        ("length", s.length.is_some()),
        ("size", s.size.is_some()),
        ("cells", s.cells.is_some()),
        ("subdivisions", s.subdivisions.is_some()),
        ("opening", s.opening.is_some()),
        ("diagonals", s.diagonals.is_some()),
    ];
    let only = |used: &[&str]| -> Result<(), SceneError> {
        match set.iter().find(|(k, given)| *given && !used.contains(k)) {
            Some((k, _)) => Err(ctx.err(
                format!("shell.{k}"),
                format!(
                    "not a setting of a {}",
                    s.surface.as_deref().unwrap_or("surface read from a file")
                ),
            )),
            None => Ok(()),
        }
    };
    let gen_err = |e: generate::GenerateError| ctx.err("shell", e.to_string());
    let surf = match (s.surface.as_deref(), &s.file) {
        (Some(_), Some(_)) => {
            return Err(ctx.err("shell", "give either surface or file, not both"));
        }
        (None, None) => {
            return Err(ctx.err(
                "shell",
                "give surface (\"sphere\", \"ellipsoid\", \"cylinder\", \"sheet\", \"bowl\") or \
                 file",
            ))
        }
        (None, Some(file)) => {
            only(&[])?;
            let path = scene.path.parent().unwrap_or(Path::new(".")).join(file);
            let data = perifrac_io::read_surface(&path).map_err(|e| SceneError::Mesh {
                file: scene.path.clone(),
                message: format!("{}: {e}", path.display()),
            })?;
            generate::Surface {
                vertices: data.vertices,
                triangles: data.faces,
            }
        }
        (Some("sphere"), None) => {
            only(&["radius", "subdivisions"])?;
            generate::icosphere(need(s.radius, "radius", "m")?, subdivisions()?).map_err(gen_err)?
        }
        (Some("ellipsoid"), None) => {
            only(&["radii", "subdivisions"])?;
            let Some(r) = s.radii else {
                return Err(ctx.err("shell.radii", "an ellipsoid needs its three semi-axes"));
            };
            for (k, v) in r.iter().enumerate() {
                ctx.positive(&format!("shell.radii[{k}]"), *v, "m")?;
            }
            generate::ellipsoid(r, subdivisions()?).map_err(gen_err)?
        }
        (Some("cylinder"), None) => {
            only(&["radius", "length", "cells"])?;
            let [around, along] = cells([32, 16], [3, 1])?;
            generate::cylinder(
                need(s.radius, "radius", "m")?,
                need(s.length, "length", "m")?,
                around,
                along,
            )
            .map_err(gen_err)?
        }
        (Some("sheet"), None) => {
            only(&["size", "cells", "diagonals"])?;
            let Some([w, h]) = s.size else {
                return Err(ctx.err("shell.size", "a sheet needs its extent along x and y"));
            };
            ctx.positive("shell.size[0]", w, "m")?;
            ctx.positive("shell.size[1]", h, "m")?;
            let [nx, ny] = cells([16, 16], [1, 1])?;
            match s.diagonals.as_deref() {
                None | Some("uniform") => generate::sheet_uniform(w, h, nx, ny),
                Some("alternating") => generate::sheet(w, h, nx, ny),
                Some(other) => {
                    return Err(ctx.err(
                        "shell.diagonals",
                        format!("\"{other}\": expected \"uniform\" or \"alternating\""),
                    ))
                }
            }
            .map_err(gen_err)?
        }
        (Some("bowl"), None) => {
            only(&["radius", "opening", "cells"])?;
            let opening = s.opening.unwrap_or(defaults::OPENING);
            if !(opening > 0.0 && opening < 180.0) {
                return Err(ctx.err(
                    "shell.opening",
                    format!("{} degrees must be in (0, 180)", show(opening)),
                ));
            }
            let [rings, segments] = cells([12, 48], [1, 3])?;
            generate::bowl(need(s.radius, "radius", "m")?, opening, rings, segments)
                .map_err(gen_err)?
        }
        (Some(other), None) => {
            return Err(ctx.err(
                "shell.surface",
                format!(
                    "\"{other}\": expected \"sphere\", \"ellipsoid\", \"cylinder\", \"sheet\" or \
                     \"bowl\""
                ),
            ))
        }
    };
    let scale = match s.scale {
        Some(k) => ctx.positive("shell.scale", k, "")?,
        None => 1.0,
    };
    let rotate = match s.rotate {
        Some(r) => ctx.finite3("shell.rotate", r)?,
        None => [0.0; 3],
    };
    let translate = match s.translate {
        Some(t) => ctx.finite3("shell.translate", t)?,
        None => [0.0; 3],
    };
    let vertices = surf
        .vertices
        .iter()
        .map(|p| {
            let mut q = p.map(|c| c * scale);
            for (axis, deg) in rotate.iter().enumerate() {
                q = rotate_about(q, axis, deg.to_radians());
            }
            [0, 1, 2].map(|k| q[k] + translate[k])
        })
        .collect();
    Ok((vertices, surf.triangles))
}

/// `p` rotated by `angle` (rad) about coordinate axis `axis` (0, 1, 2: x, y, z), right-handed.
fn rotate_about(p: Vec3, axis: usize, angle: f64) -> Vec3 {
    if angle == 0.0 {
        return p;
    }
    let (s, c) = angle.sin_cos();
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut q = p;
    q[i] = c * p[i] - s * p[j];
    q[j] = s * p[i] + c * p[j];
    q
}
