//! Material presets fill the keys a material does not give, and only those.

use std::path::Path;

use perifrac_scene::schema::Preset;
use perifrac_scene::setup::presets::values;
use perifrac_scene::{Scene, SceneError, Setup};

/// A 2 x 1 x 1 cm box of one material with the keys `material`.
fn scene(material: &str) -> String {
    format!(
        "[mesh]\nprimitive = \"box\"\nsize = [0.02, 0.01, 0.01]\ncells = [4, 2, 2]\n\
         structure = \"lattice\"\n\n[[material]]\n{material}\n\n[simulation]\nduration = 1e-6\n\
         self_contact = false\n"
    )
}

fn setup(material: &str) -> Result<Setup, SceneError> {
    let scene = Scene::parse(&scene(material), Path::new("p.toml"))?;
    Setup::new(&scene, Some(1))
}

#[test]
fn a_preset_is_the_keys_it_stands_for() {
    // glass as a preset and glass spelt out: the same mass, stable step and threshold
    let glass = values(Preset::Glass);
    let preset = setup("preset = \"glass\"").unwrap();
    let spelt = setup(&format!(
        "young = {:e}\npoisson = {}\ndensity = {}\nfracture_energy = {}",
        glass.young, glass.poisson, glass.density, glass.fracture_energy
    ))
    .unwrap();
    assert_eq!(preset.info.mass, spelt.info.mass);
    assert_eq!(preset.info.dt_limit, spelt.info.dt_limit);
    assert_eq!(preset.info.from_energy, spelt.info.from_energy);
    assert_eq!(
        preset.info.from_energy[0].fracture_energy,
        glass.fracture_energy
    );
    // 2 cm^3 of glass
    assert!((preset.info.mass / (glass.density * 2e-6) - 1.0).abs() < 1e-12);
    // every preset loads, with both models
    for name in [
        "glass",
        "ceramic",
        "concrete",
        "steel",
        "aluminium",
        "rubber",
        "acrylic",
    ] {
        for model in ["chen", "xu"] {
            let s = setup(&format!("preset = \"{name}\"\nmodel = \"{model}\""));
            assert!(
                s.is_ok(),
                "{name}, {model}: {:?}",
                s.err().map(|e| e.to_string())
            );
        }
    }
}

#[test]
fn a_key_given_overrides_the_preset() {
    let glass = values(Preset::Glass);
    let heavy = setup("preset = \"glass\"\ndensity = 4880.0").unwrap();
    assert!((heavy.info.mass / (2.0 * glass.density * 2e-6) - 1.0).abs() < 1e-12);
    // s_crit in place of the preset's fracture energy: no threshold from an energy
    let raw = setup("preset = \"glass\"\ns_crit = 1e-4").unwrap();
    assert!(raw.info.from_energy.is_empty());
    // moduli as bulk and shear replace young and poisson
    assert!(setup("preset = \"glass\"\nbulk_modulus = 4e10\nshear_modulus = 3e10").is_ok());
    // inf: the preset's material, unbreakable
    let tough = setup("preset = \"glass\"\nfracture_energy = inf").unwrap();
    assert!(tough.info.from_energy.is_empty());
}

#[test]
fn an_unknown_preset_or_a_missing_density_is_refused() {
    let e = setup("preset = \"glas\"").err().unwrap().to_string();
    assert!(e.contains("preset") && e.contains("`glass`"), "{e}");
    let e = setup("young = 1e9\npoisson = 0.3")
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("material[0].density") && e.contains("preset"),
        "{e}"
    );
}

#[test]
fn docs_scenes_md_lists_the_presets_values() {
    // the table of docs/scenes.md, "Material presets", rounds to three or four figures
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scenes.md");
    let text = std::fs::read_to_string(path).unwrap();
    let presets = [
        ("glass", Preset::Glass),
        ("ceramic", Preset::Ceramic),
        ("concrete", Preset::Concrete),
        ("steel", Preset::Steel),
        ("aluminium", Preset::Aluminium),
        ("rubber", Preset::Rubber),
        ("acrylic", Preset::Acrylic),
    ];
    for (name, p) in presets {
        let row = text
            .lines()
            .find(|l| l.starts_with(&format!("| `\"{name}\"` |")))
            .unwrap_or_else(|| panic!("no row for {name}"));
        let cells: Vec<f64> = row
            .split('|')
            .skip(2)
            .take(4)
            .map(|c| c.trim().parse().unwrap())
            .collect();
        let v = values(p);
        for (doc, code) in cells
            .iter()
            .zip([v.young, v.poisson, v.density, v.fracture_energy])
        {
            assert!(
                (doc / code - 1.0).abs() < 2e-3,
                "{name}: {doc} against {code}"
            );
        }
    }
}
