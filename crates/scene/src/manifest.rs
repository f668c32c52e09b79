//! `run.json`: what a run wrote, for `perifrac render`, `perifrac export` and other readers. One
//! schema for every body: the fields all runs share, a body section (`body` names it:
//! `"solid"` for tet solids, `"shell"` for thin shells) and, per frame, the shared frame fields
//! with the body's own counts. It holds no wall times, so two runs of one scene give identical
//! files.

use serde::{Deserialize, Serialize};

use crate::fragments::FragmentBirth;

/// The identifier of the run-directory layout, written into `run.json`.
pub const RUN_FORMAT: &str = "perifrac-run/1";

/// `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunManifest {
    /// [`RUN_FORMAT`].
    pub format: String,
    /// File name of the scene.
    pub scene: String,
    /// World up (unit vector).
    pub up: [f64; 3],
    /// Rest bounding box of the body (m).
    pub rest_bounds: Bounds,
    /// Ground planes.
    pub grounds: Vec<GroundJson>,
    /// What the body is, with its own facts.
    #[serde(flatten)]
    pub body: BodyJson,
    /// Time step (s).
    pub dt: f64,
    /// Estimated stable limit of explicit steps (s).
    pub dt_limit: f64,
    /// Total mass (kg).
    pub mass: f64,
    /// Playback frames per second for caches made from the frames (`[output] fps`).
    pub fps: f64,
    /// Frames written so far.
    pub frames: Vec<FrameJson>,
    /// Every fragment so far, in id order, with the fragment it split from and the first frame
    /// it appears in; the `fragment` ids of the frames' faces and points are these.
    pub fragments: Vec<FragmentBirth>,
    /// True once the last frame is written.
    pub finished: bool,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
}

/// The body section of `run.json`, tagged by `body`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "body", rename_all = "snake_case")]
pub enum BodyJson {
    /// A tet solid of peridynamic particles.
    Solid(SolidJson),
    /// A thin shell on a triangle mesh.
    Shell(ShellJson),
}

/// A tet solid's facts in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SolidJson {
    /// Particles.
    pub particles: usize,
    /// Directed bonds at the start.
    pub bonds: usize,
    /// Horizon (m).
    pub horizon: f64,
    /// The model and integrator, when not the default Chen model stepped explicitly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverJson>,
    /// How far the model's constants stray from docs/model.md's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub correction: Option<CorrectionJson>,
    /// The thresholds a material's `fracture_energy` set.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub from_energy: Vec<FromEnergyJson>,
}

/// A threshold set from a fracture energy, in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct FromEnergyJson {
    /// The material's index.
    pub material: usize,
    /// Its fracture energy `G_c` (J/m^2).
    pub fracture_energy: f64,
    /// The bond threshold it gives on the run's families (1).
    pub s_crit: f64,
}

/// A thin shell's facts in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ShellJson {
    /// Vertices at the start.
    pub vertices: usize,
    /// Triangles at the start.
    pub triangles: usize,
    /// Rest thickness (m).
    pub thickness: f64,
    /// Thickness given to every piece in the frames (m; 0: the mid-surface).
    pub frame_thickness: f64,
    /// The event search's finest level (0: none).
    pub event_levels: u32,
    /// `"explicit"` or `"newmark"`.
    pub integrator: String,
}

/// One frame in `run.json`; paths are relative to the run directory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameJson {
    /// 0 is the rest state.
    pub index: usize,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken up to this frame.
    pub step: u64,
    /// Surface PLY.
    pub surface: String,
    /// POV-Ray include, when written.
    pub povray: Option<String>,
    /// Balls at this time.
    pub balls: Vec<BallJson>,
    /// Bounds of the whole surface and any debris balls (m).
    pub bounds: Bounds,
    /// Bounds of the heaviest fragments making up [`MAIN_MASS_SHARE`] of the mass (m).
    pub main_bounds: Bounds,
    /// Connected pieces.
    pub fragments: usize,
    /// Kinetic energy (J).
    pub kinetic_energy: f64,
    /// Elastic energy (J).
    pub elastic_energy: f64,
    /// Runs with the event search: sub-steps so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search: Option<SearchJson>,
    /// The body's own counts.
    #[serde(flatten)]
    pub body: FrameBodyJson,
}

/// A frame's counts that depend on the body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
pub enum FrameBodyJson {
    /// A tet solid's.
    Solid(SolidFrameJson),
    /// A thin shell's.
    Shell(ShellFrameJson),
}

/// A tet solid's frame counts in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SolidFrameJson {
    /// Particle PLY, when written.
    pub particles: Option<String>,
    /// Debris points, when the scene writes small pieces as debris.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub debris: Option<DebrisJson>,
    /// Bonds broken so far.
    pub broken_bonds: u64,
    /// Crack triangles in the surface (both sides counted).
    pub crack_triangles: usize,
    /// Implicit runs: iterations so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub implicit: Option<IterationsJson>,
    /// Runs with self contact: pairs in contact in the frame's last step, and the deepest
    /// overlap so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_contact: Option<SelfContactJson>,
    /// Runs with `[[load]]` tables: the work they have done so far (J).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_work: Option<f64>,
    /// Runs that can break: per material, the largest share of its fracture threshold a bond
    /// has reached so far (1; 1 or more once one broke), null for a material that cannot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_threshold_share: Option<Vec<Option<f64>>>,
}

