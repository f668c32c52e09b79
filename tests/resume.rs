//! Checkpoints and resume: a run interrupted at any step and resumed writes the same bytes as
//! one that never stopped, for a brittle scene hit by a ball, a plastic one held at its rim,
//! and an implicit one that tears; a checkpoint of another scene, a damaged one or one of
//! another version is refused. The command line's SIGINT path is tested here too.

mod common;

use std::path::{Path, PathBuf};

use perifrac_scene::{
    resume, run, AnyScene, Checkpoint, Observer, Progress, Scene, SceneError, Setup, ShellScene,
    ShellSetup, Silent, CHECKPOINT_FILE,
};

/// The tet scene a checkpoint was written for.
fn solid_scene(cp: &Checkpoint) -> Scene {
    match cp.scene().unwrap() {
        AnyScene::Solid(scene) => *scene,
        AnyScene::Shell(_) => panic!("the checkpoint's scene is a shell's"),
    }
}

/// Asks for an interruption at a given step count, or after a given frame is written.
struct InterruptAt {
    step: Option<u64>,
    after_frame: Option<usize>,
    steps: u64,
    frames: usize,
}

impl Observer for InterruptAt {
    fn step(&mut self, p: &Progress) {
        self.steps = p.steps;
    }
    fn frame(&mut self, p: &Progress) {
        self.frames = p.frames_written;
    }
    fn interrupted(&mut self) -> bool {
        let at_step = self.step.is_some_and(|s| s == self.steps);
        let at_frame = self.after_frame.is_some_and(|f| f + 1 == self.frames);
        if at_step || at_frame {
            // once only: the resumed run goes on to the end
            self.step = None;
            self.after_frame = None;
            true
        } else {
            false
        }
    }
}

fn setup(scene: &Path, frames: usize) -> Setup {
    Setup::new(&Scene::load(scene).unwrap(), Some(frames)).unwrap()
}

/// Runs `scene` once through, then interrupted at each of `points` (a step, or `None` with a
/// frame) and resumed, and compares every file of the runs.
fn check_resume(
    scene: &Path,
    frames: usize,
    points: &[(Option<u64>, Option<usize>)],
) -> perifrac_scene::Summary {
    let tmp = tempfile::tempdir().unwrap();
    let reference = tmp.path().join("reference");
    let whole = run(setup(scene, frames), &reference, &mut Silent).unwrap();
    assert!(
        !reference.join(CHECKPOINT_FILE).exists(),
        "a finished run leaves no checkpoint"
    );
    let expected = common::files(&reference);
    for (k, &(step, after_frame)) in points.iter().enumerate() {
        let dir = tmp.path().join(format!("interrupted_{k}"));
        let mut obs = InterruptAt {
            step,
            after_frame,
            steps: 0,
            frames: 0,
        };
        let err = run(setup(scene, frames), &dir, &mut obs).unwrap_err();
        let SceneError::Interrupted { step: at, .. } = err else {
            panic!("expected an interruption, got {err}");
        };
        if let Some(s) = step {
            assert_eq!(at, s);
        }
        let manifest = std::fs::read_to_string(dir.join("run.json")).unwrap();
        assert!(
            manifest.contains("\"finished\": false") && manifest.contains("interrupted at"),
            "run.json records the interruption:\n{manifest}"
        );
        let cp = Checkpoint::read(&dir).unwrap();
        let resumed_setup = Setup::new(&solid_scene(&cp), Some(cp.frames)).unwrap();
        let summary = resume(resumed_setup, &cp, &dir, &mut Silent).unwrap();
        assert_eq!(summary.steps, whole.steps);
        assert_eq!(
            summary.solid().unwrap().broken_bonds,
            whole.solid().unwrap().broken_bonds
        );
        let got = common::files(&dir);
        assert_eq!(
            got.keys().collect::<Vec<_>>(),
            expected.keys().collect::<Vec<_>>(),
            "{}: the same files after an interruption at {step:?}/{after_frame:?}",
            scene.display()
        );
        for (name, bytes) in &expected {
            assert!(
                &got[name] == bytes,
                "{}: {} differs after an interruption at step {step:?} / after frame \
                 {after_frame:?}",
                scene.display(),
                name.display()
            );
        }
    }
    whole
}

