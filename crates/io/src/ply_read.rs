//! PLY reader (ASCII and binary, through ply-rs-bw).
//!
//! Reads `vertex` `x y z` (any numeric type), `face` `vertex_indices` or `vertex_index` (a list
//! of any integer type; polygons fan-triangulated) and an optional per-face `crack` scalar.

use crate::error::read_all;
use crate::{IoError, SurfaceData};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Encoding, Header, Property};
use std::path::Path;

/// Reads a PLY surface and, when the faces carry a `crack` property, the per-triangle flags
/// (a polygon's flag is repeated for each of its triangles).
///
/// NaN and infinite coordinates are refused: by line in an ASCII file (one element per line,
/// as the format has it), by vertex number (from 1) in a binary one.
pub fn read_ply_crack(path: &Path) -> Result<(SurfaceData, Option<Vec<u8>>), IoError> {
    parse_ply_crack(path, &read_all(path)?)
}

/// [`read_ply_crack`] on the bytes of a PLY file; `path` only names it in errors.
pub fn parse_ply_crack(
    path: &Path,
    data: &[u8],
) -> Result<(SurfaceData, Option<Vec<u8>>), IoError> {
    let mut reader = data;
    let parser = Parser::<DefaultElement>::new();
    let ply = parser.read_ply(&mut reader).map_err(|e| {
        let text = e.to_string();
        match e.line() {
            Some(line) => {
                let message = text
                    .strip_prefix(&format!("Line {line}: "))
                    .unwrap_or(&text)
                    .to_string();
                IoError::parse(path, line, message)
            }
            None => format_error(path, text),
        }
    })?;
    let mut surface = SurfaceData::default();
    if let Some(vertices) = ply.payload.get("vertex") {
        surface.vertices.reserve(vertices.len());
        for (i, v) in vertices.iter().enumerate() {
            let mut p = [0.0; 3];
            for (c, key) in p.iter_mut().zip(["x", "y", "z"]) {
                *c = v.get(key).and_then(scalar_f64).ok_or_else(|| {
                    format_error(
                        path,
                        format!("vertex {} has no numeric \"{key}\" property", i + 1),
                    )
                })?;
            }
            if !p.iter().all(|c| c.is_finite()) {
                let n = vertices.len();
                let message = format!("vertex {} of {n} has a non-finite coordinate {p:?}", i + 1);
                return Err(match first_line_of(data, &ply.header, "vertex") {
                    Some(first) => IoError::parse(path, first + i, message),
                    None => format_error(path, message),
                });
            }
            surface.vertices.push(p);
        }
    } else {
        return Err(format_error(path, "no \"vertex\" element".into()));
    }
    let n = surface.vertices.len();
    let has_crack = ply
        .header
        .elements
        .get("face")
        .is_some_and(|f| f.properties.contains_key("crack"));
    let mut crack = has_crack.then(Vec::new);
    for (i, f) in ply.payload.get("face").into_iter().flatten().enumerate() {
        let list = f
            .get("vertex_indices")
            .or_else(|| f.get("vertex_index"))
            .and_then(Property::to_u32_list)
            .ok_or_else(|| {
                format_error(
                    path,
                    format!("face {} has no integer \"vertex_indices\" list", i + 1),
                )
            })?;
        if list.len() < 3 {
            return Err(format_error(
                path,
                format!(
                    "face {} has {} vertices, expected at least 3",
                    i + 1,
                    list.len()
                ),
            ));
        }
        if let Some(&bad) = list.iter().find(|&&v| v as usize >= n) {
            return Err(format_error(
                path,
                format!(
                    "face {}: vertex index {bad} out of range ({n} vertices, counted from 0)",
                    i + 1
                ),
            ));
        }
        let flag = match (&crack, f.get("crack")) {
            (Some(_), Some(p)) => scalar_u8(p).ok_or_else(|| {
                format_error(
                    path,
                    format!("face {}: crack value {p:?} is not an integer 0..255", i + 1),
                )
            })?,
            _ => 0,
        };
        for k in 2..list.len() {
            if let (Some(&a), Some(&b), Some(&c)) = (list.first(), list.get(k - 1), list.get(k)) {
                surface.faces.push([a, b, c]);
                if let Some(cr) = &mut crack {
                    cr.push(flag);
                }
            }
        }
    }
    Ok((surface, crack))
}

/// The 1-based line of the first `element` of an ASCII PLY (`None` for a binary one): the line
/// after `end_header`, plus the counts of the elements before it.
pub(crate) fn first_line_of(data: &[u8], header: &Header, element: &str) -> Option<usize> {
    if !matches!(header.encoding, Encoding::Ascii) {
        return None;
    }
    let marker = b"end_header";
    let at = data.windows(marker.len()).position(|w| w == marker)?;
    let header_lines = data[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    let mut first = header_lines + 1;
    for (name, def) in &header.elements {
        if name == element {
            return Some(first);
        }
        first = first.saturating_add(def.count);
    }
    None
}

fn format_error(path: &Path, message: String) -> IoError {
    IoError::Format {
        file: path.to_path_buf(),
        message,
    }
}

/// A numeric PLY scalar as f64 (`None` for lists).
pub(crate) fn scalar_f64(p: &Property) -> Option<f64> {
    match *p {
        Property::Float(v) => Some(f64::from(v)),
        Property::Double(v) => Some(v),
        Property::Char(v) => Some(f64::from(v)),
        Property::UChar(v) => Some(f64::from(v)),
        Property::Short(v) => Some(f64::from(v)),
        Property::UShort(v) => Some(f64::from(v)),
        Property::Int(v) => Some(f64::from(v)),
        Property::UInt(v) => Some(f64::from(v)),
        _ => None,
    }
}

fn scalar_u8(p: &Property) -> Option<u8> {
    let v: i64 = match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        _ => return None,
    };
    u8::try_from(v).ok()
}
