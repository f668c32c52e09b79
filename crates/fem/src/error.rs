//! The crate's error type.

use crate::math::Vec3;

/// What can go wrong building or solving a finite-element problem. Each variant names the
/// tet, vertex, node or point it is about.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FemError {
    /// A tet refers to a vertex past the end of the vertex list.
    #[error("tet {tet} refers to vertex {vertex}, but there are only {count} vertices")]
    VertexOutOfRange {
        /// Index of the tet.
        tet: usize,
        /// The vertex id it refers to.
        vertex: u32,
        /// Number of vertices given.
        count: usize,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} is not finite: {position:?}")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: usize,
        /// Its coordinates (m).
        position: Vec3,
    },
    /// A tet has (nearly) zero volume: its signed volume is below 1e-12 of its longest edge cubed.
    #[error("tet {tet} is degenerate: signed volume {volume:e} m^3")]
    DegenerateTet {
        /// Index of the tet.
        tet: usize,
        /// Its signed volume (m^3).
        volume: f64,
    },
    /// A tet is inverted (negative signed volume); list its vertices so that
    /// `(v1 - v0) . ((v2 - v0) x (v3 - v0)) > 0`. Inverted tets are rejected, not reoriented.
    #[error("tet {tet} is inverted: signed volume {volume:e} m^3 (swap two of its vertices)")]
    InvertedTet {
        /// Index of the tet.
        tet: usize,
        /// Its signed volume (m^3).
        volume: f64,
    },
    /// The mesh has no tets.
    #[error("the mesh has no tets")]
    EmptyMesh,
    /// A material parameter is out of its range.
    #[error("material {name} = {value} is out of range ({range})")]
    BadMaterial {
        /// Field name (`young`, `poisson`, `density`).
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range, in words.
        range: &'static str,
    },
    /// A time step that is not positive and finite.
    #[error("time step {dt} s is not positive and finite")]
    BadTimeStep {
        /// The step given (s).
        dt: f64,
    },
    /// An array has the wrong length for the mesh.
    #[error("{what} has {got} entries, expected {expected}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length the mesh needs.
        expected: usize,
    },
    /// The reduced stiffness matrix is not positive definite: the constraints do not hold the
    /// body against every rigid motion (or the mesh is disconnected from them).
    #[error("the stiffness matrix is not positive definite (pivot {pivot} of {free} free DOFs): the body is not held against rigid motion")]
    NotPositiveDefinite {
        /// Index of the failing pivot in the (permuted) free DOFs.
        pivot: usize,
        /// Number of free degrees of freedom.
        free: usize,
    },
    /// Every degree of freedom is constrained, or the sparse solver failed for another reason.
    #[error("sparse solver failed: {0}")]
    Solver(String),
    /// An element inverted (det F <= 0 at a quadrature point) under corotated kinematics, which
    /// has no rotation for it, or under neo-Hookean elasticity, whose energy is infinite there
    /// (the static solver reports `time` = load parameter times its final time).
    #[error("element {element} inverted (det F <= 0) at time {time:?} s")]
    ElementInverted {
        /// Index of the element (tet); the lowest one when several inverted.
        element: usize,
        /// Simulated time (s) of the step that inverted it, when a time integrator reports it.
        time: Option<f64>,
    },
    /// An element id past the end of the mesh's elements.
    #[error("element {element} does not exist: the mesh has {count} elements")]
    ElementOutOfRange {
        /// The id given.
        element: usize,
        /// Number of elements.
        count: usize,
    },
    /// A solver setting out of its range.
    #[error("solver option {name} = {value} is out of range ({range})")]
    BadOption {
        /// Field name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range, in words.
        range: &'static str,
    },
    /// Newton's method did not reach the tolerance within its iteration cap in a load step,
    /// even after the allowed step cuts.
    #[error("Newton did not converge at load step {step} (load {load}): residual {residual:e} N after {iterations} iterations, tolerance {tolerance:e} N")]
    NotConverged {
        /// Index of the load step (from 0) the failure happened in.
        step: usize,
        /// Load parameter in (0, 1] it was aiming at.
        load: f64,
        /// Iterations made.
        iterations: usize,
        /// Residual norm (N) at the end.
        residual: f64,
        /// Residual norm (N) it had to reach.
        tolerance: f64,
    },
    /// No step along the Newton direction lowered the total potential energy.
    #[error("line search failed at load step {step} (load {load}), iteration {iteration}: residual {residual:e} N")]
    LineSearchFailed {
        /// Index of the load step (from 0).
        step: usize,
        /// Load parameter in (0, 1] it was aiming at.
        load: f64,
        /// Newton iteration within the step.
        iteration: usize,
        /// Residual norm (N) where it stopped.
        residual: f64,
    },
    /// A sample point lies outside the mesh by more than the snapping tolerance.
    #[error("sample point {index} at {point:?} lies outside the mesh ({distance:e} m from the nearest element, tolerance {tolerance:e} m)")]
    PointOutside {
        /// Index of the point.
        index: usize,
        /// Its coordinates (m).
        point: Vec3,
        /// Distance to the nearest element found (m).
        distance: f64,
        /// The snapping tolerance (m).
        tolerance: f64,
    },
}
