//! Work and memory estimates made before anything big is allocated, and the budgets a run must
//! stay within unless large runs are allowed ([`Limits::allow_large`]).
//!
//! The memory estimate is made twice: from the scene's mesh spec before the mesh is built (a
//! box's cell counts, a surface's lattice, a tet file's counts), and from the built mesh before
//! the bond families are. The step estimate is made once the step is known (and earlier, from
//! the frame count and the contact travel limit, where those alone pass the budget); the output
//! and run-time estimates then.

use std::f64::consts::PI;
use std::fmt;

/// Bytes per particle (= tet) at the peak of setup and run, an over-estimate by about 1.5x:
/// the topology mesh (tets, face neighbours, crack flags, vertex stars: about 50 B), its
/// face hash map while it is built (up to about 100 B), the setup's barycentres, volumes,
/// adjacency and radii (about 60 B), the solver's per-particle arrays (positions, velocities,
/// forces, rest state, masses, stable-step iteration vectors: about 250 B) and the output's
/// per-particle scalars.
pub const BYTES_PER_PARTICLE: u64 = 600;

/// Bytes per mesh vertex: rest and current positions, vertex copies, star offsets, splitting
/// scratch, and the file's or primitive's own copy.
pub const BYTES_PER_VERTEX: u64 = 100;

/// Bytes per directed bond at the peak: the family build's per-particle rows (4 B, up to twice
/// that while they grow) next to the final neighbour list (4 B) and rest lengths (8 B), the
/// fitted dilatation's pair of weights (16 B, and a 4 B reverse index while they are made; Xu's
/// keeps its reverse index) and
/// the model's bond state (damage, plastic extensions: up to 17 B). BENCHMARKS.md measures
/// 28.8 B per bond for the default elastic model and 46.4 for a ductile one once built, so
/// this over-estimates by 1.2x to 2x.
pub const BYTES_PER_BOND: u64 = 56;

/// Extra bytes per directed bond of an inversion guard: Chen's model keeps each bond's rest
/// stiffness and its reverse's (Xu's computes them as it goes: an over-estimate there).
pub const GUARD_BYTES_PER_BOND: u64 = 16;

/// Extra bytes per directed bond of an implicit step: the sparse step matrix (a 3 x 3 block of
/// f64 per bond pair, 36 B per directed bond) and its Cholesky factor, its fill-in taken as
/// about three times the matrix. A rough guess: the fill-in depends on the mesh's ordering.
pub const IMPLICIT_BYTES_PER_BOND: u64 = 150;

/// Bytes per tet of `perifrac mesh` (no bonds): the primitive's or mesher's arrays, the topology
/// mesh with its face hash map while it is built, and the copy handed to the writer.
pub const MESH_BYTES_PER_TET: u64 = 200;

/// Seconds per bond update on one core, an estimate with room to spare: BENCHMARKS.md's
/// bond-rate block measures 5.4 ns elastic, 5.9 brittle and 6.0 ductile (the default model,
/// one thread, the vector loops; 9 to 11 ns on a CPU without AVX2 or with anisotropic
/// weights, which take the scalar ones: 17.7 ns anisotropic), 26 ns where every bond yields;
/// the rest covers contact, output and a slower or busier machine (it was set when the
/// brittle path took 18 ns and the ductile one 32).
pub const SECONDS_PER_BOND_UPDATE: f64 = 27e-9;

/// Speed-up per worker thread: BENCHMARKS.md measures 1.9 to 2.0 times one thread on two.
pub const SPEEDUP_PER_THREAD: f64 = 0.8;

/// Passes over the bonds an implicit step is counted as in the run-time estimate: a typical
/// quasi-Newton step of a few iterations with line-search trials (the cap is the scene's
/// `iterations`).
pub const IMPLICIT_PASSES_PER_STEP: f64 = 10.0;

/// Steps a run may take: 1e8 steps of even a tiny scene take hours; a scene that needs more
/// has a step far below what its frames need (a very fast ball, a stiff or tiny mesh) or a
/// duration far beyond an animation's.
pub const MAX_STEPS: u64 = 100_000_000;

