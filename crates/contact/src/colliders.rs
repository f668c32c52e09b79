//! The collider set: parry3d shapes with their poses, validation, setup checks and state.

use crate::desc::{BallDesc, BallMotion, GroundDesc};
use crate::error::ContactError;
use crate::implicit::ImplicitState;
use crate::kernel::{scale_of, Coeffs};
use crate::math::{add, dot, from_parry, norm, scale, sub, to_parry};
use crate::params::ContactParams;
use crate::step::Scratch;
use crate::Vec3;
use parry3d_f64::math::Pose;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{Ball, HalfSpace};
use rayon::prelude::*;

/// A ground plane: parry half-space (unit outward normal) at a pose whose translation is a
/// point of the plane; the rotation stays the identity.
#[derive(Debug, Clone)]
pub(crate) struct Ground {
    pub shape: HalfSpace,
    pub pose: Pose,
    pub params: ContactParams,
    pub coeffs: Coeffs,
    /// World outward unit normal, cached from the shape for the particle loop.
    pub normal: Vec3,
    /// `normal . point` (m): the signed distance of `y` is `normal . y - offset`.
    pub offset: f64,
}

impl Ground {
    /// A point of the plane (m).
    #[inline]
    pub fn point(&self) -> Vec3 {
        from_parry(self.pose.translation)
    }
}

/// A ball: parry ball at a pose whose translation is the centre; no rotation.
#[derive(Debug, Clone)]
pub(crate) struct BallBody {
    pub shape: Ball,
    pub pose: Pose,
    pub velocity: Vec3,
    /// `Some(mass)` for a dynamic ball.
    pub mass: Option<f64>,
    pub coeffs: Coeffs,
    /// Total force (N) at the current state, used by the next first half kick.
    pub force: Vec3,
    /// Force (N) from the particles at the last step.
    pub reaction: Vec3,
    /// Force (N) from the ground planes at the last step.
    pub ground_force: Vec3,
}

impl BallBody {
    #[inline]
    pub fn center(&self) -> Vec3 {
        from_parry(self.pose.translation)
    }
}

/// A ball as seen from outside, for output and rendering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallState {
    /// Centre (m).
    pub center: Vec3,
    /// Radius (m).
    pub radius: f64,
    /// Velocity (m/s); after [`Colliders::step`], the full-step velocity.
    pub velocity: Vec3,
    /// Mass (kg) of a dynamic ball, `None` for a kinematic one.
    pub mass: Option<f64>,
    /// Force (N) the particles exerted on the ball at the last step: minus the sum of the
    /// contact forces this ball added to the particles.
    pub reaction: Vec3,
    /// Force (N) the ground planes exerted on a dynamic ball at the last step.
    pub ground_force: Vec3,
}

/// A ground plane as seen from outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundState {
    /// A point of the plane (m).
    pub point: Vec3,
    /// Outward unit normal.
    pub normal: Vec3,
}

/// Ground planes and balls that particles collide with. Built once per scene; [`Colliders::step`]
/// is called once per time step.
#[derive(Debug, Clone)]
pub struct Colliders {
    pub(crate) grounds: Vec<Ground>,
    pub(crate) balls: Vec<BallBody>,
    pub(crate) gravity: Vec3,
    /// Mass (kg) the ball-ground stiffness is scaled against; see
    /// [`Colliders::ball_ground_stiffness`].
    pub(crate) reference_mass: Option<f64>,
    /// Per particle, the factor on every collider's stiffness (dimensionless); empty: 1.
    pub(crate) stiffness_scale: Vec<f64>,
    pub(crate) scratch: Scratch,
    /// The lagged state and buffers of the implicit step (`implicit.rs`).
    pub(crate) implicit: ImplicitState,
}

fn check_vec(collider: &str, what: &'static str, v: Vec3) -> Result<(), ContactError> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(&value) => Err(ContactError::NonFinite {
            collider: collider.to_owned(),
            what,
            value,
        }),
        None => Ok(()),
    }
}

