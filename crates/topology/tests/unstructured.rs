//! The unstructured box mesher: Delaunay tetrahedralisation (empty spheres, hull coverage,
//! degenerate input), the box meshes it makes (orientation, volume, boundary, quality,
//! determinism) and their isotropy against the Kuhn lattice.

use std::collections::HashMap;

use perifrac_topology::faces::{signed_volume, FACE_CORNERS};
use perifrac_topology::mesher::delaunay::{delaunay, in_sphere, orient, DelaunayError};
use perifrac_topology::mesher::scatter::{scatter_box, Placement, Rng};
use perifrac_topology::mesher::unstructured::{unstructured_box, UnstructuredMesh};
use perifrac_topology::mesher::{unstructured_box_data, UnstructuredError};
use perifrac_topology::{dihedral_angles_deg, primitives, TetMesh};

/// Faces (corners as they appear in a tet, outward) with the number of tets holding each.
fn faces(tets: &[[u32; 4]]) -> HashMap<[u32; 3], ([u32; 3], usize)> {
    let mut map: HashMap<[u32; 3], ([u32; 3], usize)> = HashMap::new();
    for tet in tets {
        for corners in FACE_CORNERS {
            let face = corners.map(|k| tet[k]);
            let mut key = face;
            key.sort_unstable();
            map.entry(key).or_insert((face, 0)).1 += 1;
        }
    }
    map
}

fn total_volume(points: &[[f64; 3]], tets: &[[u32; 4]]) -> f64 {
    tets.iter()
        .map(|t| {
            let [a, b, c, d] = t.map(|v| points[v as usize]);
            signed_volume(a, b, c, d)
        })
        .sum()
}

/// Checks that `tets` triangulate the convex hull of `points`: every tet exactly positive,
/// every face in at most two tets, every boundary face with all points on or behind it (so the
/// boundary is the hull's), and the tets' volume equal to the volume the boundary encloses
/// (so they neither overlap nor leave holes). Returns the volume.
fn assert_hull_triangulation(points: &[[f64; 3]], tets: &[[u32; 4]]) -> f64 {
    for t in tets {
        let [a, b, c, d] = t.map(|v| points[v as usize]);
        assert!(orient(a, b, c, d) > 0.0, "tet {t:?} is not positive");
    }
    let mut enclosed = 0.0;
    for (face, count) in faces(tets).into_values() {
        assert!(count <= 2, "face {face:?} is in {count} tets");
        if count == 1 {
            let [a, b, c] = face.map(|v| points[v as usize]);
            // Outward face of a positive tet: every point is on its negative side or on it.
            for (i, p) in points.iter().enumerate() {
                assert!(
                    orient(*p, a, b, c) >= 0.0,
                    "point {i} lies outside boundary face {face:?}"
                );
            }
            enclosed += signed_volume([0.0; 3], a, b, c);
        }
    }
    let volume = total_volume(points, tets);
    assert!(
        (volume - enclosed).abs() <= 1e-12 * enclosed.abs().max(1.0),
        "tets hold {volume}, their boundary encloses {enclosed}"
    );
    volume
}

/// Brute force: no point lies strictly inside a tet's circumsphere.
fn assert_empty_spheres(points: &[[f64; 3]], tets: &[[u32; 4]]) {
    for t in tets {
        let [a, b, c, d] = t.map(|v| points[v as usize]);
        for (i, &p) in points.iter().enumerate() {
            if !t.contains(&(i as u32)) {
                assert!(
                    in_sphere(a, b, c, d, p) <= 0.0,
                    "point {i} is inside the circumsphere of {t:?}"
                );
            }
        }
    }
}

fn random_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| [rng.uniform(), rng.uniform(), rng.uniform()])
        .collect()
}

#[test]
fn delaunay_of_random_points_has_empty_spheres_and_fills_the_hull() {
    for seed in 1..=3 {
        let points = random_points(400, seed);
        let tets = delaunay(&points).unwrap();
        assert_empty_spheres(&points, &tets);
        assert_hull_triangulation(&points, &tets);
        // Random points are in general position: every one is a vertex.
        let mut used = vec![false; points.len()];
        tets.iter().flatten().for_each(|&v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u));
    }
    // With the unit cube's corners added the hull is the cube.
    let mut points = random_points(300, 9);
    for corner in 0..8 {
        points.push([0, 1, 2].map(|d| (corner >> d & 1) as f64));
    }
    let tets = delaunay(&points).unwrap();
    assert_empty_spheres(&points, &tets);
    let volume = assert_hull_triangulation(&points, &tets);
    assert!((volume - 1.0).abs() < 1e-12, "volume {volume}");
}

