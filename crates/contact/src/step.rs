//! One explicit contact step: ball kicks and drift, the parallel particle loop, reactions.

use crate::colliders::{ball_ground_coeffs, BallBody, Colliders, Ground};
use crate::kernel::{ball_normal, penalty_force, scale_of};
use crate::math::{add, add_assign, dot, from_parry, scale, sub, to_parry};
use crate::Vec3;
use rayon::prelude::*;

/// Particles per parallel chunk. Fixed, so the chunk partition (and with it the order of the
/// reaction sums) does not depend on the thread count.
pub(crate) const CHUNK: usize = 2048;

/// What one [`Colliders::step`] found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactStats {
    /// Particle-collider pairs in contact (penetration > 0).
    pub contacts: usize,
    /// Dynamic ball-ground pairs in contact.
    pub ball_ground_contacts: usize,
    /// Largest penetration depth (m) over all pairs in contact, 0 when none.
    pub max_penetration: f64,
}

impl ContactStats {
    fn merge(&mut self, o: &ContactStats) {
        self.contacts += o.contacts;
        self.ball_ground_contacts += o.ball_ground_contacts;
        self.max_penetration = self.max_penetration.max(o.max_penetration);
    }
}

/// Per-chunk buffers, grown (never shrunk) when the particle count grows, reused otherwise.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    /// Balls per chunk row (at least 1 so chunking by it is valid).
    stride: usize,
    /// `reaction[c * stride + j]`: force on ball `j` from the particles of chunk `c`.
    reaction: Vec<Vec3>,
    /// Per-chunk statistics.
    stats: Vec<ContactStats>,
}

impl Scratch {
    pub(crate) fn new(num_balls: usize) -> Self {
        Self {
            stride: num_balls.max(1),
            reaction: Vec::new(),
            stats: Vec::new(),
        }
    }

    fn prepare(&mut self, chunks: usize) {
        if self.stats.len() < chunks {
            self.stats.resize(chunks, ContactStats::default());
            self.reaction.resize(chunks * self.stride, [0.0; 3]);
        }
    }
}

impl Colliders {
    /// One explicit contact step, inside the caller's velocity-Verlet step.
    ///
    /// Call it after the particles drifted to `y` = `y_{n+1}` (m) and the internal forces (and
    /// gravity) at `y_{n+1}` were written to `forces` (N), before the second half kick; `v`
    /// (m/s) is the particles' half-step velocity `v_{n+1/2}` (the latest known), `mass` (kg)
    /// and `radius` (contact radius, m) per particle, `dt` (s) the step just drifted. It
    ///
    /// 1. gives dynamic balls their first half kick with the force stored at the end of the
    ///    previous step (reaction + gravity + ground), then drifts every ball by `dt`
    ///    (kinematic balls at their constant velocity);
    /// 2. adds, for every particle and collider in contact, the penalty, damping and friction
    ///    force into `forces[i]`, summing the opposite force onto each ball;
    /// 3. computes the dynamic balls' ball-ground forces (parry3d contact query) and gives
    ///    them the second half kick with the new total force, which it keeps for step 1 next
    ///    time.
    ///
    /// The same inputs and thread count give bit-identical results; the reactions are summed
    /// per fixed-size chunk and combined in chunk order. No allocation once the buffers fit the
    /// particle count. With no collider it returns at once.
    ///
    /// Panics when the slice lengths differ or `dt` is not finite and > 0.
    #[track_caller]
    pub fn step(
        &mut self,
        dt: f64,
        y: &[Vec3],
        v: &[Vec3],
        mass: &[f64],
        radius: &[f64],
        forces: &mut [Vec3],
    ) -> ContactStats {
        let n = y.len();
        assert!(dt.is_finite() && dt > 0.0, "time step {dt} must be > 0");
        assert!(
            v.len() == n && mass.len() == n && radius.len() == n && forces.len() == n,
            "slice lengths differ: y {}, v {}, mass {}, radius {}, forces {}",
            n,
            v.len(),
            mass.len(),
            radius.len(),
            forces.len()
        );
        if self.is_empty() {
            return ContactStats::default();
        }
        assert!(
            self.stiffness_scale.is_empty() || self.stiffness_scale.len() == n,
            "{} stiffness scales for {n} particles",
            self.stiffness_scale.len()
        );
        if self.reference_mass.is_none() && n > 0 {
            let m_min = reference_mass(mass, &self.stiffness_scale);
            if m_min.is_finite() && m_min > 0.0 {
                self.reference_mass = Some(m_min);
            }
        }
        let half = 0.5 * dt;
        for b in &mut self.balls {
            if let Some(m) = b.mass {
                b.velocity = add(b.velocity, scale(b.force, half / m));
            }
            b.pose.translation += to_parry(scale(b.velocity, dt));
        }

        let mut stats = self.particle_forces(dt, y, v, mass, radius, forces);

        let Self {
            grounds,
            balls,
            gravity,
            reference_mass,
            ..
        } = self;
        for b in balls.iter_mut() {
            let Some(m) = b.mass else { continue };
            let mut ground_force = [0.0; 3];
            for g in grounds.iter() {
                let c = ball_ground_coeffs(*reference_mass, m, g);
                if let Some(f) = ball_ground_force(b, g, m, dt, &c, &mut stats) {
                    add_assign(&mut ground_force, f);
                }
            }
            b.ground_force = ground_force;
            b.force = add(add(b.reaction, ground_force), scale(*gravity, m));
            b.velocity = add(b.velocity, scale(b.force, half / m));
        }
        stats
    }

