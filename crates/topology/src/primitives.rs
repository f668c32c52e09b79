//! Built-in primitive meshes, so scenes and tests need no mesh files.

use crate::error::TopologyError;
use crate::mesh::TetMesh;

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
pub fn box_data(min: [f64; 3], max: [f64; 3], cells: [usize; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
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
                let corner = |b: usize| index(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                for kuhn in KUHN {
                    tets.push(kuhn.map(corner));
                }
            }
        }
    }
    (vertices, tets)
}

/// Cell counts for a box of extent `size` (m) with `resolution` cells across its longest side
/// and the other sides in proportion (at least one cell each); `resolution` 0 counts as 1.
pub fn cells_for_resolution(size: [f64; 3], resolution: usize) -> [usize; 3] {
    let longest = size.iter().cloned().fold(0.0, f64::max);
    let h = longest / resolution.max(1) as f64;
    size.map(|s| ((s / h).round() as usize).max(1))
}

/// Like [`box_mesh`], but returns an error for an empty or non-finite extent.
pub fn try_box_mesh(
    min: [f64; 3],
    max: [f64; 3],
    cells: [usize; 3],
) -> Result<TetMesh, TopologyError> {
    if (0..3).any(|d| !(min[d].is_finite() && max[d].is_finite() && max[d] > min[d])) {
        return Err(TopologyError::BadExtent { min, max });
    }
    let (v, t) = box_data(min, max, cells);
    TetMesh::new(v, t).map(|(mesh, _)| mesh)
}

/// Box mesh from [`box_data`].
///
/// # Panics
/// If the extent is empty or not finite on some axis; use [`try_box_mesh`] for user input.
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

/// Like [`bar_mesh`], but returns an error for an empty or non-finite extent.
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
