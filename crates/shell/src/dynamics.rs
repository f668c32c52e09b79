//! Time stepping of a shell: explicit (Newmark with `beta = 0`, `gamma = 1/2`: velocity
//! Verlet) by default, with the estimate of its stable step, or implicit Newmark
//! ([`newmark`], the paper's production integrator) when set.

mod loads;
mod newmark;
pub use loads::ShellLoad;
pub use newmark::{NewmarkConfig, NewmarkStats};

use hashbrown::HashMap;
use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_contact::{Colliders, ContactStats};

use crate::error::ShellError;
use crate::fracture::FractureReport;
use crate::model::ShellModel;
use crate::self_contact::{PairKey, SelfContact, SelfContactStats, ShellSelfContact};
use perifrac_physics::lanczos_frequency_of;
use perifrac_physics::math::{add, axpy, dot, norm, scale, sub, Vec3};
use perifrac_physics::stable_step::{LANCZOS_ITERATIONS, LANCZOS_TOLERANCE};

/// What a trial step can change, kept to undo it: buffers reused from trial to trial.
#[derive(Debug, Clone, Default)]
pub(crate) struct Snapshot {
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    f: Vec<Vec3>,
    ps: Vec<[f64; 3]>,
    pphi: Vec<[f64; 3]>,
    elastic: f64,
    self_energy: f64,
    time: f64,
    /// The implicit step's accelerations (empty when explicit).
    acc: Vec<Vec3>,
    /// The contact radii (a step regrows forgiven ones).
    radii: Vec<f64>,
    /// The loads' work (J).
    load_work: f64,
    /// Self-contact's forgiven overlaps (a step regrows them).
    forgiven: HashMap<PairKey, f64>,
    /// The colliders' moving state (balls).
    colliders: Writer,
}

/// A shell moving under its elastic forces, gravity, pinned vertices, colliders and (when set)
/// its own pieces' repulsion, stepped explicitly, or by implicit Newmark when
/// [`ShellDynamics::set_newmark`] says so.
#[derive(Debug, Clone)]
pub struct ShellDynamics {
    model: ShellModel,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    f: Vec<Vec3>,
    pinned: Vec<bool>,
    gravity: Vec3,
    damping: f64,
    elastic: f64,
    time: f64,
    /// Ground planes and balls the vertices touch, with each vertex's contact radius (m).
    colliders: Option<Colliders>,
    /// Each vertex's contact radius (m): `contact_radius`, or less while a fracture round's
    /// overlap is forgiven ([`Self::forgive_overlaps`]).
    radii: Vec<f64>,
    /// The vertices' contact radius (m): half the thickness.
    contact_radius: f64,
    /// Each vertex's reference mass for contact (kg): its mass when the colliders were set;
    /// a vertex fracture adds takes its sources' mean. A vertex's penalty stiffness is the
    /// colliders' times its mass over this, so it follows the vertex's share of the surface.
    contact_mass: Vec<f64>,
    contact: ContactStats,
    /// Wall time spent in the colliders' contact pass, all steps (s).
    collider_seconds: f64,
    /// Each vertex's penetration into the colliders before a fracture round (m; reused).
    depths: Vec<f64>,
    /// Repulsion between the shell's own pieces, when set.
    self_contact: Option<SelfContact>,
    /// Its penalty energy at the current positions (J).
    self_energy: f64,
    /// The implicit Newmark solver, when set.
    newmark: Option<Box<newmark::Newmark>>,
    /// Counts changes of the mesh and of the held set (the implicit step's matrix follows it).
    topology: u64,
    /// Forces from outside (tractions, pressures, body forces) and their work.
    loads: loads::Loads,
}

impl ShellDynamics {
    /// The shell at rest at its mesh's vertices, at time 0, without gravity.
    pub fn new(mut model: ShellModel) -> Result<ShellDynamics, ShellError> {
        let x = model.mesh().vertices().to_vec();
        let n = x.len();
        let mut f = vec![[0.0; 3]; n];
        let elastic = model.forces(&x, &mut f)?;
        Ok(ShellDynamics {
            model,
            x,
            v: vec![[0.0; 3]; n],
            f,
            pinned: vec![false; n],
            gravity: [0.0; 3],
            damping: 0.0,
            elastic,
            time: 0.0,
            colliders: None,
            radii: Vec::new(),
            contact_radius: 0.0,
            contact_mass: Vec::new(),
            contact: ContactStats::default(),
            collider_seconds: 0.0,
            depths: Vec::new(),
            self_contact: None,
            self_energy: 0.0,
            newmark: None,
            topology: 0,
            loads: loads::Loads::default(),
        })
    }

