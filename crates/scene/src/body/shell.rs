//! A thin shell as a [`Body`]: the searched shell steps it (plain steps cut into parts where
//! fracture lowers the stable step); a frame is its surface with crack flags and stable
//! fragment ids, each piece as a slab of the frame thickness.

use std::path::Path;
use std::time::{Duration, Instant};

use perifrac_checkpoint::{Reader, Writer};
use perifrac_io::SurfaceRef;
use perifrac_physics::math::{cross, norm, sub};
use perifrac_shell::output::pieces;

use super::{Body, BodySummary, Head, Plan, StepError};
use crate::error::SceneError;
use crate::fragments::{FragmentBirth, FragmentIds};
use crate::manifest::{
    balls_json, grounds_json, BodyJson, Bounds, FrameBodyJson, FrameJson, NewmarkJson, SearchJson,
    ShellFrameJson, ShellJson, MAIN_MASS_SHARE,
};
use crate::setup::math::bounds;
use crate::shell::{ShellSetup, ShellSetupInfo};
use crate::sinks::{FrameView, SinkChoice, Sinks};

/// A thin shell's part of a run's summary.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellSummary {
    /// Triangles broken (fracture events).
    pub broken_triangles: usize,
    /// Triangles of the mesh at the end.
    pub triangles: usize,
    /// Triangles that have yielded, at the end.
    pub yielded: usize,
    /// Sub-steps taken (the steps, or more where steps were cut or searched).
    pub substeps: u64,
    /// Trial sub-steps discarded.
    pub rejected: u64,
    /// The event search's finest level (0: plain steps, cut where fracture lowers the limit).
    pub event_levels: u32,
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
    /// Runs with `[[load]]` tables: the work they did (J).
    pub load_work: Option<f64>,
}

/// A thin shell being run.
pub(crate) struct Shell {
    shell: perifrac_shell::SearchedShell,
    info: ShellSetupInfo,
    /// Thickness (m) given to each piece in the frames (0: the mid-surface).
    frame_thickness: f64,
    /// Steps taken.
    steps: u64,
    /// Plain steps: how many equal parts each step is cut into (more after splits shrink the
    /// triangles).
    substeps: u64,
    /// Triangle force updates by this process (not kept in checkpoints).
    updates: u64,
    /// Stable fragment ids of the mesh's triangles.
    ids: FragmentIds,
    /// Triangles of the mesh at the last frame.
    triangles_before: usize,
    physics_time: Duration,
    output_time: Duration,
}

/// The shell body of `setup` and the plan around it.
pub(crate) fn split(setup: ShellSetup) -> (Box<dyn Body>, Plan) {
    let ShellSetup {
        scene_path,
        scene_text,
        shell,
        frames,
        steps_per_frame,
        povray,
        frame_thickness,
        usd,
        fps,
        checkpoints,
        info,
    } = setup;
    let plan = Plan {
        scene_path,
        scene_text,
        frames,
        steps_per_frame,
        dt: info.dt,
        fps,
        checkpoints,
        sinks: SinkChoice {
            povray,
            particles: false,
            debris: false,
            usd,
        },
    };
    let body = Shell {
        shell,
        info,
        frame_thickness,
        steps: 0,
        substeps: 1,
        updates: 0,
        ids: FragmentIds::default(),
        triangles_before: 0,
        physics_time: Duration::ZERO,
        output_time: Duration::ZERO,
    };
    (Box::new(body), plan)
}

impl Body for Shell {
    fn head(&self) -> Head {
        let info = &self.info;
        let grounds = grounds_json(self.shell.shell().colliders());
        Head {
            up: info.up,
            rest_bounds: Bounds::of(info.rest_bounds),
            grounds,
            dt: info.dt,
            dt_limit: info.dt_limit,
            mass: info.mass,
            body: BodyJson::Shell(ShellJson {
                vertices: info.vertices,
                triangles: info.triangles,
                thickness: info.thickness,
                frame_thickness: self.frame_thickness,
                event_levels: info.event_levels,
                integrator: if info.newmark.is_some() {
                    "newmark"
                } else {
                    "explicit"
                }
                .into(),
            }),
        }
    }

