//! Helpers shared by the end-to-end tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The default scene (`data/scenes/wall.toml`) with fewer cells, written into `dir`; everything
/// else (glass, ball, duration) is the default scene's.
pub fn tiny_wall(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo().join("data/scenes/wall.toml")).unwrap();
    let tiny = text.replace("cells = [24, 24, 3]", "cells = [12, 12, 2]");
    assert_ne!(
        tiny, text,
        "wall.toml no longer has the cells line this test shrinks"
    );
    let path = dir.join("tiny_wall.toml");
    std::fs::write(&path, tiny).unwrap();
    path
}

/// `../shared/data/meshes` beside the checkout (CI clones the repo with `shared/` beside it).
pub fn shared_meshes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes")
}

/// Path of a shared mesh, or `None` (with a note on stderr) when `../shared` is absent.
pub fn shared_mesh(name: &str) -> Option<PathBuf> {
    let p = shared_meshes().join(name);
    if p.exists() {
        Some(p)
    } else {
        eprintln!(
            "SKIPPED: {} not found (../shared/data is absent)",
            p.display()
        );
        None
    }
}

/// Whether `program` runs from the PATH.
pub fn have_program(program: &str) -> bool {
    std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("command -v {program}"))
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// Runs the `perifrac` binary built for these tests.
pub fn perifrac(args: &[&str]) -> Output {
    perifrac_cached(args, &test_cache())
}

/// The stable-step cache of the tests' runs (under the build's scratch directory, not the
/// user's cache).
pub fn test_cache() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("perifrac-cache")
}

/// Runs `perifrac` with its stable-step cache in `cache`.
pub fn perifrac_cached(args: &[&str], cache: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_perifrac"))
        .args(args)
        .env("PERIFRAC_CACHE", cache)
        .output()
        .expect("the perifrac binary runs")
}

/// Runs `perifrac` expecting success; returns stdout (stderr is shown on failure).
pub fn ok(args: &[&str]) -> String {
    let out = perifrac(args);
    assert!(
        out.status.success(),
        "perifrac {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `perifrac` expecting a failure that is reported, not a panic; returns stderr.
pub fn fails(args: &[&str]) -> String {
    let out = perifrac(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "perifrac {args:?} should fail");
    assert!(
        !err.contains("panicked"),
        "perifrac {args:?} panicked:\n{err}"
    );
    err
}

/// Every file under `dir` (relative path -> bytes).
pub fn files(dir: &Path) -> std::collections::BTreeMap<PathBuf, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

/// Runs `python3 tests/python/SCRIPT ARGS...`, asserting it succeeds; returns its stdout.
pub fn python_script(script: &str, args: &[&std::ffi::OsStr]) -> String {
    let res = Command::new("python3")
        .arg(repo().join("tests/python").join(script))
        .args(args)
        .output()
        .expect("python3 runs");
    let stdout = String::from_utf8_lossy(&res.stdout).into_owned();
    assert!(
        res.status.success(),
        "{script} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&res.stderr)
    );
    stdout
}
