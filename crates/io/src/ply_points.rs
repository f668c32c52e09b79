//! PLY point clouds with per-point scalars (particles with damage, mass, ...).
//!
//! Written as binary little-endian: `float x y z` then one `float` per named scalar. Read back
//! (any encoding, any numeric types) through ply-rs-bw.

use crate::ply_read::scalar_f64;
use crate::{atomic_write, IoError};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::DefaultElement;
use std::io::Write;
use std::path::Path;

/// Points (m) with named per-point scalars, as read from a PLY file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    /// Point positions.
    pub points: Vec<[f64; 3]>,
    /// `(name, values)` for every vertex property other than x, y, z, in header order.
    pub scalars: Vec<(String, Vec<f64>)>,
}

impl PointCloud {
    /// The values of scalar `name`, if present.
    pub fn scalar(&self, name: &str) -> Option<&[f64]> {
        self.scalars
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Writes `points` (m) with `scalars` (`(name, values)`, one value per point, stored as f32)
/// as a binary PLY point cloud, atomically. Names must be PLY identifiers (letters, digits, `_`).
pub fn write_ply_points(
    path: &Path,
    points: &[[f64; 3]],
    scalars: &[(&str, &[f64])],
) -> Result<(), IoError> {
    for (name, values) in scalars {
        if values.len() != points.len() {
            return Err(IoError::invalid(
                path,
                format!(
                    "scalar `{name}` has {} values for {} points",
                    values.len(),
                    points.len()
                ),
            ));
        }
        let ok = !name.is_empty()
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !["x", "y", "z"].contains(name);
        if !ok {
            return Err(IoError::invalid(
                path,
                format!("`{name}` is not a usable PLY property name"),
            ));
        }
    }
    atomic_write(path, |w| {
        writeln!(w, "ply\nformat binary_little_endian 1.0")?;
        writeln!(w, "comment written by perifrac-io; values are float (f32)")?;
        writeln!(w, "element vertex {}", points.len())?;
        w.write_all(b"property float x\nproperty float y\nproperty float z\n")?;
        for (name, _) in scalars {
            writeln!(w, "property float {name}")?;
        }
        w.write_all(b"end_header\n")?;
        let mut row = Vec::with_capacity(4 * (3 + scalars.len()));
        for (i, p) in points.iter().enumerate() {
            row.clear();
            for c in p {
                row.extend_from_slice(&(*c as f32).to_le_bytes());
            }
            for (_, values) in scalars {
                row.extend_from_slice(&(values[i] as f32).to_le_bytes());
            }
            w.write_all(&row)?;
        }
        Ok(())
    })
}

/// Reads the `vertex` element of a PLY file as points with every other numeric vertex
/// property as a named scalar; a NaN or infinite coordinate is an error naming the point
/// (counted from 1).
pub fn read_ply_points(path: &Path) -> Result<PointCloud, IoError> {
    parse_ply_points(path, &crate::error::read_all(path)?)
}

/// [`read_ply_points`] on the bytes of a PLY file; `path` only names it in errors.
pub fn parse_ply_points(path: &Path, data: &[u8]) -> Result<PointCloud, IoError> {
    let mut reader = data;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| IoError::invalid(path, e.to_string()))?;
    let names: Vec<String> = ply
        .header
        .elements
        .get("vertex")
        .map(|e| {
            e.properties
                .keys()
                .filter(|k| !["x", "y", "z"].contains(&k.as_str()))
                .cloned()
                .collect()
        })
        .ok_or_else(|| IoError::invalid(path, "no \"vertex\" element"))?;
    let mut cloud = PointCloud {
        points: Vec::new(),
        scalars: names.iter().map(|n| (n.clone(), Vec::new())).collect(),
    };
    for (i, v) in ply.payload.get("vertex").into_iter().flatten().enumerate() {
        let mut p = [0.0; 3];
        for (c, key) in p.iter_mut().zip(["x", "y", "z"]) {
            *c = v.get(key).and_then(scalar_f64).ok_or_else(|| {
                IoError::invalid(path, format!("vertex {} has no numeric \"{key}\"", i + 1))
            })?;
        }
        if !p.iter().all(|c| c.is_finite()) {
            return Err(IoError::Format {
                file: path.to_path_buf(),
                message: format!("point {} has a non-finite coordinate {p:?}", i + 1),
            });
        }
        cloud.points.push(p);
        for (name, values) in &mut cloud.scalars {
            let value = v.get(name.as_str()).and_then(scalar_f64).ok_or_else(|| {
                IoError::invalid(
                    path,
                    format!("vertex {}: \"{name}\" is not a number", i + 1),
                )
            })?;
            values.push(value);
        }
    }
    Ok(cloud)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_round_trip_at_f32_precision() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.ply");
        let pts = vec![[0.0, 1.0, 2.0], [0.25, -3.5, 1e-3]];
        let damage = [0.0, 0.75];
        let mass = [1.5, 2.5];
        write_ply_points(&path, &pts, &[("damage", &damage), ("mass", &mass)]).unwrap();
        let cloud = read_ply_points(&path).unwrap();
        assert_eq!(cloud.points.len(), 2);
        for (a, b) in cloud.points.iter().zip(&pts) {
            for k in 0..3 {
                // stored as f32: exact for these values except 1e-3 (rel 2^-24)
                assert!((a[k] - b[k]).abs() <= 1e-7 * b[k].abs(), "{a:?} {b:?}");
            }
        }
        assert_eq!(cloud.scalar("damage").unwrap(), &damage);
        assert_eq!(cloud.scalar("mass").unwrap(), &mass);
        assert!(write_ply_points(&path, &pts, &[("bad name", &damage)]).is_err());
        let bad = vec![[0.0, 1.0, 2.0], [0.0, f64::NAN, 0.0]];
        write_ply_points(&path, &bad, &[]).unwrap();
        let e = read_ply_points(&path).unwrap_err().to_string();
        assert!(e.contains("point 2 has a non-finite coordinate"), "{e}");
        assert!(write_ply_points(&path, &pts, &[("short", &[1.0])]).is_err());
    }
}
