//! Material presets: handbook constants for the keys a `[[material]]` does not give
//! (docs/scenes.md, "Material presets", cites each value).

use crate::schema::{MaterialSpec, Preset, SceneFile};

/// The constants of one preset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PresetValues {
    /// Young's modulus (Pa).
    pub young: f64,
    /// Poisson's ratio (1).
    pub poisson: f64,
    /// Density (kg/m^3).
    pub density: f64,
    /// Fracture energy `G_c` (J/m^2).
    pub fracture_energy: f64,
}

/// `K_IC^2 (1 - nu^2) / E` (J/m^2): the plane-strain fracture energy of a toughness `k_ic`
/// (Pa m^0.5), Young's modulus `young` (Pa) and Poisson's ratio `nu`.
fn from_toughness(k_ic: f64, young: f64, nu: f64) -> f64 {
    k_ic * k_ic * (1.0 - nu * nu) / young
}

/// The constants of preset `p`.
pub fn values(p: Preset) -> PresetValues {
    let (young, poisson, density, k_ic) = match p {
        Preset::Glass => (72e9, 0.22, 2440.0, 0.75e6),
        Preset::Ceramic => (370e9, 0.22, 3900.0, 4.0e6),
        Preset::Steel => (210e9, 0.3, 7850.0, 100e6),
        Preset::Aluminium => (69e9, 0.33, 2700.0, 29e6),
        Preset::Acrylic => (3.2e9, 0.35, 1190.0, 1.0e6),
        // fib Model Code 2010 for C30: E_ci = 21.5 GPa (f_cm / 10)^(1/3), G_F = 73 f_cm^0.18
        Preset::Concrete => {
            let f_cm: f64 = 38.0;
            return PresetValues {
                young: 21.5e9 * (f_cm / 10.0).cbrt(),
                poisson: 0.2,
                density: 2400.0,
                fracture_energy: 73.0 * f_cm.powf(0.18),
            };
        }
        // a rubber's toughness is its tearing energy, not a K_IC
        Preset::Rubber => {
            return PresetValues {
                young: 2e6,
                poisson: 0.49,
                density: 930.0,
                fracture_energy: 1e4,
            }
        }
    };
    PresetValues {
        young,
        poisson,
        density,
        fracture_energy: from_toughness(k_ic, young, poisson),
    }
}

/// `f` with each material's preset filling the keys it does not give. Young's modulus and
/// Poisson's ratio are filled only where neither `bulk_modulus` nor `shear_modulus` is given;
/// the fracture energy only where none of `s_crit`, `tensile_strength` and `fracture_energy`
/// is.
pub(super) fn resolve(f: &SceneFile) -> SceneFile {
    let mut out = f.clone();
    for m in &mut out.material {
        fill(m);
    }
    out
}

/// Fills `m`'s absent keys from its preset.
fn fill(m: &mut MaterialSpec) {
    let Some(p) = m.preset else { return };
    let v = values(p);
    if m.bulk_modulus.is_none() && m.shear_modulus.is_none() {
        m.young.get_or_insert(v.young);
        m.poisson.get_or_insert(v.poisson);
    }
    m.density.get_or_insert(v.density);
    if m.s_crit.is_none() && m.tensile_strength.is_none() {
        m.fracture_energy.get_or_insert(v.fracture_energy);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_toughness_gives_the_handbook_fracture_energies() {
        // G_c from K_IC by hand: glass 0.75^2 (1 - 0.22^2) / 72e-3 = 7.43 J/m^2; steel
        // 100^2 (1 - 0.09) / 210e-3 = 43,333 J/m^2; concrete 73 * 38^0.18 = 140.5 J/m^2
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-3;
        assert!(close(values(Preset::Glass).fracture_energy, 7.434));
        assert!(close(values(Preset::Steel).fracture_energy, 43_333.3));
        assert!(close(values(Preset::Concrete).fracture_energy, 140.51));
        assert!(close(values(Preset::Concrete).young, 33.54e9));
    }
}
