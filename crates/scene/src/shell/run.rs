//! Running a thin-shell scene: steps between frames, frames into a run directory laid out as a
//! tet run's (`run.json`, `scene.toml`, `frames/surface_NNNN.ply` with per-vertex normals and
//! velocities, per-face `crack` and stable `fragment` ids, `frames/surface_NNNN.inc`), so
//! `perifrac render` and `perifrac export` read it as they read a tet run's. Every file is
//! written to a temporary name and renamed into place.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use perifrac_io::{write_ply, write_povray_mesh2, PlyEncoding, SurfaceRef};
use perifrac_physics::math::{cross, norm, sub};
use perifrac_shell::output::pieces;
use serde::{Deserialize, Serialize};

use perifrac_checkpoint::{CheckpointError, Reader};

use crate::checkpoint::{Checkpoint, Position, RunIdentity, CHECKPOINT_FILE};
use crate::error::SceneError;
use crate::fragments::{FragmentBirth, FragmentIds};
use crate::output::{
    clear_output_dir, write_scene_and_frames_dir, BallJson, Bounds, GroundJson, SearchJson,
    POVRAY_MESH_NAME, RUN_FORMAT,
};
use crate::run::{Observer, Progress};
use crate::setup::math::bounds;

use super::setup::ShellSetup;

/// `run.json` of a shell run: the fields `perifrac render` reads from a tet run's
/// ([`crate::RunManifest`]), with the shell's own counts. It holds no wall times, so two runs
/// of one scene give identical files.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShellManifest {
    /// [`RUN_FORMAT`].
    pub format: String,
    /// `"shell"`: what the run simulated.
    pub body: String,
    /// File name of the scene.
    pub scene: String,
    /// World up (unit vector).
    pub up: [f64; 3],
    /// Rest bounding box of the surface (m).
    pub rest_bounds: Bounds,
    /// Ground planes.
    pub grounds: Vec<GroundJson>,
    /// Vertices at the start.
    pub vertices: usize,
    /// Triangles at the start.
    pub triangles: usize,
    /// Rest thickness (m).
    pub thickness: f64,
    /// Thickness given to every piece in the frames (m; 0: the mid-surface).
    pub frame_thickness: f64,
    /// Playback frames per second for caches made from the frames (`[output] fps`).
    pub fps: f64,
    /// Time step (s).
    pub dt: f64,
    /// Measured stable limit (s).
    pub dt_limit: f64,
    /// The event search's finest level (0: none).
    pub event_levels: u32,
    /// `"explicit"` or `"newmark"`.
    pub integrator: String,
    /// Total mass (kg).
    pub mass: f64,
    /// Frames written so far.
    pub frames: Vec<ShellFrameJson>,
    /// Every fragment id the frames used, with the fragment it split from and its first frame
    /// (a piece keeps its id from the frame it separates until the frame it splits).
    pub fragments: Vec<FragmentBirth>,
    /// True once the last frame is written.
    pub finished: bool,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
}

/// One frame of a shell run in `run.json`; paths relative to the run directory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShellFrameJson {
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
    /// Bounds of the surface (m).
    pub bounds: Bounds,
    /// Bounds of the largest pieces by area that together hold
    /// [`crate::output::MAIN_MASS_SHARE`] of the area (m): flying chips do not shrink the picture.
    pub main_bounds: Bounds,
    /// Connected pieces.
    pub fragments: usize,
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
    /// Kinetic energy (J).
    pub kinetic_energy: f64,
    /// Elastic energy (J).
    pub elastic_energy: f64,
    /// Runs with the event search: sub-steps so far.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search: Option<SearchJson>,
    /// Runs stepped by Newmark: what the implicit solves did so far.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub newmark: Option<NewmarkJson>,
}

/// The implicit Newmark solves of a shell run so far, in `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
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

