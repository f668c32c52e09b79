//! Ball placement check against a closed triangle surface (parry3d `TriMesh` containment).

use crate::colliders::Colliders;
use crate::error::ContactError;
use crate::math::{is_finite, to_parry};
use crate::Vec3;
use parry3d_f64::math::Pose;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};

impl Colliders {
    /// Indices of the balls whose centre lies inside the closed surface given by `vertices` (m)
    /// and `triangles` (vertex ids, counter-clockwise seen from outside), e.g. the object's
    /// boundary at the start: a ball placed inside the object is a scene error. Uses a parry3d
    /// `TriMesh` with oriented pseudo-normals for the containment test.
    ///
    /// Errors when the surface has no triangles, a vertex is not finite, or a triangle uses a
    /// vertex id out of range.
    pub fn balls_inside_surface(
        &self,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<Vec<usize>, ContactError> {
        if triangles.is_empty() {
            return Err(ContactError::BadSurface("no triangles".into()));
        }
        if let Some(i) = vertices.iter().position(|v| !is_finite(*v)) {
            return Err(ContactError::BadSurface(format!(
                "vertex {i} is not finite: {:?}",
                vertices[i]
            )));
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&k| k as usize >= vertices.len()) {
                return Err(ContactError::BadSurface(format!(
                    "triangle {t} uses vertex {bad}, but there are only {} vertices",
                    vertices.len()
                )));
            }
        }
        let mesh = TriMesh::with_flags(
            vertices.iter().map(|&v| to_parry(v)).collect(),
            triangles.to_vec(),
            TriMeshFlags::ORIENTED,
        )
        .map_err(|e| ContactError::BadSurface(e.to_string()))?;
        Ok(self
            .balls
            .iter()
            .enumerate()
            .filter(|(_, b)| mesh.contains_point(&Pose::IDENTITY, b.pose.translation))
            .map(|(i, _)| i)
            .collect())
    }
}
