//! A USD text layer (`.usda`) writer for animated caches.
//!
//! A usda file lists each attribute's time samples together, so a cache written frame by frame
//! cannot be streamed straight out. [`UsdaLayer`] keeps the prim tree and, for every time
//! sample, only an index entry: the sample's text goes to a spool file beside the output as it
//! is given. [`UsdaLayer::finish`] then writes the layer atomically, attribute by attribute,
//! reading each sample back from the spool. Memory stays that of one frame's text whatever the
//! length of the run; the disk holds the spool and the output until the spool is removed.
//!
//! The values are written as USD's text format has them: numbers in Rust's shortest form that
//! reads back to the same `f32` or `f64`, so a reader gets exactly the numbers it was given.

use crate::{atomic_write, IoError};
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// A prim of a [`UsdaLayer`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PrimId(usize);

/// A time-sampled attribute of a [`UsdaLayer`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AttrId(usize);

#[derive(Debug, Default)]
struct Prim {
    /// `def Mesh "name"`.
    head: String,
    /// Lines inside the prim's metadata parentheses.
    metadata: Vec<String>,
    /// Property lines that are not time-sampled, in order.
    properties: Vec<String>,
    /// Time-sampled attributes, in order.
    sampled: Vec<usize>,
    children: Vec<usize>,
}

#[derive(Debug)]
struct Attr {
    /// `point3f[] points`.
    declaration: String,
    /// Metadata lines (`interpolation = "vertex"`).
    metadata: Vec<String>,
    /// The attribute's samples: (time, spool offset, length), in the order given.
    samples: Vec<(f64, u64, u64)>,
}

/// A usda layer being written to `path` (see the module documentation).
#[derive(Debug)]
pub struct UsdaLayer {
    path: PathBuf,
    metadata: Vec<String>,
    prims: Vec<Prim>,
    roots: Vec<usize>,
    attrs: Vec<Attr>,
    spool_path: PathBuf,
    spool: Option<BufWriter<File>>,
    spooled: u64,
    text: Vec<u8>,
}

