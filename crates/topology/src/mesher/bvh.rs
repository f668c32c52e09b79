//! A bounding volume hierarchy over surface triangles, with the per-node aggregates the fast
//! winding number needs (area-weighted centre, summed area vector, radius) and a closest-point
//! query for snapping.

/// One node: a box over the triangles `start..end` of the permuted order.
#[derive(Debug, Clone)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Area-weighted centre of the node's triangles.
    centre: [f64; 3],
    /// Sum of the triangles' area vectors (half the cross product of two edges).
    area_vector: [f64; 3],
    /// Largest distance from `centre` to a corner of the box.
    radius: f64,
    /// Children, or `u32::MAX` for a leaf.
    left: u32,
    right: u32,
    start: u32,
    end: u32,
}

/// Triangles per leaf.
const LEAF_SIZE: usize = 8;

/// Triangle hierarchy; triangles are stored with their corner positions.
#[derive(Debug, Clone)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    tris: Vec<[[f64; 3]; 3]>,
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn area_vector(t: &[[f64; 3]; 3]) -> [f64; 3] {
    let c = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    [0.5 * c[0], 0.5 * c[1], 0.5 * c[2]]
}

impl TriangleBvh {
    /// Builds the hierarchy over triangles given by corner positions.
    pub fn new(mut tris: Vec<[[f64; 3]; 3]>) -> Self {
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF_SIZE + 1);
        if !tris.is_empty() {
            let n = tris.len();
            build(&mut nodes, &mut tris, 0, n);
        }
        Self { nodes, tris }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Sum of the solid angles (steradians) the triangles subtend at `q`, exact for nodes closer
    /// than `beta` radii and by the node's dipole (first-order) expansion beyond.
    pub fn solid_angle(&self, q: [f64; 3], beta: f64) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let mut total = 0.0;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            let d = sub(n.centre, q);
            let dist = norm(d);
            if dist > beta * n.radius {
                total += dot(d, n.area_vector) / (dist * dist * dist);
            } else if n.left == u32::MAX {
                for t in &self.tris[n.start as usize..n.end as usize] {
                    total += triangle_solid_angle(t, q);
                }
            } else {
                stack.push(n.left);
                stack.push(n.right);
            }
        }
        total
    }

    /// The point on the triangles closest to `q` and its distance, looking no farther than
    /// `max_dist`; `None` when nothing is that close.
    pub fn closest_point(&self, q: [f64; 3], max_dist: f64) -> Option<([f64; 3], f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<([f64; 3], f64)> = None;
        let mut best_d2 = max_dist * max_dist;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i as usize];
            if box_dist2(n, q) > best_d2 {
                continue;
            }
            if n.left == u32::MAX {
                for t in &self.tris[n.start as usize..n.end as usize] {
                    let p = closest_on_triangle(q, t);
                    let d = sub(p, q);
                    let d2 = dot(d, d);
                    if d2 <= best_d2 {
                        best_d2 = d2;
                        best = Some((p, d2.sqrt()));
                    }
                }
            } else {
                stack.push(n.left);
                stack.push(n.right);
            }
        }
        best
    }
}

fn box_dist2(n: &Node, q: [f64; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let e = (n.lo[k] - q[k]).max(0.0).max(q[k] - n.hi[k]);
            e * e
        })
        .sum()
}

/// Solid angle of one triangle at `q` (Van Oosterom and Strackee's formula); positive when `q`
/// is behind the triangle's counter-clockwise normal.
pub fn triangle_solid_angle(t: &[[f64; 3]; 3], q: [f64; 3]) -> f64 {
    let a = sub(t[0], q);
    let b = sub(t[1], q);
    let c = sub(t[2], q);
    let (la, lb, lc) = (norm(a), norm(b), norm(c));
    let det = dot(a, cross(b, c));
    let den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    2.0 * det.atan2(den)
}

/// Closest point to `p` on triangle `t` (region tests on the barycentric coordinates).
pub(crate) fn closest_on_triangle(p: [f64; 3], t: &[[f64; 3]; 3]) -> [f64; 3] {
    let [a, b, c] = *t;
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let lerp = |x: [f64; 3], y: [f64; 3], s: f64| {
        [
            x[0] + s * (y[0] - x[0]),
            x[1] + s * (y[1] - x[1]),
            x[2] + s * (y[2] - x[2]),
        ]
    };
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return lerp(a, b, d1 / (d1 - d3));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return lerp(a, c, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return lerp(b, c, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    [
        a[0] + ab[0] * v + ac[0] * w,
        a[1] + ab[1] * v + ac[1] * w,
        a[2] + ab[2] * v + ac[2] * w,
    ]
}

/// Builds the node over `tris[start..end]`, returning its index.
fn build(nodes: &mut Vec<Node>, tris: &mut [[[f64; 3]; 3]], start: usize, end: usize) -> u32 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut clo = [f64::INFINITY; 3];
    let mut chi = [f64::NEG_INFINITY; 3];
    let mut area_sum = 0.0;
    let mut weighted = [0.0; 3];
    let mut av = [0.0; 3];
    for t in &tris[start..end] {
        let v = area_vector(t);
        let area = norm(v);
        for k in 0..3 {
            for p in t {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            let c = (t[0][k] + t[1][k] + t[2][k]) / 3.0;
            clo[k] = clo[k].min(c);
            chi[k] = chi[k].max(c);
            weighted[k] += area * c;
            av[k] += v[k];
        }
        area_sum += area;
    }
    let centre = if area_sum > 0.0 {
        weighted.map(|w| w / area_sum)
    } else {
        [
            0.5 * (lo[0] + hi[0]),
            0.5 * (lo[1] + hi[1]),
            0.5 * (lo[2] + hi[2]),
        ]
    };
    let mut radius: f64 = 0.0;
    for corner in 0..8 {
        let p = [
            if corner & 1 == 0 { lo[0] } else { hi[0] },
            if corner & 2 == 0 { lo[1] } else { hi[1] },
            if corner & 4 == 0 { lo[2] } else { hi[2] },
        ];
        radius = radius.max(norm(sub(p, centre)));
    }
    let index = nodes.len();
    nodes.push(Node {
        lo,
        hi,
        centre,
        area_vector: av,
        radius,
        left: u32::MAX,
        right: u32::MAX,
        start: start as u32,
        end: end as u32,
    });
    if end - start > LEAF_SIZE {
        let axis = (0..3)
            .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
            .unwrap_or(0);
        let mid = (start + end) / 2;
        let key = |t: &[[f64; 3]; 3]| t[0][axis] + t[1][axis] + t[2][axis];
        tris[start..end].select_nth_unstable_by(mid - start, |a, b| key(a).total_cmp(&key(b)));
        let left = build(nodes, tris, start, mid);
        let right = build(nodes, tris, mid, end);
        nodes[index].left = left;
        nodes[index].right = right;
    }
    index as u32
}
