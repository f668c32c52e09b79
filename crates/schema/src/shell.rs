//! The thin-shell scene file: a `[shell]` table (a triangle surface and its thickness) in place
//! of `[mesh]`, one `[[material]]` with the shell's constants, and the colliders, anchors,
//! initial velocities and output of tet scenes. Every table rejects unknown keys; the refusal of
//! a key only solid scenes take says so.

use serde::Deserialize;
use std::path::PathBuf;
use toml::de::DeTable;

use crate::choice::{
    all_keys, keys_of, split, table_mut, tables_mut, variants_of, Choice, Hints, Named, Refusal,
    Schema,
};
use crate::{
    AnchorSpec, BallSpec, DtSpec, GroundSpec, LoadSpec, OutputSpec, SceneFile, ShellIntegrator,
    VelocitySpec,
};

/// A whole thin-shell scene file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShellSceneFile {
    /// The surface and its thickness.
    pub shell: ShellSpec,
    /// The shell's material: exactly one.
    pub material: Vec<ShellMaterialSpec>,
    /// Time stepping and loads.
    pub simulation: ShellSimulationSpec,
    /// Ground planes (as in tet scenes; a vertex touches them as a sphere of half the
    /// thickness).
    #[serde(default)]
    pub ground: Vec<GroundSpec>,
    /// Balls (as in tet scenes).
    #[serde(default)]
    pub ball: Vec<BallSpec>,
    /// Vertices held fixed or moved at a constant velocity (`region` and `velocity` only).
    #[serde(default)]
    pub anchor: Vec<AnchorSpec>,
    /// Initial velocities (as in tet scenes, of the vertices).
    #[serde(default)]
    pub velocity: Vec<VelocitySpec>,
    /// Loads: a traction on the rim edges, a pressure on the surface or a body force on the
    /// vertices of a region.
    #[serde(default)]
    pub load: Vec<LoadSpec>,
    /// What is written.
    #[serde(default)]
    pub output: ShellOutputSpec,
}

/// The shell's surface: a generated one or a file, then scaled, rotated and moved.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ShellSpec {
    /// `"sphere"`, `"ellipsoid"`, `"cylinder"` (an open tube along z from z = 0), `"sheet"`
    /// (in the z = 0 plane from the origin) or `"bowl"` (a spherical cap resting on the
    /// origin); exclusive with `file`.
    pub surface: Option<String>,
    /// A triangle surface (`.obj`, `.off`, `.ply`), relative to the scene file: a 2-manifold,
    /// with or without boundary.
    pub file: Option<PathBuf>,
    /// Rest thickness `h` (m).
    pub thickness: f64,
    /// Sphere, cylinder or bowl radius (m).
    pub radius: Option<f64>,
    /// Ellipsoid semi-axes along x, y, z (m).
    pub radii: Option<[f64; 3]>,
    /// Cylinder length (m).
    pub length: Option<f64>,
    /// Sheet extent along x and y (m).
    pub size: Option<[f64; 2]>,
    /// Sheet: quads along x and y; cylinder: vertices around and quads along; bowl: rings
    /// and vertices around.
    pub cells: Option<[usize; 2]>,
    /// Sphere or ellipsoid: subdivisions of the icosahedron (`20 4^s` triangles; default 3).
    pub subdivisions: Option<u32>,
    /// Bowl: the cap's opening half-angle at the sphere's centre (degrees, default 90: a
    /// hemisphere).
    pub opening: Option<f64>,
    /// Sheet: `"uniform"` (default: every quad cut along the same diagonal, which reads twist
    /// exactly) or `"alternating"` (a checkerboard of diagonals).
    pub diagonals: Option<String>,
    /// Uniform scale of the coordinates (first).
    pub scale: Option<f64>,
    /// Rotation (degrees) about x, then y, then z, through the origin (after the scale).
    pub rotate: Option<[f64; 3]>,
    /// Translation (m), last.
    pub translate: Option<[f64; 3]>,
}

/// The shell's material (Gingold et al. 2004): elasticity, optional plasticity with linear
/// kinematic hardening, optional fracture.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ShellMaterialSpec {
    /// A name for messages.
    pub name: Option<String>,
    /// Young's modulus (Pa).
    pub young: f64,
    /// Poisson's ratio, in (-1, 0.5].
    pub poisson: f64,
    /// Density (kg/m^3).
    pub density: f64,
    /// Yield: the thickness-averaged deviatoric strain at which the shell yields
    /// (dimensionless); absent: elastic.
    pub yield_strain: Option<f64>,
    /// Linear kinematic hardening `gamma = h_kin / (2 mu)` (dimensionless, default 0: ideal
    /// plasticity).
    pub hardening: Option<f64>,
    /// The principal strain at which a triangle breaks, in tension and compression alike
    /// (dimensionless); absent: no fracture.
    pub fracture_strain: Option<f64>,
    /// Fracture energy `G_c` (J/m^2): a triangle breaks where releasing the stress across the
    /// split would free `G_c` times its area of crack (`G_c h` per metre); exclusive with
    /// `fracture_strain`.
    pub fracture_energy: Option<f64>,
    /// The tensile threshold alone (overrides `fracture_strain` in tension).
    pub tensile_strain: Option<f64>,
    /// The compressive threshold alone, as a magnitude (overrides `fracture_strain` in
    /// compression).
    pub compressive_strain: Option<f64>,
    /// A split point closer than this share of its edge to an end moves that vertex instead
    /// (vertex budging; in [0, 0.5), default 0.25).
    pub budge: Option<f64>,
    /// Share of the stress across a new crack released into the triangles beside it (in
    /// [0, 1], default 1: a free edge carries none).
    pub release: Option<f64>,
}

