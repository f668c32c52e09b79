//! `perifrac bench accuracy | stability | events | contact | speed | look | shells | fracture`: run the benchmark harness and write its
//! Markdown report and PNG plots into a directory.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use perifrac_bench::{accuracy, speed, stability, Effort};

/// Arguments of `perifrac bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// What to measure.
    #[command(subcommand)]
    pub which: Which,
}

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum Which {
    /// Error against references (closed forms, converged FEM) over resolution and horizon, and
    /// the thin-shell model against plate and membrane answers.
    Accuracy {
        /// Output and effort.
        #[command(flatten)]
        common: Common,
        /// Only these cases (cantilever, swing, twist, moduli, wave_speed, xu_bend, xu_twist,
        /// shell_strip, shell_plate, shell_membrane, ghosts); default all.
        #[arg(long, value_delimiter = ',')]
        case: Vec<String>,
    },
    /// Hard cases: each survives, stops with a message, or is reported as a failure.
    Stability(Common),
    /// The explicit step's event search on the default scene's impact: bonds broken,
    /// fragments and crack pattern against a fine-step reference, at equal cost.
    Events(Common),
    /// Contact between particles on the default wall (overlaps with it off and on, its cost,
    /// pair-list builds) and on a block of pieces at rest.
    Contact(Common),
    /// Bond-update rates per material path, seconds per step at the paper's wall size, the
    /// topology's share of a step during heavy fracture, memory per bond, the implicit step.
    Speed(Common),
    /// Thin shells: the event search on a dropped egg shell against plain steps, and the
    /// shell model's speed (its accuracy is in `accuracy`, the `shell_*` cases).
    Shells(Common),
    /// Dynamic fracture against experiment: the Kalthoff-Winkler impact at three resolutions
    /// and a glass plate's crack branching at three tractions (crack angles, branching,
    /// crack-tip speeds against the Rayleigh speed, damage pictures).
    Fracture(Common),
    /// Preview and final alike: the default wall and the bunny drop at three resolutions, with
    /// `s_crit` and with `fracture_energy` (fragments over 1% of the mass, their shares, the
    /// damaged zone's radius).
    Preview(Common),
    /// The cut surface: a split bar's crack roughness, the default wall's crack directions and
    /// fragment sizes at three resolutions, every piece checked closed and right side out.
    Look(Common),
}

/// Options every benchmark takes.
#[derive(clap::Args, Debug)]
pub struct Common {
    /// Directory for the report (`<name>.md`) and the plots (`<name>_<case>.png`).
    #[arg(short, long, default_value = "out/bench")]
    pub output: PathBuf,
    /// Only the smallest cases (seconds): a check that the harness runs, not a measurement.
    #[arg(long)]
    pub quick: bool,
}

/// Runs a benchmark.
pub fn run(args: &BenchArgs) -> Result<()> {
    match &args.which {
        Which::Accuracy { common, case } => accuracy_report(common, case),
        Which::Stability(c) => stability_report(c),
        Which::Speed(c) => speed_report(c),
        Which::Events(c) => events_report(c),
        Which::Contact(c) => contact_report(c),
        Which::Look(c) => look_report(c),
        Which::Shells(c) => shells_report(c),
        Which::Fracture(c) => fracture_report(c),
        Which::Preview(c) => preview_report(c),
    }
}

fn effort(c: &Common) -> Effort {
    if c.quick {
        Effort::Tiny
    } else {
        Effort::Full
    }
}

fn accuracy_report(c: &Common, only: &[String]) -> Result<()> {
    if let Some(bad) = only.iter().find(|o| !accuracy::CASES.contains(&o.as_str())) {
        anyhow::bail!(
            "unknown case {bad:?}; the cases are {}",
            accuracy::CASES.join(", ")
        );
    }
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let names = accuracy::selected(only);
    // the report is rewritten after every case, so an interrupted run keeps what it finished
    let mut sections = String::new();
    for (done, name) in names.iter().enumerate() {
        let case = accuracy::run_case(name, effort(c), &mut progress)?;
        sections.push_str(&case_section(c, &case));
        let mut md = report.header("accuracy");
        if done + 1 < names.len() {
            md.push_str(&format!(
                "(Still running: {}.)\n\n",
                names[done + 1..].join(", ")
            ));
        }
        md.push_str(&sections);
        report.write("accuracy", &md)?;
    }
    Ok(())
}

