//! End-to-end tests of `perifrac run`: a tiny version of the default scene runs, its frames
//! parse, crack faces appear, it ends in several closed fragments with its mass intact, and a
//! second run writes identical files; bad scenes are refused with one message and nothing
//! written; an instability mid-run keeps the frames written before it.

mod common;

use std::path::Path;

use common::{fails, ok, perifrac, tiny_wall};
use perifrac_io::{read_ply_crack, read_ply_frame, read_ply_points};
use perifrac_topology::Surface;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn manifest(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("run.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Connected components of a triangle surface through shared vertices: component id per face.
fn components(faces: &[[u32; 3]], vertices: usize) -> (usize, Vec<usize>) {
    let mut parent: Vec<usize> = (0..vertices).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for f in faces {
        for k in 1..3 {
            let (a, b) = (
                find(&mut parent, f[0] as usize),
                find(&mut parent, f[k] as usize),
            );
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut id = vec![usize::MAX; vertices];
    let mut count = 0;
    let of_face = faces
        .iter()
        .map(|f| {
            let r = find(&mut parent, f[0] as usize);
            if id[r] == usize::MAX {
                id[r] = count;
                count += 1;
            }
            id[r]
        })
        .collect();
    (count, of_face)
}

#[test]
fn tiny_wall_breaks_into_closed_fragments_and_reruns_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    let out = tmp.path().join("out");
    let args = [
        "run",
        s(&scene),
        "-o",
        s(&out),
        "--frames",
        "6",
        "--threads",
        "2",
    ];
    ok(&args);

    let run = manifest(&out);
    assert_eq!(run["format"], "perifrac-run/1");
    assert_eq!(run["finished"], true);
    assert!(run["error"].is_null());
    let frames = run["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 7, "the initial frame and 6 more");
    let total_mass = run["mass"].as_f64().unwrap();
    // 0.6 x 0.6 x 0.06 m of glass at 2200 kg/m^3.
    assert!((total_mass / 47.52 - 1.0).abs() < 1e-12, "{total_mass}");

    for f in frames {
        // Every frame parses: the surface with its crack flags, the particles with their mass.
        let (surface, crack) = read_ply_crack(&out.join(f["surface"].as_str().unwrap())).unwrap();
        let crack = crack.expect("surfaces carry the crack flag");
        assert_eq!(crack.len(), surface.faces.len());
        let povray = std::fs::read_to_string(out.join(f["povray"].as_str().unwrap())).unwrap();
        assert!(povray.contains("mesh2"), "frame {}", f["index"]);
        let particles = read_ply_points(&out.join(f["particles"].as_str().unwrap())).unwrap();
        assert_eq!(
            particles.points.len(),
            run["particles"].as_u64().unwrap() as usize
        );
        // Nothing is lost: the particle masses (stored as f32, 6e-8 relative each) still add up
        // to the scene's mass at every frame.
        let mass: f64 = particles.scalar("mass").unwrap().iter().sum();
        assert!(
            (mass / total_mass - 1.0).abs() < 1e-6,
            "frame {}: {mass}",
            f["index"]
        );
        let damage = particles.scalar("damage").unwrap();
        assert!(damage.iter().all(|d| (0.0..=1.0).contains(d)));
    }

    // The last frame: cracks, several fragments, each with a closed, outward surface. Its
    // vertices are split where shading is sharp; the copies of a mesh vertex share its
    // `vertex_id` and position, so welding by id gives the fragments' closed surfaces.
    let last = frames.last().unwrap();
    let frame = read_ply_frame(&out.join(last["surface"].as_str().unwrap())).unwrap();
    let crack = frame.crack.unwrap();
    let crack_faces = crack.iter().filter(|&&c| c != 0).count();
    assert!(crack_faces > 0, "no crack faces in the last frame");
    assert_eq!(
        crack_faces as u64,
        last["crack_triangles"].as_u64().unwrap()
    );
    let ids = frame.vertex_ids.unwrap();
    let n = ids.iter().max().map_or(0, |&m| m as usize + 1);
    let mut welded = vec![[f64::NAN; 3]; n];
    for (p, &id) in frame.vertices.iter().zip(&ids) {
        let w = &mut welded[id as usize];
        if w[0].is_nan() {
            *w = p.map(f64::from);
        }
        assert_eq!(*w, p.map(f64::from), "copies of vertex {id} apart");
    }
    let faces: Vec<[u32; 3]> = frame
        .faces
        .iter()
        .map(|f| f.map(|v| ids[v as usize]))
        .collect();
    let (count, of_face) = components(&faces, n);
    // The pieces of at most `debris_tets` tets are debris points, not surfaces.
    let debris = last["debris"]["pieces"].as_u64().unwrap_or(0);
    assert_eq!(count as u64 + debris, last["fragments"].as_u64().unwrap());
    assert!(count > 1, "the wall did not break: {count} fragment(s)");
    // The connected pieces are the fragments the faces name.
    let fragment = frame.fragment.unwrap();
    for (f, &c) in of_face.iter().enumerate() {
        let first = of_face.iter().position(|&x| x == c).unwrap();
        assert_eq!(fragment[f], fragment[first], "face {f}");
    }
    // One surface per fragment: its faces over the frame's (welded) vertices.
    let mut fragments = vec![
        Surface {
            vertices: welded.clone(),
            ..Surface::default()
        };
        count
    ];
    for (f, &c) in faces.iter().zip(&of_face) {
        fragments[c].faces.push(*f);
    }
    for (c, fragment) in fragments.iter().enumerate() {
        assert!(fragment.is_closed(), "fragment {c} is not closed");
        let volume = fragment.signed_volume();
        assert!(volume > 0.0, "fragment {c} is inside out: {volume}");
    }
    // Normals are unit and outward: against the face they belong to.
    let normals = frame.normals.unwrap();
    for (f, face) in frame.faces.iter().enumerate() {
        let [a, b, c] = face.map(|v| frame.vertices[v as usize].map(f64::from));
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let fnormal = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        for &v in face {
            let nv = normals[v as usize].map(f64::from);
            let len = (nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]).sqrt();
            // Unit to f32 rounding.
            assert!((len - 1.0).abs() < 1e-6, "normal {nv:?}");
            let along = nv[0] * fnormal[0] + nv[1] * fnormal[1] + nv[2] * fnormal[2];
            // Smooth normals lean off a face by less than the sharp angle (60 degrees), so
            // never point into it; a degenerate face has no direction to compare.
            assert!(along >= 0.0, "face {f}: normal {nv:?} against {fnormal:?}");
        }
    }

    // A second run with the same scene and thread count writes the same bytes, whether it
    // recalls the stable step from the cache the first left, or iterates it.
    let cache = tmp.path().join("cache");
    let (first, again, iterated) = (
        tmp.path().join("first"),
        tmp.path().join("again"),
        tmp.path().join("iterated"),
    );
    // the summary (stderr) of the run into `dir`, with `extra` arguments and `cache`
    let run_in = |dir: &Path, extra: &[&str], cache: &Path| {
        let mut a = args.to_vec();
        a[3] = s(dir);
        a.extend_from_slice(extra);
        let out = common::perifrac_cached(&a, cache);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "perifrac {a:?} failed:\n{err}");
        err
    };
    assert!(!run_in(&first, &[], &cache).contains("recalled"));
    assert!(run_in(&again, &[], &cache).contains("recalled from the cache"));
    let no_cache = tmp.path().join("unused");
    assert!(!run_in(&iterated, &["--no-cache"], &no_cache).contains("recalled"));
    assert!(
        !no_cache.exists(),
        "--no-cache wrote {}",
        no_cache.display()
    );
    let a = common::files(&out);
    for other in [&first, &again, &iterated] {
        let b = common::files(other);
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
        for (name, bytes) in &a {
            assert!(
                bytes == &b[name],
                "{} differs between two runs ({})",
                name.display(),
                other.display()
            );
        }
    }
}

#[test]
fn output_directory_is_refused_when_not_empty_and_force_keeps_foreign_files() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    let out = tmp.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let err = fails(&["run", s(&scene), "-o", s(&out), "--frames", "1"]);
    assert!(
        err.contains("is not empty") && err.contains("--force"),
        "{err}"
    );
    assert!(!out.join("run.json").exists());
    ok(&["run", s(&scene), "-o", s(&out), "--frames", "1", "--force"]);
    assert!(out.join("run.json").is_file());
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
}

/// A scene that must be refused: (what it changes in the tiny wall, what the message says).
const BAD_SCENES: &[(&str, &str, &str, &str)] = &[
    (
        "unknown key",
        "density = 2200.0",
        "density = 2200.0\ndensty = 2200.0",
        "unknown field `densty`",
    ),
    (
        "wrong type",
        "density = 2200.0",
        "density = \"heavy\"",
        "invalid type",
    ),
    (
        "missing mesh",
        "primitive = \"box\"",
        "file = \"no_such_mesh.mesh\"",
        "no_such_mesh.mesh not found",
    ),
    (
        "negative density",
        "density = 2200.0",
        "density = -2200.0",
        "material[0].density: -2200 kg/m^3 must be positive",
    ),
    (
        "collider inside the object",
        "center = [0.3, 0.3, 0.12]",
        "center = [0.3, 0.3, 0.03]",
        "collider inside the object at the start",
    ),
    (
        "time step above the stable limit",
        "dt = \"auto\"",
        "dt = 1e-3",
        "simulation.dt: 1e-3 s is above the stable limit",
    ),
];

#[test]
fn bad_scenes_get_one_clear_message_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(tiny_wall(tmp.path())).unwrap();
    for (what, from, to, expect) in BAD_SCENES {
        let text = good.replacen(from, to, 1);
        assert_ne!(text, good, "{what}: `{from}` is not in the scene");
        let scene = tmp.path().join("bad.toml");
        std::fs::write(&scene, &text).unwrap();
        let out = tmp.path().join("out");
        let err = fails(&["run", s(&scene), "-o", s(&out)]);
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{what}: one message expected:\n{err}");
        assert!(lines[0].starts_with("error: "), "{what}: {err}");
        assert!(
            lines[0].contains("bad.toml"),
            "{what}: names the file: {err}"
        );
        assert!(
            err.contains(expect),
            "{what}: expected `{expect}` in:\n{err}"
        );
        assert!(!out.exists(), "{what}: the output directory was created");
    }
    // Syntax errors point at the line and column: `densty` is the first word of its line.
    let text = good.replacen("density = 2200.0", "density = 2200.0\ndensty = 2200.0", 1);
    let line = text.lines().position(|l| l.starts_with("densty")).unwrap() + 1;
    std::fs::write(tmp.path().join("bad.toml"), &text).unwrap();
    let err = fails(&["run", s(&tmp.path().join("bad.toml")), "-o", "unused"]);
    assert!(err.contains(&format!("bad.toml:{line}:1: ")), "{err}");
}

