//! Built-in primitive meshes, so scenes and tests need no mesh files.

use crate::error::TopologyError;
use crate::mesh::{TetMesh, NO_TET};

/// Corner offsets (bit 0 = x, bit 1 = y, bit 2 = z) of the six Kuhn tets of a cell: each tet walks
/// from the cell's min corner to its max corner along one permutation of the axes. Odd
/// permutations have their last two corners swapped so every tet is positively oriented.
const KUHN: [[usize; 4]; 6] = [
    [0b000, 0b001, 0b011, 0b111], // x, y, z (even)
    [0b000, 0b010, 0b110, 0b111], // y, z, x (even)
    [0b000, 0b100, 0b101, 0b111], // z, x, y (even)
    [0b000, 0b001, 0b111, 0b101], // x, z, y (odd, last two swapped)
    [0b000, 0b010, 0b111, 0b011], // y, x, z (odd, last two swapped)
    [0b000, 0b100, 0b111, 0b110], // z, y, x (odd, last two swapped)
];

/// Vertices and tets of an axis-aligned box from `min` to `max` (length), cut into
/// `cells[0] x cells[1] x cells[2]` cuboids (a zero count is taken as 1), each split into six
/// positive Kuhn tets. The subdivision is the same in every cell, so neighbouring cells agree on
/// their shared faces. Vertex `(i, j, k)` has index `i + (nx + 1) * (j + (ny + 1) * k)`.
///
/// The counts are not checked here: call [`box_counts`] (or [`check_box`]) first for counts
/// that come from a user.
pub fn box_data(min: [f64; 3], max: [f64; 3], cells: [usize; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    lattice_box_data(min, max, cells, Lattice::Kuhn)
}

/// How a lattice box's cells are cut into six tets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Lattice {
    /// Every cell the same six Kuhn tets along its main diagonal (the same direction everywhere:
    /// the lattice has no mirror symmetry, and a bar bent down also bends a little sideways).
    #[default]
    Kuhn,
    /// Each cell's Kuhn tets mirrored along every axis whose cell index is odd, so neighbouring
    /// cells are mirror images across their shared face (which the mirror maps to itself, so
    /// the cells still agree on its diagonal). A box with an even count of cells along an axis
    /// is then mirror-symmetric across its mid-plane normal to that axis.
    Mirrored,
}

/// [`box_data`] with the cells cut as `lattice` says. Vertices are numbered the same way.
pub fn lattice_box_data(
    min: [f64; 3],
    max: [f64; 3],
    cells: [usize; 3],
    lattice: Lattice,
) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    let [nx, ny, nz] = cells.map(|c| c.max(1));
    let index = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let mut vertices = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let lerp =
                    |a: usize, n: usize, d: usize| min[d] + (max[d] - min[d]) * a as f64 / n as f64;
                vertices.push([lerp(i, nx, 0), lerp(j, ny, 1), lerp(k, nz, 2)]);
            }
        }
    }
    let mut tets = Vec::with_capacity(nx * ny * nz * 6);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                // Corner bits flipped along the mirrored axes; an odd count of flips turns the
                // tets inside out, so their last two corners swap back.
                let flip = match lattice {
                    Lattice::Kuhn => 0,
                    Lattice::Mirrored => (i & 1) | (j & 1) << 1 | (k & 1) << 2,
                };
                let corner = |b: usize| {
                    let b = b ^ flip;
                    index(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1))
                };
                for kuhn in KUHN {
                    let mut tet = kuhn.map(corner);
                    if flip.count_ones() % 2 == 1 {
                        tet.swap(2, 3);
                    }
                    tets.push(tet);
                }
            }
        }
    }
    (vertices, tets)
}

