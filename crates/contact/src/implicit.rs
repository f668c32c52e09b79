//! Contact as an incremental potential for an implicit (backward-Euler-like) step.
//!
//! The integrator minimises, per step of length `dt`, over the particles' end positions `q` and
//! the dynamic balls' end centres `c`,
//!
//! `Phi(q, c) = sum_i m_i / (2 dt^2) |q_i - q*_i|^2 + E_material(q) + P(q, c)`.
//!
//! [`Colliders::implicit_potential`] is `P`: the dynamic balls' own inertia
//! `sum_b M_b / (2 dt^2) |c_b - c*_b|^2` (`c* = c_n + dt v_n + dt^2 g`), the elastic penalty
//! `k d^2 / 2` of every pair penetrating at the trial state, and, for the pairs in contact at
//! the start, damping and Coulomb friction as lagged dissipative potentials (as in
//! incremental-potential contact, Li et al. 2020). `incremental.rs` holds the per-pair
//! terms; [`Colliders::begin_implicit`] gives the call order.

use crate::colliders::{ball_ground_coeffs, BallBody, Colliders, Ground};
use crate::error::ContactError;
use crate::incremental::{dissipation, elastic, Lagged};
use crate::kernel::{ball_normal, scale_of, Coeffs};
use crate::math::{add, add_assign, dot, is_finite, scale, sub, to_parry};
use crate::step::{ContactStats, CHUNK};
use crate::Vec3;
use rayon::prelude::*;

/// A particle-collider pair in contact at the start of the step.
#[derive(Debug, Clone, Copy)]
struct ParticlePair {
    particle: usize,
    /// `None`: a ground plane; `Some(j)`: ball `j`.
    ball: Option<usize>,
    /// The particle's start position (m).
    y0: Vec3,
    lag: Lagged,
}

/// A dynamic ball-ground pair in contact at the start of the step.
#[derive(Debug, Clone, Copy)]
struct BodyGroundPair {
    body: usize,
    lag: Lagged,
}

/// The first unusable particle value of a chunk.
#[derive(Debug, Clone, Copy)]
struct Bad {
    particle: usize,
    what: &'static str,
    expected: &'static str,
    value: f64,
}

/// The lagged data of the current implicit step and the buffers its evaluations reuse. Grown,
/// never shrunk: no allocation once they fit the particle count.
#[derive(Debug, Clone, Default)]
pub(crate) struct ImplicitState {
    /// Between `begin_implicit` and `end_implicit`.
    active: bool,
    dt: f64,
    particles: usize,
    /// User-set slip velocity (m/s); `None`: [`Colliders::IMPLICIT_SLIP_FRACTION`] of a radius.
    slip_velocity: Option<f64>,
    /// Contact radii (m) of the step's particles.
    radius: Vec<f64>,
    /// Per ball: body index of a dynamic ball.
    ball_body: Vec<Option<usize>>,
    /// Per ball: centre at t_n (m).
    start: Vec<Vec3>,
    /// Per ball: end centre (m); kinematic `c_n + dt v`, dynamic the latest trial `c`.
    centre: Vec<Vec3>,
    /// Per body: its ball index, mass (kg), start centre and inertia target (m), diagonal (N/m).
    body_ball: Vec<usize>,
    body_mass: Vec<f64>,
    body_start: Vec<Vec3>,
    body_target: Vec<Vec3>,
    body_diag: Vec<f64>,
    body_ground: Vec<BodyGroundPair>,
    /// Per chunk: the lagged pairs of its particles, in particle then collider order.
    pairs: Vec<Vec<ParticlePair>>,
    /// Per chunk: energy (J), statistics, first bad value.
    energy: Vec<f64>,
    stats: Vec<ContactStats>,
    bad: Vec<Option<Bad>>,
    /// `part[c * stride + j]`: sum over chunk `c`'s particles of `dP/dq` of their pairs with
    /// ball `j` (N), i.e. the force they exert on the ball; `part_k` the same for stiffness.
    stride: usize,
    part: Vec<Vec3>,
    part_k: Vec<f64>,
}

