//! `perifrac bench speed`: how fast the particles go. The bond-update rate of each material
//! path on one core and on all of them, seconds per step at the size of the paper's glass
//! wall, the share of a step the topology takes while a slab shatters, and memory per bond.
//! Timings are wall clock on whatever machine runs it; the report says which. [`implicit_step`]
//! times Xu's model under the implicit step.

use std::path::Path;
use std::time::{Duration, Instant};

use perifrac_physics::{
    ChenMaterial, ChenModel, Explicit, ForceModel, FractureParams, Loads, YieldParams,
};
use perifrac_scene::{Scene, Setup};

use crate::bar;
use crate::table::Table;
use crate::{BenchError, Effort};

mod implicit;
mod lammps;

pub use implicit::implicit_step;
pub use lammps::{lammps_match, lammps_side_by_side, FLOOR_NOTE};

/// A material path of the Chen model.
#[derive(Debug, Clone, Copy)]
struct MaterialPath {
    name: &'static str,
    plastic: bool,
    /// Plastic with a yield limit of almost nothing: every bond yields at every step (the
    /// plastic paths' worst case; the others never yield).
    yielding: bool,
    fracture: bool,
    anisotropic: bool,
}

const PATHS: [MaterialPath; 6] = [
    MaterialPath {
        name: "elastic",
        plastic: false,
        yielding: false,
        fracture: false,
        anisotropic: false,
    },
    MaterialPath {
        name: "brittle (fracture)",
        plastic: false,
        yielding: false,
        fracture: true,
        anisotropic: false,
    },
    MaterialPath {
        name: "plastic",
        plastic: true,
        yielding: false,
        fracture: false,
        anisotropic: false,
    },
    MaterialPath {
        name: "ductile (plastic + fracture)",
        plastic: true,
        yielding: false,
        fracture: true,
        anisotropic: false,
    },
    MaterialPath {
        name: "plastic, every bond yielding",
        plastic: true,
        yielding: true,
        fracture: false,
        anisotropic: false,
    },
    MaterialPath {
        name: "anisotropic elastic",
        plastic: false,
        yielding: false,
        fracture: false,
        anisotropic: true,
    },
];

fn material(p: MaterialPath) -> ChenMaterial {
    let mut m = ChenMaterial::from_young_poisson(70e9, 0.22, 2500.0).expect("valid constants");
    if p.plastic {
        m.plasticity = Some(YieldParams {
            psi0: if p.yielding { 1e-30 } else { 1e30 },
            gamma_ratio: 0.2,
            from_strain: false,
        });
    }
    if p.fracture {
        m.fracture = Some(FractureParams {
            s_crit: 0.01,
            alpha: 0.0,
        });
    }
    if p.anisotropic {
        m.anisotropy = Some([[2.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]);
    }
    m
}

/// Batches [`time_steps`] takes the fastest of: a shared machine's noise only ever adds time.
const BATCHES: u32 = 3;

/// Times [`BATCHES`] batches of `steps` explicit steps of `s` (after one untimed step);
/// returns the mean per step of the fastest batch.
fn time_steps(s: &mut Explicit<ChenModel>, steps: u32, case: &str) -> Result<Duration, BenchError> {
    let physics = |cause| BenchError::Physics {
        case: case.into(),
        cause,
    };
    s.step().map_err(physics)?;
    let mut best = Duration::MAX;
    for _ in 0..BATCHES {
        let t = Instant::now();
        for _ in 0..steps {
            s.step().map_err(physics)?;
        }
        best = best.min(t.elapsed() / steps);
    }
    Ok(best)
}

/// Chen's two corrections the report times: the scalar calibration (the rows as first
/// measured) and the fitted dilatation (the default since issue 18; 16 bytes a bond more).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Correction {
    Calibrated,
    Fitted,
}

impl Correction {
    const BOTH: [Correction; 2] = [Correction::Calibrated, Correction::Fitted];

