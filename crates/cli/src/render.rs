//! `perifrac render DIR`: a POV-Ray scene per frame of a run directory, and a PNG per frame
//! when `povray` is on the PATH.
//!
//! Every scene shares one camera, framed on the union of the rest bounds and all frames' bounds
//! in `run.json`, so frame N looks the same whether it is rendered alone or in a sequence.
//! perifrac data is z-up (in general: `up` from `run.json`) and right-handed; POV-Ray is y-up and
//! left-handed. Every point written here goes through [`pov`], which swaps y and z, and the mesh
//! include gets the same swap as a `matrix`; the swap is a reflection, which also fixes the
//! handedness, and the camera's `sky` is the swapped `up`.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Component, Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{anyhow, bail, ensure, Context, Result};
use perifrac_io::{atomic_write, read_ply_frame, read_ply_points, write_povray_mesh2, SurfaceRef};
use perifrac_physics::math::{add, cross, dot, norm, scale, sub};
use perifrac_scene::manifest::{BallJson as Ball, Bounds, GroundJson as Ground};
use perifrac_scene::{POVRAY_MESH_NAME as MESH_NAME, RUN_FORMAT};
use serde::Deserialize;

/// Horizontal field of view of the camera, degrees.
const FOV_DEG: f64 = 40.0;
/// Camera azimuth from the first horizontal axis (x when z is up) towards minus the second
/// (-y), degrees: a 3/4 view like `docs/cut_box.pov`.
const CAMERA_AZIMUTH_DEG: f64 = 50.0;
/// Camera elevation above the horizontal plane through the target, degrees.
const CAMERA_ELEVATION_DEG: f64 = 25.0;
/// A ball whose radius passes this many times the framed extent is drawn see-through (a press
/// plate: flat over the object, it would otherwise fill the picture).
const PLATE_RADIUS: f64 = 20.0;

/// Fraction of the half-width and half-height of the picture the bounds may fill.
const FILL: f64 = 0.85;
/// Lines of `povray` output quoted when it fails.
const ERROR_LINES: usize = 8;

/// Options of `perifrac render`.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Run directory written by `perifrac run` (holds run.json).
    pub dir: PathBuf,
    /// Render only the frame with this index.
    #[arg(long, conflicts_with = "last")]
    pub frame: Option<usize>,
    /// Render only the last frame.
    #[arg(long)]
    pub last: bool,
    /// Picture width in pixels.
    #[arg(long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Picture height in pixels.
    #[arg(long, default_value_t = 480, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// POV-Ray anti-aliasing threshold (`+A`); 0 turns anti-aliasing off.
    #[arg(long, default_value_t = 0.3)]
    pub antialias: f64,
    /// Only write the .pov scenes; do not run povray.
    #[arg(long)]
    pub no_povray: bool,
    /// Camera azimuth (degrees) round the up axis, from the first horizontal axis (x when z is
    /// up) towards minus the second.
    #[arg(long, default_value_t = CAMERA_AZIMUTH_DEG, allow_negative_numbers = true)]
    pub azimuth: f64,
    /// Camera elevation (degrees, in [-85, 85]) above the horizontal plane through what it
    /// looks at; below 0 it looks up from beneath, and the grounds turn see-through.
    #[arg(long, default_value_t = CAMERA_ELEVATION_DEG, allow_negative_numbers = true)]
    pub elevation: f64,
    /// How much closer than the framing of the whole run the camera comes (> 0; 2 is twice
    /// as close, the object twice as large).
    #[arg(long, default_value_t = 1.0)]
    pub zoom: f64,
}

/// Where the camera sits: azimuth and elevation (degrees) and zoom.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Aim {
    azimuth: f64,
    elevation: f64,
    zoom: f64,
}

impl Default for Aim {
    fn default() -> Self {
        Aim {
            azimuth: CAMERA_AZIMUTH_DEG,
            elevation: CAMERA_ELEVATION_DEG,
            zoom: 1.0,
        }
    }
}

