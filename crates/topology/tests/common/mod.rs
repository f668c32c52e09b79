//! Helpers shared by the topology integration tests: random meshes, brute-force invariant checks,
//! canonical forms.
#![allow(dead_code)]

use perifrac_topology::faces::{signed_volume, FACE_CORNERS};
use perifrac_topology::{primitives, TetMesh, NO_TET};

/// Tiny deterministic generator (splitmix64) driven by a proptest-chosen seed.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    pub fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            v.swap(i, self.below(i + 1));
        }
    }
}

/// A box mesh with its interior vertices jittered by up to `0.05 * min cell size` per axis.
///
/// Why 0.05: every Kuhn tet of a cuboid cell has all heights at least `h_min / sqrt 2 ~ 0.71
/// h_min`; moving each corner by at most `sqrt 3 * 0.05 h_min ~ 0.09 h_min` cannot bring a vertex
/// to the plane of its opposite face, so every tet stays positive (the caller asserts it).
pub fn jittered_box(cells: [usize; 3], extent: [f64; 3], rng: &mut Rng) -> TetMesh {
    let (mut v, t) = primitives::box_data([0.0; 3], extent, cells);
    let h_min = (0..3)
        .map(|d| extent[d] / cells[d] as f64)
        .fold(f64::INFINITY, f64::min);
    let amp = 0.05 * h_min;
    for p in v.iter_mut() {
        let interior = (0..3).all(|d| p[d] > 1e-9 * extent[d] && p[d] < extent[d] * (1.0 - 1e-9));
        if interior {
            for c in p.iter_mut() {
                *c += amp * (2.0 * rng.unit() - 1.0);
            }
        }
    }
    let (mesh, report) = TetMesh::new(v, t).expect("jittered box is valid");
    assert_eq!(
        report.inverted_fixed, 0,
        "jitter must keep every tet positive"
    );
    mesh
}

/// Every interior face once, as (tet, local face) with tet < neighbour.
pub fn interior_faces(m: &TetMesh) -> Vec<(u32, u8)> {
    let mut out = Vec::new();
    for (t, nb) in m.neighbours().iter().enumerate() {
        for (f, &n) in nb.iter().enumerate() {
            if n != NO_TET && (n as usize) > t {
                out.push((t as u32, f as u8));
            }
        }
    }
    out
}

/// For every (tet, corner) slot, the smallest slot that uses the same vertex id: the topology up
/// to renumbering of vertex copies.
pub fn canonical(m: &TetMesh) -> Vec<u32> {
    let mut first = vec![u32::MAX; m.num_vertices()];
    let mut out = Vec::with_capacity(m.num_tets() * 4);
    for (t, tet) in m.tets().iter().enumerate() {
        for (k, &v) in tet.iter().enumerate() {
            let slot = (t * 4 + k) as u32;
            let f = &mut first[v as usize];
            if *f == u32::MAX {
                *f = slot;
            }
            out.push(*f);
        }
    }
    out
}

