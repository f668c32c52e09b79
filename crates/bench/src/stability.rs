//! `perifrac bench stability`: hard cases, each ending in one of three outcomes: it survived
//! (finite, bounded energy), it stopped with a message (the blow-up guard or a setup error),
//! or it failed: a NaN that nothing caught or a panic ([`Outcome::Failed`], a defect), or
//! energy that grew without the guard stopping it yet ([`Outcome::Runaway`], a limit of a
//! displacement guard). The tests of this crate run every case at [`Effort::Tiny`] and require
//! no NaN and no panic.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::Instant;

use perifrac_physics::{
    stable_frequency, ChenMaterial, ChenModel, Explicit, FractureParams, Loads, Solver, TimeStep,
    Vec3,
};
use perifrac_scene::{Scene, Setup};
use perifrac_topology::primitives::box_data;

use crate::bar::{block, mesh_body, set_velocities, tet_mesh};
use crate::table::Table;
use crate::{BenchError, Effort};

/// How a case ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Finite to the end, energy bounded.
    Survived,
    /// Stopped with this message (a guard or a refusal): the run ends cleanly.
    Stopped(String),
    /// A defect: an uncaught NaN or a panic.
    Failed(String),
    /// Energy grew without bound in an undamped run and nothing had stopped it yet.
    Runaway(String),
}

/// One hard case's result.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseResult {
    /// What was run.
    pub name: String,
    /// How it ended.
    pub outcome: Outcome,
    /// Steps taken.
    pub steps: u64,
    /// Relative change of the total energy (kinetic plus elastic, balls included): the mean
    /// over the last tenth of its samples against the mean over the second tenth; NaN where
    /// the case has no meaningful start energy.
    pub energy_drift: f64,
    /// Largest particle speed seen (m/s).
    pub max_speed: f64,
    /// Wall time (s).
    pub wall_s: f64,
    /// What to read into it.
    pub note: String,
    /// For a pressed body that did not break: its pairs within a horizon at rest whose
    /// separation points against the rest one at the end (where it folded through itself).
    pub turned_over: Option<usize>,
}

/// Energy growth beyond which an undamped run that did not stop counts as failed.
const RUNAWAY: f64 = 1.0;

fn steel() -> ChenMaterial {
    ChenMaterial::from_young_poisson(200e9, 0.25, 7800.0).expect("valid constants")
}

fn max_speed(v: &[Vec3]) -> f64 {
    v.iter()
        .map(|a| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt())
        .fold(0.0, f64::max)
}

fn all_finite(v: &[Vec3]) -> bool {
    v.iter().all(|a| a.iter().all(|c| c.is_finite()))
}

/// Kinetic plus elastic energy of `s` (J).
fn energy(s: &mut dyn Solver) -> f64 {
    s.kinetic_energy() + s.elastic_energy()
}

/// Steps an explicit solver `steps` times, tracking speed and the total energy (sampled every
/// [`ENERGY_EVERY`] steps); turns the end into an outcome. The drift compares the mean energy
/// over the last tenth of the samples with the second tenth ([`windowed_drift`]), so the
/// bounded oscillation of velocity Verlet's energy (of order `(omega dt)^2` in the fastest
/// modes) is not read as drift. `damped` runs do not fail on energy growth.
fn drive(
    name: &str,
    s: Explicit<ChenModel>,
    steps: u64,
    damped: bool,
    note: String,
    started: Instant,
) -> CaseResult {
    drive_then(name, s, steps, damped, |_| note, started)
}

/// [`drive`], with the note written from the solver's state at the end.
fn drive_then(
    name: &str,
    mut s: Explicit<ChenModel>,
    steps: u64,
    damped: bool,
    note: impl FnOnce(&Explicit<ChenModel>) -> String,
    started: Instant,
) -> CaseResult {
    let mut watch = Watch::new(energy(&mut s), s.velocities());
    for _ in 0..steps {
        if let Err(e) = s.step() {
            watch.outcome = Outcome::Stopped(e.to_string());
            break;
        }
        if !watch.stepped(s.velocities(), s.positions()) {
            break;
        }
        if watch.samples_now() {
            watch.energy.push(energy(&mut s));
        }
    }
    let note = note(&s);
    watch.finish(name, damped, || energy(&mut s), note, started)
}

