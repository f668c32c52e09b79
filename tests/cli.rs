//! End-to-end tests of the `perifrac` binary: convert, mesh, info, and its errors.

mod common;

use common::{fails, ok};

use std::path::Path;

fn info_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&ok(&["info", "--json", path.to_str().unwrap()])).unwrap()
}

#[test]
fn mesh_box_then_info_reports_what_was_built() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slab.mesh");
    ok(&[
        "mesh",
        "box:1x0.2x0.5",
        "--resolution",
        "10",
        "-o",
        out.to_str().unwrap(),
    ]);
    let info = info_json(&out);
    // 10 x 2 x 5 cells, 6 tets each; (11 * 3 * 6) lattice vertices.
    assert_eq!(info["tets"], 600);
    assert_eq!(info["vertices"], 198);
    // Boundary: 2 triangles per cell face on the surface: 2 * 2 * (10*2 + 10*5 + 2*5).
    assert_eq!(info["boundary_faces"], 320);
    assert_eq!(info["pieces"], 1);
    assert_eq!(info["inverted_fixed"], 0);
    let volume = info["volume"].as_f64().unwrap();
    assert!((volume - 0.1).abs() < 1e-12, "volume {volume}");
    // Kuhn cubes: dihedral angles are 45, 60 and 90 degrees (cubic cells, h = 0.1).
    let min_dihedral = info["min_dihedral_deg"].as_f64().unwrap();
    assert!(
        (min_dihedral - 45.0).abs() < 1e-9,
        "min dihedral {min_dihedral}"
    );
    // Distinct edges of a Kuhn lattice of n cells per side, by kind: axis edges of length h,
    // one face diagonal per cell face (h sqrt 2), one body diagonal per cell (h sqrt 3).
    let (nx, ny, nz) = (10.0, 2.0, 5.0);
    let (vx, vy, vz) = (nx + 1.0, ny + 1.0, nz + 1.0);
    let axis = nx * vy * vz + ny * vx * vz + nz * vx * vy;
    let faces = nx * ny * vz + ny * nz * vx + nx * nz * vy;
    let body = nx * ny * nz;
    let h = 0.1;
    let expected = h * (axis + faces * 2f64.sqrt() + body * 3f64.sqrt()) / (axis + faces + body);
    let lambda = info["mean_edge_length"].as_f64().unwrap();
    assert!(
        (lambda - expected).abs() < 1e-12,
        "lambda {lambda} vs {expected}"
    );
    assert!(info["problems"].as_array().unwrap().is_empty());
}

#[test]
fn a_mirrored_box_has_the_lattice_counts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slab.mesh");
    let o = out.to_str().unwrap();
    ok(&[
        "mesh",
        "box:1x0.2x0.5",
        "--resolution",
        "10",
        "--mirrored",
        "-o",
        o,
    ]);
    // The same cells, tets and edge lengths as the Kuhn lattice above (a mirror keeps one
    // diagonal per cell face and one per cell); conforming, so the same boundary.
    let info = info_json(&out);
    assert_eq!(info["tets"], 600);
    assert_eq!(info["boundary_faces"], 320);
    assert_eq!(info["pieces"], 1);
    assert_eq!(info["inverted_fixed"], 0);
    let err = fails(&["mesh", "box:1x1x1", "--mirrored", "--unstructured", "-o", o]);
    assert!(
        err.contains("--unstructured") || err.contains("--mirrored"),
        "{err}"
    );
    let err = fails(&["mesh", "sphere:1", "--mirrored", "-o", o]);
    assert!(err.contains("--mirrored"), "{err}");
}

#[test]
fn info_human_summary_names_the_counts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bar.vtk");
    ok(&[
        "mesh",
        "bar:1x0.1x0.1",
        "--cells",
        "10,1,1",
        "-o",
        out.to_str().unwrap(),
    ]);
    let text = ok(&["info", out.to_str().unwrap()]);
    assert!(text.contains("60 tets"), "{text}");
    assert!(text.contains("no problems found"), "{text}");
}

#[test]
fn convert_chain_through_every_format_keeps_the_mesh() {
    let Some(bunny) = common::shared_mesh("bunny.mesh") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let reference = info_json(&bunny);
    let mut previous = bunny.clone();
    for name in ["a.vtk", "b.msh", "c.node", "d.mesh"] {
        let next = dir.path().join(name);
        ok(&[
            "convert",
            previous.to_str().unwrap(),
            next.to_str().unwrap(),
        ]);
        previous = next;
    }
    let back = info_json(&previous);
    for key in [
        "vertices",
        "tets",
        "boundary_faces",
        "volume",
        "mean_edge_length",
        "min_dihedral_deg",
    ] {
        assert_eq!(back[key], reference[key], "{key} changed through the chain");
    }
    // The chain kept the labels too (VTK carries them as cell data or drops them to 0).
    assert_eq!(back["tets"], 34_055);
}

