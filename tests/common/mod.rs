//! Helpers shared by the end-to-end tests.
#![allow(dead_code)]

use std::path::PathBuf;

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
