//! Helpers shared by the integration tests.
#![allow(dead_code)]

use perifrac_fem::{Mat3, Material, Mesh, Problem, Vec3};

/// xorshift64: a deterministic generator so the tests need no `rand`.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }
}

/// The material of the benchmark's cantilever (issue 6): E = 1e8 Pa, nu = 0.3, rho = 1000.
pub fn cantilever_material() -> Material {
    Material::new(1e8, 0.3, 1000.0).unwrap()
}

/// Kuhn-lattice box [0,1]^3 cut into `n^3` cells, interior vertices moved by up to `jitter` of
/// a cell (still positively oriented for jitter <= 0.2).
pub fn jittered_box(n: usize, jitter: f64, seed: u64) -> (Vec<Vec3>, Vec<[u32; 4]>) {
    let (mut v, t) = perifrac_topology::primitives::box_data([0.0; 3], [1.0; 3], [n; 3]);
    let h = 1.0 / n as f64;
    let mut rng = Rng(seed);
    for p in &mut v {
        if p.iter().all(|&c| c > 1e-9 && c < 1.0 - 1e-9) {
            for c in p.iter_mut() {
                *c += jitter * h * rng.signed();
            }
        }
    }
    (v, t)
}

/// Whether a rest point is on the boundary of the unit cube.
pub fn on_unit_cube_boundary(p: Vec3) -> bool {
    p.iter()
        .any(|&c| c.abs() < 1e-12 || (c - 1.0).abs() < 1e-12)
}

/// The cantilever of the benchmark: 1 x 0.1 x 0.1 m bar along x (y, z in [-0.05, 0.05]),
/// `cells_along` Kuhn cells along x, clamped at x = 0, gravity 9.81 m/s^2 along -z.
pub fn cantilever(cells_along: usize, quadratic: bool) -> Problem {
    let (v, t) = perifrac_topology::primitives::bar_data(1.0, [0.1, 0.1], cells_along);
    let mesh = if quadratic {
        Mesh::quadratic(v, t)
    } else {
        Mesh::linear(v, t)
    }
    .unwrap();
    let mut p = Problem::new(mesh, cantilever_material())
        .unwrap()
        .with_gravity([0.0, 0.0, -9.81]);
    assert!(p.fix_where(|x| x[0] <= 1e-12) > 0);
    p
}

/// Rotation by `angle` (rad) about the unit `axis`.
pub fn rotation(axis: Vec3, angle: f64) -> Mat3 {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|c| c / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// `m v`.
pub fn apply(m: &Mat3, v: Vec3) -> Vec3 {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// Largest component magnitude over a field.
pub fn max_abs(field: &[Vec3]) -> f64 {
    field.iter().flatten().fold(0.0, |a, &b| a.max(b.abs()))
}