/// Bytes a run may write: 100 GB, more than a disk usually has to spare for one animation.
pub const MAX_OUTPUT_BYTES: u64 = 100_000_000_000;

/// Estimated wall time a run may take: one day (s).
pub const MAX_SECONDS: f64 = 86_400.0;

/// Memory assumed when the machine's available memory cannot be read (8 GiB).
pub const FALLBACK_MEMORY_BYTES: u64 = 8 << 30;

/// Mean distinct edge length of a BCC lattice (the built-in mesher's) as a multiple of its
/// spacing `h`: per cube 8 corner-centre edges of `sqrt(3)/2 h` and 6 axis edges of `h`.
pub const BCC_MEAN_EDGE: f64 = (8.0 * 0.866_025_403_784_438_6 + 6.0) / 14.0;

/// Volume of a BCC tet as a multiple of `h^3` (12 tets per cube).
pub const BCC_TET_VOLUME: f64 = 1.0 / 12.0;

/// What the estimate needs of a mesh: counts, mean edge length (m) and mean tet volume (m^3).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshShape {
    /// Tets (= particles).
    pub tets: u64,
    /// Vertices.
    pub vertices: u64,
    /// Mean edge length (m).
    pub mean_edge: f64,
    /// Mean tet volume (m^3).
    pub mean_volume: f64,
}

impl MeshShape {
    /// The shape of tets given as vertex positions (m) and corner indices: the mean over tets
    /// of their six edge lengths, and of their volumes. `O(tets)`, allocates nothing; corners
    /// out of range are skipped.
    pub fn of_tets(vertices: &[[f64; 3]], tets: &[[u32; 4]]) -> MeshShape {
        let (mut edges, mut volumes, mut counted) = (0.0, 0.0, 0usize);
        for t in tets {
            let Some(p) = corners(vertices, t) else {
                continue;
            };
            let d = |a: [f64; 3], b: [f64; 3]| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            };
            let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
            edges += pairs.iter().map(|&(i, j)| d(p[i], p[j])).sum::<f64>() / 6.0;
            let e = |i: usize| [0, 1, 2].map(|k| p[i][k] - p[0][k]);
            let (a, b, c) = (e(1), e(2), e(3));
            let det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]);
            volumes += det.abs() / 6.0;
            counted += 1;
        }
        let n = counted.max(1) as f64;
        MeshShape {
            tets: tets.len() as u64,
            vertices: vertices.len() as u64,
            mean_edge: edges / n,
            mean_volume: volumes / n,
        }
    }

    /// The shape of a box of `cells` Kuhn cells with sides `cell` (m): the mean distinct edge
    /// ([`perifrac_topology::primitives::kuhn_mean_edge`]) and `abc / 6` per tet. `counts` are
    /// `(vertices, tets)` from [`perifrac_topology::primitives::box_counts`].
    pub fn of_box(cell: [f64; 3], counts: (usize, usize)) -> MeshShape {
        MeshShape {
            tets: counts.1 as u64,
            vertices: counts.0 as u64,
            mean_edge: perifrac_topology::primitives::kuhn_mean_edge(cell),
            mean_volume: cell[0] * cell[1] * cell[2] / 6.0,
        }
    }

    /// The shape of about `tets` BCC tets (the built-in mesher) at unit spacing: only the ratio
    /// of edge to volume matters to the family size. A BCC cube has 2 points and 12 tets, so
    /// there is about one vertex per six tets.
    pub fn of_bcc(tets: f64) -> MeshShape {
        let tets = saturating_u64(tets);
        MeshShape {
            tets,
            vertices: tets / 6 + 1,
            mean_edge: BCC_MEAN_EDGE,
            mean_volume: BCC_TET_VOLUME,
        }
    }
}

fn corners(vertices: &[[f64; 3]], t: &[u32; 4]) -> Option<[[f64; 3]; 4]> {
    Some([
        *vertices.get(t[0] as usize)?,
        *vertices.get(t[1] as usize)?,
        *vertices.get(t[2] as usize)?,
        *vertices.get(t[3] as usize)?,
    ])
}

/// `x` as a count, saturating (NaN and negatives to 0).
fn saturating_u64(x: f64) -> u64 {
    // `as` saturates at both ends and takes NaN to 0.
    x.ceil() as u64
}