/// The end of a shell run.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellSummary {
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub time: f64,
    /// The step (s).
    pub dt: f64,
    /// Triangles broken.
    pub broken_triangles: usize,
    /// Pieces at the end.
    pub fragments: usize,
    /// Triangles at the end (splits add them).
    pub triangles: usize,
    /// Triangles that have yielded, at the end.
    pub yielded: usize,
    /// Sub-steps taken (the steps, or more where steps were cut or searched).
    pub substeps: u64,
    /// Trial sub-steps discarded.
    pub rejected: u64,
    /// Kinetic energy at the end (J).
    pub kinetic_energy: f64,
    /// Elastic energy at the end (J).
    pub elastic_energy: f64,
    /// Frames written, the initial one included.
    pub frames_written: usize,
    /// Wall time stepping.
    pub physics_time: Duration,
    /// Wall time writing frames.
    pub output_time: Duration,
    /// Triangle force updates: every sub-step and discarded trial times the triangles then,
    /// made by this process (a resumed run's earlier ones are left out, as its earlier wall
    /// time is), so that over `physics_time` they give its rate.
    pub triangle_updates: u64,
    /// Self contact, when on: wall time (s, discarded trials included) and candidate-list
    /// builds.
    pub self_contact: Option<(f64, u64)>,
    /// Wall time (s) in the contact pass with grounds and balls, discarded trials included.
    pub collider_seconds: f64,
    /// What the implicit Newmark solves did (`None`: explicit steps).
    pub newmark: Option<perifrac_shell::NewmarkStats>,
    /// The USD cache written at the end (`[output] usd`) and the wall time it took.
    pub usd: Option<(crate::usd::UsdReport, Duration)>,
}

/// Runs a shell scene to the end, writing frames into `dir` (cleared of an earlier run's
/// files first, as for tet runs). On an instability the frames written so far stay,
/// `run.json` records the error and [`SceneError::ShellStopped`] is returned. An interruption
/// the observer reports writes a checkpoint and returns [`SceneError::Interrupted`]
/// ([`resume_shell`] continues from it), as do frame boundaries the scene's checkpoint policy
/// names.
pub fn run_shell(
    setup: ShellSetup,
    dir: &Path,
    observer: &mut dyn Observer,
) -> Result<ShellSummary, SceneError> {
    clear_output_dir(dir)?;
    let id = RunIdentity::of_shell(&setup);
    let mut writer = ShellWriter::start(dir, &setup)?;
    let t = Instant::now();
    let fragments = writer.write_frame(0, 0, &setup, false)?.fragments;
    let stand = Stand {
        frame: 1,
        step_in_frame: 0,
        steps: 0,
        substeps: 1,
        updates: 0,
        fragments,
    };
    drive(setup, &id, writer, dir, stand, t.elapsed(), observer)
}

/// Continues the shell run in `dir` from `checkpoint` (read by [`Checkpoint::read`]); `setup`
/// must be built from [`Checkpoint::scene`]'s shell scene with [`Checkpoint::frames`]. A
/// checkpoint of another scene or step is refused. The files written are byte-identical to
/// those of a run that was never interrupted.
pub fn resume_shell(
    mut setup: ShellSetup,
    checkpoint: &Checkpoint,
    dir: &Path,
    observer: &mut dyn Observer,
) -> Result<ShellSummary, SceneError> {
    let id = RunIdentity::of_shell(&setup);
    checkpoint.check_identity(dir, &id, "its frames, step or surface")?;
    let bad = |message: String| SceneError::Checkpoint {
        path: dir.join(CHECKPOINT_FILE),
        message,
    };
    let mut r = Reader::new(checkpoint.state());
    let mut read = || -> Result<_, CheckpointError> {
        r.tag("shell run")?;
        let stand = Stand {
            frame: checkpoint.position.frame,
            step_in_frame: checkpoint.position.step_in_frame,
            steps: r.u64("steps")?,
            substeps: r.u64("sub-step parts")?,
            updates: 0,
            fragments: r.usize("fragments")?,
        };
        let manifest = r.str("run.json")?;
        let triangles_before = r.usize("triangles at the last frame")?;
        let mut ids = FragmentIds::default();
        ids.restore(&mut r, triangles_before)?;
        setup.shell.read_checkpoint(&mut r)?;
        r.finish()?;
        Ok((stand, manifest, ids, triangles_before))
    };
    let (stand, manifest, ids, triangles_before) = read().map_err(|e| bad(e.to_string()))?;
    let manifest: ShellManifest =
        serde_json::from_str(&manifest).map_err(|e| bad(format!("run.json: {e}")))?;
    let writer = ShellWriter {
        dir: dir.to_path_buf(),
        manifest,
        ids,
        triangles_before,
    };
    drive(setup, &id, writer, dir, stand, Duration::ZERO, observer)
}

