//! Extraction of the surface of every piece: rest boundary faces plus separated crack faces.

use crate::faces::{cross, dot, FACE_CORNERS};
use crate::mesh::{TetMesh, NO_TET};
use crate::pieces::Pieces;

/// A triangle surface in current positions, compacted to the vertices it uses.
///
/// Faces are outward oriented (counter-clockwise seen from outside). `crack[i]` is 1 for a crack
/// face and 0 for an original boundary face; `piece[i]` is the piece id of the face's tet (see
/// [`crate::Pieces`]); `vertex_ids[k]` is the mesh vertex id of compact vertex `k`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Surface {
    /// Positions of the compact vertices (length).
    pub vertices: Vec<[f64; 3]>,
    /// Mesh vertex id of each compact vertex.
    pub vertex_ids: Vec<u32>,
    /// Triangles as compact vertex indices, outward.
    pub faces: Vec<[u32; 3]>,
    /// 1 for a crack face, 0 for an original boundary face.
    pub crack: Vec<u8>,
    /// Piece id of each face's tet.
    pub piece: Vec<u32>,
    /// Vertices added at the middle of an edge shared by two wedges of a pinched piece, as
    /// `(vertex, end a, end b)` compact ids; `vertex_ids` gives them end a's mesh vertex.
    pub midpoints: Vec<(u32, u32, u32)>,
}

