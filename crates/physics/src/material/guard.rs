//! The inversion guard (docs/model.md section 5, Xu's; Chen's model takes it too): a spring on each
//! bond towards the particle's least-squares affine deformation,
//! `E_inv = f/2 sum_i sum_j k_ij |eta_ij - F_i xi_ij|^2`, with `F_i` flipped (two rows swapped)
//! where `det F_i < 0` so an inverted neighbourhood is pulled back out. `F_i` is lagged: fitted
//! at [`crate::ForceModel::update_forces`] (once per step) and held fixed by trial forces and
//! energies, so within a step the guard is a quadratic energy whose gradient the forces are
//! exactly. `k_ij` is the model's own rest stiffness of the bond ([`RestStiffness`]).

use crate::family::Family;
use crate::math::{norm_squared, sub, Mat3, Vec3, IDENTITY};
use crate::par::map_particles;
use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use rayon::prelude::*;

/// A model's rest stiffness of its bonds as the guard weighs them.
pub(crate) trait RestStiffness: Sync {
    /// `(k_ij, k_ji)` (N/m) of directed bond `k` of particle `i` and of its reverse.
    fn pair(&self, i: usize, k: usize) -> (f64, f64);
}

/// What the guard reads.
pub(crate) struct GuardInputs<'a, S> {
    pub family: &'a Family,
    pub rest: &'a [Vec3],
    pub y: &'a [Vec3],
    pub stiffness: S,
    /// Intact flags per directed bond, when bonds can break.
    pub alive: Option<&'a [u8]>,
}

impl<S> GuardInputs<'_, S> {
    #[inline(always)]
    fn alive(&self, k: usize) -> bool {
        self.alive.is_none_or(|a| a[k] != 0)
    }
}

/// The lagged deformation gradients; `None` where a particle's intact bonds do not span 3D.
#[derive(Debug, Clone)]
pub(crate) struct Guard {
    f: Vec<Option<Mat3>>,
    factor: f64,
}

impl Guard {
    pub(crate) fn new(n: usize, factor: f64) -> Self {
        Guard {
            f: vec![Some(IDENTITY); n],
            factor,
        }
    }

    /// The guard's factor on the rest bond stiffness.
    pub(crate) fn factor(&self) -> f64 {
        self.factor
    }

    /// Writes the lagged gradients: a flag per particle (0 where none), then the gradients.
    pub(crate) fn save(&self, w: &mut Writer) {
        w.tag("guard");
        let flags: Vec<u8> = self.f.iter().map(|f| u8::from(f.is_some())).collect();
        w.array(&flags);
        let f: Vec<Mat3> = self.f.iter().flatten().copied().collect();
        w.array(&f);
    }