/// Expected directed bonds per particle for horizon factor `horizon_factor` (the horizon is
/// that many mean edges): the particles within the horizon of an interior particle,
/// `(4/3) pi (k lambda)^3 / v` with `lambda` the mean edge (m) and `v` the mean tet volume
/// (m^3). Particles near the boundary have fewer, so this over-estimates the mean: 161
/// against the 144 measured on BENCHMARKS.md's 96,000-particle block at k = 1.45 (12%), more
/// on thin plates (about 2x on a plate three cells thick).
pub fn family_size(horizon_factor: f64, mean_edge: f64, mean_volume: f64) -> f64 {
    if mean_volume.is_nan() || mean_volume <= 0.0 {
        return 0.0;
    }
    4.0 / 3.0 * PI * (horizon_factor * mean_edge).powi(3) / mean_volume
}

/// The estimate of a run: sizes, memory, steps, output and wall time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WorkEstimate {
    /// Particles (= tets).
    pub particles: u64,
    /// Mesh vertices.
    pub vertices: u64,
    /// Directed bonds: estimated ([`family_size`]) until the families are built, then counted.
    pub bonds: u64,
    /// Peak memory (bytes), an over-estimate (see [`BYTES_PER_PARTICLE`], [`BYTES_PER_BOND`]).
    pub memory_bytes: u64,
    /// Steps, all frames together (0 until the step is known).
    pub steps: u64,
    /// Bytes of output, all frames together (0 until known).
    pub output_bytes: u64,
    /// Wall time (s) at [`SECONDS_PER_BOND_UPDATE`] (0 until known).
    pub seconds: f64,
}

impl WorkEstimate {
    /// Sizes and memory of a run on a mesh of `shape` with horizon factor `horizon_factor`;
    /// `extra` bytes a bond more ([`extra_per_bond`]).
    pub fn of_mesh(shape: MeshShape, horizon_factor: f64, extra: u64) -> WorkEstimate {
        let family = family_size(horizon_factor, shape.mean_edge, shape.mean_volume);
        let bonds = saturating_u64(shape.tets as f64 * family);
        WorkEstimate {
            particles: shape.tets,
            vertices: shape.vertices,
            bonds,
            memory_bytes: memory(shape.tets, shape.vertices, bonds, extra),
            ..WorkEstimate::default()
        }
    }

    /// The same run with the counted bonds: the memory is estimated again from them.
    pub fn with_bonds(self, bonds: u64, extra: u64) -> WorkEstimate {
        WorkEstimate {
            bonds,
            memory_bytes: memory(self.particles, self.vertices, bonds, extra),
            ..self
        }
    }

    /// The same run with a ghost layer of `ghosts` ghosts, `bonds` directed bonds to real
    /// particles and `layer_bytes` of its own (its maps and the extended discretisation the
    /// model copies): the ghosts' bonds walk the loops as the real ones do, and the ghosts
    /// take a particle's bytes each (the output still counts the real particles alone).
    pub fn with_ghosts(self, ghosts: u64, bonds: u64, layer_bytes: u64, extra: u64) -> Self {
        let bonds = self.bonds.saturating_add(bonds);
        WorkEstimate {
            bonds,
            memory_bytes: memory(
                self.particles.saturating_add(ghosts),
                self.vertices,
                bonds,
                extra,
            )
            .saturating_add(layer_bytes),
            ..self
        }
    }
}

/// Bytes a bond beyond [`BYTES_PER_BOND`]: the implicit step's matrix and factor, the
/// inversion guard's stiffnesses.
pub fn extra_per_bond(implicit: bool, guard: bool) -> u64 {
    u64::from(implicit) * IMPLICIT_BYTES_PER_BOND + u64::from(guard) * GUARD_BYTES_PER_BOND
}

/// Peak memory (bytes) of a run with these counts and `extra` bytes a bond more, saturating.
pub fn memory(particles: u64, vertices: u64, bonds: u64, extra: u64) -> u64 {
    let per_bond = BYTES_PER_BOND.saturating_add(extra);
    particles
        .saturating_mul(BYTES_PER_PARTICLE)
        .saturating_add(vertices.saturating_mul(BYTES_PER_VERTEX))
        .saturating_add(bonds.saturating_mul(per_bond))
}