impl Colliders {
    /// Builds the colliders. `gravity` (m/s^2) acts on dynamic balls only (the caller applies it
    /// to the particles). Checks every value is finite, ball radii and masses are > 0, ground
    /// normals are nonzero (they are normalised), coefficients are >= 0, and no dynamic ball
    /// starts with its centre below a ground plane.
    pub fn new(
        grounds: Vec<GroundDesc>,
        balls: Vec<BallDesc>,
        gravity: Vec3,
    ) -> Result<Self, ContactError> {
        check_vec("gravity", "gravity", gravity)?;
        let mut gs = Vec::with_capacity(grounds.len());
        for (i, g) in grounds.iter().enumerate() {
            let name = format!("ground {i}");
            check_vec(&name, "point", g.point)?;
            check_vec(&name, "normal", g.normal)?;
            g.params.validate(&name)?;
            let len = norm(g.normal);
            if len == 0.0 || !len.is_finite() {
                return Err(ContactError::ZeroNormal {
                    collider: name,
                    normal: g.normal,
                });
            }
            let normal = g.normal.map(|x| x / len);
            // The pose carries no rotation, so the shape's local normal is the world normal.
            let shape = HalfSpace::new(to_parry(normal));
            let pose = Pose::from_translation(to_parry(g.point));
            gs.push(Ground {
                shape,
                pose,
                params: g.params,
                coeffs: Coeffs::new(&g.params),
                normal,
                offset: dot(normal, g.point),
            });
        }
        let mut bs = Vec::with_capacity(balls.len());
        for (i, b) in balls.iter().enumerate() {
            let name = format!("ball {i}");
            check_vec(&name, "center", b.center)?;
            if !b.radius.is_finite() {
                return Err(ContactError::NonFinite {
                    collider: name,
                    what: "radius",
                    value: b.radius,
                });
            }
            if b.radius <= 0.0 {
                return Err(ContactError::NotPositive {
                    collider: name,
                    what: "radius",
                    value: b.radius,
                });
            }
            b.params.validate(&name)?;
            let (velocity, mass) = match b.motion {
                BallMotion::Kinematic { velocity } => (velocity, None),
                BallMotion::Dynamic { mass, velocity } => {
                    if !mass.is_finite() {
                        return Err(ContactError::NonFinite {
                            collider: name,
                            what: "mass",
                            value: mass,
                        });
                    }
                    if mass <= 0.0 {
                        return Err(ContactError::NotPositive {
                            collider: name,
                            what: "mass",
                            value: mass,
                        });
                    }
                    (velocity, Some(mass))
                }
            };
            check_vec(&name, "velocity", velocity)?;
            let pose = Pose::from_translation(to_parry(b.center));
            if mass.is_some() {
                for (j, g) in gs.iter().enumerate() {
                    // Signed distance of the centre to the plane (negative inside).
                    let dist = g.shape.distance_to_point(&g.pose, pose.translation, false);
                    let depth = b.radius - dist;
                    if depth > overlap_tolerance(b.radius) {
                        return Err(ContactError::BallInGround {
                            ball: name,
                            ground: format!("ground {j}"),
                            depth,
                        });
                    }
                }
            }
            bs.push(BallBody {
                shape: Ball::new(b.radius),
                pose,
                velocity,
                mass,
                coeffs: Coeffs::new(&b.params),
                force: scale(gravity, mass.unwrap_or(0.0)),
                reaction: [0.0; 3],
                ground_force: [0.0; 3],
            });
        }
        let scratch = Scratch::new(bs.len());
        Ok(Self {
            grounds: gs,
            balls: bs,
            gravity,
            reference_mass: None,
            stiffness_scale: Vec::new(),
            scratch,
            implicit: ImplicitState::default(),
        })
    }

    /// True when there is no collider: the caller can skip [`Colliders::step`] entirely.
    pub fn is_empty(&self) -> bool {
        self.grounds.is_empty() && self.balls.is_empty()
    }

