//! Contact between a shell's own pieces (`self_contact.rs`).

use perifrac_physics::lanczos_frequency_of;
use perifrac_physics::math::{mat_vec, norm, rotation, sub};
use perifrac_physics::stable_step::{LANCZOS_ITERATIONS, LANCZOS_TOLERANCE};
use perifrac_shell::generate::{ellipsoid, sheet};
use perifrac_shell::*;

/// Steel, 1 mm thick: `Y h` = 2e8 N/m, so the default stiffness is 2e6 N/m a pair and the
/// band 0.5 mm.
fn steel() -> ShellMaterial {
    ShellMaterial::new(200e9, 0.3, 7800.0, 1e-3).unwrap()
}

const H: f64 = 1e-3;
const BAND: f64 = 0.5 * H;

/// Two `size` x `size` sheets of `n` x `n` quads in one mesh: the lower at z = 0, the upper at
/// z = `gap` shifted by `shift` in x and y.
fn two_sheets(size: f64, n: usize, gap: f64, shift: [f64; 2]) -> ShellMesh {
    let s = sheet(size, size, n, n).unwrap();
    let nv = s.vertices.len() as u32;
    let mut v = s.vertices.clone();
    v.extend(
        s.vertices
            .iter()
            .map(|p| [p[0] + shift[0], p[1] + shift[1], gap]),
    );
    let mut t = s.triangles.clone();
    t.extend(s.triangles.iter().map(|t| t.map(|i| i + nv)));
    ShellMesh::new(v, t).unwrap()
}

/// A shell of `mesh` with default self-contact.
fn shell_of(mesh: ShellMesh) -> ShellDynamics {
    let mut shell = ShellDynamics::new(ShellModel::new(mesh, steel()).unwrap()).unwrap();
    shell
        .set_self_contact(Some(ShellSelfContact::default()))
        .unwrap();
    shell
}

/// The upper sheet (vertices from `half` on) moved down to z = `gap`.
fn lowered(shell: &mut ShellDynamics, half: usize, gap: f64) {
    let mut x = shell.positions().to_vec();
    for p in &mut x[half..] {
        p[2] = gap;
    }
    shell.set_positions(&x).unwrap();
}

fn total_energy(s: &ShellDynamics) -> f64 {
    s.kinetic_energy() + s.elastic_energy() + s.gravity_energy() + s.self_contact_energy()
}