/// Peak memory (bytes) of `perifrac mesh` making `tets` tets on `vertices` vertices.
pub fn mesh_memory(tets: u64, vertices: u64) -> u64 {
    tets.saturating_mul(MESH_BYTES_PER_TET)
        .saturating_add(vertices.saturating_mul(BYTES_PER_VERTEX))
}

/// Bytes written per frame: the surface PLY (12 B per vertex, 14 B per triangle), the POV-Ray
/// include (about 70 B per vertex and 30 B per triangle of text) and the particle PLY (24 B per
/// particle), plus headers and the frame's entry in `run.json`. A closed surface of `faces`
/// triangles has about `faces / 2` vertices. Cracks add surface, so for a run that breaks this
/// is a lower bound.
pub fn frame_bytes(faces: u64, particles: u64, povray: bool, particles_ply: bool) -> u64 {
    let vertices = faces / 2 + 2;
    let mut bytes = 2_000u64
        .saturating_add(faces.saturating_mul(14))
        .saturating_add(vertices.saturating_mul(12));
    if povray {
        bytes = bytes
            .saturating_add(faces.saturating_mul(30))
            .saturating_add(vertices.saturating_mul(70));
    }
    if particles_ply {
        bytes = bytes.saturating_add(particles.saturating_mul(24));
    }
    bytes
}

/// Wall time (s) of `steps` steps over `bonds` bonds on `threads` worker threads, no more of
/// them counted than the machine has cores (implicit steps count
/// [`IMPLICIT_PASSES_PER_STEP`] passes).
pub fn run_seconds(steps: u64, bonds: u64, threads: usize, implicit: bool) -> f64 {
    let passes = if implicit {
        IMPLICIT_PASSES_PER_STEP
    } else {
        1.0
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let speedup = (SPEEDUP_PER_THREAD * threads.min(cores) as f64).max(1.0);
    steps as f64 * bonds as f64 * passes * SECONDS_PER_BOND_UPDATE / speedup
}

/// The budgets a run is checked against.
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// Memory available to the run (bytes).
    pub memory_bytes: u64,
    /// Where [`Limits::memory_bytes`] came from, for messages.
    pub memory_source: String,
    /// Most steps ([`MAX_STEPS`]).
    pub max_steps: u64,
    /// Most bytes of output ([`MAX_OUTPUT_BYTES`]).
    pub max_output_bytes: u64,
    /// Most estimated wall time (s, [`MAX_SECONDS`]).
    pub max_seconds: f64,
    /// Worker threads the run will use (for the time estimate).
    pub threads: usize,
    /// Go on past every budget (the estimates are still made and reported).
    pub allow_large: bool,
}

impl Limits {
    /// The default budgets, this machine's available memory ([`available_memory`]) and its
    /// cores as the thread count (rayon's default; a caller that sets up its own pool says so
    /// in [`Limits::threads`]).
    pub fn for_this_machine() -> Limits {
        let (memory_bytes, memory_source) = available_memory();
        Limits {
            memory_bytes,
            memory_source,
            max_steps: MAX_STEPS,
            max_output_bytes: MAX_OUTPUT_BYTES,
            max_seconds: MAX_SECONDS,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            allow_large: false,
        }
    }

    /// Refuses `estimate` when its memory passes the available memory.
    pub fn check_memory(&self, estimate: &WorkEstimate) -> Result<(), String> {
        if self.allow_large || estimate.memory_bytes <= self.memory_bytes {
            return Ok(());
        }
        Err(format!(
            "the run would need about {} of memory ({} particles, {} bonds{}; an \
             over-estimate by up to 3x), more than the {} available ({})",
            bytes(estimate.memory_bytes),
            estimate.particles,
            count(estimate.bonds),
            if estimate.bonds > u64::from(u32::MAX) {
                ", also more than the 4294967295 a model indexes"
            } else {
                ""
            },
            bytes(self.memory_bytes),
            self.memory_source
        ))
    }

