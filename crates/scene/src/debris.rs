//! Debris: pieces of at most `[output] debris_tets` tets, written as points
//! (`frames/debris_NNNN.ply`) rather than as surfaces.
//!
//! A piece of one to a few tets has the mesh's shape, not the fracture's: written as a surface
//! it reads as a flat tile (confetti). As a point at its centre of mass, with the radius of the
//! ball of its volume, its velocity and its fragment id, it is what renderers instance shards
//! or grit onto (`perifrac render` draws balls; the USD cache holds a `Points` prim).

use perifrac_topology::Pieces;

/// The debris of one frame, in fragment-id order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Debris {
    /// Centre of mass of each debris piece (m).
    pub points: Vec<[f64; 3]>,
    /// Radius of the ball with the piece's rest volume (m).
    pub radius: Vec<f64>,
    /// Velocity of the centre of mass (m/s).
    pub velocity: Vec<[f64; 3]>,
    /// Mass (kg).
    pub mass: Vec<f64>,
    /// Stable fragment id.
    pub fragment: Vec<u32>,
}

/// Splits `pieces` into those written as surfaces (`true` in the returned mask, indexed by
/// piece id) and debris: pieces of at most `max_tets` tets (none when 0). Particle `i` is the
/// particle of tet `i`; `volumes` are the tets' rest volumes (m^3), `ids` the pieces' stable
/// fragment ids.
pub fn split_debris(
    pieces: &Pieces,
    max_tets: usize,
    ids: &[u32],
    masses: &[f64],
    positions: &[[f64; 3]],
    velocities: &[[f64; 3]],
    volumes: &[f64],
) -> (Vec<bool>, Debris) {
    let mut tets = vec![0usize; pieces.count];
    for &p in &pieces.piece_of_tet {
        tets[p as usize] += 1;
    }
    let keep: Vec<bool> = tets.iter().map(|&n| n > max_tets).collect();
    // Sums per debris piece: mass, mass-weighted position and velocity, volume.
    let mut slot = vec![usize::MAX; pieces.count];
    let mut order: Vec<usize> = (0..pieces.count).filter(|&p| !keep[p]).collect();
    order.sort_by_key(|&p| ids[p]);
    for (k, &p) in order.iter().enumerate() {
        slot[p] = k;
    }
    let n = order.len();
    let mut mass = vec![0.0; n];
    let mut moment = vec![[0.0; 3]; n];
    let mut momentum = vec![[0.0; 3]; n];
    let mut volume = vec![0.0; n];
    for (t, &p) in pieces.piece_of_tet.iter().enumerate() {
        let k = slot[p as usize];
        if k == usize::MAX {
            continue;
        }
        let m = masses[t];
        mass[k] += m;
        volume[k] += volumes[t];
        for d in 0..3 {
            moment[k][d] += m * positions[t][d];
            momentum[k][d] += m * velocities[t][d];
        }
    }
    let per_mass = |sum: [f64; 3], m: f64| sum.map(|s| if m > 0.0 { s / m } else { 0.0 });
    let debris = Debris {
        points: (0..n).map(|k| per_mass(moment[k], mass[k])).collect(),
        radius: volume
            .iter()
            .map(|&v| (3.0 * v / (4.0 * std::f64::consts::PI)).cbrt())
            .collect(),
        velocity: (0..n).map(|k| per_mass(momentum[k], mass[k])).collect(),
        fragment: order.iter().map(|&p| ids[p]).collect(),
        mass,
    };
    (keep, debris)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_pieces_become_points_at_their_centre_of_mass() {
        // Piece 0: tets 0..4 (kept at max 3); piece 1: tets 4, 5; piece 2: tet 6.
        let pieces = Pieces {
            count: 3,
            piece_of_tet: vec![0, 0, 0, 0, 1, 1, 2],
        };
        let ids = [7, 9, 8];
        let masses = [1.0, 1.0, 1.0, 1.0, 1.0, 3.0, 2.0];
        let positions = [
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [1.0, 2.0, 3.0],
        ];
        let velocities = [
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [0.0, 4.0, 0.0],
            [0.0, 0.0, 0.0],
            [5.0, 0.0, 0.0],
        ];
        let volumes = [
            1.0,
            1.0,
            1.0,
            1.0,
            0.5,
            0.5,
            4.0 * std::f64::consts::PI / 3.0,
        ];
        let (keep, d) = split_debris(&pieces, 3, &ids, &masses, &positions, &velocities, &volumes);
        assert_eq!(keep, vec![true, false, false]);
        // Fragment-id order: piece 2 (id 8) before piece 1 (id 9).
        assert_eq!(d.fragment, vec![8, 9]);
        assert_eq!(d.points, vec![[1.0, 2.0, 3.0], [3.0, 0.0, 0.0]]);
        assert_eq!(d.velocity, vec![[5.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        assert_eq!(d.mass, vec![2.0, 4.0]);
        assert!((d.radius[0] - 1.0).abs() < 1e-15);
        assert!((d.radius[1] - (0.75 / std::f64::consts::PI).cbrt()).abs() < 1e-15);
        // 0 tets: nothing is debris.
        let (keep, d) = split_debris(&pieces, 0, &ids, &masses, &positions, &velocities, &volumes);
        assert_eq!(keep, vec![true; 3]);
        assert!(d.points.is_empty());
    }
}