/// Time stepping and loads of a shell scene.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShellSimulationSpec {
    /// Simulated duration (s).
    pub duration: f64,
    /// Time step: `"auto"` (default) or seconds; a fixed step above 0.95 of the stable limit
    /// is refused.
    pub dt: Option<DtSpec>,
    /// Fraction of the stable limit used by `"auto"` (default 0.5).
    pub safety: Option<f64>,
    /// Gravity (m/s^2), default none.
    pub gravity: Option<[f64; 3]>,
    /// Mass-proportional damping (1/s), default 0.
    pub damping: Option<f64>,
    /// The paper's event search: every step covered by sub-steps of `dt 2^-k`, a trial undone
    /// and halved when the largest force grows too fast or a triangle would break in it
    /// (default false: plain steps, fracture checked after each).
    pub event_search: Option<bool>,
    /// Event search: the finest level `k_max` (default 10, the paper's; at most 20).
    pub event_levels: Option<u32>,
    /// Event search: the largest force may grow by this factor in a sub-step (default 1.1).
    pub force_growth: Option<f64>,
    /// The shell's pieces repel each other within half the thickness of the mid-surface,
    /// except across fresh cracks (default false).
    pub self_contact: Option<bool>,
    /// Self contact: penalty stiffness per pair as a multiple of `Y h` (default 0.01).
    pub self_contact_stiffness: Option<f64>,
    /// The integrator, `"explicit"` (default) or `"newmark"`, with the keys only it takes.
    pub integrator: ShellIntegrator,
}

/// Frame output of a shell scene.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ShellOutputSpec {
    /// Number of frames after the initial one (default 24); `perifrac run --frames` overrides.
    pub frames: Option<usize>,
    /// Also write POV-Ray `mesh2` includes (default true).
    pub povray: Option<bool>,
    /// Thickness (m) each piece is given in the frames, so renders show shards (default the
    /// shell's thickness; 0 writes the mid-surface).
    pub thickness: Option<f64>,
    /// Also write the frames as one USD cache, `NAME.usda`, at the end (default false), as
    /// `perifrac export` writes it.
    pub usd: Option<bool>,
    /// Lay that cache out as one mesh prim per fragment, pivoted at its centroid (default
    /// false).
    pub usd_pieces: Option<bool>,
    /// Playback frames per second of the USD cache (default 24).
    pub fps: Option<f64>,
    /// Write `checkpoint.bin` after every N frames (0: only when interrupted; default: at the
    /// first frame that ends 5 minutes of wall time or more after the last checkpoint).
    pub checkpoint_every: Option<usize>,
}

/// What a thin-shell scene says of a key only solid scenes take.
const SOLID_ONLY: &str = "solid scenes ([mesh]), not of thin shells ([shell])";

/// Every key a shell scene's `[simulation]` takes, whatever its integrator.
pub(crate) fn simulation_keys() -> Vec<&'static str> {
    all_keys(
        keys_of::<ShellSimulationSpec>(),
        &[&variants_of::<ShellIntegrator>()],
    )
}

impl Schema for ShellSceneFile {
    fn prepare(doc: &mut DeTable<'_>, hints: &mut Hints) -> Result<(), Refusal> {
        let solid = keys_of::<SceneFile>();
        hints.foreign(doc, keys_of::<ShellSceneFile>(), solid, SOLID_ONLY);
        let material = crate::material_keys();
        for (t, _) in tables_mut(doc, "material") {
            hints.foreign(t, keys_of::<ShellMaterialSpec>(), &material, SOLID_ONLY);
        }
        if let Some((t, span)) = table_mut(doc, "simulation") {
            let solid = crate::simulation_keys();
            hints.foreign(t, &simulation_keys(), &solid, SOLID_ONLY);
            let choice = Choice {
                field: "integrator",
                named: Named::InTable {
                    default: "explicit",
                },
                variants: variants_of::<ShellIntegrator>(),
            };
            split(t, span, keys_of::<ShellSimulationSpec>(), &[choice], hints)?;
        }
        if let Some((t, _)) = table_mut(doc, "output") {
            hints.foreign(
                t,
                keys_of::<ShellOutputSpec>(),
                keys_of::<OutputSpec>(),
                SOLID_ONLY,
            );
        }
        Ok(())
    }
}
