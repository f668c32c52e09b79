//! The lane loops ([`super::lanes`]) against the scalar kernel, bit for bit, on every path that
//! takes them: a model run twice, once with its packed records dropped (which sends every pass
//! to the scalar loops).

use super::*;
use crate::{ForceModel, FractureParams, YieldParams};
use perifrac_topology::primitives::{lattice_box_data, Lattice};
use perifrac_topology::TetMesh;

/// A 4 x 4 x 3-cell Kuhn block of 1 cm cells (288 particles, 22,678 bonds), horizon 1.45 mean
/// edges: rows of 37 to 142 bonds, every count of tail bonds after the last chunk of four
/// occurring (50, 64, 100 and 74 rows with 0 to 3).
fn block() -> Discretization {
    let cells = [4, 4, 3];
    let size = cells.map(|c| c as f64 * 0.01);
    let (v, t) = lattice_box_data([0.0; 3], size, cells, Lattice::Kuhn);
    let (mesh, _) = TetMesh::new(v, t).expect("a valid box");
    let x = mesh.rest_barycentres();
    let delta = 1.45 * mesh.mean_edge_length();
    Discretization::from_tets(&x, &mesh.rest_volumes(), mesh.neighbours(), delta)
        .expect("a valid family")
        .0
}

/// Positions at step `s`: a stretch along x and a shear, both growing with `s` and with x from
/// nothing at x = 0 (so part of the block stays elastic while the rest yields or breaks), a
/// bend, and a fixed jitter of 1e-6 of the cell (so no two bonds share an extension).
fn positions(x: &[Vec3], s: usize) -> Vec<Vec3> {
    let noise = crate::stable_step::start_vector(x.len());
    let stretch = 2e-4 * s as f64;
    x.iter()
        .zip(noise)
        .map(|(p, n)| {
            // x / 4 cm, 0 to 1 along the block
            let t = p[0] / 0.04;
            [
                p[0] + stretch * t * p[0] + 2e-4 * t * p[1] + 1e-8 * n[0],
                p[1] - 1e-4 * t * p[2] + 1e-8 * n[1],
                p[2] + 3e-3 * p[0] * p[0] + 1e-8 * n[2],
            ]
        })
        .collect()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn force_bits(f: &[Vec3]) -> Vec<u64> {
    f.iter().flatten().map(|x| x.to_bits()).collect()
}

/// Steps a model and its scalar twin through [`positions`] and asserts every force, dilatation,
/// plastic extension, bond state and broken bond is the same bit for bit. Returns the bonds
/// broken, the plastic extensions changed and the rows that never held one (which took the
/// lanes wherever the yield bound cleared them), so a case can show it exercised what it names.
fn same_bits(material: &ChenMaterial, options: ChenOptions) -> (usize, usize, usize) {
    let disc = block();
    let x = disc.rest_positions().to_vec();
    let mut lanes = ChenModel::with_options(disc, std::slice::from_ref(material), options)
        .expect("a valid model");
    assert_eq!(lanes.packed.len(), x.len(), "the lane loops apply");
    let mut scalar = lanes.clone();
    scalar.packed = Vec::new();
    let (mut fl, mut fs) = (vec![[0.0; 3]; x.len()], vec![[0.0; 3]; x.len()]);
    let (mut bl, mut bs) = (Vec::new(), Vec::new());
    for s in 0..8 {
        let y = positions(&x, s);
        lanes.break_bonds_and_update_forces(&y, &mut bl, &mut fl);
        scalar.break_bonds_and_update_forces(&y, &mut bs, &mut fs);
        assert_eq!(force_bits(&fl), force_bits(&fs), "forces at step {s}");
        assert_eq!(bits(&lanes.dilatations()), bits(&scalar.dilatations()));
        assert_eq!(bl, bs, "bonds broken by step {s}");
        assert_eq!(
            lanes.plastic_extensions().map(|e| bits(&e)),
            scalar.plastic_extensions().map(|e| bits(&e))
        );
        assert_eq!(
            lanes.damage().map(|d| d.bond_state().to_vec()),
            scalar.damage().map(|d| d.bond_state().to_vec())
        );
        // the energy's own dilatation pass, and a trial evaluation, as the event search runs
        assert_eq!(
            lanes.elastic_energy(&y).to_bits(),
            scalar.elastic_energy(&y).to_bits()
        );
        lanes.trial_forces(&y, &mut fl);
        scalar.trial_forces(&y, &mut fs);
        assert_eq!(force_bits(&fl), force_bits(&fs), "trial forces at step {s}");
    }
    let fam = lanes.discretization().family();
    let (yielded, clean) = lanes.plastic_extensions().map_or((0, 0), |e| {
        let rows = (0..fam.len()).filter(|&i| e[fam.range(i)].iter().all(|&e| e == 0.0));
        (e.iter().filter(|&&e| e != 0.0).count(), rows.count())
    });
    (bl.len(), yielded, clean)
}

fn glass() -> ChenMaterial {
    ChenMaterial::from_young_poisson(70e9, 0.22, 2500.0).expect("valid constants")
}

/// Every combination of the options the lanes read (fitted weights or not, the moment term
/// or not).
fn options() -> [ChenOptions; 4] {
    [(true, true), (true, false), (false, true), (false, false)].map(|(fitted, moment)| {
        ChenOptions {
            fitted_dilatation: fitted,
            energy_consistent: moment,
            ..ChenOptions::default()
        }
    })
}

#[test]
fn elastic_and_brittle_lanes_keep_the_scalar_bits() {
    // s_crit where bonds of the stretched end break at the later steps (measured: 6,022 of
    // 22,678), leaving rows with broken bonds in and out of chunks of four
    let mut brittle = glass();
    brittle.fracture = Some(FractureParams {
        s_crit: 2.0e-4,
        alpha: 0.0,
    });
    for o in options() {
        assert_eq!(same_bits(&glass(), o).0, 0);
        let (broken, _, _) = same_bits(&brittle, o);
        assert!(
            broken > 1000,
            "{broken} bonds broken: the masked chunks untested"
        );
    }
}

#[test]
fn plastic_and_ductile_lanes_keep_the_scalar_bits() {
    // a yield limit that part of the block passes as the strain grows along x (measured over
    // the four option sets: 1,560 to 2,340 extensions nonzero after the last step, 50 to 68 of
    // the 288 rows never yielding, 917 to 933 bonds broken with fracture): rows the bound
    // clears (the lanes), rows it does not (the scalar loop after the lanes' try), rows that
    // yielded (the scalar loop only)
    for fracture in [None, Some(1.0e-3)] {
        let mut m = glass();
        m.plasticity = Some(YieldParams {
            psi0: 1.0e31,
            gamma_ratio: 0.2,
            from_strain: false,
        });
        m.fracture = fracture.map(|s_crit| FractureParams { s_crit, alpha: 0.0 });
        for o in options() {
            let (broken, yielded, clean) = same_bits(&m, o);
            assert!(
                yielded > 1000,
                "{yielded} extensions yielded: the scalar rows untested"
            );
            assert!(clean > 30, "{clean} rows never yielded: the lanes untested");
            if fracture.is_some() {
                assert!(
                    broken > 500,
                    "{broken} bonds broken: the masked chunks untested"
                );
            }
        }
    }
}