/// Cell counts for a box of extent `size` (m) with `resolution` cells across its longest side
/// and the other sides in proportion (at least one cell each); `resolution` 0 counts as 1.
/// Counts saturate at `usize::MAX` for absurd ratios: check them with [`box_counts`].
pub fn cells_for_resolution(size: [f64; 3], resolution: usize) -> [usize; 3] {
    let longest = size.iter().cloned().fold(0.0, f64::max);
    let h = longest / resolution.max(1) as f64;
    size.map(|s| ((s / h).round() as usize).max(1))
}

/// The largest coordinate magnitude and cell side (m) of a primitive box.
///
/// Why this value: tet quality measures take lengths to the sixth power, and `1e50^6 = 1e300`
/// is still inside f64's range (about `1.8e308`).
pub const MAX_EXTENT: f64 = 1e50;

/// The smallest cell side (m) of a primitive box: `1e-50^6 = 1e-300` is still a normal f64
/// (the smallest is about `2.2e-308`), so no quality measure underflows.
pub const MIN_EXTENT: f64 = 1e-50;

/// How far above the topology's flatness tolerance ([`crate::VOLUME_TOLERANCE`]) the tets of a
/// primitive box must stay: a factor of a thousand, so rounding cannot push a tet of a valid
/// box below it.
pub const FLATNESS_MARGIN: f64 = 1e3;

/// The vertex and tet counts of a box of `cells` cuboids (a zero count is taken as 1), with
/// checked arithmetic: `(vertices, tets)`. An error when either count overflows or passes what a
/// mesh indexes (32-bit vertex and tet ids), so nothing is allocated for an impossible box.
pub fn box_counts(cells: [usize; 3]) -> Result<(usize, usize), TopologyError> {
    let [nx, ny, nz] = cells.map(|c| c.max(1));
    let too_many = || TopologyError::TooManyCells { cells };
    let cuboids = nx
        .checked_mul(ny)
        .and_then(|c| c.checked_mul(nz))
        .ok_or_else(too_many)?;
    let tets = cuboids.checked_mul(6).ok_or_else(too_many)?;
    let corners = |n: usize| n.checked_add(1);
    let vertices = corners(nx)
        .zip(corners(ny))
        .and_then(|(a, b)| a.checked_mul(b))
        .zip(corners(nz))
        .and_then(|(a, b)| a.checked_mul(b))
        .ok_or_else(too_many)?;
    if tets >= NO_TET as usize || vertices > u32::MAX as usize {
        return Err(too_many());
    }
    Ok((vertices, tets))
}

/// Mean length (m) of the distinct edges of a lattice of Kuhn cells with sides `cell` (m): per
/// cell three axis edges, three face diagonals and one body diagonal.
pub fn kuhn_mean_edge(cell: [f64; 3]) -> f64 {
    let [a, b, c] = cell;
    let d = |x: f64, y: f64| (x * x + y * y).sqrt();
    (a + b + c + d(a, b) + d(b, c) + d(c, a) + (a * a + b * b + c * c).sqrt()) / 7.0
}

/// Checks a primitive box before anything is allocated: a finite, non-empty extent within
/// [`MAX_EXTENT`] of the origin, counts a mesh can index ([`box_counts`]), cell sides between
/// [`MIN_EXTENT`] and [`MAX_EXTENT`], and cells not so flat that their tets' volume `abc/6`
/// comes within [`FLATNESS_MARGIN`] of the topology's tolerance `1e-12 lambda^3` (`lambda` the
/// mean edge, [`kuhn_mean_edge`]).
pub fn check_box(min: [f64; 3], max: [f64; 3], cells: [usize; 3]) -> Result<(), TopologyError> {
    let usable = |x: f64| x.is_finite() && x.abs() <= MAX_EXTENT;
    if (0..3).any(|d| !(usable(min[d]) && usable(max[d]) && max[d] > min[d])) {
        return Err(TopologyError::BadExtent { min, max });
    }
    box_counts(cells)?;
    let n = cells.map(|c| c.max(1) as f64);
    let cell: [f64; 3] = std::array::from_fn(|d| (max[d] - min[d]) / n[d]);
    if cell
        .iter()
        .any(|&s| !(MIN_EXTENT..=MAX_EXTENT).contains(&s))
    {
        return Err(TopologyError::CellOutOfRange { cell });
    }
    let volume = cell[0] * cell[1] * cell[2] / 6.0;
    let tolerance = FLATNESS_MARGIN * crate::VOLUME_TOLERANCE * kuhn_mean_edge(cell).powi(3);
    if volume.is_nan() || volume <= tolerance {
        return Err(TopologyError::FlatCells {
            cell,
            volume,
            tolerance,
        });
    }
    Ok(())
}

