//! The run directory: `run.json` (written first, before anything else, then rewritten
//! atomically after every frame and when the run stops, see [`RunManifest`]), `scene.toml` (the
//! scene as run) and `frames/` with `surface_NNNN.ply` (binary PLY: vertices split where
//! the surface shades sharp, along crack edges and corners, with normals `nx ny nz`, velocities
//! `vx vy vz` (m/s), texture coordinates `s t` and the `vertex_id` of the surface vertex they
//! copy, so that welding by it gives every piece's closed 2-manifold surface; faces with
//! their `crack` flag and stable `fragment` id, see [`crate::fragments`]), optionally
//! `surface_NNNN.inc` (POV-Ray `mesh2` with normals, declaring [`POVRAY_MESH_NAME`]) and
//! `particles_NNNN.ply` (points with `damage`, `mass` and `fragment`) and `debris_NNNN.ply`
//! (pieces of at most `[output] debris_tets` tets, left out of the surface: points at their
//! centres of mass with `radius`, velocity `vx vy vz`, `mass` and `fragment`, see
//! [`crate::debris`]). Every file is written to a temporary name and renamed into place, so a
//! reader never sees half a frame.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use perifrac_io::{write_ply, write_ply_points, write_povray_mesh2, PlyEncoding, SurfaceRef};
use perifrac_topology::Surface;
use serde::{Deserialize, Serialize};

use crate::debris::{split_debris, Debris};
use crate::driver::Driver;
use crate::error::SceneError;
use crate::fragments::FragmentBirth;
use crate::setup::{bounds, OutputOptions, Setup};

/// The identifier of the run-directory layout, written into `run.json`.
pub const RUN_FORMAT: &str = "perifrac-run/1";

/// Share of the total mass that [`FrameJson::main_bounds`] frames: the heaviest fragments that
/// together make up this much, so that a cloud of small debris does not shrink the picture.
pub const MAIN_MASS_SHARE: f64 = 0.9;

/// The identifier the `mesh2` of a frame's POV-Ray include is declared as.
pub const POVRAY_MESH_NAME: &str = "surface";

/// `run.json`: what the run wrote, for `perifrac render` and other readers. It holds no wall
/// times, so two runs of one scene give identical files.
#[derive(Debug, Clone, Serialize)]
pub struct RunManifest {
    /// [`RUN_FORMAT`].
    pub format: String,
    /// File name of the scene.
    pub scene: String,
    /// World up (unit vector).
    pub up: [f64; 3],
    /// Rest bounding box of the mesh (m).
    pub rest_bounds: Bounds,
    /// Ground planes.
    pub grounds: Vec<GroundJson>,
    /// Particles.
    pub particles: usize,
    /// Directed bonds at the start.
    pub bonds: usize,
    /// Horizon (m).
    pub horizon: f64,
    /// Time step (s).
    pub dt: f64,
    /// Estimated stable limit (s).
    pub dt_limit: f64,
    /// Total particle mass (kg).
    pub mass: f64,
    /// Playback frames per second for caches made from the frames (`[output] fps`).
    pub fps: f64,
    /// Frames written so far.
    pub frames: Vec<FrameJson>,
    /// Every fragment so far, in id order, with the fragment it split from and the first frame
    /// it appears in; the `fragment` ids of the frames' faces and particles are these.
    pub fragments: Vec<FragmentBirth>,
    /// True once the last frame is written.
    pub finished: bool,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
    /// The model and integrator, when not the default Chen model stepped explicitly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverJson>,
    /// How far Chen's constants stray from MODEL.md's (absent for Xu's model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub correction: Option<CorrectionJson>,
}

/// The spread of correction factors in `run.json` (1: MODEL.md's constant).
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
    /// Dilatation weights over MODEL.md's: each particle's of largest magnitude.
    pub dilatation: SpreadJson,
    /// `b_i` over MODEL.md's, per particle.
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

/// A box (m).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct Bounds {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// A ground plane in `run.json`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct GroundJson {
    /// A point on it (m).
    pub point: [f64; 3],
    /// Outward unit normal.
    pub normal: [f64; 3],
}

