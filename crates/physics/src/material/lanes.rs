//! Chen's dilatation and force loops four bonds at a time in AVX2 vectors (x86-64 only, chosen
//! at run time): each bond's arithmetic is the scalar loop's, operation for operation
//! (exactly rounded adds, products, square roots and quotients, no fused multiply-add), and a
//! particle's sums take the bonds in the same order, so the results are the scalar loops'
//! (`kernel.rs`) to the bit. For rows that hold no plastic extension, with the isotropic
//! weight (the default), with or without the fitted dilatation weights and a row of bond
//! states (docs/DECISIONS.md, "Four bonds a vector"). The setup's rest lengths and the fitted
//! dilatation's two passes over the bonds take four bonds a vector the same way
//! ([`lengths`], [`fit_factors`], [`fit_weights`]).

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use super::kernel::isotropic_pair;
use crate::family::Family;
use crate::math::Vec3;

/// What the loops read of a neighbour, packed in one cache line so four neighbours load as
/// eight vectors: `[y_x, y_y, y_z, V]` (m, m^3) before the dilatation pass, then
/// `[p, q, b, 0]` of the force pass ([`super::kernel::force`]'s `pq` and `coef_b`).
#[repr(C, align(64))]
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Packed {
    /// Position (m) and volume (m^3).
    pub at: [f64; 4],
    /// `p = a theta - (b c / 3) S` (N/m^6), `q = b theta / 3` (N/m^7), `b` (N/m^7), 0.
    pub pq: [f64; 4],
}

/// The inputs of both loops: the family, the packed neighbours, the isotropic weight's horizon
/// `delta` (m) and the fitted dilatation weights `(d_ij, d_ji)` when they are used. Made only
/// where the CPU runs the lane loops ([`Row::new`]), which is what makes calling them sound.
#[derive(Clone, Copy)]
pub(crate) struct Row<'a> {
    family: &'a Family,
    packed: &'a [Packed],
    delta: f64,
    dw: Option<&'a [[f64; 2]]>,
    /// Off x86-64 no `Row` can be made.
    #[cfg(not(target_arch = "x86_64"))]
    never: std::convert::Infallible,
}

impl<'a> Row<'a> {
    /// The loops' inputs, or `None` where the CPU lacks AVX2 (or is not x86-64).
    pub(crate) fn new(
        family: &'a Family,
        packed: &'a [Packed],
        delta: f64,
        dw: Option<&'a [[f64; 2]]>,
    ) -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        {
            available().then_some(Row {
                family,
                packed,
                delta,
                dw,
            })
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (family, packed, delta, dw);
            None
        }
    }

    /// The isotropic weight's horizon (m).
    pub(crate) fn delta(self) -> f64 {
        self.delta
    }

    /// [`dilatation_avx2`]'s sums and greatest extension (m) over `i`'s bonds that `alive`
    /// (`i`'s row of bond states, nonzero intact; `None`: every bond) keeps.
    pub(crate) fn dilatation(self, i: usize, alive: Option<&[u8]>) -> ([f64; 3], f64) {
        let (sums, most, _) = self.dilatation_with::<false>(i, alive, 0.0);
        (sums, most)
    }

    /// [`Row::dilatation`] and the greatest `|delta| |e| (rsum - r)` (m^2 times the weight,
    /// at least 0) of a plastic row whose own ends are all zero: the bound of the kernel's
    /// `Yield::all_inside`, `rsum` the particle's `r_min + r_max` (m).
    pub(crate) fn dilatation_bounded(
        self,
        i: usize,
        alive: Option<&[u8]>,
        rsum: f64,
    ) -> ([f64; 3], f64, f64) {
        self.dilatation_with::<true>(i, alive, rsum)
    }

    fn dilatation_with<const BOUND: bool>(
        self,
        i: usize,
        alive: Option<&[u8]>,
        rsum: f64,
    ) -> ([f64; 3], f64, f64) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Row` exists only where the CPU has AVX2 (`Row::new`)
        unsafe {
            match (alive.filter(|a| has_broken(a)), self.dw.is_some()) {
                (None, false) => dilatation_avx2::<false, false, BOUND>(self, i, &[], rsum),
                (None, true) => dilatation_avx2::<false, true, BOUND>(self, i, &[], rsum),
                (Some(a), false) => dilatation_avx2::<true, false, BOUND>(self, i, a, rsum),
                (Some(a), true) => dilatation_avx2::<true, true, BOUND>(self, i, a, rsum),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        match self.never {}
    }

    /// [`force_avx2`]'s force (N).
    pub(crate) fn force(self, i: usize, alive: Option<&[u8]>) -> Vec3 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Row` exists only where the CPU has AVX2 (`Row::new`)
        unsafe {
            match (alive.filter(|a| has_broken(a)), self.dw.is_some()) {
                (None, false) => force_avx2::<false, false>(self, i, &[]),
                (None, true) => force_avx2::<false, true>(self, i, &[]),
                (Some(a), false) => force_avx2::<true, false>(self, i, a),
                (Some(a), true) => force_avx2::<true, true>(self, i, a),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        match self.never {}
    }
}

