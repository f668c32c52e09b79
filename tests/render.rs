//! End-to-end tests of `perifrac render` on a small hand-made run directory: a box cut in two at
//! x = 0.5 whose halves drift apart over two frames, one frame with the run's own POV-Ray include
//! and one with only its PLY.

mod common;

use common::{fails, ok};

use std::path::Path;
use std::process::Command;

use perifrac_io::{write_ply, write_povray_mesh2, PlyEncoding, SurfaceRef};
use perifrac_topology::{primitives, NO_TET};
use serde_json::json;

/// Runs `perifrac render` expecting failure; returns stderr.
fn render_fails(args: &[&str]) -> String {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    fails(&all)
}

/// Writes a two-frame run into `dir`: frame 0 has only a PLY, frame 1 a PLY and an include.
fn make_run(dir: &Path) {
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    // 4 x 2 x 2 cells of 6 tets over a 1 x 0.5 x 0.5 box: coarse, quick.
    let mut mesh = primitives::box_mesh([0.0; 3], [1.0, 0.5, 0.5], [4, 2, 2]);
    let centres = mesh.rest_barycentres();
    let mut broken = Vec::new();
    for (t, nbrs) in mesh.neighbours().iter().enumerate() {
        for &n in nbrs {
            if n != NO_TET
                && n as usize > t
                && (centres[t][0] < 0.5) != (centres[n as usize][0] < 0.5)
            {
                broken.push((t as u32, n));
            }
        }
    }
    assert!(mesh.crack_bonds(&broken) > 0);
    mesh.split();
    let masses: Vec<f64> = mesh.rest_volumes().iter().map(|v| 1000.0 * v).collect();
    let velocities: Vec<[f64; 3]> = centres
        .iter()
        .map(|c| [if c[0] < 0.5 { -1.0 } else { 1.0 }, 0.0, 0.0])
        .collect();

    let mut frames = Vec::new();
    for index in 0..2usize {
        if index > 0 {
            mesh.advect(0.1, &masses, &velocities);
        }
        let s = mesh.surface();
        let view = SurfaceRef {
            vertices: &s.vertices,
            faces: &s.faces,
            crack: Some(&s.crack),
            colors: None,
            ..Default::default()
        };
        let ply = format!("frames/surface_{index:04}.ply");
        write_ply(&dir.join(&ply), &view, PlyEncoding::BinaryLittleEndian).unwrap();
        let include = (index == 1).then(|| {
            let inc = format!("frames/surface_{index:04}.inc");
            write_povray_mesh2(&dir.join(&inc), &view, "surface").unwrap();
            inc
        });
        let (mut min, mut max) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &s.vertices {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        frames.push(json!({
            // A time with the rounding noise of summed steps, as a run writes it.
            "index": index, "time": 0.005000000000000044 * index as f64,
            "surface": ply, "povray": include, "particles": null,
            // a ball, and a press plate (a ball far larger than the box) just above it
            "balls": [{"center": [0.5, -0.3, 0.6], "radius": 0.1},
                      {"center": [0.5, 0.25, 100.6], "radius": 100.0}],
            "bounds": {"min": min, "max": max},
            "fragments": 2, "broken_bonds": broken.len(),
            "a_field_added_later": true
        }));
    }
    let run = json!({
        "format": "perifrac-run/1", "scene": "hand_made.toml", "up": [0, 0, 1],
        "rest_bounds": {"min": [0, 0, 0], "max": [1, 0.5, 0.5]},
        "grounds": [{"point": [0, 0, 0], "normal": [0, 0, 1]}],
        "frames": frames, "finished": true, "error": null
    });
    std::fs::write(
        dir.join("run.json"),
        serde_json::to_string_pretty(&run).unwrap(),
    )
    .unwrap();
}

fn camera_block(pov: &str) -> &str {
    let start = pov.find("camera {").expect("a camera");
    let end = start + pov[start..].find('}').expect("the camera closes");
    &pov[start..end]
}

#[test]
fn writes_one_pov_per_frame_including_its_mesh() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    make_run(dir);
    ok(&["render", dir.to_str().unwrap(), "--no-povray"]);
    let render = dir.join("render");
    let pov0 = std::fs::read_to_string(render.join("frame_0000.pov")).unwrap();
    let pov1 = std::fs::read_to_string(render.join("frame_0001.pov")).unwrap();
    // Frame 0 had no include: its PLY was converted beside the scene.
    assert!(pov0.contains("#include \"surface_0000.inc\""), "{pov0}");
    let inc0 = std::fs::read_to_string(render.join("surface_0000.inc")).unwrap();
    assert!(inc0.contains("#declare surface = mesh2"));
    assert!(inc0.contains("texture_list"), "crack flags carried over");
    // Frame 1 uses the run's own include, seen from render/.
    assert!(
        pov1.contains("#include \"../frames/surface_0001.inc\""),
        "{pov1}"
    );
    for pov in [&pov0, &pov1] {
        // The textures are declared before the include so they override its defaults.
        let include_at = pov.find("#include").unwrap();
        for name in ["surface_surface_texture", "surface_crack_texture"] {
            let at = pov.find(&format!("#declare {name}")).unwrap();
            assert!(at < include_at, "{name} declared after the include");
        }
        assert!(pov.contains("object { surface"));
        // The run's ground: a checkered plane (the backdrop floor, for runs without one, is
        // plain).
        assert!(
            pov.lines()
                .any(|l| l.starts_with("plane {") && l.contains("checker")),
            "the ground"
        );
        // the ball solid, the plate see-through and shadowless, or it would hide the box
        let spheres: Vec<&str> = pov.lines().filter(|l| l.starts_with("sphere {")).collect();
        assert_eq!(spheres.len(), 2, "{pov}");
        assert!(!spheres[0].contains("transmit"), "{}", spheres[0]);
        assert!(
            spheres[1].contains("transmit") && spheres[1].contains("no_shadow"),
            "{}",
            spheres[1]
        );
        assert!(pov.contains("light_source"));
    }
    // The time is shown rounded (issue 17: `t = 0.005000000000000044 s`).
    assert!(pov1.contains("frame 1 (t = 0.005 s)"), "{pov1}");
    // One camera for the whole sequence.
    assert_eq!(camera_block(&pov0), camera_block(&pov1));
    assert!(!render.join("frame_0000.png").exists());
}