/// Where a shell run stands between two steps, and what it has counted.
#[derive(Debug, Clone, Copy)]
struct Stand {
    /// The frame being stepped towards (1-based).
    frame: usize,
    /// Steps already taken towards it.
    step_in_frame: u64,
    /// Steps taken.
    steps: u64,
    /// Plain steps: how many equal parts each step is cut into (more after splits shrink the
    /// triangles).
    substeps: u64,
    /// Triangle force updates by this process (not kept in checkpoints).
    updates: u64,
    /// Pieces at the last frame written.
    fragments: usize,
}

/// The step loop from `stand` to the end.
fn drive(
    mut setup: ShellSetup,
    id: &RunIdentity,
    mut writer: ShellWriter,
    dir: &Path,
    mut stand: Stand,
    mut output_time: Duration,
    observer: &mut dyn Observer,
) -> Result<ShellSummary, SceneError> {
    let total_steps = setup.steps_per_frame.saturating_mul(setup.frames as u64);
    let duration = setup.steps_per_frame as f64 * setup.info.dt * setup.frames as f64;
    let mut physics_time = Duration::ZERO;
    let mut last_checkpoint = Instant::now();
    let progress = |setup: &ShellSetup, stand: &Stand, frames_written: usize| Progress {
        time: setup.shell.shell().time(),
        duration,
        steps: stand.steps,
        total_steps,
        broken_bonds: setup.shell.stats().events.len() as u64,
        fragments: stand.fragments,
        frames_written,
    };
    for index in stand.frame..=setup.frames {
        let first = if index == stand.frame {
            stand.step_in_frame
        } else {
            0
        };
        for k in first..setup.steps_per_frame {
            let t = Instant::now();
            let evaluated = evaluations(&setup);
            let stepped = advance(&mut setup, &mut stand.substeps);
            physics_time += t.elapsed();
            let triangles = setup.shell.shell().model().mesh().triangles().len() as u64;
            stand.updates += (evaluations(&setup) - evaluated) * triangles;
            if let Err(cause) = stepped {
                let at = progress(&setup, &stand, index);
                return Err(stop(&mut writer, &at, cause.to_string()));
            }
            stand.steps += 1;
            observer.step(&progress(&setup, &stand, index));
            if observer.interrupted() {
                stand.frame = index;
                stand.step_in_frame = k + 1;
                return Err(interrupt(&mut writer, dir, id, &stand, &setup));
            }
        }
        let t = Instant::now();
        let frame = writer.write_frame(index, stand.steps, &setup, index == setup.frames)?;
        output_time += t.elapsed();
        stand.fragments = frame.fragments;
        observer.frame(&progress(&setup, &stand, index + 1));
        if index < setup.frames {
            stand.frame = index + 1;
            stand.step_in_frame = 0;
            if observer.interrupted() {
                return Err(interrupt(&mut writer, dir, id, &stand, &setup));
            }
            if setup.checkpoints.due(index, last_checkpoint.elapsed()) {
                let t = Instant::now();
                let saved = write_checkpoint(dir, id, &stand, &writer, &setup);
                output_time += t.elapsed();
                if let Err(e) = saved {
                    let _ = writer.record_error(e.to_string());
                    return Err(e);
                }
                last_checkpoint = Instant::now();
            }
        }
    }
    let usd = if let Some(layout) = setup.usd {
        let t = Instant::now();
        match crate::usd::export_usd(dir, None, layout, None) {
            Ok(report) => {
                let took = t.elapsed();
                output_time += took;
                Some((report, took))
            }
            Err(e) => {
                let _ = writer.record_error(e.to_string());
                return Err(e);
            }
        }
    } else {
        None
    };
    // finished: a checkpoint left from before would only resume what is done
    let _ = std::fs::remove_file(dir.join(CHECKPOINT_FILE));
    let s = setup.shell.shell();
    Ok(ShellSummary {
        steps: stand.steps,
        time: s.time(),
        dt: setup.info.dt,
        broken_triangles: setup.shell.stats().events.len(),
        fragments: stand.fragments,
        triangles: s.model().mesh().triangles().len(),
        yielded: s.model().yielded(),
        substeps: setup.shell.stats().substeps,
        rejected: setup.shell.stats().rejected,
        kinetic_energy: s.kinetic_energy(),
        elastic_energy: s.elastic_energy(),
        frames_written: setup.frames + 1,
        physics_time,
        output_time,
        triangle_updates: stand.updates,
        self_contact: s.self_contact().is_some().then(|| {
            let st = s.self_contact_stats();
            (st.total_seconds, st.builds)
        }),
        collider_seconds: s.collider_seconds(),
        newmark: setup.info.newmark.map(|_| s.newmark_stats()),
        usd,
    })
}

