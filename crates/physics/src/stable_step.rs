//! Stable time step of explicit integration (docs/model.md section 6): the largest angular
//! frequency `omega_max` of the linearised force operator, `dt_crit = 2 / omega_max`. The setup's
//! estimate is Lanczos on `M^-1 K` ([`lanczos_frequency`]); power iteration ([`max_frequency`])
//! is kept as its slower reference.

use crate::material::ForceModel;
use crate::math::{axpy, dot, Vec3};

/// Result of an eigenvalue iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrequencyEstimate {
    /// Largest angular frequency found (rad/s); a lower bound that converges from below.
    pub omega_max: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Force evaluations spent (each costs about one explicit step).
    pub evaluations: usize,
    /// Relative change of `omega^2` in the last iteration.
    pub last_change: f64,
    /// Whether the estimate was recalled from an [`EstimateMemo`] (then `evaluations` counts
    /// only those that identified the operator, one or two; `iterations` and `last_change` are
    /// those of the run that stored it).
    pub recalled: bool,
}

impl FrequencyEstimate {
    /// The critical step of velocity Verlet, `2 / omega_max` (s).
    pub fn critical_step(&self) -> f64 {
        2.0 / self.omega_max
    }
}

/// A store of finished Lanczos estimates between runs (a directory of small files, say),
/// looked up by a key that the operator itself writes: see [`lanczos_frequency_of`].
pub trait EstimateMemo {
    /// The estimate stored under `key`, if any.
    fn recall(&self, key: MemoKey) -> Option<FrequencyEstimate>;
    /// Keeps `estimate` under `key`; a store that fails only costs the next run the iteration.
    fn store(&self, key: MemoKey, estimate: &FrequencyEstimate);
}

/// 128 bits that identify one Lanczos iteration: its settings, the masses, the point it
/// linearises at and the bits of the forces there and at the first probe (two SipHash-1-3
/// digests of the same words).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MemoKey(pub [u64; 2]);

impl MemoKey {
    /// 32 lower-case hex digits.
    pub fn hex(&self) -> String {
        format!("{:016x}{:016x}", self.0[0], self.0[1])
    }
}

/// Bumped whenever the iteration changes (start vector, probe, stopping rule), so a memo
/// written by an older iteration is never read as this one's.
const MEMO_VERSION: u64 = 1;

/// Hashes everything the rest of a Lanczos run is a function of. The start vector and every
/// later probe follow from `n`, the first evaluations and the settings; a model whose
/// linearised forces differ anywhere differs in `f1` (the start vector moves every particle)
/// unless the difference is below round-off, and then the estimate is that of the same
/// operator anyway.
fn memo_key(settings: [f64; 4], mass: &[f64], y0: &[Vec3], f0: &[Vec3], f1: &[Vec3]) -> MemoKey {
    use std::hash::Hasher;
    let digest = |salt: u64| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        h.write_u64(salt);
        h.write_u64(MEMO_VERSION);
        h.write_u64(mass.len() as u64);
        settings.iter().for_each(|v| h.write_u64(v.to_bits()));
        mass.iter().for_each(|v| h.write_u64(v.to_bits()));
        for field in [y0, f0, f1] {
            field
                .iter()
                .flatten()
                .for_each(|v| h.write_u64(v.to_bits()));
        }
        h.finish()
    };
    MemoKey([digest(0x5eed_0001), digest(0x5eed_0002)])
}

/// Most Lanczos iterations of the setup's estimate.
pub const LANCZOS_ITERATIONS: usize = 100;

/// Relative change of the largest Ritz value at which the setup's Lanczos estimate stops. At
/// 1e-6, against power iteration run to a change of 1e-12, it was 1.7e-7, 4.3e-7 and 8.9e-7
/// low on the default wall, the dropped bunny and the jello, and 1.8e-5 above it on the
/// armadillo (where power iteration settled below the top), after 22, 17, 34 and 13 force
/// evaluations (power iteration stopped at a change of 1e-5 had taken 140, 74, 200 and 56, and
/// on the jello had stopped at its cap of 100 iterations 0.67% low).
pub const LANCZOS_TOLERANCE: f64 = 1e-6;