/// `(theta_i, S_i)` from [`Row::dilatation`]'s sums with the dilatation constant `c` (as
/// [`super::kernel::dilatation`] forms them; `S_i = 0` unless `moment`).
pub(crate) fn theta_moment(c: f64, [acc, u, m]: [f64; 3], moment: bool) -> (f64, f64) {
    let theta = c * acc;
    let (u, m) = if moment { (u, m) } else { (0.0, 0.0) };
    (theta, u - theta * m / 3.0)
}

/// Runs `f` compiled for AVX2 and FMA where the CPU has both, else as it stands: the same
/// operations in the same order (Rust fuses no multiply and add unless asked), so the same
/// bits, with wider instructions where the compiler finds them (the setup's fit: 0.48 -> 0.46 s
/// on the speed benchmark's cube on one thread). `f` and what it calls should be
/// `#[inline]` so that they are compiled into the AVX2 copy.
#[inline(always)]
pub(crate) fn wide<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has both features, checked just above
        return unsafe { wide_avx2(f) };
    }
    f()
}

/// [`wide`]'s AVX2 copy.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn wide_avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Whether this CPU runs the lane loops.
pub(crate) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// `(sum_j d_ij V_j e_ij, sum_j delta V_j e_ij, sum_j delta V_j r_ij)` over particle `i`'s
/// intact bonds, `d_ij = delta / r_ij` without fitted weights: the three sums of
/// [`super::kernel::dilatation`] with no plastic extension; the greatest extension summed (m;
/// minus infinity with none); with `BOUND`, the greatest `|delta| |e| (rsum - r)` (else 0).
/// Reads the packed records' `at`. With `MASKED`, `alive` is `i`'s row of bond states
/// (nonzero intact); without, every bond is.
///
/// # Safety
/// The CPU must have AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dilatation_avx2<const MASKED: bool, const SPLIT: bool, const BOUND: bool>(
    row: Row,
    i: usize,
    alive: &[u8],
    rsum: f64,
) -> ([f64; 3], f64, f64) {
    let fam = row.family;
    let (nb, rl) = (fam.neighbours(), fam.rest_lengths());
    let at = row.packed[i].at;
    let yi = [at[0], at[1], at[2]];
    let yi4 = yi.map(|c| _mm256_set1_pd(c));
    let delta = _mm256_set1_pd(row.delta);
    let (wabs4, rsum4) = (_mm256_set1_pd(row.delta.abs()), _mm256_set1_pd(rsum));
    let sign = _mm256_set1_pd(-0.0);
    let dw = row.dw.unwrap_or_default();
    let range = fam.range(i);
    let first = range.start;
    let mut acc = _mm256_setzero_pd();
    let mut most4 = _mm256_set1_pd(f64::NEG_INFINITY);
    let mut x4 = _mm256_setzero_pd();
    let mut tail = Tail {
        most: f64::NEG_INFINITY,
        x: 0.0,
    };
    let mut k = range.start;
    while k + 4 <= range.end {
        let dead = dead_lanes::<MASKED>(alive, k - first);
        let [x, y, z, v] = gather(row.packed, &nb[k..k + 4], |p| &p.at);
        let r = _mm256_loadu_pd(rl[k..k + 4].as_ptr());
        let eta = [
            _mm256_sub_pd(x, yi4[0]),
            _mm256_sub_pd(y, yi4[1]),
            _mm256_sub_pd(z, yi4[2]),
        ];
        let e = _mm256_sub_pd(length(eta), r);
        // e > most ? e : most, lane by lane: a NaN extension is left out, as in the kernel; a
        // broken bond's as minus infinity
        let live_e = if MASKED {
            _mm256_blendv_pd(e, _mm256_set1_pd(f64::NEG_INFINITY), dead)
        } else {
            e
        };
        most4 = _mm256_max_pd(live_e, most4);
        if BOUND {
            // |wr| |e| (rsum - r), as `OwnSums::add` forms it (abs: the sign bit cleared)
            let b = _mm256_mul_pd(
                _mm256_mul_pd(wabs4, _mm256_andnot_pd(sign, e)),
                _mm256_sub_pd(rsum4, r),
            );
            x4 = _mm256_max_pd(drop_dead::<MASKED>(dead, b), x4);
        }
        let d = if SPLIT {
            own_weights(&dw[k..k + 4]).0
        } else {
            _mm256_div_pd(delta, r)
        };
        let wrv = _mm256_mul_pd(delta, v);
        let term = _mm256_mul_pd(_mm256_mul_pd(d, v), e);
        acc = add_in_order(
            acc,
            drop_dead::<MASKED>(dead, term),
            drop_dead::<MASKED>(dead, _mm256_mul_pd(wrv, e)),
            drop_dead::<MASKED>(dead, _mm256_mul_pd(wrv, r)),
        );
        k += 4;
    }
    let mut out = unpack(acc);
    for k in k..range.end {
        if MASKED && alive[k - first] == 0 {
            continue;
        }
        let (e, t) = dilatation_bond(row, yi, k);
        tail.add::<BOUND>(row.delta, e, rsum, fam.rest_lengths()[k]);
        for (o, t) in out.iter_mut().zip(t) {
            *o += t;
        }
    }
    // the greatest of the lanes' and the rest's (the order of a maximum is immaterial)
    for l in unpack4(most4) {
        tail.most = if l > tail.most { l } else { tail.most };
    }
    for l in unpack4(x4) {
        tail.x = if l > tail.x { l } else { tail.x };
    }
    (out, tail.most, tail.x)
}

