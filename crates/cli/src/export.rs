//! `perifrac export`: a run directory's frames as one USD cache.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::Args;
use perifrac_scene::{export_usd, UsdLayout, UsdReport};

/// Arguments of `perifrac export`.
#[derive(Args)]
pub struct ExportArgs {
    /// The run directory (written by `perifrac run`).
    dir: PathBuf,
    /// Write a USD cache (`.usda`): the only format so far, and the default.
    #[arg(long)]
    usd: bool,
    /// One mesh prim per fragment, pivoted at its centre of mass, visible from the frame it
    /// separates until the frame it splits (for rigid-body hand-off); default one mesh.
    #[arg(long)]
    pieces: bool,
    /// Output file (default DIR/NAME.usda, NAME the scene's); written atomically.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Playback frames per second (default the scene's `[output] fps`, else 24).
    #[arg(long)]
    fps: Option<f64>,
}

/// Runs `perifrac export`.
pub fn run(args: &ExportArgs) -> Result<()> {
    if let Some(fps) = args.fps {
        if !(fps.is_finite() && fps > 0.0 && fps <= perifrac_scene::setup::MAX_FPS) {
            bail!(
                "--fps {fps}: expected a playback rate above 0 and at most {}",
                perifrac_scene::setup::MAX_FPS
            );
        }
    }
    if let Some(out) = &args.output {
        if out.extension().and_then(|e| e.to_str()) != Some("usda") {
            bail!(
                "{}: the cache is written as USD text; name it .usda",
                out.display()
            );
        }
    }
    let layout = if args.pieces {
        UsdLayout::Pieces
    } else {
        UsdLayout::Mesh
    };
    let started = Instant::now();
    let report = export_usd(&args.dir, args.output.as_deref(), layout, args.fps)
        .with_context(|| format!("cannot export {}", args.dir.display()))?;
    eprintln!("{}", describe(&report, started.elapsed()));
    Ok(())
}

/// One line on a written cache: where, how big, how long it took.
pub fn describe(report: &UsdReport, took: Duration) -> String {
    format!(
        "USD cache {}: {} frames, {} mesh prim(s), {:.1} MB, written in {:.2} s",
        report.path.display(),
        report.frames,
        report.meshes,
        report.bytes as f64 / 1e6,
        took.as_secs_f64()
    )
}