/// The highest angular frequency (rad/s) that sets the stable step of [`crate::TimeStep::Auto`],
/// and the iteration behind it: [`lanczos_frequency`] with [`LANCZOS_ITERATIONS`] and
/// [`LANCZOS_TOLERANCE`], or `2 / dt` of [`ForceModel::silling_askari_step`] when it finds no
/// finite positive frequency. `rest` are the positions (m) it linearises at, `horizon` (m) the
/// probe length.
pub fn stable_frequency(
    model: &mut dyn ForceModel,
    rest: &[Vec3],
    horizon: f64,
) -> (f64, FrequencyEstimate) {
    stable_frequency_memo(model, rest, horizon, None)
}

/// [`stable_frequency`], recalling the estimate from `memo` when the same iteration on the
/// same operator was stored there (the result is the stored one bit for bit) and storing it
/// there otherwise. Where the model vouches that its forces at `rest` vanish
/// ([`ForceModel::forces_vanish_at`]) they are not evaluated: a recalled estimate then costs one
/// force evaluation, an iterated one an evaluation less.
pub fn stable_frequency_memo(
    model: &mut dyn ForceModel,
    rest: &[Vec3],
    horizon: f64,
    memo: Option<&dyn EstimateMemo>,
) -> (f64, FrequencyEstimate) {
    let mass = model.masses().to_vec();
    let at_rest = model.forces_vanish_at(rest);
    let est = lanczos(
        &mass,
        (rest, at_rest),
        horizon,
        (LANCZOS_ITERATIONS, LANCZOS_TOLERANCE),
        &mut |y: &[Vec3], f: &mut [Vec3]| model.trial_forces(y, f),
        memo,
    );
    let omega = if est.omega_max.is_finite() && est.omega_max > 0.0 {
        est.omega_max
    } else {
        2.0 / model.silling_askari_step()
    };
    (omega, est)
}