/// The maxima of [`dilatation_avx2`] over the bonds it takes one at a time.
struct Tail {
    most: f64,
    x: f64,
}

impl Tail {
    /// Takes a bond of extension `e` and rest length `r` (m); `BOUND` as in [`dilatation_avx2`].
    #[inline(always)]
    fn add<const BOUND: bool>(&mut self, delta: f64, e: f64, rsum: f64, r: f64) {
        self.most = if e > self.most { e } else { self.most };
        if BOUND {
            let x = delta.abs() * e.abs() * (rsum - r);
            self.x = if x > self.x { x } else { self.x };
        }
    }
}

/// Bond `k`'s extension (m) and its terms of [`dilatation_avx2`]' three sums, as the scalar
/// loop computes them.
#[inline(always)]
fn dilatation_bond(row: Row, yi: Vec3, k: usize) -> (f64, [f64; 3]) {
    let fam = row.family;
    let at = row.packed[fam.neighbours()[k] as usize].at;
    let r = fam.rest_lengths()[k];
    let vj = at[3];
    let e = crate::math::norm(crate::math::sub([at[0], at[1], at[2]], yi)) - r;
    let d = match row.dw {
        Some(dw) => dw[k][0],
        None => row.delta / r,
    };
    let wrv = row.delta * vj;
    (e, [d * vj * e, wrv * e, wrv * r])
}