/// `data/scenes/NAME` with `replacements` applied (each must match), written into `dir`.
fn variant(dir: &Path, name: &str, replacements: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(common::repo().join("data/scenes").join(name)).unwrap();
    for (from, to) in replacements {
        assert!(text.contains(from), "{name} no longer has '{from}'");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_brittle_slab_hit_by_a_ball_resumes_byte_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = variant(
        tmp.path(),
        "wall.toml",
        &[
            ("cells = [24, 24, 3]", "cells = [10, 10, 2]"),
            ("duration = 0.005", "duration = 0.002"),
        ],
    );
    // 6 frames of about 60 steps: mid-frame while the ball breaks the slab, just before a
    // frame is written (its last step), and at a frame boundary after writing it
    let spf = setup(&scene, 6).steps_per_frame;
    let whole = check_resume(
        &scene,
        6,
        &[
            (Some(spf + spf / 2), None),
            (Some(3 * spf), None),
            (None, Some(4)),
        ],
    );
    assert!(
        whole.solid().unwrap().broken_bonds > 0 && whole.fragments > 1,
        "{whole:?}"
    );
}

#[test]
fn a_plastic_slab_resumes_byte_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = variant(
        tmp.path(),
        "wall_plastic.toml",
        &[
            ("cells = [24, 24, 3]", "cells = [10, 10, 2]"),
            ("duration = 0.2", "duration = 0.004"),
        ],
    );
    // the ball dents it from the first frame on: the plastic extensions are state that must
    // be restored (leaving them out of the restore makes frame 3 differ)
    let spf = setup(&scene, 4).steps_per_frame;
    check_resume(
        &scene,
        4,
        &[
            (Some(spf / 3), None),
            (Some(2 * spf + 1), None),
            (None, Some(3)),
        ],
    );
}

#[test]
fn an_implicit_tear_resumes_byte_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = variant(
        tmp.path(),
        "xu_tear.toml",
        &[("cells = [32, 24, 2]", "cells = [16, 12, 1]")],
    );
    // 12 frames of 4 implicit steps; the tear starts in the first frames, so the step matrix
    // is refactored after bonds break and the resumed run must factor the same one again
    let whole = check_resume(
        &scene,
        12,
        &[(Some(5), None), (Some(24), None), (None, Some(9))],
    );
    assert!(
        whole.solid().unwrap().broken_bonds > 0 && whole.solid().unwrap().solver.factorizations > 1,
        "{whole:?}"
    );
}

#[test]
fn an_event_search_run_resumes_byte_identically() {
    // the second time with Chen's inversion guard, whose springs enter every sub-step's forces
    // (its lagged gradients are written with the model's state, but each step fits them afresh
    // before reading them, so this checks the guarded stepping, not that part of the file)
    for guard in ["", "\ninversion_guard = 1.0"] {
        let tmp = tempfile::tempdir().unwrap();
        let search = format!("dt = \"auto\"\nevent_search = true{guard}");
        let scene = variant(
            tmp.path(),
            "wall.toml",
            &[
                ("cells = [24, 24, 3]", "cells = [8, 8, 1]"),
                ("duration = 0.005", "duration = 0.002"),
                ("dt = \"auto\"", &search),
            ],
        );
        // the search's level and largest force so far are saved with the rest, so a resumed
        // run proposes the sub-steps the uninterrupted one did
        let spf = setup(&scene, 4).steps_per_frame;
        let whole = check_resume(&scene, 4, &[(Some(spf + 3), None), (None, Some(2))]);
        assert!(
            whole.solid().unwrap().solver.rejected > 0 && whole.solid().unwrap().broken_bonds > 0,
            "{guard}: {whole:?}"
        );
    }
}