/// One accuracy case's section of the report: its text, table, plot (written beside the
/// report) and further tables.
fn case_section(c: &Common, case: &accuracy::CaseReport) -> String {
    let png = format!("accuracy_{}.png", case.name);
    let plotted = match case.plot.write_png(&c.output.join(&png)) {
        Ok(()) => true,
        Err(e) => {
            eprintln!("note: {e}; the table is written without its plot");
            false
        }
    };
    let mut md = format!("## {}\n\n{}\n\n", case.title, case.text);
    md.push_str(&case.table.to_markdown());
    if plotted {
        md.push_str(&format!(
            "\n![{}: error against wall time]({png})\n",
            case.title
        ));
    }
    for (heading, table) in &case.tables {
        md.push_str(&format!("\n### {heading}\n\n"));
        md.push_str(&table.to_markdown());
    }
    md.push('\n');
    md
}

fn stability_report(c: &Common) -> Result<()> {
    let report = Report::start(c)?;
    let results = stability::run_all(effort(c), &mut report.progress());
    let failed = results
        .iter()
        .filter(|r| matches!(r.outcome, stability::Outcome::Failed(_)))
        .count();
    let mut md = report.header("stability");
    md.push_str(&stability::table(&results).to_markdown());
    let path = report.write("stability", &md)?;
    anyhow::ensure!(
        failed == 0,
        "{failed} case(s) failed; see {}",
        path.display()
    );
    Ok(())
}

fn events_report(c: &Common) -> Result<()> {
    let report = Report::start(c)?;
    let (table, plot, text) = perifrac_bench::events::impact(effort(c), &mut report.progress())?;
    let mut md = report.header("events");
    md.push_str(&format!("{text}\n\n"));
    md.push_str(&table.to_markdown());
    let png = "events_wall.png";
    match plot.write_png(&c.output.join(png)) {
        Ok(()) => md.push_str(&format!("\n![bonds broken against time]({png})\n")),
        Err(e) => eprintln!("note: {e}; the table is written without its plot"),
    }
    report.write("events", &md)?;
    Ok(())
}

fn contact_report(c: &Common) -> Result<()> {
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let e = effort(c);
    let wall = perifrac_bench::contact::wall(e, &mut progress)?;
    let pile = perifrac_bench::contact::pile(e, &mut progress)?;
    let mut md = report.header("contact");
    md.push_str(
        "## The default wall shot through

",
    );
    md.push_str(&wall.to_markdown());
    md.push_str(
        "
## A block cut into pieces, at rest

",
    );
    md.push_str(&pile.to_markdown());
    report.write("contact", &md)?;
    Ok(())
}

fn shells_report(c: &Common) -> Result<()> {
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let e = effort(c);
    // The runs step on a worker of the pool, as `perifrac run` does (run.rs, `run_on_pool`);
    // the speed case installs its own pools.
    let (egg, text) = rayon::scope(|_| perifrac_bench::shells::egg_drop(e, &mut progress))?;
    let (newmark, newmark_text) =
        rayon::scope(|_| perifrac_bench::shells::egg_newmark(e, &mut progress))?;
    let speed = perifrac_bench::shells::speed(e, &mut progress)?;
    let bulb = rayon::scope(|_| perifrac_bench::shells::bulb(e, &mut progress))?;
    let mut md = report.header("shells");
    md.push_str(
        "The shell model's accuracy (plates against Kirchhoff, a stretched sheet against \
         the closed form) is in `perifrac bench accuracy`, cases `shell_strip`, \
         `shell_plate` and `shell_membrane`.\n\n",
    );
    md.push_str("## The event search on a dropped egg shell (the paper's Figure 9)\n\n");
    md.push_str(&format!("{text}\n\n"));
    md.push_str(&egg.to_markdown());
    md.push_str("\n## The same drop with the paper's integrator (implicit Newmark)\n\n");
    md.push_str(&format!("{newmark_text}\n\n"));
    md.push_str(&newmark.to_markdown());
    md.push_str("\n## Speed: the force pass and the step with colliders\n\n");
    md.push_str(&speed.to_markdown());
    md.push_str(
        "\n## The light bulb (the paper's Figure 1): speed and collisions\n\n\
         `data/scenes/shell_bulb.toml` run whole (1,280 triangles), and at 320. Triangle updates \
         count every sub-step and discarded trial; the rate is over the stepping (fracture, \
         stable-step re-measurements after splits and contact included) per worker thread. \
         The paper's bulb took about 70 minutes on a 2.4 GHz Pentium 4 Xeon, collision \
         detection included, at a mesh size and duration it does not give.\n\n",
    );
    md.push_str(&bulb.to_markdown());
    report.write("shells", &md)?;
    Ok(())
}