#[test]
fn convert_surface_to_ply() {
    let Some(off) = common::shared_mesh("bunny.off") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("bunny.ply");
    ok(&["convert", off.to_str().unwrap(), ply.to_str().unwrap()]);
    let back = perifrac_io::read_surface(&ply).unwrap();
    // Vertex count of bunny.off from ../shared/data/meshes/SOURCES.md.
    assert_eq!(back.vertices.len(), 3_485);
}

#[test]
fn bad_inputs_get_clear_errors_and_a_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);

    // Unknown extension: names the file and the known ones.
    std::fs::write(p("x.stl"), "solid x\n").unwrap();
    let err = fails(&["info", p("x.stl").to_str().unwrap()]);
    assert!(err.contains("x.stl") && err.contains(".mesh"), "{err}");

    // Missing file.
    let err = fails(&["info", p("missing.mesh").to_str().unwrap()]);
    assert!(err.contains("missing.mesh"), "{err}");

    // Truncated Medit file: the tet section ends early; the error names the file and a line.
    let medit = "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\nTetrahedra\n2\n1 2 3 4 0\n";
    std::fs::write(p("short.mesh"), medit).unwrap();
    let err = fails(&["info", p("short.mesh").to_str().unwrap()]);
    assert!(err.contains("short.mesh:"), "{err}");

    // Index out of range, on line 11.
    let bad_index = medit.replace("Tetrahedra\n2\n1 2 3 4 0\n", "Tetrahedra\n1\n1 2 3 9 0\n");
    std::fs::write(p("index.mesh"), bad_index).unwrap();
    let err = fails(&["info", p("index.mesh").to_str().unwrap()]);
    assert!(err.contains("index.mesh:11"), "{err}");

    // NaN coordinate on line 6.
    let nan = medit.replace("1 0 0 0\n", "nan 0 0 0\n");
    std::fs::write(p("nan.mesh"), nan).unwrap();
    let err = fails(&["info", p("nan.mesh").to_str().unwrap()]);
    assert!(err.contains("nan.mesh:6"), "{err}");

    // A flat (zero-volume) tet: the error names the file, the tet's line and the tet counted
    // from 1, as the readers do.
    let flat = medit
        .replace("0 0 1 0\n", "1 1 0 0\n")
        .replace("Tetrahedra\n2\n1 2 3 4 0\n", "Tetrahedra\n1\n1 2 3 4 0\n");
    std::fs::write(p("flat.mesh"), flat).unwrap();
    let err = fails(&["info", p("flat.mesh").to_str().unwrap()]);
    assert!(err.contains("flat.mesh:11: tet 1 has volume"), "{err}");

    // Convert to an unknown extension writes nothing.
    let good = p("good.mesh");
    ok(&[
        "mesh",
        "box:1x1x1",
        "--resolution",
        "2",
        "-o",
        good.to_str().unwrap(),
    ]);
    let err = fails(&[
        "convert",
        good.to_str().unwrap(),
        p("out.xyz").to_str().unwrap(),
    ]);
    assert!(err.contains("out.xyz"), "{err}");
    assert!(!p("out.xyz").exists());

    // Bad primitive specs.
    let err = fails(&["mesh", "box:1x0", "-o", p("o.mesh").to_str().unwrap()]);
    assert!(err.contains("box:1x0"), "{err}");
}

#[test]
fn inverted_tets_are_reoriented_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    // One tet given with negative orientation (corners 2 and 3 swapped).
    let medit = "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\nTetrahedra\n1\n1 3 2 4 0\nEnd\n";
    let path = dir.path().join("inv.mesh");
    std::fs::write(&path, medit).unwrap();
    let info = info_json(&path);
    assert_eq!(info["inverted_fixed"], 1);
    let volume = info["volume"].as_f64().unwrap();
    assert!((volume - 1.0 / 6.0).abs() < 1e-15);
    let out = dir.path().join("fixed.mesh");
    ok(&["convert", path.to_str().unwrap(), out.to_str().unwrap()]);
    assert_eq!(info_json(&out)["inverted_fixed"], 0);
}

#[test]
fn help_names_every_subcommand_in_its_first_line() {
    let help = ok(&["--help"]);
    let first = help.lines().next().unwrap();
    // The subcommands are the first words of the lines under "Commands:", up to a blank line.
    let commands: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|&c| c != "help")
        .collect();
    assert!(commands.len() >= 7, "too few subcommands found in:\n{help}");
    for c in commands {
        assert!(
            first.split([' ', ',', ':']).any(|w| w == c),
            "`{c}` is missing from the help's first line: {first}"
        );
    }
}