/// A ball at a frame.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct BallJson {
    /// Centre (m).
    pub center: [f64; 3],
    /// Radius (m).
    pub radius: f64,
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
    /// Particle PLY, when written.
    pub particles: Option<String>,
    /// Debris points, when the scene writes small pieces as debris.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub debris: Option<DebrisJson>,
    /// Balls at this time.
    pub balls: Vec<BallJson>,
    /// Bounds of the whole surface and the debris balls (m).
    pub bounds: Bounds,
    /// Bounds of the heaviest fragments making up [`MAIN_MASS_SHARE`] of the mass (m).
    pub main_bounds: Bounds,
    /// Connected pieces.
    pub fragments: usize,
    /// Bonds broken so far.
    pub broken_bonds: u64,
    /// Crack triangles in the surface (both sides counted).
    pub crack_triangles: usize,
    /// Particle kinetic energy (J).
    pub kinetic_energy: f64,
    /// Elastic energy (J).
    pub elastic_energy: f64,
    /// Implicit runs: iterations so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub implicit: Option<IterationsJson>,
    /// Runs with the event search: sub-steps so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search: Option<SearchJson>,
    /// Runs with self contact: pairs in contact in the frame's last step, and the deepest
    /// overlap so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_contact: Option<SelfContactJson>,
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

/// Refuses a non-empty `dir` unless `force`; reads only, so it can run before the setup.
pub fn check_output_dir(dir: &Path, force: bool) -> Result<(), SceneError> {
    let err = |message: String| SceneError::Output {
        dir: dir.to_path_buf(),
        message,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(err("exists and is not a directory".into()));
    }
    if dir.is_dir() && !force {
        let mut entries = std::fs::read_dir(dir).map_err(|e| err(e.to_string()))?;
        if entries.next().is_some() {
            return Err(err(
                "is not empty; choose another directory or pass --force to overwrite".into(),
            ));
        }
    }
    Ok(())
}

/// Writes frames and `run.json` into a run directory.
pub struct FrameWriter {
    dir: PathBuf,
    frames_dir: PathBuf,
    options: OutputOptions,
    manifest: RunManifest,
}

impl FrameWriter {
    /// Prepares `dir`: removes what an earlier run left there (`run.json`, `scene.toml`,
    /// `checkpoint.bin`, `frames/`, `render/`, the USD cache named after its scene) and
    /// nothing else, writes the initial `run.json` (no frames, not
    /// finished), then `scene.toml` and `frames/`; a failure after `run.json` is recorded in
    /// it.
    pub fn create(dir: &Path, setup: &Setup) -> Result<FrameWriter, SceneError> {
        clear_output_dir(dir)?;
        FrameWriter::start(dir, setup, Vec::new())
    }

    /// Takes over `dir` for a resumed run: `run.json` holds the frames `recorded` before the
    /// checkpoint (later ones, written after it, are dropped and written again), and
    /// `scene.toml` and `frames/` are written as by [`FrameWriter::create`]; nothing else is
    /// removed.
    pub fn resume(
        dir: &Path,
        setup: &Setup,
        recorded: Vec<FrameJson>,
    ) -> Result<FrameWriter, SceneError> {
        FrameWriter::start(dir, setup, recorded)
    }

    fn start(
        dir: &Path,
        setup: &Setup,
        recorded: Vec<FrameJson>,
    ) -> Result<FrameWriter, SceneError> {
        let Setup {
            scene_path,
            scene_text,
            driver,
            output: options,
            info,
            ..
        } = setup;
        let options = *options;
        let manifest = RunManifest {
            format: RUN_FORMAT.into(),
            scene: scene_path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            up: info.up,
            rest_bounds: Bounds {
                min: info.rest_bounds.0,
                max: info.rest_bounds.1,
            },
            grounds: driver
                .colliders()
                .map(|c| {
                    c.grounds()
                        .map(|g| GroundJson {
                            point: g.point,
                            normal: g.normal,
                        })
                        .collect()
                })
                .unwrap_or_default(),
            particles: info.particles,
            bonds: info.bonds,
            horizon: info.horizon,
            dt: info.dt,
            dt_limit: info.dt_limit,
            mass: info.mass,
            fps: options.fps,
            frames: recorded,
            fragments: driver.fragment_births().to_vec(),
            finished: false,
            error: None,
            solver: (info.model != "chen" || info.integrator != "explicit").then(|| SolverJson {
                model: info.model.into(),
                integrator: info.integrator.into(),
            }),
            correction: info.correction.map(|c| CorrectionJson {
                dilatation: c.dilatation.into(),
                deviatoric: c.deviatoric.into(),
                ghosts: info.ghosts.as_ref().map(|g| GhostsJson {
                    count: g.ghosts,
                    bonds: g.bonds,
                    affine_fallbacks: g.affine_fallbacks,
                    short_bonds: g.short,
                    gain: g.gain.into(),
                }),
            }),
        };
        let mut writer = FrameWriter {
            dir: dir.to_path_buf(),
            frames_dir: dir.join("frames"),
            options,
            manifest,
        };
        // run.json first: whatever fails after it is recorded in it.
        writer.write_manifest()?;
        let rest = write_scene_and_frames_dir(dir, scene_text);
        if let Err(e) = rest {
            // Best effort: the error itself is what the caller reports.
            let _ = writer.record_error(e.to_string());
            return Err(e);
        }
        Ok(writer)
    }