fn fracture_report(c: &Common) -> Result<()> {
    use perifrac_bench::fracture;
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let mut runs = Vec::new();
    for cells in fracture::resolutions(effort(c)) {
        runs.push(fracture::kalthoff_winkler(cells, &mut progress)?);
    }
    let (table, facets) = fracture::report(&runs);
    // the header is written again at the end, with the whole run's time
    let mut md = String::from(
        "## Kalthoff-Winkler: crack angles and speeds
\n",
    );
    md.push_str(&format!(
        "The experiment's cracks leave the notch tips at about {:.0} degrees. The angle is the \
         median direction of the particles on the crack {:.0} to {:.0} mm from its tip, when it \
         first reaches {:.0} mm. A crack tip's speed is fitted over {} looks 2 us apart; the \
         Rayleigh speed is {:.0} m/s.\n\n",
        fracture::EXPERIMENT_ANGLE,
        fracture::ANGLE_RANGE.0 * 1e3,
        fracture::ANGLE_RANGE.1 * 1e3,
        fracture::ANGLE_RANGE.1 * 1e3,
        fracture::SPEED_WINDOW,
        runs.first().map_or(0.0, |r| r.rayleigh),
    ));
    md.push_str(&table.to_markdown());
    match facets.write_png(&c.output.join("fracture_kalthoff_winkler.png")) {
        Ok(()) => {
            md.push_str("\n![Kalthoff-Winkler: damage at the end](fracture_kalthoff_winkler.png)\n")
        }
        Err(e) => eprintln!("note: {e}; the table is written without its picture"),
    }
    report.write("fracture", &(report.header("fracture") + &md))?;
    let mut branching = Vec::new();
    for (cells, traction) in fracture::branching_cases(effort(c)) {
        branching.push(fracture::branching(cells, traction, &mut progress)?);
    }
    let (table, facets) = fracture::branching_report(&branching);
    md.push_str("\n## Crack branching in glass under tractions\n\n");
    md.push_str(&format!(
        "A crack runs as two where a column {:.0} mm wide holds two cracks for three columns \
         running. The Rayleigh speed is {:.0} m/s.\n\n",
        1e3 * fracture::COLUMN,
        branching.first().map_or(0.0, |r| r.rayleigh),
    ));
    md.push_str(&table.to_markdown());
    match facets.write_png(&c.output.join("fracture_branching.png")) {
        Ok(()) => md.push_str("\n![Glass branching: damage at the end](fracture_branching.png)\n"),
        Err(e) => eprintln!("note: {e}; the table is written without its picture"),
    }
    report.write("fracture", &(report.header("fracture") + &md))?;
    Ok(())
}

fn preview_report(c: &Common) -> Result<()> {
    use perifrac_bench::preview;
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let mut runs = Vec::new();
    for scene in preview::scenes(effort(c)) {
        let middle = &scene.resolutions[scene.resolutions.len() / 2];
        let energy = scene.matching_energy(middle)?;
        for k in [scene.s_crit_line(), format!("fracture_energy = {energy:e}")] {
            for resolution in &scene.resolutions {
                runs.push(scene.run(resolution, &k, &mut progress)?);
                let (table, spread) = preview::report(&runs);
                let mut md = report.header("preview");
                md.push_str(&format!(
                    "Each scene runs with the paper's `s_crit` and with the `fracture_energy` \
                     that gives it at the middle resolution. A fragment is large from {:.0}% of the \
                     mass. The damaged radius is the mass-weighted RMS distance of the particles \
                     with damage of at least {} from their centre, at rest.\n\n",
                    100.0 * preview::LARGE,
                    perifrac_bench::fracture::ON_A_CRACK,
                ));
                md.push_str(&table.to_markdown());
                md.push_str(
                    "\n### Against the middle resolution\n\nThe mass in fragments of another size \
                     is half the sum of the differences of the large fragments' shares, matched \
                     largest to largest.\n\n",
                );
                md.push_str(&spread.to_markdown());
                report.write("preview", &md)?;
            }
        }
    }
    Ok(())
}