/// Writes a checkpoint at `stand` (the frames recorded so far with it), records the
/// interruption in `run.json` and returns it as the error.
fn interrupt(
    writer: &mut ShellWriter,
    dir: &Path,
    id: &RunIdentity,
    stand: &Stand,
    setup: &ShellSetup,
) -> SceneError {
    let time = setup.shell.shell().time();
    let e = match write_checkpoint(dir, id, stand, writer, setup) {
        Ok(checkpoint) => SceneError::Interrupted {
            time,
            step: stand.steps,
            frames: writer.manifest.frames.len(),
            checkpoint,
        },
        Err(e) => e,
    };
    let _ = writer.record_error(e.to_string());
    e
}

/// Writes `dir/checkpoint.bin` atomically: the run's place (read back by
/// [`Checkpoint::read`], as a tet run's, with no tet frames), then the shell run's counts,
/// `run.json` as it stands, the fragment ids and the searched shell.
fn write_checkpoint(
    dir: &Path,
    id: &RunIdentity,
    stand: &Stand,
    writer: &ShellWriter,
    setup: &ShellSetup,
) -> Result<PathBuf, SceneError> {
    let manifest = serde_json::to_string(&writer.manifest).map_err(|e| SceneError::Output {
        dir: dir.to_path_buf(),
        message: format!("cannot encode run.json for the checkpoint: {e}"),
    })?;
    let position = Position {
        frame: stand.frame,
        step_in_frame: stand.step_in_frame,
    };
    let summary = format!(
        "{} at step {} (t = {:.6e} s), stepping to frame {} of {}",
        id.scene_path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        stand.steps,
        setup.shell.shell().time(),
        stand.frame,
        id.frames
    );
    crate::checkpoint::write_with(dir, id, position, &[], summary, |w| {
        w.tag("shell run");
        w.u64(stand.steps);
        w.u64(stand.substeps);
        w.usize(stand.fragments);
        w.str(&manifest);
        w.usize(writer.triangles_before);
        writer.ids.save(w);
        setup.shell.write_checkpoint(w);
    })
}

/// Force evaluations so far: sub-steps taken and trials discarded.
fn evaluations(setup: &ShellSetup) -> u64 {
    let st = setup.shell.stats();
    st.substeps + st.rejected
}

/// One step of the scene. With the event search, the search covers it. Without, it is cut into
/// parts of `dt / substeps`, fracture checked after each; when triangles broke, the stable step
/// is measured again on the new mesh (lighter vertices, smaller triangles) and `substeps`
/// raised so the rest of the step, and the steps after, keep within the scene's share of it (a
/// part that was stable before a split can run away after it).
fn advance(setup: &mut ShellSetup, substeps: &mut u64) -> Result<(), perifrac_shell::ShellError> {
    let dt = setup.info.dt;
    // The search covers the step itself; a Newmark step has no stable limit to keep under.
    if setup.info.event_levels > 0 || setup.info.newmark.is_some() {
        return setup.shell.advance(dt);
    }
    let mut done = 0.0;
    while done < dt * (1.0 - 1e-12) {
        let h = (dt / *substeps as f64).min(dt - done);
        let before = setup.shell.stats().events.len();
        setup.shell.advance(h)?;
        done += h;
        if setup.shell.stats().events.len() > before {
            let omega = 2.0 / setup.shell.shell_mut().stable_step()?;
            let limit = 2.0 / (omega * omega + setup.info.ball_omega2).sqrt();
            let needed = (dt / (setup.info.safety * limit)).ceil();
            if needed.is_finite() && needed as u64 > *substeps {
                *substeps = needed as u64;
            }
        }
    }
    Ok(())
}

