//! `perifrac bench look`: what the cut surface looks like, measured (issue 13). A bar of the
//! default glass pulled apart (a mode-I split) gives the crack's roughness: its area over the
//! ideal plane's and how far its faces' normals lean from the plane's; the default wall gives
//! the directions cracks run in the slab's plane (a lattice shows peaks at its few directions)
//! and the sizes of its fragments at three resolutions; and every piece of every run is checked
//! closed, 2-manifold and of positive volume at its last step.

use std::path::Path;

use perifrac_io::{write_tet_mesh, TetFormat, TetMeshData};
use perifrac_scene::{Scene, Setup};
use perifrac_topology::mesher::unstructured_box_data;
use perifrac_topology::{primitives::box_data, CrackSmoothing, Pieces, Surface};

use crate::bars::Bars;
use crate::facets::{Facets, Panel};
use crate::table::Table;
use crate::{BenchError, Effort};

/// The default scene, whose cells the fragment runs change.
const WALL: &str = include_str!("../../../data/scenes/wall.toml");

/// Bins of the in-plane crack-direction histogram over 180 degrees (the 12: 15 degrees
/// each).
pub const DIRECTION_BINS: usize = 12;

fn scene_error(case: &str, e: &dyn std::fmt::Display) -> BenchError {
    BenchError::Scene {
        case: case.into(),
        message: e.to_string(),
    }
}

/// Steps `setup` to the end of its run.
fn step_to_end(
    case: &str,
    setup: &mut Setup,
    progress: &mut dyn FnMut(&str),
) -> Result<(), BenchError> {
    progress(&format!("look: {case}"));
    step(case, setup, setup.frames as u64 * setup.steps_per_frame)
}

/// Takes `steps` steps of `setup`; a failed step is an error of `case`.
fn step(case: &str, setup: &mut Setup, steps: u64) -> Result<(), BenchError> {
    for _ in 0..steps {
        setup.driver.step().map_err(|cause| BenchError::Physics {
            case: case.into(),
            cause,
        })?;
    }
    Ok(())
}

/// Area (length^2) and unit normal of face `f`.
fn area_normal(s: &Surface, f: usize) -> (f64, [f64; 3]) {
    let [a, b, c] = s.faces[f].map(|k| s.vertices[k as usize]);
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 {
        (0.5 * l, n.map(|c| c / l))
    } else {
        (0.0, [0.0; 3])
    }
}

/// The area-weighted `q` quantile of `values` (`(value, weight)`).
fn weighted_quantile(values: &mut [(f64, f64)], q: f64) -> f64 {
    values.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = values.iter().map(|v| v.1).sum();
    let mut acc = 0.0;
    for &(v, w) in values.iter() {
        acc += w;
        if acc >= q * total {
            return v;
        }
    }
    values.last().map_or(0.0, |v| v.0)
}

/// `s` with its cracks smoothed as frames are written ([`CrackSmoothing::default`]), and the
/// seconds that took.
fn smoothed(s: &Surface) -> (Surface, f64) {
    let mut out = s.clone();
    let started = std::time::Instant::now();
    out.smooth_cracks(&CrackSmoothing::default());
    (out, started.elapsed().as_secs_f64())
}

/// The crack faces of piece `piece` of `s`: their area (length^2), and how far their normals
/// lean from `axis` (degrees, area-weighted mean and 90th percentile).
fn roughness(s: &Surface, piece: u32, axis: [f64; 3]) -> (f64, f64, f64) {
    let mut area = 0.0;
    let mut angles = Vec::new();
    for f in 0..s.faces.len() {
        if s.crack[f] == 0 || s.piece[f] != piece {
            continue;
        }
        let (a, n) = area_normal(s, f);
        let cos = (n[0] * axis[0] + n[1] * axis[1] + n[2] * axis[2]).abs();
        area += a;
        angles.push((cos.min(1.0).acos().to_degrees(), a));
    }
    let mean = angles.iter().map(|(d, a)| d * a).sum::<f64>() / area.max(f64::MIN_POSITIVE);
    (area, mean, weighted_quantile(&mut angles, 0.9))
}