/// Steps between energy samples.
const ENERGY_EVERY: u64 = 10;

/// Energy samples below which the table shows no drift: over fewer it says nothing.
const MIN_DRIFT_SAMPLES: u64 = 20;

/// What a run has seen so far: energy samples, the fastest particle, steps, the outcome.
struct Watch {
    energy: Vec<f64>,
    top: f64,
    taken: u64,
    outcome: Outcome,
}

impl Watch {
    fn new(energy: f64, v: &[Vec3]) -> Watch {
        Watch {
            energy: vec![energy],
            top: max_speed(v),
            taken: 0,
            outcome: Outcome::Survived,
        }
    }

    /// Records a step that ended at velocities `v`, positions `y`. Returns false when the run
    /// must end (a non-finite state).
    fn stepped(&mut self, v: &[Vec3], y: &[Vec3]) -> bool {
        self.taken += 1;
        self.top = self.top.max(max_speed(v));
        if !all_finite(y) || !all_finite(v) {
            self.outcome = Outcome::Failed("non-finite state without an error".into());
            return false;
        }
        true
    }

    /// Whether this step's energy is sampled.
    fn samples_now(&self) -> bool {
        self.taken.is_multiple_of(ENERGY_EVERY)
    }

    /// The result; `end_energy` is sampled once more when the run survived.
    fn finish(
        mut self,
        name: &str,
        damped: bool,
        end_energy: impl FnOnce() -> f64,
        note: String,
        started: Instant,
    ) -> CaseResult {
        if self.outcome == Outcome::Survived {
            self.energy.push(end_energy());
        }
        let drift = windowed_drift(&self.energy);
        if self.outcome == Outcome::Survived && !damped && drift > RUNAWAY {
            self.outcome = Outcome::Runaway(format!(
                "energy grew {:.1}-fold in {} steps and the guard had not stopped it yet",
                1.0 + drift,
                self.taken
            ));
        }
        CaseResult {
            name: name.into(),
            outcome: self.outcome,
            steps: self.taken,
            energy_drift: drift,
            max_speed: self.top,
            wall_s: started.elapsed().as_secs_f64(),
            note,
            turned_over: None,
        }
    }
}

/// `(mean of the last tenth - mean of the second tenth) / mean of the second tenth` of the
/// samples (at least one each; the first tenth is skipped because a start with all the energy
/// kinetic settles into a discrete energy that differs from it by `(omega dt)^2`: a bias, not
/// a drift); NaN without a positive reference.
fn windowed_drift(e: &[f64]) -> f64 {
    let w = (e.len() / 10).max(1);
    let from = w.min(e.len() - w);
    let first = e[from..from + w].iter().sum::<f64>() / w as f64;
    let last = e[e.len() - w..].iter().sum::<f64>() / w as f64;
    if first > 0.0 {
        (last - first) / first
    } else {
        f64::NAN
    }
}

