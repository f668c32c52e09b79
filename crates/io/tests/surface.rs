//! Surface readers and writers: PLY (checked by Python's plyfile), OBJ, OFF, POV-Ray mesh2.

mod common;

use perifrac_io::{
    read_ply_crack, read_surface, write_obj, write_ply, write_povray_mesh2, write_surface,
    PlyEncoding, SurfaceRef,
};
use std::path::Path;
use std::process::Command;

const VERTICES: [[f64; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.25, -2.5, 1e3],
];
const FACES: [[u32; 3]; 4] = [[0, 1, 2], [0, 1, 3], [4, 2, 3], [1, 2, 4]];
const CRACK: [u8; 4] = [0, 1, 1, 0];
const COLORS: [[u8; 3]; 5] = [
    [255, 0, 0],
    [0, 255, 0],
    [0, 0, 255],
    [1, 2, 3],
    [200, 100, 50],
];

fn surface() -> SurfaceRef<'static> {
    SurfaceRef {
        vertices: &VERTICES,
        faces: &FACES,
        crack: Some(&CRACK),
        colors: Some(&COLORS),
        ..Default::default()
    }
}

fn have_plyfile() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import plyfile"])
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        eprintln!("SKIPPED: python plyfile not installed");
    }
    ok
}

/// Reads `path` with plyfile and prints counts, face 2, crack flags and vertex 4's colour.
fn plyfile_summary(path: &Path) -> String {
    let script = "import sys, plyfile\n\
        d = plyfile.PlyData.read(sys.argv[1])\n\
        v = d['vertex']; f = d['face']\n\
        print(len(v.data), len(f.data))\n\
        print(' '.join(str(int(i)) for i in f.data['vertex_indices'][2]))\n\
        print(' '.join(str(int(c)) for c in f.data['crack']))\n\
        print(int(v.data['red'][4]), int(v.data['green'][4]), int(v.data['blue'][4]))\n\
        print(float(v.data['x'][4]), float(v.data['y'][4]), float(v.data['z'][4]))\n";
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "plyfile failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn ply_read_by_plyfile_and_by_us() {
    let dir = tempfile::tempdir().unwrap();
    for (enc, name) in [
        (PlyEncoding::BinaryLittleEndian, "b.ply"),
        (PlyEncoding::Ascii, "a.ply"),
    ] {
        let path = dir.path().join(name);
        write_ply(&path, &surface(), enc).unwrap();
        let (s, crack) = read_ply_crack(&path).unwrap();
        assert_eq!(s.faces, FACES.to_vec());
        assert_eq!(crack.as_deref(), Some(&CRACK[..]));
        // Coordinates are stored as f32: these values are exact in f32.
        assert_eq!(s.vertices, VERTICES.to_vec());
        if have_plyfile() {
            let got = plyfile_summary(&path);
            let want = "5 4\n4 2 3\n0 1 1 0\n200 100 50\n0.25 -2.5 1000.0\n";
            assert_eq!(got, want, "{name}");
        }
    }
}

#[test]
fn ply_binary_size_is_exact() {
    // Binary layout: 12 (xyz f32) + 3 (rgb) bytes per vertex; 1 + 12 (list) + 1 (crack) per face.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.ply");
    write_ply(&path, &surface(), PlyEncoding::default()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header_end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    assert_eq!(bytes.len() - header_end, 5 * 15 + 4 * 14);
    assert_eq!(bytes[header_end + 5 * 15], 3, "list count byte");
}

#[test]
fn ply_without_crack_reads_none() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.ply");
    write_surface(&path, &SurfaceRef::new(&VERTICES, &FACES)).unwrap();
    let (s, crack) = read_ply_crack(&path).unwrap();
    assert_eq!((s.vertices.len(), s.faces.len(), crack), (5, 4, None));
}