    /// Writes frame `index` from the driver's current state and records it in `run.json`
    /// (`last` marks the run finished). Returns what was recorded.
    pub fn write_frame(
        &mut self,
        index: usize,
        driver: &mut Driver,
        last: bool,
    ) -> Result<&FrameJson, SceneError> {
        let started = Instant::now();
        let pieces = driver.mesh().pieces();
        driver.place_surface(&pieces);
        let ids = driver.fragment_ids(&pieces, index);
        let mesh = driver.mesh();
        let mut surface = mesh.surface_of(&pieces);
        let debris = if self.options.debris_tets > 0 {
            let volumes = mesh.rest_volumes();
            let solver = driver.solver();
            let (keep, debris) = split_debris(
                &pieces,
                self.options.debris_tets,
                &ids,
                driver.masses(),
                solver.positions(),
                solver.velocities(),
                &volumes,
            );
            surface.retain_pieces(&keep);
            Some(debris)
        } else {
            None
        };
        if let Some(smoothing) = &self.options.smooth_cracks {
            surface.smooth_cracks(smoothing);
        }
        let velocities = mesh.vertex_velocities(driver.masses(), driver.solver().velocities());
        let shaded = mesh.shade(&surface, &velocities, &mesh.shading_options());
        // The surface vertex each shading copy belongs to: welding by it gives every piece's
        // closed 2-manifold surface.
        let vertex_ids = &shaded.source;
        let face_fragment: Vec<u32> = shaded.piece.iter().map(|&p| ids[p as usize]).collect();
        let name = format!("surface_{index:04}");
        let view = SurfaceRef {
            vertices: &shaded.vertices,
            faces: &shaded.faces,
            crack: Some(&shaded.crack),
            normals: Some(&shaded.normals),
            velocities: Some(&shaded.velocities),
            uv: Some(&shaded.uv),
            vertex_ids: Some(vertex_ids),
            fragment: Some(&face_fragment),
            colors: None,
        };
        write_ply(
            &self.frames_dir.join(format!("{name}.ply")),
            &view,
            PlyEncoding::BinaryLittleEndian,
        )?;
        let povray = if self.options.povray {
            let path = self.frames_dir.join(format!("{name}.inc"));
            write_povray_mesh2(&path, &view, POVRAY_MESH_NAME)?;
            Some(format!("frames/{name}.inc"))
        } else {
            None
        };
        let particles = if self.options.particles {
            let path = format!("frames/particles_{index:04}.ply");
            let damage = driver.damage();
            let fragment: Vec<f64> = pieces
                .piece_of_tet
                .iter()
                .map(|&p| f64::from(ids[p as usize]))
                .collect();
            write_ply_points(
                &self.dir.join(&path),
                driver.solver().positions(),
                &[
                    ("damage", &damage),
                    ("mass", driver.masses()),
                    ("fragment", &fragment),
                ],
            )?;
            Some(path)
        } else {
            None
        };
        let (mut lo, mut hi) = bounds(&surface.vertices);
        if let Some(d) = &debris {
            for (p, r) in d.points.iter().zip(&d.radius) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k] - r);
                    hi[k] = hi[k].max(p[k] + r);
                }
            }
        }
        let debris = match &debris {
            Some(d) => {
                let path = format!("frames/debris_{index:04}.ply");
                write_debris(&self.dir.join(&path), d)?;
                Some(DebrisJson {
                    path,
                    pieces: d.points.len(),
                })
            }
            None => None,
        };
        let piece_mass = piece_masses(&pieces.piece_of_tet, pieces.count, driver.masses());
        let frame = FrameJson {
            index,
            time: driver.solver().time(),
            step: driver.solver().steps(),
            surface: format!("frames/{name}.ply"),
            povray,
            particles,
            debris,
            balls: driver
                .colliders()
                .map(|c| {
                    c.balls()
                        .map(|b| BallJson {
                            center: b.center,
                            radius: b.radius,
                        })
                        .collect()
                })
                .unwrap_or_default(),
            bounds: Bounds { min: lo, max: hi },
            main_bounds: main_bounds(&surface, &piece_mass),
            fragments: pieces.count,
            broken_bonds: driver.broken_bonds(),
            crack_triangles: surface.crack.iter().filter(|&&c| c != 0).count(),
            kinetic_energy: driver.solver().kinetic_energy(),
            elastic_energy: driver.solver_mut().elastic_energy(),
            implicit: (driver.solver().integrator_name() == "implicit").then(|| {
                let s = driver.solver().stats();
                IterationsJson {
                    iterations: s.iterations,
                    capped_steps: s.capped_steps,
                    evaluations: s.evaluations,
                    factorizations: s.factorizations,
                    factor_bytes: s.factor_bytes,
                }
            }),
            search: (driver.solver().integrator_name() == "event_search").then(|| {
                let s = driver.solver().stats();
                SearchJson {
                    substeps: s.substeps,
                    rejected: s.rejected,
                }
            }),
            self_contact: driver.self_contact().map(|_| {
                let deepest = driver.self_contact_deepest();
                SelfContactJson {
                    pairs: driver.self_contact_last().pairs,
                    deepest: deepest.max_overlap,
                    deepest_share: deepest.max_overlap_share,
                }
            }),
        };
        self.manifest.frames.push(frame);
        self.manifest.fragments = driver.fragment_births().to_vec();
        self.manifest.finished = last;
        self.write_manifest()?;
        driver.add_output_time(started.elapsed());
        Ok(self
            .manifest
            .frames
            .last()
            .expect("a frame was just pushed"))
    }

    /// Records why the run stopped in `run.json` (and that it did not finish); the frames
    /// written stay. When the atomic rewrite fails (on a full disk it needs room for a second
    /// copy), `run.json` is overwritten in place, which needs little more room than it had; the
    /// first error is returned when that fails too.
    pub fn record_error(&mut self, message: String) -> Result<(), SceneError> {
        self.manifest.error = Some(message);
        self.manifest.finished = false;
        match self.write_manifest() {
            Ok(()) => Ok(()),
            Err(first) => {
                let text = self.manifest_text()?;
                std::fs::write(self.dir.join("run.json"), text).map_err(|_| first)
            }
        }
    }

    /// Frames written so far, the initial one included.
    pub fn frames_written(&self) -> usize {
        self.manifest.frames.len()
    }

    /// What `run.json` holds now.
    pub fn manifest(&self) -> &RunManifest {
        &self.manifest
    }

    /// `run.json`'s text, with its final newline.
    fn manifest_text(&self) -> Result<String, SceneError> {
        let mut text =
            serde_json::to_string_pretty(&self.manifest).map_err(|e| SceneError::Output {
                dir: self.dir.clone(),
                message: format!("cannot encode run.json: {e}"),
            })?;
        text.push('\n');
        Ok(text)
    }

    fn write_manifest(&self) -> Result<(), SceneError> {
        let text = self.manifest_text()?;
        perifrac_io::atomic_write(&self.dir.join("run.json"), |w| w.write_all(text.as_bytes()))?;
        Ok(())
    }
}