/// Force on particle `i` (N) of [`super::kernel::force`] with no plastic extension, from the
/// packed records (both halves filled), over the bonds `alive` (`i`'s row of bond states,
/// nonzero intact; `None` when every bond is).
///
/// # Safety
/// The CPU must have AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn force_avx2<const MASKED: bool, const SPLIT: bool>(
    row: Row,
    i: usize,
    alive: &[u8],
) -> Vec3 {
    let fam = row.family;
    let (nb, rl) = (fam.neighbours(), fam.rest_lengths());
    let own = row.packed[i];
    let Packed { at, pq } = own;
    let yi4 = [0, 1, 2].map(|c| _mm256_set1_pd(at[c]));
    let [pi, qi, bi, _] = pq;
    let (pi4, qi4, bi4, vi4) = (
        _mm256_set1_pd(pi),
        _mm256_set1_pd(qi),
        _mm256_set1_pd(bi),
        _mm256_set1_pd(at[3]),
    );
    let delta = _mm256_set1_pd(row.delta);
    let two = _mm256_set1_pd(2.0);
    let one = _mm256_set1_pd(1.0);
    let dw = row.dw.unwrap_or_default();
    let range = fam.range(i);
    let first = range.start;
    let mut acc = _mm256_setzero_pd();
    let mut k = range.start;
    while k + 4 <= range.end {
        let dead = dead_lanes::<MASKED>(alive, k - first);
        let j = &nb[k..k + 4];
        let [x, y, z, vj] = gather(row.packed, j, |p| &p.at);
        let [pj, qj, bj, _] = gather(row.packed, j, |p| &p.pq);
        let r = _mm256_loadu_pd(rl[k..k + 4].as_ptr());
        let eta = [
            _mm256_sub_pd(x, yi4[0]),
            _mm256_sub_pd(y, yi4[1]),
            _mm256_sub_pd(z, yi4[2]),
        ];
        let len = length(eta);
        let e = _mm256_sub_pd(len, r);
        let inv = _mm256_div_pd(one, _mm256_mul_pd(r, len));
        let bsum = _mm256_add_pd(_mm256_mul_pd(bi4, e), _mm256_mul_pd(bj, e));
        let qr = _mm256_mul_pd(_mm256_add_pd(qi4, qj), r);
        let t = if SPLIT {
            let (dij, dji) = own_weights(&dw[k..k + 4]);
            _mm256_add_pd(
                _mm256_mul_pd(
                    r,
                    _mm256_add_pd(_mm256_mul_pd(dij, pi4), _mm256_mul_pd(dji, pj)),
                ),
                _mm256_mul_pd(delta, _mm256_sub_pd(bsum, qr)),
            )
        } else {
            _mm256_mul_pd(
                delta,
                _mm256_sub_pd(_mm256_add_pd(_mm256_add_pd(pi4, pj), bsum), qr),
            )
        };
        let vv = _mm256_mul_pd(vi4, vj);
        let s = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(two, t), vv), inv);
        acc = add_in_order(
            acc,
            drop_dead::<MASKED>(dead, _mm256_mul_pd(s, eta[0])),
            drop_dead::<MASKED>(dead, _mm256_mul_pd(s, eta[1])),
            drop_dead::<MASKED>(dead, _mm256_mul_pd(s, eta[2])),
        );
        k += 4;
    }
    let mut out = unpack(acc);
    for k in k..range.end {
        if MASKED && alive[k - first] == 0 {
            continue;
        }
        for (o, f) in out.iter_mut().zip(force_bond(row, own, k)) {
            *o += f;
        }
    }
    out
}

/// Bond `k`'s term `s eta` of [`force_avx2`] for the particle whose record is `own`, as the scalar
/// loop computes it.
#[inline(always)]
fn force_bond(row: Row, own: Packed, k: usize) -> Vec3 {
    let fam = row.family;
    let Packed { at, pq } = row.packed[fam.neighbours()[k] as usize];
    let [pi, qi, bi, _] = own.pq;
    let r = fam.rest_lengths()[k];
    let eta = crate::math::sub([at[0], at[1], at[2]], [own.at[0], own.at[1], own.at[2]]);
    let l = crate::math::norm(eta);
    let [pj, qj, bj, _] = pq;
    let ends = [[pi, qi, bi], [pj, qj, bj]];
    let dil = row.dw.map(|dw| (dw[k][0], dw[k][1]));
    let s = isotropic_pair(row.delta, r, l, ends, (0.0, 0.0), dil, own.at[3] * at[3]);
    [s * eta[0], s * eta[1], s * eta[2]]
}

/// Whether a row of bond states holds a broken bond (0): rows without take the loops that
/// read no state.
#[inline(always)]
fn has_broken(alive: &[u8]) -> bool {
    alive.iter().fold(false, |any, &s| any | (s == 0))
}

