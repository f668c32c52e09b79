//! The harness itself on its tiny cases: every accuracy row has a finite error, refining the
//! cantilever does not make it worse, the motion cases carry every method (Chen, Chen fitted,
//! both on unstructured tets, and Xu explicit, Xu implicit at 1, 4 and 16 steps per frame) and
//! Xu's static cases their implicit runs, no stability case ends in a NaN or a panic, the speed
//! tables hold positive rates, and the event-search report holds its five runs.
//! (The measurements are in BENCHMARKS.md, made with the full cases; timings are never
//! asserted.)

use perifrac_bench::stability::Outcome;
use perifrac_bench::{accuracy, speed, stability, Effort};

#[test]
fn accuracy_rows_are_finite_and_refinement_helps_the_cantilever() {
    let reports = accuracy::run_all(Effort::Tiny, &[], &mut |_| {}).unwrap();
    let names: Vec<&str> = reports.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, accuracy::CASES);
    for r in &reports {
        assert!(!r.runs.is_empty(), "{}", r.name);
        for run in &r.runs {
            assert!(
                run.error.is_finite() && run.value.is_finite() && run.wall_s >= 0.0,
                "{}: {run:?}",
                r.name
            );
        }
        assert_eq!(r.table.rows.len(), r.runs.len());
        assert!(r.table.to_markdown().contains(&r.runs[0].resolution));
    }
    let by_name = |n: &str| reports.iter().find(|r| r.name == n).unwrap();
    for name in ["swing", "twist"] {
        let r = by_name(name);
        let methods: Vec<&str> = r.runs.iter().map(|run| run.method.as_str()).collect();
        assert_eq!(
            methods,
            [
                "PD Chen explicit",
                "PD Chen fitted explicit",
                "PD Chen explicit unstructured",
                "PD Chen fitted explicit unstructured",
                "PD Xu explicit",
                "PD Xu implicit 1/frame",
                "PD Xu implicit 4/frame",
                "PD Xu implicit 16/frame"
            ],
            "{name}"
        );
        // 1, 4 and 16 steps per 1/24 s frame over 0.6 s and 0.3 s, rounded to whole steps
        let steps: Vec<u64> = r.runs[5..].iter().map(|run| run.steps).collect();
        let want: [u64; 3] = if name == "swing" {
            [14, 58, 230]
        } else {
            [7, 29, 115]
        };
        assert_eq!(steps, want, "{name}");
        for run in &r.runs[5..] {
            let st = run
                .implicit
                .expect("implicit rows carry the solver's counters");
            assert!(
                st.iterations > 0 && st.evaluations >= st.iterations,
                "{run:?}"
            );
        }
        assert!(r.runs[..5].iter().all(|run| run.implicit.is_none()));
        // the speed-against-error table has every run of its resolution
        let (_, speed) = &r.tables[0];
        assert_eq!(speed.rows.len(), r.runs.len(), "{name}");
    }
    for name in ["xu_bend", "xu_twist"] {
        let r = by_name(name);
        assert_eq!(r.runs.len(), 1, "{name}");
        let st = r.runs[0].implicit.expect("an implicit run");
        assert!(st.iterations > 0, "{name}: {st:?}");
        // the error is a deviation, positive; the reading table has one row per run
        assert!(r.runs[0].error > 0.0, "{name}");
        assert_eq!(r.tables[0].1.rows.len(), 1, "{name}");
    }
    // The shells' coarsest plates sag less than Kirchhoff's answer (measured -19.0% for the
    // strip at 10x2 and -9.5% for the square at 8x8: the model is too stiff on coarse meshes,
    // converging at first order), so within (-30%, 0).
    for name in ["shell_strip", "shell_plate"] {
        let run = &by_name(name).runs[0];
        assert!(run.error < 0.0 && run.error > -0.3, "{name}: {run:?}");
    }
    // A uniform stretch: the pull is the closed form to round-off (measured 3e-14).
    let membrane = &by_name("shell_membrane").runs[0];
    assert!(membrane.error.abs() < 1e-10, "{membrane:?}");
    let cantilever = &reports[0];
    let series = |method: &str| -> Vec<_> {
        cantilever
            .runs
            .iter()
            .filter(|r| r.method == method)
            .collect()
    };
    let pd = series("PD");
    // 20x2x2 then 30x3x3 cells at k = 1.5: measured +8.3% then -3.4%.
    assert_eq!(pd.len(), 2);
    assert!(pd[1].error.abs() <= pd[0].error.abs(), "{pd:?}");
    // With the fitted dilatation: measured +21.6% then +8.0%, soft and converging.
    let fitted = series("PD fitted");
    assert_eq!(fitted.len(), 2);
    assert!(fitted[1].error.abs() < fitted[0].error.abs(), "{fitted:?}");
    assert!(fitted.iter().all(|r| r.error > 0.0), "{fitted:?}");
    // and the second table carries an order and a sideways share for every peridynamic row:
    // the default and fitted on the Kuhn lattice, the mirrored lattice and unstructured tets
    let (_, convergence) = &cantilever.tables[0];
    assert_eq!(convergence.rows.len(), 12);
    // The mirrored lattice two cells across is symmetric across the bar: no sideways
    // deflection but round-off (the Kuhn lattice's is 7.5-7.7% there); three across it is not.
    for fitted in [false, true] {
        let method = if fitted {
            "PD fitted mirrored"
        } else {
            "PD mirrored"
        };
        let rows: Vec<&Vec<String>> = convergence
            .rows
            .iter()
            .filter(|row| row[0] == method)
            .collect();
        assert_eq!(rows.len(), 2, "{method}");
        assert_eq!(rows[0][5], "0.00%", "{method}: {:?}", rows[0]);
        assert_ne!(rows[1][5], "0.00%", "{method}: {:?}", rows[1]);
    }
    // The quadratic reference is within 1% of scikit-fem's converged answer already at 20
    // cells along (measured -0.52%), and linear tets lock (measured -49%).
    let p2 = cantilever
        .runs
        .iter()
        .rfind(|r| r.method == "FEM P2")
        .unwrap();
    assert!(
        (p2.value / accuracy::SCIKIT_FEM - 1.0).abs() < 0.01,
        "{p2:?}"
    );
    let p1 = cantilever
        .runs
        .iter()
        .find(|r| r.method == "FEM P1")
        .unwrap();
    assert!(p1.error < -0.3, "{p1:?}");
}

