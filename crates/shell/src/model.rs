//! The discrete shell's strains, energy and forces (Gingold et al. 2004, docs/model.md section 8).
//!
//! Per triangle, both strains are constant and written in the rest triangle's plane:
//!
//! - membrane: the Green strain `E_m` of the affine map from the rest triangle to the current
//!   one, linear in the changes of the squared edge lengths `s_k = l~_k^2 - l_k^2`
//!   (`v_k^T E_m v_k = s_k / 2` for each rest edge vector `v_k`);
//! - bending: `E_c = sum_k dphi_k / (2 A l_k) t_k (x) t_k`, with `t_k` the rest edge `k` turned a
//!   quarter in the plane, `A` the rest area and `dphi_k = phi(theta~_k) - phi(theta_k)` the
//!   change of `phi(theta) = 2 tan(theta / 2)` of the dihedral angle at edge `k`; a boundary edge
//!   has no dihedral angle and adds nothing.
//!
//! The energy of a triangle is Koiter's with both strains, its area `A` times
//! `c_m ((1 - nu) tr E_m^2 + nu (tr E_m)^2) + c_b ((1 - nu) tr E_c^2 + nu (tr E_c)^2)` with
//! `c_m = Y h / (2 (1 - nu^2))` and `c_b = Y h^3 / (24 (1 - nu^2))`. Since the strains are
//! linear in `s` and `dphi` with coefficients of the rest state, each part is a quadratic form
//! whose 3x3 matrix is computed once per triangle. Forces are the exact negative gradient:
//! the chain rule through `s_k` (an edge's two ends) and `theta_k` (the edge's four-vertex
//! stencil).
//!
//! A force evaluation runs three parallel passes, each writing only its own entries: per edge
//! (squared length change, dihedral angle and its gradient), per triangle (the energy's
//! derivatives by `s` and `dphi`), per edge again (summing its triangles' derivatives) and per
//! vertex (gathering over the edges whose stencil holds it). No locks or atomics, the same sums
//! for any thread count, no allocation once built.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use rayon::prelude::*;

use crate::error::ShellError;
use crate::material::ShellMaterial;
use crate::mesh::{Role, ShellMesh, NONE};
use crate::plastic::{combine, return_map, yield_measure, PlasticState, ShellYield};
use perifrac_physics::math::{add, axpy, cross, dot, norm, scale, sub, Vec3};

/// Items per parallel task at least: a small mesh runs its passes on one thread, where waking
/// others would cost more than the work (the clamped-strip example, up to 369 vertices, took
/// 42 s with no minimum, 25 s of it in the kernel, and 21 s with it).
const MIN_PER_TASK: usize = 512;

/// Rest dihedral angles within this of +-pi (rad) are refused: `phi` is infinite there.
const FOLD_MARGIN: f64 = 1e-3;

/// What a triangle's energy needs of its rest state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FaceRest {
    /// Rest area (m^2).
    pub area: f64,
    /// `tr(M_k M_l)`, symmetric, as `[00, 11, 22, 01, 02, 12]`, with `E_m = sum_k s_k M_k`
    /// (1/m^4).
    mm: [f64; 6],
    /// `tr M_k` (1/m^2).
    tm: [f64; 3],
    /// `tr(N_k N_l)` with `E_c = sum_k dphi_k N_k` (1/m^2).
    mb: [f64; 6],
    /// `tr N_k` (1/m).
    tb: [f64; 3],
    /// `M_k` as `[xx, yy, xy]` (1/m^2): `E_m = sum_k s_k M_k`.
    pub m: [[f64; 3]; 3],
    /// `N_k` as `[xx, yy, xy]` (1/m): `E_c = sum_k dphi_k N_k`.
    pub n: [[f64; 3]; 3],
}

/// The strains of one triangle, in its rest plane's frame `(u, w)` with `u` along rest edge
/// `v0 -> v1`: symmetric 2x2 tensors as `[xx, yy, xy]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceStrain {
    /// Membrane (Green) strain (dimensionless).
    pub membrane: [f64; 3],
    /// Bending strain, the change of the shape operator (1/m).
    pub bending: [f64; 3],
}

/// Per-edge results of a force evaluation.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct EdgeWork {
    /// Squared length change `s` (m^2).
    pub s: f64,
    /// `phi(theta) - phi(theta_rest)` (dimensionless); 0 on a boundary.
    pub dphi: f64,
    /// `d phi / d theta`.
    slope: f64,
    /// Gradient of `theta` by the stencil's vertices `[v0, v1, opposite0, opposite1]` (1/m).
    grad: [Vec3; 4],
    /// `dW / ds` summed over the edge's triangles (J/m^2).
    g: f64,
    /// `dW / dtheta` summed over the edge's triangles (J).
    b: f64,
}

