//! `perifrac run SCENE -o DIR`: load and validate a scene, then simulate it with a progress bar
//! and write frames into DIR.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use perifrac_scene::{check_output_dir, Limits, Observer, Progress, Scene, SceneError, Setup};

/// Arguments of `perifrac run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Scene file (TOML); see data/scenes/ for examples.
    pub scene: PathBuf,
    /// Output directory for frames and run.json (must be empty unless --force).
    #[arg(short, long)]
    pub output: PathBuf,
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
    check_output_dir(&args.output, args.force)?;
    let started = Instant::now();
    let scene = Scene::load(&args.scene)?;
    let limits = Limits {
        threads,
        allow_large: args.allow_large,
        ..Limits::for_this_machine()
    };
    let setup = Setup::with_limits(&scene, args.frames, &limits).map_err(|e| match e {
        SceneError::TooLarge { .. } => {
            anyhow::anyhow!("{e}; pass --allow-large to run it anyway")
        }
        other => other.into(),
    })?;
    let info = &setup.info;
    let frames = setup.frames;
    eprintln!(
        "{}: {} particles, {} bonds, {} model, {} integrator, horizon {:.3e} m, dt {:.3e} s \
         (explicit stable limit {:.3e} s{}), {} frames of {} steps, {} on {threads} \
         thread(s), setup {:.2} s",
        args.scene.display(),
        info.particles,
        info.bonds,
        info.model,
        info.integrator,
        info.horizon,
        info.dt,
        info.dt_limit,
        if info.travel_limit.is_finite() {
            format!(", contact travel limit {:.3e} s", info.travel_limit)
        } else {
            String::new()
        },
        frames,
        setup.steps_per_frame,
        info.estimate,
        started.elapsed().as_secs_f64()
    );
    let interactive = std::io::stderr().is_terminal() && !args.quiet;
    let mut bar = Bar::new(interactive);
    let t0 = Instant::now();
    let result = perifrac_scene::run(setup, &args.output, &mut bar);
    bar.finish();
    let wall = t0.elapsed().as_secs_f64();
    let summary = result.with_context(|| {
        format!(
            "run of {} stopped; frames written so far are in {}",
            args.scene.display(),
            args.output.display()
        )
    })?;
    let t = summary.stage_times;
    let share =
        |d: std::time::Duration| 100.0 * d.as_secs_f64() / t.total().as_secs_f64().max(1e-12);
    eprintln!(
        "done in {wall:.2} s: {} steps ({:.0} steps/s), t = {:.4e} s, {} bonds broken, \
         {} fragments, {} crack triangles",
        summary.steps,
        summary.steps as f64 / wall.max(1e-9),
        summary.time,
        summary.broken_bonds,
        summary.fragments,
        summary.crack_triangles,
    );
    eprintln!(
        "energy at the end: kinetic {:.4e} J, elastic {:.4e} J{}",
        summary.kinetic_energy,
        summary.elastic_energy,
        if summary.ball_kinetic_energy > 0.0 {
            format!(", balls {:.4e} J", summary.ball_kinetic_energy)
        } else {
            String::new()
        }
    );
    if summary.integrator == "implicit" {
        let it = summary.solver;
        eprintln!(
            "implicit: {} iterations ({:.1} per step, {} evaluations), {} steps at the \
             iteration cap, {} factorisations ({:.2} s), solves {:.2} s, factor {:.1} MB",
            it.iterations,
            it.iterations as f64 / summary.steps.max(1) as f64,
            it.evaluations,
            it.capped_steps,
            it.factorizations,
            it.factor_seconds,
            it.solve_seconds,
            it.factor_bytes as f64 / 1e6
        );
    }
    eprintln!(
        "time per stage: physics {:.0}%, topology {:.0}%, advection {:.0}%, output {:.0}%",
        share(t.physics),
        share(t.topology),
        share(t.advect),
        share(t.output)
    );
    eprintln!(
        "{} frames in {}",
        summary.frames_written,
        args.output.join("frames").display()
    );
    Ok(())
}

/// The progress bar: simulated time as the position, steps per second, broken bonds,
/// fragments, ETA. Hidden when stderr is not a terminal.
struct Bar {
    bar: ProgressBar,
    started: Instant,
    last: Instant,
}

impl Bar {
    fn new(visible: bool) -> Bar {
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
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Observer for Bar {
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
