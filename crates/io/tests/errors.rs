//! Every parse error names the file, the 1-based line and what was expected vs found.

use perifrac_io::{read_surface, read_tet_mesh, write_surface, IoError, SurfaceRef, TetFormat};
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Reads `path`, expects a parse error and checks file name, line and key phrase.
fn expect_error(path: &Path, line: usize, phrase: &str) {
    let err = read_tet_mesh(path).expect_err("should fail");
    let msg = err.to_string();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(
        msg.contains(&format!("{name}:{line}: ")),
        "wrong file/line: {msg}"
    );
    assert!(msg.contains(phrase), "missing \"{phrase}\": {msg}");
    assert!(
        matches!(err, IoError::Parse { line: l, .. } if l == line),
        "{err:?}"
    );
}

const NODE: &str = "# four points\n4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const MESH_HEAD: &str =
    "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n";

#[test]
fn medit_truncated() {
    let d = tempfile::tempdir().unwrap();
    let p = write(
        d.path(),
        "t.mesh",
        &format!("{MESH_HEAD}Tetrahedra\n2\n1 2 3 4 0\n1 2 3"),
    );
    expect_error(
        &p,
        12,
        "expected 4 vertex indices and a reference after \"Tetrahedra\", found end of file",
    );
}

#[test]
fn medit_wrong_count_names_line_where_it_ended() {
    let d = tempfile::tempdir().unwrap();
    // Header says 3 tets, the section has 1 and then End (line 12).
    let p = write(
        d.path(),
        "c.mesh",
        &format!("{MESH_HEAD}Tetrahedra\n3\n1 2 3 4 0\nEnd\n"),
    );
    expect_error(&p, 12, "found \"End\" (tet 2 of 3)");
}

#[test]
fn medit_out_of_range_and_repeated() {
    let d = tempfile::tempdir().unwrap();
    let p = write(
        d.path(),
        "r.mesh",
        &format!("{MESH_HEAD}Tetrahedra\n1\n1 2 3 5 0\nEnd\n"),
    );
    expect_error(
        &p,
        11,
        "vertex index 5 out of range (the file has 4 vertices)",
    );
    let p = write(
        d.path(),
        "z.mesh",
        &format!("{MESH_HEAD}Tetrahedra\n1\n1 2 3 0 0\nEnd\n"),
    );
    expect_error(&p, 11, "vertex index 0 out of range");
    let p = write(
        d.path(),
        "d.mesh",
        &format!("{MESH_HEAD}Tetrahedra\n1\n1 2 2 4 0\nEnd\n"),
    );
    expect_error(&p, 11, "tet 1 repeats vertex index 2");
}

#[test]
fn medit_nan_coordinate() {
    let d = tempfile::tempdir().unwrap();
    let p = write(
        d.path(),
        "n.mesh",
        "Dimension 3\nVertices 2\n0 0 0 0\n1 NaN 0 0\n",
    );
    expect_error(&p, 4, "coordinate is NaN/infinite");
}

#[test]
fn tetgen_errors() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "a.node", NODE);
    let ele = write(
        d.path(),
        "a.ele",
        "2 4 0\n0 0 1 2 3\n\n# gap\n1 0 1 2 9001\n",
    );
    expect_error(
        &ele,
        5,
        "vertex index 9001 out of range (the .node file has 4 vertices)",
    );
    write(d.path(), "b.node", NODE);
    let ele = write(d.path(), "b.ele", "1 4 0\n0 0 1 3 3\n");
    expect_error(&ele, 2, "tetrahedron 0 repeats vertex index 3");
    write(d.path(), "c.node", NODE);
    let ele = write(d.path(), "c.ele", "3 4 0\n0 0 1 2 3\n");
    expect_error(&ele, 2, "found end of file (tetrahedron 2 of 3)");
    let node = write(d.path(), "x.node", "2 3 0 0\n0 0 0 0\n1 inf 0 0\n");
    write(d.path(), "x.ele", "0 4 0\n");
    expect_error(&node, 3, "coordinate is NaN/infinite");
}

#[test]
fn tetgen_missing_sibling() {
    let d = tempfile::tempdir().unwrap();
    let ele = write(d.path(), "lonely.ele", "0 4 0\n");
    let msg = read_tet_mesh(&ele).unwrap_err().to_string();
    assert!(
        msg.contains("lonely.node") && msg.contains("not found") && msg.contains("lonely.ele"),
        "{msg}"
    );
}

