//! PLY writer, hand-written (binary little-endian or ASCII).
//!
//! Vertex coordinates are written as `float` (f32): what Blender, MeshLab and most tools expect,
//! and half the size; the f64 to f32 rounding is the only loss. Faces are
//! `list uchar int vertex_indices` (count byte always 3), then an optional `uchar crack` and
//! `uint fragment`; vertices optionally carry `float nx ny nz` (normal), `float vx vy vz`
//! (velocity), `float s t` (texture coordinates), `uint vertex_id` and `uchar red green blue`,
//! in that order.

use crate::{atomic_write, IoError, SurfaceRef};
use std::io::{self, Write};
use std::path::Path;

/// How a PLY file's payload is encoded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PlyEncoding {
    /// `binary_little_endian 1.0` (compact and fast; the default).
    #[default]
    BinaryLittleEndian,
    /// `ascii 1.0` (readable).
    Ascii,
}

/// Writes `surface` as PLY in `encoding`, atomically.
pub fn write_ply(path: &Path, surface: &SurfaceRef, encoding: PlyEncoding) -> Result<(), IoError> {
    surface.validate(path)?;
    if surface.vertices.len() > i32::MAX as usize {
        return Err(IoError::invalid(
            path,
            "more vertices than a PLY int index can address",
        ));
    }
    atomic_write(path, |w| {
        header(w, surface, encoding)?;
        match encoding {
            PlyEncoding::BinaryLittleEndian => binary(w, surface),
            PlyEncoding::Ascii => ascii(w, surface),
        }
    })
}

fn header<W: Write>(w: &mut W, s: &SurfaceRef, encoding: PlyEncoding) -> io::Result<()> {
    let format = match encoding {
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::Ascii => "ascii",
    };
    writeln!(w, "ply\nformat {format} 1.0")?;
    writeln!(
        w,
        "comment written by perifrac-io; coordinates are float (f32)"
    )?;
    if s.velocities.is_some() {
        writeln!(w, "comment vx vy vz: vertex velocity (length/time)")?;
    }
    if s.vertex_ids.is_some() {
        writeln!(
            w,
            "comment vertex_id: the welded vertex this one copies (equal ids: weld them)"
        )?;
    }
    writeln!(w, "element vertex {}", s.vertices.len())?;
    w.write_all(b"property float x\nproperty float y\nproperty float z\n")?;
    if s.normals.is_some() {
        w.write_all(b"property float nx\nproperty float ny\nproperty float nz\n")?;
    }
    if s.velocities.is_some() {
        w.write_all(b"property float vx\nproperty float vy\nproperty float vz\n")?;
    }
    if s.uv.is_some() {
        w.write_all(b"property float s\nproperty float t\n")?;
    }
    if s.vertex_ids.is_some() {
        w.write_all(b"property uint vertex_id\n")?;
    }
    if s.colors.is_some() {
        w.write_all(b"property uchar red\nproperty uchar green\nproperty uchar blue\n")?;
    }
    writeln!(w, "element face {}", s.faces.len())?;
    w.write_all(b"property list uchar int vertex_indices\n")?;
    if s.crack.is_some() {
        w.write_all(b"property uchar crack\n")?;
    }
    if s.fragment.is_some() {
        w.write_all(b"property uint fragment\n")?;
    }
    w.write_all(b"end_header\n")
}

/// The optional per-vertex floats of vertex `i` in header order (normal, velocity, uv).
fn vertex_floats(s: &SurfaceRef, i: usize, out: &mut [f32; 8]) -> usize {
    let mut n = 0;
    let mut put = |vals: &[f64]| {
        for &v in vals {
            out[n] = v as f32;
            n += 1;
        }
    };
    if let Some(v) = s.normals {
        put(&v[i]);
    }
    if let Some(v) = s.velocities {
        put(&v[i]);
    }
    if let Some(v) = s.uv {
        put(&v[i]);
    }
    n
}

fn binary<W: Write>(w: &mut W, s: &SurfaceRef) -> io::Result<()> {
    let mut buf = [0u8; 64];
    let mut extra = [0f32; 8];
    for (i, p) in s.vertices.iter().enumerate() {
        let mut len = 0;
        for &c in p {
            buf[len..len + 4].copy_from_slice(&(c as f32).to_le_bytes());
            len += 4;
        }
        let count = vertex_floats(s, i, &mut extra);
        for &c in &extra[..count] {
            buf[len..len + 4].copy_from_slice(&c.to_le_bytes());
            len += 4;
        }
        if let Some(id) = s.vertex_ids.and_then(|v| v.get(i)) {
            buf[len..len + 4].copy_from_slice(&id.to_le_bytes());
            len += 4;
        }
        if let Some(rgb) = s.colors.and_then(|c| c.get(i)) {
            buf[len..len + 3].copy_from_slice(rgb);
            len += 3;
        }
        w.write_all(&buf[..len])?;
    }
    for (i, f) in s.faces.iter().enumerate() {
        buf[0] = 3;
        for (k, &v) in f.iter().enumerate() {
            // Validated: every index < vertex count <= i32::MAX.
            buf[1 + 4 * k..5 + 4 * k].copy_from_slice(&(v as i32).to_le_bytes());
        }
        let mut len = 13;
        if let Some(&flag) = s.crack.and_then(|c| c.get(i)) {
            buf[len] = flag;
            len += 1;
        }
        if let Some(id) = s.fragment.and_then(|c| c.get(i)) {
            buf[len..len + 4].copy_from_slice(&id.to_le_bytes());
            len += 4;
        }
        w.write_all(&buf[..len])?;
    }
    Ok(())
}

fn ascii<W: Write>(w: &mut W, s: &SurfaceRef) -> io::Result<()> {
    let mut extra = [0f32; 8];
    for (i, p) in s.vertices.iter().enumerate() {
        write!(w, "{:?} {:?} {:?}", p[0] as f32, p[1] as f32, p[2] as f32)?;
        let count = vertex_floats(s, i, &mut extra);
        for c in &extra[..count] {
            write!(w, " {c:?}")?;
        }
        if let Some(id) = s.vertex_ids.and_then(|v| v.get(i)) {
            write!(w, " {id}")?;
        }
        if let Some(rgb) = s.colors.and_then(|c| c.get(i)) {
            write!(w, " {} {} {}", rgb[0], rgb[1], rgb[2])?;
        }
        w.write_all(b"\n")?;
    }
    for (i, f) in s.faces.iter().enumerate() {
        write!(w, "3 {} {} {}", f[0], f[1], f[2])?;
        if let Some(flag) = s.crack.and_then(|c| c.get(i)) {
            write!(w, " {flag}")?;
        }
        if let Some(id) = s.fragment.and_then(|c| c.get(i)) {
            write!(w, " {id}")?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}