    /// Stage 2: the parallel particle loop; writes each ball's `reaction`.
    fn particle_forces(
        &mut self,
        dt: f64,
        y: &[Vec3],
        v: &[Vec3],
        mass: &[f64],
        radius: &[f64],
        forces: &mut [Vec3],
    ) -> ContactStats {
        let n = y.len();
        let chunks = n.div_ceil(CHUNK);
        let inv_dt = 1.0 / dt;
        let Self {
            grounds,
            balls,
            scratch,
            stiffness_scale,
            ..
        } = self;
        let stiffness_scale: &[f64] = stiffness_scale;
        scratch.prepare(chunks);
        let stride = scratch.stride;
        let grounds: &[Ground] = grounds;
        let balls_ro: &[BallBody] = balls;
        forces
            .par_chunks_mut(CHUNK)
            .zip(scratch.reaction[..chunks * stride].par_chunks_mut(stride))
            .zip(scratch.stats[..chunks].par_iter_mut())
            .enumerate()
            .for_each(|(c, ((f, part), st))| {
                part.fill([0.0; 3]);
                *st = ContactStats::default();
                let start = c * CHUNK;
                for (k, fi) in f.iter_mut().enumerate() {
                    let i = start + k;
                    let s = scale_of(stiffness_scale, i);
                    particle_vs_colliders(
                        y[i], v[i], mass[i], radius[i], s, inv_dt, grounds, balls_ro, fi, part, st,
                    );
                }
            });
        let mut stats = ContactStats::default();
        for s in &scratch.stats[..chunks] {
            stats.merge(s);
        }
        for (j, b) in balls.iter_mut().enumerate() {
            let mut r = [0.0; 3];
            for c in 0..chunks {
                add_assign(&mut r, scratch.reaction[c * stride + j]);
            }
            b.reaction = r;
        }
        stats
    }
}

/// All contacts of one particle at `p` (m) moving at `vp` (m/s), mass `m` (kg), radius `r` (m)
/// and stiffness scale `s`: adds its forces into `fi` and the opposite ball forces into `part`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn particle_vs_colliders(
    p: Vec3,
    vp: Vec3,
    m: f64,
    r: f64,
    s: f64,
    inv_dt: f64,
    grounds: &[Ground],
    balls: &[BallBody],
    fi: &mut Vec3,
    part: &mut [Vec3],
    st: &mut ContactStats,
) {
    for g in grounds {
        let d = r - (dot(p, g.normal) - g.offset);
        if d > 0.0 {
            add_assign(
                fi,
                penalty_force(d, g.normal, vp, m, inv_dt, &g.coeffs.scaled(s)),
            );
            st.contacts += 1;
            st.max_penetration = st.max_penetration.max(d);
        }
    }
    for (j, b) in balls.iter().enumerate() {
        let dx = sub(p, from_parry(b.pose.translation));
        let d2 = dot(dx, dx);
        let reach = r + b.shape.radius;
        if d2 < reach * reach {
            let (nrm, dist) = ball_normal(dx, d2);
            let d = reach - dist;
            let f = penalty_force(d, nrm, sub(vp, b.velocity), m, inv_dt, &b.coeffs.scaled(s));
            add_assign(fi, f);
            add_assign(&mut part[j], scale(f, -1.0));
            st.contacts += 1;
            st.max_penetration = st.max_penetration.max(d);
        }
    }
}

/// Force (N) of ground `g` on dynamic ball `b` of mass `m` (kg), from parry3d's half-space/ball
/// contact query; `None` when they do not touch.
fn ball_ground_force(
    b: &BallBody,
    g: &Ground,
    m: f64,
    dt: f64,
    c: &crate::kernel::Coeffs,
    stats: &mut ContactStats,
) -> Option<Vec3> {
    let contact = parry3d_f64::query::contact(&g.pose, &g.shape, &b.pose, &b.shape, 0.0)
        .expect("parry3d supports half-space/ball contact")?;
    let d = -contact.dist;
    if d <= 0.0 {
        return None;
    }
    stats.ball_ground_contacts += 1;
    stats.max_penetration = stats.max_penetration.max(d);
    Some(penalty_force(
        d,
        from_parry(contact.normal1),
        b.velocity,
        m,
        1.0 / dt,
        c,
    ))
}

/// The smallest `mass[i] / scale[i]` (kg; the masses alone when `scale` is empty): the
/// particle whose collider spring rings fastest. Particles of zero scale feel no collider.
pub(crate) fn reference_mass(mass: &[f64], scale: &[f64]) -> f64 {
    mass.iter()
        .enumerate()
        .map(|(i, &m)| {
            let s = scale_of(scale, i);
            if s > 0.0 {
                m / s
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min)
}