/// Per-triangle results of a force evaluation.
#[derive(Debug, Clone, Copy, Default)]
struct FaceWork {
    /// `dW / ds_k` (J/m^2).
    ds: [f64; 3],
    /// `dW / d dphi_k` (J).
    dphi: [f64; 3],
    /// Energy (J).
    energy: f64,
    /// Whether the triangle yielded in the last evaluation that updated plasticity.
    yielded: bool,
}

/// An elastic shell: the mesh, its material, the rest state's per-triangle constants and the
/// buffers of the force passes.
#[derive(Debug, Clone)]
pub struct ShellModel {
    pub(crate) mesh: ShellMesh,
    pub(crate) material: ShellMaterial,
    pub(crate) faces: Vec<FaceRest>,
    pub(crate) rest_length2: Vec<f64>,
    rest_phi: Vec<f64>,
    rest_theta: Vec<f64>,
    masses: Vec<f64>,
    pub(crate) edge_work: Vec<EdgeWork>,
    face_work: Vec<FaceWork>,
    pub(crate) plastic: Option<PlasticState>,
    pub(crate) fracture: Option<crate::fracture::FractureState>,
}

/// Plastic offsets per triangle: squared edge-length changes (m^2) and `phi` changes.
pub(crate) type Offsets = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// Everything of the rest state that the mesh and material fix.
struct RestData {
    faces: Vec<FaceRest>,
    length2: Vec<f64>,
    phi: Vec<f64>,
    theta: Vec<f64>,
    masses: Vec<f64>,
}

impl RestData {
    fn of(mesh: &ShellMesh, material: &ShellMaterial) -> Result<RestData, ShellError> {
        let x = mesh.vertices();
        let mut theta = vec![0.0; mesh.edges().len()];
        let mut phis = vec![0.0; mesh.edges().len()];
        let mut length2 = vec![0.0; mesh.edges().len()];
        for (k, e) in mesh.edges().iter().enumerate() {
            let d = sub(x[e.v[1] as usize], x[e.v[0] as usize]);
            length2[k] = dot(d, d);
            if e.is_boundary() {
                continue;
            }
            let (sin, cos, _) = dihedral_terms(
                x[e.v[0] as usize],
                x[e.v[1] as usize],
                x[e.opposite[0] as usize],
                x[e.opposite[1] as usize],
            );
            let t = sin.atan2(cos);
            if std::f64::consts::PI - t.abs() < FOLD_MARGIN {
                return Err(ShellError::Folded {
                    a: e.v[0],
                    b: e.v[1],
                    angle_deg: t.to_degrees(),
                });
            }
            theta[k] = t;
            // As the force pass forms it, so a shell at rest has exactly zero bending strain.
            phis[k] = phi_of_half_tan(half_tan(sin, cos)).0;
        }
        let areal = material.areal_density();
        let mut masses = vec![0.0; x.len()];
        let faces = mesh
            .triangles()
            .iter()
            .map(|t| {
                let (v, area) = plane_edges(t.map(|i| x[i as usize]));
                for &i in t {
                    masses[i as usize] += areal * area / 3.0;
                }
                FaceRest::new(&v, area)
            })
            .collect();
        Ok(RestData {
            faces,
            length2,
            phi: phis,
            theta,
            masses,
        })
    }
}

impl FaceRest {
    fn new(v: &[[f64; 2]; 3], area: f64) -> FaceRest {
        let m = membrane_basis(v);
        let n = bending_basis(v, area);
        let sym = |b: &[[f64; 3]; 3]| {
            [
                tr_prod(b[0], b[0]),
                tr_prod(b[1], b[1]),
                tr_prod(b[2], b[2]),
                tr_prod(b[0], b[1]),
                tr_prod(b[0], b[2]),
                tr_prod(b[1], b[2]),
            ]
        };
        FaceRest {
            area,
            mm: sym(&m),
            tm: m.map(|a| a[0] + a[1]),
            mb: sym(&n),
            tb: n.map(|a| a[0] + a[1]),
            m,
            n,
        }
    }
}

/// `phi(theta) = 2 tan(theta / 2)` and its derivative `1 + tan^2(theta / 2)`.
#[inline]
pub fn phi(theta: f64) -> (f64, f64) {
    phi_of_half_tan((0.5 * theta).tan())
}

/// `phi = 2 t` and its derivative by the angle, `1 + t^2`, from `t = tan(theta / 2)`.
#[inline]
pub fn phi_of_half_tan(t: f64) -> (f64, f64) {
    (2.0 * t, 1.0 + t * t)
}

/// A half-angle tangent standing in for a fold onto itself (`theta = +-pi`, where
/// `tan(theta / 2)` is infinite): about `tan(pi / 2)` in double precision, as the tangent of the
/// angle gave, so a folded edge gives a huge but finite bending force, not an infinite one.
const FOLDED_HALF_TAN: f64 = 1.6e16;

