//! A problem: mesh, material, body force and boundary conditions.

use std::fmt;
use std::sync::Arc;

use crate::error::FemError;
use crate::material::Material;
use crate::math::Vec3;
use crate::mesh::Mesh;

/// Prescribed motion: current position (m) of a node from its rest position (m) and time (s).
pub type Motion = Arc<dyn Fn(Vec3, f64) -> Vec3 + Send + Sync>;

/// How one node is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Constraint {
    /// Moves freely.
    Free,
    /// Held at its rest position (all three components).
    Fixed,
    /// Follows the motion with this index into [`Problem::motions`].
    Prescribed(u32),
}

/// Everything a solver needs: mesh, material, gravity and the constraint of every node.
///
/// Constraints are set by predicates on rest position; a later call overrides an earlier one
/// for the nodes both select. Quadratic meshes' edge nodes are selected like vertices, by their
/// rest position.
#[derive(Clone)]
pub struct Problem {
    mesh: Mesh,
    material: Material,
    gravity: Vec3,
    constraints: Vec<Constraint>,
    motions: Vec<Motion>,
}

impl fmt::Debug for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Problem")
            .field("order", &self.mesh.order())
            .field("nodes", &self.mesh.node_count())
            .field("elements", &self.mesh.element_count())
            .field("material", &self.material)
            .field("gravity", &self.gravity)
            .field("motions", &self.motions.len())
            .finish()
    }
}

impl Problem {
    /// A problem with every node free and no gravity; checks the material.
    pub fn new(mesh: Mesh, material: Material) -> Result<Self, FemError> {
        material.validate()?;
        let constraints = vec![Constraint::Free; mesh.node_count()];
        Ok(Self {
            mesh,
            material,
            gravity: [0.0; 3],
            constraints,
            motions: Vec::new(),
        })
    }

    /// Sets the gravitational acceleration (m/s^2), a body force of `density * gravity` (N/m^3).
    pub fn with_gravity(mut self, gravity: Vec3) -> Self {
        self.gravity = gravity;
        self
    }

    /// Fixes (holds at rest, all components) every node whose rest position (m) satisfies
    /// `select`; returns how many nodes it selected.
    pub fn fix_where(&mut self, select: impl Fn(Vec3) -> bool) -> usize {
        self.set_where(select, Constraint::Fixed)
    }

    /// Makes every node whose rest position (m) satisfies `select` follow `motion`, which maps
    /// (rest position (m), time (s)) to the current position (m); returns how many nodes it
    /// selected. For the static solver the displacement is `motion(X, t) - X` at the time it
    /// is asked for.
    pub fn prescribe_where(
        &mut self,
        select: impl Fn(Vec3) -> bool,
        motion: impl Fn(Vec3, f64) -> Vec3 + Send + Sync + 'static,
    ) -> usize {
        self.motions.push(Arc::new(motion));
        let id = (self.motions.len() - 1) as u32;
        self.set_where(select, Constraint::Prescribed(id))
    }

    /// Frees every node whose rest position satisfies `select`; returns how many.
    pub fn free_where(&mut self, select: impl Fn(Vec3) -> bool) -> usize {
        self.set_where(select, Constraint::Free)
    }

    fn set_where(&mut self, select: impl Fn(Vec3) -> bool, c: Constraint) -> usize {
        let mut count = 0;
        for (slot, &x) in self.constraints.iter_mut().zip(self.mesh.nodes()) {
            if select(x) {
                *slot = c;
                count += 1;
            }
        }
        count
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The material.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// Gravitational acceleration (m/s^2).
    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Constraint of each node.
    pub fn constraints(&self) -> &[Constraint] {
        &self.constraints
    }

    /// The prescribed motions, indexed by [`Constraint::Prescribed`].
    pub fn motions(&self) -> &[Motion] {
        &self.motions
    }

    /// Position (m) a constrained node must have at time `time` (s); `None` for a free node.
    pub fn held_position(&self, node: usize, time: f64) -> Option<Vec3> {
        let rest = self.mesh.nodes()[node];
        match self.constraints[node] {
            Constraint::Free => None,
            Constraint::Fixed => Some(rest),
            Constraint::Prescribed(m) => Some((self.motions[m as usize])(rest, time)),
        }
    }
}