    /// The model.
    pub fn model(&self) -> &ShellModel {
        &self.model
    }

    /// The model, to query at other positions (its force buffers change).
    pub fn model_mut(&mut self) -> &mut ShellModel {
        &mut self.model
    }

    /// Copies the state a step changes into `s` (no allocation once its buffers fit).
    pub(crate) fn save(&self, s: &mut Snapshot) {
        s.x.clone_from(&self.x);
        s.v.clone_from(&self.v);
        s.f.clone_from(&self.f);
        self.model.save_plastic(&mut s.ps, &mut s.pphi);
        s.elastic = self.elastic;
        s.self_energy = self.self_energy;
        s.time = self.time;
        s.load_work = self.loads.work;
        match &self.newmark {
            Some(nm) => s.acc.clone_from(&nm.acc),
            None => s.acc.clear(),
        }
        s.radii.clone_from(&self.radii);
        match &self.self_contact {
            Some(sc) => s.forgiven.clone_from(sc.forgiven()),
            None => s.forgiven.clear(),
        }
        s.colliders.clear();
        if let Some(c) = &self.colliders {
            c.save(&mut s.colliders);
        }
    }

    /// Puts back what [`ShellDynamics::save`] kept (the mesh must not have changed between).
    pub(crate) fn restore(&mut self, s: &Snapshot) {
        self.x.clone_from(&s.x);
        self.v.clone_from(&s.v);
        self.f.clone_from(&s.f);
        self.model.restore_plastic(&s.ps, &s.pphi);
        self.elastic = s.elastic;
        self.self_energy = s.self_energy;
        self.time = s.time;
        self.loads.work = s.load_work;
        if let Some(nm) = &mut self.newmark {
            nm.acc.clone_from(&s.acc);
        }
        self.radii.clone_from(&s.radii);
        if let Some(sc) = &mut self.self_contact {
            sc.set_forgiven(&s.forgiven);
        }
        if let Some(c) = &mut self.colliders {
            // Saved from these very colliders a moment ago: it reads back.
            let _ = c.restore(&mut Reader::new(s.colliders.bytes()));
        }
    }

    /// Writes for a checkpoint what steps and fracture change (the model, positions,
    /// velocities, forces, held vertices, time, the colliders' state, each vertex's contact
    /// radius and reference mass, self contact's forgiven overlaps, and under Newmark its
    /// accelerations, counts and kept factors of the step matrix), between steps.
    pub fn write_checkpoint(&self, w: &mut Writer) {
        w.tag("shell dynamics");
        self.model.write_checkpoint(w);
        w.array(&self.x);
        w.array(&self.v);
        w.array(&self.f);
        let pinned: Vec<u8> = self.pinned.iter().map(|&p| u8::from(p)).collect();
        w.array(&pinned);
        w.f64(self.elastic);
        w.f64(self.time);
        w.f64(self.self_energy);
        w.f64(self.loads.work);
        w.u64(self.topology);
        w.array(&self.radii);
        w.array(&self.contact_mass);
        w.bool(self.colliders.is_some());
        if let Some(c) = &self.colliders {
            c.save(w);
        }
        w.bool(self.self_contact.is_some());
        if let Some(sc) = &self.self_contact {
            sc.write_checkpoint(w);
        }
        w.bool(self.newmark.is_some());
        if let Some(nm) = &self.newmark {
            nm.write_checkpoint(w, self.topology, &self.pinned);
        }
    }