/// `tan(theta / 2)` of the signed dihedral angle `theta` of [`dihedral`] (dimensionless), and the
/// angle's gradient by `[a, b, c0, c1]` (1/m), without forming the angle: from the two normals'
/// sine and cosine terms `s` and `c` with `r = sqrt(s^2 + c^2)`, `tan(theta / 2) = s / (r + c)`
/// where `c >= 0` and `(r - c) / s` where `c < 0` (each free of cancellation on its side). It
/// spares the force pass an `atan2` and a `tan` per edge, which took about a fifth of the
/// bulb scene's stepping.
pub fn dihedral_half_tan(a: Vec3, b: Vec3, c0: Vec3, c1: Vec3) -> (f64, [Vec3; 4]) {
    let (sin, cos, grad) = dihedral_terms(a, b, c0, c1);
    (half_tan(sin, cos), grad)
}

/// `tan(theta / 2)` from the angle's sine and cosine terms of [`dihedral_terms`], each scaled
/// alike (see [`dihedral_half_tan`]).
#[inline]
fn half_tan(sin: f64, cos: f64) -> f64 {
    let r = (sin * sin + cos * cos).sqrt();
    if cos >= 0.0 {
        if r > 0.0 {
            sin / (r + cos)
        } else {
            0.0
        }
    } else if sin != 0.0 {
        (r - cos) / sin
    } else {
        FOLDED_HALF_TAN.copysign(sin)
    }
}

/// The signed dihedral angle (rad) at edge `a -> b` between the triangle `(a, b, c0)` and the
/// triangle `(b, a, c1)`: 0 when flat, positive where the surface turns away from its normal
/// (a ridge seen from the normal's side), in (-pi, pi]; and its gradient by `[a, b, c0, c1]`
/// (1/m).
pub fn dihedral(a: Vec3, b: Vec3, c0: Vec3, c1: Vec3) -> (f64, [Vec3; 4]) {
    let (sin, cos, grad) = dihedral_terms(a, b, c0, c1);
    (sin.atan2(cos), grad)
}

/// The dihedral angle's sine and cosine, each times the two normals' lengths (m^4), and its
/// gradient (1/m).
#[inline]
fn dihedral_terms(a: Vec3, b: Vec3, c0: Vec3, c1: Vec3) -> (f64, f64, [Vec3; 4]) {
    let e = sub(b, a);
    let le2 = dot(e, e);
    let le = le2.sqrt();
    let n0 = cross(e, sub(c0, a));
    let n1 = cross(sub(c1, a), e);
    let (q0, q1) = (dot(n0, n0), dot(n1, n1));
    let sin = dot(cross(n0, n1), e) / le;
    let cos = dot(n0, n1);
    // Lifting an opposite vertex along its triangle's normal turns the surface towards that
    // normal: d theta / d c = -|e| n / |n|^2 (minus the unit normal over the triangle's height).
    let g0 = scale(n0, -le / q0);
    let g1 = scale(n1, -le / q1);
    // The edge's ends share the rest by where each opposite vertex projects onto the edge, so
    // that the four sum to zero (translation) and the angle is unchanged by rotations.
    let t0 = dot(sub(c0, a), e) / le2;
    let t1 = dot(sub(c1, a), e) / le2;
    let ga = add(scale(g0, t0 - 1.0), scale(g1, t1 - 1.0));
    let gb = add(scale(g0, -t0), scale(g1, -t1));
    (sin, cos, [ga, gb, g0, g1])
}

/// The constants of every triangle's energy.
struct FaceConsts {
    /// `Y h / (2 (1 - nu^2))` (N/m).
    cm: f64,
    /// `Y h^3 / (24 (1 - nu^2))` (N m).
    cb: f64,
    /// Poisson's ratio.
    nu: f64,
    /// Thickness (m).
    h: f64,
}

/// A triangle's energy and its derivatives by its elastic `s` and `dphi` into `w`.
#[inline]
fn face_energy(r: &FaceRest, s: [f64; 3], p: [f64; 3], c: &FaceConsts, w: &mut FaceWork) {
    let nu = c.nu;
    let (s2, qs) = quad(&r.mm, s);
    let ts = dot(r.tm, s);
    let (p2, qp) = quad(&r.mb, p);
    let tp = dot(r.tb, p);
    let (am, ab) = (r.area * c.cm, r.area * c.cb);
    w.energy = am * ((1.0 - nu) * s2 + nu * ts * ts) + ab * ((1.0 - nu) * p2 + nu * tp * tp);
    for k in 0..3 {
        w.ds[k] = 2.0 * am * ((1.0 - nu) * qs[k] + nu * ts * r.tm[k]);
        w.dphi[k] = 2.0 * ab * ((1.0 - nu) * qp[k] + nu * tp * r.tb[k]);
    }
}

/// The symmetric 2x2 `[xx, yy, xy]` products `tr(A B)`.
#[inline]
fn tr_prod(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + 2.0 * a[2] * b[2]
}