/// All ones in the lanes of the four bonds from offset `o` of the row whose state in `alive`
/// is 0 (broken), zeros elsewhere; all zeros without `MASKED`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn dead_lanes<const MASKED: bool>(alive: &[u8], o: usize) -> __m256d {
    if !MASKED {
        return _mm256_setzero_pd();
    }
    let s = &alive[o..o + 4];
    let w = i32::from_ne_bytes([s[0], s[1], s[2], s[3]]);
    let states = _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(w));
    _mm256_castsi256_pd(_mm256_cmpeq_epi64(states, _mm256_setzero_si256()))
}

/// `v` with the `dead` lanes `+0.0`. Adding `+0.0` leaves a running sum as it is, bit for bit,
/// when the sum is not `-0.0`, and one that starts at `+0.0` never is (round to nearest gives
/// `-0.0` only for two of them): so a broken bond's lane counts as the scalar loop's skipping
/// it, whatever its terms are (even NaN).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn drop_dead<const MASKED: bool>(dead: __m256d, v: __m256d) -> __m256d {
    if MASKED {
        _mm256_andnot_pd(dead, v)
    } else {
        v
    }
}

/// The four-vectors `half(packed[j_l])` of the neighbours `j_0..j_3`, transposed: component
/// `c` of every lane in vector `c`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn gather(
    packed: &[Packed],
    j: &[u32],
    half: impl Fn(&Packed) -> &[f64; 4],
) -> [__m256d; 4] {
    let row = |l: usize| _mm256_loadu_pd(half(&packed[j[l] as usize]).as_ptr());
    let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
    let t0 = _mm256_unpacklo_pd(r0, r1); // x0 x1 z0 z1
    let t1 = _mm256_unpackhi_pd(r0, r1); // y0 y1 w0 w1
    let t2 = _mm256_unpacklo_pd(r2, r3); // x2 x3 z2 z3
    let t3 = _mm256_unpackhi_pd(r2, r3); // y2 y3 w2 w3
    [
        _mm256_permute2f128_pd(t0, t2, 0x20),
        _mm256_permute2f128_pd(t1, t3, 0x20),
        _mm256_permute2f128_pd(t0, t2, 0x31),
        _mm256_permute2f128_pd(t1, t3, 0x31),
    ]
}

/// `(d_ij, d_ji)` of four consecutive bonds, one vector each.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn own_weights(dw: &[[f64; 2]]) -> (__m256d, __m256d) {
    let a = _mm256_loadu_pd(dw[0..2].as_ptr().cast()); // i0 r0 i1 r1
    let b = _mm256_loadu_pd(dw[2..4].as_ptr().cast()); // i2 r2 i3 r3
                                                       // i0 i2 i1 i3 -> i0 i1 i2 i3
    let ij = _mm256_permute4x64_pd(_mm256_unpacklo_pd(a, b), 0b11_01_10_00);
    let ji = _mm256_permute4x64_pd(_mm256_unpackhi_pd(a, b), 0b11_01_10_00);
    (ij, ji)
}

/// `sqrt((x^2 + y^2) + z^2)` lane by lane, as [`crate::math::norm`] sums it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn length(v: [__m256d; 3]) -> __m256d {
    _mm256_sqrt_pd(_mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(v[0], v[0]), _mm256_mul_pd(v[1], v[1])),
        _mm256_mul_pd(v[2], v[2]),
    ))
}

/// `acc + (a_l, b_l, c_l, 0)` for the lanes `l = 0..3` in turn: three running sums (in `acc`'s
/// first three lanes) taking four bonds' terms in bond order, as the scalar loop does.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn add_in_order(acc: __m256d, a: __m256d, b: __m256d, c: __m256d) -> __m256d {
    let z = _mm256_setzero_pd();
    let ab_lo = _mm256_unpacklo_pd(a, b); // a0 b0 a2 b2
    let ab_hi = _mm256_unpackhi_pd(a, b); // a1 b1 a3 b3
    let c_lo = _mm256_unpacklo_pd(c, z); // c0 0 c2 0
    let c_hi = _mm256_unpackhi_pd(c, z); // c1 0 c3 0
    let acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(ab_lo, c_lo, 0x20));
    let acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(ab_hi, c_hi, 0x20));
    let acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(ab_lo, c_lo, 0x31));
    _mm256_add_pd(acc, _mm256_permute2f128_pd(ab_hi, c_hi, 0x31))
}