    /// Refuses a run of at least `steps` steps past [`Limits::max_steps`]; `why` says where
    /// the count comes from.
    pub fn check_steps(&self, steps: u64, why: &str) -> Result<(), String> {
        if self.allow_large || steps <= self.max_steps {
            return Ok(());
        }
        Err(format!(
            "the run would take {} steps ({why}), more than the budget of {} steps",
            count(steps),
            count(self.max_steps)
        ))
    }

    /// Refuses a run writing `output` bytes past [`Limits::max_output_bytes`].
    pub fn check_output(&self, output: u64, why: &str) -> Result<(), String> {
        if self.allow_large || output <= self.max_output_bytes {
            return Ok(());
        }
        Err(format!(
            "the run would write about {} ({why}), more than the budget of {}",
            bytes(output),
            bytes(self.max_output_bytes)
        ))
    }

    /// Refuses a run estimated to take `seconds` past [`Limits::max_seconds`].
    pub fn check_time(&self, seconds: f64, why: &str) -> Result<(), String> {
        if self.allow_large || seconds.is_nan() || seconds <= self.max_seconds {
            return Ok(());
        }
        Err(format!(
            "the run would take about {} ({why}), more than the budget of {}",
            duration(seconds),
            duration(self.max_seconds)
        ))
    }
}

/// Memory available to this process (bytes) and where the number came from: the smaller of
/// `MemAvailable` in `/proc/meminfo` and what the cgroup's memory limit leaves; when neither
/// can be read, [`FALLBACK_MEMORY_BYTES`].
pub fn available_memory() -> (u64, String) {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| mem_available(&t));
    match (meminfo, cgroup_room()) {
        (Some(m), Some(c)) if c < m => (c, "what the cgroup's memory limit leaves".into()),
        (Some(m), _) => (m, "MemAvailable in /proc/meminfo".into()),
        (None, Some(c)) => (c, "what the cgroup's memory limit leaves".into()),
        (None, None) => (
            FALLBACK_MEMORY_BYTES,
            "assumed: /proc/meminfo cannot be read".into(),
        ),
    }
}

/// `MemAvailable` (bytes) from the text of `/proc/meminfo`.
pub fn mem_available(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut words = line.split_whitespace().skip(1);
    let value: u64 = words.next()?.parse().ok()?;
    let unit = match words.next() {
        Some("kB") => 1024,
        None => 1,
        Some(_) => return None,
    };
    value.checked_mul(unit)
}

/// Room left under the cgroup's memory limit (bytes): v2 `memory.max - memory.current`, or v1
/// `memory.limit_in_bytes - memory.usage_in_bytes`; `None` without a limit.
fn cgroup_room() -> Option<u64> {
    let read = |p: &str| -> Option<u64> { std::fs::read_to_string(p).ok()?.trim().parse().ok() };
    let (limit, used) = match read("/sys/fs/cgroup/memory.max") {
        Some(limit) => (limit, read("/sys/fs/cgroup/memory.current").unwrap_or(0)),
        None => (
            read("/sys/fs/cgroup/memory/memory.limit_in_bytes")?,
            read("/sys/fs/cgroup/memory/memory.usage_in_bytes").unwrap_or(0),
        ),
    };
    // cgroup v1 reports "no limit" as a number near 2^63.
    (limit < 1 << 60).then_some(limit.saturating_sub(used))
}

/// `n` bytes for people: `812 B`, `3.4 MB`, `1.2 GB` (SI units).
pub fn bytes(n: u64) -> String {
    let x = n as f64;
    match n {
        0..1_000 => format!("{n} B"),
        1_000..1_000_000 => format!("{:.1} kB", x / 1e3),
        1_000_000..1_000_000_000 => format!("{:.1} MB", x / 1e6),
        1_000_000_000..1_000_000_000_000 => format!("{:.1} GB", x / 1e9),
        _ => format!("{:.1} TB", x / 1e12),
    }
}

/// A count for people: exact up to a million, then `3.65e11`.
pub fn count(n: u64) -> String {
    if n < 1_000_000 {
        n.to_string()
    } else {
        format!("{:.3e}", n as f64)
    }
}

