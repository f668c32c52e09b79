//! The scene file (TOML) of perifrac: what a user writes, as typed Rust.
//!
//! A solid scene is a [`SceneFile`]; a thin-shell scene, which has a `[shell]` table in place
//! of `[mesh]`, is a [`shell::ShellSceneFile`]. [`parse`] reads either. Every table rejects
//! unknown keys, so a typo is an error with its line, column and key rather than a silently
//! ignored setting. A choice (a material's `model`, the `integrator`) is an enum whose variants
//! own their keys, so a key of another variant is refused too, with the variant that takes it.
//!
//! Units are SI: metres, seconds, kilograms, pascals.
//!
//! ```
//! let text = "[mesh]\nprimitive = \"box\"\n[[material]]\nyoung = 1e9\npoisson = 0.25\n\
//!             density = 1000.0\n[simulation]\nduration = 1e-3\niterations = 5\n";
//! let e = perifrac_schema::parse::<perifrac_schema::SceneFile>(text).unwrap_err();
//! assert_eq!((e.line, e.column), (9, 1));
//! assert!(e.message.starts_with("simulation.iterations: a key of integrator = \"implicit\""));
//! ```

#![warn(missing_docs)]

use serde::Deserialize;
use std::ops::Range;
use std::path::PathBuf;

mod choice;
pub mod shell;
mod variants;

pub use choice::Schema;
pub use variants::*;

use choice::{
    all_keys, keys_of, split, table_mut, tables_mut, variants_of, Choice, Hints, Named, Refusal,
};
use toml::de::DeTable;

/// Why a scene's text does not parse, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    /// What is wrong, led by the key's path (`material[1].young: ...`) where there is one.
    pub message: String,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.message)
    }
}

impl std::error::Error for ParseError {}

/// Parses `text` into the tables `T` ([`SceneFile`] or [`shell::ShellSceneFile`]), with line,
/// column and key in every syntax or schema error; a key refused for belonging to another
/// choice says which takes it.
pub fn parse<T: Schema>(text: &str) -> Result<T, ParseError> {
    let at = |span: Option<Range<usize>>, message: &str| {
        let (line, column) = span.map(|s| line_column(text, s.start)).unwrap_or((1, 1));
        ParseError {
            line,
            column,
            message: message.trim().to_string(),
        }
    };
    let mut doc = DeTable::parse(text).map_err(|e| at(e.span(), e.message()))?;
    let mut hints = Hints::default();
    hints.index(doc.get_ref());
    T::prepare(doc.get_mut(), &mut hints).map_err(|r| {
        at(
            Some(r.span.clone()),
            &hints.message(Some(r.span), &r.message),
        )
    })?;
    T::deserialize(toml::de::Deserializer::from(doc))
        .map_err(|e| at(e.span(), &hints.message(e.span(), e.message())))
}

/// Whether `text` is a thin-shell scene (has a top-level `shell` table). Text that is not TOML
/// is not one (the solid scene parser reports its syntax error).
pub fn is_shell_scene(text: &str) -> bool {
    DeTable::parse(text).is_ok_and(|t| t.get_ref().contains_key("shell"))
}

/// 1-based line and column (in characters) of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// The peridynamic force models a solid scene can use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// Chen et al. 2018: elastoplastic, state-based (docs/model.md section 2).
    Chen,
    /// Xu et al. 2018: hyperelastic (docs/model.md section 5).
    Xu,
}