/// The four lanes of `v`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn unpack4(v: __m256d) -> [f64; 4] {
    let hi = _mm256_permute2f128_pd(v, v, 0x11);
    [
        _mm256_cvtsd_f64(v),
        _mm256_cvtsd_f64(_mm256_permute_pd(v, 1)),
        _mm256_cvtsd_f64(hi),
        _mm256_cvtsd_f64(_mm256_permute_pd(hi, 1)),
    ]
}

/// The first three lanes of `v`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn unpack(v: __m256d) -> [f64; 3] {
    [
        _mm256_cvtsd_f64(v),
        _mm256_cvtsd_f64(_mm256_permute_pd(v, 1)),
        _mm256_cvtsd_f64(_mm256_permute2f128_pd(v, v, 0x11)),
    ]
}

/// The fitted dilatation's factors of particle `i`'s bonds, four bonds a vector:
/// `row[o] = [g_ij, g_ji]` for its `o`-th bond, with `g = q(n) . l / c` at each end
/// ([`super::fit`]'s first pass, whose scalar loop takes the bonds this leaves), and the
/// greatest `|g_ij - 1|` of them (0 with none). Returns how many bonds it took (a multiple of
/// four; none where the CPU lacks AVX2) and that greatest value. Each lane forms its bond's
/// quotients, products and sums as the scalar loop does, in the same order, so the bits are
/// the same; what it saves is instructions (the scalar loop spends about 8 ns a bond).
pub(crate) fn fit_factors(
    family: &Family,
    x: &[Vec3],
    l: &[[f64; 6]],
    c: &[f64],
    i: usize,
    row: &mut [[f64; 2]],
) -> (usize, f64) {
    #[cfg(target_arch = "x86_64")]
    if available() {
        // SAFETY: the CPU has AVX2, checked just above
        return unsafe { fit_factors_avx2(family, x, l, c, i, row) };
    }
    let _ = (family, x, l, c, i, row);
    (0, 0.0)
}

/// [`fit_factors`]' loop.
///
/// # Safety
/// The CPU must have AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn fit_factors_avx2(
    family: &Family,
    x: &[Vec3],
    l: &[[f64; 6]],
    c: &[f64],
    i: usize,
    row: &mut [[f64; 2]],
) -> (usize, f64) {
    let range = family.range(i);
    let (nb, rl) = (
        &family.neighbours()[range.clone()],
        &family.rest_lengths()[range],
    );
    let xi = x[i].map(|v| _mm256_set1_pd(v));
    let li = l[i].map(|v| _mm256_set1_pd(v));
    let ci = _mm256_set1_pd(c[i]);
    // the value a float sum starts from, whichever zero the standard library takes
    let start = _mm256_set1_pd(std::iter::empty::<f64>().sum::<f64>());
    let (one, sign) = (_mm256_set1_pd(1.0), _mm256_set1_pd(-0.0));
    let root2 = _mm256_set1_pd(std::f64::consts::SQRT_2);
    let mut worst = _mm256_setzero_pd();
    let mut o = 0;
    while o + 4 <= nb.len().min(row.len()) {
        let j = [0, 1, 2, 3].map(|b| nb[o + b] as usize);
        let r = _mm256_loadu_pd(rl[o..o + 4].as_ptr());
        // (X_j - X_i) / r, as `fit::rest_direction`
        let axis = |a: usize| {
            let xj = _mm256_set_pd(x[j[3]][a], x[j[2]][a], x[j[1]][a], x[j[0]][a]);
            _mm256_div_pd(_mm256_sub_pd(xj, xi[a]), r)
        };
        let n = [axis(0), axis(1), axis(2)];
        // `fit::mandel`: s n1 n2 is (s n1) n2
        let q = [
            _mm256_mul_pd(n[0], n[0]),
            _mm256_mul_pd(n[1], n[1]),
            _mm256_mul_pd(n[2], n[2]),
            _mm256_mul_pd(_mm256_mul_pd(root2, n[1]), n[2]),
            _mm256_mul_pd(_mm256_mul_pd(root2, n[0]), n[2]),
            _mm256_mul_pd(_mm256_mul_pd(root2, n[0]), n[1]),
        ];
        // `sum` over p of q_p t_p: a fold from `start` in p's order
        let dot = |t: [__m256d; 6]| {
            (0..6).fold(start, |s, p| _mm256_add_pd(s, _mm256_mul_pd(q[p], t[p])))
        };
        let g_ij = _mm256_div_pd(dot(li), ci);
        let cj = _mm256_set_pd(c[j[3]], c[j[2]], c[j[1]], c[j[0]]);
        let g_ji = _mm256_div_pd(dot(tensors(l, j)), cj);
        store_pairs(&mut row[o..o + 4], g_ij, g_ji);
        // max(|g - 1|, worst), a NaN left out as `f64::max` leaves it (the second operand
        // is kept when either is NaN, and `worst` never is)
        worst = _mm256_max_pd(_mm256_andnot_pd(sign, _mm256_sub_pd(g_ij, one)), worst);
        o += 4;
    }
    // the order of a maximum is immaterial
    let most = unpack4(worst).into_iter().fold(0.0, f64::max);
    (o, most)
}