/// Small deterministic pseudo-random numbers in [-1, 1).
fn noise(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

#[test]
fn forces_are_the_negative_gradient_of_the_energy() {
    // Two 2 x 2 cm sheets of 4 x 4 quads, 1 cm apart at rest, brought to 0.15 mm and every
    // coordinate jittered by up to 0.1 mm: vertex-face pairs in face, edge and corner regions,
    // crossing edge pairs and nearly parallel ones (under the mollifier) all in the band.
    let mesh = two_sheets(0.02, 4, 0.01, [0.0013, 0.0021]);
    let half = mesh.num_vertices() / 2;
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
    let mut x = mesh.vertices().to_vec();
    let mut seed = 7;
    for (i, p) in x.iter_mut().enumerate() {
        if i >= half {
            p[2] = 1.5e-4;
        }
        for c in p.iter_mut() {
            *c += 1e-4 * noise(&mut seed);
        }
    }
    let mut f = vec![[0.0; 3]; x.len()];
    sc.add_forces(&mesh, &x, &mut f).unwrap();
    let st = sc.stats();
    assert!(st.vertex_face > 10 && st.edge_edge > 10, "{st:?}");
    let largest = f.iter().map(|v| norm(*v)).fold(0.0, f64::max);
    // Central differences with a step of 1e-9 m (1e-6 of h): the energy (~1 J) is C1 and
    // piecewise smooth, so truncation is O(step) at region boundaries and round-off is
    // ~1e-16 J / 1e-9 m = 1e-7 N against forces of ~1e2 N.
    let step = 1e-9;
    let mut worst: f64 = 0.0;
    for i in 0..x.len() {
        for c in 0..3 {
            let mut y = x.clone();
            y[i][c] += step;
            let up = sc.energy(&mesh, &y).unwrap();
            y[i][c] -= 2.0 * step;
            let down = sc.energy(&mesh, &y).unwrap();
            let fd = -(up - down) / (2.0 * step);
            worst = worst.max((fd - f[i][c]).abs());
        }
    }
    eprintln!(
        "{st:?}: largest force {largest:.3e} N, worst difference {worst:.3e} N ({:.2e})",
        worst / largest
    );
    // Measured 3e-9 of the largest force; 1e-6 leaves room for other platforms' round-off.
    assert!(worst < 1e-6 * largest, "{worst} against {largest}");
}

#[test]
fn a_vertex_over_a_face_is_pushed_off_it_alone() {
    // A horizontal triangle at z = 0 and a vertical one above it whose lowest vertex is
    // 0.2 mm over the first's interior, far (> band) from its edges: one vertex-face pair.
    let d = 2e-4;
    let v = vec![
        [0.0, 0.0, 0.0],
        [0.01, 0.0, 0.0],
        [0.0, 0.01, 0.0],
        [0.003, 0.002, d],
        [0.003, 0.006, 0.01],
        [0.003, -0.002, 0.01],
    ];
    let mesh = ShellMesh::new(v.clone(), vec![[0, 1, 2], [3, 4, 5]]).unwrap();
    // At rest the pair is already close: the inset would drop it, so the rest mesh is the
    // same with the upper triangle lifted 1 cm.
    let rest: Vec<_> = v
        .iter()
        .enumerate()
        .map(|(i, p)| [p[0], p[1], p[2] + if i >= 3 { 0.01 } else { 0.0 }])
        .collect();
    let mesh_rest = ShellMesh::new(rest, mesh.triangles().to_vec()).unwrap();
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
    let mut f = vec![[0.0; 3]; 6];
    let e = sc.add_forces(&mesh_rest, &v, &mut f).unwrap();
    let st = sc.stats();
    let k = sc.stiffness();
    assert_eq!(k, 0.01 * 200e9 * 1e-3);
    assert_eq!((st.vertex_face, st.edge_edge), (1, 0), "{st:?}");
    // Closed form: k (b - d) up on the vertex, shared by the face's corners by the
    // barycentric weights of (3, 2) mm: 0.5, 0.3, 0.2; energy k (b - d)^2 / 2.
    let push = k * (BAND - d);
    let want = [
        [0.0, 0.0, -0.5 * push],
        [0.0, 0.0, -0.3 * push],
        [0.0, 0.0, -0.2 * push],
        [0.0, 0.0, push],
        [0.0; 3],
        [0.0; 3],
    ];
    for (got, want) in f.iter().zip(&want) {
        // Round-off of the barycentric weights: a few ulps of the push (600 N).
        assert!(norm(sub(*got, *want)) < 1e-12 * push, "{got:?} {want:?}");
    }
    assert!((e - 0.5 * k * (BAND - d) * (BAND - d)).abs() < 1e-12 * e);
    assert!((st.deepest - (BAND - d)).abs() < 1e-15);
}

#[test]
fn crossing_edges_are_pushed_apart_alone() {
    // Two vertical triangles whose edges cross at right angles 0.2 mm apart: a hanging one
    // with its top edge along x at z = 0 and a standing one with its bottom edge along y at
    // z = 0.2 mm; every vertex is over 1 cm from the other triangle.
    let d = 2e-4;
    let v = vec![
        [-0.01, 0.0, 0.0],
        [0.01, 0.0, 0.0],
        [0.0, 0.0, -0.01],
        [0.0, -0.01, d],
        [0.0, 0.01, d],
        [0.0, 0.0, d + 0.01],
    ];
    let rest: Vec<_> = v
        .iter()
        .enumerate()
        .map(|(i, p)| [p[0], p[1], p[2] + if i >= 3 { 0.01 } else { 0.0 }])
        .collect();
    let mesh = ShellMesh::new(rest, vec![[0, 1, 2], [3, 5, 4]]).unwrap();
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
    let mut f = vec![[0.0; 3]; 6];
    let e = sc.add_forces(&mesh, &v, &mut f).unwrap();
    let st = sc.stats();
    assert_eq!((st.vertex_face, st.edge_edge), (0, 1), "{st:?}");
    // Closed form: k (b - d) apart along z, half to each end of each edge (they cross at
    // their midpoints); perpendicular edges are not mollified.
    let push = sc.stiffness() * (BAND - d);
    for (i, fi) in f.iter().enumerate() {
        let want = match i {
            0 | 1 => [0.0, 0.0, -0.5 * push],
            3 | 4 => [0.0, 0.0, 0.5 * push],
            _ => [0.0; 3],
        };
        assert!(norm(sub(*fi, want)) < 1e-12 * push, "{i}: {fi:?}");
    }
    assert!((e - 0.5 * sc.stiffness() * (BAND - d).powi(2)).abs() < 1e-12 * e);
}

#[test]
fn a_shell_at_rest_feels_nothing_even_where_neighbours_are_within_the_band() {
    // Edges of 0.5 mm against a band of 0.5 mm: every vertex is within the band of faces
    // around it. A flat sheet and a bent one at rest (current = rest) list no pair.
    let flat = sheet(0.01, 0.01, 20, 20).unwrap();
    let bent = perifrac_shell::generate::bent_sheet(0.01, 0.01, 20, 20, 0.004).unwrap();
    let egg = ellipsoid([0.022, 0.022, 0.029], 4).unwrap();
    for s in [flat, bent, egg] {
        let mesh = ShellMesh::new(s.vertices, s.triangles).unwrap();
        let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
        let mut f = vec![[0.0; 3]; mesh.num_vertices()];
        let e = sc.add_forces(&mesh, mesh.vertices(), &mut f).unwrap();
        assert_eq!(e, 0.0);
        assert_eq!(sc.stats().candidates, 0, "{:?}", sc.stats());
        assert!(f.iter().all(|v| *v == [0.0; 3]));
    }
}

#[test]
fn neighbours_in_the_mesh_do_not_repel_even_folded_onto_each_other() {
    // A 5 mm square of two triangles folded about its diagonal to within 2.3 degrees of flat
    // on itself: the folded corner comes 0.14 mm over the other triangle, but every pair is
    // a mesh neighbour (a vertex of one is, or shares an edge with, a vertex of the other),
    // so nothing repels; the same square cut along the diagonal (its ends doubled) repels.
    let s = 0.005;
    let square = vec![[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, s, 0.0], [0.0, s, 0.0]];
    let turn = rotation(
        [0.5f64.sqrt(), 0.5f64.sqrt(), 0.0],
        (180.0f64 - 2.3).to_radians(),
    );
    let fold = |p: &[f64; 3]| {
        if p[0] < p[1] - 1e-12 {
            mat_vec(&turn, *p)
        } else {
            *p
        }
    };
    let mesh = ShellMesh::new(square.clone(), vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    let x: Vec<_> = square.iter().map(fold).collect();
    assert!(
        x[3][2].abs() < BAND && x[3][2].abs() > 0.1 * BAND,
        "{:?}",
        x[3]
    );
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
    let mut f = vec![[0.0; 3]; x.len()];
    assert_eq!(sc.add_forces(&mesh, &x, &mut f).unwrap(), 0.0);
    assert_eq!(sc.stats().candidates, 0);
    let mut v = square.clone();
    v.push(square[0]);
    v.push(square[2]);
    let cut = ShellMesh::new(v.clone(), vec![[0, 1, 2], [4, 5, 3]]).unwrap();
    let y: Vec<_> = v.iter().map(fold).collect();
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
    let mut f = vec![[0.0; 3]; y.len()];
    let e = sc.add_forces(&cut, &y, &mut f).unwrap();
    assert!(e > 0.0 && sc.stats().vertex_face > 0, "{:?}", sc.stats());
}

/// Two 2 x 1 cm sheets side by side, abutting along x = 2 cm with their own (coincident)
/// vertices there: a crack the moment it opens.
fn abutting() -> ShellMesh {
    let a = sheet(0.02, 0.01, 10, 5).unwrap();
    let nv = a.vertices.len() as u32;
    let mut v = a.vertices.clone();
    v.extend(a.vertices.iter().map(|p| [p[0] + 0.02, p[1], 0.0]));
    let mut t = a.triangles.clone();
    t.extend(a.triangles.iter().map(|t| t.map(|i| i + nv)));
    ShellMesh::new(v, t).unwrap()
}

#[test]
fn the_sides_of_a_fresh_crack_are_not_pushed_apart_until_they_overlap() {
    let mesh = abutting();
    let half = mesh.num_vertices() / 2;
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel()).unwrap();
    let mut f = vec![[0.0; 3]; mesh.num_vertices()];
    // Coincident vertices (distance 0) across the crack, 11 of them: no pair, no force.
    let x = mesh.vertices().to_vec();
    assert_eq!(sc.add_forces(&mesh, &x, &mut f).unwrap(), 0.0);
    assert_eq!(sc.stats().candidates, 0);
    // The right piece slid 0.8 mm under... over the left one (0.2 mm up), still within the
    // inset (1 mm of material): no force. At 3 mm of overlap the far pairs repel.
    let slide = |dx: f64| -> Vec<[f64; 3]> {
        x.iter()
            .enumerate()
            .map(|(i, p)| {
                if i >= half {
                    [p[0] - dx, p[1], 2e-4]
                } else {
                    *p
                }
            })
            .collect()
    };
    assert_eq!(sc.add_forces(&mesh, &slide(8e-4), &mut f).unwrap(), 0.0);
    let e = sc.add_forces(&mesh, &slide(3e-3), &mut f).unwrap();
    assert!(e > 0.0, "{:?}", sc.stats());
    // The pieces are pushed apart vertically (the right one up).
    let up: f64 = f[half..].iter().map(|v| v[2]).sum();
    assert!(up > 0.0);
}

#[test]
fn a_real_crack_opens_without_self_contact_force() {
    // The fracture tests' pulled glass sheet (its notch a missing vertex) with self-contact
    // on: every round that opens a crack leaves coincident vertex copies that are not mesh
    // neighbours, and self-contact adds no force between them.
    let s = sheet(0.1, 0.05, 20, 10).unwrap();
    let mesh = ShellMesh::new(s.vertices.clone(), s.triangles).unwrap();
    let glass = ShellMaterial::new(70e9, 0.22, 2500.0, 1e-3).unwrap();
    let model = ShellModel::new(mesh, glass)
        .unwrap()
        .with_fracture(ShellFracture::new(1e-3, 1e-3, 0.25, 1.0).unwrap());
    let mut shell = ShellDynamics::new(model).unwrap();
    shell
        .set_self_contact(Some(ShellSelfContact::default()))
        .unwrap();
    shell.set_damping(2e4).unwrap();
    for (i, p) in s.vertices.iter().enumerate() {
        if p[0] < 1e-9 {
            shell.drive(i, [-0.05, 0.0, 0.0]);
        } else if p[0] > 0.1 - 1e-9 {
            shell.drive(i, [0.05, 0.0, 0.0]);
        }
    }
    let n0 = shell.positions().len();
    let dt = 0.5 * shell.stable_step().unwrap();
    let mut opened = 0;
    for _ in 0..40_000 {
        shell.step(dt).unwrap();
        let r = shell.fracture().unwrap();
        if r.changed && shell.positions().len() > n0 {
            opened += 1;
            // Right after the round: copies sit on their originals.
            assert_eq!(shell.self_contact_energy(), 0.0);
            assert_eq!(shell.self_contact_stats().vertex_face, 0);
        }
        if pieces(shell.model().mesh()).iter().max() >= Some(&1) {
            break;
        }
    }
    let x = shell.positions();
    let coincident = (n0..x.len())
        .filter(|&i| (0..n0).any(|j| norm(sub(x[i], x[j])) < 1e-4 * H))
        .count();
    eprintln!(
        "{opened} rounds opened cracks, {} vertices added, {coincident} still within 1e-4 h of an original; {:?}",
        x.len() - n0,
        shell.self_contact_stats()
    );
    assert!(opened > 0);
    assert_eq!(shell.self_contact_energy(), 0.0);
}

/// The stable step with self-contact (Lanczos on elastic plus contact forces) against the
/// elastic one, two `n` x `n` sheets of 4 cm pressed to half the band.
fn step_ratio(n: usize, shift: [f64; 2]) -> f64 {
    let mesh = two_sheets(0.04, n, 0.01, shift);
    let half = mesh.num_vertices() / 2;
    let mut shell = shell_of(mesh);
    let elastic = shell.stable_step().unwrap();
    lowered(&mut shell, half, 0.5 * BAND);
    assert!(shell.self_contact_stats().vertex_face > 0);
    let x = shell.positions().to_vec();
    let masses = shell.model().masses().to_vec();
    let mut model = shell.model().clone();
    let mesh = model.mesh().clone();
    let mut sc = shell.self_contact().unwrap().clone();
    let est = lanczos_frequency_of(
        &masses,
        &x,
        0.04 / n as f64,
        LANCZOS_ITERATIONS,
        LANCZOS_TOLERANCE,
        &mut |y, f| {
            let _ = model.frozen_forces(y, f);
            let _ = sc.add_forces(&mesh, y, f);
        },
        None,
    );
    2.0 / est.omega_max / elastic
}

#[test]
fn the_default_stiffness_keeps_the_elastic_step_stable() {
    // Edges of 5, 2.5, 1.25 and 0.625 h; sheets aligned (each vertex over another, the most
    // pairs a vertex can have) and shifted. Measured: 1.000, 0.998, 0.992, 0.916 aligned,
    // 0.988 shifted at 1.25 h. Scenes step at 0.5 to 0.8 of the elastic step.
    let mut worst: f64 = 1.0;
    for (n, shift) in [
        (8, [0.0, 0.0]),
        (16, [0.0, 0.0]),
        (32, [0.0, 0.0]),
        (32, [3e-4, 1e-4]),
        (64, [0.0, 0.0]),
    ] {
        let r = step_ratio(n, shift);
        eprintln!("{n} x {n}, shift {shift:?}: stable step with contact / elastic {r:.3}");
        worst = worst.min(r);
        if n <= 32 {
            assert!(r > 0.97, "{n}: {r}");
        }
    }
    assert!(worst > 0.85, "{worst}");
}

#[test]
fn a_sheet_dropped_on_a_pinned_one_stays_above_it() {
    // A 4 x 4 cm steel sheet of 8 x 8 quads thrown at 1 m/s from 3 mm above a pinned one
    // (shifted by a fraction of a cell), under gravity, undamped, at half the elastic step.
    let mesh = two_sheets(0.04, 8, 3e-3, [1.1e-3, 0.7e-3]);
    let half = mesh.num_vertices() / 2;
    let mut shell = shell_of(mesh);
    for i in 0..half {
        shell.pin(i);
    }
    for v in &mut shell.velocities_mut()[half..] {
        *v = [0.0, 0.0, -1.0];
    }
    shell.set_gravity([0.0, 0.0, -9.81]);
    let dt = 0.5 * shell.stable_step().unwrap();
    // Bound: undamped, the penalty energy of the deepest pair cannot exceed the upper
    // sheet's kinetic energy plus the work of gravity down to z = 0, so
    // band - d <= sqrt(2 (M v^2 / 2 + M g z0) / k); 5% more (10% more energy) for the
    // integrator's energy error (measured 4.2e-3 of the energy in the collision test below).
    // Measured: 4.5e-6 m deep against a bound of 8.5e-5 m (many pairs share the load).
    let m: f64 = shell.model().masses()[half..].iter().sum();
    let k = shell.self_contact().unwrap().stiffness();
    let bound = 1.05 * (2.0 * (0.5 * m + m * 9.81 * 3e-3) / k).sqrt();
    let (mut deepest, mut lowest) = (0.0f64, f64::INFINITY);
    let mut touched = false;
    for _ in 0..(0.01 / dt) as usize {
        shell.step(dt).unwrap();
        let st = shell.self_contact_stats();
        touched |= st.vertex_face > 0;
        deepest = deepest.max(st.deepest);
        lowest = shell.positions()[half..]
            .iter()
            .map(|p| p[2])
            .fold(lowest, f64::min);
    }
    let rising = shell.velocities()[half..].iter().map(|v| v[2]).sum::<f64>() > 0.0;
    eprintln!(
        "deepest {deepest:.3e} m into the band (bound {bound:.3e}), lowest vertex {lowest:.3e} m, rising after: {rising}"
    );
    assert!(touched && rising);
    assert!(deepest < bound, "{deepest} {bound}");
    // Never through: every vertex of the upper sheet stays above the pinned plane by the
    // band less the bound.
    assert!(lowest > BAND - bound, "{lowest}");
}

/// Two free 4 x 4 cm sheets of `n` x `n` quads, 1 cm apart at rest, placed `gap` apart and
/// closing at 1 m/s.
fn colliding(n: usize, gap: f64) -> (ShellDynamics, usize) {
    let mesh = two_sheets(0.04, n, 0.01, [1.1e-3, 0.7e-3]);
    let half = mesh.num_vertices() / 2;
    let mut shell = shell_of(mesh);
    lowered(&mut shell, half, gap);
    for (i, v) in shell.velocities_mut().iter_mut().enumerate() {
        *v = [0.0, 0.0, if i < half { 0.5 } else { -0.5 }];
    }
    (shell, half)
}

#[test]
fn energy_is_kept_in_an_elastic_collision_of_two_sheets() {
    let (mut shell, half) = colliding(8, 1e-3);
    let dt = 0.5 * shell.stable_step().unwrap();
    let e0 = total_energy(&shell);
    let (mut drift, mut peak_contact) = (0.0f64, 0.0f64);
    for _ in 0..(3e-3 / dt) as usize {
        shell.step(dt).unwrap();
        drift = drift.max((total_energy(&shell) - e0).abs());
        peak_contact = peak_contact.max(shell.self_contact_energy());
    }
    let after = (total_energy(&shell) - e0).abs();
    assert_eq!(shell.self_contact_energy(), 0.0);
    let vz_upper: f64 = shell.velocities()[half..].iter().map(|v| v[2]).sum::<f64>() / half as f64;
    eprintln!(
        "energy {e0:.4e} J, largest drift {drift:.3e} J ({:.2e}), after the bounce {after:.3e} J ({:.2e}), peak penalty energy {peak_contact:.3e} J, upper sheet's mean vz after {vz_upper:.3} m/s",
        drift / e0,
        after / e0,
    );
    // They bounced (the upper sheet moves up again) and the penalty stored most of the
    // kinetic energy at the turn.
    assert!(vz_upper > 0.0);
    assert!(peak_contact > 0.1 * e0);
    // Velocity Verlet's error, which falls with the step squared: measured after the bounce
    // 4.2e-3 of the energy at half the stable step, 8.3e-4 at a quarter, 2.3e-4 at an eighth
    // (the force's slope jumps where a pair enters the band); 6.3e-3 at most during it.
    // Twice the measured figures.
    assert!(after < 8.4e-3 * e0, "{after} {e0}");
    assert!(drift < 1.3e-2 * e0, "{drift} {e0}");
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    // 24 x 24 quads a sheet: 1,250 vertices (5 build tasks) and thousands of pairs (several
    // force tasks) once they touch.
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (mut shell, _) = colliding(24, 5.1e-4);
            let dt = 0.5 * shell.stable_step().unwrap();
            let (mut pairs, mut peak) = (0, 0.0f64);
            for _ in 0..600 {
                shell.step(dt).unwrap();
                let st = shell.self_contact_stats();
                pairs = pairs.max(st.vertex_face + st.edge_edge);
                peak = peak.max(st.energy);
            }
            (shell.positions().to_vec(), peak, pairs)
        })
    };
    let (x1, e1, p1) = run(1);
    let (x2, e2, p2) = run(2);
    eprintln!("{p1} pairs in the band at most, penalty energy up to {e1:.3e} J");
    assert!(p1 > 2048 && e1 > 0.0, "{p1} {e1}");
    assert_eq!(p1, p2);
    assert_eq!(e1.to_bits(), e2.to_bits());
    assert!(x1
        .iter()
        .zip(&x2)
        .all(|(a, b)| a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits())));
}