/// `x^T Q x` for a symmetric 3x3 `Q` stored as `[00, 11, 22, 01, 02, 12]`, and `Q x`.
#[inline]
fn quad(q: &[f64; 6], x: [f64; 3]) -> (f64, [f64; 3]) {
    let qx = [
        q[0] * x[0] + q[3] * x[1] + q[4] * x[2],
        q[3] * x[0] + q[1] * x[1] + q[5] * x[2],
        q[4] * x[0] + q[5] * x[1] + q[2] * x[2],
    ];
    (x[0] * qx[0] + x[1] * qx[1] + x[2] * qx[2], qx)
}

/// The rest triangle's edges in its plane: edge `k` runs from vertex `k + 1` to `k + 2`.
fn plane_edges(p: [Vec3; 3]) -> ([[f64; 2]; 3], f64) {
    let e01 = sub(p[1], p[0]);
    let n = cross(e01, sub(p[2], p[0]));
    let area = 0.5 * norm(n);
    let u = scale(e01, 1.0 / norm(e01));
    let w = cross(scale(n, 1.0 / norm(n)), u);
    let mut v = [[0.0; 2]; 3];
    for (k, vk) in v.iter_mut().enumerate() {
        let d = sub(p[(k + 2) % 3], p[(k + 1) % 3]);
        *vk = [dot(d, u), dot(d, w)];
    }
    (v, area)
}

/// The tensors `M_k` with `E_m = sum_k s_k M_k`, as `[xx, yy, xy]`: the dual basis of the
/// edge functionals `E -> v_k^T E v_k`, halved (Green strain).
fn membrane_basis(v: &[[f64; 2]; 3]) -> [[f64; 3]; 3] {
    // Row k maps [xx, yy, xy] to v_k^T E v_k.
    let r = v.map(|[x, y]| [x * x, y * y, 2.0 * x * y]);
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    // Inverse by cofactors; column k of the inverse, halved, is M_k.
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        r[i1][j1] * r[i2][j2] - r[i1][j2] * r[i2][j1]
    };
    let mut m = [[0.0; 3]; 3];
    for (k, mk) in m.iter_mut().enumerate() {
        for (row, x) in mk.iter_mut().enumerate() {
            // inverse[row][k] = cofactor(k, row) / det
            *x = 0.5 * c(k, row) / det;
        }
    }
    m
}

/// The tensors `N_k = t_k (x) t_k / (2 A l_k)`, as `[xx, yy, xy]` (1/m).
fn bending_basis(v: &[[f64; 2]; 3], area: f64) -> [[f64; 3]; 3] {
    v.map(|[x, y]| {
        let l = (x * x + y * y).sqrt();
        // t = (-y, x), |t| = l.
        let c = 1.0 / (2.0 * area * l);
        [c * y * y, c * x * x, -c * x * y]
    })
}

impl ShellModel {
    /// The shell at rest in the mesh's vertex positions. Refuses a mesh with two triangles
    /// folded onto each other (rest dihedral angle within 1e-3 rad of 180 degrees).
    pub fn new(mesh: ShellMesh, material: ShellMaterial) -> Result<ShellModel, ShellError> {
        let rest = RestData::of(&mesh, &material)?;
        let ne = mesh.edges().len();
        let nf = mesh.triangles().len();
        Ok(ShellModel {
            mesh,
            material,
            faces: rest.faces,
            rest_length2: rest.length2,
            rest_phi: rest.phi,
            rest_theta: rest.theta,
            masses: rest.masses,
            edge_work: vec![EdgeWork::default(); ne],
            face_work: vec![FaceWork::default(); nf],
            plastic: None,
            fracture: None,
        })
    }

    /// Replaces the mesh (after fracture changed it) and recomputes everything of the rest
    /// state; the plastic offsets, per triangle, are the caller's.
    pub(crate) fn rebuild(
        &mut self,
        mesh: ShellMesh,
        offsets: Option<Offsets>,
    ) -> Result<(), ShellError> {
        let rest = RestData::of(&mesh, &self.material)?;
        self.edge_work = vec![EdgeWork::default(); mesh.edges().len()];
        self.face_work = vec![FaceWork::default(); mesh.triangles().len()];
        self.faces = rest.faces;
        self.rest_length2 = rest.length2;
        self.rest_phi = rest.phi;
        self.rest_theta = rest.theta;
        self.masses = rest.masses;
        self.mesh = mesh;
        if let (Some(p), Some((s, phi))) = (&mut self.plastic, offsets) {
            p.s = s;
            p.phi = phi;
        }
        Ok(())
    }

    /// Writes for a checkpoint what fracture and plasticity change: the rest mesh, the
    /// plastic offsets, the crack flags and where each triangle was split from. The rest of
    /// the model is rebuilt from them ([`ShellModel::read_checkpoint`]).
    pub fn write_checkpoint(&self, w: &mut Writer) {
        w.tag("shell model");
        w.array(self.mesh.vertices());
        w.array(self.mesh.triangles());
        w.bool(self.plastic.is_some());
        if let Some(p) = &self.plastic {
            w.array(&p.s);
            w.array(&p.phi);
        }
        w.bool(self.fracture.is_some());
        if let Some(f) = &self.fracture {
            let crack: Vec<[u8; 3]> = f.crack.iter().map(|c| c.map(u8::from)).collect();
            w.array(&crack);
            w.array(&f.split_from);
        }
    }

