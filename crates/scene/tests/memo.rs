//! The stable-step estimate kept between runs: a scene set up again recalls it (the same bits,
//! so the same steps), and a scene whose model differs does not.

use std::path::Path;

use perifrac_physics::EstimateMemo;
use perifrac_scene::{Limits, MemoDir, Scene, Setup};

/// The default scene's slab (60 x 60 x 6 cm of glass) at 8 x 8 x 2 cells with its steel ball
/// 1 cm above, `dt = "auto"`: the estimate sets the step.
const SLAB: &str = "[mesh]\nprimitive = \"box\"\nsize = [0.6, 0.6, 0.06]\ncells = [8, 8, 2]\n\n\
    [[material]]\nbulk_modulus = 3.3e10\nshear_modulus = 2.0e10\ndensity = 2200.0\n\
    s_crit = 0.0005\n\n[simulation]\nduration = 0.0002\n\n\
    [[ball]]\ncenter = [0.3, 0.3, 0.12]\nradius = 0.05\nvelocity = [0.0, 0.0, -75.0]\n\
    density = 7800.0\n\n[output]\nframes = 1\n";

fn setup(text: &str, memo: Option<&dyn EstimateMemo>) -> Setup {
    let scene = Scene::parse(text, Path::new("slab.toml")).unwrap();
    Setup::with_memo(&scene, None, &Limits::for_this_machine(), memo).unwrap()
}

/// Positions after `steps` steps.
fn stepped(mut s: Setup, steps: usize) -> Vec<[f64; 3]> {
    for _ in 0..steps {
        s.driver.step().unwrap();
    }
    s.driver.solver().positions().to_vec()
}

#[test]
fn a_scene_set_up_again_recalls_its_stable_step_and_steps_alike() {
    let dir = tempfile::tempdir().unwrap();
    let memo = MemoDir::new(dir.path().join("cache"));
    let plain = setup(SLAB, None);
    let cold = setup(SLAB, Some(&memo));
    let warm = setup(SLAB, Some(&memo));
    assert!(!cold.info.times.stable_step_recalled);
    assert!(warm.info.times.stable_step_recalled);
    assert_eq!(memo.failure(), None);
    for s in [&cold, &warm] {
        assert_eq!(s.info.dt_limit.to_bits(), plain.info.dt_limit.to_bits());
        assert_eq!(s.info.dt.to_bits(), plain.info.dt.to_bits());
        assert_eq!(s.steps_per_frame, plain.steps_per_frame);
    }
    let files = std::fs::read_dir(memo.dir()).unwrap().count();
    assert_eq!(files, 1);
    // the ball's impact region steps the same whatever the memo held
    let reference = stepped(plain, 20);
    assert_eq!(stepped(warm, 20), reference);

    // a stiffer glass is another operator: iterated again, kept beside the first
    let stiffer = SLAB.replace("shear_modulus = 2.0e10", "shear_modulus = 2.2e10");
    let other = setup(&stiffer, Some(&memo));
    assert!(!other.info.times.stable_step_recalled);
    assert!(other.info.dt_limit < cold.info.dt_limit);
    assert_eq!(std::fs::read_dir(memo.dir()).unwrap().count(), 2);
    // the ball's speed changes no material operator: recalled
    let faster = SLAB.replace("-75.0", "-80.0");
    assert!(setup(&faster, Some(&memo)).info.times.stable_step_recalled);
}
