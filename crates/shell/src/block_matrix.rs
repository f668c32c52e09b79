//! A symmetric sparse matrix of 3x3 vertex blocks on a shell's free vertices, factored by
//! faer's sparse Cholesky: the implicit step's preconditioner. The pattern is every pair of
//! vertices in one edge's four-vertex stencil (all the pairs the shell's energy couples); it
//! and the symbolic factorisation are built once per mesh and free set, and every buffer with
//! them, so assembling, factoring and solving allocate nothing.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::error::ShellError;
use crate::mesh::ShellMesh;

/// Marks a held (pinned or driven) vertex in the free numbering.
pub(crate) const HELD: u32 = u32::MAX;

/// The lower triangle of the matrix, column-major by scalar unknown `3 J + c`: per column the
/// diagonal block's rows from `c` down, then each neighbour `I > J`'s three rows.
pub(crate) struct BlockMatrix {
    /// Free index of each vertex, or [`HELD`].
    pub free: Vec<u32>,
    /// Vertex of each free index.
    pub vertices: Vec<u32>,
    /// CSR per free vertex `J`: the free neighbours `I > J`, sorted.
    nbr_start: Vec<u32>,
    nbr: Vec<u32>,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    symbolic: SymbolicCholesky<u32>,
    /// Numeric factors kept by key (the step they were made for, s), each with the matrix it
    /// was made from, and the one in use.
    factors: Vec<Kept>,
    active: Option<usize>,
    buffer: MemBuffer,
}

/// A factor kept under its key, with the assembled values it was made from (a checkpoint
/// keeps those, a fraction of the factor's size, and factors them again to the same bits).
struct Kept {
    key: f64,
    factor: Vec<f64>,
    values: Vec<f64>,
}

impl std::fmt::Debug for BlockMatrix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockMatrix")
            .field("free", &self.vertices.len())
            .field("entries", &self.values.len())
            .finish()
    }
}