#[test]
fn obj_writes_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.obj");
    write_obj(&path, &surface()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 5);
    assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 4);
    let s = read_surface(&path).unwrap();
    assert_eq!(s.vertices, VERTICES.to_vec());
    assert_eq!(s.faces.len(), 4);
    // tobj may reorder vertices per object; compare faces by position.
    for (f, g) in s.faces.iter().zip(FACES) {
        let a: Vec<_> = f.iter().map(|&i| s.vertices[i as usize]).collect();
        let b: Vec<_> = g.iter().map(|&i| VERTICES[i as usize]).collect();
        assert_eq!(a, b);
    }
}

#[test]
fn povray_mesh2_structure() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.inc");
    write_surface(&path, &surface()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("#declare perifrac_mesh = mesh2 {"));
    assert!(text.contains("texture_list { 2, texture { perifrac_mesh_surface_texture }, texture { perifrac_mesh_crack_texture } }"));
    assert_eq!(text.matches(",<").count(), 5 + 4);
    assert!(text.contains(",<4,2,3>,1"), "{text}");
    assert!(text.contains(",<0,1,2>,0"));
    assert!(text.contains(",<0.25,-2.5,1000.0>"));
    assert!(write_povray_mesh2(&path, &surface(), "9bad name").is_err());
    render_include(dir.path(), "perifrac_mesh");
}

/// Renders `dir/s.inc`'s mesh `name` in a tiny scene if POV-Ray happens to be installed.
fn render_include(dir: &Path, name: &str) {
    if Command::new("povray").arg("--version").output().is_err() {
        eprintln!("SKIPPED: povray not on PATH, include not rendered");
        return;
    }
    let scene = dir.join("scene.pov");
    std::fs::write(&scene, format!("#include \"s.inc\"\ncamera {{ location <2,2,-3> look_at 0 }}\nlight_source {{ <5,5,-5> rgb 1 }}\nobject {{ {name} }}\n")).unwrap();
    let status = Command::new("povray")
        .current_dir(dir)
        .args(["+Iscene.pov", "+W32", "+H32", "-D", "+Oout.png"])
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    // POV-Ray writes the image only when the include parsed.
    assert!(dir.join("out.png").exists());
}

#[test]
fn off_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.off");
    std::fs::write(
        &path,
        "OFF\n# quad and triangle\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n4 0 1 2 3\n3 0 1 4\n",
    )
    .unwrap();
    let s = read_surface(&path).unwrap();
    assert_eq!(s.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
}

#[test]
fn writers_refuse_inconsistent_data() {
    let dir = tempfile::tempdir().unwrap();
    let bad = SurfaceRef {
        crack: Some(&CRACK[..2]),
        ..surface()
    };
    let msg = write_ply(&dir.path().join("x.ply"), &bad, PlyEncoding::Ascii)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("x.ply") && msg.contains("2 crack flags for 4 faces"),
        "{msg}"
    );
    let faces = [[0, 1, 9]];
    let bad = SurfaceRef::new(&VERTICES, &faces);
    assert!(write_obj(&dir.path().join("x.obj"), &bad).is_err());
}

#[test]
fn real_surfaces_load() {
    let Some(dir) = common::mesh_dir() else {
        return;
    };
    let bunny = read_surface(&dir.join("bunny.off")).unwrap();
    // 3,485 vertices: the bunny.off header (and the brief).
    assert_eq!(bunny.vertices.len(), 3_485);
    assert!(!bunny.faces.is_empty());
    for name in ["spot.obj", "armadillo.obj"] {
        let s = read_surface(&dir.join(name)).unwrap();
        assert!(!s.vertices.is_empty() && !s.faces.is_empty(), "{name}");
        let n = s.vertices.len() as u32;
        assert!(s.faces.iter().flatten().all(|&i| i < n), "{name}");
    }
}