#[test]
fn an_instability_mid_run_stops_with_a_message_and_keeps_the_frames() {
    // A runaway load: gravity of 4e7 m/s^2 accelerates the slab until, after about half a
    // millisecond, a particle moves further in one step than the blow-up guard allows (half a
    // horizon). The stable-step estimate cannot see it coming (gravity adds no stiffness), so
    // the run starts and writes a few frames (0.1 ms apart; the check allows 2 to 9 of the 11)
    // before it stops. (At 2e7 the fitted dilatation's shorter step let it reach frame 10.)
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(tiny_wall(tmp.path())).unwrap();
    let text = text.replacen(
        "duration = 0.005",
        "duration = 0.001\ngravity = [0.0, 0.0, -4e7]",
        1,
    );
    let scene = tmp.path().join("unstable.toml");
    std::fs::write(&scene, text).unwrap();
    let out = tmp.path().join("out");
    let out_arg = out.to_str().unwrap();
    let res = perifrac(&["run", s(&scene), "-o", out_arg, "--frames", "10"]);
    assert!(!res.status.success());
    let err = String::from_utf8_lossy(&res.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("stopped at t ="), "{err}");
    assert!(err.contains("frames written so far are in"), "{err}");
    let run = manifest(&out);
    assert_eq!(run["finished"], false);
    let message = run["error"].as_str().expect("run.json records the error");
    assert!(message.contains("unstable at step"), "{message}");
    // The message on stderr is the one in run.json, said once.
    assert_eq!(err.matches("unstable at step").count(), 1, "{err}");
    let frames = run["frames"].as_array().unwrap();
    assert!(
        (2..10).contains(&frames.len()),
        "frames before the instability: {}",
        frames.len()
    );
    for f in frames {
        assert!(out.join(f["surface"].as_str().unwrap()).is_file());
    }
}

