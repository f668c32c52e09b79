//! The mesh command's primitive specs: the first line is a spec (`box:1x2x3`, `sphere:0.5`,
//! ...), the second either `--cells` as `NX,NY,NZ` or a resolution. Counts and sizes are
//! checked for every input; meshes are built when they are small enough to build per input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use perifrac_topology::mesher::{estimated_tets, mesh_surface, MesherOptions};
use perifrac_topology::{primitives, spec};

/// The largest mesh built per input (tets), so that each input takes milliseconds.
const MAX_TETS: f64 = 20_000.0;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (line, rest) = text.split_once('\n').unwrap_or((text, ""));
    let rest = rest.trim();
    let cells: Option<Vec<usize>> = rest
        .contains(',')
        .then(|| rest.split(',').map(|c| c.trim().parse().ok()).collect())
        .flatten();
    let resolution: usize = rest.parse().unwrap_or(8);
    match spec::parse_round(line) {
        Ok(Some((vertices, faces))) => {
            let opts = MesherOptions {
                edge_length: None,
                resolution: Some(resolution),
            };
            if estimated_tets(&vertices, &opts) <= MAX_TETS {
                let _ = mesh_surface(&vertices, &faces, &opts);
            }
        }
        Ok(None) => {
            let Ok(prim) = spec::parse_primitive(line) else {
                return;
            };
            let counts = match cells.as_deref() {
                Some(&[a, b, c]) if a > 0 && b > 0 && c > 0 => [a, b, c],
                Some(_) => return,
                None => primitives::cells_for_resolution(prim.size, resolution),
            };
            let Ok((_vertices, tets)) = primitives::box_counts(counts) else {
                return;
            };
            if primitives::check_box([0.0; 3], prim.size, counts).is_ok() && tets as f64 <= MAX_TETS
            {
                let mesh = primitives::try_box_mesh([0.0; 3], prim.size, counts);
                assert!(mesh.is_ok(), "a checked box failed to mesh: {mesh:?}");
            }
        }
        Err(_) => {}
    }
});