/// A deterministic velocity field with every mode in it: `amplitude` (m/s) times xorshift
/// noise in [-0.5, 0.5) per component.
fn noise(n: usize, amplitude: f64) -> Vec<Vec3> {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        amplitude * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

/// A free steel block of `cells` 1 cm cells at a fixed step `factor` times the estimated
/// stable limit, with noise in the velocities.
fn step_factor(factor: f64, cells: [usize; 3], steps: u64) -> Result<CaseResult, BenchError> {
    let started = Instant::now();
    let name = format!("explicit step at {factor} x the stable estimate");
    let size = cells.map(|c| c as f64 * 0.01);
    let mut b = block(&name, size, cells, 1.5, &steel())?;
    let (rest, horizon) = (b.rest().to_vec(), b.horizon());
    let (_, est) = stable_frequency(&mut b.model, &rest, horizon);
    let dt = factor * est.critical_step();
    let n = rest.len();
    let mut s = b.solver_at(&name, Loads::new(n), TimeStep::Fixed(dt))?;
    s.velocities_mut().copy_from_slice(&noise(n, 0.1));
    let note = format!(
        "estimate {:.3e} s (Lanczos, {} force evaluations); steel block of {n} particles, random \
         velocities",
        est.critical_step(),
        est.evaluations
    );
    Ok(drive(&name, s, steps, false, note, started))
}

/// A scene given as TOML text, stepped through the scene driver: `steps` steps, or to the
/// scene's end when `None`.
fn scene_case(name: &str, text: &str, note: &str, damped: bool, steps: Option<u64>) -> CaseResult {
    run_scene_case(name, text, note, damped, steps, false)
}

/// [`scene_case`]; with `pressed`, the note also gives how deep any particle's contact sphere
/// went into a collider over the run (a share of its radius: past 1, its centre went through)
/// and, when no bond broke, how many pairs of particles within a horizon of each other at rest
/// lie the other way round at the end (the block folded through itself).
fn run_scene_case(
    name: &str,
    text: &str,
    note: &str,
    damped: bool,
    steps: Option<u64>,
    pressed: bool,
) -> CaseResult {
    let started = Instant::now();
    let scene = match Scene::parse(text, Path::new(name)) {
        Ok(s) => s,
        Err(e) => return refused(name, e.to_string(), started),
    };
    let mut setup = match Setup::new(&scene, None) {
        Ok(s) => s,
        Err(e) => return refused(name, e.to_string(), started),
    };
    let total = |d: &mut perifrac_scene::Driver| {
        let balls = d.colliders().map_or(0.0, |c| c.kinetic_energy());
        energy(d.solver_mut()) + balls
    };
    let mut watch = Watch::new(total(&mut setup.driver), setup.driver.solver().velocities());
    let mut deepest_in: f64 = 0.0;
    let steps = steps.unwrap_or(setup.frames as u64 * setup.steps_per_frame);
    for _ in 0..steps {
        if let Err(e) = setup.driver.step() {
            watch.outcome = Outcome::Stopped(e.to_string());
            break;
        }
        let solver = setup.driver.solver();
        if !watch.stepped(solver.velocities(), solver.positions()) {
            break;
        }
        if watch.samples_now() {
            let e = total(&mut setup.driver);
            watch.energy.push(e);
        }
        if pressed {
            deepest_in = deepest_in.max(into_colliders(&setup.driver));
        }
    }
    // pieces tumble once apart: turned-over pairs say nothing then
    let turned = (pressed && setup.driver.broken_bonds() == 0).then(|| {
        let d = &setup.driver;
        turned_over(
            &d.mesh().rest_barycentres(),
            d.solver().positions(),
            setup.info.horizon,
        )
    });
    let note = match (pressed, turned) {
        (false, _) => note.into(),
        (true, Some(turned)) => format!(
            "{note}; deepest into the plate or ground {:.0}% of a contact radius, {turned} of \
             the pairs within a horizon at rest turned over at the end",
            100.0 * deepest_in,
        ),
        (true, _) => format!(
            "{note}; deepest into the plate or ground {:.0}% of a contact radius",
            100.0 * deepest_in
        ),
    };
    let note = match setup.driver.self_contact() {
        Some(sc) => {
            let deepest = setup.driver.self_contact_deepest();
            format!(
                "{note}; contact between particles: deepest overlap {:.1}% of a contact \
                 distance, up to {} pairs touching, {} pair-list builds",
                100.0 * deepest.max_overlap_share,
                deepest.pairs,
                sc.rebuilds()
            )
        }
        None => note,
    };
    let mut result = watch.finish(name, damped, || total(&mut setup.driver), note, started);
    result.turned_over = turned;
    result
}

/// The deepest any particle's contact sphere reaches into a collider, over its radius.
fn into_colliders(d: &perifrac_scene::Driver) -> f64 {
    let Some(c) = d.colliders() else {
        return 0.0;
    };
    let y = d.solver().positions();
    y.iter()
        .zip(d.radii())
        .map(|(&p, &r)| c.penetration(p, r) / r)
        .fold(0.0, f64::max)
}

/// Pairs of particles closer than `horizon` (m) at their rest positions `x` whose separation at
/// `y` points against the rest one (`(y_j - y_i) . (x_j - x_i) < 0`): where a body has folded
/// through itself. All pairs: for bodies of a few thousand particles.
pub fn turned_over(x: &[Vec3], y: &[Vec3], horizon: f64) -> usize {
    use perifrac_physics::math::{dot, sub};
    let mut count = 0;
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            let r = sub(x[j], x[i]);
            if dot(r, r) < horizon * horizon && dot(sub(y[j], y[i]), r) < 0.0 {
                count += 1;
            }
        }
    }
    count
}