impl Surface {
    /// Splits the faces of every wedge but the first on each edge that more than two faces
    /// share after the fans were separated: `partners` pairs the faces of one wedge (keyed by
    /// face and the edge's mesh vertices, as [`TetMesh::surface_of`] found them).
    fn split_shared_edges(&mut self, partners: &hashbrown::HashMap<(u32, u32, u32), u32>) {
        let mut on_edge: hashbrown::HashMap<(u32, u32), Vec<u32>> = hashbrown::HashMap::new();
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                on_edge
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(f as u32);
            }
        }
        let mut shared: Vec<((u32, u32), Vec<u32>)> =
            on_edge.into_iter().filter(|(_, f)| f.len() > 2).collect();
        shared.sort_unstable();
        // Each face split: (face, the edge's compact ends, the midpoint), in edge order.
        let mut splits: Vec<(u32, u32, u32, u32)> = Vec::new();
        for ((a, b), faces) in shared {
            let (ma, mb) = (self.vertex_ids[a as usize], self.vertex_ids[b as usize]);
            let key = (ma.min(mb), ma.max(mb));
            let mut done = vec![false; faces.len()];
            let mut wedge = 0;
            for i in 0..faces.len() {
                if done[i] {
                    continue;
                }
                done[i] = true;
                let partner = partners
                    .get(&(faces[i], key.0, key.1))
                    .and_then(|p| faces.iter().position(|f| f == p));
                if let Some(j) = partner {
                    done[j] = true;
                }
                if wedge > 0 {
                    let m = self.vertices.len() as u32;
                    let (pa, pb) = (self.vertices[a as usize], self.vertices[b as usize]);
                    self.vertices
                        .push(std::array::from_fn(|k| 0.5 * (pa[k] + pb[k])));
                    self.vertex_ids.push(ma);
                    self.midpoints.push((m, a, b));
                    splits.push((faces[i], a, b, m));
                    if let Some(j) = partner {
                        splits.push((faces[j], a, b, m));
                    }
                }
                wedge += 1;
            }
        }
        // Each split face (x, y, z) with edge (x, y) becomes (x, m, z) in its place and
        // (m, y, z) appended; the orientation stays. A face split at two of its edges is
        // split the second time in whichever of its halves holds that edge.
        let mut halves: hashbrown::HashMap<u32, Vec<u32>> = hashbrown::HashMap::new();
        for (f, a, b, m) in splits {
            let mut candidates = vec![f];
            candidates.extend(halves.get(&f).into_iter().flatten().copied());
            let found = candidates.iter().find_map(|&g| {
                let face = self.faces[g as usize];
                (0..3)
                    .find(|&k| {
                        let (x, y) = (face[k], face[(k + 1) % 3]);
                        (x, y) == (a, b) || (x, y) == (b, a)
                    })
                    .map(|k| (g, face, k))
            });
            let Some((g, face, k)) = found else {
                continue;
            };
            let (x, y, z) = (face[k], face[(k + 1) % 3], face[(k + 2) % 3]);
            self.faces[g as usize] = [x, m, z];
            halves.entry(f).or_default().push(self.faces.len() as u32);
            self.faces.push([m, y, z]);
            self.crack.push(self.crack[g as usize]);
            self.piece.push(self.piece[g as usize]);
        }
    }

    /// Keeps the faces of the pieces `keep` marks (indexed by piece id) and the vertices they
    /// use, renumbered in their old order; midpoints whose vertex or ends go are dropped. Pieces
    /// share no surface vertex, so every kept piece's surface stays exactly as it was.
    ///
    /// Panics if a face's piece id is not an index of `keep`.
    #[track_caller]
    pub fn retain_pieces(&mut self, keep: &[bool]) {
        let mut new_id = vec![u32::MAX; self.vertices.len()];
        let mut kept_face = 0;
        for f in 0..self.faces.len() {
            if !keep[self.piece[f] as usize] {
                continue;
            }
            for &v in &self.faces[f] {
                new_id[v as usize] = 0;
            }
            self.faces[kept_face] = self.faces[f];
            self.crack[kept_face] = self.crack[f];
            self.piece[kept_face] = self.piece[f];
            kept_face += 1;
        }
        self.faces.truncate(kept_face);
        self.crack.truncate(kept_face);
        self.piece.truncate(kept_face);
        let mut next = 0u32;
        for (v, id) in new_id.iter_mut().enumerate() {
            if *id == 0 {
                *id = next;
                self.vertices[next as usize] = self.vertices[v];
                self.vertex_ids[next as usize] = self.vertex_ids[v];
                next += 1;
            }
        }
        self.vertices.truncate(next as usize);
        self.vertex_ids.truncate(next as usize);
        for face in &mut self.faces {
            *face = face.map(|v| new_id[v as usize]);
        }
        self.midpoints = self
            .midpoints
            .iter()
            .filter_map(|&(m, a, b)| {
                let [m, a, b] = [m, a, b].map(|v| new_id[v as usize]);
                (m != u32::MAX && a != u32::MAX && b != u32::MAX).then_some((m, a, b))
            })
            .collect();
    }

    /// The faces around each vertex as CSR: vertex `v`'s are `around[start[v]..start[v + 1]]`,
    /// each as (face, corner of the face at `v`), in face order.
    pub(crate) fn faces_around_vertices(&self) -> (Vec<usize>, Vec<(u32, u8)>) {
        let n = self.vertices.len();
        let mut start = vec![0usize; n + 1];
        for f in &self.faces {
            for &v in f {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut around = vec![(0u32, 0u8); start[n]];
        for (fi, f) in self.faces.iter().enumerate() {
            for (c, &v) in f.iter().enumerate() {
                around[fill[v as usize]] = (fi as u32, c as u8);
                fill[v as usize] += 1;
            }
        }
        (start, around)
    }

    /// Enclosed volume by the divergence theorem (length^3); positive for an outward surface.
    pub fn signed_volume(&self) -> f64 {
        self.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|k| self.vertices[k as usize]);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    /// True when the surface is a closed, consistently oriented 2-manifold: every directed
    /// edge `(a, b)` is used by exactly one face and `(b, a)` by exactly one other, and the
    /// faces around every vertex form a single fan (one cycle through its edges).
    pub fn is_closed_manifold(&self) -> bool {
        let mut directed: hashbrown::HashMap<(u32, u32), u32> = hashbrown::HashMap::new();
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..3 {
                if directed
                    .insert((face[k], face[(k + 1) % 3]), f as u32)
                    .is_some()
                {
                    return false;
                }
            }
        }
        if directed
            .keys()
            .any(|&(a, b)| !directed.contains_key(&(b, a)))
        {
            return false;
        }
        // Around vertex v, face (v, a, b) is followed by the face holding the edge (v, b) the
        // other way round, i.e. the directed edge (b, v)... walk that cycle from one face and
        // count the faces reached against the faces at v.
        let mut at = vec![0u32; self.vertices.len()];
        for face in &self.faces {
            for &v in face {
                at[v as usize] += 1;
            }
        }
        let mut seen = vec![false; self.vertices.len()];
        for face in &self.faces {
            for k in 0..3 {
                let v = face[k];
                if std::mem::replace(&mut seen[v as usize], true) {
                    continue;
                }
                let mut b = face[(k + 2) % 3];
                let mut count = 1;
                // Next face around v: the one with the directed edge (v, b).
                while let Some(&g) = directed.get(&(v, b)) {
                    let next = self.faces[g as usize];
                    let i = (0..3).find(|&i| next[i] == v).unwrap_or(0);
                    if next == *face {
                        break;
                    }
                    b = next[(i + 2) % 3];
                    count += 1;
                    if count > at[v as usize] {
                        return false;
                    }
                }
                if count != at[v as usize] {
                    return false;
                }
            }
        }
        true
    }

    /// True when every directed edge `(a, b)` is matched by as many edges `(b, a)`.
    pub fn is_closed(&self) -> bool {
        let mut balance: hashbrown::HashMap<(u32, u32), i64> = hashbrown::HashMap::new();
        for f in &self.faces {
            for i in 0..3 {
                let (a, b) = (f[i], f[(i + 1) % 3]);
                let (key, d) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
                *balance.entry(key).or_insert(0) += d;
            }
        }
        balance.values().all(|&d| d == 0)
    }
}

