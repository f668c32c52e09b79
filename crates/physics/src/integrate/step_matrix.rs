//! The constant matrix of the quasi-Newton step (docs/model.md section 5),
//! `S = M / dt^2 + c M / dt + L` with `L = sum_bonds k_ij (e_i - e_j)(e_i - e_j)^T`, on the free
//! (not anchored) particles. `L` is the same for the three coordinates, so `S = S_1 (x) I_3`
//! and only the scalar `n_free x n_free` matrix `S_1` is factored (a third of the unknowns:
//! about a ninth of the factor's memory and a 27th of its flops against factoring `S`), then
//! solved for three right-hand sides. Sparse Cholesky by faer with its approximate minimum
//! degree ordering; the symbolic factorisation is done once per free set, every buffer is
//! allocated then, and a refactorisation or a solve allocates nothing.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::error::PhysicsError;
use crate::family::Family;

/// Marks an anchored particle in the free numbering.
pub(crate) const HELD: u32 = u32::MAX;

/// The factored step matrix on one free set.
pub(crate) struct StepMatrix {
    /// Free index of each particle, or [`HELD`].
    pub free: Vec<u32>,
    /// Particle of each free index.
    pub particles: Vec<u32>,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    /// For each directed bond `k` of a free particle whose neighbour is free with a larger free
    /// index: its slot in `values` (else `u32::MAX`).
    slot: Vec<u32>,
    values: Vec<f64>,
    symbolic: SymbolicCholesky<u32>,
    factor: Vec<f64>,
    buffer: MemBuffer,
    /// Right-hand sides, column-major `n_free x 3`.
    pub rhs: Vec<f64>,
}

impl StepMatrix {
    /// The pattern of `S_1` on the particles not `held`, and its symbolic factorisation.
    pub fn new(family: &Family, held: &[bool]) -> Result<Self, PhysicsError> {
        let n = family.len();
        let mut free = vec![HELD; n];
        let mut particles = Vec::new();
        for i in 0..n {
            if !held[i] {
                free[i] = particles.len() as u32;
                particles.push(i as u32);
            }
        }
        let nf = particles.len();
        let mut col_ptr = Vec::with_capacity(nf + 1);
        let mut row_idx = Vec::new();
        let mut slot = vec![u32::MAX; family.num_bonds()];
        col_ptr.push(0u32);
        for &p in &particles {
            let i = p as usize;
            row_idx.push(free[i]);
            // neighbours are sorted by particle index, and the free numbering grows with it
            for k in family.range(i) {
                let fj = free[family.neighbours()[k] as usize];
                if fj != HELD && fj > free[i] {
                    slot[k] = row_idx.len() as u32;
                    row_idx.push(fj);
                }
            }
            let len = u32::try_from(row_idx.len())
                .map_err(|_| PhysicsError::TooManyBonds(row_idx.len()))?;
            col_ptr.push(len);
        }
        let symbolic = {
            let pattern = SymbolicSparseColMatRef::new_checked(nf, nf, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(
                pattern,
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(|e| PhysicsError::Factorization(format!("symbolic: {e:?}")))?
        };
        let factor = vec![0.0; symbolic.len_val()];
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(3, Par::Seq),
        ]);
        let buffer = MemBuffer::try_new(req)
            .map_err(|_| PhysicsError::Factorization("out of memory for the factor".into()))?;
        Ok(StepMatrix {
            values: vec![0.0; row_idx.len()],
            rhs: vec![0.0; 3 * nf],
            free,
            particles,
            col_ptr,
            row_idx,
            slot,
            symbolic,
            factor,
            buffer,
        })
    }

    /// Free particles.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Whether the free set is that of `held`.
    pub fn matches(&self, held: &[bool]) -> bool {
        held.iter().zip(&self.free).all(|(&h, &f)| h == (f == HELD))
    }

    /// Heap bytes of the factor and its pattern.
    pub fn bytes(&self) -> usize {
        8 * (self.factor.len() + self.values.len())
            + 4 * (self.col_ptr.len() + self.row_idx.len() + self.slot.len())
    }

    /// Assembles `S_1` with diagonal mass term `diag[i]` (N/m per free particle's own
    /// `m / dt^2 + c m / dt`) and pair stiffness `pair[k] = k_ij + k_ji` (N/m) per directed bond,
    /// then factors it. Returns the wall time of the numeric factorisation (s).
    pub fn factor(
        &mut self,
        family: &Family,
        diag: impl Fn(usize) -> f64,
        pair: &[f64],
    ) -> Result<f64, PhysicsError> {
        self.values.fill(0.0);
        for (fi, &p) in self.particles.iter().enumerate() {
            let i = p as usize;
            let d = self.col_ptr[fi] as usize;
            let mut sum = diag(i);
            for k in family.range(i) {
                sum += pair[k];
                let s = self.slot[k];
                if s != u32::MAX {
                    self.values[s as usize] = -pair[k];
                }
            }
            self.values[d] = sum;
        }
        let started = Instant::now();
        let nf = self.len();
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(nf, nf, &self.col_ptr, None, &self.row_idx),
            &self.values,
        );
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.factor,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.buffer),
                Default::default(),
            )
            .map_err(|e| {
                PhysicsError::Factorization(format!(
                    "the step matrix is not positive definite ({e:?}): a bond stiffness is \
                     negative or a free body has no mass"
                ))
            })?;
        Ok(started.elapsed().as_secs_f64())
    }

    /// Solves `S_1 X = rhs` in place for the three columns of [`StepMatrix::rhs`].
    pub fn solve(&mut self) {
        let nf = self.len();
        let llt = LltRef::<'_, u32, f64>::new(&self.symbolic, &self.factor);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.rhs, nf, 3),
            Par::Seq,
            MemStack::new(&mut self.buffer),
        );
    }
}

#[cfg(test)]
impl StepMatrix {
    /// The assembled `S_1` as a dense row-major `n_free x n_free` matrix.
    pub fn dense(&self) -> Vec<f64> {
        let nf = self.len();
        let mut a = vec![0.0; nf * nf];
        for c in 0..nf {
            for p in self.col_ptr[c] as usize..self.col_ptr[c + 1] as usize {
                let r = self.row_idx[p] as usize;
                a[r * nf + c] = self.values[p];
                a[c * nf + r] = self.values[p];
            }
        }
        a
    }
}