fn refused(name: &str, message: String, started: Instant) -> CaseResult {
    CaseResult {
        name: name.into(),
        outcome: Outcome::Stopped(message),
        steps: 0,
        energy_drift: f64::NAN,
        max_speed: 0.0,
        wall_s: started.elapsed().as_secs_f64(),
        note: "refused at setup".into(),
        turned_over: None,
    }
}

/// A block of the same steel with `cells` 1 cm cells as a scene's mesh table.
fn block_mesh(cells: [usize; 3]) -> String {
    format!(
        "[mesh]\nprimitive = \"box\"\nsize = [{}, {}, {}]\ncells = [{}, {}, {}]\nstructure = \"lattice\"\n",
        cells[0] as f64 * 0.01,
        cells[1] as f64 * 0.01,
        cells[2] as f64 * 0.01,
        cells[0],
        cells[1],
        cells[2]
    )
}

const STEEL: &str = "[[material]]\nyoung = 200e9\npoisson = 0.25\ndensity = 7800.0\n";

fn sphere_impact(cells: [usize; 3]) -> CaseResult {
    let size = cells.map(|c| c as f64 * 0.01);
    let text = format!(
        "{}{STEEL}s_crit = 0.002\n\n[simulation]\nduration = {}\n\n\
         [[ball]]\ncenter = [{}, {}, {}]\nradius = {}\nvelocity = [0.0, 0.0, -100.0]\n\
         density = 7800.0\n",
        block_mesh(cells),
        (size[2] + 0.02) / 100.0,
        size[0] / 2.0,
        size[1] / 2.0,
        size[2] + 0.012,
        0.01,
    );
    scene_case(
        "100 m/s steel sphere into a steel block (fracture on)",
        &text,
        "dynamic 1 cm ball; bonds break, energy goes into fracture and flying pieces",
        true,
        None,
    )
}

/// What the press squeezes.
#[derive(Clone, Copy)]
enum Press {
    /// Elastic steel, contact between particles asked for.
    Elastic,
    /// The same with the inversion guard of [`PRESS_GUARD`].
    Guarded,
    /// Steel with a fracture threshold (and so, by default, contact between its fragments).
    Brittle,
}

