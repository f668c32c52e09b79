//! A material given a fracture energy `G_c` costs `G_c` per unit area of crack: a bar whose two
//! halves are pulled apart, slowly and rigidly, dissipates `G_c` times its section at every
//! resolution. The key and its neighbours are refused as they should be.

use std::path::Path;

use perifrac_scene::{Scene, Setup};

/// A bar `cells` long and `across` x `across` in section, `h` (m) a cell, of glass with the
/// fracture energy `g` (J/m^2), on the mesh `structure`.
fn bar(cells: usize, across: usize, h: f64, g: f64, structure: &str) -> String {
    format!(
        "[mesh]\nprimitive = \"box\"\nsize = [{}, {}, {}]\ncells = [{cells}, {across}, {across}]\n\
         structure = \"{structure}\"\n\n[[material]]\nyoung = 72e9\npoisson = 0.22\n\
         density = 2440.0\nfracture_energy = {g}\n\n[simulation]\nduration = 1e-6\n\
         self_contact = false\n",
        cells as f64 * h,
        across as f64 * h,
        across as f64 * h,
    )
}

/// The energy (J) that breaking dissipates while the halves of the bar in `text` (split at
/// `x_split`, m) are moved apart rigidly by a growing gap, until no bond joins them.
fn pull_apart(text: &str, x_split: f64) -> (f64, f64) {
    let scene = Scene::parse(text, Path::new("bar.toml")).unwrap();
    let mut setup = Setup::new(&scene, Some(1)).unwrap();
    let s_crit = setup.info.from_energy[0].s_crit;
    let horizon = setup.info.horizon;
    let solver = setup.driver.solver_mut();
    let rest: Vec<[f64; 3]> = solver.positions().to_vec();
    let model = solver.model_mut();
    let mut broken = Vec::new();
    let mut dissipated = 0.0;
    // the gap grows by 1% a step from a tenth of the critical extension
    let mut gap = 0.1 * s_crit * horizon;
    let mut y = rest.clone();
    loop {
        for (p, x) in y.iter_mut().zip(&rest) {
            let side = if x[0] > x_split { 0.5 } else { -0.5 };
            p[0] = x[0] + side * gap;
        }
        let before = model.elastic_energy(&y);
        broken.clear();
        model.break_bonds(&y, &mut broken);
        let after = model.elastic_energy(&y);
        dissipated += before - after;
        if gap > horizon && after <= 1e-9 * dissipated {
            break;
        }
        gap *= 1.01;
    }
    (dissipated, s_crit)
}

/// `D / (G_c A)` of a bar 8 cells long and `across` cells across (4 cm square) on `structure`,
/// with `material` and `simulation` keys added to those tables.
fn dissipated_share(
    across: usize,
    structure: &str,
    g: f64,
    material: &str,
    simulation: &str,
) -> f64 {
    let (cells, h) = (8, 0.04 / across as f64);
    let text = bar(cells, across, h, g, structure)
        .replace(
            "density = 2440.0\n",
            &format!("density = 2440.0\n{material}"),
        )
        .replace("[simulation]\n", &format!("[simulation]\n{simulation}"));
    let (d, s_crit) = pull_apart(&text, 0.5 * cells as f64 * h);
    let share = d / (g * (across as f64 * h).powi(2));
    eprintln!(
        "{structure} {material:?} {simulation:?}, {across} across: s_crit {s_crit:.4e}, \
         D / (G_c A) = {share:.4}"
    );
    share
}

#[test]
fn a_bar_pulled_apart_dissipates_its_fracture_energy() {
    // Three resolutions of the default (unstructured) mesh and one of the Kuhn lattice. The
    // threshold is set from whole families, and a section's edge, where families are cut and
    // their constants scaled up, costs a little more. The bulk, from two widths' difference
    // (`bulk_by_width_difference`), is 0.993 to 0.998 unstructured and 0.943 to 0.946 on the
    // lattice. Measured here: 1.047, 1.038, 1.021 (8, 12, 16 across) and 0.962 (the lattice,
    // 12 across). The issue asks for 10%.
    for (across, structure) in [
        (8, "unstructured"),
        (12, "unstructured"),
        (16, "unstructured"),
        (12, "lattice"),
    ] {
        let share = dissipated_share(across, structure, 8.0, "", "");
        assert!(
            (share - 1.0).abs() < 0.1,
            "{structure}, {across} across: {share}"
        );
    }
}

#[test]
fn xu_bars_dissipate_their_fracture_energy() {
    // Xu's model: glass at its brittle threshold on the fitted dilatation at two resolutions
    // and on the normalised one; and a material whose bonds break where the curves are far
    // from quadratic (G_c = 2e8 J/m^2: s_crit 0.49). The threshold follows from a rigid
    // opening with the weights normalised again at each break, as the model does; from the
    // state with every crossing bond at the threshold at once, the bars dissipated 1.19 to
    // 1.20 G_c. Measured: 1.071 and 1.034 (8 and 16 across; 1.060 at 12), 1.059 without the
    // fit, 1.057 at s_crit 0.49, 1.060 with St Venant-Kirchhoff's curve (12 across). As for
    // Chen's model, the excess is the section's edge and shrinks with the resolution: the bulk
    // (`bulk_by_width_difference`) is 0.998, 0.992 and 1.000. The issue asks for 10%.
    let xu = "model = \"xu\"\n";
    for (across, g, material, simulation) in [
        (8, 8.0, xu, ""),
        (16, 8.0, xu, ""),
        (12, 8.0, xu, "correction = \"none\"\n"),
        (12, 2e8, xu, ""),
    ] {
        let share = dissipated_share(across, "unstructured", g, material, simulation);
        assert!(
            (share - 1.0).abs() < 0.1,
            "{material:?} {simulation:?}, {across} across: {share}"
        );
    }
}

