//! Thin-shell scenes: a `[shell]` scene runs and writes frames a renderer reads (pieces and
//! crack walls flagged), and bad input is refused naming the file and the key or face.

use std::path::Path;

use perifrac_io::read_ply_frame;
use perifrac_scene::{run, Scene, SceneError, ShellScene, ShellSetup, Silent};

/// A small egg shell (320 triangles) dropped fast on the ground: it cracks within 0.5 ms.
const EGG: &str = r#"
[shell]
surface = "ellipsoid"
radii = [0.022, 0.022, 0.029]
subdivisions = 2
thickness = 3.5e-4
translate = [0.0, 0.0, 0.02928]

[[material]]
young = 30e9
poisson = 0.3
density = 2000.0
fracture_strain = 2e-3

[simulation]
duration = 5e-4
gravity = [0.0, 0.0, -9.81]
event_search = true

[[velocity]]
linear = [0.0, 0.0, -4.0]

[[ground]]

[output]
frames = 2
"#;

fn parse(text: &str) -> Result<ShellScene, SceneError> {
    ShellScene::parse(text, Path::new("egg.toml"))
}

fn setup_error(text: &str) -> String {
    match parse(text).and_then(|s| ShellSetup::new(&s, None, false)) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn an_egg_scene_cracks_and_writes_frames_with_pieces_and_crack_walls() {
    let scene = parse(EGG).unwrap();
    let setup = ShellSetup::new(&scene, None, false).unwrap();
    assert_eq!(setup.info.triangles, 320);
    let dir = tempfile::tempdir().unwrap();
    let summary = run(setup, dir.path(), &mut Silent).unwrap();
    // Dropped at 4 m/s it breaks: the count depends on the stepping, so only that it broke
    // and came apart is asserted.
    assert!(summary.shell().unwrap().broken_triangles > 0, "{summary:?}");
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("run.json")).unwrap())
            .unwrap();
    assert_eq!(run["finished"], true);
    assert_eq!(run["body"], "shell");
    let frames = run["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    let last = frames[2]["surface"].as_str().unwrap();
    let frame = read_ply_frame(&dir.path().join(last)).unwrap();
    let crack = frame.crack.expect("crack flags");
    let fragment = frame.fragment.expect("fragment ids");
    // Every piece is a closed slab of the shell's thickness: with cracks, some walls are
    // crack walls.
    assert!(crack.contains(&1));
    let pieces = fragment
        .iter()
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    assert_eq!(pieces, summary.fragments);
    // Fragment ids are stable: each id the frame uses is in run.json's record, and a piece
    // that split off has the fragment it came from as its parent.
    let births = run["fragments"].as_array().unwrap();
    assert!(fragment.iter().all(|&f| (f as usize) < births.len()));
    assert!(births.iter().skip(1).any(|b| !b["parent"].is_null()));
    assert_eq!(frames[2]["fragments"].as_u64().unwrap() as usize, pieces);
    assert!(dir.path().join("frames/surface_0002.inc").is_file());
}

#[test]
fn tet_only_keys_are_named_as_keys_of_solid_scenes() {
    for (extra, key) in [
        (
            "[simulation]\nhorizon_factor = 1.45\n",
            "simulation.horizon_factor",
        ),
        ("[[material]]\ns_crit = 0.1\n", "material[0].s_crit"),
        ("[mesh]\nprimitive = \"box\"\n", "mesh"),
        ("[output]\nparticles = true\n", "output.particles"),
    ] {
        // put the key into the table it belongs to
        let (table, line) = extra.split_once('\n').unwrap();
        let text = EGG.replacen(&format!("{table}\n"), &format!("{table}\n{line}"), 1);
        let text = if text == EGG {
            format!("{EGG}\n{extra}")
        } else {
            text
        };
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("egg.toml") && e.contains(key) && e.contains("a key of solid scenes"),
            "{key}: {e}"
        );
    }
    // and a shell scene given where a tet scene is expected says what it is
    let e = Scene::parse(EGG, Path::new("egg.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("thin-shell scene") && e.contains("perifrac run"),
        "{e}"
    );
}

