//! The TetGen reader on arbitrary bytes split at NUL bytes into `.node`, `.ele` and an optional
//! `.face` (the seeds are the three files joined by NULs), then the topology of what it loads.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let mut parts = data.splitn(3, |&b| b == 0);
    let node = parts.next().unwrap_or_default();
    let ele = parts.next().unwrap_or_default();
    let face = parts.next();
    if let Ok(mesh) = perifrac_io::parse_tetgen(Path::new("s.node"), node, ele, face) {
        common::exercise_tet_mesh(mesh);
    }
});
