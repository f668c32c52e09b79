//! The step matrix against the Hessian of `Phi`, and the implicit step's error paths.

use super::*;
use crate::environment::{External, ImplicitEnvironment};
use crate::material::{Curve, XuMaterial, XuModel, XuModuli, XuOptions};
use crate::particles::Discretization;
use crate::ForceModel;
use perifrac_topology::primitives::box_data;
use perifrac_topology::TetMesh;

fn xu_block(cells: [usize; 3], h: Curve, options: XuOptions) -> XuModel {
    let size = cells.map(|c| c as f64 * 0.01);
    let (v, t) = box_data([0.0; 3], size, cells);
    let (mesh, _) = TetMesh::new(v, t).unwrap();
    let (disc, _) = Discretization::from_tets(
        &mesh.rest_barycentres(),
        &mesh.rest_volumes(),
        mesh.neighbours(),
        1.5 * mesh.mean_edge_length(),
    )
    .unwrap();
    let mat = XuMaterial::from_young_poisson(1e5, 0.3, 1000.0, h.clone(), h, XuModuli::Consistent)
        .unwrap();
    XuModel::new(disc, &[mat], options).unwrap()
}

/// `(S (x) I_3, H)` at rest, both `3n x 3n` row-major: `S` as assembled for `dt`, `H` the
/// Hessian of `Phi` by central differences of the forces.
fn matrices(model: &mut XuModel, dt: f64) -> (Vec<f64>, Vec<f64>) {
    let x = model.discretization().rest_positions().to_vec();
    let n = x.len();
    let sim = Implicit::new(
        model.clone(),
        &x,
        Loads::new(n),
        ImplicitConfig::with_dt(dt),
    )
    .unwrap();
    let s1 = sim.integrator.matrix.dense();
    let m = 3 * n;
    let mut s = vec![0.0; m * m];
    for i in 0..n {
        for j in 0..n {
            for d in 0..3 {
                s[(3 * i + d) * m + 3 * j + d] = s1[i * n + j];
            }
        }
    }
    let mut hess = vec![0.0; m * m];
    let h = 1e-7;
    let (mut fp, mut fm) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
    for j in 0..n {
        for e in 0..3 {
            let (mut yp, mut ym) = (x.clone(), x.clone());
            yp[j][e] += h;
            ym[j][e] -= h;
            model.trial_forces(&yp, &mut fp);
            model.trial_forces(&ym, &mut fm);
            for i in 0..n {
                for d in 0..3 {
                    hess[(3 * i + d) * m + 3 * j + e] = -(fp[i][d] - fm[i][d]) / (2.0 * h);
                }
            }
        }
        let mass = model.masses()[j] / (dt * dt);
        for e in 0..3 {
            hess[(3 * j + e) * m + 3 * j + e] += mass;
        }
    }
    (s, hess)
}

fn eigenvalues(a: &[f64], m: usize) -> Vec<f64> {
    let mat = faer::Mat::<f64>::from_fn(m, m, |r, c| 0.5 * (a[r * m + c] + a[c * m + r]));
    mat.self_adjoint_eigenvalues(faer::Side::Lower).unwrap()
}

/// `S` is symmetric positive definite, and it bounds the true Hessian of `Phi` at rest from
/// above: `S - H` is positive semi-definite. docs/model.md's `S` is not the Hessian itself: each
/// bond contributes `k I_3` where the Hessian has `k n n^T`, and the dilatation term's
/// coupling of a particle's whole family is replaced by its pairwise Cauchy-Schwarz bound
/// (`(sum_j w V a_j)^2 <= sum_j w V a_j^2` with `sum_j w V = 1`). So `S` agrees with `H` on the
/// mass, is exact on uniform translations, and overestimates every other curvature: a step
/// with `S` never overshoots at rest. (With the normalised weights; the fitted dilatation keeps
/// the same `S`, below.)
#[test]
fn step_matrix_is_spd_and_bounds_the_rest_hessian() {
    let options = XuOptions {
        fitted_dilatation: false,
        ..XuOptions::default()
    };
    let mut model = xu_block([3, 2, 2], Curve::NeoHookean, options);
    let n = model.num_particles();
    let m = 3 * n;
    for dt in [1e-3, 1e-1] {
        let (s, h) = matrices(&mut model, dt);
        for r in 0..m {
            for c in 0..m {
                assert_eq!(s[r * m + c], s[c * m + r]);
            }
        }
        let ev_s = eigenvalues(&s, m);
        let scale = ev_s.iter().cloned().fold(0.0, f64::max);
        assert!(ev_s[0] > 0.0, "S not positive definite: {}", ev_s[0]);
        // the FD Hessian carries truncation ~h^2 and rounding ~1e-16 |f| / h; 1e-7 of the
        // largest eigenvalue is far above both and far below any real violation
        let diff: Vec<f64> = s.iter().zip(&h).map(|(a, b)| a - b).collect();
        let ev_d = eigenvalues(&diff, m);
        assert!(
            ev_d[0] > -1e-7 * scale,
            "S - H has eigenvalue {:e} of {scale:e}",
            ev_d[0]
        );
        // the bound is not trivial: S overestimates some curvature by a factor of several
        let ev_h = eigenvalues(&h, m);
        let top = ev_h.iter().cloned().fold(0.0, f64::max);
        eprintln!(
            "dt {dt}: eig S {:e}..{scale:e}, eig H {:e}..{top:e}, eig (S - H) min {:e}",
            ev_s[0], ev_h[0], ev_d[0]
        );
        assert!(scale > 1.5 * top);
        // translations: S u = H u = M u / dt^2
        let mut u = vec![0.0; m];
        for i in 0..n {
            u[3 * i] = 1.0;
        }
        for r in 0..m {
            let (su, hu): (f64, f64) = (0..m).fold((0.0, 0.0), |(a, b), c| {
                (a + s[r * m + c] * u[c], b + h[r * m + c] * u[c])
            });
            assert!((su - hu).abs() <= 1e-6 * scale, "row {r}: {su} vs {hu}");
        }
    }
}

