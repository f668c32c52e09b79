//! Geomview OFF reader (ASCII).
//!
//! Header `OFF` (or a variant such as `COFF`; it may be omitted), then `nv nf ne`, vertices
//! `x y z`, faces `k i1 .. ik` (0-based), each optionally followed by colour values. `#`
//! comments. Polygons are fan-triangulated.

use crate::tokens::Tokens;
use crate::{IoError, SurfaceData};
use std::path::Path;

/// Parses the bytes of an `.off` file.
pub(crate) fn parse(path: &Path, data: &[u8]) -> Result<SurfaceData, IoError> {
    let mut t = Tokens::new(path, data);
    let mut vertex_extras = false;
    if let Some(head) = t.peek() {
        if head.first().is_some_and(|b| b.is_ascii_alphabetic()) {
            if !head.to_ascii_uppercase().ends_with(b"OFF") {
                return Err(t.unexpected("\"OFF\"", head));
            }
            // Plain OFF vertices are exactly x y z; variants (COFF, NOFF, ...) add values.
            vertex_extras = head.len() > 3;
            t.next();
        }
    }
    let nv = t.usize("the number of vertices")?;
    let nf = t.usize("the number of faces")?;
    t.usize("the number of edges")?;
    let mut s = SurfaceData {
        vertices: Vec::with_capacity(t.capacity_hint(nv, 6)),
        faces: Vec::with_capacity(t.capacity_hint(nf, 8)),
    };
    for i in 0..nv {
        let mut p = [0.0; 3];
        for c in &mut p {
            *c = t
                .f64("coordinate")
                .map_err(|e| e.context(|| format!("vertex {} of {nv}", i + 1)))?;
        }
        if vertex_extras {
            t.skip_line();
        }
        s.vertices.push(p);
    }
    for i in 0..nf {
        let ctx = || format!("face {} of {nf}", i + 1);
        let k = t
            .usize("the number of vertices of a face")
            .map_err(|e| e.context(ctx))?;
        if k < 3 {
            return Err(t.error(format!(
                "face {} has {k} vertices, expected at least 3",
                i + 1
            )));
        }
        let mut first = 0u32;
        let mut prev = 0u32;
        for j in 0..k {
            let v = t.u64("a vertex index").map_err(|e| e.context(ctx))?;
            if v >= nv as u64 {
                return Err(t.error(format!(
                    "vertex index {v} out of range (the file has {nv} vertices)"
                )));
            }
            let v = v as u32;
            match j {
                0 => first = v,
                1 => {}
                _ => s.faces.push([first, prev, v]),
            }
            prev = v;
        }
        t.skip_line();
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_is_fanned_and_colours_skipped() {
        let src = b"OFF\n# c\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 255 0 0\n";
        let s = parse(Path::new("a.off"), src).unwrap();
        assert_eq!(s.faces, vec![[0, 1, 2], [0, 2, 3]]);
        let e = parse(Path::new("a.off"), b"OFF\n1 1 0\n0 0 0\n3 0 0 5\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("a.off:4: vertex index 5 out of range"),
            "{e}"
        );
    }
}