impl UsdaLayer {
    /// Starts a layer that [`UsdaLayer::finish`] writes to `path`; the spool is created beside
    /// it (`.NAME.spool`) and removed when the layer is finished or dropped.
    pub fn create(path: &Path) -> Result<UsdaLayer, IoError> {
        let name = path
            .file_name()
            .map_or_else(|| "layer".into(), |n| n.to_string_lossy().into_owned());
        let spool_path = path.with_file_name(format!(".{name}.spool{}", std::process::id()));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&spool_path)
            .map_err(|e| IoError::io(&spool_path, e))?;
        Ok(UsdaLayer {
            path: path.to_path_buf(),
            metadata: Vec::new(),
            prims: Vec::new(),
            roots: Vec::new(),
            attrs: Vec::new(),
            spool_path,
            spool: Some(BufWriter::with_capacity(1 << 20, file)),
            spooled: 0,
            text: Vec::new(),
        })
    }

    /// Adds a line of layer metadata, `key = value` with `value` in usda syntax (see
    /// [`quote`] for strings).
    pub fn metadata(&mut self, key: &str, value: &str) {
        self.metadata.push(format!("{key} = {value}"));
    }

    /// Adds a prim `def TYPE "name"` under `parent` (or at the root). `name` must be a USD
    /// identifier ([`is_identifier`]).
    pub fn prim(
        &mut self,
        parent: Option<PrimId>,
        type_name: &str,
        name: &str,
    ) -> Result<PrimId, IoError> {
        if !is_identifier(name) || !(type_name.is_empty() || is_identifier(type_name)) {
            return Err(IoError::invalid(
                &self.path,
                format!("\"{name}\" of type \"{type_name}\" is not a valid USD prim"),
            ));
        }
        let id = self.prims.len();
        let head = if type_name.is_empty() {
            format!("def \"{name}\"")
        } else {
            format!("def {type_name} \"{name}\"")
        };
        self.prims.push(Prim {
            head,
            ..Prim::default()
        });
        match parent {
            Some(PrimId(p)) => self.prims[p].children.push(id),
            None => self.roots.push(id),
        }
        Ok(PrimId(id))
    }

    /// Adds a metadata line to a prim (`kind = "component"`, `prepend apiSchemas = [...]`).
    pub fn prim_metadata(&mut self, prim: PrimId, line: &str) {
        self.prims[prim.0].metadata.push(line.to_string());
    }

    /// Adds a property line that is not time-sampled (`uniform token subdivisionScheme =
    /// "none"`, `rel material:binding = </Looks/crack>`).
    pub fn property(&mut self, prim: PrimId, line: &str) {
        self.prims[prim.0].properties.push(line.to_string());
    }

    /// Declares a time-sampled attribute (`point3f[] points`) with metadata lines.
    pub fn sampled(&mut self, prim: PrimId, declaration: &str, metadata: &[&str]) -> AttrId {
        let id = self.attrs.len();
        self.attrs.push(Attr {
            declaration: declaration.to_string(),
            metadata: metadata.iter().map(|m| m.to_string()).collect(),
            samples: Vec::new(),
        });
        self.prims[prim.0].sampled.push(id);
        AttrId(id)
    }

    /// Adds the sample of `attr` at time code `time`; `value` writes its usda text (see
    /// [`write_vec3f_array`] and its siblings). Samples of one attribute must come in
    /// increasing time.
    pub fn sample(
        &mut self,
        attr: AttrId,
        time: f64,
        value: impl FnOnce(&mut Vec<u8>),
    ) -> Result<(), IoError> {
        if let Some(&(last, _, _)) = self.attrs[attr.0].samples.last() {
            if time <= last || !time.is_finite() {
                return Err(IoError::invalid(
                    &self.path,
                    format!(
                        "{}: sample at time {time} after {last}",
                        self.attrs[attr.0].declaration
                    ),
                ));
            }
        }
        self.text.clear();
        value(&mut self.text);
        let spool = self
            .spool
            .as_mut()
            .ok_or_else(|| IoError::invalid(&self.spool_path, "the layer is finished"))?;
        spool
            .write_all(&self.text)
            .map_err(|e| IoError::io(&self.spool_path, e))?;
        let len = self.text.len() as u64;
        self.attrs[attr.0].samples.push((time, self.spooled, len));
        self.spooled += len;
        Ok(())
    }

    /// Bytes of sample text spooled so far.
    pub fn spooled_bytes(&self) -> u64 {
        self.spooled
    }

    /// Writes the layer to its path atomically and removes the spool.
    pub fn finish(mut self) -> Result<(), IoError> {
        let spool = self
            .spool
            .take()
            .ok_or_else(|| IoError::invalid(&self.spool_path, "the layer is finished"))?;
        let file = spool
            .into_inner()
            .map_err(|e| IoError::io(&self.spool_path, e.into_error()))?;
        let mut reader = file;
        let this = &self;
        let result = atomic_write(&self.path, |w| {
            w.write_all(b"#usda 1.0\n(\n")?;
            for line in &this.metadata {
                writeln!(w, "    {line}")?;
            }
            w.write_all(b")\n")?;
            let mut buf = Vec::new();
            for &root in &this.roots {
                w.write_all(b"\n")?;
                this.write_prim(w, root, 0, &mut reader, &mut buf)?;
            }
            Ok(())
        });
        // Best effort: the spool is ours and temporary; a failure to remove it changes nothing.
        let _ = std::fs::remove_file(&self.spool_path);
        result
    }

    fn write_prim<W: Write>(
        &self,
        w: &mut W,
        prim: usize,
        depth: usize,
        spool: &mut File,
        buf: &mut Vec<u8>,
    ) -> std::io::Result<()> {
        let p = &self.prims[prim];
        let pad = "    ".repeat(depth);
        write!(w, "{pad}{}", p.head)?;
        if !p.metadata.is_empty() {
            writeln!(w, " (")?;
            for m in &p.metadata {
                writeln!(w, "{pad}    {m}")?;
            }
            write!(w, "{pad})")?;
        }
        writeln!(w, "\n{pad}{{")?;
        for line in &p.properties {
            writeln!(w, "{pad}    {line}")?;
        }
        for &a in &p.sampled {
            let attr = &self.attrs[a];
            if attr.samples.is_empty() {
                continue;
            }
            write!(w, "{pad}    {}", attr.declaration)?;
            let single = attr.samples.len() == 1;
            if let [(_, offset, len)] = attr.samples[..] {
                // One sample holds for all time: the attribute's default says the same, and
                // readers (and validators) that ask for the default value find it.
                read_back(spool, offset, len, buf)?;
                w.write_all(b" = ")?;
                w.write_all(buf)?;
            }
            if !attr.metadata.is_empty() {
                writeln!(w, " (")?;
                for m in &attr.metadata {
                    writeln!(w, "{pad}        {m}")?;
                }
                write!(w, "{pad}    )")?;
            }
            writeln!(w)?;
            if single {
                continue;
            }
            writeln!(w, "{pad}    {}.timeSamples = {{", attr.declaration)?;
            for &(time, offset, len) in &attr.samples {
                read_back(spool, offset, len, buf)?;
                write!(w, "{pad}        {time:?}: ")?;
                w.write_all(buf)?;
                w.write_all(b",\n")?;
            }
            writeln!(w, "{pad}    }}")?;
        }
        for (k, &c) in p.children.iter().enumerate() {
            if k > 0 || !p.properties.is_empty() || !p.sampled.is_empty() {
                writeln!(w)?;
            }
            self.write_prim(w, c, depth + 1, spool, buf)?;
        }
        writeln!(w, "{pad}}}")
    }
}