/// The egg breaks by a fracture energy as it does by a strain: at 50 J/m^2 each triangle's
/// threshold follows its width, and the drop breaks some.
#[test]
fn an_egg_breaks_by_its_fracture_energy() {
    let text = EGG.replacen("fracture_strain = 2e-3", "fracture_energy = 50.0", 1);
    let scene = parse(&text).unwrap();
    let setup = ShellSetup::new(&scene, None, false).unwrap();
    let params = setup
        .shell
        .shell()
        .model()
        .fracture_params()
        .expect("breaks");
    assert_eq!(params.energy, Some(50.0));
    let dir = tempfile::tempdir().unwrap();
    let summary = run(setup, dir.path(), &mut Silent).unwrap();
    assert!(summary.shell().unwrap().broken_triangles > 0, "{summary:?}");
}

#[test]
fn bad_thickness_material_and_placement_are_refused_by_key() {
    for (from, to, key) in [
        ("thickness = 3.5e-4", "thickness = 0.0", "shell.thickness"),
        ("thickness = 3.5e-4", "thickness = -1e-3", "shell.thickness"),
        ("poisson = 0.3", "poisson = 0.7", "material[0].poisson"),
        (
            "fracture_strain = 2e-3",
            "fracture_strain = -1.0",
            "material[0].fracture_strain",
        ),
        // fracture energy: one threshold key, positive, and a release that spends it
        (
            "fracture_strain = 2e-3",
            "fracture_strain = 2e-3\nfracture_energy = 10.0",
            "material[0].fracture_energy",
        ),
        (
            "fracture_strain = 2e-3",
            "fracture_energy = 0.0",
            "material[0].fracture_energy",
        ),
        (
            "fracture_strain = 2e-3",
            "fracture_energy = -3.0",
            "material[0].fracture_energy",
        ),
        (
            "fracture_strain = 2e-3",
            "fracture_energy = 10.0\nrelease = 0.0",
            "material[0].release",
        ),
        (
            "subdivisions = 2",
            "subdivisions = 2\nlength = 1.0",
            "shell.length",
        ),
        (
            "surface = \"ellipsoid\"",
            "surface = \"torus\"",
            "shell.surface",
        ),
        // shell scenes do not stop balls
        (
            "[[ground]]",
            "[[ball]]\ncenter = [0.0, 0.0, 1.0]\nradius = 0.1\nuntil = 0.1\n\n[[ground]]",
            "ball[0].until",
        ),
        // the shell starts through the ground
        (
            "translate = [0.0, 0.0, 0.02928]",
            "translate = [0.0, 0.0, 0.0]",
            "ball/ground",
        ),
    ] {
        let text = EGG.replacen(from, to, 1);
        assert_ne!(text, EGG);
        let e = setup_error(&text);
        assert!(e.contains("egg.toml") && e.contains(key), "{key}: {e}");
    }
}

#[test]
fn bad_surface_files_are_refused_naming_the_file_and_the_face() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        // three triangles on one edge
        (
            "fin.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
            "edge 0-1",
        ),
        // a triangle with no area
        (
            "flat.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n",
            "triangle 1",
        ),
    ];
    for (name, text, what) in cases {
        std::fs::write(dir.path().join(name), text).unwrap();
        let scene_text = EGG
            .replacen(
                "surface = \"ellipsoid\"\nradii = [0.022, 0.022, 0.029]\nsubdivisions = 2\n",
                &format!("file = \"{name}\"\n"),
                1,
            )
            .replacen(
                "translate = [0.0, 0.0, 0.02928]",
                "translate = [0.0, 0.0, 1.0]",
                1,
            );
        let path = dir.path().join("scene.toml");
        let scene = ShellScene::parse(&scene_text, &path).unwrap();
        let e = match ShellSetup::new(&scene, None, false) {
            Ok(_) => panic!("{name} accepted"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(name) && e.contains(what), "{name}: {e}");
    }
}

