//! The step loop of DESIGN.md as a short list of named stages: release anchors, physics with
//! contact forces, cut the mesh along the bonds that broke, advect its vertices. Each stage is
//! timed; the progress bar, the summary and the speed benchmark read the same counters.

use std::time::{Duration, Instant};

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_contact::{Bonds, Colliders, ContactStats, SelfContact, SelfContactStats};
use perifrac_physics::math::Vec3;
use perifrac_physics::{Environment, External, Family, ImplicitEnvironment, PhysicsError, Solver};
use perifrac_topology::{Pieces, TetMesh};

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

/// Bonds broken in one step, as particle pairs `(i, j)`, `i < j`.
type Broken<'a> = &'a [(u32, u32)];

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
/// force model under any integrator), the colliders, and per-particle contact radii. Made by
/// [`crate::Setup::new`].
pub struct Driver {
    mesh: TetMesh,
    solver: Box<dyn Solver>,
    colliders: Option<Colliders>,
    self_contact: Option<SelfContact>,
    radii: Vec<f64>,
    /// Anchors to release, sorted by time.
    releases: Releases,
    next_release: usize,
    /// Kinematic balls to stop, as (time in s, ball), sorted by time.
    ball_stops: Vec<(f64, usize)>,
    next_stop: usize,
    broken_bonds: u64,
    crack_faces: u64,
    /// Self contact: the deepest overlap so far and the last step's statistics.
    self_deepest: SelfContactStats,
    self_last: SelfContactStats,
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
        Driver {
            mesh,
            solver,
            colliders,
            self_contact,
            radii,
            releases,
            next_release: 0,
            ball_stops: Vec::new(),
            next_stop: 0,
            broken_bonds: 0,
            crack_faces: 0,
            self_deepest: SelfContactStats::default(),
            self_last: SelfContactStats::default(),
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
            colliders,
            self_contact,
            radii,
            times,
            ..
        } = self;
        let t0 = Instant::now();
        let mut contact_time = Duration::ZERO;
        if let Some(sc) = self_contact.as_mut() {
            let model = solver.model();
            let family = model.discretization().family();
            let state = model.damage().map(|d| d.bond_state());
            let bonded = FamilyBonds { family, state };
            sc.prepare(
                solver.positions(),
                solver.velocities(),
                solver.dt(),
                &bonded,
            );
            contact_time += t0.elapsed();
        }
        let (broken, contact, self_stats) = physics_with_contact(
            solver.as_mut(),
            colliders.as_mut(),
            self_contact.as_mut(),
            radii,
            &mut contact_time,
        )?;
        if let Some(sc) = self_contact.as_mut() {
            let t = Instant::now();
            sc.unbond(broken);
            contact_time += t.elapsed();
        }
        let t1 = Instant::now();
        let broken_bonds = broken.len();
        let crack_faces = cut(mesh, broken);
        let t2 = Instant::now();
        mesh.advect(solver.dt(), solver.model().masses(), solver.velocities());
        let t3 = Instant::now();
        times.physics += t1 - t0;
        times.contact += contact_time;
        times.topology += t2 - t1;
        times.advect += t3 - t2;
        let report = StepReport {
            broken_bonds,
            crack_faces,
            contact,
            self_contact: self_stats,
        };
        self.broken_bonds += report.broken_bonds as u64;
        self.self_last = self_stats;
        let deepest = &mut self.self_deepest;
        deepest.pairs = deepest.pairs.max(self_stats.pairs);
        deepest.max_overlap = deepest.max_overlap.max(self_stats.max_overlap);
        deepest.max_overlap_share = deepest.max_overlap_share.max(self_stats.max_overlap_share);
        self.crack_faces += crack_faces as u64;
        Ok(report)
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
            if let Some(c) = self.colliders.as_mut() {
                // The setup made these balls kinematic and in range.
                let _ = c.stop_ball(ball);
            }
            self.next_stop += 1;
        }
    }

    /// Contact between particles, when the scene has it.
    pub fn self_contact(&self) -> Option<&SelfContact> {
        self.self_contact.as_ref()
    }

    /// Self contact over the run so far: the most pairs in contact in one step and the
    /// deepest overlap (m, and as a share of its pair's contact distance); zeros without it.
    pub fn self_contact_deepest(&self) -> SelfContactStats {
        self.self_deepest
    }

    /// Self contact in the last step; zeros without it.
    pub fn self_contact_last(&self) -> SelfContactStats {
        self.self_last
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
        self.colliders.as_ref()
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
        w.bool(self.colliders.is_some());
        if let Some(c) = &self.colliders {
            c.save(w);
        }
        w.bool(self.self_contact.is_some());
        if self.self_contact.is_some() {
            for st in [self.self_deepest, self.self_last] {
                w.usize(st.pairs);
                w.f64(st.max_overlap);
                w.f64(st.max_overlap_share);
            }
        }
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
        // The pair list is derived from positions and bonds: built again at the next step.
        if let Some(sc) = &mut self.self_contact {
            sc.invalidate();
        }
        let has = r.bool("colliders")?;
        match (&mut self.colliders, has) {
            (Some(c), true) => c.restore(r)?,
            (None, false) => {}
            (here, _) => {
                return Err(CheckpointError::Invalid {
                    what: "colliders".into(),
                    message: format!(
                        "the checkpoint {} colliders and this scene {}",
                        if has { "has" } else { "has no" },
                        if here.is_some() { "has" } else { "has none" }
                    ),
                }
                .into())
            }
        }
        let has = r.bool("self contact")?;
        if has != self.self_contact.is_some() {
            return Err(CheckpointError::Invalid {
                what: "self contact".into(),
                message: format!(
                    "the checkpoint {} self contact and this scene {}",
                    if has { "has" } else { "has no" },
                    if has { "has none" } else { "has" }
                ),
            }
            .into());
        }
        if has {
            let mut read = || -> Result<SelfContactStats, CheckpointError> {
                Ok(SelfContactStats {
                    pairs: r.usize("self contact pairs")?,
                    max_overlap: r.f64("self contact overlap")?,
                    max_overlap_share: r.f64("self contact overlap share")?,
                })
            };
            self.self_deepest = read()?;
            self.self_last = read()?;
        }
        Ok(())
    }

    /// Adds frame-output time to the counters.
    pub(crate) fn add_output_time(&mut self, d: Duration) {
        self.times.output += d;
    }
}