/// A thin shell's frame counts in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShellFrameJson {
    /// Triangles broken so far.
    pub broken_triangles: usize,
    /// Crack edges in the mesh.
    pub crack_edges: usize,
    /// Triangles of the mesh now.
    pub mesh_triangles: usize,
    /// Vertices of the mesh now.
    pub mesh_vertices: usize,
    /// Triangles that have yielded.
    pub yielded: usize,
    /// Runs stepped by Newmark: what the implicit solves did so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub newmark: Option<NewmarkJson>,
    /// Runs with `[[load]]` tables: the work they have done so far (J).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_work: Option<f64>,
}

/// Share of the total mass that [`FrameJson::main_bounds`] frames: the heaviest fragments that
/// together make up this much, so that a cloud of small debris does not shrink the picture.
pub const MAIN_MASS_SHARE: f64 = 0.9;

/// The spread of correction factors in `run.json` (1: docs/model.md's constant).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct SpreadJson {
    /// Smallest factor (a fitted dilatation weight can be negative).
    pub min: f64,
    /// Median.
    pub median: f64,
    /// 99th percentile of the magnitudes.
    pub p99: f64,
    /// Largest magnitude.
    pub max: f64,
}

impl From<perifrac_physics::Spread> for SpreadJson {
    fn from(s: perifrac_physics::Spread) -> Self {
        SpreadJson {
            min: s.min,
            median: s.median,
            p99: s.p99,
            max: s.max,
        }
    }
}

/// The correction factors in `run.json`, per particle: the largest on its dilatation
/// weights, and Chen's on `b` (Xu's fitted dilatation: its factors over the normalised weights,
/// and 1 for the bond term, whose weights stay normalised).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct CorrectionJson {
    /// Dilatation weights over docs/model.md's: each particle's of largest magnitude.
    pub dilatation: SpreadJson,
    /// `b_i` over docs/model.md's, per particle.
    pub deviatoric: SpreadJson,
    /// The ghost particles completing the families (`correction = "ghosts"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ghosts: Option<GhostsJson>,
}

/// The ghost particles of a run, in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct GhostsJson {
    /// Ghosts kept.
    pub count: usize,
    /// Directed bonds between real particles and ghosts.
    #[serde(default)]
    pub bonds: usize,
    /// Ghosts whose quadratic fit fell back to the affine one (past the gain bound).
    #[serde(default)]
    pub affine_fallbacks: usize,
    /// Bonds left out because the ghost lay closer to the real particle than half its shortest
    /// real bond.
    #[serde(default)]
    pub short_bonds: usize,
    /// Each ghost's gain: the sum of its combination's coefficients' magnitudes (1: a copy of
    /// its source).
    pub gain: SpreadJson,
}

/// Which solver ran, in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SolverJson {
    /// `"chen"` or `"xu"`.
    pub model: String,
    /// `"explicit"` or `"implicit"`.
    pub integrator: String,
}

/// An implicit run's iteration counts up to a frame, in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct IterationsJson {
    /// Quasi-Newton iterations over all steps so far.
    pub iterations: u64,
    /// Steps that reached the iteration cap.
    pub capped_steps: u64,
    /// Evaluations of the objective, line-search trials included.
    pub evaluations: u64,
    /// Factorisations of the step matrix, the first included.
    pub factorizations: u64,
    /// Heap bytes of the factor.
    pub factor_bytes: usize,
}

/// The implicit Newmark solves of a shell run so far, in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct NewmarkJson {
    /// Solves (discarded trials of the search included).
    pub solves: u64,
    /// L-BFGS iterations over all solves.
    pub iterations: u64,
    /// Solves that stopped at the iteration cap.
    pub capped: u64,
    /// Factorisations of the step matrix.
    pub factorizations: u64,
}

/// A box (m).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct Bounds {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

impl Bounds {
    /// The bounds of `(min, max)` corners.
    pub fn of(corners: ([f64; 3], [f64; 3])) -> Bounds {
        Bounds {
            min: corners.0,
            max: corners.1,
        }
    }
}

/// A ground plane in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct GroundJson {
    /// A point on it (m).
    pub point: [f64; 3],
    /// Outward unit normal.
    pub normal: [f64; 3],
}

/// A ball at a frame.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct BallJson {
    /// Centre (m).
    pub center: [f64; 3],
    /// Radius (m).
    pub radius: f64,
}

/// A frame's debris in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct DebrisJson {
    /// The debris PLY, relative to the run directory.
    pub path: String,
    /// Pieces written as debris points (left out of the surface).
    pub pieces: usize,
}

/// Contact between particles up to a frame, in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct SelfContactJson {
    /// Pairs in contact in the last step before the frame.
    pub pairs: usize,
    /// Deepest overlap so far (m): a pair's contact distance minus its distance.
    pub deepest: f64,
    /// The deepest overlap so far as a share of its pair's contact distance.
    pub deepest_share: f64,
}

/// An event-search run's sub-steps up to a frame, in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct SearchJson {
    /// Accepted sub-steps over all steps so far.
    pub substeps: u64,
    /// Trial sub-steps rejected and undone.
    pub rejected: u64,
}

/// The ground planes of `colliders` in `run.json`'s shape (none without colliders).
pub(crate) fn grounds_json(colliders: Option<&perifrac_contact::Colliders>) -> Vec<GroundJson> {
    colliders.map_or_else(Vec::new, |c| {
        c.grounds()
            .map(|g| GroundJson {
                point: g.point,
                normal: g.normal,
            })
            .collect()
    })
}

/// The balls of `colliders` where they are now, in `run.json`'s shape.
pub(crate) fn balls_json(colliders: Option<&perifrac_contact::Colliders>) -> Vec<BallJson> {
    colliders.map_or_else(Vec::new, |c| {
        c.balls()
            .map(|b| BallJson {
                center: b.center,
                radius: b.radius,
            })
            .collect()
    })
}