    fn name(self) -> &'static str {
        match self {
            Correction::Calibrated => "calibrated",
            Correction::Fitted => "fitted (default)",
        }
    }

    /// A box of `cells` cells of `size` (m) of `material` with this correction.
    fn block(
        self,
        case: &str,
        size: [f64; 3],
        cells: [usize; 3],
        material: ChenMaterial,
    ) -> Result<bar::Body<ChenModel>, BenchError> {
        match self {
            Correction::Calibrated => bar::block(case, size, cells, 1.45, &material),
            Correction::Fitted => bar::block(case, size, cells, 1.45, &bar::FittedChen(material)),
        }
    }
}

/// A block of `cells` 1 cm cells of path `p`'s material, moving gently (so plastic and damage
/// state are exercised but nothing breaks), ready to step.
fn moving_block(
    p: MaterialPath,
    correction: Correction,
    cells: [usize; 3],
    case: &str,
) -> Result<(Explicit<ChenModel>, usize), BenchError> {
    let size = cells.map(|c| c as f64 * 0.01);
    let b = correction.block(case, size, cells, material(p))?;
    let bonds = b.bonds();
    let loads = Loads::new(b.rest().len());
    let mut s = b.solver(case, loads)?;
    // the yielding path also stretches along x at 1/s, so every bond's extension moves
    let stretch = if p.yielding { 1.0 } else { 0.0 };
    bar::set_velocities(&mut s, |x| {
        [1e-3 * x[1] + stretch * x[0], -1e-3 * x[0], 0.0]
    });
    Ok((s, bonds))
}

/// A rayon pool of `threads` workers.
pub(crate) fn pool(threads: usize) -> Result<rayon::ThreadPool, BenchError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| BenchError::Threads {
            message: e.to_string(),
        })
}

fn one_thread<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, BenchError> {
    Ok(pool(1)?.install(f))
}

/// Bond updates per second of every material path, with either correction, on one thread and
/// on the global pool, and bytes per bond.
pub fn paths(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let (cells, steps): ([usize; 3], u32) = match effort {
        Effort::Tiny => ([8, 8, 8], 3),
        Effort::Full => ([40, 40, 10], 10),
    };
    let threads = rayon::current_num_threads();
    let mut t = Table::new(&[
        "material path",
        "correction",
        "particles",
        "bonds",
        "s/step, 1 thread",
        "M bond updates/s, 1 thread",
        &format!("s/step, {threads} threads"),
        &format!("M bond updates/s, {threads} threads"),
        "bytes per bond",
    ]);
    for c in Correction::BOTH {
        for p in PATHS {
            progress(&format!(
                "speed: {} ({}) on {cells:?} cells",
                p.name,
                c.name()
            ));
            let case = format!("speed {} ({})", p.name, c.name());
            let (mut s, bonds) = moving_block(p, c, cells, &case)?;
            let bytes = s.model().memory_bytes() as f64 / bonds as f64;
            let n = s.positions().len();
            let all = time_steps(&mut s, steps, &case)?;
            let (mut s1, _) = moving_block(p, c, cells, &case)?;
            let one = one_thread(move || time_steps(&mut s1, steps, &case))??;
            t.push(path_row(p, c, n, bonds, one, all, bytes));
        }
    }
    Ok(t)
}

/// One row of [`paths`]: `one` and `all` the times per step on one thread and on the pool.
fn path_row(
    p: MaterialPath,
    c: Correction,
    n: usize,
    bonds: usize,
    one: Duration,
    all: Duration,
    bytes: f64,
) -> Vec<String> {
    let rate = |d: Duration| bonds as f64 / d.as_secs_f64() / 1e6;
    vec![
        p.name.into(),
        c.name().into(),
        n.to_string(),
        bonds.to_string(),
        format!("{:.4}", one.as_secs_f64()),
        format!("{:.1}", rate(one)),
        format!("{:.4}", all.as_secs_f64()),
        format!("{:.1}", rate(all)),
        format!("{bytes:.1}"),
    ]
}