impl TetMesh {
    /// The surface of all pieces together.
    pub fn surface(&self) -> Surface {
        self.surface_and_pieces().0
    }

    /// [`TetMesh::surface`] and [`TetMesh::pieces`] from one computation of the pieces.
    pub fn surface_and_pieces(&self) -> (Surface, Pieces) {
        let pieces = self.pieces();
        (self.surface_of(&pieces), pieces)
    }

    /// The surface of all pieces together, with `pieces` this mesh's current pieces.
    ///
    /// Every piece's surface is a closed, consistently oriented 2-manifold. Where a piece's
    /// surface pinches (cracks meeting at an edge or a vertex from two sides leave a piece whose
    /// tets are joined around a vertex while its surface touches itself there), each fan of
    /// faces around a mesh vertex gets its own surface vertex (`vertex_ids` then repeats the
    /// mesh vertex), and an edge that still carries two wedges of faces after that is split in
    /// the second wedge's two faces by a vertex at its middle (listed in `midpoints`).
    ///
    /// Panics if `pieces` does not have one entry per tet.
    #[track_caller]
    pub fn surface_of(&self, pieces: &Pieces) -> Surface {
        assert_eq!(
            pieces.piece_of_tet.len(),
            self.tets.len(),
            "one piece per tet"
        );
        let mut records = Vec::new();
        self.for_each_surface_face(|t, f, face, crack| {
            records.push((t as u32, f as u8, face, crack))
        });
        let (fan, partners) = self.fans(&records);
        let mut map: hashbrown::HashMap<u32, u32> = hashbrown::HashMap::new();
        let mut s = Surface::default();
        for (r, &(t, _, face, crack)) in records.iter().enumerate() {
            let compact = std::array::from_fn(|k| {
                let root = fan[3 * r + k];
                *map.entry(root).or_insert_with(|| {
                    s.vertices.push(self.pos[face[k] as usize]);
                    s.vertex_ids.push(face[k]);
                    (s.vertices.len() - 1) as u32
                })
            });
            s.faces.push(compact);
            s.crack.push(crack);
            s.piece.push(pieces.piece_of_tet[t as usize]);
        }
        if !partners.is_empty() {
            s.split_shared_edges(&partners);
        }
        s
    }

    /// One surface per piece, indexed by piece id.
    pub fn piece_surfaces(&self) -> Vec<Surface> {
        let (all, pieces) = self.surface_and_pieces();
        let mut out = vec![Surface::default(); pieces.count];
        let mut map = vec![u32::MAX; all.vertices.len()];
        // Faces keep their order within a piece; each piece is compacted on its own.
        for (f, face) in all.faces.iter().enumerate() {
            let s = &mut out[all.piece[f] as usize];
            let compact = face.map(|k| {
                let m = &mut map[k as usize];
                if *m == u32::MAX {
                    *m = s.vertices.len() as u32;
                    s.vertices.push(all.vertices[k as usize]);
                    s.vertex_ids.push(all.vertex_ids[k as usize]);
                }
                *m
            });
            s.faces.push(compact);
            s.crack.push(all.crack[f]);
            s.piece.push(all.piece[f]);
        }
        out
    }

    /// Calls `emit(tet, local face, outward vertex ids, crack flag)` for every surface face, in
    /// tet order.
    fn for_each_surface_face(&self, mut emit: impl FnMut(usize, usize, [u32; 3], u8)) {
        for (t, tet) in self.tets.iter().enumerate() {
            for (f, corners) in FACE_CORNERS.iter().enumerate() {
                if let Some(crack) = self.surface_face(t, f) {
                    emit(t, f, corners.map(|k| tet[k]), crack);
                }
            }
        }
    }

    /// `Some(crack flag)` when local face `f` of tet `t` is on the surface: a boundary face, or
    /// a crack face whose two tets no longer share all three vertices.
    fn surface_face(&self, t: usize, f: usize) -> Option<u8> {
        let other = self.neighbours[t][f];
        if other == NO_TET {
            return Some(0);
        }
        if self.crack[t] & (1 << f) != 0 {
            let o = &self.tets[other as usize];
            if !FACE_CORNERS[f]
                .iter()
                .all(|&k| o.contains(&self.tets[t][k]))
            {
                return Some(1);
            }
        }
        None
    }

