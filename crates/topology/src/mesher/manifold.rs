//! A manifold boundary for the kept lattice tets: where the clipping leaves two parts of the
//! solid touching along a lattice edge or at a lattice vertex only (a thin neck of the surface
//! cut between lattice points), the boundary pinches there, and every reader of the mesh's
//! boundary (MeshLab, trimesh, a renderer) sees edges shared by four faces or vertices where
//! two fans of faces meet. Around each such vertex the kept tets fall into several groups that
//! share no face through it (all but the largest are removed), or form one group with holes,
//! the lattice tets missing around it falling into several groups (all but the largest, the
//! outside, are filled); around each such edge the kept tets fall into several wedges (all but
//! the largest are removed). The pass repeats until nothing pinches (a change can pinch a
//! neighbour).

use hashbrown::HashMap;

use crate::faces::FACE_CORNERS;

/// Passes at most: each removes tets, so this only bounds pathological inputs.
const MAX_PASSES: usize = 32;

/// What [`make_boundary_manifold`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ManifoldReport {
    /// Tets removed.
    pub removed_tets: usize,
    /// Lattice tets added to fill holes around a vertex.
    pub added_tets: usize,
    /// Passes over the boundary until nothing pinched was left.
    pub passes: usize,
}

/// Removes tets from `tets` and adds tets of `lattice` (all tets of the lattice the kept ones
/// come from, lattice vertex ids) until no lattice vertex or edge on the boundary pinches.
pub fn make_boundary_manifold(tets: &mut Vec<[u32; 4]>, lattice: &[[u32; 4]]) -> ManifoldReport {
    let mut report = ManifoldReport::default();
    for _ in 0..MAX_PASSES {
        report.passes += 1;
        let (remove, add) = pinched_tets(tets, lattice);
        if remove.is_empty() && add.is_empty() {
            break;
        }
        report.removed_tets += remove.len();
        report.added_tets += add.len();
        let mut k = 0;
        tets.retain(|_| {
            let keep = remove.binary_search(&k).is_err();
            k += 1;
            keep
        });
        tets.extend(add.iter().map(|&t| lattice[t as usize]));
    }
    report
}