/// Every piece of `s` checked: (pieces, not a closed 2-manifold, not of positive volume).
fn validity(s: &Surface, pieces: usize) -> (usize, usize, usize) {
    let mut by = vec![Surface::default(); pieces];
    for (f, &p) in s.piece.iter().enumerate() {
        by[p as usize].faces.push(s.faces[f]);
    }
    let (mut open, mut inside_out, mut count) = (0, 0, 0);
    for mut piece in by {
        if piece.faces.is_empty() {
            continue;
        }
        count += 1;
        piece.vertices.clone_from(&s.vertices);
        if !piece.is_closed_manifold() {
            open += 1;
        } else if piece.signed_volume() <= 0.0 {
            inside_out += 1;
        }
    }
    (count, open, inside_out)
}

/// A bar `length` x `width` x `width` m with `cells` Kuhn cells' worth of resolution, its axis
/// turned by `angle` (rad) about z from the x axis of an unturned lattice: the lattice's tets
/// whose barycentres lie inside the turned bar (pinches at its boundary mended as the mesher
/// mends them), so a crack across the bar runs at `angle` to the lattice's faces. Written as a
/// Medit mesh beside the scene, with the scene text that pulls its two ends apart along its
/// axis at 0.1 m/s each, a notch half its depth deep across its middle to start the crack
/// there, for at most [`SPLIT_LONGEST`] in [`SPLIT_FRAMES`] frames. An unstructured bar's
/// points come from `seed`; `calibrated` sets Chen's scalar calibration in place of the
/// default fit.
fn split_scene(
    dir: &Path,
    angle: f64,
    cells: [usize; 3],
    unstructured: Option<u64>,
    calibrated: bool,
) -> Result<String, BenchError> {
    // Slow ends (0.1 m/s) and a deep notch (half the depth) give one crack across the notch
    // rather than a shattered bar: at 1 m/s and a quarter-depth notch the bar came apart in
    // dozens of pieces at 24 x 4 x 4 cells, and roughness then measures debris, not the crack.
    let (speed, duration, notch) = (0.1, SPLIT_LONGEST, 0.5);
    let (length, width) = (0.3, 0.05);
    let (s, c) = angle.sin_cos();
    let shift = [0.3, 0.3, 0.0];
    let h = [
        length / cells[0] as f64,
        width / cells[1] as f64,
        width / cells[2] as f64,
    ];
    // The lattice over the turned bar's bounds, centred on its centre (`shift`).
    let half = [
        0.5 * (length * c.abs() + width * s.abs()),
        0.5 * (length * s.abs() + width * c.abs()),
    ];
    let counts = [
        (2.0 * half[0] / h[0] - 1e-9).ceil().max(1.0) as usize,
        (2.0 * half[1] / h[1] - 1e-9).ceil().max(1.0) as usize,
        cells[2],
    ];
    let lo = [
        shift[0] - 0.5 * counts[0] as f64 * h[0],
        shift[1] - 0.5 * counts[1] as f64 * h[1],
        0.0,
    ];
    let hi = [
        lo[0] + counts[0] as f64 * h[0],
        lo[1] + counts[1] as f64 * h[1],
        width,
    ];
    let (all_vertices, lattice) = match unstructured {
        // Along x only (no lattice to turn): the box is the bar, every tet kept.
        Some(seed) => {
            unstructured_box_data(lo, hi, counts, seed).map_err(|e| scene_error("split", &e))?
        }
        None => box_data(lo, hi, counts),
    };
    let inside = |t: &[u32; 4]| {
        let b: [f64; 2] = std::array::from_fn(|k| {
            t.iter().map(|&v| all_vertices[v as usize][k]).sum::<f64>() / 4.0 - shift[k]
        });
        let (along, across) = (c * b[0] + s * b[1], -s * b[0] + c * b[1]);
        along.abs() <= 0.5 * length && across.abs() <= 0.5 * width
    };
    let mut kept: Vec<[u32; 4]> = lattice.iter().copied().filter(|t| inside(t)).collect();
    perifrac_topology::mesher::manifold::make_boundary_manifold(&mut kept, &lattice);
    // Only the vertices the kept tets use, renumbered.
    let mut index = vec![u32::MAX; all_vertices.len()];
    let mut vertices = Vec::new();
    let tets: Vec<[u32; 4]> = kept
        .iter()
        .map(|t| {
            t.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = vertices.len() as u32;
                    vertices.push(all_vertices[v as usize]);
                }
                index[v as usize]
            })
        })
        .collect();
    let mesh = TetMeshData {
        tet_labels: vec![0; tets.len()],
        vertices,
        tets,
        ..TetMeshData::default()
    };
    let path = dir.join(format!(
        "bar_{:.0}{}.mesh",
        angle.to_degrees(),
        unstructured.map_or(String::new(), |seed| format!("_unstructured_{seed}"))
    ));
    write_tet_mesh(&path, &mesh, TetFormat::Medit).map_err(|e| scene_error("split", &e))?;
    let axis = [c, s, 0.0];
    let end = |sign: f64| [0, 1].map(|k| shift[k] + sign * 0.5 * length * axis[k]);
    let (left, right) = (end(-1.0), end(1.0));
    // End caps: the particles within 2 cm of each end's centre line.
    let cap = |p: [f64; 2]| {
        format!(
            "{{ min = [{}, {}, -1.0], max = [{}, {}, 1.0] }}",
            p[0] - 0.02,
            p[1] - 0.02,
            p[0] + 0.02,
            p[1] + 0.02
        )
    };
    Ok(format!(
        "[mesh]\nfile = \"{}\"\n\n\
         [[material]]\nbulk_modulus = 3.3e10\nshear_modulus = 2.0e10\ndensity = 2200.0\n\
         s_crit = 0.0005\n\n[simulation]\nduration = {duration}\n{}\n\
         [[anchor]]\nregion = {}\nvelocity = [{}, {}, 0.0]\n\n\
         [[anchor]]\nregion = {}\nvelocity = [{}, {}, 0.0]\n\n\
         [[precrack]]\npoint = [{}, {}, 0.0]\nnormal = [{c}, {s}, 0.0]\n\
         region = {{ min = [{}, {}, -1.0], max = [{}, {}, {}] }}\n\n[output]\n\
         frames = {SPLIT_FRAMES}\n",
        path.display(),
        if calibrated {
            "correction = \"calibrated\""
        } else {
            ""
        },
        cap(left),
        -speed * axis[0],
        -speed * axis[1],
        cap(right),
        speed * axis[0],
        speed * axis[1],
        shift[0],
        shift[1],
        shift[0] - 0.05,
        shift[1] - 0.05,
        shift[0] + 0.05,
        shift[1] + 0.05,
        notch * width,
    ))
}

