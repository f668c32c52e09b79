//! Issue 17's reproducers end to end: inputs that panicked, aborted or ran away now get a clear
//! error and a non-zero exit, or a bounded run; misleading messages name the right thing.

mod common;

use std::path::{Path, PathBuf};

use common::{fails, perifrac};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 2 x 2 x 2-cell cube: a run of two frames takes a fraction of a second.
const TINY: &str = "[mesh]\nprimitive = \"box\"\nsize = [0.1, 0.1, 0.1]\ncells = [2, 2, 2]\n\n\
    [[material]]\nyoung = 1e7\npoisson = 0.25\ndensity = 1000.0\n\n\
    [simulation]\nduration = 1e-4\n\n[output]\nframes = 2\n";

/// [`TINY`] with `from` replaced by `to` (nothing replaced when `from` is empty), in `dir`.
fn tiny(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let text = if from.is_empty() {
        TINY.to_string()
    } else {
        TINY.replacen(from, to, 1)
    };
    assert!(
        from.is_empty() || text != TINY,
        "`{from}` is not in the scene"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn mesh_primitives_that_panicked_or_aborted_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o.mesh");
    for (args, expect) in [
        (vec!["box:1e8x1x1"], "too flat"),
        (vec!["box:1e-30x1x1"], "too flat"),
        (vec!["box:1e308x1x1"], "beyond 1e50"),
        (vec!["bar:1e308x1x1"], "beyond 1e50"),
        (
            vec!["box:1x1x1", "--cells", "4294967296,4294967296,1"],
            "more than a mesh can index",
        ),
        (
            vec!["box:1x1x1", "--cells", "9223372036854775808,2,1"],
            "more than a mesh can index",
        ),
        // 3.6e9 tets fit 32-bit ids but not memory: refused with the estimate.
        (vec!["box:1x1x1", "--cells", "1000,1000,600"], "of memory"),
    ] {
        let mut all = vec!["mesh"];
        all.extend(&args);
        all.extend(["-o", s(&out)]);
        let err = fails(&all);
        assert!(
            err.contains(args[0]) || err.contains("tets"),
            "{args:?}: {err}"
        );
        assert!(
            err.contains(expect),
            "{args:?}: expected `{expect}` in {err}"
        );
        assert!(!out.exists(), "{args:?} wrote a mesh");
    }
    let err = fails(&[
        "mesh",
        "box:1x1x1",
        "--cells",
        "1000,1000,600",
        "-o",
        s(&out),
    ]);
    assert!(err.contains("--allow-large"), "{err}");
    // A directory is neither a surface nor a primitive.
    let err = fails(&["mesh", s(tmp.path()), "-o", s(&out)]);
    assert!(err.contains("is a directory"), "{err}");
}

#[test]
fn scenes_that_never_fit_or_finish_are_refused_before_they_start() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let out = dir.join("out");
    for (name, from, to, expect) in [
        // 228 s and 7 GB before aborting, in issue 17.
        (
            "memory.toml",
            "cells = [2, 2, 2]",
            "cells = [271, 271, 271]",
            "of memory",
        ),
        // Aborted on a wrapped product.
        (
            "index.toml",
            "cells = [2, 2, 2]",
            "cells = [4294967296, 4294967296, 1]",
            "more than a mesh can index",
        ),
        (
            "frames.toml",
            "frames = 2",
            "frames = 1000000000",
            "budget of 1.000e8 steps",
        ),
        (
            "duration.toml",
            "duration = 1e-4",
            "duration = 1e6",
            "budget of 1.000e8 steps",
        ),
        (
            "ball.toml",
            "[output]",
            "[[ball]]\ncenter = [0.05, 0.05, 0.3]\nradius = 0.05\nvelocity = [0.0, 0.0, -1e12]\n\
             density = 7800.0\n\n[output]",
            "contact travel limit",
        ),
    ] {
        let scene = tiny(dir, name, from, to);
        let err = fails(&["run", s(&scene), "-o", s(&out)]);
        assert!(err.contains(expect), "{name}: expected `{expect}` in {err}");
        assert!(err.contains(name), "{name}: names the scene: {err}");
        assert_eq!(err.lines().count(), 1, "{name}: one message: {err}");
        assert!(!out.exists(), "{name}: the output directory was created");
        if expect != "more than a mesh can index" {
            assert!(err.contains("--allow-large"), "{name}: {err}");
        }
    }
}

#[test]
fn a_huge_thread_count_is_capped_with_a_message_and_the_estimate_is_printed() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny(tmp.path(), "tiny.toml", "", "");
    let out = tmp.path().join("out");
    let res = perifrac(&["run", s(&scene), "-o", s(&out), "--threads", "100000"]);
    let err = String::from_utf8_lossy(&res.stderr);
    assert!(res.status.success(), "{err}");
    assert!(
        err.contains("--threads 100000 is more than 2 per core"),
        "{err}"
    );
    assert!(err.contains("; using "), "{err}");
    // The setup line carries the work estimate.
    assert!(
        err.contains("estimated ") && err.contains("of memory"),
        "{err}"
    );
    assert!(out.join("run.json").is_file());
}

#[test]
fn surfaces_with_nan_or_nothing_in_them_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name);
    let out = p("x.ply");
    // Issue 17: exit 0 and an empty PLY.
    std::fs::write(p("empty.obj"), "").unwrap();
    let err = fails(&["convert", s(&p("empty.obj")), s(&out)]);
    assert!(
        err.contains("empty.obj") && err.contains("no vertices"),
        "{err}"
    );
    // Issue 17: exit 0 and NaN in the PLY.
    std::fs::write(
        p("cube_nan.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 nan\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
    )
    .unwrap();
    let err = fails(&["convert", s(&p("cube_nan.obj")), s(&out)]);
    assert!(err.contains("cube_nan.obj:3: "), "{err}");
    assert!(!out.exists());
}

#[test]
fn surfaces_and_directories_given_as_tet_meshes_say_what_they_are() {
    let tmp = tempfile::tempdir().unwrap();
    let cow = tmp.path().join("cow.off");
    std::fs::write(
        &cow,
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    )
    .unwrap();
    let err = fails(&["info", s(&cow)]);
    assert!(err.contains("is a surface mesh"), "{err}");
    assert!(
        err.contains(&format!("perifrac mesh {}", cow.display())),
        "{err}"
    );
    let err = fails(&["convert", s(&cow), s(&tmp.path().join("cow.mesh"))]);
    assert!(err.contains("perifrac mesh"), "{err}");
    let err = fails(&["info", s(tmp.path())]);
    assert!(err.contains("is a directory"), "{err}");
}