#[test]
fn a_loaded_run_resumes_byte_identically() {
    // a ramped pressure on the slab's top with the event search: the loads' strengths,
    // positions and work are saved with the rest and undone with each rejected trial, so the
    // resumed run's forces and run.json's load_work are the same bits
    let tmp = tempfile::tempdir().unwrap();
    let load = "[[load]]\npressure = 2e7\nramp = 5e-4\n\
                region = { min = [-1.0, -1.0, 0.059], max = [1.0, 1.0, 1.0] }\n\n[simulation]";
    let scene = variant(
        tmp.path(),
        "wall.toml",
        &[
            ("cells = [24, 24, 3]", "cells = [8, 8, 1]"),
            ("duration = 0.005", "duration = 0.002"),
            ("dt = \"auto\"", "dt = \"auto\"\nevent_search = true"),
            ("[simulation]", load),
        ],
    );
    let spf = setup(&scene, 4).steps_per_frame;
    let whole = check_resume(&scene, 4, &[(Some(spf + 3), None), (None, Some(2))]);
    let work = whole.solid().unwrap().load_work.unwrap();
    assert!(work > 0.0, "{whole:?}");
}

#[test]
fn a_self_contact_run_resumes_byte_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = variant(
        tmp.path(),
        "wall.toml",
        &[
            ("cells = [24, 24, 3]", "cells = [10, 10, 2]"),
            ("duration = 0.005", "duration = 0.002"),
            ("dt = \"auto\"", "dt = \"auto\"\nself_contact = true"),
        ],
    );
    // the pair list is built again on resume, at other steps than in the uninterrupted run:
    // each particle sums over its pairs in index order, and pairs out of reach add nothing,
    // so the forces do not depend on when the list was built
    let spf = setup(&scene, 5).steps_per_frame;
    let whole = check_resume(&scene, 5, &[(Some(spf + spf / 3), None), (None, Some(3))]);
    let (builds, deepest) = whole.solid().unwrap().self_contact.unwrap();
    assert!(
        builds > 1 && deepest.pairs > 0 && whole.solid().unwrap().broken_bonds > 0,
        "{whole:?}"
    );
}

/// An interrupted tiny wall in `tmp/name`: (scene, run directory).
fn interrupted_wall(tmp: &Path, name: &str) -> (PathBuf, PathBuf) {
    let scene = variant(
        tmp,
        "wall.toml",
        &[
            ("cells = [24, 24, 3]", "cells = [6, 6, 1]"),
            ("duration = 0.005", "duration = 0.001"),
        ],
    );
    let dir = tmp.join(name);
    let mut obs = InterruptAt {
        step: Some(20),
        after_frame: None,
        steps: 0,
        frames: 0,
    };
    assert!(matches!(
        run(setup(&scene, 3), &dir, &mut obs),
        Err(SceneError::Interrupted { .. })
    ));
    (scene, dir)
}

fn refusal(dir: &Path, setup: Setup) -> String {
    let cp = match Checkpoint::read(dir) {
        Ok(cp) => cp,
        Err(e) => return e.to_string(),
    };
    resume(setup, &cp, dir, &mut Silent)
        .unwrap_err()
        .to_string()
}

