//! Body-centred cubic (BCC) lattice: cube corners plus cube centres, cut into tets that each
//! join two neighbouring cube centres with one edge of the square face they share. Every BCC
//! tet is congruent, with dihedral angles of 60 and 90 degrees, and the lattice fills space.

/// A BCC lattice over a box: `cells` cubes of side `h` from `origin`.
#[derive(Debug, Clone)]
pub struct BccLattice {
    /// Lower corner of the lattice.
    pub origin: [f64; 3],
    /// Cube side; also the length of the axis-aligned edges.
    pub h: f64,
    /// Cubes along x, y, z.
    pub cells: [usize; 3],
}

impl BccLattice {
    /// A lattice of cube side `h` covering `lo..hi` with one spare cube on every side. The
    /// counts saturate at `usize::MAX` for a spacing far below the extent, so that
    /// [`BccLattice::num_points`] reports an impossible lattice instead of wrapping.
    pub fn covering(lo: [f64; 3], hi: [f64; 3], h: f64) -> Self {
        // `as` saturates (and takes NaN to 0); the `+ 2` saturates too.
        let cells =
            [0, 1, 2].map(|k| (((hi[k] - lo[k]) / h).ceil().max(1.0) as usize).saturating_add(2));
        let origin = [0, 1, 2].map(|k| {
            let span = cells[k] as f64 * h;
            0.5 * (lo[k] + hi[k]) - 0.5 * span
        });
        Self { origin, h, cells }
    }

    /// Number of lattice points (corners then centres), saturating at `usize::MAX`.
    pub fn num_points(&self) -> usize {
        let centres = self.cells.iter().fold(1usize, |a, &c| a.saturating_mul(c));
        self.num_corners().saturating_add(centres)
    }

    fn num_corners(&self) -> usize {
        self.cells
            .iter()
            .fold(1usize, |a, &c| a.saturating_mul(c.saturating_add(1)))
    }

    /// Index of corner `(i, j, k)`.
    pub fn corner(&self, i: usize, j: usize, k: usize) -> u32 {
        let [_, ny, nz] = self.cells;
        ((i * (ny + 1) + j) * (nz + 1) + k) as u32
    }

    /// Index of the centre of cube `(i, j, k)`.
    pub fn centre(&self, i: usize, j: usize, k: usize) -> u32 {
        let [_, ny, nz] = self.cells;
        (self.num_corners() + (i * ny + j) * nz + k) as u32
    }

    /// Position of lattice point `index`.
    pub fn point(&self, index: u32) -> [f64; 3] {
        let [_, ny, nz] = self.cells;
        let index = index as usize;
        let (ijk, offset) = if index < self.num_corners() {
            let (i, r) = (index / ((ny + 1) * (nz + 1)), index % ((ny + 1) * (nz + 1)));
            ([i, r / (nz + 1), r % (nz + 1)], 0.0)
        } else {
            let c = index - self.num_corners();
            let (i, r) = (c / (ny * nz), c % (ny * nz));
            ([i, r / nz, r % nz], 0.5)
        };
        [0, 1, 2].map(|k| self.origin[k] + (ijk[k] as f64 + offset) * self.h)
    }

    /// Calls `f` with every lattice tet (corner order not yet oriented).
    pub fn for_each_tet(&self, mut f: impl FnMut([u32; 4])) {
        let [nx, ny, nz] = self.cells;
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let c = self.centre(i, j, k);
                    // Neighbour along +x: shared face at corner index i + 1.
                    if i + 1 < nx {
                        let d = self.centre(i + 1, j, k);
                        let q = [
                            self.corner(i + 1, j, k),
                            self.corner(i + 1, j + 1, k),
                            self.corner(i + 1, j + 1, k + 1),
                            self.corner(i + 1, j, k + 1),
                        ];
                        square_tets(c, d, q, &mut f);
                    }
                    if j + 1 < ny {
                        let d = self.centre(i, j + 1, k);
                        let q = [
                            self.corner(i, j + 1, k),
                            self.corner(i + 1, j + 1, k),
                            self.corner(i + 1, j + 1, k + 1),
                            self.corner(i, j + 1, k + 1),
                        ];
                        square_tets(c, d, q, &mut f);
                    }
                    if k + 1 < nz {
                        let d = self.centre(i, j, k + 1);
                        let q = [
                            self.corner(i, j, k + 1),
                            self.corner(i + 1, j, k + 1),
                            self.corner(i + 1, j + 1, k + 1),
                            self.corner(i, j + 1, k + 1),
                        ];
                        square_tets(c, d, q, &mut f);
                    }
                }
            }
        }
    }
}

/// The four tets joining centres `c`, `d` with each edge of the square `q` between them.
fn square_tets(c: u32, d: u32, q: [u32; 4], f: &mut impl FnMut([u32; 4])) {
    for e in 0..4 {
        f([c, d, q[e], q[(e + 1) % 4]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::faces::signed_volume;
    use crate::quality::dihedral_angles_deg;

    #[test]
    fn tets_fill_the_interior_with_bcc_angles() {
        let lat = BccLattice {
            origin: [0.0; 3],
            h: 0.5,
            cells: [3, 3, 3],
        };
        let mut volume = 0.0;
        let mut count = 0;
        lat.for_each_tet(|t| {
            let p = t.map(|v| lat.point(v));
            volume += signed_volume(p[0], p[1], p[2], p[3]).abs();
            count += 1;
            for a in dihedral_angles_deg(p) {
                // BCC tets have dihedral angles of exactly 60 or 90 degrees.
                assert!((a - 60.0).abs() < 1e-9 || (a - 90.0).abs() < 1e-9, "{a}");
            }
        });
        // 3 axes x 2 x 3 x 3 neighbour pairs x 4 tets, each h^3 / 12.
        assert_eq!(count, 3 * 18 * 4);
        assert!((volume - count as f64 * 0.125 / 12.0).abs() < 1e-12);
    }

    #[test]
    fn an_absurdly_fine_spacing_saturates_instead_of_wrapping() {
        let lat = BccLattice::covering([0.0; 3], [1.0; 3], 1e-300);
        assert_eq!(lat.num_points(), usize::MAX);
        let lat = BccLattice::covering([0.0; 3], [1.0; 3], 0.5);
        // 2 cubes plus a spare on each side: 4^3 centres and 5^3 corners.
        assert_eq!(lat.num_points(), 64 + 125);
    }
}
