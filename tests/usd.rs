//! The USD cache (`[output] usd`, `perifrac export --usd`), checked by its reference readers:
//! Pixar's USD library (`pip install usd-core`) opens it, runs every validator it registers and
//! finds each frame's points, normals, topology, crack flags, fragment ids, texture coordinates
//! and velocities equal to the PLY frames (tests/python/check_usd.py); Blender 5 (`pip install
//! bpy`) imports it through a Mesh Sequence Cache with the crack attribute on every frame. Each
//! check says SKIPPED when its reader is not installed; CI installs usd-core.

mod common;

use std::path::Path;
use std::process::Command;

use common::{fails, ok, tiny_wall};
use perifrac_io::read_ply_frame;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Whether python3 imports every module in `modules`; says SKIPPED when not.
fn have_python(modules: &[&str], what: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {}", modules.join(", "))])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!("SKIPPED: {what} (python3 lacks {})", modules.join(" or "));
    }
    ok
}

/// The tiny wall with `[output] usd = true`, run for `frames` frames into `dir/out`.
fn run_with_usd(dir: &Path, frames: &str) -> std::path::PathBuf {
    let scene = tiny_wall(dir);
    let text = std::fs::read_to_string(&scene).unwrap();
    let with = text.replace("[output]\n", "[output]\nusd = true\n");
    assert_ne!(with, text);
    std::fs::write(&scene, with).unwrap();
    let out = dir.join("out");
    ok(&["run", s(&scene), "-o", s(&out), "--frames", frames]);
    out
}

fn check(out: &Path, cache: &Path, pieces: bool) -> String {
    let mut args = vec![out.as_os_str(), cache.as_os_str()];
    if pieces {
        args.push("--pieces".as_ref());
    }
    common::python_script("check_usd.py", &args)
}

#[test]
fn the_cache_validates_and_matches_every_frame() {
    if !have_python(&["pxr", "numpy", "plyfile"], "USD cache not checked") {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = run_with_usd(tmp.path(), "4");
    let cache = out.join("tiny_wall.usda");
    assert!(cache.is_file(), "the run wrote no cache");
    let report = check(&out, &cache, false);
    assert!(report.contains(", 0 errors"), "{report}");
    for k in 0..=4 {
        assert!(
            report.contains(&format!("frame {k}: ")) && report.contains("equal"),
            "{report}"
        );
    }
    // The per-fragment layout, through `perifrac export`.
    let pieces = tmp.path().join("pieces.usda");
    ok(&["export", s(&out), "--usd", "--pieces", "-o", s(&pieces)]);
    let report = check(&out, &pieces, true);
    assert!(
        report.contains(", 0 errors") && report.contains("frame 4: "),
        "{report}"
    );
}

/// A shell scene (the bulb of `data/scenes`, its first 0.4 ms: the ball is through the glass)
/// with `[output] usd = true` and `fps`, run into `dir/shell`.
fn shell_run_with_usd(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(common::repo().join("data/scenes/shell_bulb.toml"))
        .unwrap()
        .replace("[output]\n", "[output]\nusd = true\nfps = 30.0\n")
        .replace("duration = 1.5e-3", "duration = 4e-4");
    assert!(text.contains("usd = true") && text.contains("duration = 4e-4"));
    let scene = dir.join("bulb.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("shell");
    ok(&["run", s(&scene), "-o", s(&out), "--frames", "2"]);
    out
}

#[test]
fn a_shell_run_writes_a_cache_that_matches_its_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let out = shell_run_with_usd(tmp.path());
    let cache = out.join("bulb.usda");
    assert!(cache.is_file(), "the shell run wrote no cache");
    let text = std::fs::read_to_string(&cache).unwrap();
    assert!(
        text.contains("timeCodesPerSecond = 30.0"),
        "the scene's fps"
    );
    // Its frames carry unit normals and velocities for the cache to pass on.
    let frame = read_ply_frame(&out.join("frames/surface_0002.ply")).unwrap();
    let normals = frame.normals.expect("normals");
    assert!(normals
        .iter()
        .all(|n| ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-6));
    let velocities = frame.velocities.expect("velocities");
    assert!(velocities.iter().any(|v| v != &[0.0; 3]));
    // Its fragment ids are stable, so the per-piece layout works as for a solid.
    let pieces = out.join("pieces.usda");
    ok(&["export", s(&out), "--usd", "--pieces", "-o", s(&pieces)]);
    if !have_python(&["pxr", "numpy", "plyfile"], "shell USD cache not checked") {
        return;
    }
    for (cache, layout) in [(&cache, false), (&pieces, true)] {
        let report = check(&out, cache, layout);
        assert!(
            report.contains(", 0 errors") && report.contains("frame 2: "),
            "{report}"
        );
    }
}

#[test]
fn export_refuses_what_it_cannot_write_and_reruns_drop_a_stale_cache() {
    let tmp = tempfile::tempdir().unwrap();
    let err = fails(&["export", s(tmp.path()), "--usd"]);
    assert!(err.contains("run.json"), "{err}");
    let out = run_with_usd(tmp.path(), "1");
    let err = fails(&["export", s(&out), "--usd", "--fps", "0"]);
    assert!(err.contains("--fps 0"), "{err}");
    let err = fails(&["export", s(&out), "--usd", "-o", s(&out.join("x.usd"))]);
    assert!(err.contains(".usda"), "{err}");
    // A second run of the same directory without the cache removes the first run's.
    assert!(out.join("tiny_wall.usda").is_file());
    let scene = tmp.path().join("tiny_wall.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("usd = true\n", "")).unwrap();
    ok(&["run", s(&scene), "-o", s(&out), "--frames", "1", "--force"]);
    assert!(!out.join("tiny_wall.usda").exists());
    // The scene keys are checked.
    let bad = text.replace("usd = true\n", "usd = true\nfps = -24.0\n");
    std::fs::write(&scene, bad).unwrap();
    let err = fails(&[
        "run",
        s(&scene),
        "-o",
        s(&tmp.path().join("b")),
        "--frames",
        "1",
    ]);
    assert!(err.contains("output.fps"), "{err}");
}

#[test]
fn blender_5_imports_the_cache_with_its_crack_attribute() {
    if !have_python(
        &["bpy"],
        "Blender 5 (pip install bpy) did not import the USD cache",
    ) {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = run_with_usd(tmp.path(), "3");
    let cache = out.join("tiny_wall.usda");
    let stdout = common::python_script("blender_usd.py", &[cache.as_os_str(), "4".as_ref()]);
    assert!(stdout.contains("modifiers MESH_SEQUENCE_CACHE"), "{stdout}");
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    for (k, f) in run["frames"].as_array().unwrap().iter().enumerate() {
        let frame = read_ply_frame(&out.join(f["surface"].as_str().unwrap())).unwrap();
        let crack = f["crack_triangles"].as_u64().unwrap();
        let want = format!(
            "frame {k}: {} faces, {crack} crack, {} vertices, velocity yes, materials outside crack",
            frame.faces.len(),
            frame.vertices.len()
        );
        assert!(stdout.contains(&want), "{want}\n{stdout}");
    }
}