/// Like [`box_mesh`], but returns an error for a box [`check_box`] refuses.
pub fn try_box_mesh(
    min: [f64; 3],
    max: [f64; 3],
    cells: [usize; 3],
) -> Result<TetMesh, TopologyError> {
    check_box(min, max, cells)?;
    let (v, t) = box_data(min, max, cells);
    TetMesh::new(v, t).map(|(mesh, _)| mesh)
}

/// Box mesh from [`box_data`].
///
/// # Panics
/// If [`check_box`] refuses the box; use [`try_box_mesh`] for user input.
#[track_caller]
pub fn box_mesh(min: [f64; 3], max: [f64; 3], cells: [usize; 3]) -> TetMesh {
    match try_box_mesh(min, max, cells) {
        Ok(mesh) => mesh,
        Err(e) => panic!("box_mesh: {e}"),
    }
}

/// Vertices and tets of a bar along x from 0 to `length`, with cross-section `section` (y, z
/// extents, centred on the x axis), `cells_along` cells along x (at least 1) and, across, the
/// count that makes cells closest to cubic (at least 1).
pub fn bar_data(
    length: f64,
    section: [f64; 2],
    cells_along: usize,
) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    let (min, max, cells) = bar_layout(length, section, cells_along);
    box_data(min, max, cells)
}

/// Like [`bar_mesh`], but returns an error for a layout [`check_box`] refuses.
pub fn try_bar_mesh(
    length: f64,
    section: [f64; 2],
    cells_along: usize,
) -> Result<TetMesh, TopologyError> {
    let (min, max, cells) = bar_layout(length, section, cells_along);
    try_box_mesh(min, max, cells)
}

/// Bar mesh from [`bar_data`].
///
/// # Panics
/// If the length or a section extent is not positive and finite; use [`try_bar_mesh`] for user
/// input.
#[track_caller]
pub fn bar_mesh(length: f64, section: [f64; 2], cells_along: usize) -> TetMesh {
    match try_bar_mesh(length, section, cells_along) {
        Ok(mesh) => mesh,
        Err(e) => panic!("bar_mesh: {e}"),
    }
}