    /// For every corner `3 r + k` of surface face `records[r]`, a representative corner of its
    /// fan: the faces around the corner's vertex joined through the edges at it. An edge with
    /// two surface faces joins them; an edge with more (a pinch) joins each face with the one
    /// that closes the same wedge of tets around the edge.
    ///
    /// Also returns, for the faces on pinched edges, each face's partner in its wedge:
    /// `(face, the edge's mesh vertices (lower first)) -> partner face`.
    #[allow(clippy::type_complexity)]
    fn fans(
        &self,
        records: &[(u32, u8, [u32; 3], u8)],
    ) -> (Vec<u32>, hashbrown::HashMap<(u32, u32, u32), u32>) {
        let mut parent: Vec<u32> = (0..3 * records.len() as u32).collect();
        // Faces on each undirected edge, with the corners of the edge's two ends.
        let mut edges: hashbrown::HashMap<(u32, u32), Vec<(u32, u8, u8)>> =
            hashbrown::HashMap::with_capacity(records.len() * 3 / 2);
        for (r, &(_, _, face, _)) in records.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                let (key, ka, kb) = if a < b {
                    ((a, b), k, (k + 1) % 3)
                } else {
                    ((b, a), (k + 1) % 3, k)
                };
                edges
                    .entry(key)
                    .or_default()
                    .push((r as u32, ka as u8, kb as u8));
            }
        }
        let join = |parent: &mut Vec<u32>, x: u32, y: u32| {
            let (a, b) = (find(parent, x), find(parent, y));
            parent[a.max(b) as usize] = a.min(b);
        };
        // Records by (tet, local face), for the pinch walks.
        let mut index: hashbrown::HashMap<(u32, u8), u32> = hashbrown::HashMap::new();
        let mut partners = hashbrown::HashMap::new();
        let mut keys: Vec<&(u32, u32)> = edges.keys().collect();
        // Deterministic order whatever the hash: the union-find roots depend on it only
        // through which corner represents a fan, and that is the lowest one.
        keys.sort_unstable();
        for key in keys {
            let on = &edges[key];
            if on.len() == 2 {
                let ((r1, a1, b1), (r2, a2, b2)) = (on[0], on[1]);
                join(&mut parent, 3 * r1 + a1 as u32, 3 * r2 + a2 as u32);
                join(&mut parent, 3 * r1 + b1 as u32, 3 * r2 + b2 as u32);
                continue;
            }
            if index.is_empty() {
                for (r, &(t, f, _, _)) in records.iter().enumerate() {
                    index.insert((t, f), r as u32);
                }
            }
            for &(r1, a1, b1) in on {
                let (t, f, _, _) = records[r1 as usize];
                let Some((t2, f2)) = self.wedge_end(t, f, key.0, key.1) else {
                    continue;
                };
                let Some(&r2) = index.get(&(t2, f2)) else {
                    continue;
                };
                let Some(&(_, a2, b2)) = on.iter().find(|e| e.0 == r2) else {
                    continue;
                };
                join(&mut parent, 3 * r1 + a1 as u32, 3 * r2 + a2 as u32);
                join(&mut parent, 3 * r1 + b1 as u32, 3 * r2 + b2 as u32);
                partners.insert((r1, key.0, key.1), r2);
            }
        }
        let fan = (0..parent.len() as u32)
            .map(|c| find(&mut parent, c))
            .collect();
        (fan, partners)
    }

    /// From surface face `f` of tet `t` on the edge `(a, b)`, walks around the edge through the
    /// tets joined by faces that are not on the surface to the other surface face of the same
    /// wedge. `None` if the walk does not close (it always does on a valid mesh).
    fn wedge_end(&self, mut t: u32, mut f: u8, a: u32, b: u32) -> Option<(u32, u8)> {
        for _ in 0..=self.tets.len() {
            let tet = &self.tets[t as usize];
            // The tet's other face containing the edge: the one opposite the corner that is
            // neither a, b nor opposite f.
            let g = (0..4u8).find(|&g| {
                g != f && {
                    let opposite = tet[g as usize];
                    opposite != a && opposite != b
                }
            })?;
            if self.surface_face(t as usize, g as usize).is_some() {
                return Some((t, g));
            }
            let next = self.neighbours[t as usize][g as usize];
            let back = self.face_towards(next, t)?;
            t = next;
            f = back;
        }
        None
    }
}

/// Root of `x` with path halving.
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[x as usize];
        parent[x as usize] = parent[p as usize];
        x = parent[x as usize];
    }
    x
}