/// `out[b] = [ij_b, ji_b]` for the four lanes (the inverse of [`own_weights`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn store_pairs(out: &mut [[f64; 2]], ij: __m256d, ji: __m256d) {
    let lo = _mm256_unpacklo_pd(ij, ji); // ij0 ji0 ij2 ji2
    let hi = _mm256_unpackhi_pd(ij, ji); // ij1 ji1 ij3 ji3
    let (head, tail) = out[..4].split_at_mut(2);
    // SAFETY: each half holds two pairs, the four doubles each store writes
    unsafe {
        _mm256_storeu_pd(
            head.as_mut_ptr().cast(),
            _mm256_permute2f128_pd(lo, hi, 0x20),
        );
        _mm256_storeu_pd(
            tail.as_mut_ptr().cast(),
            _mm256_permute2f128_pd(lo, hi, 0x31),
        );
    }
}

/// The Mandel vectors `l[j_b]` of four particles, transposed: component `p` of every lane in
/// vector `p`.
///
/// # Safety
/// The CPU must have AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn tensors(l: &[[f64; 6]], j: [usize; 4]) -> [__m256d; 6] {
    let (t0, t1, t2, t3) = (&l[j[0]], &l[j[1]], &l[j[2]], &l[j[3]]);
    let head = |t: &[f64; 6]| _mm256_loadu_pd(t.as_ptr());
    let tail = |t: &[f64; 6]| _mm_loadu_pd(t[4..].as_ptr());
    let (r0, r1, r2, r3) = (head(t0), head(t1), head(t2), head(t3));
    let a = _mm256_unpacklo_pd(r0, r1); // 0_0 0_1 2_0 2_1
    let b = _mm256_unpackhi_pd(r0, r1); // 1_0 1_1 3_0 3_1
    let c = _mm256_unpacklo_pd(r2, r3); // 0_2 0_3 2_2 2_3
    let d = _mm256_unpackhi_pd(r2, r3); // 1_2 1_3 3_2 3_3
    let (s0, s1, s2, s3) = (tail(t0), tail(t1), tail(t2), tail(t3));
    [
        _mm256_permute2f128_pd(a, c, 0x20),
        _mm256_permute2f128_pd(b, d, 0x20),
        _mm256_permute2f128_pd(a, c, 0x31),
        _mm256_permute2f128_pd(b, d, 0x31),
        _mm256_set_m128d(_mm_unpacklo_pd(s2, s3), _mm_unpacklo_pd(s0, s1)),
        _mm256_set_m128d(_mm_unpackhi_pd(s2, s3), _mm_unpackhi_pd(s0, s1)),
    ]
}

/// `row[o] = |x_j - x_i|` for particle `i`'s neighbours `nb` (`row` as long), four bonds a
/// vector where the CPU has AVX2 (square roots are the loop's slowest operation), the rest one
/// at a time; each length summed and rooted as [`crate::math::norm`] does it, so the same bits.
pub(crate) fn lengths(x: &[Vec3], i: usize, nb: &[u32], row: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    let done = if available() {
        // SAFETY: the CPU has AVX2, checked just above
        unsafe { lengths_avx2(x, i, nb, row) }
    } else {
        0
    };
    #[cfg(not(target_arch = "x86_64"))]
    let done = 0;
    for (r, &j) in row[done..].iter_mut().zip(&nb[done..]) {
        *r = crate::math::norm(crate::math::sub(x[j as usize], x[i]));
    }
}