impl ModelKind {
    /// Its name in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Chen => "chen",
            ModelKind::Xu => "xu",
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A whole scene file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// What is simulated (a primitive or a mesh file).
    pub mesh: MeshSpec,
    /// Materials; the first without a `region` is the default, later regions override earlier.
    pub material: Vec<MaterialSpec>,
    /// Time stepping, horizon, loads.
    pub simulation: SimulationSpec,
    /// Ground planes.
    #[serde(default)]
    pub ground: Vec<GroundSpec>,
    /// Spheres (kinematic or dynamic).
    #[serde(default)]
    pub ball: Vec<BallSpec>,
    /// Particles held fixed or moved at a prescribed velocity.
    #[serde(default)]
    pub anchor: Vec<AnchorSpec>,
    /// Initial velocities.
    #[serde(default)]
    pub velocity: Vec<VelocitySpec>,
    /// Cracks present at the start.
    #[serde(default)]
    pub precrack: Vec<PrecrackSpec>,
    /// Tractions, pressures and body forces on regions.
    #[serde(default)]
    pub load: Vec<LoadSpec>,
    /// What is written, and how often.
    #[serde(default)]
    pub output: OutputSpec,
}

/// The object: a built-in primitive or a file.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// `"box"`, `"sphere"` or `"cylinder"` (along z); exclusive with `file`.
    pub primitive: Option<String>,
    /// A tet mesh (`.mesh`, `.node`/`.ele`, `.msh`, `.vtk`) or a closed surface (`.obj`, `.off`,
    /// `.ply`, meshed with the built-in mesher), relative to the scene file.
    pub file: Option<PathBuf>,
    /// Box extent along x, y, z (m).
    pub size: Option<[f64; 3]>,
    /// Sphere or cylinder radius (m).
    pub radius: Option<f64>,
    /// Cylinder height (m).
    pub height: Option<f64>,
    /// Box cells along x, y, z (6 tets each).
    pub cells: Option<[usize; 3]>,
    /// How a box is cut into tets: `"unstructured"` (default: a Delaunay mesh of well-spaced
    /// random points, as many tets as the cells would give, no direction preferred) or
    /// `"lattice"` (every cell into the same six Kuhn tets) or `"mirrored"` (the Kuhn tets
    /// mirrored in every other cell along each axis: a box of even counts is mirror-symmetric).
    pub structure: Option<String>,
    /// Seed of an unstructured box's points (default 1): another seed, another mesh of the
    /// same size.
    pub seed: Option<u64>,
    /// Cells across the longest side (boxes), or lattice resolution (surfaces, round primitives).
    pub resolution: Option<usize>,
    /// Uniform scale applied to the mesh's coordinates, a file's or a primitive's (before
    /// `translate`).
    pub scale: Option<f64>,
    /// Translation (m) applied last; boxes start at the origin, spheres are centred on it.
    pub translate: Option<[f64; 3]>,
}

/// An axis-aligned box of rest positions (m).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Region {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

impl Region {
    /// Whether `p` lies in the closed box.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|k| p[k] >= self.min[k] && p[k] <= self.max[k])
    }
}

/// One material: Chen's elastoplastic model with fracture (docs/model.md section 2, the default) or
/// Xu's hyperelastic one (section 5). Every material of a scene uses the same model.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// A name for messages.
    pub name: Option<String>,
    /// Handbook constants (`young`, `poisson`, `density`, `fracture_energy`) for the keys not given.
    pub preset: Option<Preset>,
    /// Particles whose rest barycentre lies in this box get this material.
    pub region: Option<Region>,
    /// Young's modulus (Pa), with `poisson`; or give `bulk_modulus` and `shear_modulus`.
    pub young: Option<f64>,
    /// Poisson's ratio.
    pub poisson: Option<f64>,
    /// Bulk modulus kappa (Pa), as in the paper's Table 1.
    pub bulk_modulus: Option<f64>,
    /// Shear modulus mu (Pa).
    pub shear_modulus: Option<f64>,
    /// Density (kg/m^3); a `preset` gives one.
    pub density: Option<f64>,
    /// Critical stretch measure `s_crit` (dimensionless); absent or `inf`: no fracture.
    pub s_crit: Option<f64>,
    /// Fracture energy `G_c` (J/m^2): what a unit area of crack costs. The bond threshold
    /// follows from it, the model's energy and the horizon; give it or `s_crit`.
    pub fracture_energy: Option<f64>,
    /// Tensile strength (Pa): `s_crit` is it over Young's modulus, the strain at which bonds a
    /// horizon long break under uniform tension; give it, `s_crit` or `fracture_energy`.
    pub tensile_strength: Option<f64>,
    /// Damage scaling of the threshold (default 0).
    pub alpha: Option<f64>,
    /// Anisotropy (default isotropic). Chen: the diagonal of `G` in `omega = delta / |G xi|`
    /// along `axes`; Xu: `Sigma = diag(s1, s2, s3)`, `s1 s2 s3 = 1`, along `axes`.
    pub anisotropy: Option<[f64; 3]>,
    /// The material axes of `anisotropy`, three orthonormal vectors (default x, y, z).
    pub axes: Option<[[f64; 3]; 3]>,
    /// The force model, `"chen"` (default) or `"xu"`, with the keys only it takes.
    pub model: MaterialModel,
}

