//! A tiny velocity-Verlet loop over free particles (no physics crate), as the driver runs it.
#![allow(dead_code)]

use perifrac_contact::{Colliders, ContactParams, ContactStats, Vec3};

/// Free particles under gravity.
pub struct World {
    pub y: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub m: Vec<f64>,
    pub r: Vec<f64>,
    /// Forces at the current positions (N), including contact.
    pub f: Vec<Vec3>,
    pub g: Vec3,
}

impl World {
    /// Particles that start clear of every collider, so the initial force is gravity alone.
    pub fn new(y: Vec<Vec3>, v: Vec<Vec3>, m: Vec<f64>, r: Vec<f64>, g: Vec3) -> Self {
        let f = m
            .iter()
            .map(|&mi| [mi * g[0], mi * g[1], mi * g[2]])
            .collect();
        Self { y, v, m, r, f, g }
    }

    /// One velocity-Verlet step: half kick, drift, forces (gravity + contact), half kick.
    pub fn step(&mut self, col: &mut Colliders, dt: f64) -> ContactStats {
        for i in 0..self.y.len() {
            for a in 0..3 {
                self.v[i][a] += 0.5 * dt * self.f[i][a] / self.m[i];
                self.y[i][a] += dt * self.v[i][a];
                self.f[i][a] = self.m[i] * self.g[a];
            }
        }
        let stats = col.step(dt, &self.y, &self.v, &self.m, &self.r, &mut self.f);
        for i in 0..self.y.len() {
            for a in 0..3 {
                self.v[i][a] += 0.5 * dt * self.f[i][a] / self.m[i];
            }
        }
        stats
    }

    /// Kinetic + gravitational + penalty-spring energy of particles and dynamic balls (J).
    pub fn energy(&self, col: &Colliders) -> f64 {
        let mut e = 0.0;
        for i in 0..self.y.len() {
            let v = self.v[i];
            let y = self.y[i];
            e += 0.5 * self.m[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            e -= self.m[i] * (self.g[0] * y[0] + self.g[1] * y[1] + self.g[2] * y[2]);
        }
        e + col.contact_energy(&self.y, &self.r)
            + col.kinetic_energy()
            + col.ball_potential_energy()
    }

    /// Total linear momentum of the particles (kg m/s).
    pub fn momentum(&self) -> Vec3 {
        let mut p = [0.0; 3];
        for (v, &m) in self.v.iter().zip(&self.m) {
            for (pa, va) in p.iter_mut().zip(v) {
                *pa += m * va;
            }
        }
        p
    }
}

/// Standard test particle: radius 1 cm, mass 1 g.
pub const R: f64 = 0.01;
pub const M: f64 = 1e-3;
pub const G: Vec3 = [0.0, 0.0, -9.81];

/// `k = E r` with E = 1e7 Pa (a stiff rubber) and r = 1 cm: 1e5 N/m, so a 1 g particle has
/// omega = sqrt(k / m) = 1e4 rad/s.
pub fn params(damping_ratio: f64, friction: f64) -> ContactParams {
    ContactParams::from_material(1e7, R, 1.0, damping_ratio, friction)
}

/// Step used with those parameters: omega dt = 0.1 (stable limit 2).
pub const DT: f64 = 1e-5;