    /// Setup check: `Err(ContactError::Overlap)` naming the particle whose contact sphere
    /// (centre `y`, radius `radius`, m) reaches deepest into a collider, with that collider and
    /// the depth (ties go to the lowest particle index, then to grounds before balls, so the
    /// message is deterministic). The deepest, not the first: the depth is how far the
    /// collider has to move. Touching is allowed (an overlap below a billionth of the radii
    /// counts as touching). A sphere that starts inside would be shot out by the penalty force
    /// stored in its overlap. Uses parry3d point queries; `O(particles x colliders)`.
    ///
    /// Panics when `y` and `radius` differ in length.
    #[track_caller]
    pub fn check_clear(&self, y: &[Vec3], radius: &[f64]) -> Result<(), ContactError> {
        assert_eq!(y.len(), radius.len(), "one radius per particle");
        // Per particle its deepest overlap: (depth, particle, collider index; grounds first).
        let deepest = |i: usize| -> Option<(f64, usize, usize)> {
            let p = to_parry(y[i]);
            let r = radius[i];
            let mut best: Option<(f64, usize, usize)> = None;
            let mut consider = |depth: f64, tolerance: f64, collider: usize| {
                if depth > tolerance && best.is_none_or(|(d, _, _)| depth > d) {
                    best = Some((depth, i, collider));
                }
            };
            for (j, g) in self.grounds.iter().enumerate() {
                let depth = r - g.shape.distance_to_point(&g.pose, p, false);
                consider(depth, overlap_tolerance(r), j);
            }
            for (j, b) in self.balls.iter().enumerate() {
                // Signed: negative inside the ball, down to -radius at its centre.
                let dist = b.shape.distance_to_point(&b.pose, p, false);
                let depth = r - dist;
                consider(
                    depth,
                    overlap_tolerance(r + b.shape.radius),
                    self.grounds.len() + j,
                );
            }
            best
        };
        // Deeper wins; at equal depth the lower particle (then collider) index.
        let deeper = |a: (f64, usize, usize), b: (f64, usize, usize)| {
            if b.0 > a.0 || (b.0 == a.0 && (b.1, b.2) < (a.1, a.2)) {
                b
            } else {
                a
            }
        };
        let hit = (0..y.len())
            .into_par_iter()
            .filter_map(deepest)
            .reduce_with(deeper);
        match hit {
            Some((depth, particle, c)) => Err(ContactError::Overlap {
                collider: if c < self.grounds.len() {
                    format!("ground {c}")
                } else {
                    format!("ball {}", c - self.grounds.len())
                },
                particle,
                depth,
            }),
            None => Ok(()),
        }
    }

    /// Number of balls.
    pub fn num_balls(&self) -> usize {
        self.balls.len()
    }

    /// Stops kinematic ball `i` where it is (a press that has reached its depth): its velocity
    /// becomes zero and it holds from the next step on. Stopping it again changes nothing.
    /// An error for a dynamic ball (it moves under its forces) or an index out of range.
    pub fn stop_ball(&mut self, i: usize) -> Result<(), ContactError> {
        match self.balls.get_mut(i) {
            Some(b) if b.mass.is_none() => {
                b.velocity = [0.0; 3];
                Ok(())
            }
            Some(_) => Err(ContactError::CannotStop {
                ball: format!("ball {i}"),
                reason: "a dynamic ball moves under its forces and cannot be stopped".into(),
            }),
            None => Err(ContactError::CannotStop {
                ball: format!("ball {i}"),
                reason: format!("there are {} balls", self.balls.len()),
            }),
        }
    }

    /// Number of ground planes.
    pub fn num_grounds(&self) -> usize {
        self.grounds.len()
    }

    /// State of ball `i` (panics when out of range).
    pub fn ball(&self, i: usize) -> BallState {
        let b = &self.balls[i];
        BallState {
            center: b.center(),
            radius: b.shape.radius,
            velocity: b.velocity,
            mass: b.mass,
            reaction: b.reaction,
            ground_force: b.ground_force,
        }
    }

