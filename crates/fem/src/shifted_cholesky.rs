//! Sparse Cholesky of a tangent that may be indefinite: the symbolic factorisation (AMD
//! ordering) once, then per matrix a numeric factorisation, retried on `K + tau I` with `tau`
//! growing tenfold from 1e-6 of the mean diagonal when `K` is not positive definite.
//!
//! Why a shift and not LDLT or LU: far from equilibrium (or past a buckling load) the tangent
//! of an energy is indefinite, and the exact Newton step of an indefinite matrix need not go
//! downhill in energy, so a line search on the energy could find no decrease along it. The
//! shifted matrix is positive definite, so its step is always a descent direction; close to a
//! stable equilibrium the tangent is positive definite, no shift is applied and Newton's
//! quadratic convergence is kept. Cholesky fails exactly when the matrix is not positive
//! definite, which is the test needed.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::linalg::LltError;
use faer::{MatMut, Side};

use crate::assembly::{cholesky_error, LowerPattern};
use crate::error::FemError;

/// Shifts tried, from 1e-6 to 1e7 times the mean diagonal.
const SHIFTS: usize = 14;

pub(crate) struct ShiftedCholesky {
    symbolic: SymbolicLlt<u32>,
    shifted: Vec<f64>,
    /// Whether the next factorisation is the first one (at rest, where a failure means the
    /// body is not held, and is reported rather than shifted away).
    first: bool,
}

impl ShiftedCholesky {
    pub fn new(pattern: &LowerPattern) -> Result<Self, FemError> {
        let symbolic = SymbolicLlt::try_new(pattern.symbolic.as_ref(), Side::Lower)
            .map_err(|e| FemError::Solver(format!("{e:?}")))?;
        Ok(Self {
            symbolic,
            shifted: Vec::new(),
            first: true,
        })
    }

    /// Factorises the matrix with `values` (lower triangle, `pattern`'s order) and solves for
    /// `rhs` in place; returns whether a shift was needed. The first call fails with
    /// [`FemError::NotPositiveDefinite`] instead of shifting.
    pub fn solve_in_place(
        &mut self,
        pattern: &LowerPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<bool, FemError> {
        let n = rhs.len();
        let first = std::mem::replace(&mut self.first, false);
        let (llt, shifted) = match Llt::try_new_with_symbolic(
            self.symbolic.clone(),
            pattern.matrix(values),
            Side::Lower,
        ) {
            Ok(llt) => (llt, false),
            Err(LltError::Numeric(_)) if !first => (self.shifted_factor(pattern, values)?, true),
            Err(e) => return Err(cholesky_error(e, n)),
        };
        llt.solve_in_place(MatMut::from_column_major_slice_mut(rhs, n, 1));
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(FemError::Solver("the Newton step is not finite".into()));
        }
        Ok(shifted)
    }

    fn shifted_factor(
        &mut self,
        pattern: &LowerPattern,
        values: &[f64],
    ) -> Result<Llt<u32, f64>, FemError> {
        let n = pattern.symbolic.ncols();
        let mean_diag = (0..n)
            .map(|c| values[pattern.diagonal(c)].abs())
            .sum::<f64>()
            / n as f64;
        let mut tau = 1e-6 * mean_diag;
        for _ in 0..SHIFTS {
            self.shifted.clear();
            self.shifted.extend_from_slice(values);
            for c in 0..n {
                self.shifted[pattern.diagonal(c)] += tau;
            }
            let m = pattern.matrix(&self.shifted);
            if let Ok(llt) = Llt::try_new_with_symbolic(self.symbolic.clone(), m, Side::Lower) {
                return Ok(llt);
            }
            tau *= 10.0;
        }
        Err(FemError::Solver(
            "the tangent stays indefinite after a shift of 1e7 times its mean diagonal".into(),
        ))
    }
}