    /// Reads what [`ShellDynamics::write_checkpoint`] wrote into a shell built from the same
    /// scene.
    pub fn read_checkpoint(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        let invalid = |message: String| CheckpointError::Invalid {
            what: "shell dynamics".into(),
            message,
        };
        r.tag("shell dynamics")?;
        self.model.read_checkpoint(r)?;
        let n = self.model.mesh().num_vertices();
        let mut pinned = Vec::<u8>::new();
        r.array_vec("shell positions", &mut self.x)?;
        r.array_vec("shell velocities", &mut self.v)?;
        r.array_vec("shell forces", &mut self.f)?;
        r.array_vec("held vertices", &mut pinned)?;
        for (what, len) in [
            ("positions", self.x.len()),
            ("velocities", self.v.len()),
            ("forces", self.f.len()),
            ("held flags", pinned.len()),
        ] {
            if len != n {
                return Err(invalid(format!("{len} {what} for {n} vertices")));
            }
        }
        self.pinned = pinned.iter().map(|&p| p != 0).collect();
        self.elastic = r.f64("elastic energy")?;
        self.time = r.f64("time")?;
        self.self_energy = r.f64("self-contact energy")?;
        self.loads.work = r.f64("work of the loads")?;
        self.topology = r.u64("mesh changes")?;
        r.array_vec("contact radii", &mut self.radii)?;
        r.array_vec("contact reference masses", &mut self.contact_mass)?;
        if r.bool("colliders")? != self.colliders.is_some() {
            return Err(invalid(
                "colliders where the scene has none, or none where it has".into(),
            ));
        }
        if let Some(c) = &mut self.colliders {
            if self.radii.len() != n || self.contact_mass.len() != n {
                return Err(invalid(format!(
                    "{} contact radii for {n} vertices",
                    self.radii.len()
                )));
            }
            c.restore(r)?;
        }
        self.scale_contact().map_err(|e| invalid(e.to_string()))?;
        if r.bool("self contact")? != self.self_contact.is_some() {
            return Err(invalid(
                "self contact where the scene has none, or none where it has".into(),
            ));
        }
        if let Some(sc) = &mut self.self_contact {
            sc.read_checkpoint(r)?;
        }
        if r.bool("Newmark stepping")? != self.newmark.is_some() {
            return Err(invalid(
                "stepped by Newmark where the scene steps explicitly, or the other way".into(),
            ));
        }
        if let Some(nm) = &mut self.newmark {
            nm.read_checkpoint(r, self.model.mesh(), self.topology, &self.pinned)?;
        }
        Ok(())
    }

    /// The largest fracture ratio at the current positions (see
    /// [`ShellModel::worst_fracture_ratio`]).
    pub fn worst_fracture_ratio(&mut self) -> Result<f64, ShellError> {
        self.model.worst_fracture_ratio(&self.x)
    }

    /// The largest force (N) on any free vertex at the current positions.
    pub fn largest_force(&self) -> f64 {
        self.f
            .iter()
            .zip(&self.pinned)
            .filter(|(_, &p)| !p)
            .map(|(f, _)| dot(*f, *f))
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// Vertex positions (m).
    pub fn positions(&self) -> &[Vec3] {
        &self.x
    }

    /// Vertex velocities (m/s).
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }

    /// Vertex velocities to set (m/s); pinned and driven vertices keep theirs when stepped.
    pub fn velocities_mut(&mut self) -> &mut [Vec3] {
        &mut self.v
    }

    /// Moves the vertices to `x` (m) and evaluates the forces there (elastic and self-contact;
    /// the colliders' come with the next step).
    pub fn set_positions(&mut self, x: &[Vec3]) -> Result<(), ShellError> {
        if x.len() != self.x.len() {
            return Err(ShellError::LengthMismatch {
                what: "shell positions",
                expected: self.x.len(),
                got: x.len(),
            });
        }
        self.x.copy_from_slice(x);
        self.internal_forces()
    }

    /// The elastic forces and self-contact's at the current positions, into `f`.
    fn internal_forces(&mut self) -> Result<(), ShellError> {
        self.elastic = self.model.forces(&self.x, &mut self.f)?;
        self.add_self_contact()
    }

    /// Adds self-contact's forces at the current positions into `f`.
    fn add_self_contact(&mut self) -> Result<(), ShellError> {
        self.self_energy = match &mut self.self_contact {
            Some(sc) => sc.add_forces(self.model.mesh(), &self.x, &mut self.f)?,
            None => 0.0,
        };
        Ok(())
    }