/// `run.json`, as far as rendering needs it; unknown fields are ignored.
///
/// A lenient reading of [`perifrac_scene::RunManifest`] (whose boxes, grounds and balls it
/// shares): every field here may be missing, so a partial or hand-made run file still renders,
/// where the manifest the run writes has them all.
#[derive(Deserialize, Debug)]
struct RunFile {
    #[serde(default)]
    format: Option<String>,
    #[serde(default = "z_up")]
    up: [f64; 3],
    #[serde(default)]
    rest_bounds: Option<Bounds>,
    #[serde(default)]
    grounds: Vec<Ground>,
    #[serde(default)]
    frames: Vec<Frame>,
    #[serde(default)]
    finished: bool,
    #[serde(default)]
    error: Option<serde_json::Value>,
}

fn z_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

/// A frame of [`RunFile`]: [`perifrac_scene::output::FrameJson`] with its optional fields.
#[derive(Deserialize, Debug)]
struct Frame {
    index: usize,
    #[serde(default)]
    time: f64,
    surface: PathBuf,
    #[serde(default)]
    povray: Option<PathBuf>,
    #[serde(default)]
    balls: Vec<Ball>,
    #[serde(default)]
    bounds: Option<Bounds>,
    /// Bounds of the heaviest fragments (90% of the mass); preferred for framing.
    #[serde(default)]
    main_bounds: Option<Bounds>,
    /// Small pieces written as points instead of surfaces.
    #[serde(default)]
    debris: Option<DebrisRef>,
}

/// A frame's debris file in [`Frame`].
#[derive(Deserialize, Debug)]
struct DebrisRef {
    path: PathBuf,
}

/// Where the camera is and what it looks at, in data coordinates.
#[derive(Debug, Clone, Copy)]
struct View {
    location: [f64; 3],
    target: [f64; 3],
    up: [f64; 3],
    /// Unit horizontal axes (`e1 × e2 = up`), for the camera and the lights.
    e1: [f64; 3],
    e2: [f64; 3],
    /// Longest side of the framed bounds.
    extent: f64,
    /// Lowest point along `up` of the framed bounds and of every frame's whole bounds (a
    /// backdrop floor goes below it).
    lowest: f64,
    /// Width over height of the picture.
    aspect: f64,
    /// Camera azimuth and elevation (degrees).
    azimuth: f64,
    elevation: f64,
}

/// Runs `perifrac render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    ensure!(
        args.antialias.is_finite() && args.antialias >= 0.0,
        "--antialias must be a threshold >= 0, got {}",
        args.antialias
    );
    ensure!(
        args.azimuth.is_finite(),
        "--azimuth must be an angle in degrees, got {}",
        args.azimuth
    );
    ensure!(
        (-85.0..=85.0).contains(&args.elevation),
        "--elevation must be in [-85, 85] degrees, got {}",
        args.elevation
    );
    ensure!(
        args.zoom.is_finite() && args.zoom > 0.0,
        "--zoom must be > 0, got {}",
        args.zoom
    );
    let aim = Aim {
        azimuth: args.azimuth,
        elevation: args.elevation,
        zoom: args.zoom,
    };
    let dir = &args.dir;
    ensure!(
        dir.is_dir(),
        "run directory {} does not exist or is not a directory",
        dir.display()
    );
    let run = read_run(dir)?;
    let selected = select_frames(&run, args)?;
    let view = frame_view(&run, args.width, args.height, aim)?;

    let render_dir = dir.join("render");
    std::fs::create_dir_all(&render_dir)
        .with_context(|| format!("cannot create {}", render_dir.display()))?;
    let mut scenes = Vec::with_capacity(selected.len());
    for frame in &selected {
        let include = frame_include(dir, &render_dir, frame)?;
        let debris = frame_debris(dir, frame)?;
        let scene = scene_text(&run, frame, &view, &include, &debris, args);
        let pov = render_dir.join(format!("frame_{:04}.pov", frame.index));
        atomic_write(&pov, |w| w.write_all(scene.as_bytes()))?;
        scenes.push((*frame, pov));
    }
    let n = scenes.len();
    if args.no_povray {
        println!(
            "wrote {n} .pov file(s) in {} (render one with: cd {} && povray +Iframe_NNNN.pov +W{} +H{} -D)",
            render_dir.display(),
            render_dir.display(),
            args.width,
            args.height
        );
        return Ok(());
    }
    let Some(povray) = find_on_path("povray") else {
        println!(
            "povray not found on PATH: wrote {n} .pov files in {}; install povray (apt-get install povray) to get PNGs",
            render_dir.display()
        );
        return Ok(());
    };
    for (k, (frame, pov)) in scenes.iter().enumerate() {
        let start = Instant::now();
        let png = render_frame(&povray, &render_dir, pov, args)
            .with_context(|| format!("rendering frame {} ({})", frame.index, pov.display()))?;
        eprintln!(
            "[{}/{n}] frame {} (t = {} s) -> {} ({:.1} s)",
            k + 1,
            frame.index,
            shown_time(frame.time),
            png.display(),
            start.elapsed().as_secs_f64()
        );
    }
    println!("rendered {n} PNG(s) in {}", render_dir.display());
    Ok(())
}

