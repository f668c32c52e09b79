//! Moving the vertices with the particles (MODEL.md section 3).

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

    /// Fills `accum[v]` with `(sum w_p q_p, sum w_p)` over the tets `p` using `v`, `w_p = m_p/4`.
    #[track_caller]
    fn accumulate(&mut self, mass: &[f64], quantity: &[[f64; 3]]) {
        assert_eq!(mass.len(), self.tets.len(), "one particle mass per tet");
        assert_eq!(
            quantity.len(),
            self.tets.len(),
            "one particle vector per tet"
        );
        self.accum.clear();
        self.accum.resize(self.pos.len(), [0.0; 4]);
        for ((tet, &m), q) in self.tets.iter().zip(mass).zip(quantity) {
            let w = 0.25 * m;
            let add = [w * q[0], w * q[1], w * q[2], w];
            for &v in tet {
                let a = &mut self.accum[v as usize];
                for i in 0..4 {
                    a[i] += add[i];
                }
            }
        }
    }
}
