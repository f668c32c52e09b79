//! Stable time step of explicit integration (MODEL.md section 6): the largest angular frequency
//! `omega_max` of the linearised force operator by power iteration, `dt_crit = 2 / omega_max`.

use crate::material::ForceModel;
use crate::math::{axpy, dot, Vec3};

/// Result of the power iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrequencyEstimate {
    /// Largest angular frequency found (rad/s); a lower bound that converges from below.
    pub omega_max: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Relative change of `omega^2` in the last iteration.
    pub last_change: f64,
}

impl FrequencyEstimate {
    /// The critical step of velocity Verlet, `2 / omega_max` (s).
    pub fn critical_step(&self) -> f64 {
        2.0 / self.omega_max
    }
}

/// The highest angular frequency (rad/s) that sets the stable step of [`crate::TimeStep::Auto`],
/// and the power iteration behind it: [`max_frequency`] with 100 iterations to a relative
/// change of 1e-5, or `2 / dt` of [`ForceModel::silling_askari_step`] when the iteration finds
/// no finite positive frequency. `rest` are the positions (m) it linearises at, `horizon` (m)
/// the probe length.
pub fn stable_frequency(
    model: &mut dyn ForceModel,
    rest: &[Vec3],
    horizon: f64,
) -> (f64, FrequencyEstimate) {
    let est = max_frequency(model, rest, horizon, 100, 1e-5);
    let omega = if est.omega_max.is_finite() && est.omega_max > 0.0 {
        est.omega_max
    } else {
        2.0 / model.silling_askari_step()
    };
    (omega, est)
}

/// Power iteration on `M^-1 K`, `K` the stiffness of `model` linearised at `y0` by central
/// differences of [`ForceModel::trial_forces`] (no internal state changes). `length` is a
/// typical bond length (m) that sets the probe amplitude. Stops after `max_iterations` or when
/// the Rayleigh quotient changes by less than `tolerance` (relative). Anchors are ignored, which
/// can only raise `omega_max` (the estimate stays safe for anchored bodies).
pub fn max_frequency(
    model: &mut dyn ForceModel,
    y0: &[Vec3],
    length: f64,
    max_iterations: usize,
    tolerance: f64,
) -> FrequencyEstimate {
    let n = y0.len();
    let mass = model.masses().to_vec();
    // deterministic start vector with all modes present (a fixed-seed xorshift)
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut u: Vec<Vec3> = (0..n).map(|_| [next(), next(), next()]).collect();
    let (mut yp, mut ym) = (y0.to_vec(), y0.to_vec());
    let (mut fp, mut fm) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
    let mut ku = vec![[0.0; 3]; n];
    let mut lambda = 0.0;
    let mut change = f64::INFINITY;
    let mut it = 0;
    while it < max_iterations {
        it += 1;
        let umax = u.iter().map(|a| dot(*a, *a)).fold(0.0, f64::max).sqrt();
        if umax == 0.0 || !umax.is_finite() {
            break;
        }
        let h = 1e-6 * length / umax;
        for i in 0..n {
            yp[i] = axpy(y0[i], h, u[i]);
            ym[i] = axpy(y0[i], -h, u[i]);
        }
        model.trial_forces(&yp, &mut fp);
        model.trial_forces(&ym, &mut fm);
        let (mut uku, mut umu) = (0.0, 0.0);
        for i in 0..n {
            for d in 0..3 {
                ku[i][d] = -(fp[i][d] - fm[i][d]) / (2.0 * h);
            }
            uku += dot(u[i], ku[i]);
            umu += mass[i] * dot(u[i], u[i]);
        }
        let new = uku / umu;
        change = ((new - lambda) / new).abs();
        lambda = new;
        // u <- M^-1 K u, normalised in the mass norm
        let mut norm2 = 0.0;
        for i in 0..n {
            let inv = 1.0 / mass[i];
            u[i] = [ku[i][0] * inv, ku[i][1] * inv, ku[i][2] * inv];
            norm2 += mass[i] * dot(u[i], u[i]);
        }
        let s = 1.0 / norm2.sqrt();
        u.iter_mut()
            .for_each(|a| *a = [a[0] * s, a[1] * s, a[2] * s]);
        if change < tolerance {
            break;
        }
    }
    FrequencyEstimate {
        omega_max: lambda.max(0.0).sqrt(),
        iterations: it,
        last_change: change,
    }
}
