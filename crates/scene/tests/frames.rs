//! What a frame carries for renderers: vertex velocities that are the ones advection moves the
//! mesh with (so motion blur shows the motion), and fragment ids that stay with a fragment from
//! the frame it separates to the end.

use std::path::Path;

use perifrac_io::{read_ply_frame, read_ply_points};
use perifrac_scene::{run, Scene, Setup, Silent};

/// A small glass slab shot through by a steel ball: it breaks within a few hundred steps.
const SHOT: &str = r#"
[mesh]
primitive = "box"
size = [0.2, 0.2, 0.02]
cells = [10, 10, 1]

[[material]]
bulk_modulus = 3.3e10
shear_modulus = 2.0e10
density = 2200.0
s_crit = 0.0005

[simulation]
duration = 0.002

[[ball]]
center = [0.1, 0.1, 0.05]
radius = 0.02
velocity = [0.0, 0.0, -75.0]
density = 7800.0

[output]
frames = 6
povray = false
"#;

fn setup() -> Setup {
    let scene = Scene::parse(SHOT, Path::new("shot.toml")).unwrap();
    Setup::new(&scene, None).unwrap()
}

#[test]
fn frame_velocities_are_the_advection_velocities() {
    let mut setup = setup();
    let driver = &mut setup.driver;
    let dt = driver.solver().dt();
    let mut checked = 0;
    for step in 0..400 {
        let before = driver.mesh().positions().to_vec();
        driver.step().unwrap();
        let mesh = driver.mesh();
        let v = mesh.vertex_velocities(driver.masses(), driver.solver().velocities());
        // Vertex copies made in this step start where their original was: compare the
        // vertices that existed before it.
        for (k, (x0, x1)) in before.iter().zip(mesh.positions()).enumerate() {
            for i in 0..3 {
                // x1 = x0 + dt v up to the rounding of two orders of the same products.
                let moved = (x1[i] - x0[i]) / dt;
                let tolerance =
                    1e-9 * (1.0 + v[k][i].abs()) + 4.0 * f64::EPSILON * x1[i].abs() / dt;
                assert!(
                    (moved - v[k][i]).abs() <= tolerance,
                    "step {step} vertex {k}: moved at {moved}, velocity {}",
                    v[k][i]
                );
            }
        }
        checked += before.len();
    }
    assert!(checked > 0);
    assert!(setup.driver.broken_bonds() > 0, "the slab should break");
}

#[test]
fn fragments_keep_their_ids_from_frame_to_frame() {
    let dir = tempfile::tempdir().unwrap();
    let summary = run(setup(), dir.path(), &mut Silent).unwrap();
    assert!(summary.fragments > 2, "{} fragments", summary.fragments);
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("run.json")).unwrap())
            .unwrap();
    let births = manifest["fragments"].as_array().unwrap();
    let mut previous: Option<Vec<u32>> = None;
    for (k, frame) in manifest["frames"].as_array().unwrap().iter().enumerate() {
        let particles =
            read_ply_points(&dir.path().join(frame["particles"].as_str().unwrap())).unwrap();
        let ids: Vec<u32> = particles
            .scalar("fragment")
            .unwrap()
            .iter()
            .map(|&f| f as u32)
            .collect();
        let surface = read_ply_frame(&dir.path().join(frame["surface"].as_str().unwrap())).unwrap();
        let mut face_ids = surface.fragment.unwrap();
        // The surface with the debris points and the particles name the same fragments, as many
        // as run.json counts.
        if let Some(debris) = frame["debris"]["path"].as_str() {
            let debris = read_ply_points(&dir.path().join(debris)).unwrap();
            face_ids.extend(debris.scalar("fragment").unwrap().iter().map(|&f| f as u32));
        }
        let mut a: Vec<u32> = ids.clone();
        a.sort_unstable();
        a.dedup();
        let mut b = face_ids.clone();
        b.sort_unstable();
        b.dedup();
        assert_eq!(a, b, "frame {k}");
        assert_eq!(a.len() as u64, frame["fragments"].as_u64().unwrap());
        for &id in &a {
            let birth = &births[id as usize];
            assert_eq!(birth["id"].as_u64(), Some(u64::from(id)));
            assert!(birth["frame"].as_u64().unwrap() <= k as u64);
        }
        if let Some(prev) = &previous {
            // An id seen in both frames names the same tets, or a part of them never:
            // it is the same fragment, whole.
            for &id in &a {
                let now: Vec<usize> = (0..ids.len()).filter(|&t| ids[t] == id).collect();
                let then: Vec<usize> = (0..prev.len()).filter(|&t| prev[t] == id).collect();
                if !then.is_empty() {
                    assert_eq!(now, then, "frame {k}: fragment {id} changed its tets");
                } else {
                    // New: born now, from the fragment its tets were in before.
                    let birth = &births[id as usize];
                    assert_eq!(birth["frame"].as_u64(), Some(k as u64));
                    let parent = birth["parent"].as_u64().unwrap() as u32;
                    assert!(now.iter().all(|&t| prev[t] == parent));
                }
            }
        }
        previous = Some(ids);
    }
}

