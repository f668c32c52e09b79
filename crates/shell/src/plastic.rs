//! Shell plasticity with linear kinematic hardening (Gingold et al. 2004, after O'Brien et
//! al.'s solid model): von Mises on the deviator of the elastic strain less `gamma` times the
//! plastic strain, averaged through the thickness, with the plastic strain a change of the rest
//! state kept per triangle in the strains' own coordinates (squared edge-length changes and
//! changes of `phi`), as the paper stores it.
//!
//! At a point `z` across the thickness the strain is `E_m + z E_c` and the plastic strain
//! `P_m + z P_c`. With plane stress the elastic strain has `e_33 = -nu / (1 - nu) tr e`; the
//! plastic strain is isochoric, `p_33 = -tr p`. The tensor `T = dev(e) - gamma p` is linear in
//! `z`, `T_m + z T_c`, so its squared norm averaged over the thickness is
//! `|T_m|^2 + h^2 / 12 |T_c|^2 = F^2`. The face yields where `F > eps_0`; the update moves
//! both in-plane plastic parts down the gradient of `F^2` until `F = eps_0` (a return to the
//! yield surface; one step reaches it to round-off, 1e-14 in the tests), once per step at the
//! step's end
//! positions before the forces, as explicit finite elements return-map.

use crate::error::ShellError;

/// Yield and hardening of a shell material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellYield {
    /// Yield strain `eps_0` (dimensionless, > 0): the thickness-averaged norm of the
    /// deviatoric elastic strain at which the material yields.
    pub yield_strain: f64,
    /// Linear kinematic hardening `gamma = h_kin / (2 mu)` (dimensionless, >= 0): 0 is ideal
    /// plasticity.
    pub hardening: f64,
}

impl ShellYield {
    /// Checks the yield strain is finite and > 0 and the hardening finite and >= 0.
    pub fn new(yield_strain: f64, hardening: f64) -> Result<ShellYield, ShellError> {
        if !(yield_strain.is_finite() && yield_strain > 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell yield strain",
                expected: "finite and > 0",
                value: yield_strain,
            });
        }
        if !(hardening.is_finite() && hardening >= 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell hardening",
                expected: "finite and >= 0",
                value: hardening,
            });
        }
        Ok(ShellYield {
            yield_strain,
            hardening,
        })
    }
}

/// The plastic state of every triangle: its plastic strain in the coordinates of the strains
/// (the squared edge-length changes and the `phi` changes it takes off the total ones). Kept
/// when the material yields, and when it fractures (vertex budging changes the rest state
/// through it).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PlasticState {
    /// Yield and hardening; `None`: the offsets change only by fracture.
    pub params: Option<ShellYield>,
    /// Per triangle, the plastic squared edge-length change of each edge (m^2).
    pub s: Vec<[f64; 3]>,
    /// Per triangle, the plastic change of `phi` at each edge (dimensionless).
    pub phi: Vec<[f64; 3]>,
}

impl PlasticState {
    pub fn new(params: Option<ShellYield>, faces: usize) -> PlasticState {
        PlasticState {
            params,
            s: vec![[0.0; 3]; faces],
            phi: vec![[0.0; 3]; faces],
        }
    }
}

/// `sum_k c_k B_k` of three symmetric 2x2 tensors `[xx, yy, xy]`.
#[inline]
pub(crate) fn combine(basis: &[[f64; 3]; 3], c: [f64; 3]) -> [f64; 3] {
    let mut t = [0.0; 3];
    for k in 0..3 {
        for (j, tj) in t.iter_mut().enumerate() {
            *tj += c[k] * basis[k][j];
        }
    }
    t
}

/// The coefficients `c` with `sum_k c_k B_k = t` (Cramer's rule; the three tensors of a
/// non-degenerate triangle are independent).
pub(crate) fn coordinates(basis: &[[f64; 3]; 3], t: [f64; 3]) -> [f64; 3] {
    // Columns of the matrix are the basis tensors.
    let col = |k: usize| basis[k];
    let det3 = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1])
            + c[0] * (a[1] * b[2] - a[2] * b[1])
    };
    let d = det3(col(0), col(1), col(2));
    [
        det3(t, col(1), col(2)) / d,
        det3(col(0), t, col(2)) / d,
        det3(col(0), col(1), t) / d,
    ]
}

/// `dev(e) - gamma p` as `[xx, yy, zz, xy]` for in-plane elastic strain `e` (plane stress)
/// and plastic strain `p` (isochoric), both `[xx, yy, xy]`.
#[inline]
fn driving(e: [f64; 3], p: [f64; 3], nu: f64, gamma: f64) -> [f64; 4] {
    let e33 = -nu / (1.0 - nu) * (e[0] + e[1]);
    let mean = (e[0] + e[1] + e33) / 3.0;
    [
        e[0] - mean - gamma * p[0],
        e[1] - mean - gamma * p[1],
        e33 - mean + gamma * (p[0] + p[1]),
        e[2] - gamma * p[2],
    ]
}

