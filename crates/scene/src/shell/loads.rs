//! A shell scene's `[[load]]` tables as forces on its vertices: a traction on the rim, a
//! pressure on the surface, a body force through the thickness.

use perifrac_physics::math::{cross, norm, scale, sub};
use perifrac_shell::{ShellLoad, ShellMesh, Vec3};

use crate::error::SceneError;
use crate::schema::LoadSpec;
use crate::setup::check::Ctx;
use crate::setup::loads::{select, timing};

/// The loads of `specs` on the rest `mesh` of thickness `thickness` (m), with vertex `masses`
/// (kg) of a material of `density` (kg/m^3), as forces (N) at full strength:
/// - `traction` (Pa) on the rim edges (boundary edges) whose midpoint lies in the region: the
///   traction times the edge's length times the thickness, half to each end;
/// - `pressure` (Pa) on the triangles whose centroid lies in the region, against their normal
///   (outward on a closed surface wound outward, so a positive pressure squeezes and a negative
///   one inflates): the pressure times the area, a third to each corner;
/// - `body_force` (N/m^3) on the vertices in the region, times each one's volume (its mass
///   over the density).
pub(super) fn shell_loads(
    ctx: &Ctx,
    specs: &[LoadSpec],
    mesh: &ShellMesh,
    thickness: f64,
    masses: &[f64],
    density: f64,
) -> Result<Vec<ShellLoad>, SceneError> {
    let x = mesh.vertices();
    let mut out = Vec::with_capacity(specs.len());
    for (k, l) in specs.iter().enumerate() {
        let key = format!("load[{k}]");
        if let Some(r) = &l.region {
            ctx.region(&format!("{key}.region"), r)?;
        }
        let (ramp, until) = timing(ctx, &key, l)?;
        let inside = |p: Vec3| l.region.as_ref().is_none_or(|r| r.contains(p));
        let mut force = vec![[0.0; 3]; x.len()];
        let mut any = false;
        let mut push = |i: u32, f: Vec3| {
            let v = &mut force[i as usize];
            *v = [v[0] + f[0], v[1] + f[1], v[2] + f[2]];
            any = true;
        };
        let what = match (l.traction, l.pressure, l.body_force) {
            (Some(t), None, None) => {
                let t = ctx.finite3(&format!("{key}.traction"), t)?;
                for e in mesh.edges().iter().filter(|e| e.is_boundary()) {
                    let [a, b] = e.v.map(|i| x[i as usize]);
                    if inside(scale([a[0] + b[0], a[1] + b[1], a[2] + b[2]], 0.5)) {
                        let f = scale(t, 0.5 * norm(sub(b, a)) * thickness);
                        push(e.v[0], f);
                        push(e.v[1], f);
                    }
                }
                "selects no rim edge: no boundary edge of the surface has its midpoint in the box"
            }
            (None, Some(p), None) => {
                if !p.is_finite() {
                    return Err(ctx.err(format!("{key}.pressure"), format!("{p} must be finite")));
                }
                for t in mesh.triangles() {
                    let [a, b, c] = t.map(|i| x[i as usize]);
                    let centroid = [0, 1, 2].map(|d| (a[d] + b[d] + c[d]) / 3.0);
                    if inside(centroid) {
                        // half the cross product is the area vector along the winding's normal
                        let f = scale(cross(sub(b, a), sub(c, a)), -p / 6.0);
                        for &i in t {
                            push(i, f);
                        }
                    }
                }
                "selects no triangle: no triangle of the surface has its centroid in the box"
            }
            (None, None, Some(b)) => {
                let b = ctx.finite3(&format!("{key}.body_force"), b)?;
                for i in select(ctx, &format!("{key}.region"), x, l.region.as_ref())? {
                    push(i, scale(b, masses[i as usize] / density));
                }
                ""
            }
            _ => {
                return Err(ctx.err(
                    &key,
                    "give exactly one of traction (Pa), pressure (Pa) and body_force (N/m^3)",
                ))
            }
        };
        if !any {
            return Err(ctx.err(format!("{key}.region"), what));
        }
        let vertices: Vec<u32> = (0..x.len() as u32)
            .filter(|&i| force[i as usize] != [0.0; 3])
            .collect();
        let forces = vertices.iter().map(|&i| force[i as usize]).collect();
        out.push(ShellLoad {
            vertices,
            forces,
            ramp,
            until,
        });
    }
    Ok(out)
}