    /// Reads what [`Guard::save`] wrote.
    pub(crate) fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("guard")?;
        let mut flags = vec![0u8; self.f.len()];
        r.array_into("guard flags", &mut flags)?;
        let mut f: Vec<Mat3> = Vec::new();
        r.array_vec("lagged gradients", &mut f)?;
        let set = flags.iter().filter(|&&b| b != 0).count();
        perifrac_checkpoint::expect_count("lagged gradients", set, f.len())?;
        let mut next = f.into_iter();
        for (slot, &flag) in self.f.iter_mut().zip(&flags) {
            *slot = if flag != 0 { next.next() } else { None };
        }
        Ok(())
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.f.len() * std::mem::size_of::<Option<Mat3>>()
    }

    /// Fits `F_i = (sum k eta xi^T)(sum k xi xi^T)^-1` over intact bonds at `inp.y`, flipped
    /// where its determinant is negative.
    pub(crate) fn update<S: RestStiffness>(&mut self, inp: &GuardInputs<S>) {
        map_particles(&mut self.f, |i| fit(inp, i));
    }

    /// Adds `f sum_j [k_ij (eta - F_i xi) + k_ji (eta - F_j xi)]` to each particle's force (N).
    pub(crate) fn add_forces<S: RestStiffness>(&self, inp: &GuardInputs<S>, forces: &mut [Vec3]) {
        let (f, factor) = (&self.f, self.factor);
        let fam = inp.family;
        forces
            .par_iter_mut()
            .with_min_len(crate::par::GRAIN)
            .enumerate()
            .for_each(|(i, out)| {
                let mut acc = [0.0; 3];
                let (xi0, yi, fi) = (inp.rest[i], inp.y[i], f[i].as_ref());
                for k in fam.range(i) {
                    if !inp.alive(k) {
                        continue;
                    }
                    let j = fam.neighbours()[k] as usize;
                    let (kij, kji) = inp.stiffness.pair(i, k);
                    let xi = sub(inp.rest[j], xi0);
                    let eta = sub(inp.y[j], yi);
                    // own end, then the other (the order of the sums fixes the bits); the
                    // gradients by reference: copying both per bond cost 8% of the pass
                    for (fk, kk) in [(fi, kij), (f[j].as_ref(), kji)] {
                        if let Some(fm) = fk {
                            let res = residual(fm, eta, xi);
                            for d in 0..3 {
                                acc[d] += kk * res[d];
                            }
                        }
                    }
                }
                for d in 0..3 {
                    out[d] += factor * acc[d];
                }
            });
    }

    /// `E_inv` (J) at `inp.y` with the lagged gradients.
    pub(crate) fn energy<S: RestStiffness>(&self, inp: &GuardInputs<S>) -> f64 {
        let fam = inp.family;
        let total: f64 = (0..fam.len())
            .filter_map(|i| self.f[i].map(|fm| (i, fm)))
            .map(|(i, fm)| {
                fam.range(i)
                    .filter(|&k| inp.alive(k))
                    .map(|k| {
                        let j = fam.neighbours()[k] as usize;
                        let xi = sub(inp.rest[j], inp.rest[i]);
                        let eta = sub(inp.y[j], inp.y[i]);
                        inp.stiffness.pair(i, k).0 * norm_squared(residual(&fm, eta, xi))
                    })
                    .sum::<f64>()
            })
            .sum();
        0.5 * self.factor * total
    }
}

/// `eta - F xi`.
#[inline(always)]
fn residual(f: &Mat3, eta: Vec3, xi: Vec3) -> Vec3 {
    let fx = crate::math::mat_vec(f, xi);
    sub(eta, fx)
}

fn fit<S: RestStiffness>(inp: &GuardInputs<S>, i: usize) -> Option<Mat3> {
    let fam = inp.family;
    let (mut a, mut b) = ([[0.0; 3]; 3], [[0.0; 3]; 3]);
    for k in fam.range(i) {
        if !inp.alive(k) {
            continue;
        }
        let j = fam.neighbours()[k] as usize;
        let w = inp.stiffness.pair(i, k).0;
        let xi = sub(inp.rest[j], inp.rest[i]);
        let eta = sub(inp.y[j], inp.y[i]);
        for r in 0..3 {
            for c in 0..3 {
                a[r][c] += w * eta[r] * xi[c];
                b[r][c] += w * xi[r] * xi[c];
            }
        }
    }
    let binv = inverse(&b)?;
    let mut f = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            f[r][c] = (0..3).map(|m| a[r][m] * binv[m][c]).sum();
        }
    }
    if det(&f) < 0.0 {
        f.swap(0, 1);
    }
    Some(f)
}

fn det(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Inverse of a symmetric positive semi-definite moment matrix, `None` when it is singular
/// relative to its size (bonds that do not span 3D).
fn inverse(m: &Mat3) -> Option<Mat3> {
    let d = det(m);
    let scale = (m[0][0] + m[1][1] + m[2][2]).powi(3);
    if !(scale > 0.0 && d > 1e-9 * scale) {
        return None;
    }
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    Some([
        [c(1, 2, 1, 2) / d, -c(0, 2, 1, 2) / d, c(0, 1, 1, 2) / d],
        [-c(1, 2, 0, 2) / d, c(0, 2, 0, 2) / d, -c(0, 1, 0, 2) / d],
        [c(1, 2, 0, 1) / d, -c(0, 2, 0, 1) / d, c(0, 1, 0, 1) / d],
    ])
}
