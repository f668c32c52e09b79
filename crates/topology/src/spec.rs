//! Primitive shape specs as `perifrac mesh` and scenes write them: `box:LXxLYxLZ`,
//! `bar:LxWxH`, `sphere:R`, `cylinder:RxH` (sizes in metres).

use crate::mesher::{cylinder_surface, sphere_surface};
use thiserror::Error;

/// A spec that does not parse; the message quotes it and says what was expected.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{0}")]
pub struct SpecError(pub String);

/// A parsed box spec such as `box:1x0.2x1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primitive {
    /// Extent along x, y, z in metres.
    pub size: [f64; 3],
}

/// A triangle surface as vertex positions (m) and faces (0-based vertex indices).
pub type SurfaceArrays = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Facets of the round primitives' surfaces: rings of the sphere, sides of the cylinder (twice
/// this many).
pub const ROUND_SEGMENTS: usize = 64;

/// Parses one size of `spec`: a positive, finite number.
fn size(spec: &str, p: &str) -> Result<f64, SpecError> {
    let x = p
        .trim()
        .parse::<f64>()
        .map_err(|_| SpecError(format!("`{spec}`: `{p}` is not a number")))?;
    if !x.is_finite() || x <= 0.0 {
        return Err(SpecError(format!(
            "`{spec}`: sizes must be positive and finite, found {p}"
        )));
    }
    Ok(x)
}

/// Parses `box:LXxLYxLZ` or `bar:LxWxH` (both axis-aligned boxes from the origin).
pub fn parse_primitive(spec: &str) -> Result<Primitive, SpecError> {
    let Some((kind, dims)) = spec.split_once(':') else {
        return Err(SpecError(format!(
            "`{spec}` is neither an existing surface file (.obj, .ply, .off) nor a primitive \
             spec; expected `box:LXxLYxLZ`, `bar:LxWxH`, `sphere:R` or `cylinder:RxH`"
        )));
    };
    if kind != "box" && kind != "bar" {
        return Err(SpecError(format!(
            "unknown primitive `{kind}` in `{spec}`; known: box, bar, sphere, cylinder"
        )));
    }
    let parts: Vec<&str> = dims.split('x').collect();
    if parts.len() != 3 {
        return Err(SpecError(format!(
            "`{spec}`: expected three sizes separated by `x`, e.g. {kind}:1x0.2x0.5"
        )));
    }
    let mut out = [0.0; 3];
    for (s, p) in out.iter_mut().zip(&parts) {
        *s = size(spec, p)?;
    }
    Ok(Primitive { size: out })
}

/// Parses `sphere:R` (about the origin) or `cylinder:RxH` (along z from the origin) into a
/// closed surface; `None` for any other spec.
pub fn parse_round(spec: &str) -> Result<Option<SurfaceArrays>, SpecError> {
    let Some((kind, dims)) = spec.split_once(':') else {
        return Ok(None);
    };
    if kind != "sphere" && kind != "cylinder" {
        return Ok(None);
    }
    let sizes = dims
        .split('x')
        .map(|p| size(spec, p))
        .collect::<Result<Vec<f64>, SpecError>>()?;
    match (kind, sizes.as_slice()) {
        ("sphere", &[r]) => Ok(Some(sphere_surface(r, ROUND_SEGMENTS))),
        ("cylinder", &[r, h]) => Ok(Some(cylinder_surface(r, h, 2 * ROUND_SEGMENTS))),
        _ => Err(SpecError(format!(
            "`{spec}`: expected sphere:RADIUS or cylinder:RADIUSxHEIGHT"
        ))),
    }
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
    fn parses_round_primitives() {
        assert!(parse_round("sphere:0.5").unwrap().is_some());
        assert!(parse_round("cylinder:0.5x2").unwrap().is_some());
        assert!(parse_round("box:1x1x1").unwrap().is_none());
        assert!(parse_round("sphere:1x2").is_err());
        assert!(parse_round("cylinder:-1x2").is_err());
        assert!(parse_round("cylinder:1").is_err());
    }
}
