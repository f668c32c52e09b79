//! Moving the vertices with the particles (docs/model.md section 3).

use crate::mesh::TetMesh;

impl TetMesh {
    /// Advances every vertex by `dt * v_v`, where `v_v` is the mass-weighted mean velocity of the
    /// tets using the vertex (weights `m_p / 4`). `dt` in time, masses in mass, velocities in
    /// length/time, one entry per tet. Vertices used by no tet (or only by massless tets) stay.
    ///
    /// Panics if the slices do not have one entry per tet.
    #[track_caller]
    pub fn advect(&mut self, dt: f64, particle_mass: &[f64], particle_velocity: &[[f64; 3]]) {
        self.accumulate(particle_mass, particle_velocity);
        for (x, a) in self.pos.iter_mut().zip(&self.accum) {
            if a[3] > 0.0 {
                let s = dt / a[3];
                for i in 0..3 {
                    x[i] += s * a[i];
                }
            }
        }
    }

    /// Drift-free alternative to [`TetMesh::advect`]: sets every vertex to its rest position plus
    /// the mass-weighted mean displacement (length) of the tets using it. Vertices used by no tet
    /// (or only by massless tets) go to their rest position.
    ///
    /// Panics if the slices do not have one entry per tet.
    #[track_caller]
    pub fn place_from_particles(
        &mut self,
        particle_mass: &[f64],
        particle_displacement: &[[f64; 3]],
    ) {
        self.accumulate(particle_mass, particle_displacement);
        for ((x, a), &r) in self.pos.iter_mut().zip(&self.accum).zip(&self.origin) {
            let rest = self.rest[r as usize];
            let s = if a[3] > 0.0 { 1.0 / a[3] } else { 0.0 };
            for i in 0..3 {
                x[i] = rest[i] + s * a[i];
            }
        }
    }

    /// The velocity every vertex moves with in [`TetMesh::advect`] (length/time): the
    /// mass-weighted mean of the velocities of the tets using it, zero for a vertex used by no
    /// tet with mass. Frames write it so that renderers can blur motion.
    ///
    /// Panics if the slices do not have one entry per tet.
    #[track_caller]
    pub fn vertex_velocities(
        &self,
        particle_mass: &[f64],
        particle_velocity: &[[f64; 3]],
    ) -> Vec<[f64; 3]> {
        let mut accum = Vec::new();
        accumulate(
            &self.tets,
            self.pos.len(),
            particle_mass,
            particle_velocity,
            &mut accum,
        );
        accum
            .iter()
            .map(|a| {
                if a[3] > 0.0 {
                    let s = 1.0 / a[3];
                    [s * a[0], s * a[1], s * a[2]]
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    }

    /// Fills `accum[v]` with `(sum w_p q_p, sum w_p)` over the tets `p` using `v`, `w_p = m_p/4`.
    #[track_caller]
    fn accumulate(&mut self, mass: &[f64], quantity: &[[f64; 3]]) {
        let mut accum = std::mem::take(&mut self.accum);
        accumulate(&self.tets, self.pos.len(), mass, quantity, &mut accum);
        self.accum = accum;
    }
}

/// Fills `accum[v]` (one per vertex of `vertices`) with `(sum w_p q_p, sum w_p)` over the tets
/// `p` using `v`, `w_p = m_p / 4`.
#[track_caller]
fn accumulate(
    tets: &[[u32; 4]],
    vertices: usize,
    mass: &[f64],
    quantity: &[[f64; 3]],
    accum: &mut Vec<[f64; 4]>,
) {
    assert_eq!(mass.len(), tets.len(), "one particle mass per tet");
    assert_eq!(quantity.len(), tets.len(), "one particle vector per tet");
    accum.clear();
    accum.resize(vertices, [0.0; 4]);
    for ((tet, &m), q) in tets.iter().zip(mass).zip(quantity) {
        let w = 0.25 * m;
        let add = [w * q[0], w * q[1], w * q[2], w];
        for &v in tet {
            let a = &mut accum[v as usize];
            for i in 0..4 {
                a[i] += add[i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::primitives;

    #[test]
    fn vertex_velocities_are_what_advection_moves_by() {
        let mut mesh = primitives::box_mesh([0.0; 3], [1.0, 1.0, 1.0], [2, 2, 2]);
        let n = mesh.num_tets();
        let mass: Vec<f64> = (0..n).map(|t| 1.0 + t as f64).collect();
        let vel: Vec<[f64; 3]> = (0..n).map(|t| [t as f64, -2.0 * t as f64, 0.5]).collect();
        let before = mesh.positions().to_vec();
        let v = mesh.vertex_velocities(&mass, &vel);
        // The two compute dt / w and 1 / w in different orders: they agree to a few roundings.
        mesh.advect(0.25, &mass, &vel);
        for ((x0, x1), vv) in before.iter().zip(mesh.positions()).zip(&v) {
            for k in 0..3 {
                assert!((x0[k] + 0.25 * vv[k] - x1[k]).abs() <= 1e-15 * (1.0 + x1[k].abs()));
            }
        }
    }
}