/// Writes `scene.toml` (the scene as run) into the run directory `dir` and creates `frames/`.
pub(crate) fn write_scene_and_frames_dir(dir: &Path, scene_text: &str) -> Result<(), SceneError> {
    perifrac_io::atomic_write(&dir.join("scene.toml"), |w| {
        w.write_all(scene_text.as_bytes())
    })?;
    std::fs::create_dir_all(dir.join("frames")).map_err(|e| SceneError::Output {
        dir: dir.to_path_buf(),
        message: format!("cannot create frames/: {e}"),
    })
}

/// Removes an earlier run's files from `dir` (and nothing else), creating `dir` if needed.
pub(crate) fn clear_output_dir(dir: &Path) -> Result<(), SceneError> {
    let err = |message: String| SceneError::Output {
        dir: dir.to_path_buf(),
        message,
    };
    for name in ["frames", "render"] {
        let p = dir.join(name);
        if p.is_dir() {
            std::fs::remove_dir_all(&p).map_err(|e| err(format!("cannot clear {name}/: {e}")))?;
        }
    }
    // The USD cache an earlier run wrote under its scene's name (`[output] usd`).
    if let Ok(text) = std::fs::read_to_string(dir.join("run.json")) {
        let scene = serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|m| m["scene"].as_str().map(str::to_owned));
        if let Some(stem) = scene.as_deref().and_then(|s| Path::new(s).file_stem()) {
            let p = dir.join(format!("{}.usda", stem.to_string_lossy()));
            if p.is_file() {
                std::fs::remove_file(&p)
                    .map_err(|e| err(format!("cannot remove {}: {e}", p.display())))?;
            }
        }
    }
    for name in ["run.json", "scene.toml", crate::checkpoint::CHECKPOINT_FILE] {
        let p = dir.join(name);
        if p.is_file() {
            std::fs::remove_file(&p).map_err(|e| err(format!("cannot remove {name}: {e}")))?;
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| err(format!("cannot create: {e}")))?;
    Ok(())
}