impl ImplicitState {
    fn prepare(&mut self, chunks: usize, balls: usize) {
        self.stride = balls.max(1);
        if self.pairs.len() < chunks {
            self.pairs.resize_with(chunks, Vec::new);
            self.energy.resize(chunks, 0.0);
            self.stats.resize(chunks, ContactStats::default());
            self.bad.resize(chunks, None);
        }
        if self.part.len() < chunks * self.stride {
            self.part.resize(chunks * self.stride, [0.0; 3]);
            self.part_k.resize(chunks * self.stride, 0.0);
        }
    }

    /// Friction smoothing displacement (m, > 0) for a pair of size `size` (m) that starts at
    /// penetration `d0` > 0 (m).
    fn eps(&self, size: f64, d0: f64) -> f64 {
        let e = match self.slip_velocity {
            Some(v) => v * self.dt,
            None => Colliders::IMPLICIT_SLIP_FRACTION * size.max(d0),
        };
        e.max(f64::MIN_POSITIVE)
    }

    fn reaction(&self, ball: usize, chunks: usize) -> Vec3 {
        let mut r = [0.0; 3];
        for c in 0..chunks {
            add_assign(&mut r, self.part[c * self.stride + ball]);
        }
        r
    }

    fn chunks(&self) -> usize {
        self.particles.div_ceil(CHUNK)
    }
}

fn merge(a: &mut ContactStats, o: &ContactStats) {
    a.contacts += o.contacts;
    a.ball_ground_contacts += o.ball_ground_contacts;
    a.max_penetration = a.max_penetration.max(o.max_penetration);
}

impl Colliders {
    /// Default friction smoothing (dimensionless): the static regime of friction covers slips
    /// below this fraction of the particle's contact radius per step (the ball's radius for a
    /// ball on the ground), `eps = 1e-3 r`, i.e. a slip velocity `eps_v = 1e-3 r / dt`.
    ///
    /// Why a fraction of a radius per step rather than a fixed velocity: the smoothed friction
    /// acts in the static regime as a tangential spring of stiffness up to `2 mu lambda / eps`,
    /// `lambda = k d0`. With `eps = 1e-3 r` this is `2000 mu (d0 / r)` times the normal
    /// penalty `k`; penetrations are a small fraction of a radius (resting sag `m g / k` is
    /// about `1e-5 r` with [`crate::ContactParams::from_material`]), so friction never
    /// stiffens the step's Hessian much beyond what the penalty already does, for any `dt`. The
    /// cost: a particle held by static friction creeps by at most `eps` (a thousandth of its
    /// radius) per step, far below the particle scale at the large steps an implicit
    /// integrator takes; every slip faster than `1e-3 r` per step obeys Coulomb's law exactly.
    /// Where a fixed creep velocity matters more (small steps), set one with
    /// [`Colliders::set_implicit_slip_velocity`].
    pub const IMPLICIT_SLIP_FRACTION: f64 = 1e-3;

    /// Sets the slip velocity `eps_v` (m/s, finite, > 0) below which implicit-step friction is
    /// smoothed (`eps = eps_v dt`), bounding the static creep speed by `eps_v` whatever the step;
    /// `None` restores the default, [`Colliders::IMPLICIT_SLIP_FRACTION`] of a contact radius
    /// per step. Takes effect at the next [`Colliders::begin_implicit`].
    pub fn set_implicit_slip_velocity(&mut self, slip: Option<f64>) -> Result<(), ContactError> {
        if let Some(v) = slip {
            if !(v.is_finite() && v > 0.0) {
                return Err(ContactError::BadSetting {
                    what: "implicit slip velocity",
                    expected: "finite and > 0",
                    value: v,
                });
            }
        }
        self.implicit.slip_velocity = slip;
        Ok(())
    }

