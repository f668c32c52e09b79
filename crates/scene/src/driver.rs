//! A solid's step as a short list of named stages: release anchors, physics under the
//! influences (contact forces, loads), cut the mesh along the bonds that broke, advect its
//! vertices. Each stage is
//! timed; the progress bar, the summary and the speed benchmark read the same counters.

use std::time::{Duration, Instant};

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_contact::{Colliders, ContactStats, SelfContact, SelfContactStats};
use perifrac_physics::{PhysicsError, Solver};
use perifrac_topology::{Pieces, TetMesh};

use crate::environment::{CollidersInfluence, Influence, Influences, SelfContactInfluence};
use crate::fragments::{FragmentBirth, FragmentIds};

/// Wall time spent in each stage since the driver was made.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Peridynamic forces, integration, fracture check and contact forces.
    pub physics: Duration,
    /// The part of `physics` spent on contact: collider forces, and between particles the
    /// pair list (its builds and the check whether one is due) and the forces.
    pub contact: Duration,
    /// Crack faces from broken bonds and vertex splitting.
    pub topology: Duration,
    /// Mass-weighted vertex advection.
    pub advect: Duration,
    /// Frame output (surfaces, particles, `run.json`), counted by the writer.
    pub output: Duration,
}

impl StageTimes {
    /// All stages together.
    pub fn total(&self) -> Duration {
        self.physics + self.topology + self.advect + self.output
    }
}

/// Anchor releases: (time in s, the particles freed then).
pub(crate) type Releases = Vec<(f64, Vec<u32>)>;

/// What one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Bonds (pairs) broken in this step.
    pub broken_bonds: usize,
    /// Crack faces the broken bonds added to the mesh.
    pub crack_faces: usize,
    /// Contacts found in this step.
    pub contact: ContactStats,
    /// Contact between particles in this step (zero without self contact).
    pub self_contact: SelfContactStats,
}

/// The simulation state of a running scene: the embedded mesh, the peridynamic solver (any
/// force model under any integrator), what acts on it from outside (colliders, contact
/// between fragments, loads: a list of [`Influence`]s), and per-particle contact radii. Made
/// by [`crate::Setup::new`].
pub struct Driver {
    mesh: TetMesh,
    solver: Box<dyn Solver>,
    influences: Influences,
    radii: Vec<f64>,
    /// Anchors to release, sorted by time.
    releases: Releases,
    next_release: usize,
    /// Kinematic balls to stop, as (time in s, ball), sorted by time.
    ball_stops: Vec<(f64, usize)>,
    next_stop: usize,
    broken_bonds: u64,
    crack_faces: u64,
    times: StageTimes,
    /// Stable fragment ids, updated at every frame written.
    fragments: FragmentIds,
}

impl Driver {
    /// Ties the pieces together. `radii` (m) are per particle (= per tet);
    /// `releases` lists anchor releases as (time in s, particles).
    pub(crate) fn new(
        mesh: TetMesh,
        solver: Box<dyn Solver>,
        colliders: Option<Colliders>,
        self_contact: Option<SelfContact>,
        radii: Vec<f64>,
        mut releases: Releases,
    ) -> Driver {
        releases.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Colliders first, then contact between particles: the order their forces are summed.
        let mut influences = Influences::default();
        if let Some(c) = colliders {
            influences.push(Box::new(CollidersInfluence::new(c, radii.clone())));
        }
        if let Some(sc) = self_contact {
            influences.push(Box::new(SelfContactInfluence::new(sc)));
        }
        Driver {
            mesh,
            solver,
            influences,
            radii,
            releases,
            next_release: 0,
            ball_stops: Vec::new(),
            next_stop: 0,
            broken_bonds: 0,
            crack_faces: 0,
            times: StageTimes::default(),
            fragments: FragmentIds::default(),
        }
    }

    /// Kinematic balls to stop, as (time in s, ball index; checked by the setup).
    pub(crate) fn with_ball_stops(mut self, mut stops: Vec<(f64, usize)>) -> Driver {
        stops.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.ball_stops = stops;
        self
    }

    /// Advances one time step. On an instability the error is returned and the state is that
    /// of the failed step.
    pub fn step(&mut self) -> Result<StepReport, PhysicsError> {
        self.release_anchors();
        self.stop_balls();
        let Driver {
            mesh,
            solver,
            influences,
            times,
            ..
        } = self;
        let t0 = Instant::now();
        let broken = physics_with_influences(solver.as_mut(), influences)?;
        let t1 = Instant::now();
        let broken_bonds = broken.len();
        let crack_faces = cut(mesh, broken);
        let t2 = Instant::now();
        mesh.advect(solver.dt(), solver.model().masses(), solver.velocities());
        let t3 = Instant::now();
        times.physics += t1 - t0;
        times.contact += influences.take_time();
        times.topology += t2 - t1;
        times.advect += t3 - t2;
        self.broken_bonds += broken_bonds as u64;
        self.crack_faces += crack_faces as u64;
        Ok(StepReport {
            broken_bonds,
            crack_faces,
            contact: self
                .influences
                .get::<CollidersInfluence>()
                .map_or_else(ContactStats::default, |c| c.stats()),
            self_contact: self.self_contact_last(),
        })
    }