#[test]
fn no_stability_case_ends_in_a_nan_or_a_panic() {
    let results = stability::run_all(Effort::Tiny, &mut |_| {});
    assert!(results.len() >= 12);
    for r in &results {
        assert!(
            !matches!(r.outcome, Outcome::Failed(_)),
            "{}: {:?}",
            r.name,
            r.outcome
        );
        assert!(r.max_speed.is_finite(), "{}", r.name);
    }
    let by_name = |s: &str| results.iter().find(|r| r.name.contains(s)).unwrap();
    // Half the stable step survives; one and a half and twice are stopped by the guard with a
    // message that says what to do.
    assert_eq!(by_name("at 0.5 x").outcome, Outcome::Survived);
    for f in ["at 1.5 x", "at 2 x"] {
        match &by_name(f).outcome {
            Outcome::Stopped(m) => assert!(m.contains("reduce the time step"), "{m}"),
            other => panic!("{f}: {other:?}"),
        }
    }
    // Both presses run to the end (a layer of particles driven down instead was stopped by
    // the guard once particles squeezed past each other, before contact between particles).
    for c in ["press a steel", "press a brittle", "inversion guard"] {
        assert_eq!(by_name(c).outcome, Outcome::Survived, "{c}");
    }
    // Both elastic presses count their folds (at this size, 4 cells squeezed into 0.8 of one,
    // both fold: 1,072 and 919 pairs; the full report's 8-cell block is where the guard shows)
    let folds = |c: &str| {
        by_name(c)
            .turned_over
            .expect("an unbroken press counts its folds")
    };
    eprintln!(
        "turned over: {} without the guard, {} with it",
        folds("press a steel"),
        folds("inversion guard")
    );
    // The guard is in the model the guarded press steps: its springs shorten the stable step
    // (measured 1.6 times more steps at 8 cells; a guard that went missing would give as many)
    let steps = |c: &str| by_name(c).steps;
    assert!(
        steps("inversion guard") > steps("press a steel"),
        "{} against {}",
        steps("inversion guard"),
        steps("press a steel")
    );
    // A rigid spin keeps its energy to rounding (measured 7e-10 over 300 steps).
    assert!(by_name("spinning").energy_drift.abs() < 1e-6);
}