fn bar_layout(
    length: f64,
    section: [f64; 2],
    cells_along: usize,
) -> ([f64; 3], [f64; 3], [usize; 3]) {
    let nx = cells_along.max(1);
    let h = length / nx as f64;
    let across = |s: f64| {
        let n = (s / h).round();
        if n.is_finite() && n >= 1.0 {
            n as usize
        } else {
            1
        }
    };
    let min = [0.0, -0.5 * section[0], -0.5 * section[1]];
    let max = [length, 0.5 * section[0], 0.5 * section[1]];
    (min, max, [nx, across(section[0]), across(section[1])])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mirrored_lattice_is_conforming_and_symmetric() {
        let cells = [4, 2, 3];
        let (v, t) = lattice_box_data([-2.0, -1.0, 0.0], [2.0, 1.0, 3.0], cells, Lattice::Mirrored);
        let (mesh, report) = TetMesh::new(v.clone(), t.clone()).unwrap();
        // Every tet built positive, and the only boundary faces are the box's own: two
        // triangles per boundary cell face (a mismatched diagonal inside would add four).
        assert_eq!(report.inverted_fixed, 0);
        let [nx, ny, nz] = cells;
        assert_eq!(
            mesh.boundary_face_count(),
            4 * (nx * ny + ny * nz + nz * nx)
        );
        let volume: f64 = mesh.rest_volumes().iter().sum();
        assert!((volume - 4.0 * 2.0 * 3.0).abs() < 1e-12, "{volume}");
        // Even counts along x and y: the tets, as sets of corners, map onto themselves under
        // the mirror x -> -x and under y -> -y (z has an odd count and no such symmetry).
        let key = |p: [f64; 3]| p.map(|c| (c * 1e6).round() as i64);
        let as_set = |tets: &[[u32; 4]], mirror: [f64; 3]| {
            let mut s: Vec<[[i64; 3]; 4]> = tets
                .iter()
                .map(|tet| {
                    let mut c = tet.map(|i| {
                        let p = v[i as usize];
                        key([p[0] * mirror[0], p[1] * mirror[1], p[2] * mirror[2]])
                    });
                    c.sort();
                    c
                })
                .collect();
            s.sort();
            s
        };
        let same = as_set(&t, [1.0; 3]);
        assert_eq!(as_set(&t, [-1.0, 1.0, 1.0]), same);
        assert_eq!(as_set(&t, [1.0, -1.0, 1.0]), same);
        // The Kuhn lattice has neither symmetry.
        let (_, kuhn) = box_data([-2.0, -1.0, 0.0], [2.0, 1.0, 3.0], cells);
        assert_ne!(as_set(&kuhn, [1.0, -1.0, 1.0]), as_set(&kuhn, [1.0; 3]));
    }

    #[test]
    fn counts_are_checked_not_wrapped() {
        // 2 x 3 x 4 cells: 3 x 4 x 5 corners, 6 tets per cell.
        assert_eq!(box_counts([2, 3, 4]).unwrap(), (60, 144));
        // The reproducers of issue 17: a product that wraps to 0, and one that overflows.
        for cells in [
            [4_294_967_296, 4_294_967_296, 1],
            [9_223_372_036_854_775_808, 2, 1],
            [usize::MAX, 1, 1],
            // 6e9 tets fit a usize but not 32-bit ids.
            [1_000, 1_000, 1_000],
        ] {
            let e = box_counts(cells).unwrap_err();
            assert_eq!(e, TopologyError::TooManyCells { cells });
            assert!(e.to_string().contains("more than a mesh can index"), "{e}");
        }
    }

    #[test]
    fn flat_huge_and_tiny_boxes_are_refused_before_building() {
        let cells = |size| cells_for_resolution(size, 20);
        // box:1e8x1x1 and box:1e-30x1x1 at the default resolution: cells far too flat.
        for size in [[1e8, 1.0, 1.0], [1e-30, 1.0, 1.0]] {
            let e = check_box([0.0; 3], size, cells(size)).unwrap_err();
            assert!(matches!(e, TopologyError::FlatCells { .. }), "{e:?}");
            assert!(e.to_string().contains("too flat"), "{e}");
            assert!(try_box_mesh([0.0; 3], size, cells(size)).is_err());
        }
        // box:1e308x1x1: beyond the range where tet quality is computable.
        let size = [1e308, 1.0, 1.0];
        let e = check_box([0.0; 3], size, cells(size)).unwrap_err();
        assert!(matches!(e, TopologyError::BadExtent { .. }), "{e:?}");
        // A tiny but well-shaped box is beyond the smallest side.
        let e = check_box([0.0; 3], [1e-49; 3], [20; 3]).unwrap_err();
        assert!(matches!(e, TopologyError::CellOutOfRange { .. }), "{e:?}");
        assert!(check_box([0.0; 3], [f64::NAN, 1.0, 1.0], [1; 3]).is_err());
        // Thin but sane cells (1000 : 1) build.
        let mesh = try_box_mesh([0.0; 3], [1.0, 1.0, 1e-3], [1, 1, 1]).unwrap();
        assert_eq!(mesh.num_tets(), 6);
        assert!(check_box([0.0; 3], [1e40; 3], [2; 3]).is_ok());
    }
}