    /// Adds `influence` after the scene's own (colliders, then contact between particles).
    pub fn add_influence(&mut self, influence: Box<dyn Influence>) {
        self.influences.push(influence);
    }

    /// What acts on the particles from outside the material.
    pub fn influences(&self) -> &Influences {
        &self.influences
    }

    /// Frees the anchors whose release time falls within half a step of now.
    fn release_anchors(&mut self) {
        let now = self.solver.time() + 0.5 * self.solver.dt();
        while let Some((t, particles)) = self.releases.get(self.next_release) {
            if *t > now {
                break;
            }
            // The indices were checked when the anchors were made.
            let _ = self.solver.loads_mut().release(particles);
            self.next_release += 1;
        }
    }

    /// Stops the kinematic balls whose stop time falls within half a step of now (the anchors'
    /// rule). A checkpoint keeps the balls' velocities, so a resumed run starts the list again
    /// and stops the balls already stopped once more, which changes nothing.
    fn stop_balls(&mut self) {
        let now = self.solver.time() + 0.5 * self.solver.dt();
        while let Some(&(t, ball)) = self.ball_stops.get(self.next_stop) {
            if t > now {
                break;
            }
            if let Some(c) = self.influences.get_mut::<CollidersInfluence>() {
                // The setup made these balls kinematic and in range.
                let _ = c.colliders_mut().stop_ball(ball);
            }
            self.next_stop += 1;
        }
    }

    /// Contact between particles, when the scene has it.
    pub fn self_contact(&self) -> Option<&SelfContact> {
        let sc = self.influences.get::<SelfContactInfluence>();
        sc.map(SelfContactInfluence::contact)
    }

    /// Self contact over the run so far: the most pairs in contact in one step and the
    /// deepest overlap (m, and as a share of its pair's contact distance); zeros without it.
    pub fn self_contact_deepest(&self) -> SelfContactStats {
        let sc = self.influences.get::<SelfContactInfluence>();
        sc.map_or_else(SelfContactStats::default, SelfContactInfluence::deepest)
    }

    /// Self contact in the last step; zeros without it.
    pub fn self_contact_last(&self) -> SelfContactStats {
        let sc = self.influences.get::<SelfContactInfluence>();
        sc.map_or_else(SelfContactStats::default, SelfContactInfluence::last)
    }

    /// The embedded tet mesh, cut and advected so far.
    pub fn mesh(&self) -> &TetMesh {
        &self.mesh
    }

    /// The peridynamic solver (positions, velocities, time, step).
    pub fn solver(&self) -> &dyn Solver {
        self.solver.as_ref()
    }

    /// The solver, mutably (elastic energy needs it).
    pub fn solver_mut(&mut self) -> &mut dyn Solver {
        self.solver.as_mut()
    }

    /// The colliders, when the scene has any.
    pub fn colliders(&self) -> Option<&Colliders> {
        let c = self.influences.get::<CollidersInfluence>();
        c.map(CollidersInfluence::colliders)
    }

    /// Particle masses (kg).
    pub fn masses(&self) -> &[f64] {
        self.solver.model().masses()
    }

    /// Particle contact radii (m).
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// Damage `phi` of every particle (0 intact, 1 all bonds broken); zeros without fracture.
    pub fn damage(&self) -> Vec<f64> {
        match self.solver.model().damage() {
            Some(d) => (0..self.radii.len()).map(|i| d.phi(i)).collect(),
            None => vec![0.0; self.radii.len()],
        }
    }

    /// Per material, the largest share of its fracture threshold that any bond reached so far
    /// (1; a bond that broke reached 1 or more), `None` for a material that cannot break; `None`
    /// when nothing can break.
    pub fn peak_threshold_shares(&self) -> Option<Vec<Option<f64>>> {
        let model = self.solver.model();
        let damage = model.damage()?;
        let ids = model.discretization().materials();
        let count = ids.iter().map(|&m| m as usize + 1).max().unwrap_or(0);
        let mut out: Vec<Option<f64>> = vec![None; count];
        for (i, (&m, &p)) in ids.iter().zip(damage.peak_share()).enumerate() {
            if damage.can_break(i) {
                let slot = &mut out[m as usize];
                *slot = Some(slot.map_or(p, |q| q.max(p)));
            }
        }
        Some(out)
    }

    /// Bonds (pairs) at the start.
    pub fn bonds(&self) -> u64 {
        self.solver.model().discretization().family().num_bonds() as u64 / 2
    }