/// Reads `len` bytes at `offset` of the spool into `buf`.
fn read_back(spool: &mut File, offset: u64, len: u64, buf: &mut Vec<u8>) -> std::io::Result<()> {
    let len = usize::try_from(len).map_err(std::io::Error::other)?;
    buf.clear();
    buf.resize(len, 0);
    spool.seek(SeekFrom::Start(offset))?;
    spool.read_exact(buf)
}

impl Drop for UsdaLayer {
    fn drop(&mut self) {
        if self.spool.take().is_some() {
            // Best effort, as in finish.
            let _ = std::fs::remove_file(&self.spool_path);
        }
    }
}

/// True for a USD identifier: a letter or `_`, then letters, digits and `_`.
pub fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// `name` made into a USD identifier: other characters become `_`, and a leading digit (or an
/// empty name) gets a `_` in front.
pub fn identifier(name: &str) -> String {
    let mut out: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !out.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        out.insert(0, '_');
    }
    out
}

/// A usda string literal: `"..."` with `\` and `"` escaped and control characters as `\n`,
/// `\t` or `\xNN`.
pub fn quote(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\x{:02x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Writes `[(x, y, z), ...]`.
pub fn write_vec3f_array(out: &mut Vec<u8>, values: &[[f32; 3]]) {
    write_tuples(out, values.iter().map(|v| v.as_slice()));
}

/// Writes `[(u, v), ...]`.
pub fn write_vec2f_array(out: &mut Vec<u8>, values: &[[f32; 2]]) {
    write_tuples(out, values.iter().map(|v| v.as_slice()));
}

/// Writes `[a, b, ...]` of integers.
pub fn write_int_array(out: &mut Vec<u8>, values: impl IntoIterator<Item = i64>) {
    // Writing to a Vec cannot fail.
    write_separated(out, b"[]", values, |o, v| {
        let _ = write!(o, "{v}");
    });
}

/// Writes `[a, b, ...]` of floats, each as the shortest text that reads back to it.
pub fn write_float_array(out: &mut Vec<u8>, values: impl IntoIterator<Item = f32>) {
    write_separated(out, b"[]", values, |o, v| {
        let _ = write!(o, "{v:?}");
    });
}

/// Writes `(x, y, z)` of doubles.
pub fn write_double3(out: &mut Vec<u8>, v: [f64; 3]) {
    let _ = write!(out, "({:?}, {:?}, {:?})", v[0], v[1], v[2]);
}

fn write_tuples<'a>(out: &mut Vec<u8>, values: impl Iterator<Item = &'a [f32]>) {
    write_separated(out, b"[]", values, |o, v| {
        write_separated(o, b"()", v, |o, c| {
            // Debug: the shortest text that reads back to the same f32, `1.0` for whole
            // numbers, exponent form far from 1.
            let _ = write!(o, "{c:?}");
        })
    });
}

/// Writes `items` between the two `brackets`, separated by `, `, each by `each`.
fn write_separated<T>(
    out: &mut Vec<u8>,
    brackets: &[u8; 2],
    items: impl IntoIterator<Item = T>,
    mut each: impl FnMut(&mut Vec<u8>, T),
) {
    out.push(brackets[0]);
    for (k, item) in items.into_iter().enumerate() {
        if k > 0 {
            out.extend_from_slice(b", ");
        }
        each(out, item);
    }
    out.push(brackets[1]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layer_lists_each_attributes_samples_together() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.usda");
        let mut layer = UsdaLayer::create(&path).unwrap();
        layer.metadata("upAxis", &quote("Z"));
        let root = layer.prim(None, "Xform", "root").unwrap();
        let mesh = layer.prim(Some(root), "Mesh", "m").unwrap();
        layer.property(mesh, "uniform token subdivisionScheme = \"none\"");
        let points = layer.sampled(mesh, "point3f[] points", &[]);
        let counts = layer.sampled(mesh, "int[] faceVertexCounts", &[]);
        let once = layer.sampled(mesh, "token visibility", &[]);
        layer
            .sample(once, 3.0, |o| o.extend_from_slice(b"\"invisible\""))
            .unwrap();
        for frame in 0..3 {
            let z = frame as f32 * 0.1;
            layer
                .sample(points, frame as f64, |o| {
                    write_vec3f_array(o, &[[0.0, 0.0, z], [1e-7, 3.0e20, -2.5]])
                })
                .unwrap();
            if frame != 1 {
                layer
                    .sample(counts, frame as f64, |o| write_int_array(o, [3, 3]))
                    .unwrap();
            }
        }
        // Out of order is refused.
        assert!(layer.sample(points, 1.0, |o| o.push(b'0')).is_err());
        let spool = dir
            .path()
            .join(format!(".a.usda.spool{}", std::process::id()));
        assert!(spool.exists());
        layer.finish().unwrap();
        assert!(!spool.exists());
        let text = std::fs::read_to_string(&path).unwrap();
        let expected = "#usda 1.0\n(\n    upAxis = \"Z\"\n)\n\ndef Xform \"root\"\n{\n    def Mesh \"m\"\n    {\n        uniform token subdivisionScheme = \"none\"\n        point3f[] points\n        point3f[] points.timeSamples = {\n            0.0: [(0.0, 0.0, 0.0), (1e-7, 3e20, -2.5)],\n            1.0: [(0.0, 0.0, 0.1), (1e-7, 3e20, -2.5)],\n            2.0: [(0.0, 0.0, 0.2), (1e-7, 3e20, -2.5)],\n        }\n        int[] faceVertexCounts\n        int[] faceVertexCounts.timeSamples = {\n            0.0: [3, 3],\n            2.0: [3, 3],\n        }\n        token visibility = \"invisible\"\n    }\n}\n";
        assert_eq!(text, expected);
    }

    #[test]
    fn names_and_strings() {
        assert!(is_identifier("wall_2") && is_identifier("_x"));
        assert!(!is_identifier("2wall") && !is_identifier("a-b") && !is_identifier(""));
        assert_eq!(identifier("bunny drop-2"), "bunny_drop_2");
        assert_eq!(identifier("3d"), "_3d");
        assert_eq!(quote("a \"b\"\\\n"), "\"a \\\"b\\\"\\\\\\n\"");
        let dir = tempfile::tempdir().unwrap();
        let mut layer = UsdaLayer::create(&dir.path().join("b.usda")).unwrap();
        assert!(layer.prim(None, "Mesh", "not valid").is_err());
        // Dropping an unfinished layer removes its spool.
        drop(layer);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
