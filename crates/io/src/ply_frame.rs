//! Reading a frame surface PLY back with every attribute [`crate::write_ply`] can write, at
//! the precision it was stored in (f32), so that what is made from it (a USD cache, a render)
//! carries the frame's numbers exactly.

use crate::error::read_all;
use crate::ply_read::{parse_ply_crack, scalar_f64};
use crate::IoError;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::path::Path;

/// A frame surface as stored: f32 vertex data, triangles, and the optional attributes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameSurface {
    /// Vertex positions (length).
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as 0-based vertex indices (polygons fan-triangulated).
    pub faces: Vec<[u32; 3]>,
    /// Per vertex unit normal (`nx ny nz`).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Per vertex velocity (`vx vy vz`, length/time).
    pub velocities: Option<Vec<[f32; 3]>>,
    /// Per vertex texture coordinates (`s t`).
    pub uv: Option<Vec<[f32; 2]>>,
    /// Per vertex mesh vertex id (`vertex_id`).
    pub vertex_ids: Option<Vec<u32>>,
    /// Per face crack flag (`crack`).
    pub crack: Option<Vec<u8>>,
    /// Per face fragment id (`fragment`).
    pub fragment: Option<Vec<u32>>,
}

/// Reads a frame surface PLY (any encoding; see [`FrameSurface`]). A vertex attribute is read
/// when all its properties are present; values that are not numbers are format errors.
pub fn read_ply_frame(path: &Path) -> Result<FrameSurface, IoError> {
    parse_ply_frame(path, &read_all(path)?)
}

/// [`read_ply_frame`] on the bytes of a PLY file; `path` only names it in errors.
pub fn parse_ply_frame(path: &Path, data: &[u8]) -> Result<FrameSurface, IoError> {
    if let Some(frame) = binary::parse(path, data) {
        return frame;
    }
    // The checked reader first: counts, indices, finite coordinates, crack flags.
    let (checked, crack) = parse_ply_crack(path, data)?;
    let mut reader = data;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| format_error(path, e.to_string()))?;
    let vertices = ply.payload.get("vertex").map_or(&[][..], |v| v.as_slice());
    let floats = |keys: &[&str]| -> Result<Option<Vec<f32>>, IoError> {
        let Some(first) = vertices.first() else {
            return Ok(None);
        };
        if !keys.iter().all(|k| first.contains_key(*k)) {
            return Ok(None);
        }
        let mut out = Vec::with_capacity(vertices.len() * keys.len());
        for (i, v) in vertices.iter().enumerate() {
            for k in keys {
                out.push(v.get(*k).and_then(scalar_f32).ok_or_else(|| {
                    format_error(path, format!("vertex {}: \"{k}\" is not a number", i + 1))
                })?);
            }
        }
        Ok(Some(out))
    };
    let triples = |v: Vec<f32>| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mut frame = FrameSurface {
        vertices: triples(floats(&["x", "y", "z"])?.unwrap_or_default()),
        normals: floats(&["nx", "ny", "nz"])?.map(triples),
        velocities: floats(&["vx", "vy", "vz"])?.map(triples),
        uv: floats(&["s", "t"])?.map(|v| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect()),
        faces: checked.faces,
        crack,
        ..FrameSurface::default()
    };
    let has = |element: &str, key: &str| {
        ply.header
            .elements
            .get(element)
            .is_some_and(|e| e.properties.contains_key(key))
    };
    if has("vertex", "vertex_id") {
        let mut ids = Vec::with_capacity(vertices.len());
        for (i, v) in vertices.iter().enumerate() {
            ids.push(v.get("vertex_id").and_then(scalar_u32).ok_or_else(|| {
                format_error(path, format!("vertex {}: vertex_id is not an index", i + 1))
            })?);
        }
        frame.vertex_ids = Some(ids);
    }
    if has("face", "fragment") {
        let mut ids = Vec::new();
        for (i, f) in ply.payload.get("face").into_iter().flatten().enumerate() {
            let id = f.get("fragment").and_then(scalar_u32).ok_or_else(|| {
                format_error(path, format!("face {}: fragment is not an index", i + 1))
            })?;
            // A polygon's id is repeated for each of its triangles, as its crack flag is.
            let corners = f
                .get("vertex_indices")
                .or_else(|| f.get("vertex_index"))
                .and_then(Property::to_u32_list)
                .map_or(3, |l| l.len());
            ids.extend(std::iter::repeat_n(id, corners.saturating_sub(2)));
        }
        frame.fragment = Some(ids);
    }
    Ok(frame)
}