#[test]
fn gmsh_errors() {
    let d = tempfile::tempdir().unwrap();
    let head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n7 0 0 1\n$EndNodes\n";
    let p = write(
        d.path(),
        "u.msh",
        &format!("{head}$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n"),
    );
    expect_error(
        &p,
        13,
        "tetrahedron 1 uses node tag 4, which is not in $Nodes",
    );
    let p = write(
        d.path(),
        "t.msh",
        &format!("{head}$Elements\n2\n1 4 2 1 1 1 2 3 7\n"),
    );
    expect_error(&p, 13, "found end of file (element 2 of 2)");
    let p = write(d.path(), "b.msh", "$MeshFormat\n4.1 1 8\n$EndMeshFormat\n");
    let msg = read_tet_mesh(&p).unwrap_err().to_string();
    assert!(msg.contains("b.msh") && msg.contains("binary"), "{msg}");
}

#[test]
fn vtk_errors() {
    let d = tempfile::tempdir().unwrap();
    let head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0 1 0 0\n0 1 0\n0 0 1\n";
    let p = write(
        d.path(),
        "r.vtk",
        &format!("{head}CELLS 1 5\n4 0 1 2 4\nCELL_TYPES 1\n10\n"),
    );
    expect_error(&p, 10, "point index 4 out of range (the file has 4 points)");
    let p = write(
        d.path(),
        "d.vtk",
        &format!("{head}CELLS 1 5\n4 0 1 1 3\nCELL_TYPES 1\n10\n"),
    );
    expect_error(&p, 10, "cell 0 repeats vertex index 1");
    let p = write(d.path(), "b.vtk", "# vtk DataFile Version 3.0\nt\nBINARY\n");
    let msg = read_tet_mesh(&p).unwrap_err().to_string();
    assert!(msg.contains("b.vtk") && msg.contains("binary"), "{msg}");
}

#[test]
fn unknown_extensions_list_known_ones() {
    let msg = read_tet_mesh(Path::new("cube.stl"))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("cube.stl")
            && msg.contains(".mesh")
            && msg.contains(".msh")
            && msg.contains(".vtk"),
        "{msg}"
    );
    assert!(TetFormat::from_path(Path::new("noext")).is_err());
    let msg = read_surface(Path::new("s.stl")).unwrap_err().to_string();
    assert!(
        msg.contains("s.stl") && msg.contains(".obj") && msg.contains(".off"),
        "{msg}"
    );
    let s = SurfaceRef::new(&[], &[]);
    let msg = write_surface(Path::new("s.stl"), &s)
        .unwrap_err()
        .to_string();
    assert!(msg.contains(".ply") && msg.contains(".inc"), "{msg}");
}

#[test]
fn io_errors_carry_the_path() {
    let msg = read_tet_mesh(Path::new("/nonexistent/dir/m.mesh"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("/nonexistent/dir/m.mesh"), "{msg}");
}

#[test]
fn surfaces_with_nan_or_infinite_coordinates_are_refused() {
    let d = tempfile::tempdir().unwrap();
    // OBJ: the file and the line (issue 17: `convert cube_nan.obj x.ply` exited 0).
    let p = write(
        d.path(),
        "nan.obj",
        "v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
    );
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(msg.contains("nan.obj:3: vertex 3"), "{msg}");
    assert!(msg.contains("NaN/infinite"), "{msg}");
    let p = write(
        d.path(),
        "inf.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n",
    );
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(msg.contains("inf.obj:3: "), "{msg}");
    // Binary PLY: the vertex, counted from 1.
    let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, f64::INFINITY, 0.0]];
    let p = d.path().join("inf.ply");
    write_surface(&p, &SurfaceRef::new(&vertices, &[[0, 1, 2]])).unwrap();
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(
        msg.contains("inf.ply") && msg.contains("vertex 3 of 3"),
        "{msg}"
    );
    assert!(msg.contains("non-finite"), "{msg}");
    // ASCII PLY: refused too, with a line.
    let p = write(
        d.path(),
        "nan_ascii.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n",
    );
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(msg.contains("nan_ascii.ply"), "{msg}");
}

#[test]
fn obj_errors_name_the_line() {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}:4: ", p.display())), "{msg}");
    assert!(msg.contains("no vertex 7"), "{msg}");
    let p = write(d.path(), "word.obj", "v 0 0 0\nv 1 zero 0\n");
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(
        msg.contains("word.obj:2: ") && msg.contains("\"zero\""),
        "{msg}"
    );
}

#[test]
fn empty_surfaces_are_refused() {
    let d = tempfile::tempdir().unwrap();
    // Issue 17: an empty .obj converted to an empty PLY with exit 0.
    let p = write(d.path(), "empty.obj", "");
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(
        msg.contains("empty.obj") && msg.contains("no vertices"),
        "{msg}"
    );
    let p = write(d.path(), "points.obj", "# only points\nv 0 0 0\nv 1 0 0\n");
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(
        msg.contains("no faces") || msg.contains("no vertices"),
        "{msg}"
    );
    let p = write(d.path(), "empty.off", "OFF\n0 0 0\n");
    let msg = read_surface(&p).unwrap_err().to_string();
    assert!(
        msg.contains("empty.off") && msg.contains("no vertices"),
        "{msg}"
    );
}
