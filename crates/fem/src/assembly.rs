//! Sparse assembly on the free degrees of freedom, shared by the static solvers: the free-DOF
//! numbering, the lower-triangle CSC pattern of a stiffness-like matrix, the serial scatter of
//! element matrices in element order, and the mapping of faer's Cholesky errors.

use faer::sparse::linalg::LltError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use rayon::prelude::*;

use crate::error::FemError;
use crate::mesh::Mesh;
use crate::problem::{Constraint, Problem};

/// Elements whose local matrices are held at once during assembly.
pub(crate) const CHUNK: usize = 2048;
/// Marks a constrained DOF in [`FreeDofs::index`].
pub(crate) const CONSTRAINED: u32 = u32::MAX;

/// Numbering of the free DOFs, increasing with the global DOF `3 * node + component`.
#[derive(Debug, Clone)]
pub(crate) struct FreeDofs {
    /// Free index of each global DOF, or [`CONSTRAINED`].
    pub index: Vec<u32>,
    /// Number of free DOFs.
    pub count: usize,
}

impl FreeDofs {
    /// Every component of a node with [`Constraint::Free`] is free; the others are held.
    /// Fails when nothing is free.
    pub fn new(problem: &Problem) -> Result<Self, FemError> {
        let constraints = problem.constraints();
        let mut index = vec![CONSTRAINED; 3 * constraints.len()];
        let mut count = 0u32;
        for (node, c) in constraints.iter().enumerate() {
            if *c == Constraint::Free {
                for d in 0..3 {
                    index[3 * node + d] = count;
                    count += 1;
                }
            }
        }
        if count == 0 {
            return Err(FemError::Solver(
                "every degree of freedom is constrained".into(),
            ));
        }
        Ok(Self {
            index,
            count: count as usize,
        })
    }
}

/// Lower-triangle CSC pattern (column pointers, sorted row indices) of a matrix coupling the
/// free DOFs of nodes that share an element. The diagonal entry of every column is the first
/// one stored in it.
#[derive(Debug, Clone)]
pub(crate) struct LowerPattern {
    pub symbolic: SymbolicSparseColMat<u32>,
}

impl LowerPattern {
    pub fn new(mesh: &Mesh, free: &FreeDofs) -> Self {
        let (col_ptr, row_idx) = lower_pattern(mesh, &free.index, free.count);
        Self {
            symbolic: SymbolicSparseColMat::new_checked(
                free.count, free.count, col_ptr, None, row_idx,
            ),
        }
    }

    /// Number of stored entries.
    pub fn len(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// The matrix with these values.
    pub fn matrix<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, u32, f64> {
        SparseColMatRef::new(self.symbolic.as_ref(), values)
    }

    /// Position in the values of the diagonal entry of free DOF `c`.
    pub fn diagonal(&self, c: usize) -> usize {
        self.symbolic.col_ptr()[c] as usize
    }

    /// Adds the element matrix `k` (`3N x 3N`, row-major, DOF `3a + i`) of the element with
    /// nodes `conn` into `values`, lower triangle of free rows and columns only. For each free
    /// row `r` and constrained column (node `nb`, component `j`) calls `constrained(r, nb, j,
    /// k_value)`, in a fixed order.
    pub fn add_element(
        &self,
        values: &mut [f64],
        k: &[f64],
        conn: &[u32],
        free: &[u32],
        mut constrained: impl FnMut(usize, usize, usize, f64),
    ) {
        let n = conn.len();
        let n3 = 3 * n;
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for a in 0..n {
            for i_d in 0..3 {
                let r = free[3 * conn[a] as usize + i_d];
                if r == CONSTRAINED {
                    continue;
                }
                for b in 0..n {
                    let nb = conn[b] as usize;
                    for j_d in 0..3 {
                        let kv = k[(3 * a + i_d) * n3 + 3 * b + j_d];
                        let c = free[3 * nb + j_d];
                        if c == CONSTRAINED {
                            constrained(r as usize, nb, j_d, kv);
                        } else if r >= c {
                            let (lo, hi) = (
                                col_ptr[c as usize] as usize,
                                col_ptr[c as usize + 1] as usize,
                            );
                            let pos = row_idx[lo..hi]
                                .binary_search(&r)
                                .expect("pattern holds every element pair");
                            values[lo + pos] += kv;
                        }
                    }
                }
            }
        }
    }
}

/// The crate's error for a failed sparse Cholesky factorisation of `free` DOFs.
pub(crate) fn cholesky_error(e: LltError, free: usize) -> FemError {
    match e {
        LltError::Numeric(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot {
            index,
        }) => FemError::NotPositiveDefinite { pivot: index, free },
        other => FemError::Solver(format!("{other:?}")),
    }
}

fn lower_pattern(mesh: &Mesh, free: &[u32], n_free: usize) -> (Vec<u32>, Vec<u32>) {
    let n_nodes = mesh.node_count();
    let npe = mesh.nodes_per_element();
    let conn = mesh.elements();
    let mut offsets = vec![0usize; n_nodes + 1];
    for &n in conn {
        offsets[n as usize + 1] += 1;
    }
    for i in 0..n_nodes {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut node_elems = vec![0u32; conn.len()];
    for (slot, &n) in conn.iter().enumerate() {
        node_elems[fill[n as usize]] = (slot / npe) as u32;
        fill[n as usize] += 1;
    }
    let neighbours: Vec<Vec<u32>> = (0..n_nodes)
        .into_par_iter()
        .map(|n| {
            let mut nb: Vec<u32> = node_elems[offsets[n]..offsets[n + 1]]
                .iter()
                .flat_map(|&e| mesh.element(e as usize).iter().copied())
                .filter(|&m| m as usize >= n)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            nb
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(n_free + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0u32);
    for (n, nb) in neighbours.iter().enumerate() {
        for d in 0..3 {
            let c = free[3 * n + d];
            if c == CONSTRAINED {
                continue;
            }
            for &m in nb {
                for e in 0..3 {
                    let r = free[3 * m as usize + e];
                    if r != CONSTRAINED && r >= c {
                        row_idx.push(r);
                    }
                }
            }
            col_ptr.push(u32::try_from(row_idx.len()).expect("fewer than 2^32 nonzeros"));
        }
    }
    (col_ptr, row_idx)
}