/// A direct decoder for the common case, little-endian binary files whose vertex element has
/// only scalar properties and whose face element is the index list followed by scalars (what
/// [`crate::write_ply`] writes): four times faster than the generic reader, which stores
/// every value in a map. Anything else is left to the generic reader.
mod binary {
    use super::{format_error, FrameSurface};
    use crate::IoError;
    use std::path::Path;

    #[derive(Clone, Copy, PartialEq)]
    enum Ty {
        I8,
        U8,
        I16,
        U16,
        I32,
        U32,
        F32,
        F64,
    }

    impl Ty {
        fn parse(name: &str) -> Option<Ty> {
            Some(match name {
                "char" | "int8" => Ty::I8,
                "uchar" | "uint8" => Ty::U8,
                "short" | "int16" => Ty::I16,
                "ushort" | "uint16" => Ty::U16,
                "int" | "int32" => Ty::I32,
                "uint" | "uint32" => Ty::U32,
                "float" | "float32" => Ty::F32,
                "double" | "float64" => Ty::F64,
                _ => return None,
            })
        }

        fn size(self) -> usize {
            match self {
                Ty::I8 | Ty::U8 => 1,
                Ty::I16 | Ty::U16 => 2,
                Ty::I32 | Ty::U32 | Ty::F32 => 4,
                Ty::F64 => 8,
            }
        }

        /// The value at the start of `b` (at least `size` bytes) as f64.
        fn get(self, b: &[u8]) -> f64 {
            let a = |n: usize| -> [u8; 8] {
                let mut out = [0u8; 8];
                out[..n].copy_from_slice(&b[..n]);
                out
            };
            match self {
                Ty::I8 => f64::from(b[0] as i8),
                Ty::U8 => f64::from(b[0]),
                Ty::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
                Ty::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
                Ty::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                Ty::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                Ty::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                Ty::F64 => f64::from_le_bytes(a(8)),
            }
        }
    }

    /// An element of the header: name, count, scalar properties, and the index list's count
    /// and index types when the list comes first.
    type Element = (String, usize, Vec<(String, Ty)>, Option<(Ty, Ty)>);

    /// `None` when the file is not of the handled shape.
    pub(super) fn parse(path: &Path, data: &[u8]) -> Option<Result<FrameSurface, IoError>> {
        let end = find(data, b"end_header\n")?;
        let header = std::str::from_utf8(&data[..end]).ok()?;
        let mut lines = header.lines();
        if lines.next()? != "ply" {
            return None;
        }
        let mut elements: Vec<Element> = Vec::new();
        let mut binary = false;
        for line in lines {
            let w: Vec<&str> = line.split_whitespace().collect();
            match w.as_slice() {
                ["format", "binary_little_endian", "1.0"] => binary = true,
                ["format", ..] => return None,
                ["comment", ..] | ["obj_info", ..] | [] => {}
                ["element", name, count] => {
                    elements.push((name.to_string(), count.parse().ok()?, Vec::new(), None))
                }
                ["property", "list", ct, it, name] => {
                    let e = elements.last_mut()?;
                    let list_ok = e.0 == "face"
                        && e.2.is_empty()
                        && e.3.is_none()
                        && matches!(*name, "vertex_indices" | "vertex_index");
                    if !list_ok {
                        return None;
                    }
                    e.3 = Some((Ty::parse(ct)?, Ty::parse(it)?));
                }
                ["property", ty, name] => {
                    let e = elements.last_mut()?;
                    e.2.push((name.to_string(), Ty::parse(ty)?));
                }
                _ => return None,
            }
        }
        let names: Vec<&str> = elements.iter().map(|e| e.0.as_str()).collect();
        if !binary || !(names == ["vertex", "face"] || names == ["vertex"]) {
            return None;
        }
        if elements[0].3.is_some() || elements.get(1).is_some_and(|f| f.3.is_none()) {
            return None;
        }
        Some(decode(
            path,
            &data[end + b"end_header\n".len()..],
            &elements,
        ))
    }

    fn find(data: &[u8], what: &[u8]) -> Option<usize> {
        data.windows(what.len()).position(|w| w == what)
    }