/// Seconds per step of a glass wall of the paper's size (Table 1: 3.0e5 particles, 5.0e7
/// bonds at delta = 1.45 lambda): 100 x 100 x 5 cells of a 1 x 1 x 0.05 m wall, with either
/// correction.
pub fn glass_wall(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let (cells, steps): ([usize; 3], u32) = match effort {
        Effort::Tiny => ([20, 20, 2], 2),
        Effort::Full => ([100, 100, 5], 5),
    };
    let mut t = Table::new(&[
        "correction",
        "particles",
        "bonds",
        "setup (s)",
        &format!("s/step ({} threads)", rayon::current_num_threads()),
        "model memory (MB)",
        "paper (s/step)",
    ]);
    for c in Correction::BOTH {
        progress(&format!(
            "speed: glass wall of {cells:?} cells ({})",
            c.name()
        ));
        let case = format!("speed glass wall ({})", c.name());
        let started = Instant::now();
        let size = [1.0, 1.0, 0.05 * cells[2] as f64 / 5.0];
        let mut glass = ChenMaterial::elastic(3.3e10, 2.0e10, 2200.0);
        glass.fracture = Some(FractureParams {
            s_crit: 0.0005,
            alpha: 0.0,
        });
        let b = c.block(&case, size, cells, glass)?;
        let (n, bonds) = (b.rest().len(), b.bonds());
        let mut s = b.solver(&case, Loads::new(n))?;
        let setup = started.elapsed();
        let bytes = s.model().memory_bytes();
        let per_step = time_steps(&mut s, steps, &case)?;
        t.push(vec![
            c.name().into(),
            n.to_string(),
            bonds.to_string(),
            format!("{:.1}", setup.as_secs_f64()),
            format!("{:.3}", per_step.as_secs_f64()),
            format!("{:.0}", bytes as f64 / 1e6),
            "~2.4 (3.0e5 particles, 5.0e7 bonds, 6-core i7, OpenMP)".into(),
        ]);
    }
    Ok(t)
}

/// The share of each stage of the driver's step while a glass slab is shot to pieces: the
/// default scene's slab and ball at 150 m/s, stepped for `steps` steps from the impact on.
pub fn fracture_share(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let cells = match effort {
        Effort::Tiny => [12, 12, 2],
        Effort::Full => [36, 36, 4],
    };
    progress(&format!(
        "speed: stage shares while a slab of {cells:?} cells shatters"
    ));
    let text = format!(
        "[mesh]\nprimitive = \"box\"\nsize = [0.6, 0.6, 0.06]\ncells = [{}, {}, {}]\nstructure = \"lattice\"\n\n\
         [[material]]\nbulk_modulus = 3.3e10\nshear_modulus = 2.0e10\ndensity = 2200.0\n\
         s_crit = 0.0005\n\n[simulation]\nduration = 0.001\n\n\
         [[ball]]\ncenter = [0.3, 0.3, 0.111]\nradius = 0.05\nvelocity = [0.0, 0.0, -150.0]\n\n\
         [output]\nframes = 1\n",
        cells[0], cells[1], cells[2]
    );
    let scene_error = |e: &dyn std::fmt::Display| BenchError::Scene {
        case: "fracture share".into(),
        message: e.to_string(),
    };
    let scene =
        Scene::parse(&text, Path::new("fracture-share.toml")).map_err(|e| scene_error(&e))?;
    let mut setup = Setup::new(&scene, None).map_err(|e| scene_error(&e))?;
    let steps = setup.frames as u64 * setup.steps_per_frame;
    let mut crack_faces = 0;
    for _ in 0..steps {
        let r = setup.driver.step().map_err(|cause| BenchError::Physics {
            case: "fracture share".into(),
            cause,
        })?;
        crack_faces += r.crack_faces;
    }
    let st = setup.driver.stage_times();
    let total = st.physics + st.topology + st.advect;
    let share = |d: Duration| format!("{:.2}%", 100.0 * d.as_secs_f64() / total.as_secs_f64());
    let mut t = Table::new(&[
        "particles",
        "steps",
        "bonds broken",
        "crack faces",
        "physics + contact",
        "of which contact (colliders, between particles)",
        "topology (crack faces, splitting)",
        "advection",
        "ms/step",
    ]);
    t.push(vec![
        setup.info.particles.to_string(),
        steps.to_string(),
        setup.driver.broken_bonds().to_string(),
        crack_faces.to_string(),
        share(st.physics),
        share(st.contact),
        share(st.topology),
        share(st.advect),
        format!("{:.2}", 1e3 * total.as_secs_f64() / steps as f64),
    ]);
    Ok(t)
}
