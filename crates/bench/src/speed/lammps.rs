//! LAMMPS side by side: one matched problem, a cube pulled apart at its middle, run through
//! `perifrac run`'s own path (scene text, [`Setup`], [`perifrac_scene::run`]) and through
//! LAMMPS's PERI package (`lmp`, `mpirun -np 2` on two cores) when it is installed; and the
//! machine's memory bandwidth, the floor under any bond loop.
//!
//! The match: the same particle count within 2% (perifrac's Kuhn cube of `c^3` cells has
//! `6 c^3` particles; LAMMPS's simple cubic lattice `m^3`, `m` the nearest whole cube root),
//! about as many bonds per particle (LAMMPS's horizon between the lattice's 11th and 12th
//! shells: 170 neighbours inside, 157 on average with the faces), the same glass (E = 70 GPa,
//! nu = 0.22, 2500 kg/m^3), the same 100 steps of 1 us with the halves moving apart at 1 m/s
//! each, nothing breaking. Elastic pairs with `peri/lps` (state-based, like Chen's model),
//! brittle (fracture on, contact between particles on, as a breaking scene has by default)
//! with `peri/pmb` (bond-based, fracture and short-range contact built in).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use perifrac_scene::{Limits, MemoDir, Scene, Setup, Silent};
use rayon::prelude::*;

use crate::table::Table;
use crate::{BenchError, Effort};

/// What the side-by-side table of `effort` matches, for the report.
pub fn lammps_match(effort: Effort) -> String {
    let (cells, m) = sizes(effort);
    format!(
        "One problem is run by both codes: a glass cube (E = 70 GPa, nu = 0.22, 2500 kg/m^3). \
         Its halves move apart at 1 m/s each for {STEPS} steps of 1 us, with nothing breaking. \
         In perifrac, the cube is {cells} x {cells} x {cells} Kuhn cells. Its horizon is 1.45 \
         of the mean edge. It is run as `perifrac run` runs a scene: setup, steps, and the \
         frame files written. The elastic path is Chen's model without fracture. The brittle \
         path has fracture on and contact between particles, as a breaking scene has by \
         default. LAMMPS runs as `lmp`, under `mpirun -np 2` on two cores, with one OpenMP \
         thread a rank. It has {m}^3 particles on a simple cubic lattice. Its horizon is \
         sqrt(11.5) spacings, for about as many bonds a particle. `peri/lps` (state-based) \
         runs against the elastic path. `peri/pmb` (bond-based, fracture and short-range \
         contact built in) runs against the brittle one. Time per bond update compares the \
         stepping loops. The whole run includes setup and output. For LAMMPS, setup is the \
         wall time outside its loop. The setup of perifrac is that of any run of the scene \
         after its first. Such a run recalls the stable-step estimate the first run left in \
         the cache. Recalling it takes one force evaluation in place of the iteration and gives \
         the same bits. The first run's setup is given beside it. Peak memory is resident memory, \
         sampled every 20 ms. For LAMMPS, it is summed over its ranks."
    )
}

/// Kuhn cells across perifrac's cube, and lattice sites across LAMMPS's (the nearest whole
/// cube root of perifrac's particle count).
fn sizes(effort: Effort) -> (usize, usize) {
    let cells = match effort {
        Effort::Tiny => 6,
        Effort::Full => 26,
    };
    (
        cells,
        ((6 * cells * cells * cells) as f64).cbrt().round() as usize,
    )
}

/// How the floor table is computed, for the report.
pub const FLOOR_NOTE: &str = "The triad `a = b + s c` measures the memory bandwidth on one \
    thread and on all. It runs over arrays far larger than the caches, at 24 bytes an element. \
    It takes the best of five passes. The floor of a step is the time to stream the model's \
    arrays twice at that bandwidth. Chen's step makes two passes over the bonds: dilatation, \
    then forces. The per-bond arrays are nearly all of the model's memory. Gathers of \
    neighbours' positions are not counted, so the floor is optimistic.";