/// The pieces of every frame pass an independent check (tests/python/check_pieces.py, with
/// plyfile and numpy): welded by `vertex_id`, grouped by `fragment`, each is a closed
/// 2-manifold with a positive volume. Skipped, and says so, without plyfile or numpy.
#[test]
fn every_piece_of_every_frame_passes_the_independent_check() {
    let have = std::process::Command::new("python3")
        .args(["-c", "import plyfile, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        eprintln!("SKIPPED: python3 lacks plyfile or numpy; pieces not checked independently");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    // Every piece as a surface, the smallest too (by default they are debris points).
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(
        &scene,
        text.replace("[output]\n", "[output]\ndebris_tets = 0\n"),
    )
    .unwrap();
    let out = tmp.path().join("out");
    ok(&["run", s(&scene), "-o", s(&out), "--frames", "8"]);
    let stdout = common::python_script("check_pieces.py", &[out.as_os_str()]);
    // The tiny wall breaks into many pieces: the check saw them.
    let total: usize = stdout
        .lines()
        .last()
        .and_then(|l| l.strip_prefix("pieces: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap();
    assert!(total > 50, "{stdout}");
    assert!(
        stdout.contains("0 open, 0 non-manifold, 0 inside out"),
        "{stdout}"
    );
}

/// Crack smoothing is output only: with it off the particles (positions, damage, fragments)
/// of every frame are byte-identical, while the surfaces differ (it did something).
#[test]
fn crack_smoothing_leaves_the_physics_byte_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    let text = std::fs::read_to_string(&scene).unwrap();
    let off = tmp.path().join("tiny_wall_rough.toml");
    let rough = text.replace("[output]\n", "[output]\nsmooth_cracks = false\n");
    assert_ne!(
        rough, text,
        "wall.toml has no [output] table to add the key to"
    );
    std::fs::write(&off, rough).unwrap();
    let (a, b) = (tmp.path().join("on"), tmp.path().join("off"));
    ok(&["run", s(&scene), "-o", s(&a), "--frames", "6"]);
    ok(&["run", s(&off), "-o", s(&b), "--frames", "6"]);
    let mut surfaces_differ = false;
    for k in 0..=6 {
        let particles = format!("frames/particles_{k:04}.ply");
        assert_eq!(
            std::fs::read(a.join(&particles)).unwrap(),
            std::fs::read(b.join(&particles)).unwrap(),
            "{particles}"
        );
        let surface = format!("frames/surface_{k:04}.ply");
        let (sa, sb) = (
            read_ply_frame(&a.join(&surface)).unwrap(),
            read_ply_frame(&b.join(&surface)).unwrap(),
        );
        // Same faces (welded through their vertex ids: shading splits vertices by angle, and
        // angles move), flags and fragments: only positions and what follows from them move.
        let welded = |f: &perifrac_io::FrameSurface| -> Vec<[u32; 3]> {
            let ids = f.vertex_ids.as_ref().unwrap();
            f.faces.iter().map(|t| t.map(|k| ids[k as usize])).collect()
        };
        assert_eq!(welded(&sa), welded(&sb));
        assert_eq!(sa.crack, sb.crack);
        assert_eq!(sa.fragment, sb.fragment);
        surfaces_differ |= sa.vertices != sb.vertices;
    }
    assert!(surfaces_differ, "smoothing moved no vertex of any frame");
}

/// Pieces of at most `debris_tets` tets leave the surface for `frames/debris_NNNN.ply`: each
/// such fragment is one point at the centre of mass of its particles, with their mass, the
/// ball radius of their volume and their mean velocity; every other fragment keeps its surface,
/// as it is with debris off; the particles do not change.
#[test]
fn small_pieces_are_written_as_debris_points() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    let text = std::fs::read_to_string(&scene).unwrap();
    let all = tmp.path().join("tiny_wall_all.toml");
    std::fs::write(
        &all,
        text.replace("[output]\n", "[output]\ndebris_tets = 0\n"),
    )
    .unwrap();
    let (a, b) = (tmp.path().join("debris"), tmp.path().join("all"));
    ok(&["run", s(&scene), "-o", s(&a), "--frames", "4"]);
    ok(&["run", s(&all), "-o", s(&b), "--frames", "4"]);
    let last = "frames/particles_0004.ply";
    assert_eq!(
        std::fs::read(a.join(last)).unwrap(),
        std::fs::read(b.join(last)).unwrap()
    );
    let run = manifest(&a);
    let frame = &run["frames"][4];
    let debris = read_ply_points(&a.join(frame["debris"]["path"].as_str().unwrap())).unwrap();
    let pieces = frame["debris"]["pieces"].as_u64().unwrap() as usize;
    assert_eq!(debris.points.len(), pieces);
    assert!(pieces > 0, "the tiny wall left no debris to test");
    assert!(manifest(&b)["frames"][4]["debris"].is_null());
    let particles = read_ply_points(&a.join(last)).unwrap();
    let (pm, pf) = (
        particles.scalar("mass").unwrap(),
        particles.scalar("fragment").unwrap(),
    );
    let (dm, df, dr) = (
        debris.scalar("mass").unwrap(),
        debris.scalar("fragment").unwrap(),
        debris.scalar("radius").unwrap(),
    );
    let density = 2200.0; // wall.toml's glass
    for k in 0..pieces {
        let mine: Vec<usize> = (0..pf.len()).filter(|&i| pf[i] == df[k]).collect();
        assert!(
            (1..=3).contains(&mine.len()),
            "debris fragment {} has {} particles",
            df[k],
            mine.len()
        );
        let mass: f64 = mine.iter().map(|&i| pm[i]).sum();
        // Both files store f32 (6e-8 relative each): sums of up to 3 agree to 1e-6.
        assert!(
            (dm[k] / mass - 1.0).abs() < 1e-6,
            "{} against {mass}",
            dm[k]
        );
        let volume = 4.0 / 3.0 * std::f64::consts::PI * dr[k].powi(3);
        assert!((volume * density / mass - 1.0).abs() < 1e-5);
        for d in 0..3 {
            let centre: f64 = mine
                .iter()
                .map(|&i| pm[i] * particles.points[i][d])
                .sum::<f64>()
                / mass;
            // f32 positions of metre-sized scenes: 1e-7 m apart at most.
            assert!((debris.points[k][d] - centre).abs() < 1e-6);
        }
    }
    // The surfaces: with debris on, the fragments of the surface are those of the full
    // surface less the debris, with the same faces.
    let (sa, sb) = (
        read_ply_frame(&a.join("frames/surface_0004.ply")).unwrap(),
        read_ply_frame(&b.join("frames/surface_0004.ply")).unwrap(),
    );
    let is_debris = |f: u32| df.contains(&f64::from(f));
    let (fa, fb) = (sa.fragment.unwrap(), sb.fragment.unwrap());
    assert!(fa.iter().all(|&f| !is_debris(f)));
    let kept: Vec<u32> = fb.iter().copied().filter(|&f| !is_debris(f)).collect();
    assert_eq!(fa, kept);
    assert!(fb.len() > fa.len());
}

#[test]
fn a_ghosted_run_reports_its_ghosts() {
    // the tiny wall with ghosts, one frame: the setup prints the ghosts a particle and the
    // ghost bonds a real one, and run.json keeps the count, bonds, gains, fallbacks and the
    // bonds left out as too short
    let tmp = tempfile::tempdir().unwrap();
    let scene = tiny_wall(tmp.path());
    let text = std::fs::read_to_string(&scene).unwrap();
    let ghosted = text.replace("[simulation]", "[simulation]\ncorrection = \"ghosts\"");
    assert_ne!(ghosted, text);
    std::fs::write(&scene, ghosted).unwrap();
    let out = tmp.path().join("out");
    let run = perifrac(&["run", s(&scene), "-o", s(&out), "--frames", "1"]);
    assert!(run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("ghost particles across the boundary") && err.contains("a real one"),
        "{err}"
    );
    let g = &manifest(&out)["correction"]["ghosts"];
    let (count, bonds) = (g["count"].as_u64().unwrap(), g["bonds"].as_u64().unwrap());
    // a slab two cells thick: every particle is within a horizon of a face, most of two
    assert!(count > 0 && bonds > count, "{g}");
    let largest = g["gain"]["max"].as_f64().unwrap();
    assert!(
        (1.0..=perifrac_physics::GHOST_GAIN_BOUND).contains(&largest),
        "{g}"
    );
    assert!(
        g["affine_fallbacks"].is_u64() && g["short_bonds"].is_u64(),
        "{g}"
    );
}