/// Reads and checks `DIR/run.json`.
fn read_run(dir: &Path) -> Result<RunFile> {
    let path = dir.join("run.json");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "cannot read {} (is {} a run directory written by `perifrac run`?)",
            path.display(),
            dir.display()
        )
    })?;
    let run: RunFile = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a valid perifrac run file", path.display()))?;
    let at = || path.display().to_string();
    if let Some(format) = &run.format {
        ensure!(
            format == RUN_FORMAT,
            "{}: unsupported format \"{format}\" (this perifrac reads \"{RUN_FORMAT}\")",
            at()
        );
    }
    ensure!(
        finite(&run.up) && norm(run.up) > 0.0,
        "{}: \"up\" must be a non-zero finite vector, got {:?}",
        at(),
        run.up
    );
    if let Some(b) = &run.rest_bounds {
        check_bounds(b).with_context(|| format!("{}: rest_bounds", at()))?;
    }
    for (i, g) in run.grounds.iter().enumerate() {
        ensure!(
            finite(&g.point) && finite(&g.normal) && norm(g.normal) > 0.0,
            "{}: ground {i} needs a finite point and a non-zero finite normal",
            at()
        );
    }
    for f in &run.frames {
        if let Some(b) = &f.bounds {
            check_bounds(b).with_context(|| format!("{}: frame {} bounds", at(), f.index))?;
        }
        if let Some(b) = &f.main_bounds {
            check_bounds(b).with_context(|| format!("{}: frame {} main_bounds", at(), f.index))?;
        }
        for (i, ball) in f.balls.iter().enumerate() {
            ensure!(
                finite(&ball.center) && ball.radius.is_finite() && ball.radius > 0.0,
                "{}: frame {} ball {i} needs a finite centre and a positive radius, got {:?} and {}",
                at(),
                f.index,
                ball.center,
                ball.radius
            );
        }
    }
    ensure!(
        !run.frames.is_empty(),
        "{} lists no frames (the run may not have written its first frame yet)",
        at()
    );
    if let Some(error) = run.error.as_ref().filter(|e| !e.is_null()) {
        let error = error
            .as_str()
            .map_or_else(|| error.to_string(), str::to_string);
        eprintln!(
            "note: the run stopped with an error ({error}); rendering the {} frame(s) it wrote",
            run.frames.len()
        );
    } else if !run.finished {
        eprintln!(
            "note: the run has not finished; rendering the {} frame(s) written so far",
            run.frames.len()
        );
    }
    Ok(run)
}

fn check_bounds(b: &Bounds) -> Result<()> {
    ensure!(
        finite(&b.min) && finite(&b.max) && (0..3).all(|k| b.min[k] <= b.max[k]),
        "min {:?} and max {:?} must be finite with min <= max",
        b.min,
        b.max
    );
    Ok(())
}

/// The frames `--frame` / `--last` ask for (all by default).
fn select_frames<'a>(run: &'a RunFile, args: &RenderArgs) -> Result<Vec<&'a Frame>> {
    let frames = &run.frames;
    if let Some(n) = args.frame {
        let frame = frames.iter().find(|f| f.index == n).ok_or_else(|| {
            let lo = frames.iter().map(|f| f.index).min().unwrap_or(0);
            let hi = frames.iter().map(|f| f.index).max().unwrap_or(0);
            anyhow!(
                "--frame {n} is not in the run: its {} frame(s) have indices {lo} to {hi}",
                frames.len()
            )
        })?;
        return Ok(vec![frame]);
    }
    if args.last {
        return Ok(frames.last().into_iter().collect());
    }
    Ok(frames.iter().collect())
}