/// Current volume of tet `t`.
pub fn current_volume(m: &TetMesh, t: usize) -> f64 {
    let [a, b, c, d] = m.tets()[t].map(|v| m.positions()[v as usize]);
    signed_volume(a, b, c, d)
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// Checks every invariant of docs/model.md section 3 by brute force; `rest_volume` is the total
/// rest volume of the uncut mesh.
pub fn check_invariants(m: &TetMesh, rest_volume: f64) {
    let tets = m.tets();
    let nb = m.neighbours();
    let origin = m.vertex_origin();
    // Total rest volume unchanged: copies keep their rest vertex, so the sum is bit-identical.
    assert_eq!(m.total_rest_volume(), rest_volume);
    // Four distinct corners, all in range.
    for (t, tet) in tets.iter().enumerate() {
        for i in 0..4 {
            assert!(
                (tet[i] as usize) < m.num_vertices(),
                "tet {t} corner out of range"
            );
            for j in i + 1..4 {
                assert_ne!(tet[i], tet[j], "tet {t} lost a distinct corner");
            }
        }
    }
    // Uncracked shared faces reference identical ids; crack bits are symmetric.
    for (t, tet) in tets.iter().enumerate() {
        for f in 0..4 {
            let n = nb[t][f];
            if n == NO_TET {
                continue;
            }
            let g = nb[n as usize].iter().position(|&x| x == t as u32).unwrap();
            assert_eq!(
                m.is_cracked(t as u32, f as u8),
                m.is_cracked(n, g as u8),
                "crack bit of tet {t} face {f} is one-sided"
            );
            if !m.is_cracked(t as u32, f as u8) {
                for k in FACE_CORNERS[f] {
                    assert!(
                        tets[n as usize].contains(&tet[k]),
                        "uncracked face {f} of tet {t} disagrees with tet {n}"
                    );
                }
            }
        }
    }
    // Stars by brute force: group the tets around each rest vertex through uncracked faces that
    // contain it, and compare with the copies.
    let nr = m.num_rest_vertices();
    let mut star: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nr];
    for (t, tet) in tets.iter().enumerate() {
        for (k, &v) in tet.iter().enumerate() {
            star[origin[v as usize] as usize].push((t, k));
        }
    }
    let mut used = vec![false; m.num_vertices()];
    for tet in tets {
        for &v in tet {
            used[v as usize] = true;
        }
    }
    assert!(
        used.iter().all(|&u| u),
        "every vertex copy is used by some tet"
    );
    for (r, s) in star.iter().enumerate() {
        let mut parent: Vec<usize> = (0..s.len()).collect();
        for (a, &(t, k)) in s.iter().enumerate() {
            for (b, &(u, _)) in s.iter().enumerate() {
                let joined = (0..4)
                    .any(|f| f != k && nb[t][f] == u as u32 && !m.is_cracked(t as u32, f as u8));
                if joined {
                    let (x, y) = (find(&mut parent, a), find(&mut parent, b));
                    parent[x] = y;
                }
            }
        }
        let mut group_of_copy = std::collections::HashMap::new();
        let mut groups = std::collections::HashSet::new();
        for (a, &(t, k)) in s.iter().enumerate() {
            let g = find(&mut parent, a);
            groups.insert(g);
            let v = tets[t][k];
            let prev = group_of_copy.insert(v, g);
            assert!(
                prev.is_none() || prev == Some(g),
                "copy {v} of rest vertex {r} spans two groups (tets not connected around it)"
            );
        }
        let copies = origin.iter().filter(|&&o| o as usize == r).count();
        assert_eq!(copies, groups.len(), "rest vertex {r}: copies != groups");
        assert_eq!(group_of_copy.len(), copies);
    }
    // Splitting again with no new crack changes nothing.
    let mut again = m.clone();
    let rep = again.split();
    assert_eq!((rep.vertices_split, rep.copies_added), (0, 0));
    assert_eq!(again.tets(), m.tets());
    assert_eq!(again.num_vertices(), m.num_vertices());
    // Pieces are closed under uncracked adjacency.
    let pieces = m.pieces();
    for (t, n4) in nb.iter().enumerate() {
        for (f, &n) in n4.iter().enumerate() {
            if n != NO_TET && !m.is_cracked(t as u32, f as u8) {
                assert_eq!(pieces.piece_of_tet[t], pieces.piece_of_tet[n as usize]);
            }
        }
    }
    check_surfaces(m);
}

/// Every piece surface is a closed 2-manifold and encloses the piece's tet volume, positively.
pub fn check_surfaces(m: &TetMesh) {
    let pieces = m.pieces();
    let mut volume = vec![0.0; pieces.count];
    for t in 0..m.num_tets() {
        volume[pieces.piece_of_tet[t] as usize] += current_volume(m, t);
    }
    let surfaces = m.piece_surfaces();
    assert_eq!(surfaces.len(), pieces.count);
    let mut total_faces = 0;
    for (p, s) in surfaces.iter().enumerate() {
        assert!(s.is_closed(), "surface of piece {p} is not closed");
        assert!(
            s.is_closed_manifold(),
            "surface of piece {p} is not a closed 2-manifold"
        );
        assert!(s.piece.iter().all(|&q| q as usize == p));
        let sv = s.signed_volume();
        assert!(sv > 0.0, "piece {p} surface is inward ({sv})");
        // 1e-9 relative: the two volumes are sums of the same few hundred terms in a different
        // order, so they agree to ~1e-14; 1e-9 leaves room without hiding a missing face (which
        // changes the volume by a whole tet's share, > 1e-3 relative here).
        assert!(
            (sv - volume[p]).abs() <= 1e-9 * volume[p],
            "piece {p}: surface volume {sv} vs tets {}",
            volume[p]
        );
        // Crack smoothing keeps every piece right side out (with its fold guard off and no
        // move limit, random crack sets here turn pieces over: the guard is what holds).
        let mut smooth = s.clone();
        // Every piece, however small (by default pieces of 48 faces or fewer keep theirs).
        smooth.smooth_cracks(&perifrac_topology::CrackSmoothing {
            min_piece_faces: 0,
            ..perifrac_topology::CrackSmoothing::default()
        });
        let after = smooth.signed_volume();
        assert!(
            after > 0.0,
            "piece {p} turned inside out by smoothing ({after})"
        );
        total_faces += s.faces.len();
    }
    let all = m.surface();
    assert_eq!(all.faces.len(), total_faces);
    assert!(all.is_closed());
    assert!(all.is_closed_manifold());
}
