//! Chen plasticity: the return map lands on the yield surface, the cap holds, pure pressure does
//! not yield, and a block sheared past yield keeps a permanent set.

mod support;

use perifrac_physics::{
    ChenMaterial, ChenModel, ChenOptions, Explicit, ExplicitConfig, ForceModel, Loads, TimeStep,
    YieldParams,
};
use support::{affine, block, steel};

const SIZE: f64 = 0.04;
const CELLS: usize = 4;

/// Steel with a yield limit reached at a simple-shear strain of about `gamma_y`: the largest
/// deviatoric extension of a bond in simple shear is `r gamma / 2`, so
/// `A_dev = 4 (delta / r) b r gamma / 2 = 2 delta b gamma` and `Psi0 = (2 delta b gamma_y)^2 / 2`.
fn plastic_model(gamma_y: f64, cap: f64, opts: ChenOptions) -> ChenModel {
    let (disc, _, _) = block([SIZE; 3], [CELLS; 3], 1.5);
    let delta = disc.horizon();
    let mut mat: ChenMaterial = steel();
    let b = 15.0 * mat.shear_modulus / (2.0 * std::f64::consts::PI * delta.powi(5));
    let a_y = 2.0 * delta * b * gamma_y;
    mat.plasticity = Some(YieldParams {
        psi0: 0.5 * a_y * a_y,
        gamma_ratio: cap,
        from_strain: false,
    });
    ChenModel::with_options(disc, &[mat], opts).unwrap()
}

/// The default options (the fitted dilatation over the calibration): pure pressure never
/// reaches the yield test.
fn calibrated() -> ChenOptions {
    ChenOptions::default()
}

fn psi0(m: &ChenModel) -> f64 {
    // as in plastic_model for gamma_y = 0.002 (docs/model.md's uniform b, not the calibrated b_i)
    let delta = m.discretization().horizon();
    let b = 15.0 * support::steel().shear_modulus / (2.0 * std::f64::consts::PI * delta.powi(5));
    let a_y = 2.0 * delta * b * 0.002;
    0.5 * a_y * a_y
}