/// A deterministic start vector with all modes present (fixed-seed xorshift in [-0.5, 0.5)).
pub(crate) fn start_vector(n: usize) -> Vec<Vec3> {
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

/// `sqrt(v^T M v)`.
fn mass_norm(v: &[Vec3], mass: &[f64]) -> f64 {
    v.iter()
        .zip(mass)
        .map(|(a, m)| m * dot(*a, *a))
        .sum::<f64>()
        .sqrt()
}

/// Scales `v` by `s`.
fn scale(v: &mut [Vec3], s: f64) {
    v.iter_mut()
        .for_each(|a| *a = [a[0] * s, a[1] * s, a[2] * s]);
}

/// The probe step along `u` (m per unit of `u`): its largest displacement is `1e-6 length`;
/// `None` for a zero or non-finite `u`.
fn probe(u: &[Vec3], length: f64) -> Option<f64> {
    let umax = u.iter().map(|a| dot(*a, *a)).fold(0.0, f64::max).sqrt();
    (umax > 0.0 && umax.is_finite()).then(|| 1e-6 * length / umax)
}

/// Power iteration on `M^-1 K`, `K` the stiffness of `model` linearised at `y0` by central
/// differences of [`ForceModel::trial_forces`] (no internal state changes; two evaluations per
/// iteration). `length` is a typical bond length (m) that sets the probe amplitude. Stops after
/// `max_iterations` or when the Rayleigh quotient changes by less than `tolerance` (relative).
/// Anchors are ignored, which can only raise `omega_max` (the estimate stays safe for anchored
/// bodies). Slow where the top of the spectrum is dense: the reference for
/// [`lanczos_frequency`].
pub fn max_frequency(
    model: &mut dyn ForceModel,
    y0: &[Vec3],
    length: f64,
    max_iterations: usize,
    tolerance: f64,
) -> FrequencyEstimate {
    let n = y0.len();
    let mass = model.masses().to_vec();
    let mut u = start_vector(n);
    let (mut yp, mut ym) = (y0.to_vec(), y0.to_vec());
    let (mut fp, mut fm) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
    let mut ku = vec![[0.0; 3]; n];
    let mut lambda = 0.0;
    let mut change = f64::INFINITY;
    let mut it = 0;
    while it < max_iterations {
        let Some(h) = probe(&u, length) else {
            break;
        };
        it += 1;
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
        for i in 0..n {
            let inv = 1.0 / mass[i];
            u[i] = [ku[i][0] * inv, ku[i][1] * inv, ku[i][2] * inv];
        }
        let s = 1.0 / mass_norm(&u, &mass);
        scale(&mut u, s);
        if change < tolerance {
            break;
        }
    }
    FrequencyEstimate {
        omega_max: lambda.max(0.0).sqrt(),
        iterations: it,
        evaluations: 2 * it,
        last_change: change,
        recalled: false,
    }
}

/// Lanczos on `M^-1 K` (self-adjoint in the mass inner product), `K` the stiffness of `model`
/// linearised at `y0` by one-sided differences of [`ForceModel::trial_forces`] from the
/// forces at `y0` (no internal state changes): one evaluation per iteration after the one at
/// `y0`. The largest eigenvalue of the Lanczos tridiagonal matrix is a lower bound on the
/// operator's that rises with each iteration, and rises much faster than power iteration's
/// Rayleigh quotient where the top of the spectrum is dense (the highest modes of a large body
/// differ little). Stops after `max_iterations`, when it changes by less than `tolerance`
/// (relative), or when the Krylov space is exhausted. `length` (m) sets the probe amplitude;
/// anchors are ignored, as in [`max_frequency`]. Without reorthogonalisation: lost
/// orthogonality repeats converged Ritz values but does not move the largest.
pub fn lanczos_frequency(
    model: &mut dyn ForceModel,
    y0: &[Vec3],
    length: f64,
    max_iterations: usize,
    tolerance: f64,
) -> FrequencyEstimate {
    let mass = model.masses().to_vec();
    lanczos_frequency_of(
        &mass,
        y0,
        length,
        max_iterations,
        tolerance,
        &mut |y: &[Vec3], f: &mut [Vec3]| model.trial_forces(y, f),
        None,
    )
}

/// [`lanczos_frequency`] for any system of point masses `mass` (kg) whose forces (N) at
/// positions `y` (m) `forces(y, f)` writes into `f` (a thin shell's, say): the same iteration,
/// linearised at `y0`. With a `memo` of finished estimates: after the forces at `y0` and at the
/// first probe, the bits of both (with the masses, `y0` and the settings) make the key; the
/// rest of the iteration is a function of them, so an estimate stored under that key is the one
/// the iteration would reach now, and is returned as it was stored (`recalled`, two
/// evaluations spent). Otherwise the iteration runs on and stores its result there.
pub fn lanczos_frequency_of(
    mass: &[f64],
    y0: &[Vec3],
    length: f64,
    max_iterations: usize,
    tolerance: f64,
    forces: &mut dyn FnMut(&[Vec3], &mut [Vec3]),
    memo: Option<&dyn EstimateMemo>,
) -> FrequencyEstimate {
    let settings = (max_iterations, tolerance);
    lanczos(mass, (y0, false), length, settings, forces, memo)
}

/// [`lanczos_frequency_of`], told whether the forces at `y0` vanish (`at_rest`,
/// [`ForceModel::forces_vanish_at`]): then they are taken as zeros, not evaluated, and a
/// recalled estimate costs one evaluation.
fn lanczos(
    mass: &[f64],
    (y0, at_rest): (&[Vec3], bool),
    length: f64,
    (max_iterations, tolerance): (usize, f64),
    forces: &mut dyn FnMut(&[Vec3], &mut [Vec3]),
    memo: Option<&dyn EstimateMemo>,
) -> FrequencyEstimate {
    let n = y0.len();
    let mut key = None;
    let mut q = start_vector(n);
    let s = 1.0 / mass_norm(&q, mass);
    scale(&mut q, s);
    // `w` holds the previous Lanczos vector until it is overwritten by the next residual
    let mut w = vec![[0.0; 3]; n];
    let mut y = y0.to_vec();
    let (mut f0, mut f) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
    if !at_rest {
        forces(y0, &mut f0);
    }
    let spent = usize::from(!at_rest);
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    let (mut theta, mut beta) = (0.0, 0.0);
    let mut change = f64::INFINITY;
    let mut it = 0;
    while it < max_iterations {
        let Some(h) = probe(&q, length) else {
            break;
        };
        it += 1;
        for i in 0..n {
            y[i] = axpy(y0[i], h, q[i]);
        }
        forces(&y, &mut f);
        if let (Some(_), 1) = (memo, it) {
            key = Some(memo_key(
                [max_iterations as f64, tolerance, length, h],
                mass,
                y0,
                &f0,
                &f,
            ));
        }
        // K q into f; alpha = q^T K q
        let mut alpha = 0.0;
        for i in 0..n {
            for d in 0..3 {
                f[i][d] = -(f[i][d] - f0[i][d]) / h;
            }
            alpha += dot(q[i], f[i]);
        }
        if let (Some(memo), Some(k), 1) = (memo, key, it) {
            // the iteration's result is its largest Ritz value, never below this first one
            // (to the rounding of its square root): a stored value that is (a damaged or
            // foreign file) would allow too long a step, and is not taken
            let credible =
                |s: &FrequencyEstimate| s.omega_max * s.omega_max >= alpha * (1.0 - 1e-12);
            if let Some(stored) = memo.recall(k).filter(credible) {
                return FrequencyEstimate {
                    evaluations: 1 + spent,
                    recalled: true,
                    ..stored
                };
            }
        }
        for i in 0..n {
            let inv = 1.0 / mass[i];
            for d in 0..3 {
                w[i][d] = f[i][d] * inv - alpha * q[i][d] - beta * w[i][d];
            }
        }
        alphas.push(alpha);
        let new = tridiagonal_max(&alphas, &betas);
        change = ((new - theta) / new).abs();
        theta = new;
        beta = mass_norm(&w, mass);
        if change < tolerance || !(beta > 0.0 && beta.is_finite()) {
            break;
        }
        betas.push(beta);
        // next vector w / beta into q, the current one into w
        let s = 1.0 / beta;
        for (qi, wi) in q.iter_mut().zip(w.iter_mut()) {
            let next = [wi[0] * s, wi[1] * s, wi[2] * s];
            *wi = *qi;
            *qi = next;
        }
    }
    let est = FrequencyEstimate {
        omega_max: theta.max(0.0).sqrt(),
        iterations: it,
        evaluations: it + spent,
        last_change: change,
        recalled: false,
    };
    if let (Some(memo), Some(k)) = (memo, key) {
        memo.store(k, &est);
    }
    est
}

/// Largest eigenvalue of the symmetric tridiagonal matrix with diagonal `a` and off-diagonal
/// `b` (`b.len() + 1 == a.len()`), by bisection on Sturm counts to the last bit.
fn tridiagonal_max(a: &[f64], b: &[f64]) -> f64 {
    let k = a.len();
    let off = |i: usize| if i < b.len() { b[i].abs() } else { 0.0 };
    // Gershgorin interval of all eigenvalues
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, &ai) in a.iter().enumerate() {
        let r = off(i) + if i > 0 { off(i - 1) } else { 0.0 };
        lo = lo.min(ai - r);
        hi = hi.max(ai + r);
    }
    // eigenvalues below x: the negative pivots of T - x I = L D L^T
    let below = |x: f64| {
        let mut count = 0;
        let mut d = 1.0;
        for (i, &ai) in a.iter().enumerate() {
            d = if i == 0 {
                ai - x
            } else {
                ai - x - b[i - 1] * b[i - 1] / d
            };
            if d == 0.0 {
                d = -f64::MIN_POSITIVE;
            }
            if d < 0.0 {
                count += 1;
            }
        }
        count
    };
    loop {
        let mid = 0.5 * (lo + hi);
        if !(mid > lo && mid < hi) {
            return hi;
        }
        if below(mid) < k {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tridiagonal_max;

    #[test]
    fn tridiagonal_max_matches_closed_forms() {
        // 2 x 2: (a + c) / 2 + sqrt(((a - c) / 2)^2 + b^2)
        let got = tridiagonal_max(&[1.0, 3.0], &[2.0]);
        let want = 2.0 + (1.0f64 + 4.0).sqrt();
        assert!(
            (got - want).abs() <= 4.0 * f64::EPSILON * want,
            "{got} {want}"
        );
        // the k x k matrix tridiag(-1, 2, -1): 2 - 2 cos(k pi / (k + 1))
        for k in [1usize, 2, 7, 40] {
            let got = tridiagonal_max(&vec![2.0; k], &vec![-1.0; k - 1]);
            let want = 2.0 - 2.0 * (k as f64 * std::f64::consts::PI / (k as f64 + 1.0)).cos();
            assert!((got - want).abs() <= 1e-14 * want, "k {k}: {got} {want}");
        }
    }
}