/// The camera for the whole run: a 3/4 elevated view that fits the union of the rest bounds and
/// every frame's main bounds (the heaviest fragments, so that flying dust does not shrink the
/// object to a speck), or its whole bounds for runs that did not record main bounds.
fn frame_view(run: &RunFile, width: u32, height: u32, aim: Aim) -> Result<View> {
    let boxes: Vec<Bounds> = run
        .rest_bounds
        .iter()
        .chain(
            run.frames
                .iter()
                .filter_map(|f| f.main_bounds.as_ref().or(f.bounds.as_ref())),
        )
        .copied()
        .collect();
    let Some(first) = boxes.first() else {
        bail!(
            "run.json gives neither rest_bounds nor frame bounds: nothing to frame the camera on"
        );
    };
    let mut b = *first;
    for other in &boxes[1..] {
        for k in 0..3 {
            b.min[k] = b.min[k].min(other.min[k]);
            b.max[k] = b.max[k].max(other.max[k]);
        }
    }
    let mut view = view_of(b, run.up, f64::from(width) / f64::from(height), aim);
    // The backdrop goes below everything any frame holds, debris that left the framed bounds
    // included (the wall's exit plume falls below the slab), so that it hides no fragment.
    for full in run.frames.iter().filter_map(|f| f.bounds.as_ref()) {
        for p in corners(full) {
            view.lowest = view.lowest.min(dot(p, view.up));
        }
    }
    Ok(view)
}

/// Places the camera at `aim`'s azimuth and elevation so the 8 corners of `b` fall inside
/// [`FILL`] of the picture, then `aim.zoom` times closer.
fn view_of(b: Bounds, up: [f64; 3], aspect: f64, aim: Aim) -> View {
    let up = scale(up, 1.0 / norm(up));
    // Horizontal axes: the data axis least aligned with up, made perpendicular to it.
    let axis = (0..3)
        .min_by(|&i, &j| up[i].abs().total_cmp(&up[j].abs()))
        .unwrap_or(0);
    let mut e1 = [0.0; 3];
    e1[axis] = 1.0;
    let e1 = normalized(sub(e1, scale(up, dot(e1, up))));
    let e2 = cross(up, e1);
    let to_camera = direction(up, e1, e2, aim.azimuth, aim.elevation);
    let forward = scale(to_camera, -1.0);
    let right = normalized(cross(forward, up));
    let cam_up = cross(right, forward);

    let target = scale(add(b.min, b.max), 0.5);
    let size = sub(b.max, b.min);
    let extent = size[0].max(size[1]).max(size[2]).max(1e-6);
    let tan_x = (FOV_DEG.to_radians() / 2.0).tan() * FILL;
    let tan_y = tan_x / aspect;
    let mut distance = extent * 0.5 / tan_x.min(tan_y);
    let mut lowest = f64::INFINITY;
    for p in corners(&b) {
        let rel = sub(p, target);
        let (x, y, z) = (dot(rel, right), dot(rel, cam_up), dot(rel, forward));
        distance = distance.max(x.abs() / tan_x - z).max(y.abs() / tan_y - z);
        lowest = lowest.min(dot(p, up));
    }
    View {
        location: add(target, scale(to_camera, distance / aim.zoom)),
        target,
        up,
        e1,
        e2,
        extent,
        lowest,
        aspect,
        azimuth: aim.azimuth,
        elevation: aim.elevation,
    }
}

/// The 8 corners of `b`.
fn corners(b: &Bounds) -> [[f64; 3]; 8] {
    std::array::from_fn(|c| [0, 1, 2].map(|k| if c >> k & 1 == 1 { b.max[k] } else { b.min[k] }))
}