#[test]
fn settings_out_of_range_are_refused() {
    let d = ShellSelfContact::default();
    for bad in [
        ShellSelfContact { band: 0.0, ..d },
        ShellSelfContact {
            stiffness: f64::NAN,
            ..d
        },
        ShellSelfContact { skin: -1.0, ..d },
        ShellSelfContact { inset: 0.4, ..d },
    ] {
        assert!(matches!(
            SelfContact::new(bad, &steel()),
            Err(ShellError::BadSetting { .. })
        ));
    }
    let mesh = two_sheets(0.01, 2, 0.01, [0.0; 2]);
    let mut sc = SelfContact::new(d, &steel()).unwrap();
    let mut f = vec![[0.0; 3]; 3];
    assert!(matches!(
        sc.add_forces(&mesh, mesh.vertices(), &mut f),
        Err(ShellError::LengthMismatch { .. })
    ));
}

#[test]
fn cost_on_the_egg() {
    // The benchmark's egg (5,120 triangles, 3.5e-4 m thick) falling at 3 m/s and spinning at
    // 100 rad/s about x (rim speed 2.2 m/s, so the list is rebuilt now and then), 400 steps
    // with and without self-contact: what a scene that has it on pays when nothing touches.
    let s = ellipsoid([0.022, 0.022, 0.029], 4).unwrap();
    let mat = ShellMaterial::new(30e9, 0.3, 2000.0, 3.5e-4).unwrap();
    let steps = 400;
    let time = |on: bool| {
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles.clone()).unwrap();
        let mut shell = ShellDynamics::new(ShellModel::new(mesh, mat).unwrap()).unwrap();
        if on {
            shell
                .set_self_contact(Some(ShellSelfContact::default()))
                .unwrap();
        }
        shell.set_gravity([0.0, 0.0, -9.81]);
        let x = shell.positions().to_vec();
        for (v, p) in shell.velocities_mut().iter_mut().zip(&x) {
            *v = [0.0, -100.0 * p[2], 100.0 * p[1] - 3.0];
        }
        let dt = 0.5 * shell.stable_step().unwrap();
        let start = std::time::Instant::now();
        for _ in 0..steps {
            shell.step(dt).unwrap();
        }
        (start.elapsed().as_secs_f64(), shell.self_contact_stats())
    };
    let (off, _) = time(false);
    let (on, st) = time(true);
    eprintln!(
        "egg: {:.1} us a step without self-contact, {:.1} us with; self-contact {:.1} us a step on average ({:.1}% of the step), {} list builds in {} evaluations, {} candidates",
        off / steps as f64 * 1e6,
        on / steps as f64 * 1e6,
        st.total_seconds / st.evaluations as f64 * 1e6,
        100.0 * st.total_seconds / on,
        st.builds,
        st.evaluations,
        st.candidates,
    );
    assert_eq!(st.candidates, 0);
    assert!(st.builds > 1);
}
