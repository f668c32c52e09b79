//! The OFF surface reader on arbitrary bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = perifrac_io::parse_surface(Path::new("s.off"), data);
});