/// The `#include` string of the frame's mesh2, converting its PLY into `render/` when the run
/// wrote no include.
fn frame_include(dir: &Path, render_dir: &Path, frame: &Frame) -> Result<String> {
    if let Some(inc) = &frame.povray {
        let full = dir.join(inc);
        ensure!(
            full.is_file(),
            "frame {}: POV-Ray include {} is missing",
            frame.index,
            full.display()
        );
        return include_string(inc);
    }
    let ply = dir.join(&frame.surface);
    ensure!(
        ply.is_file(),
        "frame {}: surface {} is missing",
        frame.index,
        ply.display()
    );
    let surface = read_ply_frame(&ply)
        .with_context(|| format!("frame {}: reading the surface", frame.index))?;
    let name = format!("surface_{:04}.inc", frame.index);
    let vertices: Vec<[f64; 3]> = surface.vertices.iter().map(|p| p.map(f64::from)).collect();
    let normals: Option<Vec<[f64; 3]>> = surface
        .normals
        .as_ref()
        .map(|n| n.iter().map(|p| p.map(f64::from)).collect());
    let view = SurfaceRef {
        vertices: &vertices,
        faces: &surface.faces,
        crack: surface.crack.as_deref(),
        normals: normals.as_deref(),
        ..Default::default()
    };
    write_povray_mesh2(&render_dir.join(&name), &view, MESH_NAME).with_context(|| {
        format!(
            "frame {}: converting {} to POV-Ray",
            frame.index,
            ply.display()
        )
    })?;
    Ok(name)
}

/// The frame's debris as balls (centre, radius; m), none when the frame has no debris file.
fn frame_debris(dir: &Path, frame: &Frame) -> Result<Vec<([f64; 3], f64)>> {
    let Some(debris) = &frame.debris else {
        return Ok(Vec::new());
    };
    let path = dir.join(&debris.path);
    let cloud = read_ply_points(&path)
        .with_context(|| format!("frame {}: reading the debris", frame.index))?;
    let radius = cloud.scalar("radius").ok_or_else(|| {
        anyhow!(
            "frame {}: debris {} has no radius property",
            frame.index,
            path.display()
        )
    })?;
    let balls: Vec<([f64; 3], f64)> = cloud
        .points
        .iter()
        .copied()
        .zip(radius.iter().copied())
        .collect();
    ensure!(
        balls.iter().all(|(_, r)| r.is_finite() && *r > 0.0),
        "frame {}: debris {} has a radius that is not positive and finite",
        frame.index,
        path.display()
    );
    Ok(balls)
}

/// The path as a POV-Ray string literal body, seen from `render/` (POV-Ray runs there); paths in
/// run.json are relative to the run directory, one level up.
fn include_string(path: &Path) -> Result<String> {
    let mut parts: Vec<String> = Vec::new();
    if path.is_relative() {
        parts.push("..".into());
    }
    for c in path.components() {
        match c {
            Component::RootDir => parts.push(String::new()),
            Component::CurDir => {}
            other => {
                let s = other
                    .as_os_str()
                    .to_str()
                    .ok_or_else(|| anyhow!("include path {} is not valid UTF-8", path.display()))?;
                parts.push(s.to_string());
            }
        }
    }
    let s = parts.join("/");
    ensure!(
        !s.contains(['"', '\\']),
        "include path {} contains a quote or backslash POV-Ray cannot take",
        path.display()
    );
    Ok(s)
}