    /// Starts an implicit step of `dt` (s) from particle positions `y0` (m) and velocities `v0`
    /// (m/s) at `t_n`, with masses `mass` (kg) and contact radii `radius` (m).
    ///
    /// Records what stays lagged for the step: for every particle-collider pair and dynamic
    /// ball-ground pair in contact at the start (penetration `d0 > 0`), its normal `n0`, the
    /// normal force `lambda = k d0` (friction bound `mu lambda`) and the damping coefficient
    /// `c = 2 zeta sqrt(k m)`; the balls' start centres and velocities. Kinematic balls end the
    /// step at `c_n + dt v`; dynamic balls' inertia targets are `c* = c_n + dt v_n + dt^2 g`
    /// ([`Colliders::implicit_body_targets`]). The same stiffness as [`Colliders::step`] is
    /// used per collider (and [`Colliders::ball_ground_stiffness`] for balls on the ground; the
    /// reference mass is set here as there, if not yet known). The balls do not move until
    /// [`Colliders::end_implicit`].
    ///
    /// Call order per step: `begin_implicit`, any number of [`Colliders::implicit_potential`]
    /// (and [`Colliders::implicit_stiffness_hint`]) evaluations, then `end_implicit` at the
    /// accepted state. `v0` is only validated: the dissipative terms use displacements.
    ///
    /// Errors ([`ContactError::BadParticle`], lowest index) when a position or velocity is not
    /// finite, a mass is not finite and > 0, or a radius is not finite and >= 0. No allocation
    /// once the buffers fit the particle count. Panics when the slice lengths differ or `dt` is
    /// not finite and > 0.
    #[track_caller]
    pub fn begin_implicit(
        &mut self,
        dt: f64,
        y0: &[Vec3],
        v0: &[Vec3],
        mass: &[f64],
        radius: &[f64],
    ) -> Result<(), ContactError> {
        let n = y0.len();
        assert!(dt.is_finite() && dt > 0.0, "time step {dt} must be > 0");
        assert!(
            v0.len() == n && mass.len() == n && radius.len() == n,
            "slice lengths differ: y0 {}, v0 {}, mass {}, radius {}",
            n,
            v0.len(),
            mass.len(),
            radius.len()
        );
        assert!(
            self.stiffness_scale.is_empty() || self.stiffness_scale.len() == n,
            "{} stiffness scales for {n} particles",
            self.stiffness_scale.len()
        );
        if self.reference_mass.is_none() && n > 0 {
            let m_min = crate::step::reference_mass(mass, &self.stiffness_scale);
            if m_min.is_finite() && m_min > 0.0 {
                self.reference_mass = Some(m_min);
            }
        }
        let Self {
            grounds,
            balls,
            gravity,
            reference_mass,
            stiffness_scale,
            implicit: st,
            ..
        } = self;
        st.active = false;
        st.dt = dt;
        st.particles = n;
        st.radius.clear();
        st.radius.extend_from_slice(radius);
        begin_balls(st, grounds, balls, *gravity, *reference_mass);
        let chunks = n.div_ceil(CHUNK);
        st.prepare(chunks, balls.len());
        let stride = st.stride;
        // Split borrows: the per-chunk outputs are written while `ctx` reads the rest.
        let mut pairs = std::mem::take(&mut st.pairs);
        let mut part_k = std::mem::take(&mut st.part_k);
        let mut bad = std::mem::take(&mut st.bad);
        let ctx = BeginCtx {
            st: &*st,
            grounds,
            balls,
            y0,
            v0,
            mass,
            radius,
            scale: stiffness_scale,
        };
        pairs[..chunks]
            .par_iter_mut()
            .zip(part_k[..chunks * stride].par_chunks_mut(stride))
            .zip(bad[..chunks].par_iter_mut())
            .enumerate()
            .for_each(|(c, ((list, pk), b))| *b = ctx.chunk(c, list, pk));
        st.pairs = pairs;
        st.part_k = part_k;
        st.bad = bad;
        if let Some(b) = st.bad[..chunks].iter().find_map(|b| *b) {
            return Err(ContactError::BadParticle {
                particle: b.particle,
                what: b.what,
                expected: b.expected,
                value: b.value,
            });
        }
        for (body, &j) in st.body_ball.iter().enumerate() {
            for c in 0..chunks {
                st.body_diag[body] += st.part_k[c * stride + j];
            }
        }
        st.active = true;
        Ok(())
    }

    /// Number of dynamic balls: the extra unknowns `c` of the implicit step, in ball order
    /// ([`Colliders::implicit_body_balls`]).
    pub fn implicit_bodies(&self) -> usize {
        self.balls.iter().filter(|b| b.mass.is_some()).count()
    }

    /// Ball index (as given to [`Colliders::new`]) of each implicit body. Filled by
    /// [`Colliders::begin_implicit`] (empty before the first).
    pub fn implicit_body_balls(&self) -> &[usize] {
        &self.implicit.body_ball
    }

    /// Mass (kg) of each implicit body. Filled by [`Colliders::begin_implicit`].
    pub fn implicit_body_masses(&self) -> &[f64] {
        &self.implicit.body_mass
    }