/// Steps of every run.
const STEPS: u32 = 100;
/// The step (s). The scene asks for a hair more so that `duration / dt` rounds up to exactly
/// [`STEPS`].
const DT: f64 = 1e-6;
/// Side of the cube (m).
const SIDE: f64 = 0.26;
/// LAMMPS's horizon over its lattice spacing, squared: between the shells at `sqrt(11)` and
/// `sqrt(12)`.
const LAMMPS_HORIZON2: f64 = 11.5;

/// Glass: Young's modulus (Pa), Poisson's ratio, density (kg/m^3).
const GLASS: (f64, f64, f64) = (70e9, 0.22, 2500.0);

/// One run of either code.
#[derive(Debug, Clone, Copy)]
struct RunFigures {
    particles: usize,
    bonds: usize,
    /// The stepping loop (s).
    steps_s: f64,
    /// Everything before the first step (s); perifrac's with the stable-step estimate recalled
    /// from the memo a first setup of the same cube left, as every `perifrac run` of a scene
    /// after its first.
    setup_s: f64,
    /// perifrac's first setup, the stable step iterated (s); `None` for LAMMPS.
    setup_cold_s: Option<f64>,
    /// The whole run (s).
    whole_s: f64,
    /// Peak resident memory (bytes), summed over processes; `None` where it cannot be read.
    peak: Option<u64>,
}

/// Which material path.
#[derive(Debug, Clone, Copy, PartialEq)]
enum CubePath {
    Elastic,
    Brittle,
}

impl CubePath {
    fn name(self) -> &'static str {
        match self {
            CubePath::Elastic => "elastic",
            CubePath::Brittle => "brittle",
        }
    }

    fn lammps_style(self) -> &'static str {
        match self {
            CubePath::Elastic => "peri/lps",
            CubePath::Brittle => "peri/pmb",
        }
    }
}

/// The side-by-side table (and a line saying what was skipped, empty when nothing was), and
/// the bandwidth table with each perifrac run's distance from the floor.
pub fn lammps_side_by_side(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, String, Table), BenchError> {
    let (cells, lattice) = sizes(effort);
    let lammps = lammps_available();
    let mpirun = lammps.is_ok() && command_runs("mpirun", &["--version"]);
    let mut skipped = String::new();
    if let Err(why) = &lammps {
        skipped = format!("LAMMPS rows skipped: {why}.");
    } else if !mpirun {
        skipped = "LAMMPS's two-core rows skipped: `mpirun` is not installed.".into();
    }
    progress("speed: memory bandwidth");
    let bandwidth = [
        triad_bandwidth(1, effort)?,
        triad_bandwidth(rayon::current_num_threads(), effort)?,
    ];
    let mut t = Table::new(&[
        "path",
        "cores",
        "code",
        "particles",
        "bonds",
        "s/step",
        "M bond updates/s/core",
        "setup (s)",
        "setup, first run (s)",
        "setup / whole run",
        "whole run (s)",
        "peak memory (MB)",
        "perifrac / LAMMPS: time per bond update, whole run",
    ]);
    let mut floor = Table::new(&[
        "path",
        "cores",
        "triad bandwidth (GB/s)",
        "model bytes streamed per step (MB)",
        "floor (s/step)",
        "perifrac (s/step)",
        "x floor",
    ]);
    let cores = [1, rayon::current_num_threads().max(2)];
    for path in [CubePath::Elastic, CubePath::Brittle] {
        for (c, &threads) in cores.iter().enumerate() {
            progress(&format!(
                "speed: perifrac {} cube, {threads} thread(s)",
                path.name()
            ));
            let (ours, streamed) = perifrac_cube(path, cells, threads)?;
            let theirs = match &lammps {
                Ok(()) if threads == 1 || mpirun => {
                    progress(&format!(
                        "speed: LAMMPS {} cube, {threads} core(s)",
                        path.lammps_style()
                    ));
                    Some(lammps_cube(path, lattice, threads)?)
                }
                _ => None,
            };
            let ratio = theirs.map_or("-".to_string(), |l| {
                format!(
                    "{:.2}, {:.2}",
                    ours.steps_s / STEPS as f64 / (l.steps_s / STEPS as f64)
                        * (l.bonds as f64 / ours.bonds as f64),
                    ours.whole_s / l.whole_s
                )
            });
            t.push(row(path, threads, "perifrac", &ours, ratio));
            if let Some(l) = theirs {
                t.push(row(path, threads, path.lammps_style(), &l, String::new()));
            }
            let gbs = bandwidth[c.min(1)];
            let floor_s = streamed as f64 / (gbs * 1e9);
            let per_step = ours.steps_s / STEPS as f64;
            floor.push(vec![
                path.name().into(),
                threads.to_string(),
                format!("{gbs:.1}"),
                format!("{:.0}", streamed as f64 / 1e6),
                format!("{floor_s:.4}"),
                format!("{per_step:.4}"),
                format!("{:.1}", per_step / floor_s),
            ]);
        }
    }
    Ok((t, skipped, floor))
}