    fn decode(path: &Path, body: &[u8], elements: &[Element]) -> Result<FrameSurface, IoError> {
        let short = |what: &str| format_error(path, format!("the file ends inside {what}"));
        let (_, n, props, _) = &elements[0];
        let row: usize = props.iter().map(|p| p.1.size()).sum();
        let need = n.checked_mul(row).ok_or_else(|| short("the vertices"))?;
        let vbytes = body.get(..need).ok_or_else(|| short("the vertices"))?;
        let at = |key: &str| -> Option<(usize, Ty)> {
            let mut off = 0;
            for (name, ty) in props {
                if name == key {
                    return Some((off, *ty));
                }
                off += ty.size();
            }
            None
        };
        let column =
            |keys: &[&str]| -> Option<Vec<(usize, Ty)>> { keys.iter().map(|k| at(k)).collect() };
        let Some(xyz) = column(&["x", "y", "z"]) else {
            return Err(format_error(
                path,
                "vertex has no numeric \"x\", \"y\" and \"z\"".into(),
            ));
        };
        let f32s = |cols: &[(usize, Ty)]| -> Vec<f32> {
            let mut out = Vec::with_capacity(n * cols.len());
            for r in vbytes.chunks_exact(row.max(1)).take(*n) {
                for &(off, ty) in cols {
                    out.push(match ty {
                        Ty::F32 => f32::from_le_bytes([r[off], r[off + 1], r[off + 2], r[off + 3]]),
                        _ => ty.get(&r[off..]) as f32,
                    });
                }
            }
            out
        };
        let triples = |v: Vec<f32>| -> Vec<[f32; 3]> {
            v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
        };
        let vertices = triples(f32s(&xyz));
        if let Some(k) = vertices
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format_error(
                path,
                format!(
                    "vertex {} of {n} has a non-finite coordinate {:?}",
                    k + 1,
                    vertices[k]
                ),
            ));
        }
        let mut frame = FrameSurface {
            vertices,
            normals: column(&["nx", "ny", "nz"]).map(|c| triples(f32s(&c))),
            velocities: column(&["vx", "vy", "vz"]).map(|c| triples(f32s(&c))),
            uv: column(&["s", "t"])
                .map(|c| f32s(&c).chunks_exact(2).map(|p| [p[0], p[1]]).collect()),
            ..FrameSurface::default()
        };
        if let Some((off, ty)) = at("vertex_id") {
            let mut ids = Vec::with_capacity(*n);
            for (k, r) in vbytes.chunks_exact(row.max(1)).take(*n).enumerate() {
                let v = ty.get(&r[off..]);
                if v < 0.0 || v > f64::from(u32::MAX) || v.fract() != 0.0 {
                    return Err(format_error(
                        path,
                        format!("vertex {}: vertex_id is not an index", k + 1),
                    ));
                }
                ids.push(v as u32);
            }
            frame.vertex_ids = Some(ids);
        }
        let Some((_, m, fprops, Some((ct, it)))) = elements.get(1) else {
            return Ok(frame);
        };
        let mut pos = need;
        let has = |key: &str| fprops.iter().any(|p| p.0 == key);
        let mut crack = has("crack").then(Vec::new);
        let mut fragment = has("fragment").then(Vec::new);
        frame.faces.reserve(*m);
        for f in 0..*m {
            let count = body
                .get(pos..pos + ct.size())
                .map(|b| ct.get(b))
                .ok_or_else(|| short("the faces"))?;
            pos += ct.size();
            if !(3.0..=f64::from(u16::MAX)).contains(&count) || count.fract() != 0.0 {
                return Err(format_error(
                    path,
                    format!("face {} has {count} vertices, expected at least 3", f + 1),
                ));
            }
            let count = count as usize;
            let bytes = body
                .get(pos..pos + count * it.size())
                .ok_or_else(|| short("the faces"))?;
            pos += count * it.size();
            let mut list = Vec::with_capacity(count);
            for b in bytes.chunks_exact(it.size()) {
                let v = it.get(b);
                if v < 0.0 || v >= *n as f64 || v.fract() != 0.0 {
                    return Err(format_error(
                        path,
                        format!(
                            "face {}: vertex index {v} out of range ({n} vertices, counted from 0)",
                            f + 1
                        ),
                    ));
                }
                list.push(v as u32);
            }
            let mut flag = 0u8;
            let mut id = 0u32;
            for (name, ty) in fprops {
                let b = body
                    .get(pos..pos + ty.size())
                    .ok_or_else(|| short("the faces"))?;
                pos += ty.size();
                let v = ty.get(b);
                match name.as_str() {
                    "crack" => {
                        if !(0.0..=255.0).contains(&v) || v.fract() != 0.0 {
                            return Err(format_error(
                                path,
                                format!("face {}: crack value {v} is not an integer 0..255", f + 1),
                            ));
                        }
                        flag = v as u8;
                    }
                    "fragment" => {
                        if v < 0.0 || v > f64::from(u32::MAX) || v.fract() != 0.0 {
                            return Err(format_error(
                                path,
                                format!("face {}: fragment is not an index", f + 1),
                            ));
                        }
                        id = v as u32;
                    }
                    _ => {}
                }
            }
            for k in 2..count {
                frame.faces.push([list[0], list[k - 1], list[k]]);
                if let Some(c) = &mut crack {
                    c.push(flag);
                }
                if let Some(g) = &mut fragment {
                    g.push(id);
                }
            }
        }
        frame.crack = crack;
        frame.fragment = fragment;
        Ok(frame)
    }
}