#[test]
fn renders_the_last_frame_when_povray_is_installed() {
    if !common::have_program("povray") {
        eprintln!("SKIPPED: povray not installed");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    make_run(dir);
    ok(&[
        "render",
        dir.to_str().unwrap(),
        "--last",
        "--width",
        "160",
        "--height",
        "120",
    ]);
    let render = dir.join("render");
    assert!(
        !render.join("frame_0000.pov").exists(),
        "only the last frame"
    );
    let png = std::fs::read(render.join("frame_0001.png")).unwrap();
    // PNG signature, then the IHDR chunk: width and height big-endian at bytes 16..24.
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(png[20..24].try_into().unwrap());
    assert_eq!((width, height), (160, 120));
}

#[test]
fn without_povray_on_the_path_it_writes_scenes_and_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    make_run(dir);
    let out = Command::new(env!("CARGO_BIN_EXE_perifrac"))
        .args(["render", dir.to_str().unwrap(), "--frame", "1"])
        .env("PATH", "")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "render without povray failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("povray not found on PATH"), "{stdout}");
    assert!(stdout.contains("wrote 1 .pov files"), "{stdout}");
    assert!(dir.join("render/frame_0001.pov").exists());
    assert!(!dir.join("render/frame_0000.pov").exists());
}

#[test]
fn missing_run_json_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let err = render_fails(&[tmp.path().to_str().unwrap(), "--no-povray"]);
    assert!(err.contains("run.json"), "{err}");
    let err = render_fails(&[tmp.path().join("absent").to_str().unwrap()]);
    assert!(err.contains("does not exist"), "{err}");
}

#[test]
fn invalid_run_json_gives_line_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("run.json"),
        "{\"format\": \"perifrac-run/1\",\n \"frames\": [ }",
    )
    .unwrap();
    let err = render_fails(&[tmp.path().to_str().unwrap(), "--no-povray"]);
    assert!(err.contains("run.json"), "{err}");
    assert!(err.contains("line 2 column"), "{err}");
    std::fs::write(tmp.path().join("run.json"), "{\"frames\": []}").unwrap();
    let err = render_fails(&[tmp.path().to_str().unwrap(), "--no-povray"]);
    assert!(err.contains("no frames"), "{err}");
}

#[test]
fn frame_out_of_range_and_missing_frame_files_fail() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    make_run(dir);
    let d = dir.to_str().unwrap();
    let err = render_fails(&[d, "--frame", "5", "--no-povray"]);
    assert!(err.contains("--frame 5"), "{err}");
    assert!(err.contains("0 to 1"), "{err}");
    std::fs::remove_file(dir.join("frames/surface_0000.ply")).unwrap();
    let err = render_fails(&[d, "--no-povray"]);
    assert!(err.contains("surface_0000.ply"), "{err}");
    assert!(err.contains("frame 0"), "{err}");
}