/// `dt = "auto"` or a number of seconds.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum DtSpec {
    /// A fixed step (s).
    Seconds(f64),
    /// Only `"auto"` is accepted.
    Word(String),
}

/// Time stepping and global loads.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Horizon as a multiple of the mean tet edge length (default 1.45, the paper's).
    pub horizon_factor: Option<f64>,
    /// Time step: `"auto"` (default) or seconds; a fixed step above the stable limit is refused.
    pub dt: Option<DtSpec>,
    /// Simulated duration (s).
    pub duration: f64,
    /// Gravity (m/s^2), default none.
    pub gravity: Option<[f64; 3]>,
    /// Mass-proportional damping (1/s), default 0.
    pub damping: Option<f64>,
    /// Contact radius of a particle as a multiple of its volume-equivalent radius, capped on the
    /// boundary at the distance to the surface (default 1; see `setup::radii`).
    pub contact_radius: Option<f64>,
    /// The inversion guard's factor on the rest bond stiffness (default none): springs towards
    /// each particle's affine deformation that keep a crushed body from folding through itself.
    pub inversion_guard: Option<f64>,
    /// Contact between particles that share no intact bond: fragments and the faces of cracks
    /// push each other apart (default: on when a material can break).
    pub self_contact: Option<bool>,
    /// Self contact: penalty stiffness of a particle as a multiple of `E r_p` (default 0.25).
    pub self_contact_stiffness: Option<f64>,
    /// Self contact: contact distance as a multiple of the sum of two contact radii
    /// (default 1.3).
    pub self_contact_distance: Option<f64>,
    /// Self contact: normal damping as a fraction of critical (default 0.1).
    pub self_contact_damping: Option<f64>,
    /// Self contact: Coulomb friction coefficient (default 0.5).
    pub self_contact_friction: Option<f64>,
    /// The integrator, `"explicit"` (default) or `"implicit"`, with the keys only it takes.
    pub integrator: Integrator,
    /// The keys of the materials' model (named in `[[material]]`, not here).
    pub model: SimulationModel,
}

/// A ground plane (half-space) through `point` with outward `normal`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// A point on the plane (m); default the origin.
    pub point: Option<[f64; 3]>,
    /// Outward normal (default +z).
    pub normal: Option<[f64; 3]>,
    /// Penalty stiffness as a multiple of `E r_p` (default 1).
    pub stiffness_factor: Option<f64>,
    /// Normal damping as a fraction of critical (default 0.1).
    pub damping_ratio: Option<f64>,
    /// Coulomb friction coefficient (default 0.5).
    pub friction: Option<f64>,
}