#[test]
fn delaunay_of_degenerate_points_is_a_valid_triangulation() {
    // A 4 x 4 x 4 grid: every face plane holds 16 points, every cell's corners are cospherical.
    let grid: Vec<[f64; 3]> = (0..64)
        .map(|i| [(i % 4) as f64, (i / 4 % 4) as f64, (i / 16) as f64])
        .collect();
    let tets = delaunay(&grid).unwrap();
    assert_empty_spheres(&grid, &tets);
    let volume = assert_hull_triangulation(&grid, &tets);
    assert!((volume - 27.0).abs() < 1e-12, "grid volume {volume}");
    let mut used = vec![false; grid.len()];
    tets.iter().flatten().for_each(|&v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u), "a grid point is left out");

    // All 30 integer points on the sphere of radius 5: every in-sphere test is a tie.
    let mut sphere = Vec::new();
    for x in -5i32..=5 {
        for y in -5i32..=5 {
            for z in -5i32..=5 {
                if x * x + y * y + z * z == 25 {
                    sphere.push([x as f64, y as f64, z as f64]);
                }
            }
        }
    }
    assert_eq!(sphere.len(), 30);
    let tets = delaunay(&sphere).unwrap();
    assert_empty_spheres(&sphere, &tets);
    assert_hull_triangulation(&sphere, &tets);
    // The same input gives the same tets.
    assert_eq!(delaunay(&sphere).unwrap(), tets);

    // A repeated point is left out; flat, short and non-finite input is refused.
    let mut repeated = grid.clone();
    repeated.push(grid[21]);
    let tets = delaunay(&repeated).unwrap();
    assert!(!tets.iter().flatten().any(|&v| v == 64));
    assert!((total_volume(&repeated, &tets) - 27.0).abs() < 1e-12);
    let flat: Vec<[f64; 3]> = (0..16)
        .map(|i| [(i % 4) as f64, (i / 4) as f64, 0.0])
        .collect();
    assert_eq!(delaunay(&flat), Err(DelaunayError::Flat { count: 16 }));
    assert_eq!(
        delaunay(&grid[..3]),
        Err(DelaunayError::TooFewPoints { count: 3 })
    );
    let mut bad = grid.clone();
    bad[5][1] = f64::NAN;
    assert!(matches!(
        delaunay(&bad),
        Err(DelaunayError::NonFinite { index: 5, .. })
    ));
}

#[test]
fn scattered_points_keep_their_places_and_spacing() {
    let (min, max, h) = ([-1.0, 0.5, 2.0], [3.0, 2.5, 3.0], 0.4);
    let s = scatter_box(min, max, h, 3).unwrap();
    let on = |p: [f64; 3], d: usize| p[d] == min[d] || p[d] == max[d];
    for (p, place) in s.points.iter().zip(&s.placement) {
        let count = (0..3).filter(|&d| on(*p, d)).count();
        match *place {
            Placement::Corner => assert_eq!(count, 3),
            Placement::Edge { axis } => assert!(count == 2 && !on(*p, axis)),
            Placement::Face { axis } => assert!(count == 1 && on(*p, axis)),
            Placement::Interior => assert_eq!(count, 0),
        }
        assert!((0..3).all(|d| p[d] >= min[d] && p[d] <= max[d]));
    }
    // Poisson-disk: no two points closer than 0.75 h (brute force).
    for (i, p) in s.points.iter().enumerate() {
        for q in &s.points[i + 1..] {
            let d2: f64 = (0..3).map(|d| (p[d] - q[d]).powi(2)).sum();
            assert!(d2 >= (0.75 * h) * (0.75 * h) * (1.0 - 1e-12));
        }
    }
    assert_eq!(scatter_box(min, max, h, 3).unwrap(), s);
    assert_ne!(scatter_box(min, max, h, 4).unwrap().points, s.points);
    assert!(matches!(
        scatter_box(min, max, 0.0, 3),
        Err(UnstructuredError::BadSpacing { .. })
    ));
}