    /// Centre (m) of each implicit body at `t_n`, the start of the step.
    pub fn implicit_body_start(&self) -> &[Vec3] {
        &self.implicit.body_start
    }

    /// Inertia target `c* = c_n + dt v_n + dt^2 g` (m) of each implicit body: where it would
    /// end without contact, a good start for the solver's iteration.
    pub fn implicit_body_targets(&self) -> &[Vec3] {
        &self.implicit.body_target
    }

    /// Diagonal preconditioner hint (N/m) per implicit body: `M_b / dt^2` plus the stiffness
    /// `k` of every pair (particles and grounds) it touched at the start of the step.
    pub fn implicit_body_diagonal(&self) -> &[f64] {
        &self.implicit.body_diag
    }

    /// The contact potential `P(q, c)` (J) at trial particle end positions `q` (m) and implicit
    /// body end centres `c` (m); when `grad` is given, ADDS `dP/dq` (N, i.e. J/m) into its
    /// first slice and `dP/dc` (N) into its second.
    ///
    /// `P` = the bodies' inertia `sum_b M_b / (2 dt^2) |c_b - c*_b|^2`, plus `k d^2 / 2` for
    /// every particle-ground, particle-ball (kinematic at its end centre, dynamic at `c`) and
    /// body-ground pair penetrating by `d > 0` (ground `d = r - (n . q - offset)`, ball
    /// `d = R + r - |q - c|`, body-ground `d = R - (n . c - offset)`), plus, for the pairs in
    /// contact at the start, with `u` the relative displacement over the step (end minus start,
    /// particle or body minus collider) and `u_t` its part tangential to `n0`:
    /// damping `c / (2 dt) min(0, n0 . u)^2` and friction `mu lambda f0(|u_t|)`, `f0` smoothed
    /// below `eps` ([`Colliders::IMPLICIT_SLIP_FRACTION`]; `f0(0) = eps / 3`, so a lagged
    /// pair with friction adds the constant `mu lambda eps / 3` at zero slip, which moves no
    /// minimiser). `P` is C1 in `(q, c)` except at a
    /// particle exactly at a ball centre, where the normal is fixed ([`crate::Colliders::step`]
    /// does the same) so the value and gradient stay finite.
    ///
    /// Deterministic for any thread count (per-chunk partial sums combined in chunk order); no
    /// allocation once warm. Finite inputs give finite outputs. Panics when no step is begun or
    /// the slice lengths differ from the step's particle and body counts.
    #[track_caller]
    pub fn implicit_potential(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        self.check_trial(q, c);
        let (gq, gc) = match grad {
            Some((gq, gc)) => {
                assert!(
                    gq.len() == q.len() && gc.len() == c.len(),
                    "gradient lengths {} and {} differ from q {} and c {}",
                    gq.len(),
                    gc.len(),
                    q.len(),
                    c.len()
                );
                (Some(gq), Some(gc))
            }
            None => (None, None),
        };
        let mut stats = ContactStats::default();
        let mut e = self.particle_terms(q, c, gq, &mut stats);
        let st = &self.implicit;
        let chunks = st.chunks();
        let mut gc = gc;
        for b in 0..st.body_ball.len() {
            let (eb, mut g) = self.body_own_terms(b, c[b], &mut stats);
            e += eb;
            // dP/dc of the particle pairs is minus their dP/dq (they depend on q - c).
            let r = st.reaction(st.body_ball[b], chunks);
            g = sub(g, r);
            if let Some(gc) = gc.as_deref_mut() {
                add_assign(&mut gc[b], g);
            }
        }
        e
    }

