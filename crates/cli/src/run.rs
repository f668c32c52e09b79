//! `perifrac run SCENE -o DIR`: load and validate a scene, then simulate it with a progress bar
//! and write frames into DIR. SIGINT or SIGTERM writes a checkpoint and stops (a second one
//! stops at once); `perifrac run --resume DIR` continues from it.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use perifrac_physics::EstimateMemo;
use perifrac_scene::{
    check_output_dir, AnyScene, AnySetup, Checkpoint, Limits, MemoDir, Observer, Progress,
    SceneError,
};

mod report;

/// Arguments of `perifrac run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Scene file (TOML); see data/scenes/ for examples. With --resume it is optional and, when
    /// given, must be the scene the run was started with.
    #[arg(required_unless_present = "resume")]
    pub scene: Option<PathBuf>,
    /// Output directory for frames and run.json (must be empty unless --force).
    #[arg(short, long, required_unless_present = "resume")]
    pub output: Option<PathBuf>,
    /// Continue the interrupted run in DIR from its checkpoint (written on SIGINT or SIGTERM,
    /// and at frames as `[output] checkpoint_every` says); the files come out byte-identical
    /// to those of a run that was never interrupted.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["output", "force", "frames"])]
    pub resume: Option<PathBuf>,
    /// Overwrite the run files in a non-empty output directory.
    #[arg(long)]
    pub force: bool,
    /// Frames after the initial one (overrides the scene's output.frames).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Worker threads (default: all cores; at most twice the cores). Results are identical for
    /// the same count.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Go on with a run that passes a budget: more memory than is available, more than 1e8
    /// steps, more than 100 GB of output or more than a day's estimated run time.
    #[arg(long)]
    pub allow_large: bool,
    /// No progress bar, only the summary.
    #[arg(short, long)]
    pub quiet: bool,
    /// Neither recall nor keep the stable-step estimate in the cache directory
    /// ($PERIFRAC_CACHE, else $XDG_CACHE_HOME/perifrac, else ~/.cache/perifrac), where a run
    /// of a model built before finds it after one or two force evaluations (same bits, same
    /// output).
    #[arg(long)]
    pub no_cache: bool,
}

/// Most worker threads per core: more only adds switching (compute-bound work), and a typo
/// such as `--threads 100000` would start that many threads.
pub const MAX_THREADS_PER_CORE: usize = 2;

/// The thread count to use for `--threads requested` on a machine with `cores` cores: at most
/// [`MAX_THREADS_PER_CORE`] per core, with a note when it is lowered.
pub fn capped_threads(requested: usize, cores: usize) -> (usize, Option<String>) {
    let most = MAX_THREADS_PER_CORE.saturating_mul(cores.max(1));
    if requested > most {
        let note = format!(
            "--threads {requested} is more than {MAX_THREADS_PER_CORE} per core on this \
             machine's {cores} core(s); using {most}"
        );
        (most, Some(note))
    } else {
        (requested, None)
    }
}

/// Runs a scene.
pub fn run(args: &RunArgs) -> Result<()> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = match args.threads {
        Some(t) => {
            anyhow::ensure!(t >= 1, "--threads must be at least 1");
            let (t, note) = capped_threads(t, cores);
            if let Some(note) = note {
                eprintln!("{note}");
            }
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build_global()
                .context("cannot set up the worker threads")?;
            t
        }
        None => rayon::current_num_threads(),
    };
    if args.frames == Some(0) {
        anyhow::bail!("--frames must be at least 1");
    }
    // The whole run steps on a worker of the pool: a parallel loop started from outside the
    // pool hands its work to a worker and waits to be woken, even when the loop is too short
    // to split; at a shell's 1,280 triangles that hand-off took half the run on one thread
    // (docs/DECISIONS.md, "Runs step on a worker of the pool").
    rayon::scope(|_| run_on_pool(args, threads))
}