/// Every piece of every frame, welded by `vertex_id` and grouped by `fragment`, as a surface.
fn frame_pieces(path: &Path) -> Vec<perifrac_topology::Surface> {
    let frame = read_ply_frame(path).unwrap();
    let ids = frame.vertex_ids.unwrap();
    let fragment = frame.fragment.unwrap();
    let n = ids.iter().max().map_or(0, |&m| m as usize + 1);
    let mut welded = vec![[0.0; 3]; n];
    for (p, &id) in frame.vertices.iter().zip(&ids) {
        welded[id as usize] = p.map(f64::from);
    }
    let mut by: std::collections::BTreeMap<u32, perifrac_topology::Surface> = Default::default();
    for (f, face) in frame.faces.iter().enumerate() {
        let s = by
            .entry(fragment[f])
            .or_insert_with(|| perifrac_topology::Surface {
                vertices: welded.clone(),
                ..Default::default()
            });
        s.faces.push(face.map(|v| ids[v as usize]));
    }
    by.into_values().collect()
}

/// Random impacts on a small slab (ball position, speed, direction and size drawn from a
/// seeded generator), run for 8 ms so that debris spins after it breaks off: at every frame
/// every piece written is a closed 2-manifold enclosing a positive volume. Without placing
/// small pieces rigidly the first case already writes an inside-out piece at frame 2.
#[test]
fn every_piece_of_random_impacts_is_closed_manifold_and_positive() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut unit = || {
        // xorshift64*: a fixed sequence, so the cases are the same on every run.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pieces_checked = 0;
    for case in 0..3 {
        let (x, y) = (0.04 + 0.12 * unit(), 0.04 + 0.12 * unit());
        let speed = 40.0 + 80.0 * unit();
        let tilt = 0.6 * (unit() - 0.5);
        let radius = 0.01 + 0.02 * unit();
        let text = SHOT
            .replace(
                "center = [0.1, 0.1, 0.05]",
                &format!("center = [{x}, {y}, 0.05]"),
            )
            .replace(
                "velocity = [0.0, 0.0, -75.0]",
                &format!("velocity = [{}, 0.0, {}]", speed * tilt, -speed),
            )
            .replace("radius = 0.02", &format!("radius = {radius}"))
            // Long enough for debris to spin for a while after it breaks off.
            .replace("duration = 0.002", "duration = 0.008");
        let scene = Scene::parse(&text, Path::new("shot.toml")).unwrap();
        let dir = tempfile::tempdir().unwrap();
        run(Setup::new(&scene, None).unwrap(), dir.path(), &mut Silent).unwrap();
        for k in 0..=6 {
            let path = dir.path().join(format!("frames/surface_{k:04}.ply"));
            for (p, s) in frame_pieces(&path).iter().enumerate() {
                assert!(s.is_closed_manifold(), "case {case} frame {k} piece {p}");
                let v = s.signed_volume();
                assert!(v > 0.0, "case {case} frame {k} piece {p}: volume {v}");
                pieces_checked += 1;
            }
        }
    }
    assert!(pieces_checked > 100, "{pieces_checked}");
}
