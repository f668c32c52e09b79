//! Surfaces the shell scenes and tests are made from.
//!
//! Every generator returns a [`Surface`]: plain vertex positions (m) and triangles as vertex
//! indices, counter-clockwise seen from the side the normal points to. Bad input (sizes that
//! are not finite and positive, too few segments, counts whose vertices would not fit `u32`
//! indices) gives a [`GenerateError`] naming the generator, the parameter and its value.
//!
//! Grids of quads (sheet, tube, bowl rings) are split into two triangles per quad with the
//! diagonal alternating in a checkerboard, so the mesh has no preferred diagonal direction.

use std::collections::HashMap;
use std::f64::consts::PI;

use thiserror::Error;

/// A triangle surface as plain arrays: vertex positions (m) and triangles as vertex indices,
/// counter-clockwise seen from the side the normal points to.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Vertex positions (m).
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, each three vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// What is wrong with a generator's input.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GenerateError {
    /// A size (m) or angle that must be a finite positive number is not.
    #[error("{generator}: {parameter} must be finite and > 0, got {value}")]
    NotPositive {
        /// The generator function that refused.
        generator: &'static str,
        /// The parameter's name.
        parameter: &'static str,
        /// The value given (m, or degrees for angles).
        value: f64,
    },
    /// A count (segments, rings) is below its minimum.
    #[error("{generator}: {parameter} must be at least {min}, got {value}")]
    TooFew {
        /// The generator function that refused.
        generator: &'static str,
        /// The parameter's name.
        parameter: &'static str,
        /// The smallest accepted value.
        min: usize,
        /// The value given.
        value: usize,
    },
    /// A count is above its maximum.
    #[error("{generator}: {parameter} must be at most {max}, got {value}")]
    TooMany {
        /// The generator function that refused.
        generator: &'static str,
        /// The parameter's name.
        parameter: &'static str,
        /// The largest accepted value.
        max: usize,
        /// The value given.
        value: usize,
    },
    /// The counts ask for more vertices than `u32` indices can address (or more triangles
    /// than `usize` can count).
    #[error(
        "{generator}: {detail} gives too many {what} (vertex indices must fit u32, at most {})",
        u32::MAX
    )]
    Overflow {
        /// The generator function that refused.
        generator: &'static str,
        /// What overflows: "vertices" or "triangles".
        what: &'static str,
        /// The counts that overflow, e.g. "nx = 100000, ny = 100000".
        detail: String,
    },
    /// A value is outside its open interval.
    #[error("{generator}: {parameter} must be in ({low}, {high}), got {value}")]
    OutOfRange {
        /// The generator function that refused.
        generator: &'static str,
        /// The parameter's name (with its unit).
        parameter: &'static str,
        /// Lower end of the open interval.
        low: f64,
        /// Upper end of the open interval.
        high: f64,
        /// The value given.
        value: f64,
    },
}

/// The most icosphere subdivisions accepted: 8 gives 655 362 vertices and 1 310 720 triangles.
const MAX_SUBDIVISIONS: u32 = 8;

/// Checks that `value` is finite and > 0.
fn positive(
    generator: &'static str,
    parameter: &'static str,
    value: f64,
) -> Result<f64, GenerateError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(GenerateError::NotPositive {
            generator,
            parameter,
            value,
        })
    }
}

/// Checks that `value >= min`.
fn at_least(
    generator: &'static str,
    parameter: &'static str,
    value: usize,
    min: usize,
) -> Result<usize, GenerateError> {
    if value >= min {
        Ok(value)
    } else {
        Err(GenerateError::TooFew {
            generator,
            parameter,
            min,
            value,
        })
    }
}

/// Checks that a vertex count was computed without overflow and fits `u32` indices (every
/// index `< count <= u32::MAX`).
fn vertex_count(
    generator: &'static str,
    count: Option<usize>,
    detail: impl FnOnce() -> String,
) -> Result<usize, GenerateError> {
    match count {
        Some(n) if u32::try_from(n).is_ok() => Ok(n),
        _ => Err(GenerateError::Overflow {
            generator,
            what: "vertices",
            detail: detail(),
        }),
    }
}

/// Checks that a triangle count was computed without overflowing `usize`.
fn triangle_count(
    generator: &'static str,
    count: Option<usize>,
    detail: impl FnOnce() -> String,
) -> Result<usize, GenerateError> {
    count.ok_or_else(|| GenerateError::Overflow {
        generator,
        what: "triangles",
        detail: detail(),
    })
}

/// Index as `u32`; only called on indices below a count already checked by [`vertex_count`].
#[inline]
fn idx(i: usize) -> u32 {
    debug_assert!(i <= u32::MAX as usize);
    i as u32
}

/// Pushes the two triangles of the quad `v00 v10 v11 v01` (counter-clockwise in the
/// parameter plane), choosing the diagonal by `flip`: `v00-v11` when false, `v10-v01` when true.
#[inline]
fn push_quad(triangles: &mut Vec<[u32; 3]>, v00: u32, v10: u32, v11: u32, v01: u32, flip: bool) {
    if flip {
        triangles.push([v00, v10, v01]);
        triangles.push([v10, v11, v01]);
    } else {
        triangles.push([v00, v10, v11]);
        triangles.push([v00, v11, v01]);
    }
}

/// Validated sheet grid: vertex count `(nx + 1)(ny + 1)` and triangle count `2 nx ny`.
fn grid_counts(
    generator: &'static str,
    nx: usize,
    ny: usize,
) -> Result<(usize, usize), GenerateError> {
    at_least(generator, "nx", nx, 1)?;
    at_least(generator, "ny", ny, 1)?;
    let detail = || format!("nx = {nx}, ny = {ny}");
    let vertices = vertex_count(
        generator,
        nx.checked_add(1)
            .and_then(|a| ny.checked_add(1).and_then(|b| a.checked_mul(b))),
        detail,
    )?;
    let triangles = triangle_count(
        generator,
        nx.checked_mul(ny).and_then(|q| q.checked_mul(2)),
        detail,
    )?;
    Ok((vertices, triangles))
}