/// A steel block pressed at 10 m/s to 20% of its height between the ground and a press plate
/// (a kinematic ball of radius 10 m, flat over the block to 0.1 mm), which then stops and holds
/// for as long again. Plate and ground are ten times as stiff as the default contact (contact
/// spheres then reach at most 30% of their radius into them, measured in the elastic press).
fn crush(cells: [usize; 3], press: Press) -> CaseResult {
    let size = cells.map(|c| c as f64 * 0.01);
    let speed = 10.0;
    let squeeze = 0.8 * size[2] / speed;
    let radius = 10.0;
    let guard = format!("self_contact = true\ninversion_guard = {PRESS_GUARD:?}\n");
    let (material, contact) = match press {
        Press::Brittle => ("s_crit = 0.002\n", ""),
        Press::Elastic => ("", "self_contact = true\n"),
        Press::Guarded => ("", guard.as_str()),
    };
    let text = format!(
        "{}{STEEL}{material}\n[simulation]\nduration = {}\ndamping = 0.0\n{contact}\n\
         [[ground]]\nstiffness_factor = {PRESS_STIFFNESS}\n\n\
         [[ball]]\ncenter = [{}, {}, {}]\nradius = {radius}\nvelocity = [0.0, 0.0, {}]\n\
         until = {squeeze}\nstiffness_factor = {PRESS_STIFFNESS}\n\n[output]\nframes = 4\n",
        block_mesh(cells),
        2.0 * squeeze,
        size[0] / 2.0,
        size[1] / 2.0,
        size[2] + radius,
        -speed,
    );
    let (name, note) = match press {
        Press::Brittle => (
            "press a brittle steel block to 20% of its height, then hold",
            "as the elastic press with s_crit = 0.002: it shatters; contact between fragments",
        ),
        Press::Elastic => (
            "press a steel block to 20% of its height, then hold (self contact)",
            "pressed between the ground and a plate at 10 m/s to 20% of the height, then held \
             for as long again",
        ),
        Press::Guarded => (
            "the same press with the inversion guard (factor 10)",
            "as the elastic press with inversion_guard = 10: springs towards each particle's \
             affine deformation",
        ),
    };
    run_scene_case(name, &text, note, true, None, true)
}

/// The press plate's and the ground's stiffness over the default contact's, in the crushes.
const PRESS_STIFFNESS: f64 = 10.0;

/// The guarded press's inversion guard factor: the least of 1, 3 and 10 under which the 8-cell
/// block does not fold (12 of its 171,876 pairs within a horizon turn over; docs/DECISIONS.md).
const PRESS_GUARD: f64 = 10.0;

fn two_materials(cells: [usize; 3], steps: u64) -> CaseResult {
    let size = cells.map(|c| c as f64 * 0.01);
    let text = format!(
        "{}[[material]]\nyoung = 2e7\npoisson = 0.25\ndensity = 7800.0\n\
         [[material]]\nyoung = 2e11\npoisson = 0.25\ndensity = 7800.0\n\
         region = {{ min = [-1.0, -1.0, -1.0], max = [{}, 1.0, 1.0] }}\n\n\
         [simulation]\nduration = 1.0\n\n[[velocity]]\nlinear = [0.0, 0.0, 1.0]\n\
         region = {{ min = [{}, -1.0, -1.0], max = [1.0, 1.0, 1.0] }}\n\n[output]\nframes = 1\n",
        block_mesh(cells),
        size[0] / 2.0,
        size[0] / 2.0,
    );
    scene_case(
        "two materials, stiffness ratio 10,000",
        &text,
        "E = 2e7 and 2e11 Pa halves; the soft half starts moving at 1 m/s across the interface",
        false,
        Some(steps),
    )
}

fn spinning(cells: [usize; 3], steps: u64) -> CaseResult {
    let text = format!(
        "{}{STEEL}\n[simulation]\nduration = 1.0\n\n[[velocity]]\nangular = [0.0, 0.0, 100.0]\n\n\
         [output]\nframes = 1\n",
        block_mesh(cells),
    );
    scene_case(
        "a block spinning at 100 rad/s",
        &text,
        "rigid spin about z, free; the centrifugal stretch is tiny for steel",
        false,
        Some(steps),
    )
}

