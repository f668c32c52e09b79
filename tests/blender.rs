//! Blender reads our frames with the crack flag: `tools/blender_import.py`, run inside
//! Blender, imports a tiny run of the default scene and reports, per frame, the faces and
//! crack faces it made. Checked: it runs without a traceback, reports every frame `run.json`
//! lists, each with the crack-face count `run.json` gives (`crack_triangles`), and saves the
//! .blend; the total face counts are not compared. Skipped (and said so) when `blender` is not
//! installed: it is a large package, not installed by CI.

mod common;

use std::process::Command;

use common::{ok, repo, tiny_wall};

#[test]
fn blender_imports_every_frame_with_its_crack_faces() {
    if !common::have_program("blender") {
        eprintln!("SKIPPED: blender is not installed (apt-get install blender to run this check)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    let out = tmp.path().join("out");
    ok(&[
        "run",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--frames",
        "3",
    ]);
    let blend = tmp.path().join("tiny.blend");
    let res = Command::new("blender")
        .args(["-b", "--python"])
        .arg(repo().join("tools/blender_import.py"))
        .arg("--")
        .arg(&out)
        .args(["--report", "--save"])
        .arg(&blend)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&res.stdout);
    assert!(
        res.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&res.stderr)
    );
    assert!(!stdout.contains("Traceback"), "{stdout}");
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    for f in run["frames"].as_array().unwrap() {
        let index = f["index"].as_u64().unwrap();
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&format!("perifrac frame {index}:")))
            .unwrap_or_else(|| panic!("frame {index} not imported:\n{stdout}"));
        let crack = f["crack_triangles"].as_u64().unwrap();
        assert!(
            line.ends_with(&format!(" {crack} crack faces")),
            "{line} vs {crack}"
        );
    }
    assert!(blend.is_file());
}