/// Checks a box mesh: positive tets, the box's volume, boundary faces on the box's planes,
/// accepted by `TetMesh::new`, tet count near the lattice's, the report's angles, the quality
/// bounds.
fn assert_box_mesh(min: [f64; 3], max: [f64; 3], cells: [usize; 3], m: &UnstructuredMesh) {
    let (v, t) = (&m.vertices, &m.tets);
    for tet in t {
        let [a, b, c, d] = tet.map(|i| v[i as usize]);
        assert!(orient(a, b, c, d) > 0.0 && signed_volume(a, b, c, d) > 0.0);
    }
    let box_volume: f64 = (0..3).map(|d| max[d] - min[d]).product();
    let volume = total_volume(v, t);
    assert!(
        (volume - box_volume).abs() <= 1e-9 * box_volume,
        "volume {volume} of a box of {box_volume}"
    );
    let mut boundary = 0;
    for (face, count) in faces(t).into_values() {
        assert!(count <= 2);
        if count == 1 {
            boundary += 1;
            let p = face.map(|i| v[i as usize]);
            let on_plane = (0..3)
                .any(|d| p.iter().all(|q| q[d] == min[d]) || p.iter().all(|q| q[d] == max[d]));
            assert!(on_plane, "boundary face {face:?} at {p:?} is off the box");
        }
    }
    assert!(boundary > 0);
    let (mesh, report) = TetMesh::new(v.clone(), t.clone()).unwrap();
    assert_eq!(report.inverted_fixed, 0);
    assert_eq!(mesh.num_tets(), t.len());
    // Within 15% of the lattice's count; measured 0.90 to 1.07 over seeds 1 to 10 on the
    // cases below (the smallest boxes spread most).
    let lattice = 6 * cells[0] * cells[1] * cells[2];
    let ratio = t.len() as f64 / lattice as f64;
    assert!((0.85..=1.15).contains(&ratio), "{cells:?}: ratio {ratio}");
    let mut lo = 180.0f64;
    let mut hi = 0.0f64;
    for tet in t {
        for a in dihedral_angles_deg(tet.map(|i| v[i as usize])) {
            lo = lo.min(a);
            hi = hi.max(a);
        }
    }
    assert_eq!(
        (lo, hi),
        (m.report.min_dihedral_deg, m.report.max_dihedral_deg)
    );
    // Measured over seeds 1 to 10 for the cubic-cell cases below: smallest 20.6 degrees
    // (16 x 16 x 16), largest 158.4 (8 x 8 x 8); 15 and 165 leave about 5 degrees of margin.
    assert!(lo > 15.0, "{cells:?}: smallest dihedral {lo}");
    assert!(hi < 165.0, "{cells:?}: largest dihedral {hi}");
    // Measured smallest tet volume over seeds 1 to 10: 0.012 of a cell's volume (16 x 16 x 16),
    // 0.03 or more for the cases below.
    let cell_volume = box_volume / lattice as f64 * 6.0;
    assert!(m.report.min_volume > 0.005 * cell_volume);
}

#[test]
fn unstructured_boxes_are_valid_conforming_and_good() {
    let cases: [([f64; 3], [f64; 3], [usize; 3]); 5] = [
        ([0.0; 3], [8.0; 3], [8, 8, 8]),
        ([0.0; 3], [24.0, 24.0, 3.0], [24, 24, 3]),
        ([0.0; 3], [10.0, 10.0, 1.0], [10, 10, 1]),
        ([0.0; 3], [4.0, 4.0, 1.0], [4, 4, 1]),
        // Off the origin, small cells (0.25), not a round number anywhere.
        ([-1.0, 2.0, 0.5], [1.0, 3.0, 0.75], [8, 4, 1]),
    ];
    for (min, max, cells) in cases {
        let m = unstructured_box(min, max, cells, 1).unwrap();
        assert_box_mesh(min, max, cells, &m);
        assert_eq!(m.report.flat_dropped, 0);
    }
}