/// A steel block with one layer of cells squashed to 2% of its height: its tets are flat
/// slivers (dihedral angles down to 1.15 degrees, none above 90) with a fiftieth of the
/// others' volume.
fn slivers(cells: [usize; 3], steps: u64) -> Result<CaseResult, BenchError> {
    let started = Instant::now();
    let name = "an input mesh with sliver tets";
    let h = 0.01;
    let size = cells.map(|c| c as f64 * h);
    let (mut v, t) = box_data([0.0; 3], size, cells);
    let z0 = h * (cells[2] / 2) as f64;
    let squash = 0.02;
    for p in v.iter_mut() {
        p[2] = if p[2] <= z0 + 1e-12 {
            p[2]
        } else if p[2] <= z0 + h + 1e-12 {
            z0 + squash * (p[2] - z0)
        } else {
            p[2] - (1.0 - squash) * h
        };
    }
    let moved = cells[0] * cells[1] * 6;
    let mesh = tet_mesh(name, v, t)?;
    let q = mesh.quality();
    let b = mesh_body(name, &mesh, 1.5, &steel())?;
    let n = b.rest().len();
    let mut s = b.solver(name, Loads::new(n))?;
    s.velocities_mut().copy_from_slice(&noise(n, 0.1));
    let note = format!(
        "{moved} sliver tets; dihedral angles {:.2} to {:.2} deg, tet volumes {:.1e} to {:.1e} \
         m^3; dt {:.2e} s",
        q.min_dihedral_deg,
        q.max_dihedral_deg,
        q.min_volume,
        q.max_volume,
        s.dt()
    );
    Ok(drive(name, s, steps, false, note, started))
}

/// A block of glass flung apart so fast that every bond breaks, then stepped on: isolated
/// particles must fly straight, not turn to NaN.
fn isolated(cells: [usize; 3], steps: u64) -> Result<CaseResult, BenchError> {
    let started = Instant::now();
    let name = "fully damaged, isolated particles";
    let size = cells.map(|c| c as f64 * 0.01);
    let mut glass = ChenMaterial::from_young_poisson(70e9, 0.22, 2500.0).map_err(|cause| {
        BenchError::Physics {
            case: name.into(),
            cause,
        }
    })?;
    glass.fracture = Some(FractureParams {
        s_crit: 1e-4,
        alpha: 0.0,
    });
    let b = block(name, size, cells, 1.5, &glass)?;
    let n = b.rest().len();
    let centre = size.map(|s| s / 2.0);
    let mut s = b.solver(name, Loads::new(n))?;
    // Radial expansion at 200 1/s: every bond is past its threshold within a few steps.
    set_velocities(&mut s, |p| [0, 1, 2].map(|k| 200.0 * (p[k] - centre[k])));
    let bonds = s.model().discretization().family().num_bonds();
    let result = drive_then(
        name,
        s,
        steps,
        true,
        |s| {
            let intact = s.model().damage().map_or(bonds, |d| d.intact_bonds());
            format!(
                "radial velocity 200 r (1/s): {} of {bonds} directed bonds broken; then the \
                 particles fly free",
                bonds - intact
            )
        },
        started,
    );
    Ok(result)
}

fn long_run(cells: [usize; 3], steps: u64) -> Result<CaseResult, BenchError> {
    let started = Instant::now();
    let name = format!("{steps} undamped steps");
    let size = cells.map(|c| c as f64 * 0.01);
    let b = block(&name, size, cells, 1.5, &steel())?;
    let n = b.rest().len();
    let mut s = b.solver(&name, Loads::new(n))?;
    // A smooth twist and shear, 0.1 m/s at most: the low modes a simulation carries, not the
    // grid-scale ones whose energy velocity Verlet resolves only to (omega dt)^2.
    let pi = std::f64::consts::PI;
    set_velocities(&mut s, |p| {
        let (x, y, z) = (p[0] / size[0], p[1] / size[1], p[2] / size[2]);
        [
            0.1 * (pi * z).sin(),
            0.1 * (pi * x).sin() * (pi * z).cos(),
            0.05 * (pi * y).sin(),
        ]
    });
    let note = format!(
        "steel block of {n} particles at 0.8 of the stable estimate, smooth initial velocities"
    );
    Ok(drive(&name, s, steps, false, note, started))
}