    /// States of all balls, in the order given to [`Colliders::new`].
    pub fn balls(&self) -> impl ExactSizeIterator<Item = BallState> + '_ {
        (0..self.balls.len()).map(|i| self.ball(i))
    }

    /// All ground planes, in the order given to [`Colliders::new`].
    pub fn grounds(&self) -> impl ExactSizeIterator<Item = GroundState> + '_ {
        self.grounds.iter().map(|g| GroundState {
            point: g.point(),
            normal: g.normal,
        })
    }

    /// The penalty stiffnesses of every ground and ball summed (N/m, before any per-particle
    /// scale): the most a particle touching all of them at once is held by, so
    /// `stiffness_sum / m` bounds what contact adds to a particle of mass `m`'s squared
    /// frequency.
    pub fn stiffness_sum(&self) -> f64 {
        self.grounds.iter().map(|g| g.coeffs.k).sum::<f64>()
            + self.balls.iter().map(|b| b.coeffs.k).sum::<f64>()
    }

    /// Gravity acting on dynamic balls (m/s^2).
    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Kinetic energy of the dynamic balls (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.balls
            .iter()
            .filter_map(|b| b.mass.map(|m| 0.5 * m * dot(b.velocity, b.velocity)))
            .sum()
    }

    /// Gravitational potential energy of the dynamic balls (J), zero at the origin.
    pub fn ball_potential_energy(&self) -> f64 {
        self.balls
            .iter()
            .filter_map(|b| b.mass.map(|m| -m * dot(self.gravity, b.center())))
            .sum()
    }

    /// The deepest penetration (m, 0 when clear) of a sphere of `radius` (m) at `p` into any
    /// ground or ball.
    pub fn penetration(&self, p: Vec3, radius: f64) -> f64 {
        let grounds = self
            .grounds
            .iter()
            .map(|g| radius - dot(sub(p, g.point()), g.normal));
        let balls = self
            .balls
            .iter()
            .map(|b| radius + b.shape.radius - norm(sub(p, b.center())));
        grounds.chain(balls).fold(0.0, f64::max)
    }

    /// The least gap (m) between a sphere of `radius` (m) at `p` and any ground or ball:
    /// negative when it penetrates one, infinite when there is no collider.
    pub fn clearance(&self, p: Vec3, radius: f64) -> f64 {
        let grounds = self
            .grounds
            .iter()
            .map(|g| dot(sub(p, g.point()), g.normal) - radius);
        let balls = self
            .balls
            .iter()
            .map(|b| norm(sub(p, b.center())) - radius - b.shape.radius);
        grounds.chain(balls).fold(f64::INFINITY, f64::min)
    }

    /// `p` (m) moved along each collider's normal so that a sphere of `radius` (m) there
    /// penetrates no ground or ball by more than `depth` (m, >= 0), each in turn (grounds
    /// first). For a point a mesh edit puts inside a collider (a new vertex on a chord of a
    /// surface wrapped round a ball), which the penalty would shoot out with the energy of
    /// its overlap.
    pub fn push_out(&self, p: Vec3, radius: f64, depth: f64) -> Vec3 {
        let mut p = p;
        for g in &self.grounds {
            let d = radius - dot(sub(p, g.point()), g.normal);
            if d > depth {
                p = add(p, scale(g.normal, d - depth));
            }
        }
        for b in &self.balls {
            let c = b.center();
            let off = sub(p, c);
            let dist = norm(off);
            let reach = radius + b.shape.radius - depth;
            if dist < reach && dist > 0.0 {
                p = add(c, scale(off, reach / dist));
            }
        }
        p
    }

    /// Elastic energy (J) stored in the penalty springs: `k d^2 / 2` over every penetrating
    /// particle-collider pair (particles at `y`, contact radii `radius`, m) and ball-ground pair.
    /// A diagnostic for energy checks; sequential, not for the hot loop.
    pub fn contact_energy(&self, y: &[Vec3], radius: &[f64]) -> f64 {
        let mut e = 0.0;
        for (i, (p, &r)) in y.iter().zip(radius).enumerate() {
            let s = scale_of(&self.stiffness_scale, i);
            for g in &self.grounds {
                let d = r - dot(sub(*p, g.point()), g.normal);
                if d > 0.0 {
                    e += 0.5 * s * g.coeffs.k * d * d;
                }
            }
            for b in &self.balls {
                let d = r + b.shape.radius - norm(sub(*p, b.center()));
                if d > 0.0 {
                    e += 0.5 * s * b.coeffs.k * d * d;
                }
            }
        }
        for b in &self.balls {
            if b.mass.is_none() {
                continue;
            }
            for g in &self.grounds {
                let d = b.shape.radius - dot(sub(b.center(), g.point()), g.normal);
                if d > 0.0 {
                    let k = ball_ground_coeffs(self.reference_mass, b.mass.unwrap_or(1.0), g).k;
                    e += 0.5 * k * d * d;
                }
            }
        }
        e
    }

    /// Gives particle `i` the penalty stiffness `scale[i]` times each collider's (its damping
    /// ratio and friction unchanged): the collider stiffness is then per particle, from each
    /// particle's own material and size (`k_i = factor E_i r_i` for colliders made with
    /// [`ContactParams::from_material`] at a reference `E r` when `scale[i] = E_i r_i / (E r)`).
    /// An empty `scale` gives every particle the colliders' stiffness. Errors when a factor is
    /// not finite and >= 0; the length must match the particles of every later step.
    pub fn set_stiffness_scale(&mut self, scale: Vec<f64>) -> Result<(), ContactError> {
        if let Some((particle, &value)) = scale
            .iter()
            .enumerate()
            .find(|(_, s)| !s.is_finite() || **s < 0.0)
        {
            return Err(ContactError::BadParticle {
                particle,
                what: "collider stiffness scale",
                expected: "finite and >= 0",
                value,
            });
        }
        self.stiffness_scale = scale;
        Ok(())
    }

    /// Mass (kg) the ball-ground stiffness is scaled against (see
    /// [`Colliders::ball_ground_stiffness`]). Set automatically on the first [`Colliders::step`]
    /// with particles, unless set here first, to the smallest particle mass over its stiffness
    /// scale: the particle that rings fastest on a ground.
    pub fn set_reference_mass(&mut self, mass: f64) {
        assert!(
            mass.is_finite() && mass > 0.0,
            "reference mass {mass} must be > 0"
        );
        self.reference_mass = Some(mass);
    }

    /// The reference mass (kg), once known.
    pub fn reference_mass(&self) -> Option<f64> {
        self.reference_mass
    }

    /// Penalty stiffness (N/m) between dynamic ball `ball` and ground `ground`; `None` for a
    /// kinematic ball (it does not feel the ground).
    ///
    /// The ground's `stiffness` is per particle. The ball gets the same contact *frequency* as
    /// the fastest-ringing particle on that ground: `k_bg = k_g M / m_ref`, with `M` the ball
    /// mass and `m_ref` the reference mass (the smallest particle mass over its stiffness
    /// scale). So the ball-ground spring is
    /// stable at any step that is stable for particles on the ground (`omega dt < 2` with
    /// `omega = sqrt(k_g / m_ref)`), and the resting sag `M g / k_bg = m_ref g / k_g` is the
    /// sag of one particle resting on the ground: small. Damping uses the ground's ratio
    /// (`c = 2 zeta sqrt(k_bg M)`), friction its `mu` with the same no-reversal cap. Until a
    /// reference mass is known, `m_ref = M` (`k_bg = k_g`).
    pub fn ball_ground_stiffness(&self, ball: usize, ground: usize) -> Option<f64> {
        let b = &self.balls[ball];
        let m = b.mass?;
        Some(ball_ground_coeffs(self.reference_mass, m, &self.grounds[ground]).k)
    }
}

/// Overlap (m) below which two surfaces of size `scale` (m) count as touching: rounding of the
/// positions a scene computes must not make a resting object an error.
fn overlap_tolerance(scale: f64) -> f64 {
    1e-9 * scale
}

/// Ball-ground coefficients for a dynamic ball of mass `m` (kg) on ground `g`; see
/// [`Colliders::ball_ground_stiffness`].
pub(crate) fn ball_ground_coeffs(reference_mass: Option<f64>, m: f64, g: &Ground) -> Coeffs {
    let m_ref = reference_mass.unwrap_or(m);
    let k = g.coeffs.k * (m / m_ref);
    Coeffs {
        k,
        damp: 2.0 * g.params.damping_ratio * k.sqrt(),
        mu: g.coeffs.mu,
    }
}