/// Writes `debris` as a PLY point cloud: `x y z` (m), `radius` (m), `vx vy vz` (m/s), `mass`
/// (kg), `fragment`.
fn write_debris(path: &Path, debris: &Debris) -> Result<(), SceneError> {
    let velocity = |d: usize| -> Vec<f64> { debris.velocity.iter().map(|v| v[d]).collect() };
    let fragment: Vec<f64> = debris.fragment.iter().map(|&f| f64::from(f)).collect();
    write_ply_points(
        path,
        &debris.points,
        &[
            ("radius", &debris.radius),
            ("vx", &velocity(0)),
            ("vy", &velocity(1)),
            ("vz", &velocity(2)),
            ("mass", &debris.mass),
            ("fragment", &fragment),
        ],
    )?;
    Ok(())
}

/// Mass (kg) of each of `count` pieces.
fn piece_masses(piece_of_tet: &[u32], count: usize, masses: &[f64]) -> Vec<f64> {
    let mut m = vec![0.0; count];
    for (&p, &mass) in piece_of_tet.iter().zip(masses) {
        m[p as usize] += mass;
    }
    m
}

/// Bounds of the surface faces of the heaviest pieces that together reach
/// [`MAIN_MASS_SHARE`] of the total mass (ties broken by piece id, so it is deterministic).
fn main_bounds(surface: &Surface, piece_mass: &[f64]) -> Bounds {
    let total: f64 = piece_mass.iter().sum();
    let mut order: Vec<usize> = (0..piece_mass.len()).collect();
    order.sort_by(|&a, &b| piece_mass[b].total_cmp(&piece_mass[a]).then(a.cmp(&b)));
    let mut keep = vec![false; piece_mass.len()];
    let mut sum = 0.0;
    for p in order {
        keep[p] = true;
        sum += piece_mass[p];
        if sum >= MAIN_MASS_SHARE * total {
            break;
        }
    }
    let empty = Bounds {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };
    surface
        .faces
        .iter()
        .zip(&surface.piece)
        .filter(|(_, &p)| keep[p as usize])
        .flat_map(|(face, _)| face.map(|v| surface.vertices[v as usize]))
        .fold(empty, |b, p| Bounds {
            min: std::array::from_fn(|k| b.min[k].min(p[k])),
            max: std::array::from_fn(|k| b.max[k].max(p[k])),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn main_bounds_skip_light_debris() {
        // Piece 0 (heavy) spans the unit cube; piece 1 (1% of the mass) sits far away.
        let surface = Surface {
            vertices: vec![
                [0.0; 3],
                [1.0, 1.0, 1.0],
                [0.0, 1.0, 0.0],
                [9.0; 3],
                [9.5; 3],
                [9.0, 9.5, 9.0],
            ],
            vertex_ids: (0..6).collect(),
            faces: vec![[0, 1, 2], [3, 4, 5]],
            crack: vec![0, 1],
            piece: vec![0, 1],
            midpoints: Vec::new(),
        };
        let b = main_bounds(&surface, &[99.0, 1.0]);
        assert_eq!(
            b,
            Bounds {
                min: [0.0; 3],
                max: [1.0; 3]
            }
        );
        // With two equal pieces both are needed to reach 90%.
        let b = main_bounds(&surface, &[1.0, 1.0]);
        assert_eq!(b.max, [9.5; 3]);
    }
}