    fn identify(&self, w: &mut Writer) {
        let mesh = self.shell.shell().model().mesh();
        w.array(mesh.vertices());
        w.array(mesh.triangles());
    }

    fn step(&mut self) -> Result<(), StepError> {
        let t = Instant::now();
        let evaluated = self.evaluations();
        let stepped = self.advance();
        self.physics_time += t.elapsed();
        let triangles = self.shell.shell().model().mesh().triangles().len() as u64;
        self.updates += (self.evaluations() - evaluated) * triangles;
        stepped.map_err(StepError::Shell)?;
        self.steps += 1;
        Ok(())
    }

    fn time(&self) -> f64 {
        self.shell.shell().time()
    }

    fn steps(&self) -> u64 {
        self.steps
    }

    fn broken(&self) -> u64 {
        self.shell.stats().events.len() as u64
    }

    fn frame(&mut self, index: usize, sinks: &Sinks, dir: &Path) -> Result<FrameJson, SceneError> {
        let t = Instant::now();
        let frame = self.write_frame(index, sinks, dir);
        self.output_time += t.elapsed();
        frame
    }

    fn births(&self) -> Vec<FragmentBirth> {
        self.ids.births().to_vec()
    }

    fn save(&self, w: &mut Writer) {
        w.tag("shell");
        w.u64(self.steps);
        w.u64(self.substeps);
        w.usize(self.triangles_before);
        self.ids.save(w);
        self.shell.write_checkpoint(w);
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), String> {
        let mut read = || -> Result<(), perifrac_checkpoint::CheckpointError> {
            r.tag("shell")?;
            self.steps = r.u64("steps")?;
            self.substeps = r.u64("sub-step parts")?;
            self.triangles_before = r.usize("triangles at the last frame")?;
            self.ids.restore(r, self.triangles_before)?;
            self.shell.read_checkpoint(r)
        };
        read().map_err(|e| e.to_string())
    }

    fn add_output_time(&mut self, d: Duration) {
        self.output_time += d;
    }

    fn summary(&mut self) -> BodySummary {
        let s = self.shell.shell();
        let stats = self.shell.stats();
        BodySummary::Shell(ShellSummary {
            broken_triangles: stats.events.len(),
            triangles: s.model().mesh().triangles().len(),
            yielded: s.model().yielded(),
            substeps: stats.substeps,
            rejected: stats.rejected,
            event_levels: self.info.event_levels,
            physics_time: self.physics_time,
            output_time: self.output_time,
            triangle_updates: self.updates,
            self_contact: s.self_contact().is_some().then(|| {
                let st = s.self_contact_stats();
                (st.total_seconds, st.builds)
            }),
            collider_seconds: s.collider_seconds(),
            newmark: self.info.newmark.map(|_| s.newmark_stats()),
            load_work: self.info.loads.then(|| s.load_work()),
        })
    }
}

impl Shell {
    /// Force evaluations so far: sub-steps taken and trials discarded.
    fn evaluations(&self) -> u64 {
        let st = self.shell.stats();
        st.substeps + st.rejected
    }

    /// One step of the scene. With the event search, the search covers it. Without, it is cut
    /// into parts of `dt / substeps`, fracture checked after each; when triangles broke, the
    /// stable step is measured again on the new mesh (lighter vertices, smaller triangles) and
    /// `substeps` raised so the rest of the step, and the steps after, keep within the scene's
    /// share of it (a part that was stable before a split can run away after it).
    fn advance(&mut self) -> Result<(), perifrac_shell::ShellError> {
        let dt = self.info.dt;
        // The search covers the step itself; a Newmark step has no stable limit to keep under.
        if self.info.event_levels > 0 || self.info.newmark.is_some() {
            return self.shell.advance(dt);
        }
        let mut done = 0.0;
        while done < dt * (1.0 - 1e-12) {
            let h = (dt / self.substeps as f64).min(dt - done);
            let before = self.shell.stats().events.len();
            self.shell.advance(h)?;
            done += h;
            if self.shell.stats().events.len() > before {
                let omega = 2.0 / self.shell.shell_mut().stable_step()?;
                let limit = 2.0 / (omega * omega + self.info.ball_omega2).sqrt();
                let needed = (dt / (self.info.safety * limit)).ceil();
                if needed.is_finite() && needed as u64 > self.substeps {
                    self.substeps = needed as u64;
                }
            }
        }
        Ok(())
    }