/// [`run`] once the worker threads are set up, on a worker of the pool.
fn run_on_pool(args: &RunArgs, threads: usize) -> Result<()> {
    let started = Instant::now();
    // what to run: a fresh scene into an empty directory, or the checkpoint in one
    let (dir, scene, frames, checkpoint) = match &args.resume {
        Some(dir) => {
            let cp = Checkpoint::read(dir)?;
            if let Some(path) = &args.scene {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("cannot read {}", path.display()))?;
                anyhow::ensure!(
                    text == cp.scene_text,
                    "{} is not the scene the run in {} was started with ({}); leave the scene \
                     out to resume that one",
                    path.display(),
                    dir.display(),
                    cp.scene_path.display()
                );
            }
            eprintln!("resuming {} from {}", cp.header.summary, dir.display());
            (dir.as_path(), cp.scene()?, Some(cp.frames), Some(cp))
        }
        None => {
            let (Some(scene), Some(dir)) = (&args.scene, &args.output) else {
                anyhow::bail!("give a scene and -o DIR, or --resume DIR");
            };
            check_output_dir(dir, args.force)?;
            (dir.as_path(), AnyScene::load(scene)?, args.frames, None)
        }
    };
    let limits = Limits {
        threads,
        allow_large: args.allow_large,
        ..Limits::for_this_machine()
    };
    let memo = (!args.no_cache)
        .then(MemoDir::default_dir)
        .flatten()
        .map(MemoDir::new);
    let memo_dyn = memo.as_ref().map(|m| m as &dyn EstimateMemo);
    let setup = AnySetup::new(&scene, frames, &limits, memo_dyn).map_err(|e| match e {
        SceneError::TooLarge { .. } => {
            anyhow::anyhow!("{e}; pass --allow-large to run it anyway")
        }
        other => other.into(),
    })?;
    let on = format!(
        "{} frames of {} steps on {threads} thread(s), setup {:.2} s",
        setup.frames(),
        setup.steps_per_frame(),
        started.elapsed().as_secs_f64()
    );
    match &setup {
        AnySetup::Solid(s) => report::solid_setup(scene.path(), s, &on),
        AnySetup::Shell(s) => report::shell_setup(scene.path(), s, &on),
    }
    if let Some(failure) = memo.as_ref().and_then(MemoDir::failure) {
        eprintln!(
            "warning: the stable-step estimate could not be cached ({failure}); the next run \
             estimates it again (set {} to a writable directory, or pass --no-cache)",
            perifrac_scene::memo::CACHE_ENV
        );
    }
    let interactive = std::io::stderr().is_terminal() && !args.quiet;
    let mut bar = Bar::new(interactive, interrupt_flag()?);
    let t0 = Instant::now();
    let result = match &checkpoint {
        Some(cp) => perifrac_scene::resume(setup, cp, dir, &mut bar),
        None => perifrac_scene::run(setup, dir, &mut bar),
    };
    bar.finish();
    let wall = t0.elapsed().as_secs_f64();
    let summary = result.map_err(|e| stopped(e, scene.path(), dir))?;
    // steps taken by this process (a resumed run took the others before)
    let resumed_at = checkpoint.as_ref().map_or(0, steps_before);
    report::summary(&summary, wall, resumed_at, threads, dir);
    Ok(())
}

/// Steps a resumed run took before its checkpoint.
fn steps_before(cp: &Checkpoint) -> u64 {
    (cp.position.frame as u64 - 1)
        .saturating_mul(cp.steps_per_frame)
        .saturating_add(cp.position.step_in_frame)
}

/// The exit status of a run stopped by SIGINT or SIGTERM (after its checkpoint), as a shell
/// reports a process ended by SIGINT.
pub const INTERRUPTED_EXIT: u8 = 130;

/// The error of a run that did not finish, with what to do next.
fn stopped(e: SceneError, scene: &Path, dir: &Path) -> anyhow::Error {
    match e {
        SceneError::Interrupted { .. } => anyhow::Error::new(e).context(format!(
            "run of {} interrupted; frames written so far are in {}; continue with \
             `perifrac run --resume {}`",
            scene.display(),
            dir.display(),
            dir.display()
        )),
        e => anyhow::Error::new(e).context(format!(
            "run of {} stopped; frames written so far are in {}",
            scene.display(),
            dir.display()
        )),
    }
}

/// True once SIGINT or SIGTERM arrived; a second one ends the process at once (exit 130).
fn interrupt_flag() -> Result<Arc<AtomicBool>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        // the shutdown first: it fires only when the flag is already set, by the first signal
        signal_hook::flag::register_conditional_shutdown(
            sig,
            i32::from(INTERRUPTED_EXIT),
            Arc::clone(&flag),
        )
        .context("cannot install the signal handlers")?;
        signal_hook::flag::register(sig, Arc::clone(&flag))
            .context("cannot install the signal handlers")?;
    }
    Ok(flag)
}

/// The progress bar: simulated time as the position, steps per second, broken bonds,
/// fragments, ETA. Hidden when stderr is not a terminal.
struct Bar {
    bar: ProgressBar,
    started: Instant,
    last: Instant,
    interrupt: Arc<AtomicBool>,
}

impl Bar {
    fn new(visible: bool, interrupt: Arc<AtomicBool>) -> Bar {
        let bar = ProgressBar::with_draw_target(
            Some(1),
            if visible {
                ProgressDrawTarget::stderr_with_hz(4)
            } else {
                ProgressDrawTarget::hidden()
            },
        );
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:30} {percent:>3}% {msg} [{elapsed_precise} < {eta_precise}]",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Bar {
            bar,
            started: Instant::now(),
            last: Instant::now() - Duration::from_secs(1),
            interrupt,
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Observer for Bar {
    fn interrupted(&mut self) -> bool {
        let stop = self.interrupt.load(Ordering::SeqCst);
        if stop {
            self.bar
                .println("interrupted: writing a checkpoint (interrupt again to stop at once)");
        }
        stop
    }

    fn step(&mut self, p: &Progress) {
        // Formatting the message costs more than a small step: refresh a few times a second.
        if self.last.elapsed() < Duration::from_millis(200) && p.steps < p.total_steps {
            return;
        }
        self.last = Instant::now();
        self.bar.set_length(p.total_steps);
        self.bar.set_position(p.steps);
        let rate = p.steps as f64 / self.started.elapsed().as_secs_f64().max(1e-9);
        self.bar.set_message(format!(
            "t {:.3e}/{:.3e} s, {:.0} steps/s, {} broken, {} fragments, frame {}",
            p.time, p.duration, rate, p.broken_bonds, p.fragments, p.frames_written
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_are_capped_at_twice_the_cores() {
        assert_eq!(capped_threads(4, 2), (4, None));
        let (t, note) = capped_threads(100_000, 16);
        assert_eq!(t, 32);
        let note = note.unwrap();
        assert!(
            note.contains("--threads 100000") && note.contains("using 32"),
            "{note}"
        );
        assert_eq!(capped_threads(usize::MAX, usize::MAX).0, usize::MAX);
    }
}