    /// Reads what [`ShellModel::write_checkpoint`] wrote into a model built by the same
    /// settings (a checkpoint of a plastic or breaking shell does not fit one that is not).
    pub fn read_checkpoint(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        let invalid = |message: String| CheckpointError::Invalid {
            what: "shell model".into(),
            message,
        };
        r.tag("shell model")?;
        let (mut vertices, mut triangles) = (Vec::<Vec3>::new(), Vec::<[u32; 3]>::new());
        r.array_vec("shell vertices", &mut vertices)?;
        r.array_vec("shell triangles", &mut triangles)?;
        let nt = triangles.len();
        let plastic = r.bool("shell plastic state")?;
        if plastic != self.plastic.is_some() {
            return Err(invalid(
                "plastic state where the scene has none, or none where it has".into(),
            ));
        }
        let offsets = if plastic {
            let (mut ps, mut pphi) = (Vec::new(), Vec::new());
            r.array_vec("shell plastic strains", &mut ps)?;
            r.array_vec("shell plastic bending", &mut pphi)?;
            if ps.len() != nt || pphi.len() != nt {
                return Err(invalid(format!(
                    "{} plastic offsets for {nt} triangles",
                    ps.len()
                )));
            }
            Some((ps, pphi))
        } else {
            None
        };
        let fracture = r.bool("shell fracture state")?;
        if fracture != self.fracture.is_some() {
            return Err(invalid(
                "fracture state where the scene has none, or none where it has".into(),
            ));
        }
        let cracks = if fracture {
            let (mut crack, mut split_from) = (Vec::<[u8; 3]>::new(), Vec::<u32>::new());
            r.array_vec("shell crack flags", &mut crack)?;
            r.array_vec("shell split origins", &mut split_from)?;
            if crack.len() != nt || split_from.len() != nt {
                return Err(invalid(format!(
                    "{} crack flags for {nt} triangles",
                    crack.len()
                )));
            }
            // The setup's triangles are their own origin; a split appends, so every other
            // triangle's origin is a lower index ([`ShellModel::part_of`] walks down them).
            let original = self.split_from().len();
            let bad = split_from.iter().enumerate().find(|&(t, &f)| {
                let f = f as usize;
                if t < original {
                    f != t
                } else {
                    f >= t
                }
            });
            if let Some((t, f)) = bad {
                return Err(invalid(format!("triangle {t} split from {f}")));
            }
            Some((crack, split_from))
        } else {
            None
        };
        let mesh = ShellMesh::new(vertices, triangles).map_err(|e| invalid(e.to_string()))?;
        self.rebuild(mesh, offsets)
            .map_err(|e| invalid(e.to_string()))?;
        if let (Some(fs), Some((crack, split_from))) = (&mut self.fracture, cracks) {
            fs.crack = crack.iter().map(|c| c.map(|b| b != 0)).collect();
            fs.split_from = split_from;
        }
        Ok(())
    }

    /// The same shell yielding as `params` says: [`ShellModel::forces`] then return-maps every
    /// triangle before its forces. Without this the model is elastic and keeps no plastic
    /// state.
    pub fn with_yield(mut self, params: ShellYield) -> ShellModel {
        match &mut self.plastic {
            Some(p) => p.params = Some(params),
            None => self.plastic = Some(PlasticState::new(Some(params), self.faces.len())),
        }
        self
    }

    /// The yield parameters, when the shell yields.
    pub fn yield_params(&self) -> Option<ShellYield> {
        self.plastic.as_ref().and_then(|p| p.params)
    }

    /// A force (N) below which the search does not judge growth: the membrane force of a
    /// strain of 1e-6 across the mean edge, `1e-6 Y h l_mean`. Smaller forces are round-off
    /// in a shell falling freely (1e-11 to 2e-9 N on the benchmark's egg, which discarded 655
    /// trials in its first 20 steps when judged by them).
    pub fn force_scale(&self) -> f64 {
        let n = self.rest_length2.len().max(1) as f64;
        let mean = self.rest_length2.iter().map(|l| l.sqrt()).sum::<f64>() / n;
        1e-6 * self.material.young * self.material.thickness * mean
    }

    /// Copies the plastic offsets into `s`, `phi` (left empty for a shell without them).
    pub(crate) fn save_plastic(&self, s: &mut Vec<[f64; 3]>, phi: &mut Vec<[f64; 3]>) {
        match &self.plastic {
            Some(p) => {
                s.clone_from(&p.s);
                phi.clone_from(&p.phi);
            }
            None => {
                s.clear();
                phi.clear();
            }
        }
    }