#[test]
fn speed_tables_hold_positive_rates() {
    let t = speed::paths(Effort::Tiny, &mut |_| {}).unwrap();
    // six material paths with the scalar calibration, then the same six fitted
    assert_eq!(t.rows.len(), 12);
    for row in &t.rows {
        let rate: f64 = row[5].parse().unwrap();
        let bytes: f64 = row[8].parse().unwrap();
        assert!(rate > 0.0 && bytes > 8.0, "{row:?}");
    }
    for (cal, fit) in t.rows[..6].iter().zip(&t.rows[6..]) {
        assert_eq!(
            (cal[0].as_str(), cal[1].as_str()),
            (fit[0].as_str(), "calibrated")
        );
        assert_eq!(fit[1], "fitted (default)");
        // the fit keeps each bond's weight and its reverse's (16 bytes a bond); its per-particle
        // arrays add under 0.5 byte a bond at this block's 112 bonds a particle
        let extra = fit[8].parse::<f64>().unwrap() - cal[8].parse::<f64>().unwrap();
        assert!((15.9..16.5).contains(&extra), "{cal:?} {fit:?}");
    }
    let share = speed::fracture_share(Effort::Tiny, &mut |_| {}).unwrap();
    let broken: u64 = share.rows[0][2].parse().unwrap();
    assert!(broken > 0, "the slab did not break: {:?}", share.rows[0]);
    // the implicit step: one row on one thread and one on the pool, each with iterations,
    // evaluations (at least one per iteration) and a factor in memory
    let implicit = speed::implicit_step(Effort::Tiny, &mut |_| {}).unwrap();
    assert_eq!(implicit.rows.len(), 2);
    for row in &implicit.rows {
        let iterations: f64 = row[5].parse().unwrap();
        let evaluations: f64 = row[6].parse().unwrap();
        let factor_mb: f64 = row[11].parse().unwrap();
        assert!(iterations > 0.0 && evaluations >= iterations, "{row:?}");
        assert!(factor_mb > 0.0, "{row:?}");
    }
}

#[test]
fn lammps_side_by_side_has_perifrac_rows_and_lammps_rows_when_installed() {
    let (t, skipped, floor) = speed::lammps_side_by_side(Effort::Tiny, &mut |_| {}).unwrap();
    let ours: Vec<_> = t.rows.iter().filter(|r| r[2] == "perifrac").collect();
    // elastic and brittle, on one core and on two
    assert_eq!(ours.len(), 4);
    assert_eq!(floor.rows.len(), 4);
    for row in &ours {
        // the tiny cube: 6^3 Kuhn cells
        assert_eq!(row[3], "1296", "{row:?}");
        let rate: f64 = row[6].parse().unwrap();
        // seconds print with two decimals, so the tiny cube's setup may print as 0.00; its
        // share of the whole run, taken before rounding, must be a part of it
        let setup: f64 = row[7].parse().unwrap();
        // the first run's setup: a number (it may print as the later runs' does)
        let _first: f64 = row[8].parse().unwrap();
        let share: f64 = row[9].trim_end_matches('%').parse().unwrap();
        let whole: f64 = row[10].parse().unwrap();
        assert!(rate > 0.0 && whole > 0.0, "{row:?}");
        assert!(share > 0.0 && share < 100.0, "{row:?}");
        assert!(whole >= setup, "{row:?}");
    }
    let theirs: Vec<_> = t
        .rows
        .iter()
        .filter(|r| r[2].starts_with("peri/"))
        .collect();
    if skipped.is_empty() {
        assert_eq!(theirs.len(), 4, "{:?}", t.rows);
        for row in &theirs {
            // 11^3 lattice sites, the nearest cube to 1296
            assert_eq!(row[3], "1331", "{row:?}");
            let bonds: f64 = row[4].parse().unwrap();
            assert!(bonds > 0.0, "{row:?}");
        }
    } else {
        assert!(skipped.contains("LAMMPS"), "{skipped}");
    }
    for row in &floor.rows {
        let gbs: f64 = row[2].parse().unwrap();
        assert!(gbs > 0.0, "{row:?}");
    }
}

