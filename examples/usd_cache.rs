//! Make USD caches of a run directory from code: the whole run as one mesh whose topology
//! changes as it breaks, and one prim per fragment for a rigid-body hand-off, at a playback
//! rate of your choice; then list what the run's fragments came from.
//!
//! Run: `cargo run --release --example usd_cache -- RUN_DIR [FPS]` on a directory written by
//! `perifrac run` (for example `perifrac run data/scenes/wall.toml -o out/wall`).

use std::path::PathBuf;

use perifrac_scene::{export_usd, UsdLayout};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().ok_or("usage: usd_cache RUN_DIR [FPS]")?);
    let fps: Option<f64> = args.next().map(|a| a.parse()).transpose()?;
    for (layout, name) in [
        (UsdLayout::Mesh, "cache.usda"),
        (UsdLayout::Pieces, "pieces.usda"),
    ] {
        let started = std::time::Instant::now();
        let report = export_usd(&dir, Some(&dir.join(name)), layout, fps)?;
        println!(
            "{}: {} frames, {} mesh prim(s), {:.1} MB in {:.2} s",
            report.path.display(),
            report.frames,
            report.meshes,
            report.bytes as f64 / 1e6,
            started.elapsed().as_secs_f64()
        );
    }
    // run.json records where every fragment came from.
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("run.json"))?)?;
    let fragments = run["fragments"]
        .as_array()
        .map_or(&[][..], |f| f.as_slice());
    let split = fragments.iter().filter(|f| !f["parent"].is_null()).count();
    println!(
        "{} fragments over the run, {split} of them split from another",
        fragments.len()
    );
    Ok(())
}