/// The punctured sheets of `data/scenes/shell_puncture_1e-3.toml` over their first 0.45 ms
/// and `shell_puncture_1e-4.toml` over 0.3 ms, when the ball has torn them open: a sheet must
/// not gain energy from its own fracture. Three defects did so, each measured here: releasing
/// the bending moment across new cracks made the small triangles beside them run away (1e-3:
/// 0.39 J); keeping the stress along a crack, not the strain, let repeated releases pump energy
/// in (1e-4: 1.27 J); and new vertices put on chords of the sheet wrapped round the ball
/// started 0.27 mm inside its contact band and were shot out at 260 m/s (1e-4, after the first
/// two fixes: 0.44 J). The bound is the energy of the whole 12 g sheet moving with the 5 m/s
/// ball, 0.15 J (the ball drives a small patch of it: measured 0.0061 J and 0.0057 J).
#[test]
fn punctured_sheets_do_not_run_away_at_their_cracks() {
    for (file, duration) in [
        ("shell_puncture_1e-3.toml", 4.5e-4),
        ("shell_puncture_1e-4.toml", 3e-4),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/scenes")
            .join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let mut scene = ShellScene::parse(&text, &path).unwrap();
        scene.file.simulation.duration = duration;
        scene.file.output.frames = Some(1);
        let setup = ShellSetup::new(&scene, None, false).unwrap();
        let mass = setup.info.mass;
        let dir = tempfile::tempdir().unwrap();
        let summary = run(setup, dir.path(), &mut Silent).unwrap();
        assert!(
            summary.shell().unwrap().broken_triangles > 20,
            "{file}: {summary:?}"
        );
        let bound = 0.5 * mass * 5.0 * 5.0;
        assert!(
            summary.kinetic_energy < bound,
            "{file}: kinetic energy {} J against {bound} J",
            summary.kinetic_energy
        );
        eprintln!("{file}: kinetic energy {} J", summary.kinetic_energy);
    }
}

/// What a kinematic ball at 5 m/s can give a piece of the sheet is an elastic bounce off it,
/// 10 m/s, plus the snap-back of the fracture strain, `eps sqrt(Y / rho)` = 0.16 m/s; no
/// vertex of the punctured sheet may leave faster. Two defects did (1e-4 sheet, 0.3 ms: 34 to
/// 66 m/s): every vertex fracture made kept the whole contact stiffness, so a copy a tenth as
/// heavy was shot out by the overlap's energy, and new vertices on chords of the sheet wrapped
/// round the ball were pushed out of it, which put a 0.56 mm sagitta into their triangles as
/// strain (0.2 J in one round). Measured: 42.6 m/s before the fixes, 9.6 after (9.7 over the
/// whole 2 ms scene).
#[test]
fn no_piece_leaves_a_punctured_sheet_faster_than_a_bounce_off_the_ball() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes/shell_puncture_1e-4.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut scene = ShellScene::parse(&text, &path).unwrap();
    scene.file.simulation.duration = 3e-4;
    scene.file.output.frames = Some(1);
    let setup = ShellSetup::new(&scene, None, false).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let summary = run(setup, dir.path(), &mut Silent).unwrap();
    assert!(
        summary.shell().unwrap().broken_triangles > 50,
        "{summary:?}"
    );
    let frame = read_ply_frame(&dir.path().join("frames/surface_0001.ply")).unwrap();
    let fastest = frame
        .velocities
        .unwrap()
        .iter()
        .map(|v| v.map(f64::from))
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, f64::max);
    let bound = 2.0 * 5.0 + 1e-4 * (3e9f64 / 1200.0).sqrt();
    eprintln!("fastest vertex {fastest:.2} m/s, bound {bound:.2} m/s");
    assert!(fastest < bound, "a vertex at {fastest} m/s");
}