    /// The frame's surface through `sinks`, and its record.
    fn write_frame(
        &mut self,
        index: usize,
        sinks: &Sinks,
        dir: &Path,
    ) -> Result<FrameJson, SceneError> {
        let searched = &self.shell;
        let shell = searched.shell();
        let model = shell.model();
        let x = shell.positions();
        let thickness = (self.frame_thickness > 0.0).then_some(self.frame_thickness);
        let m = model.frame(x, shell.velocities(), thickness);
        // Stable ids: a triangle split off since the last frame takes the fragment of the
        // triangle it was part of then.
        let mesh_pieces = pieces(model.mesh());
        let count = mesh_pieces.iter().max().map_or(0, |p| *p as usize + 1);
        let before = self.triangles_before;
        let earlier = |t: usize| model.part_of(t, before);
        let ids = self.ids.update_split(&mesh_pieces, count, index, &earlier);
        self.triangles_before = mesh_pieces.len();
        let fragment: Vec<u32> = m.piece.iter().map(|&p| ids[p as usize]).collect();
        let view = FrameView {
            index,
            surface: SurfaceRef {
                crack: Some(&m.crack),
                fragment: Some(&fragment),
                normals: Some(&m.normals),
                velocities: Some(&m.velocities),
                ..SurfaceRef::new(&m.vertices, &m.triangles)
            },
            particles: None,
            debris: None,
        };
        let files = sinks.write(dir, &view)?;
        let (lo, hi) = bounds(&m.vertices);
        let crack_edges = model
            .crack_edges()
            .iter()
            .map(|c| c.iter().filter(|&&k| k).count())
            .sum();
        let balls = balls_json(shell.colliders());
        let stats = searched.stats();
        Ok(FrameJson {
            index,
            time: shell.time(),
            step: self.steps,
            surface: files.surface,
            povray: files.povray,
            balls,
            bounds: Bounds { min: lo, max: hi },
            main_bounds: main_bounds(&m.vertices, &m.triangles, &m.piece),
            fragments: m.piece.iter().max().map_or(0, |p| *p as usize + 1),
            kinetic_energy: shell.kinetic_energy(),
            elastic_energy: shell.elastic_energy(),
            search: (self.info.event_levels > 0).then_some(SearchJson {
                substeps: stats.substeps,
                rejected: stats.rejected,
            }),
            body: FrameBodyJson::Shell(ShellFrameJson {
                broken_triangles: stats.events.len(),
                crack_edges,
                mesh_triangles: model.mesh().triangles().len(),
                mesh_vertices: x.len(),
                yielded: model.yielded(),
                load_work: self.info.loads.then(|| shell.load_work()),
                newmark: self.info.newmark.map(|_| {
                    let st = shell.newmark_stats();
                    NewmarkJson {
                        solves: st.steps,
                        iterations: st.iterations,
                        capped: st.capped,
                        factorizations: st.factorizations,
                    }
                }),
            }),
        })
    }
}

/// Bounds (m) of the largest pieces by area that together hold [`MAIN_MASS_SHARE`] of the
/// shell's area (its mass goes with its area; by triangle count, the chips fracture cuts small
/// would weigh as much as whole triangles).
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
    let want = MAIN_MASS_SHARE * area.iter().sum::<f64>();
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
    Bounds::of(bounds(&points))
}
