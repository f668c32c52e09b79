//! Particles at tet barycentres (docs/model.md section 1) and their families.

use crate::error::PhysicsError;
use crate::family::{Family, FamilyReport, NO_NEIGHBOUR};
use crate::math::Vec3;

/// The peridynamic discretisation: one particle per tet, with its rest position, volume, material
/// region and family. Particle index == tet index.
#[derive(Debug, Clone)]
pub struct Discretization {
    rest_positions: Vec<Vec3>,
    volumes: Vec<f64>,
    materials: Vec<u16>,
    horizon: f64,
    family: Family,
}

impl Discretization {
    /// Builds particles from tet barycentres (m), rest volumes (m^3) and face adjacency, with
    /// horizon `horizon` (m, `k * mean edge length`). All particles get material 0; see
    /// [`Discretization::set_materials`]. Particles left without bonds are listed in the report.
    pub fn from_tets(
        barycentres: &[Vec3],
        volumes: &[f64],
        adjacency: &[[u32; 4]],
        horizon: f64,
    ) -> Result<(Self, FamilyReport), PhysicsError> {
        let n = barycentres.len();
        for (what, got) in [("volumes", volumes.len()), ("adjacency", adjacency.len())] {
            if got != n {
                return Err(PhysicsError::LengthMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        if !(horizon.is_finite() && horizon > 0.0) {
            return Err(PhysicsError::BadHorizon(horizon));
        }
        for (i, (&v, x)) in volumes.iter().zip(barycentres).enumerate() {
            if !(v.is_finite() && v > 0.0 && x.iter().all(|c| c.is_finite())) {
                return Err(PhysicsError::BadParticle {
                    particle: i,
                    volume: v,
                });
            }
        }
        for (t, adj) in adjacency.iter().enumerate() {
            for (f, &u) in adj.iter().enumerate() {
                if u != NO_NEIGHBOUR && u as usize >= n {
                    return Err(PhysicsError::BadAdjacency {
                        tet: t,
                        face: f,
                        neighbour: u,
                    });
                }
            }
        }
        let (family, report) = Family::build(barycentres, adjacency, horizon)?;
        Ok((
            Discretization {
                rest_positions: barycentres.to_vec(),
                volumes: volumes.to_vec(),
                materials: vec![0; n],
                horizon,
                family,
            },
            report,
        ))
    }

    /// A discretisation from its parts, the family built by the caller over `rest_positions`.
    pub(crate) fn from_parts(
        rest_positions: Vec<Vec3>,
        volumes: Vec<f64>,
        materials: Vec<u16>,
        horizon: f64,
        family: Family,
    ) -> Self {
        Discretization {
            rest_positions,
            volumes,
            materials,
            horizon,
            family,
        }
    }

    /// Assigns a material (region) id to every particle; checked against the material list when
    /// a model is built.
    pub fn set_materials(&mut self, ids: &[u16]) -> Result<(), PhysicsError> {
        if ids.len() != self.len() {
            return Err(PhysicsError::LengthMismatch {
                what: "material ids",
                expected: self.len(),
                got: ids.len(),
            });
        }
        self.materials.copy_from_slice(ids);
        Ok(())
    }

    /// Checks every particle's material id against `count` materials.
    pub fn check_material_ids(&self, count: usize) -> Result<(), PhysicsError> {
        match self.materials.iter().position(|&id| id as usize >= count) {
            Some(i) => Err(PhysicsError::UnknownMaterial {
                particle: i,
                material: self.materials[i],
                count,
            }),
            None => Ok(()),
        }
    }

    /// Panics unless `y` (and `forces`, when given) hold one entry per particle: a caller's
    /// programming error, checked once at a model's entry.
    #[track_caller]
    pub(crate) fn check_slices(&self, y: &[Vec3], forces: Option<&[Vec3]>) {
        let n = self.len();
        assert_eq!(y.len(), n, "positions: one per particle");
        if let Some(f) = forces {
            assert_eq!(f.len(), n, "forces: one per particle");
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.volumes.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.volumes.is_empty()
    }

    /// Rest positions `X_i` (m).
    pub fn rest_positions(&self) -> &[Vec3] {
        &self.rest_positions
    }

    /// Volumes `V_i` (m^3).
    pub fn volumes(&self) -> &[f64] {
        &self.volumes
    }

    /// Material id of each particle.
    pub fn materials(&self) -> &[u16] {
        &self.materials
    }

    /// Horizon `delta` (m).
    pub fn horizon(&self) -> f64 {
        self.horizon
    }

    /// The bonds.
    pub fn family(&self) -> &Family {
        &self.family
    }

    /// Heap bytes of particle and bond arrays.
    pub fn memory_bytes(&self) -> usize {
        let Discretization {
            rest_positions,
            volumes,
            materials,
            horizon: _,
            family,
        } = self;
        rest_positions.len() * 24 + volumes.len() * 8 + materials.len() * 2 + family.memory_bytes()
    }
}