/// Records why the run stopped in `run.json` and makes the error to return.
fn stop(writer: &mut ShellWriter, at: &Progress, cause: String) -> SceneError {
    if let Err(e) = writer.record_error(cause.clone()) {
        return e;
    }
    SceneError::ShellStopped {
        time: at.time,
        step: at.steps,
        frames: writer.manifest.frames.len(),
        cause,
    }
}

/// Writes a shell run's frames and `run.json`.
struct ShellWriter {
    dir: PathBuf,
    manifest: ShellManifest,
    /// Stable fragment ids of the mesh's triangles.
    ids: FragmentIds,
    /// Triangles of the mesh at the last frame.
    triangles_before: usize,
}

impl ShellWriter {
    /// `run.json` first (whatever fails after it is recorded in it), then `scene.toml` and
    /// `frames/`.
    fn start(dir: &Path, setup: &ShellSetup) -> Result<ShellWriter, SceneError> {
        let info = &setup.info;
        let shell = setup.shell.shell();
        let manifest = ShellManifest {
            format: RUN_FORMAT.into(),
            body: "shell".into(),
            scene: setup
                .scene_path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            up: info.up,
            rest_bounds: Bounds {
                min: info.rest_bounds.0,
                max: info.rest_bounds.1,
            },
            grounds: shell
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
            vertices: info.vertices,
            triangles: info.triangles,
            thickness: info.thickness,
            frame_thickness: setup.frame_thickness,
            fps: setup.fps,
            dt: info.dt,
            dt_limit: info.dt_limit,
            event_levels: info.event_levels,
            integrator: if info.newmark.is_some() {
                "newmark"
            } else {
                "explicit"
            }
            .into(),
            mass: info.mass,
            frames: Vec::new(),
            fragments: Vec::new(),
            finished: false,
            error: None,
        };
        let mut writer = ShellWriter {
            dir: dir.to_path_buf(),
            manifest,
            ids: FragmentIds::default(),
            triangles_before: 0,
        };
        writer.write_manifest()?;
        let rest = write_scene_and_frames_dir(dir, &setup.scene_text);
        if let Err(e) = rest {
            let _ = writer.record_error(e.to_string());
            return Err(e);
        }
        Ok(writer)
    }

    fn write_manifest(&self) -> Result<(), SceneError> {
        let text =
            serde_json::to_string_pretty(&self.manifest).map_err(|e| SceneError::Output {
                dir: self.dir.clone(),
                message: format!("cannot encode run.json: {e}"),
            })?;
        perifrac_io::atomic_write(&self.dir.join("run.json"), |w| {
            w.write_all(text.as_bytes())?;
            w.write_all(b"\n")
        })
        .map_err(SceneError::from)
    }

    fn record_error(&mut self, message: String) -> Result<(), SceneError> {
        self.manifest.error = Some(message);
        self.write_manifest()
    }