/// The longest a split runs (s). The crack starts about 0.45 ms in; the bars measured (48 x 8
/// x 8 cells, either correction) came apart between 1.2 and 4.2 ms, the last ligament holding
/// longest, so a run that stopped at 1.5 ms left some in one piece and counted their crack's
/// two faces (2.2 to 2.4 times the section) as one piece's roughness.
const SPLIT_LONGEST: f64 = 0.0045;

/// Frames of a split; after each the run stops if the bar is in two.
const SPLIT_FRAMES: usize = 30;

/// Steps `setup` a frame at a time until particles `ends` are in different pieces or the run
/// ends; returns the time they parted (s), if they did.
fn step_until_apart(
    case: &str,
    setup: &mut Setup,
    ends: [usize; 2],
    progress: &mut dyn FnMut(&str),
) -> Result<Option<f64>, BenchError> {
    progress(&format!("look: {case}"));
    for _ in 0..setup.frames {
        step(case, setup, setup.steps_per_frame)?;
        let pieces = setup.driver.mesh().pieces();
        if pieces.piece_of_tet[ends[0]] != pieces.piece_of_tet[ends[1]] {
            return Ok(Some(setup.driver.solver().time()));
        }
    }
    Ok(None)
}

/// The mode-I split of a bar along the lattice and at 30 degrees to it, and on unstructured
/// tets from three seeds (one at [`Effort::Tiny`]), then (at [`Effort::Full`]) on the same
/// unstructured bars with the scalar calibration for comparison (table rows, no panels): crack
/// area over the bar's section, and how far the crack faces' normals lean from the bar's axis
/// (area-weighted mean and 90th percentile), with the pieces' validity, when the bar has come
/// apart.
pub fn split(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, Facets), BenchError> {
    let (cells, seeds, compare): ([usize; 3], &[u64], bool) = match effort {
        Effort::Tiny => ([12, 2, 2], &[1], false),
        Effort::Full => ([48, 8, 8], &[1, 2, 3], true),
    };
    let dir = tempfile_dir()?;
    // (degrees to the lattice, unstructured seed, scalar calibration)
    let mut cases: Vec<(f64, Option<u64>, bool)> = vec![(0.0, None, false), (30.0, None, false)];
    cases.extend(seeds.iter().map(|&seed| (0.0, Some(seed), false)));
    if compare {
        cases.extend(seeds.iter().map(|&seed| (0.0, Some(seed), true)));
    }
    let mut panels: [Vec<Panel>; 2] = [Vec::new(), Vec::new()];
    let mut t = Table::new(&[
        "bar's mesh",
        "crack faces",
        "particles",
        "in two at (ms)",
        "pieces",
        "crack area / section",
        "normal deviation, mean (deg)",
        "normal deviation, 90th percentile (deg)",
        "pieces not closed 2-manifolds",
        "pieces inside out",
    ]);
    for (degrees, unstructured, calibrated) in cases {
        let mesh = match (unstructured, calibrated) {
            (Some(seed), false) => format!("unstructured tets, seed {seed}"),
            (Some(seed), true) => format!("unstructured tets, seed {seed}, scalar calibration"),
            (None, _) => format!("{degrees:.0} degrees to the lattice"),
        };
        let case = format!("split, {mesh}");
        let angle = degrees.to_radians();
        let text = split_scene(dir.path(), angle, cells, unstructured, calibrated)?;
        let scene = Scene::parse(&text, &dir.path().join("split.toml"))
            .map_err(|e| scene_error(&case, &e))?;
        let mut setup = Setup::new(&scene, None).map_err(|e| scene_error(&case, &e))?;
        let particles = setup.info.particles;
        // The particles nearest each end, at rest.
        let axis = [degrees.to_radians().cos(), degrees.to_radians().sin(), 0.0];
        let along = |p: &[f64; 3]| p[0] * axis[0] + p[1] * axis[1];
        let x = setup.driver.solver().positions();
        let by_along = |a: &usize, b: &usize| along(&x[*a]).total_cmp(&along(&x[*b]));
        let ends =
            [(0..x.len()).min_by(by_along), (0..x.len()).max_by(by_along)].map(|i| i.unwrap_or(0));
        let apart = step_until_apart(&case, &mut setup, ends, progress)?;
        let pieces = setup.driver.mesh().pieces();
        setup.driver.place_surface(&pieces);
        let s = setup.driver.mesh().surface_of(&pieces);
        // The left end's piece.
        let left = pieces.piece_of_tet[ends[0]];
        let smoothed = smoothed(&s);
        for (row, (which, s)) in [("as cut", &s), ("smoothed", &smoothed.0)]
            .into_iter()
            .enumerate()
        {
            if !calibrated {
                panels[row].push(crack_panel(s, left, axis, format!("{mesh}, {which}")));
            }
            let (area, mean, p90) = roughness(s, left, axis);
            let (count, open, inside_out) = validity(s, pieces.count);
            t.push(vec![
                mesh.clone(),
                which.into(),
                particles.to_string(),
                apart.map_or_else(
                    || format!("not by {:.1}", SPLIT_LONGEST * 1e3),
                    |t| format!("{:.2}", t * 1e3),
                ),
                count.to_string(),
                format!("{:.3}", area / (0.05 * 0.05)),
                format!("{mean:.1}"),
                format!("{p90:.1}"),
                open.to_string(),
                inside_out.to_string(),
            ]);
        }
    }
    let facets = Facets {
        title: "The split bar's crack, seen along the bar: each face coloured by its lean".into(),
        scale: ("normal's angle from the bar's axis (degrees)".into(), 90.0),
        panels: panels.concat(),
        rows: 2,
    };
    Ok((t, facets))
}