/// Sheet connectivity: quad `(i, j)` has corners `j (nx + 1) + i` etc., split with the diagonal
/// alternating in a checkerboard; counter-clockwise seen from +z.
fn grid_triangles(nx: usize, ny: usize, triangle_count: usize) -> Vec<[u32; 3]> {
    let row = nx + 1;
    let mut triangles = Vec::with_capacity(triangle_count);
    for j in 0..ny {
        for i in 0..nx {
            let v00 = idx(j * row + i);
            let v10 = idx(j * row + i + 1);
            let v01 = idx((j + 1) * row + i);
            let v11 = idx((j + 1) * row + i + 1);
            push_quad(&mut triangles, v00, v10, v11, v01, (i + j) % 2 == 1);
        }
    }
    triangles
}

/// `total i / n`, the fraction first so huge sizes cannot overflow, and exactly `total` at
/// `i = n` (no rounding drift at the last row or column).
fn step_at(total: f64, i: usize, n: usize) -> f64 {
    if i == n {
        total
    } else {
        total * (i as f64 / n as f64)
    }
}

/// Sheet vertices `(width i / nx, height j / ny, 0)` at index `j (nx + 1) + i`.
fn grid_vertices(width: f64, height: f64, nx: usize, ny: usize, count: usize) -> Vec<[f64; 3]> {
    let mut vertices = Vec::with_capacity(count);
    for j in 0..=ny {
        let y = step_at(height, j, ny);
        for i in 0..=nx {
            vertices.push([step_at(width, i, nx), y, 0.0]);
        }
    }
    vertices
}

/// A flat rectangle in the z = 0 plane, x in [0, `width`] (m), y in [0, `height`] (m).
///
/// An `(nx + 1) x (ny + 1)` vertex grid, grid point `(i, j)` at index `j (nx + 1) + i` and
/// position `(width i / nx, height j / ny, 0)`. Each quad is split into two triangles with the
/// diagonal alternating in a checkerboard. Normals are +z (counter-clockwise seen from +z).
/// `(nx + 1)(ny + 1)` vertices, `2 nx ny` triangles.
///
/// Errors: `width` or `height` not finite and > 0, `nx` or `ny` zero, or a grid too big for
/// `u32` indices.
pub fn sheet(width: f64, height: f64, nx: usize, ny: usize) -> Result<Surface, GenerateError> {
    const NAME: &str = "sheet";
    positive(NAME, "width", width)?;
    positive(NAME, "height", height)?;
    let (nv, nt) = grid_counts(NAME, nx, ny)?;
    Ok(Surface {
        vertices: grid_vertices(width, height, nx, ny, nv),
        triangles: grid_triangles(nx, ny, nt),
    })
}