    /// Puts back offsets saved by [`ShellModel::save_plastic`].
    pub(crate) fn restore_plastic(&mut self, s: &[[f64; 3]], phi: &[[f64; 3]]) {
        if let Some(p) = &mut self.plastic {
            p.s.copy_from_slice(s);
            p.phi.copy_from_slice(phi);
        }
    }

    /// Triangles that yielded in the last [`ShellModel::forces`].
    pub fn yielded(&self) -> usize {
        self.face_work.iter().filter(|w| w.yielded).count()
    }

    /// Each triangle's plastic strain, membrane and bending, in its rest plane's frame as
    /// [`ShellModel::strains`] gives the total; all zero for an elastic shell.
    pub fn plastic_strains(&self) -> Vec<FaceStrain> {
        self.faces
            .iter()
            .enumerate()
            .map(|(f, r)| match &self.plastic {
                Some(p) => FaceStrain {
                    membrane: combine(&r.m, p.s[f]),
                    bending: combine(&r.n, p.phi[f]),
                },
                None => FaceStrain {
                    membrane: [0.0; 3],
                    bending: [0.0; 3],
                },
            })
            .collect()
    }

    /// The thickness-averaged yield measure `F` of each triangle at positions `x` (m) with the
    /// current plastic state (see [`crate::plastic`]); a triangle yields where it passes the
    /// yield strain. `None` for an elastic shell.
    pub fn yield_measures(&mut self, x: &[Vec3]) -> Result<Option<Vec<f64>>, ShellError> {
        self.check_len("shell positions", x.len())?;
        let Some(params) = self.yield_params() else {
            return Ok(None);
        };
        self.edge_pass(x);
        let (fe, ew) = (self.mesh.face_edges(), &self.edge_work);
        let p = self.plastic.as_ref().map(|p| (&p.s, &p.phi));
        let Some((ps, pphi)) = p else {
            return Ok(None);
        };
        let (nu, h) = (self.material.poisson, self.material.thickness);
        Ok(Some(
            self.faces
                .iter()
                .enumerate()
                .map(|(f, r)| {
                    let e = fe[f];
                    let s = e.map(|k| ew[k as usize].s);
                    let d = e.map(|k| ew[k as usize].dphi);
                    yield_measure(
                        combine(&r.m, s),
                        combine(&r.n, d),
                        combine(&r.m, ps[f]),
                        combine(&r.n, pphi[f]),
                        nu,
                        params.hardening,
                        h,
                    )
                    .0
                })
                .collect(),
        ))
    }

    /// The mesh.
    pub fn mesh(&self) -> &ShellMesh {
        &self.mesh
    }

    /// The material.
    pub fn material(&self) -> &ShellMaterial {
        &self.material
    }

    /// Lumped vertex masses (kg): a third of each triangle's `rho h A` to each of its vertices.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// Rest dihedral angle of each edge (rad; 0 on boundary edges).
    pub fn rest_dihedral(&self) -> &[f64] {
        &self.rest_theta
    }

    /// Rest area of each triangle (m^2).
    pub fn rest_areas(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        self.faces.iter().map(|f| f.area)
    }

    /// Refuses `n` positions unless there is one per vertex.
    pub fn check_positions(&self, n: usize) -> Result<(), ShellError> {
        self.check_len("shell positions", n)
    }

    fn check_len(&self, what: &'static str, got: usize) -> Result<(), ShellError> {
        let expected = self.mesh.num_vertices();
        if got == expected {
            Ok(())
        } else {
            Err(ShellError::LengthMismatch {
                what,
                expected,
                got,
            })
        }
    }

    /// Pass 1: per edge, the squared length change and the dihedral angle's change, slope and
    /// gradient at positions `x`.
    pub(crate) fn edge_pass(&mut self, x: &[Vec3]) {
        let edges = self.mesh.edges();
        let (l2, rest_phi) = (&self.rest_length2, &self.rest_phi);
        self.edge_work
            .par_iter_mut()
            .with_min_len(MIN_PER_TASK)
            .enumerate()
            .for_each(|(k, w)| {
                let e = edges[k];
                let (a, b) = (x[e.v[0] as usize], x[e.v[1] as usize]);
                let d = sub(b, a);
                w.s = dot(d, d) - l2[k];
                if e.is_boundary() {
                    w.dphi = 0.0;
                    w.slope = 0.0;
                    w.grad = [[0.0; 3]; 4];
                    return;
                }
                let (t, grad) =
                    dihedral_half_tan(a, b, x[e.opposite[0] as usize], x[e.opposite[1] as usize]);
                let (p, slope) = phi_of_half_tan(t);
                w.dphi = p - rest_phi[k];
                w.slope = slope;
                w.grad = grad;
            });
    }