    /// Writes frame `index` and records it (`last` marks the run finished).
    fn write_frame(
        &mut self,
        index: usize,
        step: u64,
        setup: &ShellSetup,
        last: bool,
    ) -> Result<ShellFrameJson, SceneError> {
        let searched = &setup.shell;
        let shell = searched.shell();
        let model = shell.model();
        let x = shell.positions();
        let thickness = (setup.frame_thickness > 0.0).then_some(setup.frame_thickness);
        let m = model.frame(x, shell.velocities(), thickness);
        // Stable ids: a triangle split off since the last frame takes the fragment of the
        // triangle it was part of then.
        let mesh_pieces = pieces(model.mesh());
        let count = mesh_pieces.iter().max().map_or(0, |p| *p as usize + 1);
        let before = self.triangles_before;
        let earlier = |t: usize| model.part_of(t, before);
        let ids = self.ids.update_split(&mesh_pieces, count, index, &earlier);
        self.triangles_before = mesh_pieces.len();
        self.manifest.fragments = self.ids.births().to_vec();
        let fragment: Vec<u32> = m.piece.iter().map(|&p| ids[p as usize]).collect();
        let surface = SurfaceRef {
            crack: Some(&m.crack),
            fragment: Some(&fragment),
            normals: Some(&m.normals),
            velocities: Some(&m.velocities),
            ..SurfaceRef::new(&m.vertices, &m.triangles)
        };
        let name = format!("frames/surface_{index:04}.ply");
        let written = write_ply(
            &self.dir.join(&name),
            &surface,
            PlyEncoding::BinaryLittleEndian,
        )
        .map_err(SceneError::from)
        .and_then(|()| {
            if !setup.povray {
                return Ok(None);
            }
            let inc = format!("frames/surface_{index:04}.inc");
            write_povray_mesh2(&self.dir.join(&inc), &surface, POVRAY_MESH_NAME)
                .map(|()| Some(inc))
                .map_err(SceneError::from)
        });
        let povray = match written {
            Ok(p) => p,
            Err(e) => {
                let _ = self.record_error(e.to_string());
                return Err(e);
            }
        };
        let (lo, hi) = bounds(&m.vertices);
        let b = Bounds { min: lo, max: hi };
        let crack_edges = model
            .crack_edges()
            .iter()
            .map(|c| c.iter().filter(|&&k| k).count())
            .sum();
        let frame = ShellFrameJson {
            index,
            time: shell.time(),
            step,
            surface: name,
            povray,
            balls: shell
                .colliders()
                .map(|c| {
                    c.balls()
                        .map(|ball| BallJson {
                            center: ball.center,
                            radius: ball.radius,
                        })
                        .collect()
                })
                .unwrap_or_default(),
            bounds: b,
            main_bounds: main_bounds(&m.vertices, &m.triangles, &m.piece),
            fragments: m.piece.iter().max().map_or(0, |p| *p as usize + 1),
            broken_triangles: searched.stats().events.len(),
            crack_edges,
            mesh_triangles: model.mesh().triangles().len(),
            mesh_vertices: x.len(),
            yielded: model.yielded(),
            kinetic_energy: shell.kinetic_energy(),
            elastic_energy: shell.elastic_energy(),
            search: (setup.info.event_levels > 0).then(|| SearchJson {
                substeps: searched.stats().substeps,
                rejected: searched.stats().rejected,
            }),
            newmark: setup.info.newmark.map(|_| {
                let st = shell.newmark_stats();
                NewmarkJson {
                    solves: st.steps,
                    iterations: st.iterations,
                    capped: st.capped,
                    factorizations: st.factorizations,
                }
            }),
        };
        self.manifest.frames.push(frame.clone());
        self.manifest.finished = last;
        self.write_manifest()?;
        Ok(frame)
    }
}

/// Bounds (m) of the largest pieces by area that together hold
/// [`crate::output::MAIN_MASS_SHARE`] of the shell's area (its mass goes with its area; by
/// triangle count, the chips fracture cuts small would weigh as much as whole triangles).
fn main_bounds(x: &[[f64; 3]], triangles: &[[u32; 3]], piece: &[u32]) -> Bounds {
    let pieces = piece.iter().max().map_or(0, |p| *p as usize + 1);
    let mut area = vec![0.0f64; pieces];
    for (t, &p) in triangles.iter().zip(piece) {
        let [a, b, c] = t.map(|i| x[i as usize]);
        area[p as usize] += 0.5 * norm(cross(sub(b, a), sub(c, a)));
    }
    let mut order: Vec<usize> = (0..pieces).collect();
    // largest first; ties by id, so the choice is deterministic
    order.sort_by(|&a, &b| area[b].total_cmp(&area[a]).then(a.cmp(&b)));
    let mut kept = vec![false; pieces];
    let mut sum = 0.0;
    let want = crate::output::MAIN_MASS_SHARE * area.iter().sum::<f64>();
    for p in order {
        if sum >= want {
            break;
        }
        kept[p] = true;
        sum += area[p];
    }
    let points: Vec<[f64; 3]> = triangles
        .iter()
        .zip(piece)
        .filter(|(_, &p)| kept[p as usize])
        .flat_map(|(t, _)| t.map(|i| x[i as usize]))
        .collect();
    let (min, max) = bounds(&points);
    Bounds { min, max }
}