fn crack_panel(s: &Surface, piece: u32, axis: [f64; 3], caption: String) -> Panel {
    let across = [-axis[1], axis[0], 0.0];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let mut faces: Vec<(f64, [[f64; 2]; 3], f64)> = (0..s.faces.len())
        .filter(|&f| s.crack[f] != 0 && s.piece[f] == piece)
        .map(|f| {
            let corners = s.faces[f].map(|k| s.vertices[k as usize]);
            let depth = corners.iter().map(|&c| dot(c, axis)).sum::<f64>();
            let (_, n) = area_normal(s, f);
            let lean = dot(n, axis).abs().min(1.0).acos().to_degrees();
            (depth, corners.map(|c| [dot(c, across), c[2]]), lean)
        })
        .collect();
    faces.sort_by(|a, b| a.0.total_cmp(&b.0));
    Panel {
        caption,
        triangles: faces.iter().map(|f| f.1).collect(),
        values: faces.iter().map(|f| f.2).collect(),
    }
}

/// A temporary directory for generated meshes.
fn tempfile_dir() -> Result<TempDir, BenchError> {
    temp_dir("look")
}

/// A temporary directory named for `case` and this process, removed when dropped.
pub(crate) fn temp_dir(case: &str) -> Result<TempDir, BenchError> {
    let base = std::env::temp_dir().join(format!("perifrac-{case}-{}", std::process::id()));
    std::fs::create_dir_all(&base).map_err(|e| BenchError::Scene {
        case: case.into(),
        message: format!("cannot create {}: {e}", base.display()),
    })?;
    Ok(TempDir(base))
}