fn row(path: CubePath, cores: usize, code: &str, r: &RunFigures, ratio: String) -> Vec<String> {
    let per_step = r.steps_s / STEPS as f64;
    vec![
        path.name().into(),
        cores.to_string(),
        code.into(),
        r.particles.to_string(),
        r.bonds.to_string(),
        format!("{per_step:.4}"),
        format!("{:.1}", r.bonds as f64 / per_step / 1e6 / cores as f64),
        format!("{:.2}", r.setup_s),
        r.setup_cold_s.map_or("-".into(), |s| format!("{s:.2}")),
        format!("{:.1}%", 100.0 * r.setup_s / r.whole_s),
        format!("{:.2}", r.whole_s),
        r.peak
            .map_or("-".into(), |b| format!("{:.0}", b as f64 / 1e6)),
        ratio,
    ]
}

/// The perifrac scene of the matched cube.
fn cube_scene(path: CubePath, cells: usize) -> String {
    let (young, poisson, density) = GLASS;
    let half = SIDE / 2.0;
    let fracture = match path {
        CubePath::Elastic => "",
        CubePath::Brittle => "s_crit = 0.01\n",
    };
    format!(
        "[mesh]\nprimitive = \"box\"\nstructure = \"lattice\"\nsize = [{SIDE}, {SIDE}, {SIDE}]\n\
         cells = [{cells}, {cells}, {cells}]\n\n[[material]]\nyoung = {young:e}\n\
         poisson = {poisson}\ndensity = {density}\n{fracture}\n[simulation]\n\
         horizon_factor = 1.45\ndt = {dt:e}\nduration = {duration:e}\n\n\
         [[velocity]]\nregion = {{ min = [-1.0, -1.0, -1.0], max = [{half}, 1.0, 1.0] }}\n\
         linear = [-1.0, 0.0, 0.0]\n[[velocity]]\n\
         region = {{ min = [{half}, -1.0, -1.0], max = [1.0, 1.0, 1.0] }}\n\
         linear = [1.0, 0.0, 0.0]\n\n[output]\nframes = 1\npovray = false\nparticles = false\n",
        dt = DT * (1.0 + 1e-9),
        duration = DT * STEPS as f64,
    )
}

/// A scratch directory of its own under the system's temporary directory.
fn scratch(what: &str) -> Result<PathBuf, BenchError> {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "perifrac-speed-{what}-{}-{}",
        std::process::id(),
        COUNT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).map_err(|e| peer(what, format!("{}: {e}", dir.display())))?;
    Ok(dir)
}

fn peer(case: &str, message: String) -> BenchError {
    BenchError::Scene {
        case: case.into(),
        message,
    }
}