/// [`sheet`] with every quad split along the same diagonal, from `(i, j)` to `(i + 1, j + 1)`.
///
/// The per-triangle bending strain reads a twist exactly on this mesh, where the
/// checkerboard's alternating diagonals give each triangle spurious curvature of the twist's
/// size along both axes (mean zero, but squared in the energy: the twist energy is doubled and
/// a simply supported plate is 40% too stiff, at every resolution).
pub fn sheet_uniform(
    width: f64,
    height: f64,
    nx: usize,
    ny: usize,
) -> Result<Surface, GenerateError> {
    let mut s = sheet(width, height, nx, ny)?;
    let w = nx + 1;
    s.triangles.clear();
    for j in 0..ny {
        for i in 0..nx {
            let v = |i: usize, j: usize| (j * w + i) as u32;
            s.triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            s.triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    Ok(s)
}

/// An open tube (no caps) of `radius` (m) around the z axis from z = 0 to z = `length` (m).
///
/// `along + 1` rings of `around` vertices; ring `k` (at z = `length k / along`) vertex `m` (at
/// angle `2 pi m / around` from +x towards +y) has index `k around + m`. Quads are split with
/// the diagonal alternating in a checkerboard (where `around` is odd the two quads either side
/// of the seam at angle 0 share a diagonal direction). Normals point away from the axis.
/// `around (along + 1)` vertices, `2 around along` triangles.
///
/// Errors: `radius` or `length` not finite and > 0, `around < 3`, `along < 1`, or counts too
/// big for `u32` indices.
pub fn cylinder(
    radius: f64,
    length: f64,
    around: usize,
    along: usize,
) -> Result<Surface, GenerateError> {
    const NAME: &str = "cylinder";
    positive(NAME, "radius", radius)?;
    positive(NAME, "length", length)?;
    at_least(NAME, "around", around, 3)?;
    at_least(NAME, "along", along, 1)?;
    let detail = || format!("around = {around}, along = {along}");
    let nv = vertex_count(
        NAME,
        along.checked_add(1).and_then(|r| r.checked_mul(around)),
        detail,
    )?;
    let nt = triangle_count(
        NAME,
        around.checked_mul(along).and_then(|q| q.checked_mul(2)),
        detail,
    )?;

    let ring: Vec<(f64, f64)> = (0..around)
        .map(|m| {
            let angle = 2.0 * PI * m as f64 / around as f64;
            (radius * angle.cos(), radius * angle.sin())
        })
        .collect();
    let mut vertices = Vec::with_capacity(nv);
    for k in 0..=along {
        let z = step_at(length, k, along);
        vertices.extend(ring.iter().map(|&(x, y)| [x, y, z]));
    }

    // Parameter plane (angle, z): d/dangle x d/dz points outward, so counter-clockwise in
    // (m, k) gives outward normals.
    let mut triangles = Vec::with_capacity(nt);
    for k in 0..along {
        for m in 0..around {
            let m1 = (m + 1) % around;
            let v00 = idx(k * around + m);
            let v10 = idx(k * around + m1);
            let v01 = idx((k + 1) * around + m);
            let v11 = idx((k + 1) * around + m1);
            push_quad(&mut triangles, v00, v10, v11, v01, (m + k) % 2 == 1);
        }
    }
    Ok(Surface {
        vertices,
        triangles,
    })
}

/// [`sheet`]`(width, height, nx, ny)` bent onto a cylinder of `radius` (m) whose axis is
/// parallel to y through `(0, y, radius)`.
///
/// Identical triangle list and vertex order as the flat sheet; vertex `(x, y, 0)` goes to
/// `(R sin(x / R), y, R (1 - cos(x / R)))`, so arc length along x is preserved and the sheet
/// curls towards +z. Normals (counter-clockwise as in the flat sheet) point towards the axis,
/// +z at x = 0. For testing bending strain: a flat rest sheet and the same sheet bent.
///
/// Errors: those of [`sheet`], `radius` not finite and > 0, or `width / radius >= 2 pi`
/// (the sheet would wrap onto itself).
pub fn bent_sheet(
    width: f64,
    height: f64,
    nx: usize,
    ny: usize,
    radius: f64,
) -> Result<Surface, GenerateError> {
    const NAME: &str = "bent_sheet";
    positive(NAME, "width", width)?;
    positive(NAME, "height", height)?;
    positive(NAME, "radius", radius)?;
    let angle = width / radius;
    // Both are finite and > 0, so `angle` is never NaN (at most +inf).
    if angle >= 2.0 * PI {
        return Err(GenerateError::OutOfRange {
            generator: NAME,
            parameter: "width / radius (rad)",
            low: 0.0,
            high: 2.0 * PI,
            value: angle,
        });
    }
    let (nv, nt) = grid_counts(NAME, nx, ny)?;
    let mut vertices = grid_vertices(width, height, nx, ny, nv);
    for v in &mut vertices {
        let phi = v[0] / radius;
        *v = [radius * phi.sin(), v[1], radius * (1.0 - phi.cos())];
    }
    Ok(Surface {
        vertices,
        triangles: grid_triangles(nx, ny, nt),
    })
}

/// Normalises `v` to unit length (`v` is never near zero here: icosahedron vertices and
/// midpoints of sphere chords shorter than a diameter).
fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

/// The unit icosphere after `subdivisions` 1-to-4 splits (`subdivisions <= MAX_SUBDIVISIONS`
/// already checked), outward normals.
fn unit_icosphere(subdivisions: u32) -> Surface {
    // Regular icosahedron: the cyclic permutations of (0, +-1, +-t), t the golden ratio,
    // edge length 2.
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<[f64; 3]> = Vec::with_capacity(12);
    for &a in &[-1.0, 1.0] {
        for &b in &[-t, t] {
            vertices.push([0.0, a, b]);
            vertices.push([a, b, 0.0]);
            vertices.push([b, 0.0, a]);
        }
    }
    // Faces: the triples of mutually adjacent vertices (squared distance 4; the other
    // squared distances are 4 t^2 ~ 10.5 and 4 (1 + t^2) ~ 14.5), oriented outward: for a
    // face of a convex polyhedron around the origin, a . (b x c) > 0 iff counter-clockwise
    // seen from outside.
    let adjacent = |p: [f64; 3], q: [f64; 3]| {
        let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 5.0
    };
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(20);
    for a in 0..12 {
        for b in a + 1..12 {
            if !adjacent(vertices[a], vertices[b]) {
                continue;
            }
            for c in b + 1..12 {
                if adjacent(vertices[a], vertices[c]) && adjacent(vertices[b], vertices[c]) {
                    let (pa, pb, pc) = (vertices[a], vertices[b], vertices[c]);
                    let det = pa[0] * (pb[1] * pc[2] - pb[2] * pc[1])
                        - pa[1] * (pb[0] * pc[2] - pb[2] * pc[0])
                        + pa[2] * (pb[0] * pc[1] - pb[1] * pc[0]);
                    let (a, b, c) = (idx(a), idx(b), idx(c));
                    triangles.push(if det > 0.0 { [a, b, c] } else { [a, c, b] });
                }
            }
        }
    }
    debug_assert_eq!(triangles.len(), 20);
    for v in &mut vertices {
        *v = unit(*v);
    }

    for _ in 0..subdivisions {
        // Each level: V' = V + E = V + 3F/2, F' = 4F (at most 655 362 vertices at level 8).
        let mut midpoints: HashMap<(u32, u32), u32> =
            HashMap::with_capacity(triangles.len() * 3 / 2);
        let mut next = Vec::with_capacity(triangles.len() * 4);
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<[f64; 3]>| -> u32 {
            let key = if a < b { (a, b) } else { (b, a) };
            *midpoints.entry(key).or_insert_with(|| {
                let (p, q) = (vertices[a as usize], vertices[b as usize]);
                vertices.push(unit([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                idx(vertices.len() - 1)
            })
        };
        for &[a, b, c] in &triangles {
            let ab = midpoint(a, b, &mut vertices);
            let bc = midpoint(b, c, &mut vertices);
            let ca = midpoint(c, a, &mut vertices);
            next.push([a, ab, ca]);
            next.push([ab, b, bc]);
            next.push([ca, bc, c]);
            next.push([ab, bc, ca]);
        }
        triangles = next;
    }
    Surface {
        vertices,
        triangles,
    }
}

/// Checks `subdivisions <= MAX_SUBDIVISIONS`.
fn check_subdivisions(generator: &'static str, subdivisions: u32) -> Result<(), GenerateError> {
    if subdivisions <= MAX_SUBDIVISIONS {
        Ok(())
    } else {
        Err(GenerateError::TooMany {
            generator,
            parameter: "subdivisions",
            max: MAX_SUBDIVISIONS as usize,
            value: subdivisions as usize,
        })
    }
}

/// A closed sphere of `radius` (m) centred at the origin: a regular icosahedron whose
/// triangles are split into four `subdivisions` times (midpoints shared between neighbouring
/// triangles, no duplicate vertices), every vertex projected onto the sphere.
///
/// `10 4^s + 2` vertices and `20 4^s` triangles; outward normals. Being inscribed, its volume
/// is a little below `4/3 pi r^3` (about 0.22 % low at 4 subdivisions).
///
/// Errors: `radius` not finite and > 0, or `subdivisions > 8`.
pub fn icosphere(radius: f64, subdivisions: u32) -> Result<Surface, GenerateError> {
    const NAME: &str = "icosphere";
    positive(NAME, "radius", radius)?;
    check_subdivisions(NAME, subdivisions)?;
    let mut surface = unit_icosphere(subdivisions);
    for v in &mut surface.vertices {
        *v = [v[0] * radius, v[1] * radius, v[2] * radius];
    }
    Ok(surface)
}

/// A closed ellipsoid centred at the origin with semi-axes `radii` (m) along x, y and z: the
/// [`icosphere`] of radius 1 with `subdivisions`, scaled by `radii` per axis (an egg-like
/// shell). Same counts and connectivity as the icosphere; outward normals.
///
/// Errors: any radius not finite and > 0, or `subdivisions > 8`.
pub fn ellipsoid(radii: [f64; 3], subdivisions: u32) -> Result<Surface, GenerateError> {
    const NAME: &str = "ellipsoid";
    positive(NAME, "radii[0]", radii[0])?;
    positive(NAME, "radii[1]", radii[1])?;
    positive(NAME, "radii[2]", radii[2])?;
    check_subdivisions(NAME, subdivisions)?;
    let mut surface = unit_icosphere(subdivisions);
    for v in &mut surface.vertices {
        *v = [v[0] * radii[0], v[1] * radii[1], v[2] * radii[2]];
    }
    Ok(surface)
}

/// An open spherical cap (a hemispherical bowl at 90 degrees) of the sphere of `radius` (m)
/// centred at `(0, 0, radius)`, around its lowest point `(0, 0, 0)`.
///
/// Vertex 0 is the pole `(0, 0, 0)`; then `rings` rings of `segments` vertices: ring `r`
/// (1-based) at polar angle `phi = opening_angle_deg r / rings` (degrees, measured at the
/// centre from straight down), vertex `m` at azimuth `theta = 2 pi m / segments`, index
/// `1 + (r - 1) segments + m`, position `(R sin phi cos theta, R sin phi sin theta,
/// R (1 - cos phi))`. Normals point away from the sphere centre (the convex outside of the
/// bowl, -z at the pole). The pole's fan and the quads between rings (split with the
/// diagonal alternating in a checkerboard) give `segments (2 rings - 1)` triangles.
///
/// Errors: `radius` not finite and > 0, `opening_angle_deg` not in (0, 180), `rings < 1`,
/// `segments < 3`, or counts too big for `u32` indices.
pub fn bowl(
    radius: f64,
    opening_angle_deg: f64,
    rings: usize,
    segments: usize,
) -> Result<Surface, GenerateError> {
    const NAME: &str = "bowl";
    positive(NAME, "radius", radius)?;
    if !(opening_angle_deg > 0.0 && opening_angle_deg < 180.0) {
        return Err(GenerateError::OutOfRange {
            generator: NAME,
            parameter: "opening_angle_deg",
            low: 0.0,
            high: 180.0,
            value: opening_angle_deg,
        });
    }
    at_least(NAME, "rings", rings, 1)?;
    at_least(NAME, "segments", segments, 3)?;
    let detail = || format!("rings = {rings}, segments = {segments}");
    let nv = vertex_count(
        NAME,
        rings.checked_mul(segments).and_then(|n| n.checked_add(1)),
        detail,
    )?;
    let nt = triangle_count(
        NAME,
        rings
            .checked_mul(2)
            .and_then(|r| r.checked_sub(1))
            .and_then(|r| r.checked_mul(segments)),
        detail,
    )?;

    let opening = opening_angle_deg.to_radians();
    let azimuth: Vec<(f64, f64)> = (0..segments)
        .map(|m| {
            let theta = 2.0 * PI * m as f64 / segments as f64;
            (theta.cos(), theta.sin())
        })
        .collect();
    let mut vertices = Vec::with_capacity(nv);
    vertices.push([0.0, 0.0, 0.0]);
    for r in 1..=rings {
        let phi = opening * r as f64 / rings as f64;
        let (s, c) = (radius * phi.sin(), radius * (1.0 - phi.cos()));
        vertices.extend(azimuth.iter().map(|&(ct, st)| [s * ct, s * st, c]));
    }

    // Parameter plane (theta, phi): d/dtheta x d/dphi points away from the centre, so
    // counter-clockwise in (m, r) gives outward normals.
    let ring_start = |r: usize| 1 + (r - 1) * segments;
    let mut triangles = Vec::with_capacity(nt);
    for m in 0..segments {
        let m1 = (m + 1) % segments;
        // The pole sits below ring 1 in the (theta, phi) plane: the quad v00 v10 v11 v01
        // with v00 = v10 = pole.
        triangles.push([0, idx(ring_start(1) + m1), idx(ring_start(1) + m)]);
    }
    for r in 1..rings {
        for m in 0..segments {
            let m1 = (m + 1) % segments;
            let v00 = idx(ring_start(r) + m);
            let v10 = idx(ring_start(r) + m1);
            let v01 = idx(ring_start(r + 1) + m);
            let v11 = idx(ring_start(r + 1) + m1);
            push_quad(&mut triangles, v00, v10, v11, v01, (m + r) % 2 == 1);
        }
    }
    Ok(Surface {
        vertices,
        triangles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::{HashMap, HashSet};

    // Tolerances. Every position is computed in a handful of f64 operations (a product, a
    // sin/cos, a normalisation), each good to about 1e-16 relative, so geometric identities
    // (a vertex on its sphere, a chord length) hold to a few 1e-16 of the scale; 1e-12
    // relative leaves a wide margin while still catching any real mistake (a wrong formula
    // is off by ~1e-2 or more at these sizes).
    const REL: f64 = 1e-12;

    fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn norm(a: [f64; 3]) -> f64 {
        dot(a, a).sqrt()
    }
    fn corners(s: &Surface, t: [u32; 3]) -> [[f64; 3]; 3] {
        t.map(|i| s.vertices[i as usize])
    }
    /// Twice the area vector (normal direction by the counter-clockwise rule).
    fn area_normal(s: &Surface, t: [u32; 3]) -> [f64; 3] {
        let [a, b, c] = corners(s, t);
        cross(sub(b, a), sub(c, a))
    }

    /// Triangles valid, non-degenerate, every vertex used, edges manifold and consistently
    /// oriented. Returns (V, E, F, number of boundary edges).
    fn check_mesh(s: &Surface) -> (usize, usize, usize, usize) {
        let nv = s.vertices.len();
        assert!(s.vertices.iter().flatten().all(|x| x.is_finite()));
        let mut used = vec![false; nv];
        let mut directed: HashSet<(u32, u32)> = HashSet::new();
        let mut undirected: HashMap<(u32, u32), usize> = HashMap::new();
        for (f, &t) in s.triangles.iter().enumerate() {
            let [a, b, c] = t;
            assert!(
                a != b && b != c && c != a,
                "triangle {f} {t:?} repeats a vertex"
            );
            assert!(
                t.iter().all(|&i| (i as usize) < nv),
                "triangle {f} {t:?} out of range"
            );
            // Positive area, judged against the longest edge: area below 1e-6 of the square
            // of the longest edge is a sliver no generator here should make (the thinnest in
            // these tests, at the rim of the 179-degree bowl, is ~1e-2 of it).
            let [p, q, r] = corners(s, t);
            let longest = norm(sub(q, p)).max(norm(sub(r, q))).max(norm(sub(p, r)));
            let area = 0.5 * norm(area_normal(s, t));
            assert!(
                area > 1e-6 * longest * longest,
                "triangle {f} {t:?}: area {area:e} for longest edge {longest:e}"
            );
            for i in 0..3 {
                let (u, v) = (t[i], t[(i + 1) % 3]);
                used[u as usize] = true;
                assert!(
                    directed.insert((u, v)),
                    "directed edge {u}->{v} used twice: inconsistent orientation"
                );
                *undirected.entry((u.min(v), u.max(v))).or_default() += 1;
            }
        }
        assert!(used.iter().all(|&u| u), "a vertex is used by no triangle");
        assert!(
            undirected.values().all(|&n| n == 1 || n == 2),
            "non-manifold edge"
        );
        let boundary = undirected.values().filter(|&&n| n == 1).count();
        (nv, undirected.len(), s.triangles.len(), boundary)
    }

    fn euler(s: &Surface) -> i64 {
        let (v, e, f, _) = check_mesh(s);
        v as i64 - e as i64 + f as i64
    }

    fn signed_volume(s: &Surface) -> f64 {
        s.triangles
            .iter()
            .map(|&t| {
                let [a, b, c] = corners(s, t);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    fn undirected_edges(s: &Surface) -> HashSet<(u32, u32)> {
        s.triangles
            .iter()
            .flat_map(|t| (0..3).map(move |i| (t[i].min(t[(i + 1) % 3]), t[i].max(t[(i + 1) % 3]))))
            .collect()
    }

    #[test]
    fn sheet_counts_layout_and_normals() {
        for (nx, ny) in [(1, 1), (1, 5), (4, 3), (7, 8)] {
            let s = sheet(2.0, 0.5, nx, ny).unwrap();
            assert_eq!(s.vertices.len(), (nx + 1) * (ny + 1));
            assert_eq!(s.triangles.len(), 2 * nx * ny);
            let (_, _, _, boundary) = check_mesh(&s);
            assert_eq!(boundary, 2 * (nx + ny));
            assert_eq!(euler(&s), 1);
            for j in 0..=ny {
                for i in 0..=nx {
                    let v = s.vertices[j * (nx + 1) + i];
                    assert!((v[0] - 2.0 * i as f64 / nx as f64).abs() <= REL);
                    assert!((v[1] - 0.5 * j as f64 / ny as f64).abs() <= REL);
                    assert_eq!(v[2], 0.0);
                }
            }
            assert_eq!(s.vertices[(nx + 1) * (ny + 1) - 1], [2.0, 0.5, 0.0]);
            for &t in &s.triangles {
                let n = area_normal(&s, t);
                assert!(
                    n[2] > 0.0 && n[0] == 0.0 && n[1] == 0.0,
                    "normal {n:?} not +z"
                );
            }
            // Checkerboard: quad (i, j) has diagonal v00-v11 iff i + j is even, v10-v01
            // otherwise; never both.
            let edges = undirected_edges(&s);
            let row = nx + 1;
            for j in 0..ny {
                for i in 0..nx {
                    let v00 = (j * row + i) as u32;
                    let v11 = v00 + row as u32 + 1;
                    let (v10, v01) = (v00 + 1, v00 + row as u32);
                    let main = edges.contains(&(v00, v11));
                    let anti = edges.contains(&(v10, v01));
                    assert_eq!(main, (i + j) % 2 == 0, "quad ({i}, {j})");
                    assert_eq!(anti, (i + j) % 2 == 1, "quad ({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn cylinder_topology_and_outward_normals() {
        for (around, along) in [(3, 1), (4, 2), (7, 5), (16, 9)] {
            let (r, len) = (0.3, 1.7);
            let s = cylinder(r, len, around, along).unwrap();
            assert_eq!(s.vertices.len(), around * (along + 1));
            assert_eq!(s.triangles.len(), 2 * around * along);
            let (_, _, _, boundary) = check_mesh(&s);
            assert_eq!(boundary, 2 * around, "two rim loops");
            assert_eq!(euler(&s), 0);
            for (k, ring) in s.vertices.chunks(around).enumerate() {
                for (m, v) in ring.iter().enumerate() {
                    let angle = 2.0 * PI * m as f64 / around as f64;
                    assert!((v[0] - r * angle.cos()).abs() <= REL);
                    assert!((v[1] - r * angle.sin()).abs() <= REL);
                    assert!((v[2] - len * k as f64 / along as f64).abs() <= REL);
                }
            }
            for &t in &s.triangles {
                let n = area_normal(&s, t);
                let [a, b, c] = corners(&s, t);
                let centroid = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0, 0.0];
                // Each triangle lies in a flat facet through two vertical lines of the
                // tube: its normal is horizontal and points away from the axis.
                assert!(n[2].abs() <= REL * norm(n));
                assert!(dot(n, centroid) > 0.0, "triangle {t:?} faces the axis");
            }
        }
    }

    #[test]
    fn bent_sheet_matches_sheet_and_preserves_arc_length() {
        let (w, h, nx, ny) = (1.2, 0.4, 12, 3);
        let flat = sheet(w, h, nx, ny).unwrap();
        for radius in [0.2, 0.5, 3.0, 100.0] {
            let bent = bent_sheet(w, h, nx, ny, radius).unwrap();
            assert_eq!(bent.triangles, flat.triangles);
            assert_eq!(bent.vertices.len(), flat.vertices.len());
            assert_eq!(euler(&bent), 1);
            for (p, q) in flat.vertices.iter().zip(&bent.vertices) {
                assert_eq!(p[1], q[1], "y kept");
                // On the cylinder around the axis (0, y, R).
                let d = (q[0] * q[0] + (q[2] - radius) * (q[2] - radius)).sqrt();
                assert!(
                    (d - radius).abs() <= REL * radius,
                    "distance {d} vs {radius}"
                );
            }
            // Neighbours along x: flat distance dx becomes the chord 2 R sin(dx / 2R).
            let dx = w / nx as f64;
            let chord = 2.0 * radius * (dx / (2.0 * radius)).sin();
            for j in 0..=ny {
                for i in 0..nx {
                    let a = bent.vertices[j * (nx + 1) + i];
                    let b = bent.vertices[j * (nx + 1) + i + 1];
                    let d = norm(sub(b, a));
                    assert!((d - chord).abs() <= REL * dx, "chord {d} vs {chord}");
                }
            }
            // Normals keep the counter-clockwise rule: +z at x = 0, towards the axis.
            for &t in &bent.triangles {
                let n = area_normal(&bent, t);
                let a = bent.vertices[t[0] as usize];
                assert!(dot(n, sub([0.0, a[1], radius], a)) > 0.0);
            }
        }
        // Almost a full turn still works.
        let s = bent_sheet(2.0 * PI - 1e-3, 1.0, 64, 2, 1.0).unwrap();
        check_mesh(&s);
    }

    #[test]
    fn icosphere_counts_closed_and_outward() {
        let r = 0.7;
        let exact = 4.0 / 3.0 * PI * r * r * r;
        let mut previous_error = f64::INFINITY;
        for sub in 0..=MAX_SUBDIVISIONS {
            let s = icosphere(r, sub).unwrap();
            let p = 4usize.pow(sub);
            assert_eq!(s.vertices.len(), 10 * p + 2);
            assert_eq!(s.triangles.len(), 20 * p);
            if sub <= 6 {
                // (Levels 7 and 8, 0.3 and 1.3 million triangles, are only checked for counts,
                // radius and volume, to keep the test fast.)
                let (v, e, f, boundary) = check_mesh(&s);
                assert_eq!(
                    boundary, 0,
                    "closed: every edge used by exactly two triangles"
                );
                assert_eq!(e, 30 * p);
                assert_eq!(v as i64 - e as i64 + f as i64, 2, "Euler characteristic");
            }
            for v in &s.vertices {
                assert!((norm(*v) - r).abs() <= REL * r);
            }
            let volume = signed_volume(&s);
            let error = (exact - volume) / exact;
            println!("icosphere subdivisions {sub}: volume {volume:.9} vs {exact:.9}, relative error {error:.3e}");
            // Inscribed polyhedron: volume positive (outward) and below the sphere's. The
            // error is O(h^2): measured 3.945e-1, 1.265e-1, 3.384e-2, 8.606e-3, 2.161e-3,
            // 5.408e-4, 1.352e-4, 3.381e-5, 8.453e-6 for levels 0..8, i.e. 3.1x smaller at
            // the first split (the icosahedron's flat faces are far from the sphere) and 4.0x
            // after; asserted with margin as at least 2.5x per level and < 2.5e-3 at level 4.
            assert!(volume > 0.0 && error > 0.0);
            assert!(
                error < previous_error / 2.5,
                "level {sub}: {error} vs {previous_error}"
            );
            previous_error = error;
            if sub == 4 {
                assert!(
                    error < 2.5e-3,
                    "4 subdivisions: relative volume error {error}"
                );
            }
            if sub <= 3 {
                // No duplicate vertices (shared midpoints): the closest pair is a full edge
                // apart, far above rounding.
                for i in 0..s.vertices.len() {
                    for j in i + 1..s.vertices.len() {
                        assert!(norm(sub_v(s.vertices[i], s.vertices[j])) > 1e-3 * r);
                    }
                }
            }
        }
    }

    fn sub_v(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        sub(a, b)
    }

    #[test]
    fn ellipsoid_is_scaled_icosphere() {
        let radii = [0.5, 0.8, 1.3];
        let exact = 4.0 / 3.0 * PI * radii[0] * radii[1] * radii[2];
        for sub in 0..=4u32 {
            let s = ellipsoid(radii, sub).unwrap();
            let unit = icosphere(1.0, sub).unwrap();
            assert_eq!(s.triangles, unit.triangles);
            let (_, _, _, boundary) = check_mesh(&s);
            assert_eq!(boundary, 0);
            assert_eq!(euler(&s), 2);
            for v in &s.vertices {
                let q = (0..3).map(|k| (v[k] / radii[k]).powi(2)).sum::<f64>();
                assert!((q - 1.0).abs() <= REL);
            }
            // A linear map scales every volume by its determinant, so the relative error is
            // exactly the icosphere's (to rounding).
            let volume = signed_volume(&s);
            let error = (exact - volume) / exact;
            let unit_error = 1.0 - signed_volume(&unit) / (4.0 / 3.0 * PI);
            assert!(volume > 0.0);
            assert!((error - unit_error).abs() <= 1e-12);
            if sub == 4 {
                assert!(error < 2.5e-3);
            }
        }
    }

    #[test]
    fn bowl_topology_and_outward_normals() {
        for (radius, angle, rings, segments) in [
            (1.0, 90.0, 1, 3),
            (0.5, 90.0, 6, 24),
            (2.0, 30.0, 3, 7),
            (1.0, 179.0, 10, 16),
        ] {
            let s = bowl(radius, angle, rings, segments).unwrap();
            assert_eq!(s.vertices.len(), 1 + rings * segments);
            assert_eq!(s.triangles.len(), segments * (2 * rings - 1));
            let (_, _, _, boundary) = check_mesh(&s);
            assert_eq!(boundary, segments, "one rim loop");
            assert_eq!(euler(&s), 1);
            assert_eq!(s.vertices[0], [0.0, 0.0, 0.0]);
            let centre = [0.0, 0.0, radius];
            for v in &s.vertices {
                assert!((norm(sub(*v, centre)) - radius).abs() <= REL * radius);
            }
            // Rim at polar angle `angle`: height R (1 - cos angle).
            let rim_z = radius * (1.0 - angle.to_radians().cos());
            for v in &s.vertices[1 + (rings - 1) * segments..] {
                assert!((v[2] - rim_z).abs() <= REL * radius);
            }
            for &t in &s.triangles {
                let n = area_normal(&s, t);
                for p in corners(&s, t) {
                    assert!(
                        dot(n, sub(p, centre)) > 0.0,
                        "triangle {t:?} faces the centre"
                    );
                }
            }
            // The pole's triangles face down.
            for &t in &s.triangles[..segments] {
                assert!(area_normal(&s, t)[2] < 0.0);
            }
        }
        // Hemisphere: the rim at the centre's height.
        let s = bowl(1.0, 90.0, 4, 8).unwrap();
        let top = s.vertices.iter().map(|v| v[2]).fold(f64::MIN, f64::max);
        assert!((top - 1.0).abs() <= REL);
    }

    #[test]
    fn messages_name_parameter_and_value() {
        assert_eq!(
            sheet(-1.0, 1.0, 2, 2).unwrap_err().to_string(),
            "sheet: width must be finite and > 0, got -1"
        );
        assert_eq!(
            cylinder(1.0, 1.0, 2, 1).unwrap_err().to_string(),
            "cylinder: around must be at least 3, got 2"
        );
        assert_eq!(
            icosphere(1.0, 9).unwrap_err().to_string(),
            "icosphere: subdivisions must be at most 8, got 9"
        );
        assert_eq!(
            bowl(1.0, 180.0, 2, 8).unwrap_err().to_string(),
            "bowl: opening_angle_deg must be in (0, 180), got 180"
        );
        assert_eq!(
            ellipsoid([1.0, f64::NAN, 1.0], 1).unwrap_err().to_string(),
            "ellipsoid: radii[1] must be finite and > 0, got NaN"
        );
        let overflow = sheet(1.0, 1.0, 1 << 16, 1 << 16).unwrap_err().to_string();
        assert!(
            overflow.starts_with("sheet: nx = 65536, ny = 65536 gives too many vertices"),
            "{overflow}"
        );
    }

    #[test]
    fn bad_input_is_refused() {
        let not_positive = |e: GenerateError, name: &str| match e {
            GenerateError::NotPositive { parameter, .. } => assert_eq!(parameter, name),
            other => panic!("expected NotPositive for {name}, got {other:?}"),
        };
        not_positive(sheet(-1.0, 1.0, 1, 1).unwrap_err(), "width");
        not_positive(sheet(1.0, 0.0, 1, 1).unwrap_err(), "height");
        not_positive(sheet(f64::INFINITY, 1.0, 1, 1).unwrap_err(), "width");
        not_positive(cylinder(f64::NAN, 1.0, 3, 1).unwrap_err(), "radius");
        not_positive(cylinder(1.0, -0.0, 3, 1).unwrap_err(), "length");
        not_positive(bent_sheet(1.0, 1.0, 1, 1, 0.0).unwrap_err(), "radius");
        not_positive(icosphere(-2.0, 1).unwrap_err(), "radius");
        not_positive(icosphere(f64::NAN, 1).unwrap_err(), "radius");
        not_positive(ellipsoid([1.0, 1.0, 0.0], 1).unwrap_err(), "radii[2]");
        not_positive(bowl(f64::NEG_INFINITY, 90.0, 1, 3).unwrap_err(), "radius");

        let too_few = |e: GenerateError, name: &str| match e {
            GenerateError::TooFew { parameter, .. } => assert_eq!(parameter, name),
            other => panic!("expected TooFew for {name}, got {other:?}"),
        };
        too_few(sheet(1.0, 1.0, 0, 1).unwrap_err(), "nx");
        too_few(sheet(1.0, 1.0, 1, 0).unwrap_err(), "ny");
        too_few(bent_sheet(1.0, 1.0, 0, 1, 1.0).unwrap_err(), "nx");
        too_few(cylinder(1.0, 1.0, 0, 1).unwrap_err(), "around");
        too_few(cylinder(1.0, 1.0, 3, 0).unwrap_err(), "along");
        too_few(bowl(1.0, 90.0, 0, 3).unwrap_err(), "rings");
        too_few(bowl(1.0, 90.0, 1, 2).unwrap_err(), "segments");

        let out_of_range = |e: GenerateError| {
            assert!(matches!(e, GenerateError::OutOfRange { .. }), "{e:?}");
        };
        out_of_range(bowl(1.0, 0.0, 1, 3).unwrap_err());
        out_of_range(bowl(1.0, 180.0, 1, 3).unwrap_err());
        out_of_range(bowl(1.0, -10.0, 1, 3).unwrap_err());
        out_of_range(bowl(1.0, f64::NAN, 1, 3).unwrap_err());
        out_of_range(bent_sheet(2.0 * PI, 1.0, 4, 1, 1.0).unwrap_err());
        out_of_range(bent_sheet(10.0, 1.0, 4, 1, 1.0).unwrap_err());

        assert!(matches!(
            icosphere(1.0, 9),
            Err(GenerateError::TooMany { .. })
        ));
        assert!(matches!(
            ellipsoid([1.0; 3], u32::MAX),
            Err(GenerateError::TooMany { .. })
        ));

        // Counts past u32 (or usize) are refused without allocating or panicking.
        let overflow =
            |e: GenerateError| assert!(matches!(e, GenerateError::Overflow { .. }), "{e:?}");
        overflow(sheet(1.0, 1.0, usize::MAX, 1).unwrap_err());
        overflow(sheet(1.0, 1.0, usize::MAX / 2, usize::MAX / 2).unwrap_err());
        overflow(sheet(1.0, 1.0, 1 << 16, 1 << 16).unwrap_err());
        overflow(bent_sheet(1.0, 1.0, u32::MAX as usize, 1, 1.0).unwrap_err());
        overflow(cylinder(1.0, 1.0, usize::MAX, 1).unwrap_err());
        overflow(cylinder(1.0, 1.0, 3, usize::MAX).unwrap_err());
        overflow(cylinder(1.0, 1.0, 1 << 16, 1 << 16).unwrap_err());
        overflow(bowl(1.0, 90.0, usize::MAX, 3).unwrap_err());
        overflow(bowl(1.0, 90.0, 1 << 16, 1 << 16).unwrap_err());
        // Just inside: (nx + 1)(ny + 1) = 2^32 - 1 is the largest accepted vertex count.
        // (Not generated: that would be 100 GB.)
        assert!(vertex_count("t", Some(u32::MAX as usize), String::new).is_ok());
        assert!(vertex_count("t", Some(u32::MAX as usize + 1), String::new).is_err());
    }

    #[test]
    fn extreme_sizes_stay_finite() {
        // Grid coordinates are computed as size * (i / n), so even sizes near f64::MAX give
        // finite positions (size * i would overflow before the division).
        let s = sheet(1e308, 1e308, 3, 5).unwrap();
        assert!(s.vertices.iter().flatten().all(|x| x.is_finite()));
        assert_eq!(s.vertices.last(), Some(&[1e308, 1e308, 0.0]));
        let c = cylinder(1e300, 1e308, 3, 4).unwrap();
        assert!(c.vertices.iter().flatten().all(|x| x.is_finite()));
        check_mesh(&sheet(1e-9, 1e-9, 4, 4).unwrap());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        // Random small grids: every open generator stays a consistently oriented manifold
        // with the right Euler characteristic and counts.
        #[test]
        fn open_surfaces_are_manifold(
            nx in 1usize..12, ny in 1usize..12,
            w in 0.01f64..10.0, h in 0.01f64..10.0,
            turn in 0.05f64..6.2,
            angle in 1.0f64..179.0,
        ) {
            let s = sheet(w, h, nx, ny).unwrap();
            prop_assert_eq!(euler(&s), 1);
            let b = bent_sheet(w, h, nx, ny, w / turn).unwrap();
            prop_assert_eq!(&b.triangles, &s.triangles);
            prop_assert_eq!(euler(&b), 1);
            let c = cylinder(w, h, nx + 2, ny).unwrap();
            prop_assert_eq!(euler(&c), 0);
            let bw = bowl(w, angle, ny, nx + 2).unwrap();
            prop_assert_eq!(euler(&bw), 1);
        }
    }
}