    /// Pass 2: per triangle, the energy and its derivatives by `s` and `dphi`; with `update`
    /// and plasticity, each triangle is return-mapped first.
    fn face_pass(&mut self, update: bool) {
        let fe = self.mesh.face_edges();
        let consts = FaceConsts {
            cm: self.material.membrane_factor(),
            cb: self.material.bending_factor(),
            nu: self.material.poisson,
            h: self.material.thickness,
        };
        let (faces, ew) = (&self.faces, &self.edge_work);
        let totals = |f: usize| {
            let e = fe[f];
            (e.map(|k| ew[k as usize].s), e.map(|k| ew[k as usize].dphi))
        };
        match &mut self.plastic {
            None => self
                .face_work
                .par_iter_mut()
                .with_min_len(MIN_PER_TASK)
                .enumerate()
                .for_each(|(f, w)| {
                    let (s, p) = totals(f);
                    face_energy(&faces[f], s, p, &consts, w);
                }),
            Some(pl) => {
                let params = pl.params;
                let update = update && params.is_some();
                self.face_work
                    .par_iter_mut()
                    .with_min_len(MIN_PER_TASK)
                    .zip(pl.s.par_iter_mut().zip(pl.phi.par_iter_mut()))
                    .enumerate()
                    .for_each(|(f, (w, (ps, pphi)))| {
                        let r = &faces[f];
                        let (s, p) = totals(f);
                        if let (true, Some(params)) = (update, &params) {
                            w.yielded =
                                return_map(s, p, &r.m, &r.n, ps, pphi, params, consts.nu, consts.h);
                        }
                        let se = [s[0] - ps[0], s[1] - ps[1], s[2] - ps[2]];
                        let pe = [p[0] - pphi[0], p[1] - pphi[1], p[2] - pphi[2]];
                        face_energy(r, se, pe, &consts, w);
                    });
            }
        }
    }

    /// Pass 3: per edge, the derivatives summed over its triangles.
    fn edge_sum_pass(&mut self) {
        let (edges, fe, fw) = (self.mesh.edges(), self.mesh.face_edges(), &self.face_work);
        self.edge_work
            .par_iter_mut()
            .with_min_len(MIN_PER_TASK)
            .enumerate()
            .for_each(|(k, w)| {
                let e = edges[k];
                let (mut g, mut b) = (0.0, 0.0);
                for &f in &e.faces {
                    if f == NONE {
                        continue;
                    }
                    let f = f as usize;
                    let local = fe[f].iter().position(|&j| j as usize == k).unwrap_or(0);
                    g += fw[f].ds[local];
                    b += fw[f].dphi[local];
                }
                w.g = g;
                w.b = b * w.slope;
            });
    }

    /// The elastic energy (J) at positions `x` (m), and the forces (N) into `forces`
    /// (overwritten): minus its gradient.
    pub fn forces(&mut self, x: &[Vec3], forces: &mut [Vec3]) -> Result<f64, ShellError> {
        self.check_len("shell positions", x.len())?;
        self.check_len("shell forces", forces.len())?;
        self.edge_pass(x);
        self.face_pass(true);
        self.edge_sum_pass();
        self.gather(x, forces);
        Ok(self.face_work.iter().map(|w| w.energy).sum())
    }

    /// Pass 4: per vertex, minus the gradient gathered over the edges whose stencil holds it.
    fn gather(&self, x: &[Vec3], forces: &mut [Vec3]) {
        let (mesh, ew) = (&self.mesh, &self.edge_work);
        forces
            .par_iter_mut()
            .with_min_len(MIN_PER_TASK)
            .enumerate()
            .for_each(|(v, f)| {
                let mut sum = [0.0; 3];
                for &(k, role) in mesh.stencil(v) {
                    let e = mesh.edges()[k as usize];
                    let w = &ew[k as usize];
                    match role {
                        Role::Start => {
                            let d = sub(x[e.v[0] as usize], x[e.v[1] as usize]);
                            sum = axpy(sum, 2.0 * w.g, d);
                        }
                        Role::End => {
                            let d = sub(x[e.v[1] as usize], x[e.v[0] as usize]);
                            sum = axpy(sum, 2.0 * w.g, d);
                        }
                        _ => {}
                    }
                    sum = axpy(sum, w.b, w.grad[role as usize]);
                }
                *f = scale(sum, -1.0);
            });
    }

    /// [`ShellModel::forces`] without the plastic update: the forces (N) at `x` (m) with the
    /// plastic state as it is, and the energy (J). For probes (the stable-step estimate) that
    /// must not change the state.
    pub fn frozen_forces(&mut self, x: &[Vec3], forces: &mut [Vec3]) -> Result<f64, ShellError> {
        self.check_len("shell positions", x.len())?;
        self.check_len("shell forces", forces.len())?;
        self.edge_pass(x);
        self.face_pass(false);
        self.edge_sum_pass();
        self.gather(x, forces);
        Ok(self.face_work.iter().map(|w| w.energy).sum())
    }

