//! A run directory as one USD cache (`NAME.usda`): the frames' surfaces as a time-sampled
//! `UsdGeom.Mesh` (or one mesh per fragment), the balls and ground planes, and two materials
//! bound through `GeomSubset`s. Made from the frame files themselves, so the cache carries
//! exactly the numbers of the PLY frames.
//!
//! Layout (one mesh):
//!
//! ```text
//! /NAME                      Xform, the default prim; rotates the run's up axis onto +z
//!   surface                  Mesh: points, normals, velocities, extent every frame;
//!                            faceVertexCounts/Indices, primvars crack, fragment, st and
//!                            displayColor whenever the topology changes
//!     outside, crack         GeomSubsets (family materialBind, a partition of the faces)
//!   debris                   Points (runs that write debris): each frame's small pieces
//!                            as balls of their volume (points, widths, velocities, extent,
//!                            primvars fragment), bound to the crack material
//!   ball_K                   Sphere, translated per frame
//!   ground_K                 Mesh, a square on the plane
//!   Looks/outside, Looks/crack   UsdPreviewSurface materials
//! ```
//!
//! With [`UsdLayout::Pieces`], `surface` is replaced by `fragments/f_ID`: one mesh per fragment
//! with its points about its centre of mass, translated there per frame, visible from the frame
//! it separates until the frame it splits, with `perifrac:parent` naming the fragment it split
//! from.
//!
//! Time: time code `k` is frame `k`, played at `fps` frames per second, so velocities (m/s of
//! simulated time in the frames) are written in metres per second of playback: times the
//! simulated seconds per frame and the frames per second. Stage metadata: z up, metres.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use perifrac_io::usda::{
    identifier, quote, write_double3, write_float_array, write_int_array, write_vec2f_array,
    write_vec3f_array, AttrId, PrimId, UsdaLayer,
};
use perifrac_io::{read_ply_frame, read_ply_points, FrameSurface};
use serde::Deserialize;

use crate::error::SceneError;
use crate::fragments::FragmentBirth;
use crate::manifest::{BallJson, Bounds, DebrisJson, GroundJson};

/// Diffuse colour of the outer surface (linear RGB), as `perifrac render` shades it.
const OUTSIDE_RGB: [f32; 3] = [0.62, 0.60, 0.55];
/// Diffuse colour of crack faces (linear RGB), as `perifrac render` shades them.
const CRACK_RGB: [f32; 3] = [0.90, 0.38, 0.06];

/// Playback frames per second when the scene does not say.
pub const DEFAULT_FPS: f64 = 24.0;

/// How the surfaces are laid out in a USD cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UsdLayout {
    /// One mesh whose topology changes as the object breaks.
    Mesh,
    /// One mesh per fragment, pivoted at its centre of mass.
    Pieces,
}

impl UsdLayout {
    /// The layout the `[output]` keys `usd` and `usd_pieces` ask for (none without `usd`).
    pub(crate) fn from_keys(usd: Option<bool>, pieces: Option<bool>) -> Option<UsdLayout> {
        (usd == Some(true)).then_some(if pieces == Some(true) {
            UsdLayout::Pieces
        } else {
            UsdLayout::Mesh
        })
    }
}

/// What [`export_usd`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct UsdReport {
    /// The file.
    pub path: PathBuf,
    /// Its size (bytes).
    pub bytes: u64,
    /// Frames in it (time codes 0 to `frames - 1`).
    pub frames: usize,
    /// Mesh prims written (1, or the fragments).
    pub meshes: usize,
}

/// The part of `run.json` the export reads, a tet run's or a shell run's.
#[derive(Debug, Deserialize)]
struct Manifest {
    scene: String,
    up: [f64; 3],
    rest_bounds: Bounds,
    grounds: Vec<GroundJson>,
    frames: Vec<ManifestFrame>,
    #[serde(default)]
    fragments: Vec<FragmentBirth>,
    #[serde(default)]
    fps: Option<f64>,
}

/// The part of a frame in `run.json` the export reads.
#[derive(Debug, Deserialize)]
struct ManifestFrame {
    index: usize,
    time: f64,
    surface: String,
    #[serde(default)]
    particles: Option<String>,
    #[serde(default)]
    debris: Option<DebrisJson>,
    balls: Vec<BallJson>,
}