/// The solver's bonds as the pair list asks for them: a pair is bonded when its bond is intact,
/// by the per-bond `state` (none: a model without fracture keeps every bond). Damage breaks
/// both directions of a bond together (`perifrac_physics::Damage`), so the direction from `i`
/// tells: no look into the other end's row.
struct FamilyBonds<'a> {
    family: &'a Family,
    state: Option<&'a [u8]>,
}

impl Bonds for FamilyBonds<'_> {
    fn flags(&self, i: u32, candidates: &[u32], out: &mut [u8]) {
        let start = self.family.range(i as usize).start;
        let row = self.family.row(i as usize);
        // The row and the candidates both increase: one walk along the row finds each
        // candidate's bond.
        let mut p = 0;
        for (o, &j) in out.iter_mut().zip(candidates) {
            while p < row.len() && row[p] < j {
                p += 1;
            }
            let bonded =
                p < row.len() && row[p] == j && self.state.is_none_or(|s| s[start + p] != 0);
            *o = u8::from(bonded);
        }
    }
}

/// Stage 1: one step of the particles in the colliders' field and each other's (forces for
/// an explicit step, a potential for an implicit one). Returns the bonds broken in it.
fn physics_with_contact<'a>(
    solver: &'a mut dyn Solver,
    colliders: Option<&mut Colliders>,
    self_contact: Option<&mut SelfContact>,
    radii: &[f64],
    time: &mut Duration,
) -> Result<(Broken<'a>, ContactStats, SelfContactStats), PhysicsError> {
    let mut env = ContactEnvironment {
        colliders,
        self_contact,
        radii,
        stats: ContactStats::default(),
        self_stats: SelfContactStats::default(),
        time: Duration::ZERO,
    };
    let broken = solver.step(&mut env);
    *time += env.time;
    Ok((broken?, env.stats, env.self_stats))
}

/// The colliders and contact between particles as the physics crate's [`Environment`]:
/// contact forces on the particles and the balls' own motion, with the statistics of the step.
struct ContactEnvironment<'a> {
    colliders: Option<&'a mut Colliders>,
    self_contact: Option<&'a mut SelfContact>,
    radii: &'a [f64],
    stats: ContactStats,
    self_stats: SelfContactStats,
    /// Time spent in the explicit contact forces (the implicit step's contact terms are not
    /// timed apart: they are evaluated inside its line search).
    time: Duration,
}

impl Environment for ContactEnvironment<'_> {
    fn add_forces(&mut self, ext: External<'_>) {
        let t0 = Instant::now();
        if let Some(colliders) = self.colliders.as_deref_mut() {
            self.stats = colliders.step(
                ext.dt,
                ext.positions,
                ext.velocities,
                ext.masses,
                self.radii,
                ext.forces,
            );
        }
        if let Some(sc) = self.self_contact.as_deref() {
            self.self_stats = sc.add_forces(
                ext.dt,
                ext.positions,
                ext.velocities,
                ext.masses,
                ext.forces,
            );
        }
        self.time += t0.elapsed();
    }

    fn implicit(&mut self) -> Option<&mut dyn ImplicitEnvironment> {
        Some(self)
    }

    fn save(&self, w: &mut Writer) {
        if let Some(c) = self.colliders.as_deref() {
            c.save(w);
        }
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        match self.colliders.as_deref_mut() {
            Some(c) => c.restore(r),
            None => Ok(()),
        }
    }
}