    /// A positive semi-definite stand-in for the energy's Hessian at `x` (m), for an implicit
    /// step's preconditioner: each 3x3 block `B` (N/m) of vertex pair `(i, j)`, the derivative
    /// of the force on `i` by `-x_j`, is handed to `add(i, j, B)` (both orders of a pair, and
    /// `i == j`, each once per term; a pair may come many times: sum them).
    ///
    /// Membrane: the Gauss-Newton term `J^T Q J` per triangle, `J` the squared edge lengths'
    /// Jacobian and `Q` the energy's 3x3 matrix in them (exact; only `s`'s own curvature, which
    /// carries the stress, is left out). Bending: per interior edge of a triangle, `w_k phi'^2
    /// grad(theta) grad(theta)^T` with `w_k` the absolute row sum of the triangle's bending
    /// matrix over its interior edges, which majorises the Gauss-Newton term.
    pub(crate) fn gauss_newton(
        &mut self,
        x: &[Vec3],
        mut add: impl FnMut(u32, u32, [[f64; 3]; 3]),
    ) -> Result<(), ShellError> {
        self.check_len("shell positions", x.len())?;
        self.edge_pass(x);
        let nu = self.material.poisson;
        let (cm, cb) = (
            self.material.membrane_factor(),
            self.material.bending_factor(),
        );
        let (mesh, ew) = (&self.mesh, &self.edge_work);
        let hess = |q: &[f64; 6], t: &[f64; 3], c: f64| {
            let s = |a: usize, b: usize| {
                const IDX: [[usize; 3]; 3] = [[0, 3, 4], [3, 1, 5], [4, 5, 2]];
                2.0 * c * ((1.0 - nu) * q[IDX[a][b]] + nu * t[a] * t[b])
            };
            [
                [s(0, 0), s(0, 1), s(0, 2)],
                [s(1, 0), s(1, 1), s(1, 2)],
                [s(2, 0), s(2, 1), s(2, 2)],
            ]
        };
        for (f, (t, fe)) in mesh.triangles().iter().zip(mesh.face_edges()).enumerate() {
            let r = &self.faces[f];
            // Membrane: the gradient of s_k is -2 d_k at t[k + 1] and +2 d_k at t[k + 2].
            let qm = hess(&r.mm, &r.tm, r.area * cm);
            let d = [0, 1, 2].map(|k| sub(x[t[(k + 2) % 3] as usize], x[t[(k + 1) % 3] as usize]));
            let jac = |k: usize, v: usize| -> Vec3 {
                if v == (k + 1) % 3 {
                    scale(d[k], -2.0)
                } else if v == (k + 2) % 3 {
                    scale(d[k], 2.0)
                } else {
                    [0.0; 3]
                }
            };
            for a in 0..3 {
                for b in 0..3 {
                    let mut block = [[0.0; 3]; 3];
                    for (k, qk) in qm.iter().enumerate() {
                        let ja = jac(k, a);
                        for (l, &q) in qk.iter().enumerate() {
                            let jb = jac(l, b);
                            for (row, ra) in block.iter_mut().enumerate() {
                                for (col, c) in ra.iter_mut().enumerate() {
                                    *c += q * ja[row] * jb[col];
                                }
                            }
                        }
                    }
                    add(t[a], t[b], block);
                }
            }
            // Bending, majorised per interior edge.
            let qb = hess(&r.mb, &r.tb, r.area * cb);
            let interior = fe.map(|k| !mesh.edges()[k as usize].is_boundary());
            for (k, &e) in fe.iter().enumerate() {
                if !interior[k] {
                    continue;
                }
                let w: f64 = (0..3)
                    .filter(|&l| interior[l])
                    .map(|l| qb[k][l].abs())
                    .sum();
                let edge = mesh.edges()[e as usize];
                let work = &ew[e as usize];
                let c = w * work.slope * work.slope;
                let ids = [edge.v[0], edge.v[1], edge.opposite[0], edge.opposite[1]];
                for (a, ga) in ids.iter().zip(&work.grad) {
                    for (b, gb) in ids.iter().zip(&work.grad) {
                        let block = [0, 1, 2].map(|row| [0, 1, 2].map(|col| c * ga[row] * gb[col]));
                        add(*a, *b, block);
                    }
                }
            }
        }
        Ok(())
    }

    /// The elastic energy (J) at positions `x` (m).
    pub fn energy(&mut self, x: &[Vec3]) -> Result<f64, ShellError> {
        self.check_len("shell positions", x.len())?;
        self.edge_pass(x);
        self.face_pass(false);
        Ok(self.face_work.iter().map(|w| w.energy).sum())
    }

    /// Each triangle's membrane and bending strain at positions `x` (m), in its rest plane's
    /// frame.
    pub fn strains(&mut self, x: &[Vec3]) -> Result<Vec<FaceStrain>, ShellError> {
        self.check_len("shell positions", x.len())?;
        self.edge_pass(x);
        let ew = &self.edge_work;
        Ok(self
            .faces
            .iter()
            .zip(self.mesh.face_edges())
            .map(|(r, e)| FaceStrain {
                membrane: combine(&r.m, e.map(|k| ew[k as usize].s)),
                bending: combine(&r.n, e.map(|k| ew[k as usize].dphi)),
            })
            .collect())
    }
}