fn shear(x: &[[f64; 3]], gamma: f64) -> Vec<[f64; 3]> {
    affine(
        x,
        &[[1.0, 0.0, gamma], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [0.0; 3],
    )
}

#[test]
fn return_map_puts_a_dev_on_the_yield_surface_and_respects_the_cap() {
    let cap = 0.004;
    let mut m = plastic_model(0.002, cap, calibrated());
    let x = m.discretization().rest_positions().to_vec();
    let y = shear(&x, 0.01);
    let mut f = vec![[0.0; 3]; x.len()];
    m.update_forces(&y, &mut f);
    let theta = m.dilatations();
    let ep = m.plastic_extensions().unwrap();
    let fam = m.discretization().family().clone();
    let delta = m.discretization().horizon();
    let limit = (2.0 * psi0(&m)).sqrt();
    let (mut on_surface, mut capped, mut worst) = (0, 0, 0.0f64);
    for i in 0..x.len() {
        let (_, b) = m.constants(i);
        for k in fam.range(i) {
            let j = fam.neighbours()[k] as usize;
            let r = fam.rest_lengths()[k];
            let e = perifrac_physics::math::norm(perifrac_physics::math::sub(y[j], y[i])) - r;
            let a_dev = 4.0 * (delta / r) * b * (e - theta[i] * r / 3.0 - ep[k]);
            assert!(ep[k].abs() <= cap * r * (1.0 + 1e-15), "cap");
            if ep[k] == 0.0 {
                assert!(a_dev.abs() <= limit);
            } else if ep[k].abs() < cap * r {
                on_surface += 1;
                worst = worst.max((a_dev.abs() - limit).abs() / limit);
            } else {
                capped += 1;
            }
        }
    }
    eprintln!("{on_surface} bonds returned to the surface (worst relative miss {worst:.2e}), {capped} capped");
    assert!(on_surface > 1000 && capped > 0);
    // A_dev is recomputed here from e, theta and ep: measured worst 2.4e-15 (rounding); bound 1e-12
    assert!(worst < 1e-12);
}

#[test]
fn pure_hydrostatic_compression_does_not_yield() {
    // (calibrated, fitted dilatation, no bond yields)
    for (calibrated, fitted_dilatation, expect_zero) in [
        (true, true, true),
        (true, false, true),
        (false, true, true),
        (false, false, false),
    ] {
        let opts = ChenOptions {
            calibrated,
            fitted_dilatation,
            ..ChenOptions::default()
        };
        let mut m = plastic_model(0.002, 0.05, opts);
        let x = m.discretization().rest_positions().to_vec();
        // 1% volumetric compression per axis: five times the shear yield strain
        let s = 0.99;
        let y = affine(&x, &[[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]], [0.0; 3]);
        let mut f = vec![[0.0; 3]; x.len()];
        m.update_forces(&y, &mut f);
        let ep = m.plastic_extensions().unwrap();
        let yielded = ep.iter().filter(|&&e| e != 0.0).count();
        eprintln!(
            "calibrated {calibrated}, fitted {fitted_dilatation}: {yielded} of {} bonds \
             yielded under pure pressure",
            ep.len()
        );
        if expect_zero {
            // theta = 3 eps exactly (either correction), so ed = e - theta r / 3 vanishes
            // bond by bond (to rounding, ~1e-16 r)
            assert_eq!(yielded, 0);
        } else {
            // docs/model.md's uniform c: surface families see theta < 3 eps and yield spuriously
            assert!(yielded > 0);
        }
    }
}

/// Shears the block by moving its top layer, releases it, damps it to rest and returns the
/// remaining shear of the top layer relative to the applied one.
fn permanent_set(m: ChenModel) -> f64 {
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let h = SIZE / CELLS as f64;
    let bottom: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize][2] < 0.5 * h)
        .collect();
    let top: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize][2] > SIZE - 0.5 * h)
        .collect();
    let mut loads = Loads::new(x.len()).with_damping(2e4).unwrap();
    loads.anchor(&bottom, [0.0; 3]).unwrap();
    let speed = 0.5; // m/s: quasi-static (wave speed ~5000 m/s)
    loads.anchor(&top, [speed, 0.0, 0.0]).unwrap();
    let cfg = ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.8 },
        guard_fraction: 0.5,
    };
    let mut s = Explicit::new(m, &x, delta, loads, cfg).unwrap();
    let target = 0.02 * SIZE; // 2% shear: ten times the yield strain
    let load_steps = (target / speed / s.dt()).ceil() as usize;
    for _ in 0..load_steps {
        s.step().unwrap();
    }
    let mean_dx = |s: &Explicit<ChenModel>, set: &[u32]| {
        set.iter()
            .map(|&i| s.positions()[i as usize][0] - x[i as usize][0])
            .sum::<f64>()
            / set.len() as f64
    };
    let applied = mean_dx(&s, &top);
    s.loads_mut().release(&top).unwrap();
    s.loads_mut().damping = 1e5; // about critical for the lowest shear mode
    for _ in 0..3000 {
        s.step().unwrap();
    }
    let ke = s.kinetic_energy();
    let left = mean_dx(&s, &top);
    eprintln!(
        "applied {applied:.3e} m, left {left:.3e} m after release (kinetic energy {ke:.2e} J)"
    );
    left / applied
}

#[test]
fn sheared_past_yield_keeps_a_permanent_set() {
    let plastic = permanent_set(plastic_model(0.002, 0.05, calibrated()));
    let (disc, _, _) = block([SIZE; 3], [CELLS; 3], 1.5);
    let elastic = permanent_set(ChenModel::new(disc, &[steel()]).unwrap());
    eprintln!("set / applied: plastic {plastic:.3}, elastic {elastic:.3}");
    // measured: plastic keeps 0.852 of the 2% shear (0.833 with the scalar calibration); the
    // elastic block springs back to ~1e-15
    assert!(plastic > 0.5);
    assert!(elastic.abs() < 0.05);
}

