//! The vtk reader on arbitrary bytes, then the topology of what it loads.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = perifrac_io::parse_tet_mesh(Path::new("s.vtk"), data) {
        common::exercise_tet_mesh(mesh);
    }
});
