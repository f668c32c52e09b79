//! `perifrac mesh`: tet meshes from built-in primitives.

use std::path::Path;

use anyhow::{bail, Context, Result};
use perifrac_io::TetFormat;
use perifrac_topology::primitives;

use crate::load::to_data;

/// A parsed primitive spec such as `box:1x0.2x1`.
#[derive(Debug, PartialEq)]
pub struct Primitive {
    /// Extent along x, y, z in metres.
    pub size: [f64; 3],
}

/// Parses `box:LXxLYxLZ` or `bar:LxWxH` (both are axis-aligned boxes from the origin).
pub fn parse_primitive(spec: &str) -> Result<Primitive> {
    let Some((kind, dims)) = spec.split_once(':') else {
        bail!(
            "`{spec}` is not a primitive spec; expected `box:LXxLYxLZ` or `bar:LxWxH` \
             (meshing surface files is not built yet: run `tetgen -pq1.414 FILE.off` and \
             `perifrac convert FILE.1.ele OUT.mesh`)"
        );
    };
    if kind != "box" && kind != "bar" {
        bail!("unknown primitive `{kind}` in `{spec}`; known: box, bar");
    }
    let parts: Vec<&str> = dims.split('x').collect();
    if parts.len() != 3 {
        bail!("`{spec}`: expected three sizes separated by `x`, e.g. {kind}:1x0.2x0.5");
    }
    let mut size = [0.0; 3];
    for (s, p) in size.iter_mut().zip(&parts) {
        *s = p
            .trim()
            .parse::<f64>()
            .with_context(|| format!("`{spec}`: `{p}` is not a number"))?;
        if !s.is_finite() || *s <= 0.0 {
            bail!("`{spec}`: sizes must be positive and finite, found {p}");
        }
    }
    Ok(Primitive { size })
}

/// Cell counts: explicit, or `resolution` cells across the longest side, others in proportion.
pub fn cell_counts(
    size: [f64; 3],
    resolution: usize,
    cells: Option<&[usize]>,
) -> Result<[usize; 3]> {
    if let Some(c) = cells {
        if c.len() != 3 || c.contains(&0) {
            bail!("--cells needs three positive counts, e.g. 40,8,40");
        }
        return Ok([c[0], c[1], c[2]]);
    }
    if resolution == 0 {
        bail!("--resolution must be at least 1");
    }
    let longest = size.iter().cloned().fold(0.0, f64::max);
    let h = longest / resolution as f64;
    Ok(size.map(|s| ((s / h).round() as usize).max(1)))
}

/// Builds the primitive and writes it to `output`.
pub fn run(spec: &str, output: &Path, resolution: usize, cells: Option<&[usize]>) -> Result<()> {
    let prim = parse_primitive(spec)?;
    let counts = cell_counts(prim.size, resolution, cells)?;
    let tets = 6u64 * counts.iter().map(|&c| c as u64).product::<u64>();
    if tets > u32::MAX as u64 / 2 {
        bail!("{counts:?} cells would make {tets} tets, more than perifrac indexes");
    }
    let format = TetFormat::from_path(output)?;
    let mesh = primitives::box_mesh([0.0; 3], prim.size, counts);
    let data = to_data(&mesh, vec![0; mesh.num_tets()], Vec::new());
    perifrac_io::write_tet_mesh(output, &data, format)?;
    eprintln!(
        "wrote {} ({} vertices, {} tets, {}x{}x{} cells)",
        output.display(),
        mesh.num_vertices(),
        mesh.num_tets(),
        counts[0],
        counts[1],
        counts[2]
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_box_and_rejects_nonsense() {
        assert_eq!(
            parse_primitive("box:1x0.2x3").unwrap().size,
            [1.0, 0.2, 3.0]
        );
        assert!(parse_primitive("box:1x0.2").is_err());
        assert!(parse_primitive("box:1x-2x3").is_err());
        assert!(parse_primitive("box:1xNaNx3").is_err());
        assert!(parse_primitive("ball:1x1x1").is_err());
        assert!(parse_primitive("bunny.off").is_err());
    }

    #[test]
    fn resolution_spreads_cells_in_proportion() {
        // 1 x 0.2 x 0.5 at 20 across the longest side: cell size 0.05 -> 20, 4, 10.
        assert_eq!(cell_counts([1.0, 0.2, 0.5], 20, None).unwrap(), [20, 4, 10]);
        // A side much thinner than a cell still gets one cell.
        assert_eq!(
            cell_counts([1.0, 0.001, 1.0], 10, None).unwrap(),
            [10, 1, 10]
        );
        assert!(cell_counts([1.0; 3], 0, None).is_err());
        assert!(cell_counts([1.0; 3], 5, Some(&[1, 0, 1])).is_err());
    }
}