/// The fitted dilatation keeps the normalised weights' `S` bit for bit (a preconditioner
/// measured faster than the springs that bound the fitted Hessian; docs/DECISIONS.md), so `S`
/// stays symmetric positive definite while its corner families' fitted curvature can pass it.
#[test]
fn the_fitted_dilatation_keeps_the_step_matrix() {
    let plain = XuOptions {
        fitted_dilatation: false,
        ..XuOptions::default()
    };
    let fitted = XuOptions {
        fitted_dilatation: true,
        ..plain
    };
    let mut a = xu_block([3, 2, 2], Curve::NeoHookean, plain);
    let mut b = xu_block([3, 2, 2], Curve::NeoHookean, fitted);
    let m = 3 * a.num_particles();
    let (sa, _) = matrices(&mut a, 1e-3);
    let (sb, hb) = matrices(&mut b, 1e-3);
    assert!(sa.iter().zip(&sb).all(|(x, y)| x.to_bits() == y.to_bits()));
    let diff: Vec<f64> = sb.iter().zip(&hb).map(|(s, h)| s - h).collect();
    let ev = eigenvalues(&diff, m);
    let top = eigenvalues(&sb, m).into_iter().fold(0.0, f64::max);
    eprintln!("fitted: eig (S - H) min {:e} of eig S max {top:e}", ev[0]);
}

/// An environment that pushes particle 0 at the predictor but whose potential is not finite
/// anywhere else: the line search can never accept, and the step reports it.
struct Poisoned(Option<Vec3>);
impl Environment for Poisoned {
    fn add_forces(&mut self, _ext: External<'_>) {}
    fn implicit(&mut self) -> Option<&mut dyn ImplicitEnvironment> {
        Some(self)
    }
}
impl ImplicitEnvironment for Poisoned {
    fn begin(&mut self, _: f64, _: &[Vec3], _: &[Vec3], _: &[f64]) -> Result<(), PhysicsError> {
        Ok(())
    }
    fn bodies(&self) -> usize {
        0
    }
    fn body_guess(&self, _: &mut [Vec3]) {}
    fn body_curvature(&self, _: &mut [f64]) {}
    fn potential(
        &mut self,
        q: &[Vec3],
        _: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        let first = *self.0.get_or_insert(q[0]);
        if q[0] != first {
            return f64::NAN;
        }
        if let Some((g, _)) = grad {
            g[0][2] += 1.0;
        }
        0.0
    }
    fn end(&mut self, _: &[Vec3], _: &[Vec3], _: &[Vec3]) {}
}

#[test]
fn a_step_that_cannot_decrease_phi_is_an_error_and_a_failed_factor_too() {
    let model = xu_block([2, 2, 2], Curve::Linear, XuOptions::default());
    let x = model.discretization().rest_positions().to_vec();
    let n = x.len();
    let loads = Loads::new(n).with_gravity([0.0, 0.0, -9.81]);
    let mut sim = Implicit::new(model, &x, loads, ImplicitConfig::with_dt(0.01)).unwrap();
    // every trial along the direction is NaN
    let e = sim.step_in(&mut Poisoned(None)).unwrap_err();
    assert!(matches!(e, PhysicsError::Stalled { .. }), "{e}");
    assert!(e.to_string().contains("no decrease"), "{e}");
    // an objective already not finite at the predictor is an error too, not a silent NaN
    let mut nan = Poisoned(Some([f64::NAN; 3]));
    let e = sim.step_in(&mut nan).unwrap_err();
    assert!(matches!(e, PhysicsError::NotFinite { .. }), "{e}");
    // a step matrix with a negative pair stiffness is not positive definite: a clear error
    let model = xu_block([2, 2, 2], Curve::Linear, XuOptions::default());
    let family = model.discretization().family();
    let mut m = StepMatrix::new(family, &vec![false; n]).unwrap();
    let pair = vec![-1.0; family.num_bonds()];
    let e = m.factor(family, |_| 1e-3, &pair).unwrap_err();
    assert!(e.to_string().contains("not positive definite"), "{e}");
}