/// Writes the frames of run directory `dir` as one USD cache at `path` (default
/// `dir/NAME.usda`, NAME the scene file's stem), atomically. `fps` overrides the playback rate
/// `run.json` records.
pub fn export_usd(
    dir: &Path,
    path: Option<&Path>,
    layout: UsdLayout,
    fps: Option<f64>,
) -> Result<UsdReport, SceneError> {
    let err = |message: String| SceneError::Output {
        dir: dir.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(dir.join("run.json"))
        .map_err(|e| err(format!("cannot read run.json: {e}")))?;
    let manifest: Manifest =
        serde_json::from_str(&text).map_err(|e| err(format!("run.json: {e}")))?;
    if manifest.frames.is_empty() {
        return Err(err("run.json lists no frames yet".into()));
    }
    let fps = fps.or(manifest.fps).unwrap_or(DEFAULT_FPS);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(err(format!(
            "{fps} frames per second is not a playback rate"
        )));
    }
    let stem = Path::new(&manifest.scene)
        .file_stem()
        .map_or_else(|| "perifrac".into(), |s| s.to_string_lossy().into_owned());
    let out = path.map_or_else(|| dir.join(format!("{stem}.usda")), Path::to_path_buf);
    let mut cache = Cache::new(&out, &manifest, &stem, fps)?;
    let frames = &manifest.frames;
    for (k, frame) in frames.iter().enumerate() {
        if frame.index != k {
            return Err(err(format!(
                "run.json's frame {k} says it is frame {}",
                frame.index
            )));
        }
        let path = dir.join(&frame.surface);
        let surface = read_ply_frame(&path)?;
        check_finite(&path, &surface)?;
        let centres = match (&frame.particles, layout) {
            (Some(p), UsdLayout::Pieces) => Some(centres_of_mass(&dir.join(p))?),
            _ => None,
        };
        cache.frame(k, &surface, centres.as_ref(), &frame.balls, layout)?;
        if let Some(prim) = cache.debris.clone() {
            let cloud = match &frame.debris {
                Some(d) => read_ply_points(&dir.join(&d.path))?,
                None => Default::default(),
            };
            cache.debris_frame(&prim, k, &cloud)?;
        }
    }
    let meshes = cache.finish(layout)?;
    let bytes = std::fs::metadata(&out).map_or(0, |m| m.len());
    Ok(UsdReport {
        path: out,
        bytes,
        frames: frames.len(),
        meshes,
    })
}

/// A mesh prim's time-sampled attributes and the topology it last wrote.
struct MeshPrim {
    prim: PrimId,
    points: AttrId,
    normals: AttrId,
    velocities: AttrId,
    extent: AttrId,
    counts: AttrId,
    indices: AttrId,
    crack: AttrId,
    fragment: AttrId,
    st: AttrId,
    color: AttrId,
    outside: AttrId,
    cracked: AttrId,
    /// Faces, crack flags, fragments and texture coordinates last written.
    last: Option<Topology>,
}

/// What a mesh writes only when it changes: faces, crack flags, fragments, texture
/// coordinates.
type Topology = (Vec<[u32; 3]>, Vec<u8>, Vec<u32>, Vec<[f32; 2]>);

/// The debris `Points` prim's time-sampled attributes.
#[derive(Debug, Clone)]
struct DebrisPrim {
    points: AttrId,
    widths: AttrId,
    velocities: AttrId,
    extent: AttrId,
    fragment: AttrId,
}

/// A fragment's prim in the pieces layout.
struct Piece {
    mesh: MeshPrim,
    translate: AttrId,
    visibility: AttrId,
    /// Whether the last frame written showed it.
    shown: bool,
}

struct Cache {
    layer: UsdaLayer,
    root: PrimId,
    looks: String,
    mesh: Option<MeshPrim>,
    fragments: Option<PrimId>,
    pieces: BTreeMap<u32, Piece>,
    parents: BTreeMap<u32, Option<u32>>,
    balls: Vec<AttrId>,
    /// The debris points, when any frame has debris.
    debris: Option<DebrisPrim>,
    /// Velocity factor: playback seconds per simulated second, inverted (s/s).
    speed: f32,
}

