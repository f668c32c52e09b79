//! The scenes of `data/scenes/` as the papers' figures describe them: every scene loads and
//! sets up; the glass slab pressed by a heavy ball cracks but stays in one piece; the bunny
//! shatters; the elastic slab recovers while the plastic one keeps a dent; stretched beams thin
//! by their Poisson ratio; Xu's StVK-like block softens where the neo-Hookean-like one
//! stiffens, the anisotropic plate droops along its soft axis, the implicit tear breaks the
//! sheet. Some run at fewer cells than the files ask for, to keep CI short;
//! each says so.

mod common;

use std::path::PathBuf;

use perifrac_scene::schema::{ChenCorrection, ChenSettings, GhostFitKey, Model};
use perifrac_scene::{Scene, Setup, ShellScene, ShellSetup};

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes")
}

fn load(name: &str) -> Scene {
    Scene::load(&scenes_dir().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Steps `setup` to the end of its duration.
fn run_to_end(setup: &mut Setup) {
    let steps = setup.frames as u64 * setup.steps_per_frame;
    for _ in 0..steps {
        setup.driver.step().unwrap();
    }
}

/// Rest positions of the particles (m).
fn rest_positions(setup: &Setup) -> Vec<[f64; 3]> {
    let model = setup.driver.solver().model();
    model.discretization().rest_positions().to_vec()
}

/// Whether the scene reads `../shared/data`, which a checkout without it lacks.
fn needs_shared(scene: &Scene) -> bool {
    scene
        .file
        .mesh
        .file
        .as_ref()
        .is_some_and(|f| f.to_string_lossy().contains("shared/data"))
}

#[test]
fn every_scene_names_its_figure_loads_and_sets_up() {
    let mut names: Vec<_> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 15, "{} scenes", names.len());
    for path in names {
        let text = std::fs::read_to_string(&path).unwrap();
        if perifrac_scene::is_shell_scene(&text) {
            // thin shells: Gingold et al.'s figures, set up at one frame
            assert!(
                text.contains("Gingold et al. 2004"),
                "{}: the comment names no figure of the papers",
                path.display()
            );
            let scene = ShellScene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
            let setup = ShellSetup::new(&scene, Some(1), false).unwrap_or_else(|e| panic!("{e}"));
            assert!(setup.info.triangles >= 480, "{}", path.display());
            // Explicit steps keep under the stable limit; Newmark's may pass it.
            assert!(setup.info.dt > 0.0, "{}", path.display());
            assert!(
                setup.info.newmark.is_some() || setup.info.dt <= setup.info.dt_limit,
                "{}",
                path.display()
            );
            continue;
        }
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        // a benchmark of the field names its experiment instead
        assert!(
            scene.text.contains("Chen et al. 2018, Figure")
                || scene.text.contains("Xu et al. 2018, Figure")
                || scene.text.contains("Xu et al. 2018, Section")
                || scene.text.contains("# Experiment: "),
            "{}: the comment names no figure of the papers and no experiment",
            path.display()
        );
        if needs_shared(&scene) && common::shared_mesh("bunny.off").is_none() {
            continue;
        }
        let setup = Setup::new(&scene, Some(1)).unwrap_or_else(|e| panic!("{e}"));
        assert!(setup.info.particles > 1000, "{}", path.display());
        assert!(setup.info.dt > 0.0);
        // only the explicit step is bound by the stable limit
        if setup.info.integrator == perifrac_physics::IntegratorKind::Explicit {
            assert!(setup.info.dt <= setup.info.dt_limit, "{}", path.display());
        }
    }
}

#[test]
fn glass_pressed_by_a_heavy_ball_cracks_but_stays_in_one_piece() {
    // The scene as written (10,368 particles, 1,600 steps).
    let mut setup = Setup::new(&load("glass_pressed.toml"), None).unwrap();
    run_to_end(&mut setup);
    let d = &setup.driver;
    let pieces = d.mesh().pieces().count;
    let crack_triangles = d.mesh().surface().crack.iter().filter(|&&c| c != 0).count();
    assert!(d.broken_bonds() > 1000, "{} bonds broken", d.broken_bonds());
    assert!(crack_triangles > 0, "no crack reaches the surface");
    assert_eq!(pieces, 1, "the glass came apart");
    // The ball is still pressing: it has not bounced off.
    let ball = d.colliders().unwrap().ball(0);
    assert!(ball.velocity[2] <= 0.5, "{:?}", ball.velocity);
}

#[test]
fn the_dropped_bunny_shatters_into_several_pieces() {
    let scene = load("bunny_drop.toml");
    if common::shared_mesh("bunny.off").is_none() {
        return;
    }
    let mut setup = Setup::new(&scene, None).unwrap();
    run_to_end(&mut setup);
    let d = &setup.driver;
    let pieces = d.mesh().pieces();
    // Several pieces, and not only dust: the two largest weigh more than a tenth each.
    let mut mass = vec![0.0; pieces.count];
    for (&p, &m) in pieces.piece_of_tet.iter().zip(d.masses()) {
        mass[p as usize] += m;
    }
    mass.sort_by(|a, b| b.total_cmp(a));
    let total: f64 = mass.iter().sum();
    assert!(pieces.count >= 5, "{} pieces", pieces.count);
    assert!(mass[1] > 0.1 * total, "{:?}", &mass[..3]);
}

/// Mean z displacement (m) of the particles in the top layer within 3 cm of the slab's centre
/// (the impact point of the wall scenes), averaged over the last fifth of the run (a few
/// periods of the damped ringing that is left), and its most negative value over the run.
fn impact_point_dent(name: &str, cells: Option<[usize; 3]>) -> (f64, f64) {
    let mut scene = load(name);
    if cells.is_some() {
        scene.file.mesh.cells = cells;
    }
    let mut setup = Setup::new(&scene, None).unwrap();
    let rest = rest_positions(&setup);
    let top = rest.iter().map(|x| x[2]).fold(0.0, f64::max);
    let picked: Vec<usize> = (0..rest.len())
        .filter(|&i| {
            let x = rest[i];
            (x[0] - 0.3).hypot(x[1] - 0.3) < 0.03 && x[2] > top - 0.01
        })
        .collect();
    assert!(!picked.is_empty());
    let steps = setup.frames as u64 * setup.steps_per_frame;
    let window = steps / 5;
    let (mut deepest, mut sum) = (0.0f64, 0.0);
    for s in 0..steps {
        setup.driver.step().unwrap();
        let y = setup.driver.solver().positions();
        let dz = picked.iter().map(|&i| y[i][2] - rest[i][2]).sum::<f64>() / picked.len() as f64;
        deepest = deepest.min(dz);
        if s >= steps - window {
            sum += dz;
        }
    }
    (sum / window as f64, deepest)
}

#[test]
fn the_elastic_slab_recovers_and_the_plastic_slab_keeps_a_dent() {
    // 16 x 16 x 2 cells instead of 24 x 24 x 3 (a fifth of the work). At the files' own cells
    // (release, `impact_point_at_the_files_cells`) the impact point ends at -0.4 mm (elastic,
    // 0.5% of its deepest -77 mm) and -18.4 mm (plastic, 20% of its deepest -91 mm); here at
    // +0.3 mm of -81 mm and -18.8 mm of -94 mm (20%). (The plastic dent was 36% of the deepest
    // point while surface particles, whose calibrated b_i is larger, yielded at about half the
    // scene's yield strain; each particle now yields at it: docs/DECISIONS.md.)
    let cells = Some([16, 16, 2]);
    let (elastic, elastic_deepest) = impact_point_dent("wall_elastic.toml", cells);
    let (plastic, plastic_deepest) = impact_point_dent("wall_plastic.toml", cells);
    eprintln!(
        "impact point: elastic {elastic:.4} m (deepest {elastic_deepest:.4}), plastic {plastic:.4} m \
         (deepest {plastic_deepest:.4})"
    );
    // Both were struck hard: the slab's centre went down by several centimetres.
    assert!(elastic_deepest < -0.03 && plastic_deepest < -0.03);
    // Elastic: back to within 10% of the deepest point (measured 0.5% at full resolution).
    assert!(elastic.abs() < 0.1 * elastic_deepest.abs(), "{elastic}");
    // Plastic: a dent of more than 10% of the deepest point stays (measured 20%), a hundred
    // times the elastic slab's.
    assert!(plastic < 0.1 * plastic_deepest, "{plastic}");
}

#[test]
#[ignore = "minutes: docs/usage.md's impact-point figures at the scene files' own cells"]
fn impact_point_at_the_files_cells() {
    for name in [
        "wall_elastic.toml",
        "wall_plastic.toml",
        "wall_cap_10.toml",
        "wall_cap_15.toml",
        "wall_cap_20.toml",
    ] {
        let (end, deepest) = impact_point_dent(name, None);
        eprintln!(
            "{name}: impact point at {:.1} mm deepest, {:.1} mm at the end",
            1e3 * deepest,
            1e3 * end
        );
        assert!(deepest < 0.0);
    }
}

#[test]
fn stretched_beams_thin_by_their_poisson_ratio() {
    // The three beams as written (12,960 particles each, 1,500 steps). The lateral strain is
    // measured from the spread of the middle fifth's particles across the beam, the axial
    // strain between particles at x = 0.3 and 0.7 (away from the pulled ends).
    for (name, nu) in [
        ("beam_stretch_nu10.toml", 0.098),
        ("beam_stretch_nu20.toml", 0.200),
        ("beam_stretch_nu30.toml", 0.301),
    ] {
        let mut setup = Setup::new(&load(name), None).unwrap();
        let rest = rest_positions(&setup);
        run_to_end(&mut setup);
        let y = setup.driver.solver().positions();
        let mean = |sel: &dyn Fn(&[f64; 3]) -> bool, k: usize, of: &[[f64; 3]]| {
            let v: Vec<f64> = (0..rest.len())
                .filter(|&i| sel(&rest[i]))
                .map(|i| of[i][k])
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let near = |x0: f64| move |x: &[f64; 3]| (x[0] - x0).abs() < 0.02;
        let length = |of: &[[f64; 3]]| mean(&near(0.7), 0, of) - mean(&near(0.3), 0, of);
        let axial = length(y) / length(&rest) - 1.0;
        let middle = |x: &[f64; 3]| (x[0] - 0.5).abs() < 0.1;
        let spread = |of: &[[f64; 3]], k: usize| {
            let m = mean(&middle, k, of);
            let v: Vec<f64> = (0..rest.len())
                .filter(|&i| middle(&rest[i]))
                .map(|i| (of[i][k] - m).powi(2))
                .collect();
            (v.iter().sum::<f64>() / v.len() as f64).sqrt()
        };
        let lateral =
            0.5 * (spread(y, 1) / spread(&rest, 1) + spread(y, 2) / spread(&rest, 2)) - 1.0;
        let measured = -lateral / axial;
        eprintln!("{name}: axial {axial:.4}, lateral {lateral:.4}, nu {measured:.3} (given {nu})");
        assert!((axial - 0.2).abs() < 0.02, "{name}: axial strain {axial}");
        // Measured 0.061, 0.173 and 0.289 against 0.098, 0.200 and 0.301 (the scalar
        // calibration: 0.083, 0.199, 0.320). Two parts: the model's own small-strain ratio on a
        // section 6 cells across at k = 1 is 0.068, 0.172 and 0.276 with the fitted dilatation
        // (its surface particles read shear a little stiff; `cargo test --release -p
        // perifrac-physics --test fitted fitted_moduli_study -- --ignored --nocapture`), low by
        // up to 0.03; at 20% strain the engineering ratio measured here moves from that by up
        // to 0.013 (about 0.02 expected). The bound is their sum.
        assert!(
            (measured - nu).abs() < 0.05,
            "{name}: nu {measured} for {nu}"
        );
    }
}

/// Area-weighted mean of |n_x| and |n_y| over the crack faces of the mesh's surface.
fn crack_normal_spread(setup: &Setup) -> (f64, f64) {
    let s = setup.driver.mesh().surface();
    let (mut nx, mut ny, mut area) = (0.0, 0.0, 0.0);
    for (f, &c) in s.faces.iter().zip(&s.crack) {
        if c == 0 {
            continue;
        }
        let [a, b, d] = f.map(|v| s.vertices[v as usize]);
        let (u, w) = (
            [0, 1, 2].map(|k| b[k] - a[k]),
            [0, 1, 2].map(|k| d[k] - a[k]),
        );
        let n = [
            u[1] * w[2] - u[2] * w[1],
            u[2] * w[0] - u[0] * w[2],
            u[0] * w[1] - u[1] * w[0],
        ];
        // |n| is twice the area; |n_x| / |n| weighted by the area is |n_x| / 2.
        nx += n[0].abs();
        ny += n[1].abs();
        area += (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    }
    (nx / area, ny / area)
}

#[test]
fn anisotropic_glass_cracks_along_its_stiff_axis() {
    // 16 x 16 x 2 cells instead of 24 x 24 x 3. G = diag(2, 0.5, 1) makes bonds along x four
    // times softer: they stretch and break first, so the crack faces face x (cracks run along
    // y). On the unstructured tets the scenes use, the crack normals' mean |n_x| : |n_y| at
    // these cells is 0.525 : 0.508 (ratio 1.033) for the isotropic slab and 0.577 : 0.449
    // (1.285) for the anisotropic one (the scalar calibration: 0.512 : 0.510 and 0.556 :
    // 0.453). (On the Kuhn lattice, whose few face directions exaggerate it, 0.466 : 0.466 and
    // 0.599 : 0.346, calibrated.)
    let mut ratios = Vec::new();
    for name in ["wall.toml", "wall_anisotropic.toml"] {
        let mut scene = load(name);
        scene.file.mesh.cells = Some([16, 16, 2]);
        let mut setup = Setup::new(&scene, None).unwrap();
        run_to_end(&mut setup);
        let (nx, ny) = crack_normal_spread(&setup);
        eprintln!("{name}: crack normals |n_x| {nx:.3}, |n_y| {ny:.3}");
        ratios.push(nx / ny);
    }
    // The isotropic slab and its ball are symmetric under x <-> y and its mesh prefers no
    // direction: within 0.05 of 1 (measured 0.033 off). The anisotropic slab's ratio must lie
    // beyond three times that band (measured 1.285), which an isotropic one does not reach.
    assert!((ratios[0] - 1.0).abs() < 0.05, "isotropic: {}", ratios[0]);
    assert!(ratios[1] > 1.15, "anisotropic: {}", ratios[1]);
}

/// Elastic energy (J) of a squash scene at 25 mm and at 50 mm of squeeze, at `cells` cells.
fn squash_energies(name: &str, cells: usize) -> (f64, f64) {
    let mut scene = load(name);
    scene.file.mesh.cells = Some([cells; 3]);
    let mut setup = Setup::new(&scene, None).unwrap();
    let steps = setup.frames as u64 * setup.steps_per_frame;
    let mut at_half = 0.0;
    for k in 1..=steps {
        setup.driver.step().unwrap();
        if k == steps / 2 {
            at_half = setup.driver.solver_mut().elastic_energy();
        }
    }
    (at_half, setup.driver.solver_mut().elastic_energy())
}

#[test]
fn the_stvk_block_softens_under_squeeze_where_the_neo_hookean_one_stiffens() {
    // 6 x 6 x 6 cells instead of 10 x 10 x 10. Measured: neo-Hookean 2.26 J at 25 mm and
    // 8.16 J at 50 mm (x3.61), StVK 1.78 J and 4.99 J (x2.81; with the normalised weights 2.27
    // and 8.18 J, 1.79 and 5.03 J); the bounds sit under those ratios (1.63 and 1.28).
    let (n25, n50) = squash_energies("xu_squash_neo_hookean.toml", 6);
    let (s25, s50) = squash_energies("xu_squash_stvk.toml", 6);
    eprintln!("neo-Hookean {n25:.3} J, {n50:.3} J; StVK {s25:.3} J, {s50:.3} J");
    // at half the height the StVK block holds far less energy, and gained less of it in the
    // second 25 mm than the neo-Hookean one did
    assert!(n50 > 1.4 * s50, "{n50} vs {s50}");
    assert!(n50 / n25 > 1.15 * (s50 / s25));
}

#[test]
fn the_anisotropic_plate_droops_along_its_soft_axis() {
    // 12 x 12 x 2 cells instead of 20 x 20 x 2. Measured: the middles of the x edges droop
    // 4.7 mm, of the y edges 134 mm (at 20 x 20 x 2: 2.7 and 126 mm; an isotropic plate droops
    // 77 mm both ways; with the normalised weights 4.9 and 130 mm).
    let mut scene = load("xu_anisotropic.toml");
    scene.file.mesh.cells = Some([12, 12, 2]);
    let mut setup = Setup::new(&scene, None).unwrap();
    let rest = rest_positions(&setup);
    run_to_end(&mut setup);
    let y = setup.driver.solver().positions();
    let droop = |along: usize| {
        let picked: Vec<usize> = (0..rest.len())
            .filter(|&i| rest[i][along].abs() > 0.26 && rest[i][1 - along].abs() < 0.04)
            .collect();
        picked.iter().map(|&i| rest[i][2] - y[i][2]).sum::<f64>() / picked.len() as f64
    };
    let (dx, dy) = (droop(0), droop(1));
    eprintln!("droop of the x edges {dx:.4} m, of the y edges {dy:.4} m");
    assert!(dy > 0.05 && dy > 10.0 * dx.abs(), "{dx} {dy}");
}

#[test]
fn the_implicit_tear_breaks_the_sheet_and_refactors() {
    // 20 x 15 x 2 cells instead of 32 x 24 x 2. Measured: 41,611 bonds broken, 10 pieces,
    // 41 factorisations (49,604, 12 and 12 with the normalised weights).
    let mut scene = load("xu_tear.toml");
    scene.file.mesh.cells = Some([20, 15, 2]);
    let mut setup = Setup::new(&scene, None).unwrap();
    run_to_end(&mut setup);
    let d = &setup.driver;
    let pieces = d.mesh().pieces().count;
    let stats = d.solver().stats();
    eprintln!(
        "{} bonds broken, {pieces} pieces, {} factorisations",
        d.broken_bonds(),
        stats.factorizations
    );
    assert!(pieces >= 2, "{pieces} pieces");
    assert!(stats.factorizations > 1);
}

#[test]
fn ghosts_tear_a_sheet_through_its_initial_cracks() {
    // sheet_tear.toml at 20 x 10 x 2 cells with affine ghosts (quadratic ones on a sheet
    // thinner than a horizon shorten the step 1.5 times: docs/DECISIONS.md): a breaking
    // material with initial cracks, whose ghosts bond only within their sources' families,
    // so not across the cracks. Measured: 8,413 bonds broken, 21 fragments (without ghosts
    // at this size 6,077 and 11; at 30 x 15 x 2 8,574 and 11, with quadratic ghosts 7,860 and
    // 27).
    let mut scene = load("sheet_tear.toml");
    scene.file.mesh.cells = Some([20, 10, 2]);
    scene.file.simulation.model = Model::Chen(ChenSettings {
        correction: Some(ChenCorrection::Ghosts),
        ghost_fit: Some(GhostFitKey::Affine),
    });
    let mut setup = Setup::new(&scene, None).unwrap();
    assert!(setup.info.precrack_faces > 0);
    let ghosts = setup.info.ghosts.clone().expect("the ghosts' report");
    eprintln!("{ghosts:?}");
    run_to_end(&mut setup);
    let d = &setup.driver;
    let pieces = d.mesh().pieces().count;
    let damage = d.damage();
    eprintln!("{} bonds broken, {pieces} pieces", d.broken_bonds());
    // torn apart along the strips pulled either way: at least the two halves
    assert!(pieces >= 2, "{pieces} pieces");
    // the damage shown is over the real bonds
    assert!(damage.iter().all(|p| (0.0..=1.0).contains(p)));
    assert!(damage.iter().any(|&p| p > 0.0));
}

#[test]
fn ghosts_are_a_scene_option() {
    // wall_elastic.toml at a quarter of its cells, its families completed by ghost particles
    // across the slab's boundary (`correction = "ghosts"`, quadratic by default)
    let mut scene = load("wall_elastic.toml");
    scene.file.mesh.cells = Some([12, 12, 2]);
    scene.file.simulation.model = Model::Chen(ChenSettings {
        correction: Some(ChenCorrection::Ghosts),
        ghost_fit: None,
    });
    let mut setup = Setup::new(&scene, None).unwrap();
    let ghosts = setup.info.ghosts.clone().expect("the ghosts' report");
    let n = setup.info.particles;
    eprintln!("{n} particles, {ghosts:?}");
    // a slab two cells thick: every particle is within a horizon of a face, most of two or
    // three, so there are more ghosts than particles
    assert!(
        ghosts.ghosts > n,
        "{} ghosts for {n} particles",
        ghosts.ghosts
    );
    // the integrators see the real particles only
    assert_eq!(setup.driver.solver().positions().len(), n);
    // the correction's factors are reported over the completed families: a whole family's
    // b_i is docs/model.md's to the mesh's quadrature (measured median 1.005; without ghosts this
    // slab's cut families give 2.206)
    let b = setup.info.correction.unwrap().deviatoric;
    eprintln!("b_i / b0: {b:?}");
    assert!((b.median - 1.0).abs() < 0.1, "{b:?}");
    for _ in 0..20 {
        setup.driver.step().unwrap();
    }
    let y = setup.driver.solver().positions();
    assert!(y.iter().flatten().all(|c| c.is_finite()));
    // refused: a fit named without them
    let mut stray = load("wall_elastic.toml");
    stray.file.simulation.model = Model::Chen(ChenSettings {
        correction: None,
        ghost_fit: Some(GhostFitKey::Affine),
    });
    let Err(err) = Setup::new(&stray, None) else {
        panic!("ghost_fit without ghosts was accepted");
    };
    let err = err.to_string();
    assert!(err.contains("ghost_fit"), "{err}");
}