/// A hard case, run on demand.
type Case = Box<dyn Fn() -> Result<CaseResult, BenchError>>;

/// Runs every hard case; each is isolated, so a panic in one is reported, not propagated.
pub fn run_all(effort: Effort, progress: &mut dyn FnMut(&str)) -> Vec<CaseResult> {
    // Step-factor cases run long enough for a slow instability to reach the guard.
    let (cells, steps, factor_steps, long): ([usize; 3], u64, u64, u64) = match effort {
        Effort::Tiny => ([4, 4, 4], 300, 300, 2_000),
        Effort::Full => ([8, 8, 8], 2_000, 20_000, 100_000),
    };
    let mut cases: Vec<(String, Case)> = Vec::new();
    for f in [0.5, 0.9, 1.0, 1.5, 2.0] {
        cases.push((
            format!("explicit step at {f} x the stable estimate"),
            Box::new(move || step_factor(f, cells, factor_steps)),
        ));
    }
    cases.push((
        "sphere impact".into(),
        Box::new(move || Ok(sphere_impact(cells))),
    ));
    cases.push((
        "crush".into(),
        Box::new(move || Ok(crush(cells, Press::Elastic))),
    ));
    cases.push((
        "guarded crush".into(),
        Box::new(move || Ok(crush(cells, Press::Guarded))),
    ));
    cases.push((
        "brittle crush".into(),
        Box::new(move || Ok(crush(cells, Press::Brittle))),
    ));
    cases.push((
        "two materials".into(),
        Box::new(move || Ok(two_materials(cells, steps))),
    ));
    cases.push(("slivers".into(), Box::new(move || slivers(cells, steps))));
    cases.push(("isolated".into(), Box::new(move || isolated(cells, steps))));
    cases.push((
        "spinning".into(),
        Box::new(move || Ok(spinning(cells, steps))),
    ));
    cases.push(("long".into(), Box::new(move || long_run([4, 4, 4], long))));
    cases
        .into_iter()
        .map(|(name, case)| {
            progress(&format!("stability: {name}"));
            let started = Instant::now();
            match catch_unwind(AssertUnwindSafe(case)) {
                Ok(Ok(r)) => r,
                Ok(Err(e)) => refused(&name, e.to_string(), started),
                Err(panic) => CaseResult {
                    name: name.clone(),
                    outcome: Outcome::Failed(format!(
                        "panic: {}",
                        panic
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_default()
                    )),
                    steps: 0,
                    energy_drift: f64::NAN,
                    max_speed: 0.0,
                    wall_s: started.elapsed().as_secs_f64(),
                    note: String::new(),
                    turned_over: None,
                },
            }
        })
        .collect()
}

/// The results as a Markdown table.
pub fn table(results: &[CaseResult]) -> Table {
    let mut t = Table::new(&[
        "case",
        "outcome",
        "steps",
        "energy drift",
        "max speed (m/s)",
        "wall time (s)",
        "notes",
    ]);
    for r in results {
        let outcome = match &r.outcome {
            Outcome::Survived => "survived".to_string(),
            Outcome::Stopped(m) => format!("stopped: {m}"),
            Outcome::Failed(m) => format!("**FAILED**: {m}"),
            Outcome::Runaway(m) => format!("**FAILED** (runaway): {m}"),
        };
        t.push(vec![
            r.name.clone(),
            outcome,
            r.steps.to_string(),
            if r.energy_drift.is_finite() && r.steps >= MIN_DRIFT_SAMPLES * ENERGY_EVERY {
                format!("{:+.2e}", r.energy_drift)
            } else {
                "-".into()
            },
            format!("{:.3e}", r.max_speed),
            format!("{:.2}", r.wall_s),
            r.note.clone(),
        ]);
    }
    t
}