/// The whole .pov scene of one frame.
fn scene_text(
    run: &RunFile,
    frame: &Frame,
    view: &View,
    include: &str,
    debris: &[([f64; 3], f64)],
    args: &RenderArgs,
) -> String {
    let mut s = String::new();
    let w = &mut s;
    // `write!` into a String cannot fail.
    let _ = writeln!(
        w,
        "// perifrac render: frame {} (t = {} s). Render from this directory:\n//   povray +Iframe_{:04}.pov +W{} +H{} -D {}\n\
         // Data have up = {:?} and are right-handed; POV-Ray is y-up and left-handed, so every\n\
         // point here has y and z swapped, and so has the mesh (its matrix).",
        frame.index,
        shown_time(frame.time),
        frame.index,
        args.width,
        args.height,
        antialias_flag(args.antialias),
        run.up
    );
    let _ = writeln!(
        w,
        "#version 3.7;\nglobal_settings {{ assumed_gamma 1.0 }}\n"
    );
    let _ = writeln!(
        w,
        "#declare {MESH_NAME}_surface_texture = texture {{ pigment {{ rgb <0.62, 0.60, 0.55> }} finish {{ ambient 0.12 diffuse 0.8 specular 0.05 roughness 0.05 }} }}"
    );
    let _ = writeln!(
        w,
        "#declare {MESH_NAME}_crack_texture = texture {{ pigment {{ rgb <0.90, 0.38, 0.06> }} finish {{ ambient 0.15 diffuse 0.8 }} }}"
    );
    let _ = writeln!(w, "#include \"{include}\"\n");

    let _ = writeln!(
        w,
        "camera {{\n  perspective\n  location {}\n  sky {}\n  up y\n  right x*{}\n  angle {FOV_DEG}\n  look_at {}\n}}",
        pov(view.location),
        pov(view.up),
        view.aspect,
        pov(view.target)
    );
    let far = view.extent * 20.0;
    // Seen from beneath, the lights come from beneath too.
    let side = if view.elevation < 0.0 { -1.0 } else { 1.0 };
    let key = light_dir(view, 30.0, side * 55.0);
    let fill = light_dir(view, -40.0, side * 20.0);
    let _ = writeln!(
        w,
        "light_source {{ {} color rgb 1.0 }}\nlight_source {{ {} color rgb 0.35 shadowless }}",
        pov(add(view.target, scale(key, far))),
        pov(add(view.target, scale(fill, far)))
    );
    let _ = writeln!(w, "background {{ color rgb <0.78, 0.86, 0.95> }}\n");

    let checker = nice_step(view.extent / 4.0);
    for g in &run.grounds {
        let n = normalized(g.normal);
        // A camera on the ground's back side sees through it: a faint checker that casts no
        // shadow.
        let behind = dot(sub(view.location, g.point), n) < 0.0;
        let (see_through, shadow) = if behind {
            (" transmit 0.8", " no_shadow")
        } else {
            ("", "")
        };
        let _ = writeln!(
            w,
            "plane {{ {}, {} texture {{ pigment {{ checker rgb <0.50, 0.50, 0.47>{see_through} rgb <0.38, 0.38, 0.36>{see_through} scale {checker} }} finish {{ ambient 0.1 diffuse 0.8 }} }}{shadow} }}",
            pov(n),
            dot(n, g.point)
        );
    }
    if run.grounds.is_empty() && view.elevation >= 0.0 {
        // No ground in the run: a plain floor below the lowest point all frames reach, for
        // shadows and a horizon. Nothing touches it.
        let _ = writeln!(
            w,
            "// no ground in the run: a backdrop floor below everything\nplane {{ {}, {} texture {{ pigment {{ rgb <0.55, 0.55, 0.53> }} finish {{ ambient 0.1 diffuse 0.7 }} }} }}",
            pov(view.up),
            view.lowest - 0.05 * view.extent
        );
    }
    for b in &frame.balls {
        // A ball far larger than the view is a press plate over the object, and a camera
        // inside a ball sees nothing else: see-through, no shadow, or it would hide the object.
        let d = sub(view.location, b.center);
        let inside = dot(d, d) < b.radius * b.radius;
        let (see_through, shadow) = if inside || b.radius > PLATE_RADIUS * view.extent {
            (" transmit 0.8", " no_shadow")
        } else {
            ("", "")
        };
        let _ = writeln!(
            w,
            "sphere {{ {}, {} texture {{ pigment {{ rgb <0.55, 0.57, 0.60>{see_through} }} finish {{ ambient 0.05 diffuse 0.55 specular 0.8 roughness 0.01 metallic reflection {{ 0.25 metallic }} }} }}{shadow} }}",
            pov(b.center),
            b.radius
        );
    }
    if !debris.is_empty() {
        // Pieces too small to be worth a surface: balls of their volume, broken material.
        let _ = writeln!(w, "union {{");
        for (c, r) in debris {
            let _ = writeln!(w, "  sphere {{ {}, {r} }}", pov(*c));
        }
        let _ = writeln!(w, "  texture {{ {MESH_NAME}_crack_texture }}\n}}");
    }
    let _ = writeln!(
        w,
        "\nobject {{ {MESH_NAME} texture {{ {MESH_NAME}_surface_texture }} matrix <1,0,0, 0,0,1, 0,1,0, 0,0,0> }}"
    );
    s
}

