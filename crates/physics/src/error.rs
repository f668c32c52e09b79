//! Typed errors of the physics crate.

use thiserror::Error;

/// Everything that can go wrong while setting up or running the peridynamic solver.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PhysicsError {
    /// Input arrays disagree in length.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Entries expected: one per particle (tet), or per bond where `what` says so.
        expected: usize,
        /// Length supplied.
        got: usize,
    },
    /// A particle (tet) has zero, negative or non-finite volume, or a non-finite position.
    #[error("particle {particle}: volume {volume} must be finite and positive, position finite")]
    BadParticle {
        /// Particle (tet) index.
        particle: usize,
        /// Its volume in m^3.
        volume: f64,
    },
    /// A face-adjacency entry points outside the particle range.
    #[error("tet {tet}, face {face}: neighbour {neighbour} out of range")]
    BadAdjacency {
        /// Tet index.
        tet: usize,
        /// Local face 0..4.
        face: usize,
        /// The offending entry.
        neighbour: u32,
    },
    /// The horizon is not a finite positive length.
    #[error("horizon {0} m must be finite and positive")]
    BadHorizon(f64),
    /// The horizon is so small that no particle has a bond.
    #[error("horizon {horizon} m is too small: no particle has a bond (nearest barycentres are further apart)")]
    HorizonTooSmall {
        /// The horizon in m.
        horizon: f64,
    },
    /// More bonds than the 32-bit bond index can address.
    #[error("{0} bonds exceed the 32-bit bond index")]
    TooManyBonds(usize),
    /// A material parameter is out of its admissible range.
    #[error("material {material}: {message}")]
    BadMaterial {
        /// Material (region) index.
        material: usize,
        /// What is wrong, with the value.
        message: String,
    },
    /// A particle names a material that does not exist.
    #[error("particle {particle} uses material {material}, but only {count} are defined")]
    UnknownMaterial {
        /// Particle index.
        particle: usize,
        /// Its material id.
        material: u16,
        /// Number of materials given.
        count: usize,
    },
    /// An anchor or load names a particle that does not exist.
    #[error("{what}: particle {particle} out of range ({count} particles)")]
    BadParticleIndex {
        /// Which load.
        what: &'static str,
        /// The index given.
        particle: usize,
        /// Number of particles.
        count: usize,
    },
    /// A checkpoint or snapshot that does not fit this simulation.
    #[error("checkpoint: {0}")]
    Checkpoint(#[from] perifrac_checkpoint::CheckpointError),
    /// A load or integrator setting out of range.
    #[error("{0}")]
    BadSetting(String),
    /// A time step that is not finite and positive.
    #[error("time step {0} s must be finite and positive")]
    BadTimeStep(f64),
    /// The explicit integration diverged (step too large, or a runaway load).
    #[error("unstable at step {step}: particle {particle} moved {displacement} m in one step (limit {limit} m, or non-finite); reduce the time step")]
    Unstable {
        /// Step counter when detected.
        step: u64,
        /// A particle where it was detected.
        particle: usize,
        /// Its displacement in that step in m (NaN or inf when non-finite).
        displacement: f64,
        /// The guard's limit in m.
        limit: f64,
    },
    /// The implicit step's matrix could not be factored.
    #[error("factorisation failed: {0}")]
    Factorization(String),
    /// The implicit step found no decrease of its objective along its search direction before
    /// converging.
    #[error("implicit step {step}: no decrease of the objective after {halvings} halvings of the step at iteration {iteration} (predicted decrease {predicted:e} J of {phi:e} J); try a smaller time step")]
    Stalled {
        /// Step counter.
        step: u64,
        /// Iteration within the step.
        iteration: usize,
        /// Line-search halvings tried.
        halvings: usize,
        /// Decrease the direction predicted (J).
        predicted: f64,
        /// The objective's value (J).
        phi: f64,
    },
    /// The implicit step's objective or its gradient is not finite where the step starts.
    #[error("implicit step {step}: the objective ({phi:e} J) or its gradient is not finite at the predicted positions")]
    NotFinite {
        /// Step counter.
        step: u64,
        /// The objective's value (J).
        phi: f64,
    },
    /// A setting refers to something the model cannot do.
    #[error("{0}")]
    Unsupported(String),
}