/// Bonds of particles `set` with a plastic extension after one force update.
fn yielded_in(m: &ChenModel, set: &[usize]) -> usize {
    let ep = m.plastic_extensions().expect("plastic");
    let fam = m.discretization().family();
    set.iter()
        .map(|&i| fam.range(i).filter(|&k| ep[k] != 0.0).count())
        .sum()
}

#[test]
fn a_bar_in_tension_yields_at_its_yield_strain_at_the_surface_as_in_the_bulk() {
    // A bar of 8 x 3 x 3 cells under the homogeneous strain of uniaxial tension (eps along x,
    // -nu eps across). A bond along x has deviatoric strain (2/3)(1 + nu) eps, the largest of
    // any direction, so with a yield strain eps_y (the scene's `yield_strain`, converted with
    // docs/model.md's b and rescaled per particle) the first bonds yield at
    // eps = 1.5 eps_y / (1 + nu). The fitted dilatation makes theta exact on every particle,
    // so 1% under that strain nothing yields anywhere and 1% over it bonds yield both in the
    // surface layer and inside.
    let eps_y = 0.002;
    let nu = 0.3;
    let size = [0.08, 0.03, 0.03];
    let (disc, _, lambda) = block(size, [8, 3, 3], 1.5);
    let mat = support::yielding_steel(nu, eps_y, disc.horizon());
    let x = disc.rest_positions().to_vec();
    let inner = support::interior(&x, size, 0.75 * lambda);
    let surface: Vec<usize> = (0..x.len()).filter(|i| !inner.contains(i)).collect();
    assert!(!inner.is_empty() && !surface.is_empty());
    let onset = 1.5 * eps_y / (1.0 + nu);
    let fitted = ChenOptions {
        fitted_dilatation: true,
        ..ChenOptions::default()
    };
    // The model of `material` after one force update under uniaxial strain `e`.
    let pulled = |material: &ChenMaterial, opts: ChenOptions, e: f64| {
        let mut m =
            ChenModel::with_options(disc.clone(), std::slice::from_ref(material), opts).unwrap();
        let stretch = [1.0 + e, 1.0 - nu * e, 1.0 - nu * e];
        let f = [
            [stretch[0], 0.0, 0.0],
            [0.0, stretch[1], 0.0],
            [0.0, 0.0, stretch[2]],
        ];
        let mut forces = vec![[0.0; 3]; x.len()];
        m.update_forces(&affine(&x, &f, [0.0; 3]), &mut forces);
        m
    };
    for (share, expect) in [(0.99, false), (1.01, true)] {
        let m = pulled(&mat, fitted, share * onset);
        let (s, i) = (yielded_in(&m, &surface), yielded_in(&m, &inner));
        eprintln!("{share} x onset: bonds yielded at the surface {s}, inside {i}");
        assert_eq!((s > 0, i > 0), (expect, expect));
    }
    // The surface yields early, at 0.99 of the onset, with the same limit for every particle
    // (the yield strain converted with docs/model.md's b while the surface's b_i is larger), and
    // with the scalar calibration alone (its dilatation reads the edges' shear as volume
    // change).
    let mut same_limit = mat.clone();
    if let Some(p) = &mut same_limit.plasticity {
        p.from_strain = false;
    }
    let scalar = support::SCALAR;
    for (name, material, opts) in [
        ("one limit for all", &same_limit, fitted),
        ("scalar calibration", &mat, scalar),
    ] {
        let s = yielded_in(&pulled(material, opts, 0.99 * onset), &surface);
        eprintln!("{name}, 0.99 x onset: bonds yielded at the surface {s}");
        assert!(s > 0);
    }
}