/// Runs the cube through `perifrac run`'s path on `threads` threads; returns its figures and
/// the bytes one step streams by the floor's count: two passes (dilatation and forces) over the
/// model's arrays ([`perifrac_physics::ForceModel::memory_bytes`]).
fn perifrac_cube(
    path: CubePath,
    cells: usize,
    threads: usize,
) -> Result<(RunFigures, u64), BenchError> {
    let case = format!("perifrac {} cube", path.name());
    let scene = Scene::parse(&cube_scene(path, cells), Path::new("cube.toml"))
        .map_err(|e| peer(&case, e.to_string()))?;
    let dir = scratch("perifrac")?;
    let memo = MemoDir::new(scratch("memo")?);
    let pool = super::pool(threads)?;
    let limits = Limits {
        threads,
        ..Limits::for_this_machine()
    };
    let set_up = || {
        Setup::with_memo(&scene, None, &limits, Some(&memo)).map_err(|e| peer(&case, e.to_string()))
    };
    // the scene's first run: the estimate iterated and kept (its memory is not the run's peak)
    let setup_cold_s = pool.install(|| {
        let started = Instant::now();
        drop(set_up()?);
        Ok::<_, BenchError>(started.elapsed().as_secs_f64())
    })?;
    let peak = PeakSelf::start();
    let result = pool.install(|| {
        let started = Instant::now();
        let setup = set_up()?;
        let setup_s = started.elapsed().as_secs_f64();
        if !setup.info.times.stable_step_recalled {
            let why = memo
                .failure()
                .unwrap_or_else(|| "no stored estimate".into());
            return Err(peer(
                &case,
                format!("the stable step was not recalled: {why}"),
            ));
        }
        let (particles, bonds) = (setup.info.particles, setup.info.bonds);
        let streamed = 2 * setup.driver.solver().model().memory_bytes() as u64;
        let steps = setup.frames as u64 * setup.steps_per_frame;
        if steps != STEPS as u64 {
            return Err(peer(&case, format!("{steps} steps, not {STEPS}")));
        }
        let stepping = Instant::now();
        perifrac_scene::run(setup, &dir, &mut Silent).map_err(|e| peer(&case, e.to_string()))?;
        Ok((
            RunFigures {
                particles,
                bonds,
                steps_s: stepping.elapsed().as_secs_f64(),
                setup_s,
                setup_cold_s: Some(setup_cold_s),
                whole_s: started.elapsed().as_secs_f64(),
                peak: None,
            },
            streamed,
        ))
    });
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(memo.dir());
    let (mut figures, streamed) = result?;
    figures.peak = peak.read();
    Ok((figures, streamed))
}

/// Resets this process's peak resident memory (Linux: `5` into `/proc/self/clear_refs`) and
/// reads it back after a run; `None` where either is not possible.
struct PeakSelf(bool);

impl PeakSelf {
    fn start() -> PeakSelf {
        PeakSelf(std::fs::write("/proc/self/clear_refs", "5").is_ok())
    }

    fn read(&self) -> Option<u64> {
        self.0.then(|| vm_hwm(std::process::id())).flatten()
    }
}

/// `VmHWM` of process `pid` (bytes).
fn vm_hwm(pid: u32) -> Option<u64> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// `pid` and its descendants (Linux `/proc/PID/task/*/children`).
fn process_tree(pid: u32, out: &mut Vec<u32>) {
    out.push(pid);
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return;
    };
    for task in tasks.flatten() {
        if let Ok(text) = std::fs::read_to_string(task.path().join("children")) {
            for child in text.split_whitespace().filter_map(|c| c.parse().ok()) {
                process_tree(child, out);
            }
        }
    }
}