fn look_report(c: &Common) -> Result<()> {
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let e = effort(c);
    let (split, split_faces) = perifrac_bench::look::split(e, &mut progress)?;
    let wall = perifrac_bench::look::default_wall(e, &mut progress)?;
    let (directions, direction_bars) = perifrac_bench::look::wall_directions(&wall);
    let (sizes, size_bars) = perifrac_bench::look::fragment_sizes(e, &wall, &mut progress)?;
    let debris = perifrac_bench::look::debris_shapes(&wall);
    let mut md = report.header("look");
    md.push_str("## A bar pulled apart: the crack's roughness\n\n");
    md.push_str(&split.to_markdown());
    match split_faces.write_png(&c.output.join("look_split.png")) {
        Ok(()) => md.push_str("\n![the split bar's crack faces](look_split.png)\n"),
        Err(e) => eprintln!("note: {e}; the table is written without its picture"),
    }
    md.push_str("\n## The default wall: directions of its cracks in the slab's plane\n\n");
    md.push_str(&directions.to_markdown());
    for (bars, png, what) in [
        (&direction_bars, "look_directions.png", "crack directions"),
        (&size_bars, "look_fragments.png", "fragment sizes"),
    ] {
        if png == "look_fragments.png" {
            md.push_str("\n## The default wall at three resolutions: its fragments\n\n");
            md.push_str(&sizes.to_markdown());
        }
        match bars.write_png(&c.output.join(png)) {
            Ok(()) => md.push_str(&format!("\n![{what}]({png})\n")),
            Err(e) => eprintln!("note: {e}; the table is written without its chart"),
        }
    }
    md.push_str("\n## The default wall's debris: shards or confetti\n\n");
    md.push_str(&debris.to_markdown());
    report.write("look", &md)?;
    Ok(())
}

fn speed_report(c: &Common) -> Result<()> {
    let report = Report::start(c)?;
    let mut progress = report.progress();
    let e = effort(c);
    // first, while the heap is fresh: its runs' peak memory would otherwise count what the
    // allocator kept of the other cases' arrays
    let (side, skipped, floor) = speed::lammps_side_by_side(e, &mut progress)?;
    let paths = speed::paths(e, &mut progress)?;
    let wall = speed::glass_wall(e, &mut progress)?;
    let share = speed::fracture_share(e, &mut progress)?;
    let implicit = speed::implicit_step(e, &mut progress)?;
    let mut md = report.header("speed");
    md.push_str("## Bond-update rate per material path\n\n");
    md.push_str(&paths.to_markdown());
    md.push_str("\n## A glass wall of the paper's size\n\n");
    md.push_str(&wall.to_markdown());
    md.push_str("\n## Where a step goes while a slab shatters\n\n");
    md.push_str(&share.to_markdown());
    md.push_str("\n## The implicit step (Xu's model, one step per 1/24 s frame)\n\n");
    md.push_str(&implicit.to_markdown());
    md.push_str("\n## Side by side with LAMMPS's PERI package\n\n");
    md.push_str(&speed::lammps_match(e));
    md.push_str("\n\n");
    if !skipped.is_empty() {
        md.push_str(&format!("{skipped}\n\n"));
    }
    md.push_str(&side.to_markdown());
    md.push_str("\n## Distance from the memory-bandwidth floor\n\n");
    md.push_str(speed::FLOOR_NOTE);
    md.push_str("\n\n");
    md.push_str(&floor.to_markdown());
    report.write("speed", &md)?;
    Ok(())
}

/// The steps every report shares: its directory, the clock its progress lines and machine line
/// read, its header and its atomic write.
struct Report<'a> {
    output: &'a Path,
    started: Instant,
}

impl<'a> Report<'a> {
    /// Creates the output directory and starts the clock.
    fn start(c: &'a Common) -> Result<Report<'a>> {
        std::fs::create_dir_all(&c.output)
            .with_context(|| format!("cannot create {}", c.output.display()))?;
        Ok(Report {
            output: &c.output,
            started: Instant::now(),
        })
    }

    /// Progress lines on stderr, stamped with the time since the start.
    fn progress(&self) -> impl FnMut(&str) + '_ {
        |what: &str| eprintln!("[{:7.1} s] {what}", self.started.elapsed().as_secs_f64())
    }

    /// The title of `<name>.md` and the machine line, with the time taken so far.
    fn header(&self, name: &str) -> String {
        let mut md = format!("# perifrac bench {name}\n\n");
        md.push_str(&machine_line(self.started.elapsed().as_secs_f64()));
        md
    }

    /// Writes `md` to `<name>.md` in the output directory and says so; returns its path.
    fn write(&self, name: &str, md: &str) -> Result<PathBuf> {
        let path = self.output.join(format!("{name}.md"));
        write_atomic(&path, md)?;
        eprintln!("wrote {}", path.display());
        Ok(path)
    }
}

/// One line on where and how long the benchmark ran.
fn machine_line(wall: f64) -> String {
    let threads = rayon::current_num_threads();
    format!(
        "Ran with {threads} worker thread(s) in {wall:.0} s (`perifrac {}`).\n\n",
        std::env::args().skip(1).collect::<Vec<_>>().join(" ")
    )
}

fn write_atomic(path: &Path, text: &str) -> Result<()> {
    perifrac_io::atomic_write(path, |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("cannot write {}", path.display()))
}