/// [`lengths`]' loop over whole groups of four; returns how many bonds it took.
///
/// # Safety
/// The CPU must have AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lengths_avx2(x: &[Vec3], i: usize, nb: &[u32], row: &mut [f64]) -> usize {
    let xi = x[i].map(|v| _mm256_set1_pd(v));
    let mut o = 0;
    while o + 4 <= nb.len().min(row.len()) {
        let j = [0, 1, 2, 3].map(|b| nb[o + b] as usize);
        let axis = |a: usize| {
            let xj = _mm256_set_pd(x[j[3]][a], x[j[2]][a], x[j[1]][a], x[j[0]][a]);
            _mm256_sub_pd(xj, xi[a])
        };
        let r = length([axis(0), axis(1), axis(2)]);
        _mm256_storeu_pd(row[o..o + 4].as_mut_ptr(), r);
        o += 4;
    }
    o
}

/// The fitted dilatation's weights of particle `i`'s bonds without per-bond deviatoric
/// weights ([`super::fit`]'s second pass), four bonds a vector: each slot of `row` holds the
/// factors `[g_ij, g_ji]` and gets `[w (1 + a_i (g_ij - 1)) s_i, w (1 + a_j (g_ji - 1)) s_j]`
/// with `w = delta / r` and `blend[p] = [a_p, s_p]`. Starting from the caller's `m`, each
/// bond in turn whose `d_ij / w` is strictly greater in magnitude than `m` replaces it, so a
/// tie keeps the earlier bond, as the scalar loop does. Returns how many bonds it took (a
/// multiple of four; none where the CPU lacks AVX2) and `m`, with the scalar loop's bits.
pub(crate) fn fit_weights(
    family: &Family,
    delta: f64,
    blend: &[[f64; 2]],
    i: usize,
    row: &mut [[f64; 2]],
    m: f64,
) -> (usize, f64) {
    #[cfg(target_arch = "x86_64")]
    if available() {
        // SAFETY: the CPU has AVX2, checked just above
        return unsafe { fit_weights_avx2(family, delta, blend, i, row, m) };
    }
    let _ = (family, delta, blend, i, row);
    (0, m)
}

/// [`fit_weights`]' loop.
///
/// # Safety
/// The CPU must have AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn fit_weights_avx2(
    family: &Family,
    delta: f64,
    blend: &[[f64; 2]],
    i: usize,
    row: &mut [[f64; 2]],
    mut m: f64,
) -> (usize, f64) {
    let range = family.range(i);
    let (nb, rl) = (
        &family.neighbours()[range.clone()],
        &family.rest_lengths()[range],
    );
    let (ai, si) = (_mm256_set1_pd(blend[i][0]), _mm256_set1_pd(blend[i][1]));
    let (one, delta4) = (_mm256_set1_pd(1.0), _mm256_set1_pd(delta));
    let mut o = 0;
    while o + 4 <= nb.len().min(row.len()) {
        let j = [0, 1, 2, 3].map(|b| nb[o + b] as usize);
        let w = _mm256_div_pd(delta4, _mm256_loadu_pd(rl[o..o + 4].as_ptr()));
        let (g_ij, g_ji) = own_weights(&row[o..o + 4]);
        let aj = _mm256_set_pd(
            blend[j[3]][0],
            blend[j[2]][0],
            blend[j[1]][0],
            blend[j[0]][0],
        );
        let sj = _mm256_set_pd(
            blend[j[3]][1],
            blend[j[2]][1],
            blend[j[1]][1],
            blend[j[0]][1],
        );
        // w (1 + a (g - 1)) s, in that order
        let end = |g, a, s| {
            _mm256_mul_pd(
                _mm256_mul_pd(
                    w,
                    _mm256_add_pd(one, _mm256_mul_pd(a, _mm256_sub_pd(g, one))),
                ),
                s,
            )
        };
        let (d_ij, d_ji) = (end(g_ij, ai, si), end(g_ji, aj, sj));
        store_pairs(&mut row[o..o + 4], d_ij, d_ji);
        for f in unpack4(_mm256_div_pd(d_ij, w)) {
            if f.abs() > m.abs() {
                m = f;
            }
        }
        o += 4;
    }
    (o, m)
}