    /// Per particle, writes into `out` the sum of the contact stiffnesses (N/m) acting on it at
    /// the trial state `(q, c)`: `k` of each pair penetrating there, plus `c / dt` (damping)
    /// and `2 mu lambda / eps` (friction's largest curvature) of each pair lagged at the start.
    /// An upper bound of the contact Hessian's diagonal block, for a solver's preconditioner.
    /// Panics when no step is begun or the lengths differ.
    #[track_caller]
    pub fn implicit_stiffness_hint(&self, q: &[Vec3], c: &[Vec3], out: &mut [f64]) {
        self.check_trial(q, c);
        assert_eq!(out.len(), q.len(), "one stiffness per particle");
        let st = &self.implicit;
        let chunks = st.chunks();
        let (grounds, balls) = (&self.grounds, &self.balls);
        let scale = &self.stiffness_scale;
        let centre = |j: usize| match st.ball_body[j] {
            Some(b) => c[b],
            None => st.centre[j],
        };
        out.par_chunks_mut(CHUNK)
            .zip(st.pairs[..chunks].par_iter())
            .enumerate()
            .for_each(|(ci, (o, pairs))| {
                let start = ci * CHUNK;
                for (k, ok) in o.iter_mut().enumerate() {
                    let (p, r) = (q[start + k], st.radius[start + k]);
                    let mut s = 0.0;
                    for g in grounds {
                        if r - (dot(p, g.normal) - g.offset) > 0.0 {
                            s += g.coeffs.k;
                        }
                    }
                    for (j, b) in balls.iter().enumerate() {
                        let dx = sub(p, centre(j));
                        let reach = r + b.shape.radius;
                        if dot(dx, dx) < reach * reach {
                            s += b.coeffs.k;
                        }
                    }
                    *ok = s * scale_of(scale, start + k);
                }
                for pp in pairs {
                    let l = &pp.lag;
                    o[pp.particle - start] += l.damp_dt + 2.0 * l.friction / l.eps;
                }
            });
    }

    /// Ends the implicit step at the accepted state: particles at `q` (m), implicit bodies at
    /// `c` (m); `v_end` (m/s) are the particles' end velocities (checked for length only: the
    /// contact state does not depend on them).
    ///
    /// Sets each dynamic ball's centre to `c` and velocity to `(c - c_n) / dt`, each kinematic
    /// ball's centre to `c_n + dt v`, and stores each ball's `reaction` (the force the
    /// particles exert on it: the sum of its pairs' `dP/dq`, minus the contact forces on the
    /// particles) and a dynamic ball's `ground_force` (minus `dP/dc` of its ground pairs), all
    /// at the accepted state, so [`crate::BallState`] reads as after [`Colliders::step`]. Returns
    /// the contact statistics at the accepted state. Panics when no step is begun or the
    /// lengths differ.
    #[track_caller]
    pub fn end_implicit(&mut self, q: &[Vec3], c: &[Vec3], v_end: &[Vec3]) -> ContactStats {
        self.check_trial(q, c);
        assert_eq!(v_end.len(), q.len(), "one end velocity per particle");
        let mut stats = ContactStats::default();
        self.particle_terms(q, c, None, &mut stats);
        let chunks = self.implicit.chunks();
        for j in 0..self.balls.len() {
            let reaction = self.implicit.reaction(j, chunks);
            let end = self.implicit.centre[j];
            let body = self.implicit.ball_body[j];
            let ground_force = match body {
                Some(b) => scale(self.body_ground_terms(b, end, &mut stats).1, -1.0),
                None => [0.0; 3],
            };
            let dt = self.implicit.dt;
            let gravity = self.gravity;
            let start = self.implicit.start[j];
            let ball = &mut self.balls[j];
            ball.pose.translation = to_parry(end);
            ball.reaction = reaction;
            if let Some(m) = ball.mass {
                ball.velocity = scale(sub(end, start), 1.0 / dt);
                ball.ground_force = ground_force;
                ball.force = add(add(reaction, ground_force), scale(gravity, m));
            }
        }
        self.implicit.active = false;
        stats
    }

    #[track_caller]
    fn check_trial(&self, q: &[Vec3], c: &[Vec3]) {
        let st = &self.implicit;
        assert!(st.active, "begin_implicit must start the step first");
        assert!(
            q.len() == st.particles && c.len() == st.body_ball.len(),
            "the step has {} particles and {} bodies, got q {} and c {}",
            st.particles,
            st.body_ball.len(),
            q.len(),
            c.len()
        );
    }