impl Cache {
    fn new(out: &Path, m: &Manifest, stem: &str, fps: f64) -> Result<Cache, SceneError> {
        let mut layer = UsdaLayer::create(out)?;
        let name = identifier(stem);
        let frames = m.frames.len();
        let last = m.frames[frames - 1].time;
        // Simulated seconds per frame, times frames per second of playback.
        let per_frame = if frames > 1 {
            last / (frames - 1) as f64
        } else {
            0.0
        };
        let speed = per_frame * fps;
        layer.metadata("defaultPrim", &quote(&name));
        layer.metadata("upAxis", &quote("Z"));
        layer.metadata("metersPerUnit", "1.0");
        layer.metadata("timeCodesPerSecond", &format!("{fps:?}"));
        layer.metadata("framesPerSecond", &format!("{fps:?}"));
        layer.metadata("startTimeCode", "0.0");
        layer.metadata("endTimeCode", &format!("{:?}", (frames - 1) as f64));
        layer.metadata(
            "doc",
            &quote(&format!(
                "perifrac run of {}: {frames} frames, {per_frame:e} s simulated per frame, \
                 played at {fps} frames per second; velocities in metres per second of \
                 playback (simulated m/s times {speed:e})",
                m.scene
            )),
        );
        let root = layer.prim(None, "Xform", &name)?;
        layer.prim_metadata(root, "kind = \"component\"");
        if let Some(matrix) = up_to_z(m.up) {
            layer.property(root, &format!("matrix4d xformOp:transform = {matrix}"));
            layer.property(
                root,
                "uniform token[] xformOpOrder = [\"xformOp:transform\"]",
            );
        }
        let looks = format!("/{name}/Looks");
        let mut cache = Cache {
            layer,
            root,
            looks,
            mesh: None,
            fragments: None,
            pieces: BTreeMap::new(),
            parents: m.fragments.iter().map(|b| (b.id, b.parent)).collect(),
            balls: Vec::new(),
            debris: None,
            speed: speed as f32,
        };
        cache.static_prims(m)?;
        if m.frames.iter().any(|f| f.debris.is_some()) {
            cache.debris = Some(cache.debris_prim()?);
        }
        Ok(cache)
    }

