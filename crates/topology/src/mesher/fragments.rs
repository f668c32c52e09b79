//! Removal of small fragments: tets the clipping left joined to the rest by a vertex or an
//! edge only, or not at all (in features thinner than a lattice cell), would be loose pieces
//! in a simulation.

use hashbrown::HashMap;

use crate::faces::FACE_CORNERS;

/// Face-connected components holding less than this fraction of all tets are dropped.
pub const MIN_FRAGMENT_FRACTION: f64 = 0.01;

/// What fragment removal did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FragmentReport {
    /// Face-connected pieces before removal.
    pub pieces: usize,
    /// Pieces dropped.
    pub dropped_pieces: usize,
    /// Tets in the dropped pieces.
    pub dropped_tets: usize,
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

/// Keeps the tets of face-connected pieces with at least [`MIN_FRAGMENT_FRACTION`] of the tets.
pub fn drop_small_fragments(tets: &mut Vec<[u32; 4]>) -> FragmentReport {
    let mut parent: Vec<u32> = (0..tets.len() as u32).collect();
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(2 * tets.len());
    for (ti, t) in tets.iter().enumerate() {
        for corners in FACE_CORNERS {
            let mut f = corners.map(|c| t[c]);
            f.sort_unstable();
            if let Some(&other) = first.get(&f) {
                let (a, b) = (find(&mut parent, ti as u32), find(&mut parent, other));
                if a != b {
                    parent[a as usize] = b;
                }
            } else {
                first.insert(f, ti as u32);
            }
        }
    }
    let roots: Vec<u32> = (0..tets.len() as u32)
        .map(|i| find(&mut parent, i))
        .collect();
    let mut size: HashMap<u32, usize> = HashMap::new();
    for &r in &roots {
        *size.entry(r).or_insert(0) += 1;
    }
    let min = (MIN_FRAGMENT_FRACTION * tets.len() as f64).ceil() as usize;
    let report = FragmentReport {
        pieces: size.len(),
        dropped_pieces: size.values().filter(|&&n| n < min).count(),
        dropped_tets: size.values().filter(|&&n| n < min).sum(),
    };
    let mut i = 0;
    tets.retain(|_| {
        let keep = size[&roots[i]] >= min;
        i += 1;
        keep
    });
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drops_a_loose_tet_keeps_the_body() {
        // 200 tets sharing faces in a chain, plus one loose tet and one joined by a vertex only.
        let mut tets: Vec<[u32; 4]> = (0..200).map(|i| [i, i + 1, i + 2, i + 3]).collect();
        tets.push([1000, 1001, 1002, 1003]);
        tets.push([0, 2000, 2001, 2002]);
        let r = drop_small_fragments(&mut tets);
        assert_eq!(r.pieces, 3);
        assert_eq!(r.dropped_pieces, 2);
        assert_eq!(r.dropped_tets, 2);
        assert_eq!(tets.len(), 200);
    }
}