    /// The parallel particle loop: energy of all particle pairs (returned), `dP/dq` added into
    /// `gq`, per-chunk ball sums left in `part`, statistics merged into `stats`.
    fn particle_terms(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        gq: Option<&mut [Vec3]>,
        stats: &mut ContactStats,
    ) -> f64 {
        let Self {
            grounds,
            balls,
            stiffness_scale,
            implicit: st,
            ..
        } = self;
        for (b, &j) in st.body_ball.iter().enumerate() {
            st.centre[j] = c[b];
        }
        let chunks = st.chunks();
        let stride = st.stride;
        let ctx = EvalCtx {
            grounds,
            balls,
            q,
            radius: &st.radius,
            scale: stiffness_scale,
            centre: &st.centre,
            start: &st.start,
        };
        let outs = st.energy[..chunks]
            .par_iter_mut()
            .zip(st.stats[..chunks].par_iter_mut())
            .zip(st.part[..chunks * stride].par_chunks_mut(stride))
            .zip(st.pairs[..chunks].par_iter());
        match gq {
            Some(gq) => outs.zip(gq.par_chunks_mut(CHUNK)).enumerate().for_each(
                |(ci, ((((e, s), p), pairs), g))| *e = ctx.chunk(ci, pairs, Some(g), p, s),
            ),
            None => outs
                .enumerate()
                .for_each(|(ci, (((e, s), p), pairs))| *e = ctx.chunk(ci, pairs, None, p, s)),
        }
        let mut e = 0.0;
        for ci in 0..chunks {
            e += st.energy[ci];
            merge(stats, &st.stats[ci]);
        }
        e
    }

    /// Body `b`'s own terms at centre `cb`: inertia and ground pairs; energy (J) and
    /// `dP/dc_b` (N).
    fn body_own_terms(&self, b: usize, cb: Vec3, stats: &mut ContactStats) -> (f64, Vec3) {
        let st = &self.implicit;
        let w = st.body_mass[b] / (st.dt * st.dt);
        let dc = sub(cb, st.body_target[b]);
        let (e, g) = self.body_ground_terms(b, cb, stats);
        (e + 0.5 * w * dot(dc, dc), add(g, scale(dc, w)))
    }

    /// Body `b`'s ground pairs at centre `cb`: elastic (closed form of parry3d's
    /// half-space/ball contact, `d = R - (n . c - offset)`) and the lagged damping and
    /// friction; energy (J) and gradient (N).
    fn body_ground_terms(&self, b: usize, cb: Vec3, stats: &mut ContactStats) -> (f64, Vec3) {
        let st = &self.implicit;
        let ball = &self.balls[st.body_ball[b]];
        let mut e = 0.0;
        let mut g = [0.0; 3];
        for gr in &self.grounds {
            let d = ball.shape.radius - (dot(cb, gr.normal) - gr.offset);
            if d > 0.0 {
                let k = ball_ground_coeffs(self.reference_mass, st.body_mass[b], gr).k;
                let (ed, f) = elastic(k, d);
                e += ed;
                add_assign(&mut g, scale(gr.normal, -f));
                stats.ball_ground_contacts += 1;
                stats.max_penetration = stats.max_penetration.max(d);
            }
        }
        let u = sub(cb, st.body_start[b]);
        for pair in st.body_ground.iter().filter(|p| p.body == b) {
            let (ed, gd) = dissipation(&pair.lag, u);
            e += ed;
            add_assign(&mut g, gd);
        }
        (e, g)
    }
}

/// Ball bookkeeping of `begin_implicit`: start and end centres, bodies, body-ground pairs.
fn begin_balls(
    st: &mut ImplicitState,
    grounds: &[Ground],
    balls: &[BallBody],
    gravity: Vec3,
    reference_mass: Option<f64>,
) {
    let dt = st.dt;
    st.ball_body.clear();
    st.start.clear();
    st.centre.clear();
    st.body_ball.clear();
    st.body_mass.clear();
    st.body_start.clear();
    st.body_target.clear();
    st.body_diag.clear();
    st.body_ground.clear();
    for (j, b) in balls.iter().enumerate() {
        let c0 = b.center();
        st.start.push(c0);
        let Some(m) = b.mass else {
            st.ball_body.push(None);
            st.centre.push(add(c0, scale(b.velocity, dt)));
            continue;
        };
        let body = st.body_ball.len();
        let target = add(add(c0, scale(b.velocity, dt)), scale(gravity, dt * dt));
        st.ball_body.push(Some(body));
        st.centre.push(target);
        st.body_ball.push(j);
        st.body_mass.push(m);
        st.body_start.push(c0);
        st.body_target.push(target);
        let mut diag = m / (dt * dt);
        for g in grounds {
            let d0 = b.shape.radius - (dot(c0, g.normal) - g.offset);
            if d0 > 0.0 {
                let co = ball_ground_coeffs(reference_mass, m, g);
                diag += co.k;
                let lag = lag(g.normal, d0, m, dt, &co, st.eps(b.shape.radius, d0));
                st.body_ground.push(BodyGroundPair { body, lag });
            }
        }
        st.body_diag.push(diag);
    }
}