#[inline]
fn norm2(t: [f64; 4]) -> f64 {
    t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + 2.0 * t[3] * t[3]
}

/// The thickness-averaged yield measure `F` of a triangle with total strains `e_m`, `e_c`
/// and plastic strains `p_m`, `p_c` (tensors `[xx, yy, xy]`), and the tensors `T_m`, `T_c`.
pub(crate) fn yield_measure(
    e_m: [f64; 3],
    e_c: [f64; 3],
    p_m: [f64; 3],
    p_c: [f64; 3],
    nu: f64,
    gamma: f64,
    thickness: f64,
) -> (f64, [f64; 4], [f64; 4]) {
    let el = |e: [f64; 3], p: [f64; 3]| [e[0] - p[0], e[1] - p[1], e[2] - p[2]];
    let tm = driving(el(e_m, p_m), p_m, nu, gamma);
    let tc = driving(el(e_c, p_c), p_c, nu, gamma);
    let f = (norm2(tm) + thickness * thickness / 12.0 * norm2(tc)).sqrt();
    (f, tm, tc)
}

/// The return map of one triangle at total strain coordinates `s` (squared edge-length
/// changes, m^2) and `dphi`, with bases `m` (membrane) and `n` (bending): updates its plastic
/// coordinates `ps`, `pphi` and returns whether it yielded.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn return_map(
    s: [f64; 3],
    dphi: [f64; 3],
    m: &[[f64; 3]; 3],
    n: &[[f64; 3]; 3],
    ps: &mut [f64; 3],
    pphi: &mut [f64; 3],
    params: &ShellYield,
    nu: f64,
    thickness: f64,
) -> bool {
    let (e_m, e_c) = (combine(m, s), combine(n, dphi));
    let gamma = params.hardening;
    let eps0 = params.yield_strain;
    let measure = |ps: &[f64; 3], pphi: &[f64; 3]| {
        yield_measure(
            e_m,
            e_c,
            combine(m, *ps),
            combine(n, *pphi),
            nu,
            gamma,
            thickness,
        )
    };
    let (f0, _, _) = measure(ps, pphi);
    if f0 <= eps0 {
        return false;
    }
    // The plastic strain flows down the gradient of F^2 by the in-plane plastic strain (in
    // the norm's own weighting): T_in + q tr(T_in) I with q = (k + gamma) / (1 + gamma) and
    // k = nu / (1 - nu), the plane-stress thickness strain's share (derived in
    // docs/DECISIONS.md). T is affine in the plastic strain, so along that direction F^2 is a
    // quadratic in the step and its first root at eps0 is found exactly; the direction turns
    // as T does, so a few steps are taken until F is on the surface.
    let q = (nu / (1.0 - nu) + gamma) / (1.0 + gamma);
    let w = thickness * thickness / 12.0;
    let dot4 =
        |x: [f64; 4], y: [f64; 4]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2] + 2.0 * x[3] * y[3];
    let sub4 = |x: [f64; 4], y: [f64; 4]| [x[0] - y[0], x[1] - y[1], x[2] - y[2], x[3] - y[3]];
    let direction = |t: [f64; 4]| {
        let tr = t[0] + t[1];
        [t[0] + q * tr, t[1] + q * tr, t[3]]
    };
    for _ in 0..RETURN_STEPS {
        let (f, tm, tc) = measure(ps, pphi);
        if f <= eps0 * (1.0 + RETURN_TOLERANCE) {
            break;
        }
        let dm = coordinates(m, direction(tm));
        let dc = coordinates(n, direction(tc));
        let moved = |p: &[f64; 3], d: &[f64; 3]| [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
        let (_, tm1, tc1) = measure(&moved(ps, &dm), &moved(pphi, &dc));
        let (gm, gc) = (sub4(tm1, tm), sub4(tc1, tc));
        let a = dot4(gm, gm) + w * dot4(gc, gc);
        let b = dot4(tm, gm) + w * dot4(tc, gc);
        let c = f * f - eps0 * eps0;
        let disc = b * b - a * c;
        let l = if a > 0.0 && disc >= 0.0 {
            // The smaller root, written to avoid cancellation.
            c / (-b + disc.sqrt())
        } else if a > 0.0 {
            -b / a
        } else {
            break;
        };
        for k in 0..3 {
            ps[k] += l * dm[k];
            pphi[k] += l * dc[k];
        }
    }
    true
}

/// Steps of one return map at most.
const RETURN_STEPS: usize = 8;

/// A return map stops within this share above the yield strain.
const RETURN_TOLERANCE: f64 = 1e-9;