/// A sphere collider.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BallSpec {
    /// Centre at the start (m).
    pub center: [f64; 3],
    /// Radius (m).
    pub radius: f64,
    /// Velocity (m/s): constant for a kinematic ball, initial for a dynamic one.
    pub velocity: Option<[f64; 3]>,
    /// Time (s) at which a kinematic ball stops and holds where it is (a press at its depth),
    /// default never; not for a dynamic ball.
    pub until: Option<f64>,
    /// Mass (kg): the ball is dynamic (gravity, reactions) when a mass or density is given.
    pub mass: Option<f64>,
    /// Density (kg/m^3), the alternative to `mass`.
    pub density: Option<f64>,
    /// Penalty stiffness as a multiple of `E r_p` (default 1).
    pub stiffness_factor: Option<f64>,
    /// Normal damping as a fraction of critical (default 0.1).
    pub damping_ratio: Option<f64>,
    /// Coulomb friction coefficient (default 0.5).
    pub friction: Option<f64>,
}

/// Particles in a region held on a prescribed rigid motion: a translation at `velocity` (zero:
/// fixed) and a rotation at `angular` about an axis through `center`, which moves with
/// `velocity`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AnchorSpec {
    /// Which particles (rest barycentres in the box).
    pub region: Region,
    /// Prescribed velocity (m/s), default zero.
    pub velocity: Option<[f64; 3]>,
    /// Angular velocity (rad/s, axis times rate), default none.
    pub angular: Option<[f64; 3]>,
    /// A point of the rotation axis at time 0 (m), default the centroid of the anchored
    /// particles' rest positions.
    pub center: Option<[f64; 3]>,
    /// Time (s) at which the particles are released, default never.
    pub until: Option<f64>,
}

/// Initial velocity of the particles in a region (all when absent): `linear + angular x (X - center)`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VelocitySpec {
    /// Which particles; default all.
    pub region: Option<Region>,
    /// Linear velocity (m/s).
    pub linear: Option<[f64; 3]>,
    /// Angular velocity (rad/s) about `center`.
    pub angular: Option<[f64; 3]>,
    /// Centre of rotation (m), default the centre of the rest bounding box.
    pub center: Option<[f64; 3]>,
}

/// An initial crack: the faces between tets on opposite sides of the plane, within the box.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PrecrackSpec {
    /// A point on the crack plane (m).
    pub point: [f64; 3],
    /// The plane's normal.
    pub normal: [f64; 3],
    /// Faces whose centroid lies in this box are cut.
    pub region: Region,
}

/// A load on a region, fixed in the rest frame (a dead load): a traction or a pressure on the
/// boundary faces whose centroid lies in the region, or a body force on the particles whose
/// rest barycentre does. Give exactly one of `traction`, `pressure` and `body_force`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Where it acts; default everywhere.
    pub region: Option<Region>,
    /// Traction (Pa): force per unit rest area of the boundary faces.
    pub traction: Option<[f64; 3]>,
    /// Pressure (Pa) on the boundary faces, along each face's inward rest normal.
    pub pressure: Option<f64>,
    /// Body force (N/m^3) on the particles.
    pub body_force: Option<[f64; 3]>,
    /// Time (s) over which the load rises linearly from zero; default 0: at once.
    pub ramp: Option<f64>,
    /// Time (s) at which the load stops; default never.
    pub until: Option<f64>,
}

/// Frame output.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Number of frames after the initial one (default 24); `perifrac run --frames` overrides.
    pub frames: Option<usize>,
    /// Also write POV-Ray `mesh2` includes (default true).
    pub povray: Option<bool>,
    /// Also write particles with damage as PLY points (default true).
    pub particles: Option<bool>,
    /// Write a checkpoint (`checkpoint.bin`) after every this many frames; 0: only when the
    /// run is interrupted; unset: after the first frame that ends five minutes or more of
    /// wall time after the last checkpoint.
    pub checkpoint_every: Option<usize>,
    /// Also write the run as one USD cache, `NAME.usda` (default false).
    pub usd: Option<bool>,
    /// Lay the USD cache out as one prim per fragment, pivoted at its centre of mass (default
    /// false: one mesh).
    pub usd_pieces: Option<bool>,
    /// Playback frames per second of the USD cache (default 24): the simulated time between
    /// two frames plays in one frame.
    pub fps: Option<f64>,
    /// Relax the crack faces of every frame's surface towards their local crack plane
    /// (default true; surface only, the physics does not see it).
    pub smooth_cracks: Option<bool>,
    /// Pieces of at most this many tets are written as debris points
    /// (`frames/debris_NNNN.ply`) instead of surfaces (default
    /// 3; 0 writes every piece as a surface).
    pub debris_tets: Option<usize>,
}