/// The colliders as an incremental potential: penalty, damping and lagged friction, with the
/// dynamic balls as the step's extra bodies (see `perifrac_contact::Colliders::begin_implicit`).
impl ImplicitEnvironment for ContactEnvironment<'_> {
    fn begin(
        &mut self,
        dt: f64,
        y0: &[Vec3],
        v0: &[Vec3],
        masses: &[f64],
    ) -> Result<(), PhysicsError> {
        let Some(c) = self.colliders.as_deref_mut() else {
            return Ok(());
        };
        c.begin_implicit(dt, y0, v0, masses, self.radii)
            .map_err(|e| PhysicsError::BadSetting(format!("contact: {e}")))
    }

    fn bodies(&self) -> usize {
        self.colliders.as_deref().map_or(0, |c| c.implicit_bodies())
    }

    fn body_guess(&self, out: &mut [Vec3]) {
        if let Some(c) = self.colliders.as_deref() {
            out.copy_from_slice(c.implicit_body_targets());
        }
    }

    fn body_curvature(&self, out: &mut [f64]) {
        if let Some(c) = self.colliders.as_deref() {
            out.copy_from_slice(c.implicit_body_diagonal());
        }
    }

    fn potential(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        let (mut gq, gc) = match grad {
            Some((gq, gc)) => (Some(gq), Some(gc)),
            None => (None, None),
        };
        let mut energy = 0.0;
        if let Some(col) = self.colliders.as_deref_mut() {
            energy += col.implicit_potential(q, c, gq.as_deref_mut().zip(gc));
        }
        if let Some(sc) = self.self_contact.as_deref_mut() {
            energy += sc.potential(q, gq);
        }
        energy
    }

    fn end(&mut self, q: &[Vec3], c: &[Vec3], v: &[Vec3]) {
        if let Some(col) = self.colliders.as_deref_mut() {
            self.stats = col.end_implicit(q, c, v);
        }
        if let Some(sc) = self.self_contact.as_deref() {
            self.self_stats = sc.stats_at(q);
        }
    }

    fn particle_curvature(&mut self, y0: &[Vec3], out: &mut [f64]) {
        match self.colliders.as_deref_mut() {
            Some(col) => {
                let c = col.implicit_body_start();
                col.implicit_stiffness_hint(y0, c, out);
            }
            None => out.fill(0.0),
        }
        if let Some(sc) = self.self_contact.as_deref() {
            sc.curvature_hint(y0, out);
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Scene, Setup};

    /// The walk along the row gives what asking both directions pair by pair gives, with
    /// broken bonds and without.
    #[test]
    fn family_bonds_match_the_pairwise_answer() {
        let text = "[mesh]\nprimitive = \"box\"\nsize = [0.04, 0.04, 0.04]\ncells = [4, 4, 4]\n\n\
                    [[material]]\nyoung = 1e7\npoisson = 0.25\ndensity = 1000.0\n\n\
                    [simulation]\nduration = 1e-4\n";
        let scene = Scene::parse(text, std::path::Path::new("t.toml")).unwrap();
        let setup = Setup::new(&scene, None).unwrap();
        let family = setup.driver.solver().model().discretization().family();
        let n = family.len() as u32;
        // A third of the bonds broken, both directions together as damage breaks them.
        let state: Vec<u8> = (0..family.len())
            .flat_map(|i| {
                family
                    .row(i)
                    .iter()
                    .map(move |&j| u8::from(!(i as u32 + j).is_multiple_of(3)))
            })
            .collect();
        let pairwise = |state: Option<&[u8]>, i: u32, j: u32| {
            let one_way = |a: u32, b: u32| {
                let range = family.range(a as usize);
                match family.row(a as usize).binary_search(&b) {
                    Ok(k) => state.is_none_or(|s| s[range.start + k] != 0),
                    Err(_) => false,
                }
            };
            one_way(i, j) && one_way(j, i)
        };
        let (mut bonded, mut broken) = (0, 0);
        for state in [None, Some(&state[..])] {
            let bonds = FamilyBonds { family, state };
            for i in 0..n {
                // Every particle but itself, in increasing order.
                let candidates: Vec<u32> = (0..n).filter(|&j| j != i).collect();
                let mut out = vec![9u8; candidates.len()];
                bonds.flags(i, &candidates, &mut out);
                for (&j, &o) in candidates.iter().zip(&out) {
                    let want = pairwise(state, i, j);
                    assert_eq!(o, u8::from(want), "{i} {j}");
                    if want {
                        bonded += 1;
                    } else if family.row(i as usize).contains(&j) {
                        broken += 1;
                    }
                }
            }
        }
        assert!(bonded > 0 && broken > 0, "{bonded} {broken}");
    }
}