/// Unit direction towards a light: `azimuth_from_camera` degrees round from the camera's
/// azimuth (positive towards the first horizontal axis, +x when z is up), `elevation` degrees up.
fn light_dir(view: &View, azimuth_from_camera: f64, elevation: f64) -> [f64; 3] {
    direction(
        view.up,
        view.e1,
        view.e2,
        view.azimuth - azimuth_from_camera,
        elevation,
    )
}

/// Unit direction `azimuth` degrees from `e1` towards `-e2` and `elevation` degrees up, for the
/// unit horizontal axes `e1`, `e2` and `up`.
fn direction(up: [f64; 3], e1: [f64; 3], e2: [f64; 3], azimuth: f64, elevation: f64) -> [f64; 3] {
    let (az, el) = (azimuth.to_radians(), elevation.to_radians());
    let h = sub(scale(e1, az.cos()), scale(e2, az.sin()));
    add(scale(h, el.cos()), scale(up, el.sin()))
}

/// Runs povray on one scene inside `render_dir`; returns the PNG path.
fn render_frame(
    povray: &Path,
    render_dir: &Path,
    pov: &Path,
    args: &RenderArgs,
) -> Result<PathBuf> {
    let png = pov.with_extension("png");
    let file = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let antialias = antialias_flag(args.antialias);
    // Every output stream off but the fatal one, so a failure says why (`-GA` would hide that).
    let out = Command::new(povray)
        .current_dir(render_dir)
        .arg(format!("+I{}", file(pov)))
        .arg(format!("+O{}", file(&png)))
        .arg(format!("+W{}", args.width))
        .arg(format!("+H{}", args.height))
        .args(["-D", &antialias, "-GD", "-GR", "-GS", "-GW"])
        .output()
        .with_context(|| format!("cannot run {}", povray.display()))?;
    if !out.status.success() {
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
        // What follows povray's last `==== [Stage...] ====` banner says why; else the tail.
        let after_banner = lines
            .iter()
            .rposition(|l| l.starts_with("===="))
            .map_or(0, |i| i + 1);
        let tail_start = lines.len().saturating_sub(ERROR_LINES);
        let from = if after_banner < lines.len() {
            after_banner.max(tail_start)
        } else {
            tail_start
        };
        let tail = lines[from..].join("\n  ");
        bail!("povray failed ({}):\n  {tail}", out.status);
    }
    ensure!(
        png.is_file(),
        "povray exited successfully but wrote no {}",
        png.display()
    );
    Ok(png)
}

/// The povray anti-aliasing option for `--antialias threshold` (0 turns it off).
fn antialias_flag(threshold: f64) -> String {
    if threshold > 0.0 {
        format!("+A{threshold}")
    } else {
        "-A".to_string()
    }
}

/// The first executable `program` in the PATH directories.
fn find_on_path(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .filter(|d| !d.as_os_str().is_empty())
        .map(|d| d.join(program))
        .find(|p| is_executable(p))
}

#[cfg(unix)]
fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    p.metadata()
        .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn is_executable(p: &Path) -> bool {
    p.is_file() || p.with_extension("exe").is_file()
}

/// 1, 2 or 5 times a power of ten, at most `x`.
fn nice_step(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&s| s <= x)
        .unwrap_or(p)
}

/// A data point as a POV-Ray vector: y and z swapped.
fn pov(p: [f64; 3]) -> String {
    format!("<{}, {}, {}>", p[0], p[2], p[1])
}

fn finite(p: &[f64; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}
fn normalized(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / norm(a))
}

