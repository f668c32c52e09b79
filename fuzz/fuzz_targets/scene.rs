//! The scene parser and setup on arbitrary text, against small budgets so that each input
//! takes milliseconds: a scene loads and builds, or gives an error; a small one that builds
//! also takes a few steps.
#![no_main]

use libfuzzer_sys::fuzz_target;
use perifrac_scene::{Limits, Scene, Setup};
use std::path::Path;

/// Particles up to which a built scene also steps.
const STEP_PARTICLES: usize = 2_000;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scene) = Scene::parse(text, Path::new("fuzz.toml")) else {
        return;
    };
    let limits = Limits {
        memory_bytes: 32 << 20,
        memory_source: "the fuzz target's budget".into(),
        max_steps: 10_000_000,
        max_output_bytes: 1 << 30,
        max_seconds: 3600.0,
        threads: 1,
        allow_large: false,
    };
    let Ok(mut setup) = Setup::with_limits(&scene, None, &limits) else {
        return;
    };
    if setup.info.particles <= STEP_PARTICLES {
        for _ in 0..3 {
            if setup.driver.step().is_err() {
                break;
            }
        }
    }
});