#[test]
fn checkpoints_of_another_scene_mesh_or_version_and_damaged_ones_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (scene, dir) = interrupted_wall(tmp.path(), "run");
    let bytes = std::fs::read(dir.join(CHECKPOINT_FILE)).unwrap();
    // another scene: the setup of a different text
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("friction = 0.2", "friction = 0.3");
    let other = Scene::parse(&text, &scene).unwrap();
    let e = refusal(&dir, Setup::new(&other, Some(3)).unwrap());
    assert!(e.contains("belongs to another scene"), "{e}");
    // the same text, but another run length: the fingerprint differs
    let same = Scene::load(&scene).unwrap();
    let e = refusal(&dir, Setup::new(&same, Some(4)).unwrap());
    assert!(
        e.contains("no longer the one the checkpoint was written for"),
        "{e}"
    );
    // another version of perifrac
    let (mut header, body) = perifrac_checkpoint::open(&bytes).unwrap();
    header.program = "perifrac 0.0.1".into();
    std::fs::write(
        dir.join(CHECKPOINT_FILE),
        perifrac_checkpoint::seal(&header, body),
    )
    .unwrap();
    let e = refusal(&dir, setup(&scene, 3));
    assert!(e.contains("written by perifrac 0.0.1"), "{e}");
    // a flipped byte, a cut file
    let mut damaged = bytes.clone();
    let k = damaged.len() / 2;
    damaged[k] ^= 1;
    std::fs::write(dir.join(CHECKPOINT_FILE), &damaged).unwrap();
    let e = refusal(&dir, setup(&scene, 3));
    assert!(e.contains("damaged"), "{e}");
    std::fs::write(dir.join(CHECKPOINT_FILE), &bytes[..bytes.len() - 1]).unwrap();
    let e = refusal(&dir, setup(&scene, 3));
    assert!(e.contains("cut short"), "{e}");
    // restored, it resumes
    std::fs::write(dir.join(CHECKPOINT_FILE), &bytes).unwrap();
    let cp = Checkpoint::read(&dir).unwrap();
    resume(setup(&scene, 3), &cp, &dir, &mut Silent).unwrap();
    // finished: nothing to resume
    let e = Checkpoint::read(&dir).unwrap_err().to_string();
    assert!(e.contains("finished, there is nothing to resume"), "{e}");
    let e = Checkpoint::read(tmp.path()).unwrap_err().to_string();
    assert!(e.contains("not a run directory"), "{e}");
}

/// The command line: SIGINT stops a run with exit status 130 and a checkpoint, and `perifrac
/// run --resume DIR` finishes it with the files of a run never interrupted.
#[cfg(unix)]
#[test]
fn sigint_checkpoints_and_the_command_line_resumes() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let tmp = tempfile::tempdir().unwrap();
    let scene = variant(
        tmp.path(),
        "wall.toml",
        &[
            ("cells = [24, 24, 3]", "cells = [12, 12, 2]"),
            ("frames = 24", "frames = 40"),
        ],
    );
    let s = scene.to_str().unwrap();
    let (reference, dir) = (tmp.path().join("reference"), tmp.path().join("run"));
    common::ok(&["run", s, "-o", reference.to_str().unwrap(), "-q"]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_perifrac"))
        .args(["run", s, "-o", dir.to_str().unwrap(), "-q"])
        .env("PERIFRAC_CACHE", common::test_cache())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // wait until a few frames are out, then interrupt
    let t0 = Instant::now();
    loop {
        let frames = std::fs::read_dir(dir.join("frames")).map_or(0, |d| d.count());
        if frames >= 9 {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "no frames after 2 minutes"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before the signal"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap()
        .success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("perifrac run --resume"), "{err}");
    assert!(dir.join(CHECKPOINT_FILE).exists());
    common::ok(&["run", "--resume", dir.to_str().unwrap(), "-q"]);
    assert_eq!(common::files(&dir), common::files(&reference));
}

/// Asks the run to stop once it has taken `at` steps; keeps the triangles broken by then.
struct StopAt {
    at: u64,
    taken: u64,
    broken: u64,
}

impl Observer for StopAt {
    fn step(&mut self, p: &Progress) {
        self.taken = p.steps;
        self.broken = p.broken_bonds;
    }
    fn interrupted(&mut self) -> bool {
        self.taken >= self.at
    }
}

/// Runs the shell scene `text` whole, and again interrupted after three quarters of its steps
/// (mid-frame) and resumed from the checkpoint; both directories must hold the same bytes.
fn shell_resumes_byte_identically(text: &str, name: &str) {
    let scene = || ShellScene::parse(text, Path::new(name)).unwrap();
    let whole = tempfile::tempdir().unwrap();
    let setup = ShellSetup::new(&scene(), None, false).unwrap();
    let total = setup.steps_per_frame * setup.frames as u64;
    let summary = run(setup, whole.path(), &mut Silent).unwrap();
    assert!(
        summary.shell().unwrap().broken_triangles > 0,
        "{name}: {summary:?}"
    );
    let cut = tempfile::tempdir().unwrap();
    let at = 3 * total / 4 + 1;
    let setup = ShellSetup::new(&scene(), None, false).unwrap();
    let mut stop = StopAt {
        at,
        taken: 0,
        broken: 0,
    };
    let stopped = run(setup, cut.path(), &mut stop);
    assert!(
        matches!(stopped, Err(SceneError::Interrupted { step, .. }) if step == at),
        "{name}: {stopped:?}"
    );
    // triangles broke before the checkpoint and after it: it carries a cut mesh
    eprintln!(
        "{name}: {} broken at the checkpoint, {} at the end",
        stop.broken,
        summary.shell().unwrap().broken_triangles
    );
    assert!(
        stop.broken > 0 && (stop.broken as usize) < summary.shell().unwrap().broken_triangles,
        "{name}: {} of {}",
        stop.broken,
        summary.shell().unwrap().broken_triangles
    );
    let cp = Checkpoint::read(cut.path()).unwrap();
    let AnyScene::Shell(scene) = cp.scene().unwrap() else {
        panic!("{name}: the checkpoint's scene is not a shell's");
    };
    let setup = ShellSetup::new(&scene, Some(cp.frames), false).unwrap();
    let resumed = resume(setup, &cp, cut.path(), &mut Silent).unwrap();
    assert_eq!(resumed.steps, summary.steps, "{name}");
    assert_eq!(
        resumed.shell().unwrap().broken_triangles,
        summary.shell().unwrap().broken_triangles,
        "{name}"
    );
    let (a, b) = (common::files(whole.path()), common::files(cut.path()));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{name}"
    );
    for (path, x) in &a {
        assert!(
            x == &b[path],
            "{name}: {} differs after the resume",
            path.display()
        );
    }
}