    /// Bonds (pairs) broken since the start.
    pub fn broken_bonds(&self) -> u64 {
        self.broken_bonds
    }

    /// Crack faces added since the start (initial cracks not counted).
    pub fn crack_faces(&self) -> u64 {
        self.crack_faces
    }

    /// The stable ids of the mesh's `pieces` at frame `frame` (`ids[piece]`), recorded for
    /// the next frame (see [`crate::fragments`]). Call once per frame written, in order.
    pub fn fragment_ids(&mut self, pieces: &Pieces, frame: usize) -> Vec<u32> {
        self.fragments.update(pieces, frame)
    }

    /// Places the mesh's vertices for a frame from the particles, with `pieces` the mesh's
    /// current pieces: every vertex where the affine fit of the particles around it takes its
    /// rest position ([`TetMesh::place_vertices_from_particles`]: exact for rigid motion and
    /// uniform strain, no drift, whatever the step), then every piece of at most
    /// [`perifrac_topology::RIGID_PIECE_TETS`] tets back into its rest shape, turned and moved
    /// as its vertices say ([`TetMesh::place_small_pieces_rigidly`]): too few particles to fit.
    /// Surface only: the particles are untouched. Returns the vertices fitted and the pieces
    /// placed.
    pub fn place_surface(&mut self, pieces: &Pieces) -> (usize, usize) {
        let fitted = self
            .mesh
            .place_vertices_from_particles(self.solver.positions());
        let rigid = self
            .mesh
            .place_small_pieces_rigidly(pieces, perifrac_topology::RIGID_PIECE_TETS);
        (fitted, rigid)
    }

    /// Every fragment so far with its parent and first frame, in id order.
    pub fn fragment_births(&self) -> &[FragmentBirth] {
        self.fragments.births()
    }

    /// Time spent per stage.
    pub fn stage_times(&self) -> StageTimes {
        self.times
    }

    /// Writes everything a step changes: the mesh (cracks, copies, positions), the fragment
    /// ids of the last frame, the solver, the balls, the anchors still to release and the
    /// counters.
    pub fn save(&self, w: &mut Writer) {
        w.tag("driver");
        w.usize(self.next_release);
        w.u64(self.broken_bonds);
        w.u64(self.crack_faces);
        let t = &self.times;
        for d in [t.physics, t.contact, t.topology, t.advect, t.output] {
            w.f64(d.as_secs_f64());
        }
        self.mesh.save(w);
        self.fragments.save(w);
        self.solver.save(w);
        self.influences.save(w);
    }

    /// Reads what [`Driver::save`] wrote into a driver made by the same setup.
    pub fn restore(&mut self, r: &mut Reader) -> Result<(), PhysicsError> {
        r.tag("driver")?;
        let next = r.usize("releases done")?;
        if next > self.releases.len() {
            return Err(CheckpointError::Invalid {
                what: "releases done".into(),
                message: format!("{next} of {} anchor releases", self.releases.len()),
            }
            .into());
        }
        self.next_release = next;
        self.next_stop = 0;
        self.broken_bonds = r.u64("broken bonds")?;
        self.crack_faces = r.u64("crack faces")?;
        let mut secs = [0.0; 5];
        for s in &mut secs {
            // wall times only feed the summary: a bad one becomes zero rather than an error
            *s = r.f64("stage times")?;
        }
        let d = |s: f64| Duration::try_from_secs_f64(s).unwrap_or_default();
        self.times = StageTimes {
            physics: d(secs[0]),
            contact: d(secs[1]),
            topology: d(secs[2]),
            advect: d(secs[3]),
            output: d(secs[4]),
        };
        self.mesh.restore(r)?;
        self.fragments.restore(r, self.mesh.num_tets())?;
        self.solver.restore(r)?;
        self.influences.restore(r)?;
        Ok(())
    }

    /// Adds frame-output time to the counters.
    pub(crate) fn add_output_time(&mut self, d: Duration) {
        self.times.output += d;
    }
}

/// Stage 1: one step of the particles under what acts on them from outside (forces for an
/// explicit step, a potential for an implicit one). Returns the bonds broken in it.
fn physics_with_influences<'a>(
    solver: &'a mut dyn Solver,
    influences: &mut Influences,
) -> Result<&'a [(u32, u32)], PhysicsError> {
    influences.before_step(solver);
    let broken = solver.step(influences)?;
    influences.after_step(broken);
    Ok(broken)
}

/// Stage 2: crack faces between face-adjacent tets whose bond broke, then vertex splitting.
/// Returns the crack faces added.
fn cut(mesh: &mut TetMesh, broken: &[(u32, u32)]) -> usize {
    if broken.is_empty() {
        return 0;
    }
    let added = mesh.crack_bonds(broken);
    if added > 0 {
        mesh.split();
    }
    added
}