/// Whether `lmp` runs and has the PERI package; why not otherwise.
fn lammps_available() -> Result<(), String> {
    let out = Command::new("lmp")
        .arg("-h")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("`lmp` did not start ({e}); Debian's package is `lammps`"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    if text.contains("peri/pmb") && text.contains("peri/lps") {
        Ok(())
    } else {
        Err("`lmp` has no PERI package (no peri/pmb, peri/lps pair styles)".into())
    }
}

fn command_runs(program: &str, args: &[&str]) -> bool {
    Command::new(program)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The LAMMPS input of the matched cube: `m^3` particles on a simple cubic lattice of the
/// cube's side.
fn lammps_input(path: CubePath, m: usize) -> String {
    let (young, poisson, density) = GLASS;
    let a = SIDE / m as f64;
    let delta = LAMMPS_HORIZON2.sqrt() * a;
    let bulk = young / (3.0 * (1.0 - 2.0 * poisson));
    let shear = young / (2.0 * (1.0 + poisson));
    let coeff = match path {
        // K, G, horizon, s00 (no breaking), alpha
        CubePath::Elastic => format!("{bulk:e} {shear:e} {delta:e} 1.0e30 0.0"),
        // c = 18 K / (pi delta^4), horizon, s00 as perifrac's s_crit, alpha
        CubePath::Brittle => format!(
            "{:e} {delta:e} 0.01 0.0",
            18.0 * bulk / (std::f64::consts::PI * delta.powi(4))
        ),
    };
    let hi = m as f64 - 0.5;
    let mid = m as f64 / 2.0 - 0.5;
    format!(
        "units si\ndimension 3\nboundary s s s\natom_style peri\natom_modify map array\n\
         neighbor {skin:e} bin\nlattice sc {a:e}\n\
         region box block -0.5 {hi} -0.5 {hi} -0.5 {hi}\ncreate_box 1 box\n\
         create_atoms 1 region box\npair_style {style}\npair_coeff * * {coeff}\n\
         set group all density {density}\nset group all volume {vol:e}\n\
         region left block -0.5 {mid} -0.5 {hi} -0.5 {hi}\ngroup left region left\n\
         group right subtract all left\n\
         velocity left set -1.0 0.0 0.0 sum no units box\n\
         velocity right set 1.0 0.0 0.0 sum no units box\n\
         fix 1 all nve\ntimestep {DT:e}\nthermo {STEPS}\nrun {STEPS}\n",
        skin = 0.1 * a,
        style = path.lammps_style(),
        vol = a * a * a,
    )
}

/// Runs the LAMMPS cube on `cores` processes (`mpirun` for more than one), its memory sampled
/// every 20 ms.
fn lammps_cube(path: CubePath, m: usize, cores: usize) -> Result<RunFigures, BenchError> {
    let case = format!("LAMMPS {} cube", path.lammps_style());
    let dir = scratch("lammps")?;
    let input = dir.join("cube.in");
    let log = dir.join("log.lammps");
    std::fs::write(&input, lammps_input(path, m)).map_err(|e| peer(&case, e.to_string()))?;
    let mut cmd = if cores > 1 {
        let mut c = Command::new("mpirun");
        c.args(["-np", &cores.to_string(), "lmp"])
            // Open MPI refuses root without the first two, and more ranks than it counts
            // cores without the third; other MPIs ignore them
            .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .env("OMPI_MCA_rmaps_base_oversubscribe", "1");
        c
    } else {
        Command::new("lmp")
    };
    cmd.arg("-in")
        .arg(&input)
        .arg("-log")
        .arg(&log)
        .args(["-screen", "none"])
        .env("OMP_NUM_THREADS", "1")
        .current_dir(&dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let started = Instant::now();
    let mut child = cmd.spawn().map_err(|e| peer(&case, e.to_string()))?;
    let mut peak = 0u64;
    let status = loop {
        let mut tree = Vec::new();
        process_tree(child.id(), &mut tree);
        let sum: u64 = tree.iter().filter_map(|&p| vm_hwm(p)).sum();
        peak = peak.max(sum);
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(peer(&case, e.to_string())),
        }
    };
    let whole_s = started.elapsed().as_secs_f64();
    let mut stderr = String::new();
    if let Some(err) = child.stderr.take() {
        for line in BufReader::new(err).lines().map_while(Result::ok).take(20) {
            stderr.push_str(&line);
            stderr.push('\n');
        }
    }
    let text = std::fs::read_to_string(&log).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    if !status.success() {
        let tail: Vec<&str> = text.lines().rev().take(5).collect();
        return Err(peer(
            &case,
            format!(
                "{status}: {stderr}{}",
                tail.into_iter().rev().collect::<Vec<_>>().join("\n")
            ),
        ));
    }
    let parsed = parse_log(&text).ok_or_else(|| peer(&case, "no loop time in its log".into()))?;
    Ok(RunFigures {
        particles: parsed.atoms,
        bonds: parsed.bonds,
        steps_s: parsed.loop_s,
        setup_s: whole_s - parsed.loop_s,
        setup_cold_s: None,
        whole_s,
        peak: (peak > 0).then_some(peak),
    })
}

/// What a LAMMPS log says about the run.
#[derive(Debug, Clone, Copy, PartialEq)]
struct LammpsLog {
    loop_s: f64,
    atoms: usize,
    bonds: usize,
}

/// Reads `Loop time of T on P procs for N steps with A atoms` and the PERI fix's `total # of
/// bonds = B`.
fn parse_log(text: &str) -> Option<LammpsLog> {
    let lp = text.lines().find(|l| l.starts_with("Loop time of "))?;
    let words: Vec<&str> = lp.split_whitespace().collect();
    let loop_s = words.get(3)?.parse().ok()?;
    let atoms = words.iter().position(|&w| w == "with")?;
    let atoms = words.get(atoms + 1)?.parse().ok()?;
    let bonds = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("total # of bonds = "))?
        .trim()
        .parse()
        .ok()?;
    Some(LammpsLog {
        loop_s,
        atoms,
        bonds,
    })
}

/// STREAM's triad `a = b + s c` over three arrays far larger than any cache, on `threads`
/// threads: the best of five passes, counting 24 bytes per element (GB/s).
fn triad_bandwidth(threads: usize, effort: Effort) -> Result<f64, BenchError> {
    let n = match effort {
        Effort::Tiny => 1 << 20,
        Effort::Full => 1 << 25,
    };
    let pool = super::pool(threads)?;
    Ok(pool.install(|| {
        let b = vec![1.0f64; n];
        let c = vec![2.0f64; n];
        let mut a = vec![0.0f64; n];
        let chunk = n.div_ceil(threads);
        let mut best = f64::INFINITY;
        for k in 0..5 {
            let s = 1.0 + k as f64;
            let t = Instant::now();
            a.par_chunks_mut(chunk)
                .zip(b.par_chunks(chunk).zip(c.par_chunks(chunk)))
                .for_each(|(a, (b, c))| {
                    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + s * c;
                    }
                });
            best = best.min(t.elapsed().as_secs_f64());
            std::hint::black_box(&a);
        }
        24.0 * n as f64 / best / 1e9
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lammps_log_is_read() {
        let log = "Peridynamic bonds:\n  total # of bonds = 14042414\n  bonds/atom = 135.253\n\
                   Loop time of 39.4992 on 1 procs for 100 steps with 103823 atoms\n";
        assert_eq!(
            parse_log(log),
            Some(LammpsLog {
                loop_s: 39.4992,
                atoms: 103823,
                bonds: 14042414
            })
        );
        assert_eq!(parse_log("Loop time of x on 1 procs"), None);
    }

    #[test]
    fn the_cube_scene_takes_exactly_the_steps_asked_for() {
        let scene =
            Scene::parse(&cube_scene(CubePath::Brittle, 3), Path::new("cube.toml")).unwrap();
        let setup = Setup::new(&scene, None).unwrap();
        assert_eq!(setup.frames as u64 * setup.steps_per_frame, STEPS as u64);
        assert_eq!(setup.info.particles, 6 * 27);
    }
}