/// A 6 x 3 x 3-cell bar of steel yielding at a simple-shear strain of about 1e-3 (extensions
/// capped at 0.05 of a bond), breaking at a stretch of 4e-3 when `breaking`.
fn ductile_bar(breaking: bool) -> (perifrac_physics::Discretization, ChenMaterial) {
    let (disc, _, _) = block([SIZE, SIZE / 2.0, SIZE / 2.0], [6, 3, 3], 1.5);
    let delta = disc.horizon();
    let mut mat: ChenMaterial = steel();
    let b = 15.0 * mat.shear_modulus / (2.0 * std::f64::consts::PI * delta.powi(5));
    let a_y = 2.0 * delta * b * 1e-3;
    mat.plasticity = Some(YieldParams {
        psi0: 0.5 * a_y * a_y,
        gamma_ratio: 0.05,
        from_strain: true,
    });
    mat.fracture = breaking.then_some(perifrac_physics::FractureParams {
        s_crit: 4e-3,
        alpha: 0.0,
    });
    (disc, mat)
}

/// A plastic step keeps each bond's pair of extensions a mirror of its reverse's, bit for bit:
/// the return map runs on both ends of every bond from each end (the first of a pair in the
/// dilatation pass, the second in the force pass) and the two must agree, or the force on a
/// bond would differ between its ends. Checked over steps of a ductile block under a growing,
/// uneven shear with bonds yielding and breaking, isotropic and anisotropic, and under a shear
/// that leaves the block's first third unstrained (with fracture and without): there particles
/// beside yielding ones change none of their own ends, and the force pass skips the other-end
/// map of bonds to them.
#[test]
fn a_bonds_plastic_extensions_mirror_its_reverses_bit_for_bit() {
    use perifrac_physics::ForceModel;
    let tilted = Some([[2.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]);
    for (anisotropy, localized, breaking) in [
        (None, false, true),
        (tilted, false, true),
        (None, true, true),
        (tilted, true, false),
    ] {
        let (disc, mut mat) = ductile_bar(breaking);
        mat.anisotropy = anisotropy;
        let mut m = ChenModel::new(disc.clone(), &[mat]).unwrap();
        let x = disc.rest_positions().to_vec();
        let fam = disc.family();
        let rev = fam.reverse_index();
        let mut f = vec![[0.0; 3]; x.len()];
        let mut broken = Vec::new();
        // rows whose own ends did not change in a step, beside rows that did: the force pass
        // then maps only the other ends of bonds to the changed ones
        let mut before = m.plastic_extension_pairs().unwrap().to_vec();
        let mut still_rows = 0;
        for step in 1..=6 {
            let g = 2e-3 * step as f64;
            // localized: no strain for x < SIZE / 3, ramping to twice the shear over SIZE / 4
            let ramp = |x0: f64| match localized {
                true => 2.0 * ((x0 - SIZE / 3.0) / (SIZE / 4.0)).clamp(0.0, 1.0),
                false => 1.0 + 30.0 * x0,
            };
            let y: Vec<_> = x
                .iter()
                .map(|p| {
                    [
                        p[0] + g * p[1] * ramp(p[0]),
                        p[1],
                        p[2] + 1e-4 * (80.0 * p[1]).sin() * ramp(p[0]).min(1.0),
                    ]
                })
                .collect();
            if breaking {
                m.break_bonds_and_update_forces(&y, &mut broken, &mut f);
            } else {
                m.update_forces(&y, &mut f);
            }
            let pairs = m.plastic_extension_pairs().unwrap();
            let n = x.len();
            let moved: Vec<bool> = (0..n)
                .map(|i| {
                    fam.range(i)
                        .any(|k| pairs[k][0].to_bits() != before[k][0].to_bits())
                })
                .collect();
            still_rows += (0..n)
                .filter(|&i| !moved[i] && fam.range(i).any(|k| moved[fam.neighbours()[k] as usize]))
                .count();
            before.copy_from_slice(pairs);
            for (k, p) in pairs.iter().enumerate() {
                assert_eq!(
                    p[1].to_bits(),
                    pairs[rev[k] as usize][0].to_bits(),
                    "bond {k}"
                );
            }
        }
        let ep = m.plastic_extensions().unwrap();
        let yielded = ep.iter().filter(|&&e| e != 0.0).count();
        // measured: 25,911 and 25,346 of 27,360 bonds yielded, 33 and 22 pairs broke (localized:
        // 21,927 and 22,047, 1,378 and none); both branches of the return map (and of the
        // stores) are taken
        assert!(
            yielded > ep.len() / 20 && yielded < ep.len(),
            "{yielded} of {} yielded",
            ep.len()
        );
        assert_eq!(broken.is_empty(), !breaking);
        eprintln!(
            "anisotropy {anisotropy:?}, localized {localized}: {yielded} of {} yielded, {} \
             broken, {still_rows} particle-steps unchanged beside changed ones",
            ep.len(),
            broken.len()
        );
        assert!(!localized || still_rows > 0);
    }
}

/// The passes skip the plastic extensions of rows that hold only `+0.0` (their own ends never
/// yielded, nor those of their neighbours), a record the model keeps step by step. A copy told
/// its extensions anew (`set_plastic_extensions`, which rebuilds the record from the values)
/// must then give the same forces, extensions and broken bonds, bit for bit, at every step of
/// a shear that yields one part of a ductile block and leaves another unstrained.
#[test]
fn rows_skipped_as_never_yielded_hold_only_zeros() {
    for breaking in [false, true] {
        let (disc, mat) = ductile_bar(breaking);
        let mut m = ChenModel::new(disc.clone(), &[mat]).unwrap();
        let x = disc.rest_positions().to_vec();
        let n = x.len();
        let bits = |f: &[[f64; 3]]| f.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        let (mut fa, mut fb) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
        let (mut ba, mut bb) = (Vec::new(), Vec::new());
        for step in 1..=6 {
            let g = 2e-3 * step as f64;
            // no strain for x < SIZE / 2, a shear ramping up beyond it
            let y: Vec<_> = x
                .iter()
                .map(|p| {
                    let ramp = 2.0 * ((p[0] - SIZE / 2.0) / (SIZE / 4.0)).clamp(0.0, 1.0);
                    [p[0] + g * p[1] * ramp, p[1], p[2]]
                })
                .collect();
            let mut told = m.clone();
            told.set_plastic_extensions(&m.plastic_extensions().unwrap())
                .unwrap();
            if breaking {
                m.break_bonds_and_update_forces(&y, &mut ba, &mut fa);
                told.break_bonds_and_update_forces(&y, &mut bb, &mut fb);
            } else {
                m.update_forces(&y, &mut fa);
                told.update_forces(&y, &mut fb);
            }
            assert_eq!(bits(&fa), bits(&fb), "step {step}");
            assert_eq!(ba, bb, "step {step}");
            let ep = |m: &ChenModel| {
                let e = m.plastic_extensions().unwrap();
                e.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(ep(&m), ep(&told), "step {step}");
        }
        // both kinds of row are there: some never yielded, some did (else it shows little)
        let ep = m.plastic_extensions().unwrap();
        let fam = disc.family();
        let zero_rows = (0..n)
            .filter(|&i| ep[fam.range(i)].iter().all(|&e| e == 0.0))
            .count();
        eprintln!(
            "breaking {breaking}: {zero_rows} of {n} rows never yielded, {} broken",
            ba.len()
        );
        assert!(zero_rows > 0 && zero_rows < n, "{zero_rows} of {n}");
        assert_eq!(ba.is_empty(), !breaking);
    }
}