/// What the parallel lagging loop of `begin_implicit` reads.
struct BeginCtx<'a> {
    st: &'a ImplicitState,
    grounds: &'a [Ground],
    balls: &'a [BallBody],
    y0: &'a [Vec3],
    v0: &'a [Vec3],
    mass: &'a [f64],
    radius: &'a [f64],
    /// Per-particle stiffness scale (empty: 1).
    scale: &'a [f64],
}

impl BeginCtx<'_> {
    /// Lags chunk `c`'s pairs into `list` and each ball's touching stiffness into `pk`; returns
    /// the chunk's first unusable value.
    fn chunk(&self, c: usize, list: &mut Vec<ParticlePair>, pk: &mut [f64]) -> Option<Bad> {
        list.clear();
        pk.fill(0.0);
        let dt = self.st.dt;
        let start = c * CHUNK;
        let end = (start + CHUNK).min(self.y0.len());
        for i in start..end {
            let (y, m, r) = (self.y0[i], self.mass[i], self.radius[i]);
            if let Some(bad) = check_particle(i, y, self.v0[i], m, r) {
                return Some(bad);
            }
            let s = scale_of(self.scale, i);
            for g in self.grounds {
                let d0 = r - (dot(y, g.normal) - g.offset);
                if d0 > 0.0 {
                    let lag = lag(g.normal, d0, m, dt, &g.coeffs.scaled(s), self.st.eps(r, d0));
                    list.push(ParticlePair {
                        particle: i,
                        ball: None,
                        y0: y,
                        lag,
                    });
                }
            }
            for (j, b) in self.balls.iter().enumerate() {
                let dx = sub(y, self.st.start[j]);
                let d2 = dot(dx, dx);
                let reach = r + b.shape.radius;
                if d2 < reach * reach {
                    let (n0, dist) = ball_normal(dx, d2);
                    let d0 = reach - dist;
                    let co = b.coeffs.scaled(s);
                    pk[j] += co.k;
                    list.push(ParticlePair {
                        particle: i,
                        ball: Some(j),
                        y0: y,
                        lag: lag(n0, d0, m, dt, &co, self.st.eps(r, d0)),
                    });
                }
            }
        }
        None
    }
}

fn lag(n0: Vec3, d0: f64, m: f64, dt: f64, c: &Coeffs, eps: f64) -> Lagged {
    Lagged {
        n0,
        damp_dt: c.damp * m.sqrt() / dt,
        friction: c.mu * c.k * d0,
        eps,
    }
}

fn check_particle(i: usize, y: Vec3, v: Vec3, m: f64, r: f64) -> Option<Bad> {
    let bad = |what, expected, value| {
        Some(Bad {
            particle: i,
            what,
            expected,
            value,
        })
    };
    let first_bad = |a: Vec3| a.into_iter().find(|x| !x.is_finite()).unwrap_or(f64::NAN);
    if !is_finite(y) {
        return bad("position", "finite", first_bad(y));
    }
    if !is_finite(v) {
        return bad("velocity", "finite", first_bad(v));
    }
    if !(m.is_finite() && m > 0.0) {
        return bad("mass", "finite and > 0", m);
    }
    if !(r.is_finite() && r >= 0.0) {
        return bad("contact radius", "finite and >= 0", r);
    }
    None
}

/// What the parallel evaluation loop reads.
struct EvalCtx<'a> {
    grounds: &'a [Ground],
    balls: &'a [BallBody],
    q: &'a [Vec3],
    radius: &'a [f64],
    /// Per-particle stiffness scale (empty: 1).
    scale: &'a [f64],
    /// Per ball: end centre at this trial.
    centre: &'a [Vec3],
    /// Per ball: start centre.
    start: &'a [Vec3],
}

