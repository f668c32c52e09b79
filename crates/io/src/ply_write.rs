//! PLY writer, hand-written (binary little-endian or ASCII).
//!
//! Vertex coordinates are written as `float` (f32): what Blender, MeshLab and most tools expect,
//! and half the size; the f64 to f32 rounding is the only loss. Faces are
//! `list uchar int vertex_indices` (count byte always 3), then an optional `uchar crack`;
//! vertices optionally carry `uchar red green blue`.

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
    writeln!(w, "element vertex {}", s.vertices.len())?;
    w.write_all(b"property float x\nproperty float y\nproperty float z\n")?;
    if s.colors.is_some() {
        w.write_all(b"property uchar red\nproperty uchar green\nproperty uchar blue\n")?;
    }
    writeln!(w, "element face {}", s.faces.len())?;
    w.write_all(b"property list uchar int vertex_indices\n")?;
    if s.crack.is_some() {
        w.write_all(b"property uchar crack\n")?;
    }
    w.write_all(b"end_header\n")
}

fn binary<W: Write>(w: &mut W, s: &SurfaceRef) -> io::Result<()> {
    let mut buf = [0u8; 16];
    for (i, p) in s.vertices.iter().enumerate() {
        for (k, &c) in p.iter().enumerate() {
            buf[4 * k..4 * k + 4].copy_from_slice(&(c as f32).to_le_bytes());
        }
        let mut len = 12;
        if let Some(rgb) = s.colors.and_then(|c| c.get(i)) {
            buf[12..15].copy_from_slice(rgb);
            len = 15;
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
            buf[13] = flag;
            len = 14;
        }
        w.write_all(&buf[..len])?;
    }
    Ok(())
}

fn ascii<W: Write>(w: &mut W, s: &SurfaceRef) -> io::Result<()> {
    for (i, p) in s.vertices.iter().enumerate() {
        write!(w, "{:?} {:?} {:?}", p[0] as f32, p[1] as f32, p[2] as f32)?;
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
        w.write_all(b"\n")?;
    }
    Ok(())
}