    /// Turns repulsion between the shell's own pieces on with `params` (or off with `None`)
    /// and evaluates the forces at the current positions, as
    /// [`ShellDynamics::set_positions`] does (the colliders' come back with the next step).
    /// Off by default: a shell without it spends nothing on it.
    pub fn set_self_contact(&mut self, params: Option<ShellSelfContact>) -> Result<(), ShellError> {
        self.self_contact = match params {
            Some(p) => Some(SelfContact::new(p, self.model.material())?),
            None => None,
        };
        self.internal_forces()
    }

    /// Self-contact, when set.
    pub fn self_contact(&self) -> Option<&SelfContact> {
        self.self_contact.as_ref()
    }

    /// What self-contact found and cost in its last evaluation and in all (zeros when off).
    pub fn self_contact_stats(&self) -> SelfContactStats {
        self.self_contact
            .as_ref()
            .map(SelfContact::stats)
            .unwrap_or_default()
    }

    /// Self-contact's penalty energy (J) at the current positions (0 when off).
    pub fn self_contact_energy(&self) -> f64 {
        self.self_energy
    }

    /// Gravity (m/s^2) on every vertex.
    pub fn set_gravity(&mut self, g: Vec3) {
        self.gravity = g;
    }

    /// Mass-proportional damping `c` (1/s, >= 0): each kick of `h` divides the velocity by
    /// `1 + c h` after adding the force's impulse.
    pub fn set_damping(&mut self, c: f64) -> Result<(), ShellError> {
        if !(c.is_finite() && c >= 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell damping (1/s)",
                expected: "finite and >= 0",
                value: c,
            });
        }
        self.damping = c;
        Ok(())
    }

    /// Lets the vertices touch `colliders` (ground planes, balls) as spheres of `radius` (m;
    /// the paper's repulsion band is half the thickness). Refuses a vertex that starts inside
    /// a collider.
    pub fn set_colliders(&mut self, colliders: Colliders, radius: f64) -> Result<(), ShellError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell contact radius (m)",
                expected: "finite and > 0",
                value: radius,
            });
        }
        self.radii = vec![radius; self.x.len()];
        self.contact_radius = radius;
        self.contact_mass = self.model.masses().to_vec();
        let mut colliders = colliders;
        // Every vertex at the colliders' stiffness until fracture divides its surface.
        colliders
            .set_stiffness_scale(Vec::new())
            .map_err(|cause| ShellError::Contact(cause.to_string()))?;
        colliders
            .check_clear(&self.x, &self.radii)
            .map_err(|cause| ShellError::Contact(cause.to_string()))?;
        self.colliders = Some(colliders);
        Ok(())
    }

    /// The colliders, when set.
    pub fn colliders(&self) -> Option<&Colliders> {
        self.colliders.as_ref()
    }

    /// What contact found in the last step.
    pub fn contact_stats(&self) -> ContactStats {
        self.contact
    }

    /// Wall time (s) spent in the colliders' contact pass over every step so far, discarded
    /// trials included (0 without colliders).
    pub fn collider_seconds(&self) -> f64 {
        self.collider_seconds
    }

    /// Holds vertex `i` where it is (and at rest) from now on.
    pub fn pin(&mut self, i: usize) {
        self.drive(i, [0.0; 3]);
    }

    /// Moves vertex `i` at the constant `velocity` (m/s) from now on, whatever pulls on it.
    pub fn drive(&mut self, i: usize, velocity: Vec3) {
        if let Some(p) = self.pinned.get_mut(i) {
            if !*p {
                self.topology += 1;
            }
            *p = true;
            self.v[i] = velocity;
        }
    }

    /// Sets the loads on the vertices (replacing any), each checked against the vertex count.
    pub fn set_loads(&mut self, loads: Vec<ShellLoad>) -> Result<(), ShellError> {
        for l in &loads {
            l.check(self.x.len())?;
        }
        self.loads.loads = loads;
        Ok(())
    }

    /// The work (J) the loads have done so far.
    pub fn load_work(&self) -> f64 {
        self.loads.work
    }

    /// The forces (N) on each vertex at the current positions: elastic, contact and
    /// self-contact, without gravity or damping. A held vertex's holder supplies their
    /// opposite.
    pub fn forces(&self) -> &[Vec3] {
        &self.f
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Elastic energy (J) at the current positions.
    pub fn elastic_energy(&self) -> f64 {
        self.elastic
    }

    /// Kinetic energy (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.model
            .masses()
            .iter()
            .zip(&self.v)
            .map(|(m, v)| 0.5 * m * dot(*v, *v))
            .sum()
    }

    /// Potential energy of gravity (J), zero at the origin.
    pub fn gravity_energy(&self) -> f64 {
        self.model
            .masses()
            .iter()
            .zip(&self.x)
            .map(|(m, x)| -m * dot(self.gravity, *x))
            .sum()
    }

    /// Steps implicitly by Newmark with `config` from now on, or explicitly again with `None`.
    pub fn set_newmark(&mut self, config: Option<NewmarkConfig>) -> Result<(), ShellError> {
        self.newmark = match config {
            Some(c) => Some(Box::new(newmark::Newmark::new(c)?)),
            None => None,
        };
        Ok(())
    }

    /// The implicit step's settings, when it is on.
    pub fn newmark(&self) -> Option<NewmarkConfig> {
        self.newmark.as_ref().map(|nm| nm.config())
    }

    /// Caps the implicit solves of the next steps at `cap` iterations (below the settings' own
    /// cap), or lifts that with `None`; nothing for an explicit shell. The event search caps
    /// its trials so.
    pub fn set_solve_cap(&mut self, cap: Option<usize>) {
        if let Some(nm) = &mut self.newmark {
            nm.trial_cap = cap;
        }
    }

    /// Whether the last step was implicit and its solve stopped at the iteration cap.
    pub fn last_solve_capped(&self) -> bool {
        self.newmark.as_ref().is_some_and(|nm| nm.last_capped)
    }

    /// What the implicit steps did so far (zeros when explicit).
    pub fn newmark_stats(&self) -> NewmarkStats {
        self.newmark.as_ref().map(|nm| nm.stats).unwrap_or_default()
    }

    /// One step of `dt` (s). Explicit: half kick, drift, forces (elastic, colliders,
    /// self-contact), half kick. Implicit: see [`NewmarkConfig`].
    pub fn step(&mut self, dt: f64) -> Result<(), ShellError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell time step (s)",
                expected: "finite and > 0",
                value: dt,
            });
        }
        if self.newmark.is_some() {
            self.loads.remember(&self.x);
            self.newmark_step(dt)?;
            self.loads.step_work(self.time, &self.x);
            self.regrow_bands();
            return Ok(());
        }
        // The loads' half kicks come first: the damping then scales them with the rest.
        let (masses, pinned) = (self.model.masses(), &self.pinned);
        self.loads
            .kick(self.time, 0.5 * dt, &mut self.v, masses, pinned);
        self.kick(0.5 * dt);
        self.loads.drift_work(self.time, dt, &self.v);
        for (x, v) in self.x.iter_mut().zip(&self.v) {
            *x = axpy(*x, dt, *v);
        }
        self.elastic = self.model.forces(&self.x, &mut self.f)?;
        if let Some(c) = &mut self.colliders {
            let started = std::time::Instant::now();
            self.contact = c.step(
                dt,
                &self.x,
                &self.v,
                self.model.masses(),
                &self.radii,
                &mut self.f,
            );
            self.collider_seconds += started.elapsed().as_secs_f64();
        }
        self.add_self_contact()?;
        let (masses, pinned) = (self.model.masses(), &self.pinned);
        self.loads
            .kick(self.time + dt, 0.5 * dt, &mut self.v, masses, pinned);
        self.kick(0.5 * dt);
        self.time += dt;
        self.regrow_bands();
        if !(self.elastic.is_finite() && self.self_energy.is_finite()) {
            return Err(ShellError::RanAway { time: self.time });
        }
        Ok(())
    }

    fn kick(&mut self, h: f64) {
        let g = self.gravity;
        let keep = 1.0 / (1.0 + self.damping * h);
        for (((v, f), &m), &p) in self
            .v
            .iter_mut()
            .zip(&self.f)
            .zip(self.model.masses())
            .zip(&self.pinned)
        {
            if !p {
                *v = scale(axpy(axpy(*v, h / m, *f), h, g), keep);
            }
        }
    }

    /// Breaks every triangle over its threshold now (see [`ShellModel::fracture`]): vertices
    /// added take their sources' pins (a point on an edge is pinned when both ends are), and
    /// the forces (elastic and self-contact) are evaluated on the new mesh.
    pub fn fracture(&mut self) -> Result<FractureReport, ShellError> {
        // Most calls find nothing over its threshold: one pass, and back.
        if self.model.worst_fracture_ratio(&self.x)? <= 1.0 {
            return Ok(FractureReport::default());
        }
        // With colliders, each vertex's penetration before the round (with its own contact
        // radius): a vertex the round puts on a chord of the surface wrapped round a ball (or
        // budges onto one) presses no deeper than it, or its sources, did.
        if let Some(c) = &self.colliders {
            self.depths.clear();
            self.depths.extend(
                self.x
                    .iter()
                    .zip(&self.radii)
                    .map(|(p, &r)| c.penetration(*p, r)),
            );
        }
        if let Some(sc) = &mut self.self_contact {
            sc.begin_edit();
        }
        let report = self.model.fracture(&mut self.x, &mut self.v)?;
        if !report.changed {
            return Ok(report);
        }
        self.topology += 1;
        for src in &report.added {
            let (a, b) = (src[0] as usize, src[1] as usize);
            let pinned = self.pinned[a] && self.pinned[b];
            self.pinned.push(pinned);
            // An implicit shell's new vertex starts with its sources' mean acceleration (a
            // point on an edge between them).
            if let Some(nm) = &mut self.newmark {
                if let (Some(&aa), Some(&ab)) = (nm.acc.get(a), nm.acc.get(b)) {
                    nm.acc.push(scale(add(aa, ab), 0.5));
                }
            }
            if self.colliders.is_some() {
                self.radii.push(self.contact_radius);
                let m = 0.5 * (self.contact_mass[a] + self.contact_mass[b]);
                self.contact_mass.push(m);
                // A vertex added may come from one added before it in the same round.
                let allowed = self.depths[a].max(self.depths[b]);
                self.depths.push(allowed);
            }
        }
        self.scale_contact()?;
        self.forgive_overlaps();
        self.f.resize(self.x.len(), [0.0; 3]);
        // A round that only released stress beside cracks already there leaves the triangles
        // and the rest positions as they were: the self-contact list stays good (rebuilding
        // it then was most of the 1e-4 punctured sheet's 10,584 list builds).
        if !(report.events.is_empty() && report.added.is_empty()) {
            if let Some(sc) = &mut self.self_contact {
                sc.invalidate();
            }
        }
        self.internal_forces()?;
        Ok(report)
    }

    /// After a fracture round: a vertex now deeper in a collider than `depths` allows (its own
    /// depth, or its sources', before the round) has its contact radius shrunk by the excess,
    /// so the round stores no energy. A new point on a chord of a sheet wrapped round a ball
    /// lies inside the ball by the chord's sagitta (0.56 mm for an 8.3 mm edge round the
    /// punctured sheet's ball); pushed out to the allowed depth, its triangles took the
    /// sagitta as strain (0.2 J, against 1e-6 J in the whole sheet), and under the penalty
    /// the overlap's energy shot it out. Only when the radius would fall below minus half the
    /// smallest ball's (a depth no chord reaches; 0 under Newmark, whose implicit contact
    /// takes no negative radius) is the rest pushed out, and a held vertex never.
    fn forgive_overlaps(&mut self) {
        let Some(c) = &self.colliders else {
            return;
        };
        // The implicit contact takes no negative radius; the explicit one no reach past a
        // ball's centre.
        let floor = match (
            self.newmark.is_some(),
            c.balls().map(|b| b.radius).reduce(f64::min),
        ) {
            (false, Some(smallest)) => -0.5 * smallest,
            _ => 0.0,
        };
        let held = &self.pinned;
        for (((p, r), &allowed), &held) in self
            .x
            .iter_mut()
            .zip(&mut self.radii)
            .zip(&self.depths)
            .zip(held)
        {
            let excess = c.penetration(*p, *r) - allowed;
            if excess > 0.0 {
                *r = (*r - excess).max(floor);
                if !held {
                    *p = c.push_out(*p, *r, allowed);
                }
            }
        }
    }

    /// After a step: grows the contact radii that [`Self::forgive_overlaps`] shrank back
    /// towards the full radius as far as each vertex's clearance from every collider allows
    /// (so no contact starts deeper than it was), and self contact's forgiven bands likewise
    /// ([`SelfContact::regrow`]).
    fn regrow_bands(&mut self) {
        if let Some(sc) = &mut self.self_contact {
            sc.regrow();
        }
        let Some(c) = &self.colliders else {
            return;
        };
        let full = self.contact_radius;
        for (p, r) in self.x.iter().zip(&mut self.radii) {
            if *r < full {
                let clear = c.clearance(*p, *r);
                if clear > 0.0 {
                    *r = (*r + clear).min(full);
                }
            }
        }
    }

    /// Gives each vertex the colliders' stiffness times its mass over its reference mass, after
    /// fracture changed the masses: a crack through a vertex in contact divides its stiffness
    /// among the copies as it divides its mass. With one stiffness for all, each copy pressed
    /// as hard as the whole vertex had (the contact force under a ball grew with every crack
    /// through it), and a copy a tenth as heavy was shot out by the overlap's energy (chips
    /// of the punctured sheet left at 35 m/s).
    fn scale_contact(&mut self) -> Result<(), ShellError> {
        let Some(c) = &mut self.colliders else {
            return Ok(());
        };
        let scale: Vec<f64> = self
            .model
            .masses()
            .iter()
            .zip(&self.contact_mass)
            .map(|(&m, &m0)| if m0 > 0.0 { m / m0 } else { 1.0 })
            .collect();
        c.set_stiffness_scale(scale)
            .map_err(|cause| ShellError::Contact(cause.to_string()))
    }

    /// The stable step (s) at the current positions: `2 / omega` with `omega^2` the highest
    /// squared angular frequency of the elastic forces ([`max_frequency`]) plus what the
    /// colliders add ([`ShellDynamics::collider_omega2`]). Fracture adds light vertices, so
    /// both grow after splits: measure again after them.
    pub fn stable_step(&mut self) -> Result<f64, ShellError> {
        let x = self.x.clone();
        let w = max_frequency(&mut self.model, &x)?;
        if w.is_finite() && w > 0.0 {
            Ok(2.0 / (w * w + self.collider_omega2()).sqrt())
        } else {
            Err(ShellError::NoFrequency { omega: w })
        }
    }

    /// What the colliders add to the highest squared angular frequency (1/s^2): their
    /// stiffnesses summed (a vertex touching every one at once) over the lightest free
    /// vertex's reference mass (its stiffness and its mass shrink together when fracture
    /// divides it); 0 without colliders.
    pub fn collider_omega2(&self) -> f64 {
        let Some(c) = &self.colliders else {
            return 0.0;
        };
        let lightest = self
            .contact_mass
            .iter()
            .zip(&self.pinned)
            .filter(|(_, &p)| !p)
            .map(|(&m, _)| m)
            .fold(f64::INFINITY, f64::min);
        if lightest.is_finite() && lightest > 0.0 {
            c.stiffness_sum() / lightest
        } else {
            0.0
        }
    }
}

/// The highest angular frequency (rad/s) of the shell linearised at `x` (m): Lanczos on
/// `M^-1 K` with `K v` from one-sided differences of the forces
/// ([`perifrac_physics::lanczos_frequency_of`], with the solids' iteration cap and tolerance).
/// Pinned vertices are treated as free, which can only raise the estimate: the step stays safe.
pub fn max_frequency(model: &mut ShellModel, x: &[Vec3]) -> Result<f64, ShellError> {
    let masses = model.masses().to_vec();
    model.check_positions(x.len())?;
    let shortest = model
        .mesh()
        .edges()
        .iter()
        .map(|e| norm(sub(x[e.v[1] as usize], x[e.v[0] as usize])))
        .fold(f64::INFINITY, f64::min);
    let est = lanczos_frequency_of(
        &masses,
        x,
        shortest,
        LANCZOS_ITERATIONS,
        LANCZOS_TOLERANCE,
        &mut |y: &[Vec3], f: &mut [Vec3]| {
            // The lengths were checked above, so the evaluation cannot fail; the plastic
            // state is not return-mapped at the probe's positions.
            let _ = model.frozen_forces(y, f);
        },
        None,
    );
    Ok(est.omega_max)
}