/// A frame time (s) for people: rounded to 9 significant digits, which drops the rounding
/// noise of summed steps (`0.005000000000000044` is `0.005`), then the shortest digits, with
/// an exponent only where they would be long.
fn shown_time(t: f64) -> String {
    let rounded: f64 = format!("{t:.8e}").parse().unwrap_or(t);
    let plain = format!("{rounded}");
    let exponent = format!("{rounded:e}");
    if plain.len() > exponent.len() + 3 {
        exponent
    } else {
        plain
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn frame_times_are_shown_rounded() {
        use super::shown_time;
        // Issue 17: render printed `t = 0.005000000000000044 s`.
        assert_eq!(shown_time(0.005000000000000044), "0.005");
        assert_eq!(shown_time(0.0), "0");
        assert_eq!(shown_time(2.0833333333333335e-4), "0.000208333333");
        assert_eq!(shown_time(1e-9), "1e-9");
        assert_eq!(shown_time(12.5), "12.5");
    }

    use super::*;

    /// Every corner of the framed box projects inside the picture, for z-up and y-up runs and
    /// wide and tall pictures.
    #[test]
    fn camera_frames_every_corner() {
        let b = Bounds {
            min: [-1.0, 0.0, 0.2],
            max: [3.0, 0.5, 1.2],
        };
        for up in [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 1.0, 1.0]] {
            for aspect in [4.0 / 3.0, 0.5] {
                let v = view_of(b, up, aspect, Aim::default());
                let forward = normalized(sub(v.target, v.location));
                let right = normalized(cross(forward, v.up));
                let cam_up = cross(right, forward);
                let tan_x = (FOV_DEG.to_radians() / 2.0).tan();
                for p in corners(&b) {
                    let rel = sub(p, v.location);
                    let depth = dot(rel, forward);
                    assert!(depth > 0.0, "corner {p:?} behind the camera");
                    assert!(dot(rel, right).abs() / depth <= tan_x * FILL + 1e-9);
                    assert!(dot(rel, cam_up).abs() / depth <= tan_x / aspect * FILL + 1e-9);
                }
                // Elevated: the camera is above the target along up.
                assert!(dot(sub(v.location, v.target), normalized(up)) > 0.0);
            }
        }
    }

    #[test]
    fn z_up_camera_sits_at_plus_x_minus_y() {
        let b = Bounds {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        let v = view_of(b, [0.0, 0.0, 1.0], 4.0 / 3.0, Aim::default());
        assert!(v.location[0] > 1.0 && v.location[1] < 0.0 && v.location[2] > 1.0);
        assert_eq!(pov([1.0, 2.0, 3.0]), "<1, 3, 2>");
    }

    /// `--zoom 2` halves the camera's distance to what it looks at; a negative elevation puts
    /// it below, at that angle; the azimuth turns it round the up axis.
    #[test]
    fn aim_moves_the_camera() {
        let b = Bounds {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        let up = [0.0, 0.0, 1.0];
        let base = view_of(b, up, 4.0 / 3.0, Aim::default());
        let zoomed = view_of(
            b,
            up,
            4.0 / 3.0,
            Aim {
                zoom: 2.0,
                ..Aim::default()
            },
        );
        let dist = |v: &View| norm(sub(v.location, v.target));
        assert!((dist(&zoomed) - 0.5 * dist(&base)).abs() < 1e-12 * dist(&base));
        let below = view_of(
            b,
            up,
            4.0 / 3.0,
            Aim {
                elevation: -30.0,
                azimuth: 140.0,
                zoom: 1.0,
            },
        );
        let rel = normalized(sub(below.location, below.target));
        assert!(
            (rel[2] - (-30f64).to_radians().sin()).abs() < 1e-12,
            "{rel:?}"
        );
        // Azimuth 140 degrees from +x towards -y: x < 0, y < 0.
        assert!(rel[0] < 0.0 && rel[1] < 0.0, "{rel:?}");
    }

    #[test]
    fn include_paths_are_seen_from_render_dir() {
        let s = include_string(Path::new("frames/surface_0003.inc")).unwrap();
        assert_eq!(s, "../frames/surface_0003.inc");
        let s = include_string(Path::new("./a.inc")).unwrap();
        assert_eq!(s, "../a.inc");
        let s = include_string(Path::new("/abs/a.inc")).unwrap();
        assert_eq!(s, "/abs/a.inc");
        assert!(include_string(Path::new("fr\"ames/a.inc")).is_err());
    }

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(0.3), 0.2);
        assert_eq!(nice_step(1.0), 1.0);
        assert_eq!(nice_step(7.0), 5.0);
    }
}