fn scalar_f32(p: &Property) -> Option<f32> {
    match *p {
        Property::Float(v) => Some(v),
        _ => scalar_f64(p).map(|v| v as f32),
    }
}

fn scalar_u32(p: &Property) -> Option<u32> {
    match *p {
        Property::UInt(v) => Some(v),
        Property::UChar(v) => Some(v.into()),
        Property::UShort(v) => Some(v.into()),
        Property::Int(v) => u32::try_from(v).ok(),
        Property::Short(v) => u32::try_from(v).ok(),
        Property::Char(v) => u32::try_from(v).ok(),
        _ => None,
    }
}

fn format_error(path: &Path, message: String) -> IoError {
    IoError::Format {
        file: path.to_path_buf(),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{write_ply, PlyEncoding, SurfaceRef};

    #[test]
    fn every_attribute_comes_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let vertices = [
            [0.1, 0.2, 0.3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let normals = [
            [0.0, 0.0, -1.0],
            [0.6, 0.8, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let velocities = [
            [1.5, -2.0, 0.25],
            [0.0; 3],
            [3.0, 3.0, 3.0],
            [-1e-3, 0.0, 7.0],
        ];
        let uv = [[0.0, 0.5], [1.0, 0.25], [0.125, 0.0], [0.75, 1.0]];
        let ids = [7, 7, 9, 12];
        let crack = [0, 1, 1, 0];
        let fragment = [3, 3, 4, 5];
        let surface = SurfaceRef {
            vertices: &vertices,
            faces: &faces,
            crack: Some(&crack),
            normals: Some(&normals),
            velocities: Some(&velocities),
            uv: Some(&uv),
            vertex_ids: Some(&ids),
            fragment: Some(&fragment),
            ..SurfaceRef::default()
        };
        for encoding in [PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii] {
            let path = dir.path().join("f.ply");
            write_ply(&path, &surface, encoding).unwrap();
            let f = read_ply_frame(&path).unwrap();
            let f32s = |a: &[[f64; 3]]| a.iter().map(|p| p.map(|c| c as f32)).collect::<Vec<_>>();
            assert_eq!(f.vertices, f32s(&vertices));
            assert_eq!(f.faces, faces);
            assert_eq!(f.normals.unwrap(), f32s(&normals));
            assert_eq!(f.velocities.unwrap(), f32s(&velocities));
            let uv32: Vec<[f32; 2]> = uv.iter().map(|p| p.map(|c| c as f32)).collect();
            assert_eq!(f.uv.unwrap(), uv32);
            assert_eq!(f.vertex_ids.unwrap(), ids);
            assert_eq!(f.crack.unwrap(), crack);
            assert_eq!(f.fragment.unwrap(), fragment);
        }
        // The direct binary decoder and the generic reader agree.
        let path = dir.path().join("b.ply");
        write_ply(&path, &surface, PlyEncoding::BinaryLittleEndian).unwrap();
        let data = std::fs::read(&path).unwrap();
        let fast = binary::parse(&path, &data).unwrap().unwrap();
        // The same file with its format line spelled out in ASCII goes the generic way.
        let ascii = dir.path().join("a.ply");
        write_ply(&ascii, &surface, PlyEncoding::Ascii).unwrap();
        let adata = std::fs::read(&ascii).unwrap();
        assert!(binary::parse(&ascii, &adata).is_none());
        assert_eq!(fast, parse_ply_frame(&ascii, &adata).unwrap());
        // A truncated file and an index out of range are errors, not panics.
        for cut in [data.len() - 1, data.len() - 20, data.len() / 2] {
            assert!(parse_ply_frame(&path, &data[..cut]).is_err());
        }
        // Without the optional attributes: none read.
        let path = dir.path().join("plain.ply");
        write_ply(
            &path,
            &SurfaceRef::new(&vertices, &faces),
            PlyEncoding::Ascii,
        )
        .unwrap();
        let f = read_ply_frame(&path).unwrap();
        assert!(f.normals.is_none() && f.velocities.is_none() && f.uv.is_none());
        assert!(f.vertex_ids.is_none() && f.crack.is_none() && f.fragment.is_none());
    }
}