/// What a solid scene says of a key only thin-shell scenes take.
pub(crate) const SHELL_ONLY: &str = "thin-shell scenes ([shell]), not of solids ([mesh])";

impl choice::Schema for SceneFile {
    fn prepare(doc: &mut DeTable<'_>, hints: &mut Hints) -> Result<(), Refusal> {
        hints.foreign(
            doc,
            keys_of::<SceneFile>(),
            keys_of::<shell::ShellSceneFile>(),
            SHELL_ONLY,
        );
        let models = variants_of::<MaterialModel>();
        let material = material_keys();
        let mut model: Option<(String, usize)> = None;
        for (i, (t, span)) in tables_mut(doc, "material").into_iter().enumerate() {
            hints.foreign(
                t,
                &material,
                keys_of::<shell::ShellMaterialSpec>(),
                SHELL_ONLY,
            );
            let choice = Choice {
                field: "model",
                named: Named::InTable { default: "chen" },
                variants: models.clone(),
            };
            let chosen = split(t, span, keys_of::<MaterialSpec>(), &[choice], hints)?;
            let Some(this) = chosen.into_iter().next() else {
                continue;
            };
            match &model {
                None => model = Some((this.get_ref().clone(), i)),
                Some((first, j)) if first != this.get_ref() => {
                    return Err(Refusal {
                        span: this.span(),
                        message: format!(
                            "model \"{}\", but material[{j}] has model \"{first}\": one \
                             model per scene",
                            this.get_ref()
                        ),
                    })
                }
                _ => {}
            }
        }
        if let Some((t, span)) = table_mut(doc, "simulation") {
            let integrators = variants_of::<Integrator>();
            let settings = variants_of::<SimulationModel>();
            hints.foreign(t, &simulation_keys(), &shell::simulation_keys(), SHELL_ONLY);
            let choices = [
                Choice {
                    field: "integrator",
                    named: Named::InTable {
                        default: "explicit",
                    },
                    variants: integrators,
                },
                Choice {
                    field: "model",
                    named: Named::Elsewhere {
                        variant: model.map_or_else(|| "chen".to_string(), |(m, _)| m),
                        place: "[[material]]",
                    },
                    variants: settings,
                },
            ];
            split(t, span, keys_of::<SimulationSpec>(), &choices, hints)?;
        }
        if let Some((t, _)) = table_mut(doc, "output") {
            hints.foreign(
                t,
                keys_of::<OutputSpec>(),
                keys_of::<shell::ShellOutputSpec>(),
                SHELL_ONLY,
            );
        }
        Ok(())
    }
}

/// Every key a solid scene's `[simulation]` takes, whatever its choices.
pub(crate) fn simulation_keys() -> Vec<&'static str> {
    all_keys(
        keys_of::<SimulationSpec>(),
        &[
            &variants_of::<Integrator>(),
            &variants_of::<SimulationModel>(),
        ],
    )
}