#[test]
fn unstructured_boxes_depend_on_the_seed_only() {
    let (min, max, cells) = ([0.0; 3], [6.0, 5.0, 2.0], [6, 5, 2]);
    let a = unstructured_box_data(min, max, cells, 7).unwrap();
    let b = unstructured_box_data(min, max, cells, 7).unwrap();
    assert_eq!(a, b);
    let c = unstructured_box_data(min, max, cells, 8).unwrap();
    assert_ne!(a.0, c.0);
    assert_ne!(a.1, c.1);
}

#[test]
fn bad_boxes_are_refused() {
    let nan = f64::NAN;
    for (min, max) in [
        ([0.0, 0.0, nan], [1.0; 3]),
        ([0.0; 3], [1.0, f64::INFINITY, 1.0]),
        ([0.0; 3], [1.0, 0.0, 1.0]),
        ([0.0; 3], [1.0, 1.0, -1.0]),
        ([-f64::MAX, 0.0, 0.0], [f64::MAX, 1.0, 1.0]),
    ] {
        assert!(matches!(
            unstructured_box_data(min, max, [2, 2, 2], 1),
            Err(UnstructuredError::BadBox { .. })
        ));
    }
    assert_eq!(
        unstructured_box_data([0.0; 3], [1.0; 3], [2, 0, 2], 1),
        Err(UnstructuredError::ZeroCells { cells: [2, 0, 2] })
    );
    // Refused before anything is allocated.
    for cells in [[1000, 1000, 1000], [usize::MAX, usize::MAX, 2]] {
        assert!(matches!(
            unstructured_box_data([0.0; 3], [1.0; 3], cells, 1),
            Err(UnstructuredError::TooManyPoints { .. })
        ));
    }
}

/// The area-weighted histogram of interior faces' normal directions in the x-y plane (each
/// face weighted by its area times the in-plane part of its unit normal, as the bench's crack
/// direction measure), 12 bins over 180 degrees, each bin over the mean.
fn direction_histogram(v: &[[f64; 3]], t: &[[u32; 4]]) -> [f64; 12] {
    let mut hist = [0.0; 12];
    for (face, count) in faces(t).into_values() {
        if count != 2 {
            continue;
        }
        let [a, b, c] = face.map(|i| v[i as usize]);
        let (u, w) = (
            [0, 1, 2].map(|d| b[d] - a[d]),
            [0, 1, 2].map(|d| c[d] - a[d]),
        );
        // Twice the area times the unit normal.
        let n = [
            u[1] * w[2] - u[2] * w[1],
            u[2] * w[0] - u[0] * w[2],
            u[0] * w[1] - u[1] * w[0],
        ];
        let weight = n[0].hypot(n[1]);
        if weight == 0.0 {
            continue;
        }
        let theta = n[1].atan2(n[0]).rem_euclid(std::f64::consts::PI);
        let k = ((theta / std::f64::consts::PI * 12.0) as usize).min(11);
        hist[k] += weight;
    }
    let mean = hist.iter().sum::<f64>() / 12.0;
    hist.map(|h| h / mean)
}

#[test]
fn unstructured_faces_have_no_preferred_direction() {
    let (min, max, cells) = ([0.0; 3], [24.0, 24.0, 3.0], [24, 24, 3]);
    let peak = |h: [f64; 12]| h.iter().copied().fold(0.0, f64::max);
    // The lattice puts all its in-plane face area in three bins (x, y and one diagonal):
    // measured 4.41 x the mean.
    let (v, t) = primitives::box_data(min, max, cells);
    let lattice = peak(direction_histogram(&v, &t));
    assert!(lattice > 4.0, "lattice peak {lattice}");
    // Unstructured: measured peaks 1.04 to 1.09 over seeds 1 to 10. About 20 000 interior
    // faces spread over 12 bins leave each bin a noise of about 3%, so 1.2 is some five
    // standard deviations above the mean, and far below any lattice.
    for seed in [1, 2] {
        let (v, t) = unstructured_box_data(min, max, cells, seed).unwrap();
        let hist = direction_histogram(&v, &t);
        assert!(peak(hist) < 1.2, "seed {seed}: {hist:?}");
        assert!(hist.iter().all(|&h| h > 0.8), "seed {seed}: {hist:?}");
    }
}