#[test]
fn a_newmark_egg_runs_at_steps_past_the_explicit_limit_and_records_its_solves() {
    // The paper's integrator: the egg at 4 times its explicit limit (1.33e-6 s), with the
    // search over it, cracks and writes what the solves did.
    let text = EGG.replace(
        "event_search = true",
        "event_search = true\nintegrator = \"newmark\"\ndt = 5e-6\nevent_levels = 6",
    );
    let setup = ShellSetup::new(&parse(&text).unwrap(), None, false).unwrap();
    assert!(setup.info.newmark.is_some());
    assert!(
        setup.info.dt > 3.0 * setup.info.dt_limit,
        "{:?}",
        setup.info
    );
    let dir = tempfile::tempdir().unwrap();
    let summary = run(setup, dir.path(), &mut Silent).unwrap();
    assert!(summary.shell().unwrap().broken_triangles > 0, "{summary:?}");
    let nm = summary
        .shell()
        .unwrap()
        .newmark
        .expect("Newmark statistics");
    assert_eq!(
        nm.steps,
        summary.shell().unwrap().substeps + summary.shell().unwrap().rejected
    );
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("run.json")).unwrap())
            .unwrap();
    assert_eq!(run["integrator"], "newmark");
    assert_eq!(
        run["frames"][2]["newmark"]["solves"].as_u64(),
        Some(nm.steps)
    );
}

#[test]
fn newmark_keys_are_checked_by_key() {
    for (extra, key, says) in [
        (
            "integrator = \"verlet\"",
            "simulation.integrator",
            "newmark",
        ),
        (
            "integrator = \"newmark\"",
            "simulation.dt",
            "give dt in seconds",
        ),
        (
            "integrator = \"newmark\"\ndt = 1e-6\ntolerance = 2.0",
            "simulation.tolerance",
            "(0, 1)",
        ),
        (
            "integrator = \"newmark\"\ndt = 1e-6\niterations = 0",
            "simulation.iterations",
            "at least 1",
        ),
        (
            "iterations = 10",
            "simulation.iterations",
            "integrator = \"newmark\"",
        ),
        (
            "tolerance = 1e-5",
            "simulation.tolerance",
            "integrator = \"newmark\"",
        ),
    ] {
        let text = EGG.replace(
            "event_search = true",
            &format!("event_search = true\n{extra}"),
        );
        let e = setup_error(&text);
        assert!(
            e.contains("egg.toml") && e.contains(key) && e.contains(says),
            "{extra}: {e}"
        );
    }
}

/// The scene `text` after `steps` steps of 5 us: positions (m), velocities (m/s) and the
/// number of triangles broken.
fn stepped(text: &str, steps: usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, usize) {
    let mut setup = ShellSetup::new(&parse(text).unwrap(), None, false).unwrap();
    for _ in 0..steps {
        setup.shell.advance(5e-6).unwrap();
    }
    let s = setup.shell.shell();
    (
        s.positions().to_vec(),
        s.velocities().to_vec(),
        setup.shell.stats().events.len(),
    )
}

#[test]
fn newmark_results_are_the_same_for_any_thread_count() {
    // The 1,280-triangle egg (its passes split into several tasks) through its landing:
    // 20 Newmark steps of 5 us, cracking, searched to level 4.
    let text = EGG.replace("subdivisions = 2", "subdivisions = 3").replace(
        "event_search = true",
        "event_search = true\nintegrator = \"newmark\"\ndt = 5e-6\nevent_levels = 4",
    );
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| stepped(&text, 20))
    };
    let one = run(1);
    assert!(one.2 > 0, "the egg cracks in these steps");
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn explicit_results_are_the_same_on_and_off_the_pool() {
    // `perifrac run` steps on a worker of the pool (cli run.rs); a library caller may step from
    // its own thread, whose parallel loops the pool then runs. The 1,280-triangle egg through
    // its landing with the search, cracking: the same bits either way, and for 1 and 2 threads.
    let text = EGG.replace("subdivisions = 2", "subdivisions = 3");
    let run = || stepped(&text, 40);
    let here = run();
    assert!(here.2 > 0, "the egg cracks in these steps");
    assert_eq!(here, rayon::scope(|_| run()));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert_eq!(here, pool.install(run), "{threads} thread(s)");
    }
}