#[test]
fn plots_are_written_as_png() {
    if !perifrac_bench::FONT_PATHS
        .iter()
        .any(|p| std::path::Path::new(p).exists())
    {
        eprintln!("SKIPPED: no TrueType font (apt-get install fonts-dejavu-core)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let plot = perifrac_bench::Plot {
        title: "test".into(),
        x_label: "wall time (s)".into(),
        y_label: "|relative error|".into(),
        series: vec![perifrac_bench::Series {
            name: "PD k = 1.5".into(),
            points: vec![(0.1, 0.2), (1.0, 0.05), (f64::NAN, 1.0), (10.0, 0.0)],
        }],
    };
    let path = tmp.path().join("p.png");
    plot.write_png(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // Nothing but the picture is left behind.
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
}

#[test]
fn the_event_search_report_holds_every_run_and_the_search_does_extra_work() {
    let (table, plot, _) = perifrac_bench::events::impact(Effort::Tiny, &mut |_| {}).unwrap();
    assert_eq!(
        table.rows.len(),
        5,
        "fixed, search, bond test only, equal cost, reference"
    );
    let evaluations: Vec<u64> = table.rows.iter().map(|r| r[2].parse().unwrap()).collect();
    // the search tries more sub-steps than the fixed step takes, the reference the most
    assert!(evaluations[1] > evaluations[0], "{evaluations:?}");
    assert!(evaluations[4] > evaluations[0], "{evaluations:?}");
    // the reference shares all its broken bonds with itself, every run some
    let shared: Vec<f64> = table.rows.iter().map(|r| r[8].parse().unwrap()).collect();
    assert_eq!(shared[4], 1.0);
    assert!(shared.iter().all(|&s| s > 0.0 && s <= 1.0), "{shared:?}");
    assert_eq!(
        plot.series.len(),
        4,
        "every run but the reference against it"
    );
}

#[test]
fn contact_tables_measure_without_changing_the_run() {
    let t = perifrac_bench::contact::wall(Effort::Tiny, &mut |_| {}).unwrap();
    assert_eq!(t.rows.len(), 5);
    let (off, measured) = (&t.rows[0], &t.rows[1]);
    // Contact of stiffness 0 only measures: the same step, steps, bonds broken and fragments
    // as no contact at all.
    for col in [1, 2, 11, 12] {
        assert_eq!(off[col], measured[col], "column {col}");
    }
    // A stiffer contact shortens the step.
    let dt = |r: &Vec<String>| r[1].parse::<f64>().unwrap();
    assert!(dt(&t.rows[4]) < dt(&t.rows[3]) && dt(&t.rows[3]) <= dt(&t.rows[2]));
    let pile = perifrac_bench::contact::pile(Effort::Tiny, &mut |_| {}).unwrap();
    assert_eq!(pile.rows.len(), 2);
    // Eight pieces, nothing moving: one build, no pair touching.
    assert_eq!(pile.rows[1][3], "8");
    assert_eq!(pile.rows[1][7], "1");
    assert_eq!(pile.rows[1][9], "0");
}

#[test]
fn look_tables_hold_every_case_with_sound_pieces() {
    let (split, faces) = perifrac_bench::look::split(Effort::Tiny, &mut |_| {}).unwrap();
    // Two angles to the lattice and an unstructured bar, as cut and smoothed; a panel of crack
    // faces for each.
    assert_eq!(split.rows.len(), 6);
    assert_eq!(faces.panels.len(), 6);
    // Every bar is measured once it is in two (a time, not "not by").
    assert!(split.rows.iter().all(|r| r[3].parse::<f64>().is_ok()));
    assert!(faces
        .panels
        .iter()
        .all(|p| !p.triangles.is_empty() && p.values.len() == p.triangles.len()));
    let wall = perifrac_bench::look::default_wall(Effort::Tiny, &mut |_| {}).unwrap();
    let (directions, bars) = perifrac_bench::look::wall_directions(&wall);
    assert_eq!(directions.rows.len(), perifrac_bench::look::DIRECTION_BINS);
    // The shares over the bins add up to the whole crack area.
    let total: f64 = directions
        .rows
        .iter()
        .map(|r| r[1].trim_end_matches('%').parse::<f64>().unwrap())
        .sum();
    assert!(
        (total - 100.0).abs() < 0.1 * perifrac_bench::look::DIRECTION_BINS as f64,
        "{total}"
    );
    assert_eq!(bars.series[0].1.len(), perifrac_bench::look::DIRECTION_BINS);
    let (sizes, _) =
        perifrac_bench::look::fragment_sizes(Effort::Tiny, &wall, &mut |_| {}).unwrap();
    assert_eq!(sizes.rows.len(), 2);
    // Every piece of every run is a closed 2-manifold, right side out, as cut and smoothed.
    for row in &split.rows {
        let n = row.len();
        assert_eq!(
            (row[n - 2].as_str(), row[n - 1].as_str()),
            ("0", "0"),
            "{row:?}"
        );
    }
    // Debris by size class: four classes; as written, no piece flat or inside out.
    let debris = perifrac_bench::look::debris_shapes(&wall);
    assert_eq!(debris.rows.len(), 4);
    assert!(debris.rows.iter().all(|r| r[8] == "0"), "{:?}", debris.rows);
    for row in &sizes.rows {
        let n = row.len();
        assert_eq!(
            (
                row[n - 4].as_str(),
                row[n - 3].as_str(),
                row[n - 1].as_str()
            ),
            ("0", "0", "0"),
            "{row:?}"
        );
    }
}

#[test]
fn shell_egg_table_holds_every_run() {
    // Tiny: the egg stepped plainly and searched for 0.2 ms.
    let mut quiet = |_: &str| {};
    let (egg, text) = perifrac_bench::shells::egg_drop(Effort::Tiny, &mut quiet).unwrap();
    assert_eq!(egg.rows.len(), 2);
    assert!(text.contains("triangles"));
    // The search does at least as many force evaluations as the plain run at its outer step.
    let evals = |r: &Vec<String>| r[2].parse::<u64>().unwrap();
    assert!(evals(&egg.rows[1]) >= evals(&egg.rows[0]));
    // And with the implicit step: one plain run and one search, each solve counted.
    let (nm, text) = perifrac_bench::shells::egg_newmark(Effort::Tiny, &mut quiet).unwrap();
    assert_eq!(nm.rows.len(), 2);
    assert!(text.contains("Newmark"));
    assert_eq!(nm.rows[0][2], "20");
    assert!(evals(&nm.rows[1]) >= 20);
}

#[test]
fn kalthoff_winkler_cracks_leave_near_the_experiments_angle_below_the_rayleigh_speed() {
    use perifrac_bench::fracture;
    // 4 mm cells (Tiny). Measured 73.0 and 71.0 degrees (67.6 and 66.2 at 2 mm, BENCHMARKS.md)
    // against the experiment's 70: 65 to 75 still fails a crack that runs on along its notch
    // (0) or square to it (90). The plate is symmetric and its mesh is not: 2.0 degrees apart.
    let cells = fracture::resolutions(Effort::Tiny)[0];
    let run = fracture::kalthoff_winkler(cells, &mut |_| {}).unwrap();
    let angles: Vec<f64> = run.angles.iter().map(|a| a.unwrap()).collect();
    for a in &angles {
        assert!((65.0..75.0).contains(a), "{angles:?}");
    }
    assert!((angles[0] - angles[1]).abs() < 4.0, "{angles:?}");
    // a crack tip never outruns the Rayleigh speed (measured 0.86 of it here)
    let fastest = run.fastest_tip();
    assert!(fastest > 0.0 && fastest < run.rayleigh, "{fastest} m/s");
    let (table, facets) = fracture::report(&[run]);
    assert_eq!(table.rows.len(), 1);
    assert_eq!(facets.panels.len(), 1);
}

#[test]
fn the_glass_plate_crack_branches_below_the_rayleigh_speed() {
    use perifrac_bench::fracture;
    // 1 mm cells at 4 MPa. Measured: the crack runs as two from x = 66 mm, three cracks reach
    // the far edge, the tip at most 0.77 of the Rayleigh speed
    let (cells, traction) = fracture::branching_cases(Effort::Tiny)[0];
    let run = fracture::branching(cells, traction, &mut |_| {}).unwrap();
    let fastest = run.fastest_tip();
    assert!(fastest > 0.0 && fastest < run.rayleigh, "{fastest} m/s");
    assert!(
        run.first_branch.is_some_and(|x| x < 0.095),
        "{:?}",
        run.first_branch
    );
    assert!(run.at_far_edge >= 2, "{}", run.at_far_edge);
    let (table, facets) = fracture::branching_report(&[run]);
    assert_eq!(table.rows.len(), 1);
    assert_eq!(facets.panels.len(), 1);
}

#[test]
fn a_matching_fracture_energy_breaks_the_preview_wall_as_its_s_crit() {
    use perifrac_bench::preview;
    // The quick study is the wall at 16 cells: the fracture energy found for it gives the
    // same s_crit to rounding (measured 5.0000e-4 both), so the same fragments. Measured: 12
    // fragments over 1% of the mass, a damaged zone 214 mm in radius.
    let scenes = preview::scenes(Effort::Tiny);
    let wall = &scenes[0];
    let resolution = &wall.resolutions[0];
    let energy = wall.matching_energy(resolution).unwrap();
    let by_strain = wall
        .run(resolution, &wall.s_crit_line(), &mut |_| {})
        .unwrap();
    let by_energy = wall
        .run(
            resolution,
            &format!("fracture_energy = {energy:e}"),
            &mut |_| {},
        )
        .unwrap();
    assert!((by_energy.s_crit / by_strain.s_crit - 1.0).abs() < 1e-9);
    assert!(by_strain.shares.len() >= 5, "{:?}", by_strain.shares);
    assert_eq!(by_strain.shares, by_energy.shares);
    assert!(
        by_strain.radius > 0.1 && by_strain.radius < 0.3,
        "{}",
        by_strain.radius
    );
    let (table, spread) = preview::report(&[by_strain, by_energy]);
    assert_eq!(table.rows.len(), 2);
    assert_eq!(spread.rows.len(), 2);
}
