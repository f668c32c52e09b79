//! The PLY readers (surface with crack flags, frame with every attribute, point cloud) on
//! arbitrary bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("s.ply");
    let _ = perifrac_io::parse_surface(path, data);
    let _ = perifrac_io::parse_ply_crack(path, data);
    let _ = perifrac_io::parse_ply_frame(path, data);
    let _ = perifrac_io::parse_ply_points(path, data);
});