#[test]
fn an_interrupted_shell_run_resumes_byte_identically() {
    let scene = |name: &str| {
        std::fs::read_to_string(common::repo().join("data/scenes").join(name)).unwrap()
    };
    // The egg (320 triangles) under the event search, dropped at 4 m/s: it cracks on the
    // ground.
    let egg = scene("shell_egg_search.toml")
        .replace("subdivisions = 4", "subdivisions = 2")
        .replace("duration = 2e-3", "duration = 5e-4")
        .replace("linear = [0.0, 0.0, -1.0]", "linear = [0.0, 0.0, -4.0]")
        .replace("frames = 10", "frames = 2");
    shell_resumes_byte_identically(&egg, "egg.toml");
    // A punctured sheet: plain steps cut after splits, a kinematic ball, self contact, and
    // contact radii and bands forgiven at fracture rounds.
    let sheet = scene("shell_puncture_1e-4.toml")
        .replace("duration = 2e-3", "duration = 2e-4")
        .replace("frames = 4", "frames = 2");
    shell_resumes_byte_identically(&sheet, "puncture.toml");
}

#[test]
fn an_interrupted_newmark_shell_run_resumes_byte_identically() {
    let scene = |name: &str| {
        std::fs::read_to_string(common::repo().join("data/scenes").join(name)).unwrap()
    };
    // The implicit egg in plain steps (1,280 triangles): the resumed run must solve with the
    // factors the interrupted one had made at earlier steps, not new ones.
    let plain = scene("shell_egg_newmark_plain.toml");
    shell_resumes_byte_identically(&plain, "newmark_plain.toml");
    // With the event search (320 triangles, dropped at 4 m/s): factors kept for several
    // sub-step lengths, trial caps and solves undone.
    let searched = scene("shell_egg_newmark_search.toml")
        .replace("subdivisions = 3", "subdivisions = 2")
        .replace("linear = [0.0, 0.0, -1.0]", "linear = [0.0, 0.0, -4.0]");
    shell_resumes_byte_identically(&searched, "newmark_search.toml");
}