/// A directory removed when dropped.
pub(crate) struct TempDir(std::path::PathBuf);

impl TempDir {
    /// The directory.
    pub(crate) fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        // Best effort: a leftover temporary directory harms nothing.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A wall run to its end, once, for every table that reads it: its pieces, its surface where
/// advection alone put the vertices, the surface a frame writes (before smoothing), and the
/// rest positions of the surface's vertices and volumes of its tets.
pub struct WallEnd {
    cells: [usize; 3],
    particles: usize,
    pieces: Pieces,
    advected: Surface,
    placed: Surface,
    rest: Vec<[f64; 3]>,
    rest_volumes: Vec<f64>,
}

/// The default scene at `cells` cells, run to its end.
fn wall_end(cells: [usize; 3], progress: &mut dyn FnMut(&str)) -> Result<WallEnd, BenchError> {
    let case = format!("wall {}x{}x{}", cells[0], cells[1], cells[2]);
    let text = WALL.replace("cells = [24, 24, 3]", &format!("cells = {cells:?}"));
    let scene = Scene::parse(&text, Path::new("wall.toml")).map_err(|e| scene_error(&case, &e))?;
    let mut setup = Setup::new(&scene, None).map_err(|e| scene_error(&case, &e))?;
    step_to_end(&case, &mut setup, progress)?;
    let pieces = setup.driver.mesh().pieces();
    let advected = setup.driver.mesh().surface_of(&pieces);
    setup.driver.place_surface(&pieces);
    let mesh = setup.driver.mesh();
    let placed = mesh.surface_of(&pieces);
    let mut rest: Vec<[f64; 3]> = advected
        .vertex_ids
        .iter()
        .map(|&v| mesh.rest_positions()[mesh.vertex_origin()[v as usize] as usize])
        .collect();
    for &(m, a, b) in &advected.midpoints {
        rest[m as usize] =
            std::array::from_fn(|k| 0.5 * (rest[a as usize][k] + rest[b as usize][k]));
    }
    Ok(WallEnd {
        cells,
        particles: setup.info.particles,
        rest_volumes: mesh.rest_volumes(),
        pieces,
        advected,
        placed,
        rest,
    })
}

/// The default wall (at its file's cells; 8 x 8 x 1 for a quick run) run to its end, for
/// [`wall_directions`], [`fragment_sizes`] and [`debris_shapes`].
pub fn default_wall(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<WallEnd, BenchError> {
    match effort {
        Effort::Tiny => wall_end([8, 8, 1], progress),
        Effort::Full => wall_end([24, 24, 3], progress),
    }
}

/// The default wall at the end of its run ([`default_wall`]): the in-plane directions of its
/// crack faces' normals as an area-weighted histogram of [`DIRECTION_BINS`] bins over 180 degrees (each
/// face weighted by its area times the in-plane part of its normal), as shares of the total.
pub fn wall_directions(wall: &WallEnd) -> (Table, Bars) {
    let s = &wall.placed;
    let hist = direction_histogram(s);
    let smooth = direction_histogram(&smoothed(s).0);
    let mean = 1.0 / DIRECTION_BINS as f64;
    let mut t = Table::new(&[
        "direction of the crack normal in the slab's plane (deg)",
        "share of the crack area, as cut",
        "share / mean, as cut",
        "share, smoothed",
        "share / mean, smoothed",
    ]);
    let width = 180.0 / DIRECTION_BINS as f64;
    for (k, (&h, &m)) in hist.iter().zip(&smooth).enumerate() {
        t.push(vec![
            format!("{:.0}-{:.0}", k as f64 * width, (k + 1) as f64 * width),
            format!("{:.1}%", 100.0 * h),
            format!("{:.2}", h / mean),
            format!("{:.1}%", 100.0 * m),
            format!("{:.2}", m / mean),
        ]);
    }
    let bars = Bars {
        title: "Directions of crack normals in the default wall's plane".into(),
        x_label: "direction from x (degrees)".into(),
        y_label: "share of the crack area / mean".into(),
        bins: (0..DIRECTION_BINS)
            .map(|k| format!("{:.0}", (k as f64 + 0.5) * width))
            .collect(),
        series: vec![
            ("as cut".into(), hist.iter().map(|h| h / mean).collect()),
            ("smoothed".into(), smooth.iter().map(|h| h / mean).collect()),
        ],
        line: Some(("target: 1.5 x the mean".into(), 1.5)),
    };
    (t, bars)
}

/// The area-weighted histogram of the in-plane (x-y) directions of the crack faces' normals,
/// [`DIRECTION_BINS`] bins over 180 degrees, as shares.
pub fn direction_histogram(s: &Surface) -> Vec<f64> {
    let mut hist = vec![0.0; DIRECTION_BINS];
    for f in 0..s.faces.len() {
        if s.crack[f] == 0 {
            continue;
        }
        let (a, n) = area_normal(s, f);
        let inplane = n[0].hypot(n[1]);
        if inplane <= 0.0 {
            continue;
        }
        let theta = n[1].atan2(n[0]).rem_euclid(std::f64::consts::PI);
        let k = ((theta / std::f64::consts::PI * DIRECTION_BINS as f64) as usize)
            .min(DIRECTION_BINS - 1);
        hist[k] += a * inplane;
    }
    let total: f64 = hist.iter().sum();
    if total > 0.0 {
        for h in &mut hist {
            *h /= total;
        }
    }
    hist
}

/// The default wall at three resolutions: fragments, the share that are single tets, tets
/// per fragment (median, 90th percentile, largest), the largest fragment's share of the
/// volume, and the pieces' validity; with the distribution of fragment sizes. `default` is
/// [`default_wall`]'s run, reused at its resolution.
pub fn fragment_sizes(
    effort: Effort,
    default: &WallEnd,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, Bars), BenchError> {
    let runs: &[[usize; 3]] = match effort {
        Effort::Tiny => &[[6, 6, 1], [8, 8, 1]],
        Effort::Full => &[[16, 16, 2], [24, 24, 3], [32, 32, 4]],
    };
    let mut t = Table::new(&[
        "wall cells",
        "particles",
        "fragments",
        "single-tet fragments",
        "tets per fragment: median / 90th percentile / largest",
        "largest fragment's share of the volume",
        "pieces not closed 2-manifolds",
        "pieces inside out",
        "crack smoothing of the last frame (ms)",
        "smoothed pieces not closed 2-manifolds or inside out",
    ]);
    // Size classes of the distribution: 1, 2-3, 4-7, ... tets.
    let classes = 12;
    let mut series = Vec::new();
    for &cells in runs {
        let case = format!("wall {}x{}x{}", cells[0], cells[1], cells[2]);
        // The default wall's resolution is already run.
        let other;
        let wall = if cells == default.cells {
            default
        } else {
            other = wall_end(cells, progress)?;
            &other
        };
        let (s, pieces, particles) = (&wall.placed, &wall.pieces, wall.particles);
        let mut tets = vec![0usize; pieces.count];
        for &p in &pieces.piece_of_tet {
            tets[p as usize] += 1;
        }
        let volumes = &wall.rest_volumes;
        let mut volume = vec![0.0; pieces.count];
        for (t, &p) in pieces.piece_of_tet.iter().enumerate() {
            volume[p as usize] += volumes[t];
        }
        let total: f64 = volume.iter().sum();
        let largest_share =
            volume.iter().cloned().fold(0.0, f64::max) / total.max(f64::MIN_POSITIVE);
        let mut sorted = tets.clone();
        sorted.sort_unstable();
        let q = |x: f64| sorted[((sorted.len() - 1) as f64 * x).round() as usize];
        let single = tets.iter().filter(|&&n| n == 1).count();
        let (_, open, inside_out) = validity(s, pieces.count);
        let (smooth, seconds) = smoothed(s);
        let (_, smooth_open, smooth_inside_out) = validity(&smooth, pieces.count);
        t.push(vec![
            format!("{} x {} x {}", cells[0], cells[1], cells[2]),
            particles.to_string(),
            pieces.count.to_string(),
            format!(
                "{} ({:.0}%)",
                single,
                100.0 * single as f64 / pieces.count as f64
            ),
            format!(
                "{} / {} / {}",
                q(0.5),
                q(0.9),
                sorted.last().copied().unwrap_or(0)
            ),
            format!("{:.1}%", 100.0 * largest_share),
            open.to_string(),
            inside_out.to_string(),
            format!("{:.1}", 1e3 * seconds),
            (smooth_open + smooth_inside_out).to_string(),
        ]);
        let mut hist = vec![0.0; classes];
        for &n in &tets {
            let k = (usize::BITS - n.leading_zeros()) as usize - 1;
            hist[k.min(classes - 1)] += 1.0;
        }
        let count = pieces.count as f64;
        series.push((case, hist.iter().map(|h| h / count).collect()));
    }
    let bars = Bars {
        title: "Fragment sizes of the default wall at three resolutions".into(),
        x_label: "tets per fragment".into(),
        y_label: "share of the fragments".into(),
        bins: (0..classes)
            .map(|k| match k {
                0 => "1".into(),
                _ => format!("{}-{}", 1usize << k, (1usize << (k + 1)) - 1),
            })
            .collect(),
        series,
        line: None,
    };
    Ok((t, bars))
}

/// Roundness of a closed surface of volume `v` and area `a`: `6 sqrt(2) 3^(3/4) v / a^(3/2)`,
/// 1 for a regular tet, 0 for a flat piece, negative for one inside out (a cube: 1.32).
fn roundness(v: f64, a: f64) -> f64 {
    if a > 0.0 {
        6.0 * 2f64.sqrt() * 3f64.powf(0.75) * v / a.powf(1.5)
    } else {
        0.0
    }
}

/// Volume and area of every piece of `s` (`count` pieces), with its vertices at `at`.
fn piece_volumes_areas(s: &Surface, at: &[[f64; 3]], count: usize) -> Vec<(f64, f64)> {
    let mut out = vec![(0.0, 0.0); count];
    for (f, face) in s.faces.iter().enumerate() {
        let [a, b, c] = face.map(|k| at[k as usize]);
        let cr = [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ];
        let (u, w) = (
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
            [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
        );
        let n = [
            u[1] * w[2] - u[2] * w[1],
            u[2] * w[0] - u[0] * w[2],
            u[0] * w[1] - u[1] * w[0],
        ];
        let p = &mut out[s.piece[f] as usize];
        p.0 += (a[0] * cr[0] + a[1] * cr[1] + a[2] * cr[2]) / 6.0;
        p.1 += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    }
    out
}

/// The default wall's small fragments at the end of its run, by size: how round they are at
/// rest, where advection alone would put their vertices, and as a frame writes them (vertices
/// fitted to the particles, pieces of up to [`perifrac_topology::RIGID_PIECE_TETS`] tets put
/// back rigidly, cracks smoothed): the median roundness (a regular tet 1, flat 0) and the
/// pieces flatter than a third of their rest roundness or inside out; with each size's share
/// of the volume and how a run writes it (debris points up to
/// [`perifrac_scene::setup::DEFAULT_DEBRIS_TETS`] tets).
pub fn debris_shapes(wall: &WallEnd) -> Table {
    let (pieces, advected) = (&wall.pieces, &wall.advected);
    let mut written = wall.placed.clone();
    written.smooth_cracks(&CrackSmoothing::default());
    let rest = &wall.rest;
    let shapes = [
        piece_volumes_areas(advected, rest, pieces.count),
        piece_volumes_areas(advected, &advected.vertices, pieces.count),
        piece_volumes_areas(&written, &written.vertices, pieces.count),
    ];
    let mut tets = vec![0usize; pieces.count];
    for &p in &pieces.piece_of_tet {
        tets[p as usize] += 1;
    }
    let mut t = Table::new(&[
        "fragment size (tets)",
        "fragments",
        "share of the volume",
        "written as",
        "median roundness at rest",
        "as advected",
        "as written",
        "flat or inside out, as advected",
        "as written",
    ]);
    for (name, lo, hi) in [
        ("1", 1, 1),
        ("2-3", 2, 3),
        ("4-12", 4, 12),
        ("13 and more", 13, usize::MAX),
    ] {
        let members: Vec<usize> = (0..pieces.count)
            .filter(|&p| (lo..=hi).contains(&tets[p]))
            .collect();
        let round = |k: usize| -> Vec<f64> {
            members
                .iter()
                .map(|&p| roundness(shapes[k][p].0, shapes[k][p].1))
                .collect()
        };
        let median = |mut v: Vec<f64>| -> String {
            if v.is_empty() {
                return "-".into();
            }
            v.sort_by(f64::total_cmp);
            format!("{:.2}", v[v.len() / 2])
        };
        let at_rest = round(0);
        let total: f64 = shapes[0].iter().map(|s| s.0).sum();
        let volume: f64 = members.iter().map(|&p| shapes[0][p].0).sum();
        let bad = |k: usize| {
            round(k)
                .iter()
                .zip(&at_rest)
                .filter(|(r, r0)| **r < **r0 / 3.0)
                .count()
                .to_string()
        };
        t.push(vec![
            name.into(),
            members.len().to_string(),
            format!("{:.1}%", 100.0 * volume / total),
            if hi <= perifrac_scene::setup::DEFAULT_DEBRIS_TETS {
                "debris points".into()
            } else {
                "surfaces".into()
            },
            median(at_rest.clone()),
            median(round(1)),
            median(round(2)),
            bad(1),
            bad(2),
        ]);
    }
    t
}