impl BlockMatrix {
    /// The pattern on `mesh`'s vertices not `held`, and its symbolic factorisation.
    pub fn new(mesh: &ShellMesh, held: &[bool]) -> Result<BlockMatrix, ShellError> {
        let n = mesh.num_vertices();
        let mut free = vec![HELD; n];
        let mut vertices = Vec::new();
        for (i, &h) in held.iter().enumerate().take(n) {
            if !h {
                free[i] = vertices.len() as u32;
                vertices.push(i as u32);
            }
        }
        let nf = vertices.len();
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nf];
        for e in mesh.edges() {
            let ids = [e.v[0], e.v[1], e.opposite[0], e.opposite[1]];
            for &a in &ids {
                for &b in &ids {
                    let (Some(&fa), Some(&fb)) = (free.get(a as usize), free.get(b as usize))
                    else {
                        continue; // a boundary edge's missing opposite vertex
                    };
                    if fa != HELD && fb != HELD && fa > fb {
                        lists[fb as usize].push(fa);
                    }
                }
            }
        }
        let mut nbr_start = Vec::with_capacity(nf + 1);
        let mut nbr = Vec::new();
        nbr_start.push(0u32);
        for l in &mut lists {
            l.sort_unstable();
            l.dedup();
            nbr.extend_from_slice(l);
            nbr_start.push(to_u32(nbr.len())?);
        }
        let mut col_ptr = Vec::with_capacity(3 * nf + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0u32);
        for j in 0..nf {
            for c in 0..3 {
                for r in c..3 {
                    row_idx.push(to_u32(3 * j + r)?);
                }
                for &i in &nbr[nbr_start[j] as usize..nbr_start[j + 1] as usize] {
                    for r in 0..3 {
                        row_idx.push(to_u32(3 * i as usize + r)?);
                    }
                }
                col_ptr.push(to_u32(row_idx.len())?);
            }
        }
        let symbolic = {
            let pattern =
                SymbolicSparseColMatRef::new_checked(3 * nf, 3 * nf, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(
                pattern,
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(|e| ShellError::Factorization(format!("symbolic: {e:?}")))?
        };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let buffer = MemBuffer::try_new(req)
            .map_err(|_| ShellError::Factorization("out of memory for the factor".into()))?;
        Ok(BlockMatrix {
            values: vec![0.0; row_idx.len()],
            factors: Vec::new(),
            active: None,
            free,
            vertices,
            nbr_start,
            nbr,
            col_ptr,
            row_idx,
            symbolic,
            buffer,
        })
    }

    /// Free vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Whether the free set is that of `held`.
    pub fn matches(&self, held: &[bool]) -> bool {
        held.len() == self.free.len()
            && held.iter().zip(&self.free).all(|(&h, &f)| h == (f == HELD))
    }

    /// Zeroes every entry.
    pub fn clear(&mut self) {
        self.values.fill(0.0);
    }

    /// Adds `d` (N/m) to the three diagonal entries of vertex `i` (ignored when held).
    pub fn add_diagonal(&mut self, i: usize, d: f64) {
        let fi = self.free[i];
        if fi == HELD {
            return;
        }
        for c in 0..3 {
            let p = self.col_ptr[3 * fi as usize + c] as usize;
            self.values[p] += d;
        }
    }

    /// Adds block `b` (N/m) of vertex pair `(i, j)`: row `i`'s coordinates by column `j`'s.
    /// Only the lower triangle is stored, so the caller hands every ordered pair (the upper
    /// ones are skipped); a pair outside the pattern or with a held vertex is ignored.
    pub fn add_block(&mut self, i: u32, j: u32, b: [[f64; 3]; 3]) {
        let (fi, fj) = (self.free[i as usize], self.free[j as usize]);
        if fi == HELD || fj == HELD || fi < fj {
            return;
        }
        // A non-finite block (a hinge folded flat) would poison the factor: left out.
        if !b.iter().flatten().all(|x| x.is_finite()) {
            return;
        }
        let fj = fj as usize;
        if fi as usize == fj {
            for c in 0..3 {
                let p = self.col_ptr[3 * fj + c] as usize;
                for (r, row) in b.iter().enumerate().skip(c) {
                    self.values[p + r - c] += row[c];
                }
            }
            return;
        }
        let list = &self.nbr[self.nbr_start[fj] as usize..self.nbr_start[fj + 1] as usize];
        let Ok(pos) = list.binary_search(&fi) else {
            return;
        };
        for c in 0..3 {
            let p = self.col_ptr[3 * fj + c] as usize + (3 - c) + 3 * pos;
            for (r, row) in b.iter().enumerate() {
                self.values[p + r] += row[c];
            }
        }
    }

    /// Solves with the factor kept under `key` from now on, if there is one.
    pub fn use_factor(&mut self, key: f64) -> bool {
        self.active = self.factors.iter().position(|k| k.key == key);
        self.active.is_some()
    }

    /// Drops every factor kept (the positions they were made at are stale).
    pub fn forget(&mut self) {
        self.factors.clear();
        self.active = None;
    }

    /// Factors the assembled matrix, keeps the factor under `key` (replacing one kept under it)
    /// and solves with it from now on.
    pub fn factor(&mut self, key: f64) -> Result<(), ShellError> {
        let slot = match self.factors.iter().position(|k| k.key == key) {
            Some(i) => i,
            None => {
                self.factors.push(Kept {
                    key,
                    factor: vec![0.0; self.symbolic.len_val()],
                    values: vec![0.0; self.values.len()],
                });
                self.factors.len() - 1
            }
        };
        self.factors[slot].values.copy_from_slice(&self.values);
        self.active = None;
        let n = 3 * self.len();
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx),
            &self.values,
        );
        let made = self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.factors[slot].factor,
            a,
            Side::Lower,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.buffer),
            Default::default(),
        );
        if let Err(e) = made {
            // a half-made factor must not be found under its key later
            self.factors.remove(slot);
            return Err(ShellError::Factorization(format!(
                "not positive definite ({e:?})"
            )));
        }
        self.active = Some(slot);
        Ok(())
    }

    /// The factors kept: each one's key (the step it was made for, s) and the assembled
    /// values it was made from, in the order they were made.
    pub fn kept(&self) -> impl Iterator<Item = (f64, &[f64])> {
        self.factors.iter().map(|k| (k.key, k.values.as_slice()))
    }

    /// Factors each of `kept` (keys and assembled values written by [`BlockMatrix::kept`] for a
    /// matrix of the same pattern) and keeps it in place of any kept, so the factors have the
    /// bits they had; none is in use until [`BlockMatrix::use_factor`]. Refuses values whose
    /// length is not this pattern's, and a matrix that does not factor.
    pub fn refactor_kept(&mut self, kept: &[(f64, Vec<f64>)]) -> Result<(), ShellError> {
        self.forget();
        for (key, values) in kept {
            if values.len() != self.values.len() {
                return Err(ShellError::Factorization(format!(
                    "{} matrix entries for step {key} s, this pattern has {}",
                    values.len(),
                    self.values.len()
                )));
            }
            self.values.copy_from_slice(values);
            self.factor(*key)?;
        }
        self.active = None;
        Ok(())
    }

    /// Solves in place for `rhs` (`3 x` free vertices, vertex-major) with the factor in use;
    /// leaves `rhs` as it is when there is none.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        let Some(active) = self.active else {
            return;
        };
        let n = 3 * self.len();
        let llt = LltRef::<'_, u32, f64>::new(&self.symbolic, &self.factors[active].factor);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut rhs[..n], n, 1),
            Par::Seq,
            MemStack::new(&mut self.buffer),
        );
    }
}

fn to_u32(n: usize) -> Result<u32, ShellError> {
    u32::try_from(n).map_err(|_| ShellError::Factorization(format!("{n} entries: too many")))
}