/// One pass: the kept tets to remove (sorted indices into `tets`) and the lattice tets to add
/// (sorted indices into `lattice`): around every pinched boundary vertex, the smaller groups
/// of kept tets, or the smaller groups of missing ones; where no vertex pinched, the smaller
/// wedges around every pinched boundary edge.
fn pinched_tets(tets: &[[u32; 4]], lattice: &[[u32; 4]]) -> (Vec<u32>, Vec<u32>) {
    // Boundary faces: those of one tet only.
    let mut faces: HashMap<[u32; 3], u32> = HashMap::with_capacity(2 * tets.len());
    for t in tets {
        for corners in FACE_CORNERS {
            let mut f = corners.map(|c| t[c]);
            f.sort_unstable();
            *faces.entry(f).or_insert(0) += 1;
        }
    }
    let mut on_boundary: HashMap<u32, ()> = HashMap::new();
    let mut edge_faces: HashMap<(u32, u32), u32> = HashMap::new();
    for (f, &n) in &faces {
        if n == 1 {
            for k in 0..3 {
                on_boundary.insert(f[k], ());
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *edge_faces.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
    }
    // Kept tets around each boundary vertex, and all lattice tets around it.
    let mut star: HashMap<u32, Vec<u32>> = HashMap::with_capacity(on_boundary.len());
    for (ti, t) in tets.iter().enumerate() {
        for v in t {
            if on_boundary.contains_key(v) {
                star.entry(*v).or_default().push(ti as u32);
            }
        }
    }
    let mut lattice_star: HashMap<u32, Vec<u32>> = HashMap::with_capacity(on_boundary.len());
    for (ti, t) in lattice.iter().enumerate() {
        for v in t {
            if on_boundary.contains_key(v) {
                lattice_star.entry(*v).or_default().push(ti as u32);
            }
        }
    }
    let kept: hashbrown::HashSet<[u32; 4]> = tets.iter().copied().collect();
    let joined = |a: &[u32; 4], b: &[u32; 4]| shared(a, b) == 3;
    let (mut remove, mut add) = (Vec::new(), Vec::new());
    let mut vertices: Vec<u32> = star.keys().copied().collect();
    vertices.sort_unstable();
    for v in vertices {
        let around = &star[&v];
        let smaller = smaller_groups(tets, around, joined);
        if !smaller.is_empty() {
            remove.extend(smaller);
            continue;
        }
        // One group: holes in it show as more than one group of missing lattice tets.
        let missing: Vec<u32> = lattice_star
            .get(&v)
            .into_iter()
            .flatten()
            .copied()
            .filter(|&t| !kept.contains(&lattice[t as usize]))
            .collect();
        add.extend(smaller_groups(lattice, &missing, joined));
    }
    if remove.is_empty() && add.is_empty() {
        let mut edges: Vec<(u32, u32)> = edge_faces
            .iter()
            .filter(|(_, &n)| n > 2)
            .map(|(&e, _)| e)
            .collect();
        edges.sort_unstable();
        for (a, b) in edges {
            let around: Vec<u32> = star[&a]
                .iter()
                .copied()
                .filter(|&t| tets[t as usize].contains(&b))
                .collect();
            remove.extend(smaller_groups(tets, &around, joined));
        }
    }
    remove.sort_unstable();
    remove.dedup();
    add.sort_unstable();
    add.dedup();
    // A tet both removed (as part of a group at one vertex) and added (as a hole at another)
    // cannot happen: added tets are missing ones.
    (remove, add)
}

/// Vertices two tets share.
fn shared(a: &[u32; 4], b: &[u32; 4]) -> usize {
    a.iter().filter(|v| b.contains(v)).count()
}

/// The tets of `around` outside its largest group, groups joined by `joined` (ties: the group
/// of the lowest tet stays).
fn smaller_groups(
    tets: &[[u32; 4]],
    around: &[u32],
    joined: impl Fn(&[u32; 4], &[u32; 4]) -> bool,
) -> Vec<u32> {
    let n = around.len();
    let mut group: Vec<usize> = (0..n).collect();
    fn root(g: &mut [usize], mut i: usize) -> usize {
        while g[i] != i {
            g[i] = g[g[i]];
            i = g[i];
        }
        i
    }
    for i in 0..n {
        for j in i + 1..n {
            if joined(&tets[around[i] as usize], &tets[around[j] as usize]) {
                let (a, b) = (root(&mut group, i), root(&mut group, j));
                group[a.max(b)] = a.min(b);
            }
        }
    }
    let roots: Vec<usize> = (0..n).map(|i| root(&mut group, i)).collect();
    let mut size = vec![0usize; n];
    for &r in &roots {
        size[r] += 1;
    }
    // The largest group; ties go to the group whose root (lowest member) comes first.
    let Some(keep) = (0..n)
        .filter(|&r| size[r] > 0)
        .max_by(|&a, &b| size[a].cmp(&size[b]).then(b.cmp(&a)))
    else {
        return Vec::new();
    };
    (0..n)
        .filter(|&i| roots[i] != keep)
        .map(|i| around[i])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_blocks_touching_along_an_edge_come_apart() {
        // Two unit cubes of 6 Kuhn tets each, cells (0, 0) and (1, 1) of a 2x2x1 grid: they
        // share the edge x = y = 1 and nothing else.
        let (_, all) = crate::primitives::box_data([0.0; 3], [2.0, 2.0, 1.0], [2, 2, 1]);
        // Cells are stored x fastest: cell (i, j) holds tets 6 (i + 2 j) onwards.
        let cell = |i: usize, j: usize| all[6 * (i + 2 * j)..6 * (i + 2 * j) + 6].to_vec();
        let mut tets = cell(0, 0);
        tets.extend(cell(1, 1));
        assert!(!pinched_tets(&tets, &all).0.is_empty());
        let report = make_boundary_manifold(&mut tets, &all);
        // The few tets at the pinch go (those of the smaller group around each pinched
        // vertex), nothing else.
        assert!((1..=6).contains(&report.removed_tets), "{report:?}");
        let (remove, add) = pinched_tets(&tets, &all);
        assert!(remove.is_empty() && add.is_empty());
        assert_eq!(tets.len(), 12 - report.removed_tets + report.added_tets);
    }

    #[test]
    fn two_gaps_at_one_vertex_get_one_filled() {
        // A 2x2x2 block of cells; its centre vertex (1, 1, 1) is interior. Take out one tet at
        // the centre that also touches corner (0, 0, 0) and one that touches (2, 2, 2): the
        // kept tets around the centre stay one group, but the missing ones are two groups,
        // two cavities meeting at the centre, whose boundaries touch there. One is filled.
        let (_, all) = crate::primitives::box_data([0.0; 3], [2.0, 2.0, 2.0], [2, 2, 2]);
        let centre = 1 + 3 * (1 + 3);
        let gap = |corner: u32| {
            *all.iter()
                .find(|t| t.contains(&centre) && t.contains(&corner))
                .expect("a tet at the centre and the corner")
        };
        let (near, far) = (gap(0), gap(26));
        let mut tets: Vec<[u32; 4]> = all
            .iter()
            .copied()
            .filter(|t| *t != near && *t != far)
            .collect();
        assert!(!pinched_tets(&tets, &all).1.is_empty());
        let report = make_boundary_manifold(&mut tets, &all);
        assert_eq!(
            (report.removed_tets, report.added_tets),
            (0, 1),
            "{report:?}"
        );
        let (remove, add) = pinched_tets(&tets, &all);
        assert!(remove.is_empty() && add.is_empty());
    }

    #[test]
    fn a_solid_block_is_left_alone() {
        let (_, mut tets) = crate::primitives::box_data([0.0; 3], [3.0, 2.0, 2.0], [3, 2, 2]);
        let before = tets.clone();
        let report = make_boundary_manifold(&mut tets, &before);
        assert_eq!((report.removed_tets, report.added_tets), (0, 0));
        assert_eq!(tets, before);
    }
}