#[test]
#[ignore = "a measurement (about 20 minutes): cargo test -p perifrac-scene --test fracture_energy -- --ignored --nocapture"]
fn bulk_by_width_difference() {
    // D(W) = G W^2 + 4 gamma W for a square section of side W, gamma the energy a unit length
    // of the section's edge adds: two widths at one cell size give G alone
    let g = 8.0;
    for (structure, material) in [
        ("lattice", ""),
        ("unstructured", ""),
        ("unstructured", "model = \"xu\"\n"),
    ] {
        for across in [8usize, 12, 16] {
            let (cells, h) = (8, 0.04 / across as f64);
            let x_split = 0.5 * cells as f64 * h;
            let text = |n: usize| {
                bar(cells, n, h, g, structure).replace(
                    "density = 2440.0\n",
                    &format!("density = 2440.0\n{material}"),
                )
            };
            let (d1, _) = pull_apart(&text(across), x_split);
            let (d2, _) = pull_apart(&text(2 * across), x_split);
            let (w1, w2) = (across as f64 * h, 2.0 * across as f64 * h);
            let bulk = (d2 / w2 - d1 / w1) / (w2 - w1);
            eprintln!(
                "{structure} {material:?}, {across} across: D / (G_c A) = {:.4}, the bulk's {:.4}",
                d1 / (g * w1 * w1),
                bulk / g
            );
        }
    }
}

#[test]
fn fracture_energy_is_refused_beside_s_crit_or_when_not_positive() {
    let base = bar(4, 2, 0.01, 8.0, "lattice");
    let refusal = |text: String| {
        let scene = match Scene::parse(&text, Path::new("bar.toml")) {
            Ok(s) => s,
            Err(e) => return e.to_string(),
        };
        match Setup::new(&scene, Some(1)) {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e.to_string(),
        }
    };
    for other in ["s_crit = 1e-4", "tensile_strength = 5e7"] {
        let both = refusal(base.replace(
            "fracture_energy = 8",
            &format!("fracture_energy = 8\n{other}"),
        ));
        assert!(
            both.contains("material[0]") && both.contains("give one of"),
            "{both}"
        );
    }
    for bad in ["0.0", "-3.0", "nan"] {
        let e = refusal(base.replace("fracture_energy = 8", &format!("tensile_strength = {bad}")));
        assert!(
            e.contains("material[0].tensile_strength") && e.contains("must be positive"),
            "{bad}: {e}"
        );
    }
    for bad in ["0.0", "-3.0", "nan"] {
        let e = refusal(base.replace("fracture_energy = 8", &format!("fracture_energy = {bad}")));
        assert!(
            e.contains("material[0].fracture_energy") && e.contains("must be positive"),
            "{bad}: {e}"
        );
    }
    // Xu's model refuses them alike
    let xu = refusal(base.replace(
        "fracture_energy = 8",
        "fracture_energy = -8\nmodel = \"xu\"",
    ));
    assert!(xu.contains("material[0].fracture_energy"), "{xu}");
    // and alpha scales either threshold
    let scene = Scene::parse(
        &base.replace("fracture_energy = 8", "fracture_energy = 8\nalpha = 0.5"),
        Path::new("bar.toml"),
    )
    .unwrap();
    assert!(Setup::new(&scene, Some(1)).is_ok());
}

/// The bar of [`bar`] with `threshold` in place of its fracture energy, its left end held and
/// its right end pulled at 0.5 m/s for [`STEPS`] steps: broken bonds and damage.
const STEPS: usize = 40;

fn pulled_bar(threshold: &str) -> (u64, Vec<f64>) {
    let text = bar(8, 2, 0.01, 8.0, "lattice").replace("fracture_energy = 8", threshold)
        + "\n[[anchor]]\nregion = { min = [-1.0, -1.0, -1.0], max = [0.01, 1.0, 1.0] }\n\n\
           [[anchor]]\nregion = { min = [0.07, -1.0, -1.0], max = [1.0, 1.0, 1.0] }\n\
           velocity = [0.5, 0.0, 0.0]\n";
    let scene = Scene::parse(&text, Path::new("bar.toml")).unwrap();
    let mut setup = Setup::new(&scene, Some(1)).unwrap();
    for _ in 0..STEPS {
        setup.driver.step().unwrap();
    }
    (setup.driver.broken_bonds(), setup.driver.damage())
}

#[test]
fn tensile_strength_is_s_crit_times_young() {
    // 72e9 Pa x 2e-4 = 14.4 MPa: the same threshold, so the same bonds break
    let by_strain = pulled_bar("s_crit = 2e-4");
    let by_strength = pulled_bar("tensile_strength = 14.4e6");
    assert!(by_strain.0 > 0, "nothing broke");
    assert_eq!(by_strain.0, by_strength.0);
    assert_eq!(by_strain.1, by_strength.1);
    // 5% more strength breaks fewer bonds: the pull is still under way
    let stronger = pulled_bar("tensile_strength = 15.12e6").0;
    eprintln!(
        "broken: {} at 14.4 MPa, {stronger} at 15.12 MPa",
        by_strain.0
    );
    assert!(stronger < by_strain.0, "{stronger} against {}", by_strain.0);
}