impl EvalCtx<'_> {
    /// Chunk `ci`: energy (J) of its particles' pairs; `dP/dq` added into `g` (the chunk's
    /// slice), the ball sums written to `part`, statistics to `st`.
    fn chunk(
        &self,
        ci: usize,
        pairs: &[ParticlePair],
        mut g: Option<&mut [Vec3]>,
        part: &mut [Vec3],
        st: &mut ContactStats,
    ) -> f64 {
        part.fill([0.0; 3]);
        *st = ContactStats::default();
        let start = ci * CHUNK;
        let end = (start + CHUNK).min(self.q.len());
        let mut e = 0.0;
        for i in start..end {
            let (p, r) = (self.q[i], self.radius[i]);
            let s = scale_of(self.scale, i);
            for gr in self.grounds {
                let d = r - (dot(p, gr.normal) - gr.offset);
                if d > 0.0 {
                    let (ed, f) = elastic(s * gr.coeffs.k, d);
                    e += ed;
                    if let Some(g) = g.as_deref_mut() {
                        add_assign(&mut g[i - start], scale(gr.normal, -f));
                    }
                    st.contacts += 1;
                    st.max_penetration = st.max_penetration.max(d);
                }
            }
            for (j, b) in self.balls.iter().enumerate() {
                let dx = sub(p, self.centre[j]);
                let d2 = dot(dx, dx);
                let reach = r + b.shape.radius;
                if d2 < reach * reach {
                    let (nrm, dist) = ball_normal(dx, d2);
                    let d = reach - dist;
                    let (ed, f) = elastic(s * b.coeffs.k, d);
                    e += ed;
                    let gp = scale(nrm, -f);
                    if let Some(g) = g.as_deref_mut() {
                        add_assign(&mut g[i - start], gp);
                    }
                    add_assign(&mut part[j], gp);
                    st.contacts += 1;
                    st.max_penetration = st.max_penetration.max(d);
                }
            }
        }
        for pp in pairs {
            let mut u = sub(self.q[pp.particle], pp.y0);
            if let Some(j) = pp.ball {
                u = sub(u, sub(self.centre[j], self.start[j]));
            }
            let (ed, gu) = dissipation(&pp.lag, u);
            e += ed;
            if let Some(g) = g.as_deref_mut() {
                add_assign(&mut g[pp.particle - start], gu);
            }
            if let Some(j) = pp.ball {
                add_assign(&mut part[j], gu);
            }
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use crate::desc::{BallDesc, BallMotion, GroundDesc};
    use crate::math::{norm, to_parry};
    use crate::params::ContactParams;
    use crate::step::ContactStats;
    use crate::Colliders;
    use parry3d_f64::math::Pose;

    #[test]
    fn ball_ground_closed_form_matches_parry() {
        let p = ContactParams::from_material(1e7, 0.01, 1.0, 0.0, 0.0);
        let ground = GroundDesc {
            point: [0.1, -0.2, 0.05],
            normal: [0.3, -0.2, 1.0],
            params: p,
        };
        let ball = BallDesc {
            center: [0.0, 0.0, 1.0],
            radius: 0.2,
            motion: BallMotion::Dynamic {
                mass: 2.0,
                velocity: [0.0; 3],
            },
            params: p,
        };
        let mut col = Colliders::new(vec![ground], vec![ball], [0.0; 3]).unwrap();
        col.set_reference_mass(1e-3);
        col.begin_implicit(1e-3, &[], &[], &[], &[]).unwrap();
        let k = col.ball_ground_stiffness(0, 0).unwrap();
        for c in [[0.0, 0.0, 0.2], [0.3, 0.1, 0.12], [-0.2, 0.4, 0.0]] {
            let mut stats = ContactStats::default();
            let (e, g) = col.body_ground_terms(0, c, &mut stats);
            let (gr, b) = (&col.grounds[0], &col.balls[0]);
            let contact = parry3d_f64::query::contact(
                &gr.pose,
                &gr.shape,
                &Pose::from_translation(to_parry(c)),
                &b.shape,
                0.0,
            )
            .unwrap()
            .unwrap();
            let d = -contact.dist;
            // Same depth as parry to rounding (1e-15 m at these sizes), force k d along the
            // normal.
            assert!(
                (e - 0.5 * k * d * d).abs() <= 1e-12 * e,
                "{e} vs {}",
                0.5 * k * d * d
            );
            assert!((norm(g) - k * d).abs() <= 1e-12 * k * d, "{g:?}");
            assert_eq!(stats.ball_ground_contacts, 1);
        }
    }
}