const NORMALS: [[f64; 3]; 5] = [
    [0.0, 0.0, -1.0],
    [0.6, 0.0, -0.8],
    [0.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 0.8, 0.6],
];
const VELOCITIES: [[f64; 3]; 5] = [
    [1.0, 2.0, 3.0],
    [0.0; 3],
    [-4.5, 0.0, 1e-3],
    [0.0, 0.0, -9.81],
    [1e4, 0.0, 0.0],
];
const UV: [[f64; 2]; 5] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5], [0.25, 0.75]];
const IDS: [u32; 5] = [0, 1, 1, 3, 4_000_000_000];
const FRAGMENT: [u32; 4] = [0, 0, 7, 7];

fn frame_surface() -> SurfaceRef<'static> {
    SurfaceRef {
        normals: Some(&NORMALS),
        velocities: Some(&VELOCITIES),
        uv: Some(&UV),
        vertex_ids: Some(&IDS),
        fragment: Some(&FRAGMENT),
        colors: None,
        ..surface()
    }
}

#[test]
fn frame_attributes_read_by_plyfile() {
    if !have_plyfile() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (encoding, name) in [
        (PlyEncoding::BinaryLittleEndian, "b.ply"),
        (PlyEncoding::Ascii, "a.ply"),
    ] {
        let path = dir.path().join(name);
        write_ply(&path, &frame_surface(), encoding).unwrap();
        let script = "import sys, plyfile\n\
            d = plyfile.PlyData.read(sys.argv[1])\n\
            v = d['vertex'].data; f = d['face'].data\n\
            for k in ['nx', 'ny', 'nz', 'vx', 'vy', 'vz', 's', 't', 'vertex_id']:\n\
            \x20   print(k, ' '.join(repr(float(x)) for x in v[k]))\n\
            print('crack', ' '.join(str(int(c)) for c in f['crack']))\n\
            print('fragment', ' '.join(str(int(c)) for c in f['fragment']))\n\
            print(v.dtype['vertex_id'], f.dtype['fragment'])\n";
        let out = Command::new("python3")
            .args(["-c", script])
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        let row = |key: &str| -> Vec<f64> {
            let line = text
                .lines()
                .find(|l| l.split(' ').next() == Some(key))
                .unwrap();
            line.split(' ')
                .skip(1)
                .map(|x| x.parse().unwrap())
                .collect()
        };
        for (k, key) in ["nx", "ny", "nz"].iter().enumerate() {
            let want: Vec<f64> = NORMALS.iter().map(|n| f64::from(n[k] as f32)).collect();
            assert_eq!(row(key), want, "{name} {key}");
        }
        for (k, key) in ["vx", "vy", "vz"].iter().enumerate() {
            let want: Vec<f64> = VELOCITIES.iter().map(|n| f64::from(n[k] as f32)).collect();
            assert_eq!(row(key), want, "{name} {key}");
        }
        for (k, key) in ["s", "t"].iter().enumerate() {
            let want: Vec<f64> = UV.iter().map(|n| f64::from(n[k] as f32)).collect();
            assert_eq!(row(key), want, "{name} {key}");
        }
        let ids: Vec<f64> = IDS.iter().map(|&i| f64::from(i)).collect();
        assert_eq!(row("vertex_id"), ids);
        assert_eq!(row("crack"), vec![0.0, 1.0, 1.0, 0.0]);
        assert_eq!(row("fragment"), vec![0.0, 0.0, 7.0, 7.0]);
        // Unsigned 32-bit integers for both ids (4e9 would not fit a signed int).
        assert!(text.contains("uint32 uint32"), "{text}");
    }
}

#[test]
fn povray_mesh2_with_normals_renders() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.inc");
    write_povray_mesh2(&path, &frame_surface(), "m").unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("normal_vectors {\n    5\n    ,<0.0,0.0,-1.0>"),
        "{text}"
    );
    // Vertices, normals and faces, one `,<` each.
    assert_eq!(text.matches(",<").count(), 5 + 5 + 4);
    render_include(dir.path(), "m");
}