    /// Materials, balls (their translations are sampled per frame) and ground planes.
    fn static_prims(&mut self, m: &Manifest) -> Result<(), SceneError> {
        let layer = &mut self.layer;
        let looks = layer.prim(Some(self.root), "Scope", "Looks")?;
        for (name, rgb, roughness) in [("outside", OUTSIDE_RGB, 0.35), ("crack", CRACK_RGB, 0.7)] {
            let material = layer.prim(Some(looks), "Material", name)?;
            layer.property(
                material,
                &format!(
                    "token outputs:surface.connect = <{}/{name}/PreviewSurface.outputs:surface>",
                    self.looks
                ),
            );
            let shader = layer.prim(Some(material), "Shader", "PreviewSurface")?;
            layer.property(shader, "uniform token info:id = \"UsdPreviewSurface\"");
            layer.property(
                shader,
                &format!(
                    "color3f inputs:diffuseColor = ({}, {}, {})",
                    rgb[0], rgb[1], rgb[2]
                ),
            );
            layer.property(shader, &format!("float inputs:roughness = {roughness}"));
            layer.property(shader, "token outputs:surface");
        }
        if let Some(first) = m.frames.first() {
            for (k, b) in first.balls.iter().enumerate() {
                let ball = layer.prim(Some(self.root), "Sphere", &format!("ball_{k}"))?;
                let r = b.radius;
                layer.property(ball, &format!("double radius = {r:?}"));
                layer.property(
                    ball,
                    &format!(
                        "float3[] extent = [({0}, {0}, {0}), ({1}, {1}, {1})]",
                        -r, r
                    ),
                );
                layer.property(
                    ball,
                    "uniform token[] xformOpOrder = [\"xformOp:translate\"]",
                );
                self.balls
                    .push(layer.sampled(ball, "double3 xformOp:translate", &[]));
            }
        }
        let (lo, hi) = (m.rest_bounds.min, m.rest_bounds.max);
        let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
        for (k, g) in m.grounds.iter().enumerate() {
            let ground = layer.prim(Some(self.root), "Mesh", &format!("ground_{k}"))?;
            let corners = ground_square(g, centre, 2.0 * diagonal.max(f64::MIN_POSITIVE));
            let mut text = Vec::new();
            write_vec3f_array(&mut text, &corners);
            let text = String::from_utf8_lossy(&text).into_owned();
            layer.property(ground, &format!("point3f[] points = {text}"));
            layer.property(ground, "int[] faceVertexCounts = [4]");
            layer.property(ground, "int[] faceVertexIndices = [0, 1, 2, 3]");
            layer.property(ground, "uniform token subdivisionScheme = \"none\"");
            let (mut elo, mut ehi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for c in &corners {
                for i in 0..3 {
                    elo[i] = elo[i].min(c[i]);
                    ehi[i] = ehi[i].max(c[i]);
                }
            }
            let mut ext = Vec::new();
            write_vec3f_array(&mut ext, &[elo, ehi]);
            layer.property(
                ground,
                &format!("float3[] extent = {}", String::from_utf8_lossy(&ext)),
            );
        }
        Ok(())
    }

    /// The `debris` Points prim, bound to the crack material.
    fn debris_prim(&mut self) -> Result<DebrisPrim, SceneError> {
        let layer = &mut self.layer;
        let prim = layer.prim(Some(self.root), "Points", "debris")?;
        layer.prim_metadata(prim, "prepend apiSchemas = [\"MaterialBindingAPI\"]");
        layer.property(
            prim,
            &format!("rel material:binding = <{}/crack>", self.looks),
        );
        layer.property(
            prim,
            &format!(
                "color3f[] primvars:displayColor = [({}, {}, {})] (\n        interpolation = \"constant\"\n    )",
                CRACK_RGB[0], CRACK_RGB[1], CRACK_RGB[2]
            ),
        );
        let vertex = ["interpolation = \"vertex\""];
        Ok(DebrisPrim {
            points: layer.sampled(prim, "point3f[] points", &[]),
            widths: layer.sampled(prim, "float[] widths", &vertex),
            velocities: layer.sampled(prim, "vector3f[] velocities", &[]),
            extent: layer.sampled(prim, "float3[] extent", &[]),
            fragment: layer.sampled(prim, "int[] primvars:fragment", &vertex),
        })
    }

    /// Frame `k` of the debris: its points with their diameters as widths (an empty cloud when
    /// the frame has none).
    fn debris_frame(
        &mut self,
        prim: &DebrisPrim,
        k: usize,
        cloud: &perifrac_io::PointCloud,
    ) -> Result<(), SceneError> {
        let t = k as f64;
        let n = cloud.points.len();
        let column = |name: &str| -> Vec<f64> {
            cloud
                .scalar(name)
                .map_or_else(|| vec![0.0; n], <[f64]>::to_vec)
        };
        let radius = column("radius");
        let (vx, vy, vz) = (column("vx"), column("vy"), column("vz"));
        let fragment = column("fragment");
        let points: Vec<[f32; 3]> = cloud.points.iter().map(|p| p.map(|c| c as f32)).collect();
        let velocities: Vec<[f32; 3]> = (0..n)
            .map(|i| [vx[i], vy[i], vz[i]].map(|c| c as f32 * self.speed))
            .collect();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for (p, &r) in points.iter().zip(&radius) {
            for d in 0..3 {
                lo[d] = lo[d].min(p[d] - r as f32);
                hi[d] = hi[d].max(p[d] + r as f32);
            }
        }
        if n == 0 {
            (lo, hi) = ([0.0; 3], [0.0; 3]);
        }
        let layer = &mut self.layer;
        layer.sample(prim.points, t, |o| write_vec3f_array(o, &points))?;
        layer.sample(prim.widths, t, |o| {
            write_float_array(o, radius.iter().map(|&r| 2.0 * r as f32))
        })?;
        layer.sample(prim.velocities, t, |o| write_vec3f_array(o, &velocities))?;
        layer.sample(prim.extent, t, |o| write_vec3f_array(o, &[lo, hi]))?;
        layer.sample(prim.fragment, t, |o| {
            write_int_array(o, fragment.iter().map(|&f| f as i64))
        })?;
        Ok(())
    }

    /// A mesh prim `name` under `parent` with its attributes declared.
    fn mesh_prim(&mut self, parent: PrimId, name: &str) -> Result<MeshPrim, SceneError> {
        let layer = &mut self.layer;
        let prim = layer.prim(Some(parent), "Mesh", name)?;
        layer.property(prim, "uniform token subdivisionScheme = \"none\"");
        layer.property(
            prim,
            "uniform token subsetFamily:materialBind:familyType = \"partition\"",
        );
        let vertex = ["interpolation = \"vertex\""];
        let uniform = ["interpolation = \"uniform\""];
        let points = layer.sampled(prim, "point3f[] points", &[]);
        let normals = layer.sampled(prim, "normal3f[] normals", &vertex);
        let velocities = layer.sampled(prim, "vector3f[] velocities", &[]);
        let extent = layer.sampled(prim, "float3[] extent", &[]);
        let counts = layer.sampled(prim, "int[] faceVertexCounts", &[]);
        let indices = layer.sampled(prim, "int[] faceVertexIndices", &[]);
        let crack = layer.sampled(prim, "int[] primvars:crack", &uniform);
        let fragment = layer.sampled(prim, "int[] primvars:fragment", &uniform);
        let st = layer.sampled(prim, "texCoord2f[] primvars:st", &vertex);
        let color = layer.sampled(prim, "color3f[] primvars:displayColor", &uniform);
        let mut subset = |name: &str| -> Result<AttrId, SceneError> {
            let s = layer.prim(Some(prim), "GeomSubset", name)?;
            layer.prim_metadata(s, "prepend apiSchemas = [\"MaterialBindingAPI\"]");
            layer.property(s, "uniform token elementType = \"face\"");
            layer.property(s, "uniform token familyName = \"materialBind\"");
            layer.property(
                s,
                &format!("rel material:binding = <{}/{name}>", self.looks),
            );
            Ok(layer.sampled(s, "int[] indices", &[]))
        };
        let outside = subset("outside")?;
        let cracked = subset("crack")?;
        Ok(MeshPrim {
            prim,
            points,
            normals,
            velocities,
            extent,
            counts,
            indices,
            crack,
            fragment,
            st,
            color,
            outside,
            cracked,
            last: None,
        })
    }

    /// Adds frame `k`: the whole surface, or each fragment's part of it.
    fn frame(
        &mut self,
        k: usize,
        s: &FrameSurface,
        centres: Option<&BTreeMap<u32, [f64; 3]>>,
        balls: &[BallJson],
        layout: UsdLayout,
    ) -> Result<(), SceneError> {
        let t = k as f64;
        for (attr, b) in self.balls.clone().iter().zip(balls) {
            self.layer
                .sample(*attr, t, |o| write_double3(o, b.center))?;
        }
        let attrs = Attributes::of(s, self.speed);
        match layout {
            UsdLayout::Mesh => {
                if self.mesh.is_none() {
                    let mesh = self.mesh_prim(self.root, "surface")?;
                    self.mesh = Some(mesh);
                }
                let Cache { layer, mesh, .. } = self;
                if let Some(mesh) = mesh.as_mut() {
                    write_mesh(layer, mesh, t, &attrs, None)?;
                }
            }
            UsdLayout::Pieces => self.pieces_frame(k, &attrs, centres)?,
        }
        Ok(())
    }

    fn pieces_frame(
        &mut self,
        k: usize,
        all: &Attributes,
        centres: Option<&BTreeMap<u32, [f64; 3]>>,
    ) -> Result<(), SceneError> {
        let t = k as f64;
        if self.fragments.is_none() {
            self.fragments = Some(self.layer.prim(Some(self.root), "Scope", "fragments")?);
        }
        let Some(scope) = self.fragments else {
            return Ok(());
        };
        let parts = all.split_by_fragment();
        for (&id, part) in &parts {
            if !self.pieces.contains_key(&id) {
                let mesh = self.mesh_prim(scope, &format!("f_{id}"))?;
                let layer = &mut self.layer;
                if let Some(Some(parent)) = self.parents.get(&id) {
                    layer.property(mesh.prim, &format!("custom int perifrac:parent = {parent}"));
                }
                layer.property(
                    mesh.prim,
                    "uniform token[] xformOpOrder = [\"xformOp:translate\"]",
                );
                let translate = layer.sampled(mesh.prim, "double3 xformOp:translate", &[]);
                let visibility = layer.sampled(mesh.prim, "token visibility", &[]);
                if k > 0 {
                    layer.sample(visibility, 0.0, |o| o.extend_from_slice(b"\"invisible\""))?;
                }
                self.pieces.insert(
                    id,
                    Piece {
                        mesh,
                        translate,
                        visibility,
                        shown: false,
                    },
                );
            }
            let Some(piece) = self.pieces.get_mut(&id) else {
                continue;
            };
            let pivot = centres
                .and_then(|c| c.get(&id).copied())
                .unwrap_or_else(|| part.centroid());
            self.layer
                .sample(piece.translate, t, |o| write_double3(o, pivot))?;
            if !piece.shown {
                self.layer.sample(piece.visibility, t, |o| {
                    o.extend_from_slice(b"\"inherited\"")
                })?;
                piece.shown = true;
            }
            write_mesh(&mut self.layer, &mut piece.mesh, t, part, Some(pivot))?;
        }
        for (id, piece) in self.pieces.iter_mut() {
            if piece.shown && !parts.contains_key(id) {
                self.layer.sample(piece.visibility, t, |o| {
                    o.extend_from_slice(b"\"invisible\"")
                })?;
                piece.shown = false;
            }
        }
        Ok(())
    }

    fn finish(self, layout: UsdLayout) -> Result<usize, SceneError> {
        let meshes = match layout {
            UsdLayout::Mesh => 1,
            UsdLayout::Pieces => self.pieces.len(),
        };
        self.layer.finish()?;
        Ok(meshes)
    }
}

/// Writes one frame of `attrs` into `mesh` at time `t`: geometry every frame, topology and
/// face data when they changed. With a `pivot`, points are written about it.
fn write_mesh(
    layer: &mut UsdaLayer,
    mesh: &mut MeshPrim,
    t: f64,
    attrs: &Attributes,
    pivot: Option<[f64; 3]>,
) -> Result<(), SceneError> {
    let points: Vec<[f32; 3]> = match pivot {
        None => attrs.points.clone(),
        Some(c) => attrs
            .points
            .iter()
            .map(|p| std::array::from_fn(|i| (f64::from(p[i]) - c[i]) as f32))
            .collect(),
    };
    let velocities: Vec<[f32; 3]> = match pivot {
        None => attrs.velocities.clone(),
        Some(_) => {
            // The pivot's motion is in the translation samples: what is left is the motion
            // about the mean velocity of the piece's vertices.
            let n = attrs.velocities.len().max(1) as f64;
            let mean: [f64; 3] = std::array::from_fn(|i| {
                attrs
                    .velocities
                    .iter()
                    .map(|v| f64::from(v[i]))
                    .sum::<f64>()
                    / n
            });
            attrs
                .velocities
                .iter()
                .map(|v| std::array::from_fn(|i| (f64::from(v[i]) - mean[i]) as f32))
                .collect()
        }
    };
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &points {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if points.is_empty() {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    layer.sample(mesh.points, t, |o| write_vec3f_array(o, &points))?;
    layer.sample(mesh.normals, t, |o| write_vec3f_array(o, &attrs.normals))?;
    layer.sample(mesh.velocities, t, |o| write_vec3f_array(o, &velocities))?;
    layer.sample(mesh.extent, t, |o| write_vec3f_array(o, &[lo, hi]))?;
    let changed = mesh.last.as_ref().is_none_or(|(f, c, g, st)| {
        *f != attrs.faces || *c != attrs.crack || *g != attrs.fragment || *st != attrs.uv
    });
    if changed {
        let faces = &attrs.faces;
        layer.sample(mesh.counts, t, |o| {
            write_int_array(o, std::iter::repeat_n(3, faces.len()))
        })?;
        layer.sample(mesh.indices, t, |o| {
            write_int_array(o, faces.iter().flatten().map(|&v| i64::from(v)))
        })?;
        layer.sample(mesh.crack, t, |o| {
            write_int_array(o, attrs.crack.iter().map(|&c| i64::from(c)))
        })?;
        layer.sample(mesh.fragment, t, |o| {
            write_int_array(o, attrs.fragment.iter().map(|&c| i64::from(c)))
        })?;
        layer.sample(mesh.st, t, |o| write_vec2f_array(o, &attrs.uv))?;
        // What viewers without the materials show (usdview, a Houdini viewport): the two
        // materials' colours, face by face.
        let colors: Vec<[f32; 3]> = attrs
            .crack
            .iter()
            .map(|&c| if c != 0 { CRACK_RGB } else { OUTSIDE_RGB })
            .collect();
        layer.sample(mesh.color, t, |o| write_vec3f_array(o, &colors))?;
        let subset = |want: bool| {
            attrs
                .crack
                .iter()
                .enumerate()
                .filter(move |(_, &c)| (c != 0) == want)
                .map(|(i, _)| i as i64)
        };
        layer.sample(mesh.outside, t, |o| write_int_array(o, subset(false)))?;
        layer.sample(mesh.cracked, t, |o| write_int_array(o, subset(true)))?;
        mesh.last = Some((
            attrs.faces.clone(),
            attrs.crack.clone(),
            attrs.fragment.clone(),
            attrs.uv.clone(),
        ));
    }
    Ok(())
}

/// One frame's surface (or a fragment's part of it) as the cache writes it.
#[derive(Debug, Clone, Default)]
struct Attributes {
    points: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    velocities: Vec<[f32; 3]>,
    uv: Vec<[f32; 2]>,
    faces: Vec<[u32; 3]>,
    crack: Vec<u8>,
    fragment: Vec<u32>,
}

impl Attributes {
    /// The frame's arrays, missing ones filled (zero velocities, flat normals, zero texture
    /// coordinates, no cracks, fragment 0), velocities scaled to playback by `speed`.
    fn of(s: &FrameSurface, speed: f32) -> Attributes {
        let n = s.vertices.len();
        let m = s.faces.len();
        Attributes {
            points: s.vertices.clone(),
            normals: s
                .normals
                .clone()
                .unwrap_or_else(|| vec![[0.0, 0.0, 1.0]; n]),
            velocities: s.velocities.as_ref().map_or_else(
                || vec![[0.0; 3]; n],
                |v| v.iter().map(|x| x.map(|c| c * speed)).collect(),
            ),
            uv: s.uv.clone().unwrap_or_else(|| vec![[0.0; 2]; n]),
            faces: s.faces.clone(),
            crack: s.crack.clone().unwrap_or_else(|| vec![0; m]),
            fragment: s.fragment.clone().unwrap_or_else(|| vec![0; m]),
        }
    }

    /// Each fragment's faces with the vertices they use, renumbered in order of first use.
    fn split_by_fragment(&self) -> BTreeMap<u32, Attributes> {
        let mut parts: BTreeMap<u32, (Attributes, Vec<u32>)> = BTreeMap::new();
        let mut local = vec![(u32::MAX, 0u32); self.points.len()];
        for (f, face) in self.faces.iter().enumerate() {
            let id = self.fragment[f];
            let (part, _) = parts.entry(id).or_default();
            let mapped = face.map(|v| {
                let slot = &mut local[v as usize];
                if slot.0 != id {
                    *slot = (id, part.points.len() as u32);
                    part.points.push(self.points[v as usize]);
                    part.normals.push(self.normals[v as usize]);
                    part.velocities.push(self.velocities[v as usize]);
                    part.uv.push(self.uv[v as usize]);
                }
                slot.1
            });
            part.faces.push(mapped);
            part.crack.push(self.crack[f]);
            part.fragment.push(id);
        }
        parts.into_iter().map(|(id, (a, _))| (id, a)).collect()
    }

    /// The mean of the vertices (m), the pivot when no particle masses are at hand.
    fn centroid(&self) -> [f64; 3] {
        let n = self.points.len().max(1) as f64;
        std::array::from_fn(|i| self.points.iter().map(|p| f64::from(p[i])).sum::<f64>() / n)
    }
}

/// Refuses a frame whose normals, velocities or texture coordinates are not finite numbers
/// (USD's text format has no spelling for them that every reader takes).
fn check_finite(path: &Path, s: &FrameSurface) -> Result<(), SceneError> {
    let threes = [("normal", &s.normals), ("velocity", &s.velocities)];
    for (what, values) in threes {
        if let Some(k) = values
            .iter()
            .flatten()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(perifrac_io::IoError::invalid(
                path,
                format!("vertex {k} has a non-finite {what}"),
            )
            .into());
        }
    }
    if let Some(k) =
        s.uv.iter()
            .flatten()
            .position(|v| !v.iter().all(|c| c.is_finite()))
    {
        return Err(perifrac_io::IoError::invalid(
            path,
            format!("vertex {k} has non-finite texture coordinates"),
        )
        .into());
    }
    Ok(())
}

/// Each fragment's centre of mass (m) from a particles PLY (`mass`, `fragment`).
fn centres_of_mass(path: &Path) -> Result<BTreeMap<u32, [f64; 3]>, SceneError> {
    let cloud = read_ply_points(path)?;
    let bad =
        || perifrac_io::IoError::invalid(path, "particles without mass and fragment properties");
    let mass = cloud.scalar("mass").ok_or_else(bad)?;
    let fragment = cloud.scalar("fragment").ok_or_else(bad)?;
    let mut sums: BTreeMap<u32, [f64; 4]> = BTreeMap::new();
    for ((p, &m), &f) in cloud.points.iter().zip(mass).zip(fragment) {
        let s = sums.entry(f as u32).or_default();
        for i in 0..3 {
            s[i] += m * p[i];
        }
        s[3] += m;
    }
    Ok(sums
        .into_iter()
        .filter(|(_, s)| s[3] > 0.0)
        .map(|(f, s)| (f, [s[0] / s[3], s[1] / s[3], s[2] / s[3]]))
        .collect())
}

/// The rotation taking `up` onto +z as a usda `matrix4d` (rows; USD multiplies row vectors),
/// or `None` when `up` is +z already.
fn up_to_z(up: [f64; 3]) -> Option<String> {
    let l = (up[0] * up[0] + up[1] * up[1] + up[2] * up[2]).sqrt();
    if l.is_nan() || l <= 0.0 {
        return None;
    }
    let u = up.map(|c| c / l);
    if u == [0.0, 0.0, 1.0] {
        return None;
    }
    // Rodrigues: the rotation about axis u x z by the angle between u and z.
    let z = [0.0, 0.0, 1.0];
    let axis = [
        u[1] * z[2] - u[2] * z[1],
        u[2] * z[0] - u[0] * z[2],
        u[0] * z[1] - u[1] * z[0],
    ];
    let s = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let c = u[2];
    let r: [[f64; 3]; 3] = if s < 1e-12 {
        // up = -z: half a turn about x.
        [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]
    } else {
        let k = axis.map(|a| a / s);
        let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let kk: f64 = (0..3).map(|m| kx[i][m] * kx[m][j]).sum();
                f64::from(u8::from(i == j)) + s * kx[i][j] + (1.0 - c) * kk
            })
        })
    };
    // Column-vector R maps v to R v; USD's row vectors need its transpose.
    let row = |i: usize| format!("({:?}, {:?}, {:?}, 0.0)", r[0][i], r[1][i], r[2][i]);
    Some(format!(
        "( {}, {}, {}, (0.0, 0.0, 0.0, 1.0) )",
        row(0),
        row(1),
        row(2)
    ))
}

/// The corners of a square of half-size `half` (m) on ground `g`, centred on the projection of
/// `centre`, counter-clockwise seen from the side the normal points to.
fn ground_square(g: &GroundJson, centre: [f64; 3], half: f64) -> [[f32; 3]; 4] {
    let n = g.normal;
    let d: f64 = (0..3).map(|i| (centre[i] - g.point[i]) * n[i]).sum();
    let o: [f64; 3] = std::array::from_fn(|i| centre[i] - d * n[i]);
    // Any unit vector across n, then the third by the right hand.
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let dot: f64 = (0..3).map(|i| a[i] * n[i]).sum();
    let u0: [f64; 3] = std::array::from_fn(|i| a[i] - dot * n[i]);
    let lu = (u0[0] * u0[0] + u0[1] * u0[1] + u0[2] * u0[2]).sqrt();
    let u = u0.map(|c| c / lu);
    let v = [
        n[1] * u[2] - n[2] * u[1],
        n[2] * u[0] - n[0] * u[2],
        n[0] * u[1] - n[1] * u[0],
    ];
    let corner = |a: f64, b: f64| -> [f32; 3] {
        std::array::from_fn(|i| (o[i] + half * (a * u[i] + b * v[i])) as f32)
    };
    [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ]
}