/// Every key a solid scene's `[[material]]` takes, whatever its model.
pub(crate) fn material_keys() -> Vec<&'static str> {
    all_keys(
        keys_of::<MaterialSpec>(),
        &[&variants_of::<MaterialModel>()],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_characters() {
        assert_eq!(line_column("ab\ncdé\nf", 0), (1, 1));
        assert_eq!(line_column("ab\ncdé\nf", 3), (2, 1));
        assert_eq!(line_column("ab\ncdé\nf", 8), (3, 1));
    }

    const SOLID: &str = "[mesh]\nprimitive = \"box\"\n\n[[material]]\nyoung = 1e9\n\
                         poisson = 0.25\ndensity = 1000.0\n\n[simulation]\nduration = 1e-3\n";

    /// The message of `text`'s refusal, with its line and column.
    fn refusal<T: Schema + std::fmt::Debug>(text: &str) -> String {
        parse::<T>(text).unwrap_err().to_string()
    }

    #[test]
    fn keys_reach_the_chosen_variants() {
        let text = SOLID
            .replace(
                "density = 1000.0",
                "density = 1000.0\nmodel = \"xu\"\nenergy = \"stvk\"",
            )
            .replace(
                "duration = 1e-3",
                "duration = 1e-3\ninfluence = \"linear\"\nintegrator = \"implicit\"\nhistory = 4",
            );
        let f = parse::<SceneFile>(&text).unwrap();
        let Model::Xu(keys) = &f.material[0].model else {
            panic!("{:?}", f.material[0].model)
        };
        assert_eq!(keys.energy, Some(Energy::Stvk));
        let Model::Xu(settings) = &f.simulation.model else {
            panic!("{:?}", f.simulation.model)
        };
        assert_eq!(settings.influence, Some(Influence::Linear));
        let Integrator::Implicit(i) = &f.simulation.integrator else {
            panic!("{:?}", f.simulation.integrator)
        };
        assert_eq!(i.history, Some(4));
    }

    #[test]
    fn a_key_of_another_choice_names_the_choice_at_its_line() {
        let chen_material =
            SOLID.replace("duration = 1e-3", "duration = 1e-3\ninfluence = \"linear\"");
        assert_eq!(
            refusal::<SceneFile>(&chen_material),
            "11:1: simulation.influence: a key of model = \"xu\"; the model of [[material]] is \
             \"chen\""
        );
        let named_here = SOLID.replace("duration = 1e-3", "duration = 1e-3\nmodel = \"xu\"");
        assert_eq!(
            refusal::<SceneFile>(&named_here),
            "11:1: simulation.model: named in [[material]]"
        );
        let two = format!("{SOLID}\n[[material]]\nmodel = \"xu\"\ndensity = 1.0\n");
        assert_eq!(
            refusal::<SceneFile>(&two),
            "13:9: material[1].model: model \"xu\", but material[0] has model \"chen\": one \
             model per scene"
        );
        let shell_key = SOLID.replace(
            "density = 1000.0",
            "density = 1000.0\nfracture_strain = 0.1",
        );
        assert_eq!(
            refusal::<SceneFile>(&shell_key),
            "8:1: material[0].fracture_strain: a key of thin-shell scenes ([shell]), not of \
             solids ([mesh])"
        );
        let shell = "[shell]\nsurface = \"sphere\"\nthickness = 1e-3\n\n[[material]]\n\
                     young = 1e9\npoisson = 0.25\ndensity = 1.0\ns_crit = 0.1\n\n\
                     [simulation]\nduration = 1e-3\n";
        assert_eq!(
            refusal::<shell::ShellSceneFile>(shell),
            "9:1: material[0].s_crit: a key of solid scenes ([mesh]), not of thin shells \
             ([shell])"
        );
    }

    #[test]
    fn a_value_error_names_its_key() {
        let text = SOLID.replace("young = 1e9", "young = \"stiff\"");
        assert_eq!(
            refusal::<SceneFile>(&text),
            "5:9: material[0].young: invalid type: string \"stiff\", expected f64"
        );
    }

    #[test]
    fn a_shell_scene_is_told_by_its_table() {
        assert!(is_shell_scene("[shell]\nthickness = 1e-3\n"));
        assert!(!is_shell_scene("[mesh]\nprimitive = \"box\"\n"));
        assert!(!is_shell_scene("[shell"));
    }
}