/// Seconds for people: `40 s`, `12 min`, `3.2 h`, `2.1 days`.
pub fn duration(seconds: f64) -> String {
    if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 5400.0 {
        format!("{:.0} min", seconds / 60.0)
    } else if seconds < 172_800.0 {
        format!("{:.1} h", seconds / 3600.0)
    } else {
        format!("{:.1} days", seconds / 86_400.0)
    }
}

impl fmt::Display for WorkEstimate {
    /// `estimated 1.2 GB of memory, 45.0 MB of output, about 40 s`: what the setup line prints
    /// besides the counts it has already.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "estimated {} of memory, {} of output, about {}",
            bytes(self.memory_bytes),
            bytes(self.output_bytes),
            duration(self.seconds)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn family_size_of_a_kuhn_lattice_matches_the_measured_block() {
        // Cubic Kuhn cells of side 1: mean distinct edge (3 + 3 sqrt 2 + sqrt 3) / 7, tets 1/6.
        let shape = MeshShape::of_box([1.0; 3], (8, 6));
        let f = family_size(1.45, shape.mean_edge, shape.mean_volume);
        // BENCHMARKS.md: 13,857,804 bonds on 96,000 particles (144 each) with boundaries; the
        // interior estimate is above it by the boundary's share.
        assert!((150.0..175.0).contains(&f), "{f}");
        // The same from the tets themselves (per-tet edge means weigh edges a little apart).
        let (v, t) = perifrac_topology::primitives::box_data([0.0; 3], [4.0; 3], [4; 3]);
        let s = MeshShape::of_tets(&v, &t);
        assert!((s.mean_volume - 1.0 / 6.0).abs() < 1e-12);
        let g = family_size(1.45, s.mean_edge, s.mean_volume);
        assert!((g / f - 1.0).abs() < 0.1, "{g} vs {f}");
    }

    #[test]
    fn memory_saturates_and_is_refused_past_the_limit() {
        assert_eq!(memory(u64::MAX, 1, 1, 0), u64::MAX);
        let limits = Limits {
            memory_bytes: 1 << 30,
            memory_source: "test".into(),
            max_steps: 10,
            max_output_bytes: 1_000,
            max_seconds: 60.0,
            threads: 1,
            allow_large: false,
        };
        // cells = [271, 271, 271] of issue 17: 119 million tets.
        let counts = perifrac_topology::primitives::box_counts([271; 3]).unwrap();
        let e = WorkEstimate::of_mesh(MeshShape::of_box([0.01; 3], counts), 1.45, 0);
        let msg = limits.check_memory(&e).unwrap_err();
        assert!(
            msg.contains(&format!("{} particles", 6 * 271 * 271 * 271)),
            "{msg}"
        );
        assert!(msg.contains("1.1 GB available (test)"), "{msg}");
        assert!(limits
            .check_steps(11, "x")
            .unwrap_err()
            .contains("11 steps (x)"));
        assert!(limits.check_steps(10, "x").is_ok());
        assert!(limits.check_output(1_001, "y").is_err());
        assert!(limits
            .check_time(61.0, "z")
            .unwrap_err()
            .contains("61 s (z)"));
        let allowed = Limits {
            allow_large: true,
            ..limits
        };
        assert!(allowed.check_memory(&e).is_ok() && allowed.check_steps(u64::MAX, "").is_ok());
    }

    #[test]
    fn meminfo_is_read_in_kilobytes() {
        let text = "MemTotal:       16318976 kB\nMemAvailable:    8000000 kB\n";
        assert_eq!(mem_available(text), Some(8_192_000_000));
        assert_eq!(mem_available("MemTotal: 1 kB\n"), None);
        let (bytes, source) = available_memory();
        assert!(bytes > 0 && !source.is_empty());
    }

    #[test]
    fn people_read_the_numbers() {
        assert_eq!(bytes(812), "812 B");
        assert_eq!(bytes(3_400_000), "3.4 MB");
        assert_eq!(count(365_000_000_000), "3.650e11");
        assert_eq!(duration(40.0), "40 s");
        assert_eq!(duration(200_000.0), "2.3 days");
        // 1,800 steps over 1.16 million bonds on two threads: the default scene's half minute.
        let s = run_seconds(1_800, 1_160_000, 2, false);
        assert!((10.0..120.0).contains(&s), "{s}");
    }
}
