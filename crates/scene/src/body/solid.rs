//! A tet solid as a [`Body`]: the [`Driver`] steps it; a frame is the cut mesh's surface placed
//! from the particles, small pieces split off as debris, the particles themselves, and the
//! counts of `run.json`.

use std::path::Path;
use std::time::{Duration, Instant};

use perifrac_checkpoint::{Reader, Writer};
use perifrac_io::SurfaceRef;
use perifrac_topology::Surface;

use super::{Body, BodySummary, Head, Plan, StepError};
use crate::debris::split_debris;
use crate::driver::{Driver, StageTimes};
use crate::environment::Loads;
use crate::error::SceneError;
use crate::fragments::FragmentBirth;
use crate::manifest::{
    balls_json, grounds_json, BodyJson, Bounds, CorrectionJson, FrameBodyJson, FrameJson,
    FromEnergyJson, GhostsJson, IterationsJson, SearchJson, SelfContactJson, SolidFrameJson,
    SolidJson, SolverJson, MAIN_MASS_SHARE,
};
use crate::setup::{bounds, ModelKind, OutputOptions, Setup, SetupInfo};
use crate::sinks::{FrameView, ParticlesView, SinkChoice, Sinks};
use perifrac_physics::IntegratorKind;

/// A tet solid's part of a run's summary.
#[derive(Debug, Clone, PartialEq)]
pub struct SolidSummary {
    /// Bonds broken (pairs).
    pub broken_bonds: u64,
    /// Crack triangles in the last surface (both sides counted).
    pub crack_triangles: usize,
    /// Kinetic energy of the dynamic balls at the end (J).
    pub ball_kinetic_energy: f64,
    /// Wall time per stage (s).
    pub stage_times: StageTimes,
    /// The integrator's counters (iterations, factorisations and their wall times for the
    /// implicit one; zeros for the explicit one).
    pub solver: perifrac_physics::SolverStats,
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Self contact, when the scene has it: pair-list builds, and the most pairs in contact
    /// in a step with the deepest overlap (m, and as a share of the contact distance).
    pub self_contact: Option<(u64, perifrac_contact::SelfContactStats)>,
    /// The work the scene's `[[load]]` tables did (J), when it has some.
    pub load_work: Option<f64>,
    /// Bonds (pairs) at the start.
    pub bonds: u64,
    /// Per material, the largest share of its fracture threshold a bond reached (1), `None`
    /// for one that cannot break; `None` when nothing can.
    pub peak_threshold_shares: Option<Vec<Option<f64>>>,
}

/// A tet solid being run.
pub(crate) struct Solid {
    driver: Driver,
    options: OutputOptions,
    info: SetupInfo,
    /// Crack triangles of the last frame written.
    crack_triangles: usize,
}

/// The solid body of `setup` and the plan around it.
pub(crate) fn split(setup: Setup) -> (Box<dyn Body>, Plan) {
    let Setup {
        scene_path,
        scene_text,
        driver,
        frames,
        steps_per_frame,
        output,
        info,
    } = setup;
    let plan = Plan {
        scene_path,
        scene_text,
        frames,
        steps_per_frame,
        dt: info.dt,
        fps: output.fps,
        checkpoints: output.checkpoints,
        sinks: SinkChoice {
            povray: output.povray,
            particles: output.particles,
            debris: output.debris_tets > 0,
            usd: output.usd,
        },
    };
    let body = Solid {
        driver,
        options: output,
        info,
        crack_triangles: 0,
    };
    (Box::new(body), plan)
}

impl Body for Solid {
    fn head(&self) -> Head {
        let info = &self.info;
        let grounds = grounds_json(self.driver.colliders());
        Head {
            up: info.up,
            rest_bounds: Bounds::of(info.rest_bounds),
            grounds,
            dt: info.dt,
            dt_limit: info.dt_limit,
            mass: info.mass,
            body: BodyJson::Solid(SolidJson {
                particles: info.particles,
                bonds: info.bonds,
                horizon: info.horizon,
                solver: (info.model != ModelKind::Chen
                    || info.integrator != IntegratorKind::Explicit)
                    .then(|| SolverJson {
                        model: info.model.name().into(),
                        integrator: info.integrator.name().into(),
                    }),
                correction: info.correction.map(|c| CorrectionJson {
                    dilatation: c.dilatation.into(),
                    deviatoric: c.deviatoric.into(),
                    ghosts: info.ghosts.as_ref().map(|g| GhostsJson {
                        count: g.ghosts,
                        bonds: g.bonds,
                        affine_fallbacks: g.affine_fallbacks,
                        short_bonds: g.short,
                        gain: g.gain.into(),
                    }),
                }),
                from_energy: info
                    .from_energy
                    .iter()
                    .map(|e| FromEnergyJson {
                        material: e.material,
                        fracture_energy: e.fracture_energy,
                        s_crit: e.s_crit,
                    })
                    .collect(),
            }),
        }
    }

    fn identify(&self, w: &mut Writer) {
        w.usize(self.info.particles);
        w.usize(self.info.bonds);
        let mesh = self.driver.mesh();
        w.array(mesh.rest_positions());
        w.array(mesh.tets());
    }

    fn step(&mut self) -> Result<(), StepError> {
        self.driver.step().map(|_| ()).map_err(StepError::Solid)
    }

    fn time(&self) -> f64 {
        self.driver.solver().time()
    }

    fn steps(&self) -> u64 {
        self.driver.solver().steps()
    }

    fn broken(&self) -> u64 {
        self.driver.broken_bonds()
    }

    fn frame(&mut self, index: usize, sinks: &Sinks, dir: &Path) -> Result<FrameJson, SceneError> {
        let started = Instant::now();
        let frame = self.write_frame(index, sinks, dir);
        self.driver.add_output_time(started.elapsed());
        frame
    }

    fn births(&self) -> Vec<FragmentBirth> {
        self.driver.fragment_births().to_vec()
    }

    fn save(&self, w: &mut Writer) {
        self.driver.save(w);
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), String> {
        self.driver.restore(r).map_err(|e| e.to_string())
    }

    fn add_output_time(&mut self, d: Duration) {
        self.driver.add_output_time(d);
    }

    fn summary(&mut self) -> BodySummary {
        let d = &self.driver;
        BodySummary::Solid(SolidSummary {
            broken_bonds: d.broken_bonds(),
            crack_triangles: self.crack_triangles,
            ball_kinetic_energy: d.colliders().map_or(0.0, |c| c.kinetic_energy()),
            stage_times: d.stage_times(),
            solver: d.solver().stats(),
            integrator: d.solver().integrator(),
            self_contact: d
                .self_contact()
                .map(|c| (c.rebuilds(), d.self_contact_deepest())),
            load_work: d.influences().get::<Loads>().map(Loads::work),
            bonds: d.bonds(),
            peak_threshold_shares: d.peak_threshold_shares(),
        })
    }
}

impl Solid {
    /// The frame's surface, debris and particles through `sinks`, and its record.
    fn write_frame(
        &mut self,
        index: usize,
        sinks: &Sinks,
        dir: &Path,
    ) -> Result<FrameJson, SceneError> {
        let driver = &mut self.driver;
        let pieces = driver.mesh().pieces();
        driver.place_surface(&pieces);
        let ids = driver.fragment_ids(&pieces, index);
        let mesh = driver.mesh();
        let mut surface = mesh.surface_of(&pieces);
        let debris = if self.options.debris_tets > 0 {
            let volumes = mesh.rest_volumes();
            let solver = driver.solver();
            let (keep, debris) = split_debris(
                &pieces,
                self.options.debris_tets,
                &ids,
                driver.masses(),
                solver.positions(),
                solver.velocities(),
                &volumes,
            );
            surface.retain_pieces(&keep);
            Some(debris)
        } else {
            None
        };
        if let Some(smoothing) = &self.options.smooth_cracks {
            surface.smooth_cracks(smoothing);
        }
        let velocities = mesh.vertex_velocities(driver.masses(), driver.solver().velocities());
        let shaded = mesh.shade(&surface, &velocities, &mesh.shading_options());
        let face_fragment: Vec<u32> = shaded.piece.iter().map(|&p| ids[p as usize]).collect();
        let (damage, fragment) = if sinks.wants_particles() {
            let fragment: Vec<f64> = pieces
                .piece_of_tet
                .iter()
                .map(|&p| f64::from(ids[p as usize]))
                .collect();
            (driver.damage(), fragment)
        } else {
            (Vec::new(), Vec::new())
        };
        let view = FrameView {
            index,
            surface: SurfaceRef {
                vertices: &shaded.vertices,
                faces: &shaded.faces,
                crack: Some(&shaded.crack),
                normals: Some(&shaded.normals),
                velocities: Some(&shaded.velocities),
                uv: Some(&shaded.uv),
                // The surface vertex each shading copy belongs to: welding by it gives every
                // piece's closed 2-manifold surface.
                vertex_ids: Some(&shaded.source),
                fragment: Some(&face_fragment),
                colors: None,
            },
            particles: sinks.wants_particles().then(|| ParticlesView {
                positions: driver.solver().positions(),
                damage: &damage,
                mass: driver.masses(),
                fragment: &fragment,
            }),
            debris: debris.as_ref(),
        };
        let files = sinks.write(dir, &view)?;
        let (mut lo, mut hi) = bounds(&surface.vertices);
        if let Some(d) = &debris {
            for (p, r) in d.points.iter().zip(&d.radius) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k] - r);
                    hi[k] = hi[k].max(p[k] + r);
                }
            }
        }
        let piece_mass = piece_masses(&pieces.piece_of_tet, pieces.count, driver.masses());
        let crack_triangles = surface.crack.iter().filter(|&&c| c != 0).count();
        self.crack_triangles = crack_triangles;
        let balls = balls_json(driver.colliders());
        let (time, step) = (driver.solver().time(), driver.solver().steps());
        let kinetic_energy = driver.solver().kinetic_energy();
        // the energy first: the counters are read after it, as they always were
        let elastic_energy = driver.solver_mut().elastic_energy();
        let solver = driver.solver();
        let stats = solver.stats();
        let integrator = solver.integrator();
        Ok(FrameJson {
            index,
            time,
            step,
            surface: files.surface,
            povray: files.povray,
            balls,
            bounds: Bounds { min: lo, max: hi },
            main_bounds: main_bounds(&surface, &piece_mass),
            fragments: pieces.count,
            kinetic_energy,
            elastic_energy,
            search: (integrator == IntegratorKind::EventSearch).then_some(SearchJson {
                substeps: stats.substeps,
                rejected: stats.rejected,
            }),
            body: FrameBodyJson::Solid(SolidFrameJson {
                particles: files.particles,
                debris: files.debris,
                broken_bonds: driver.broken_bonds(),
                crack_triangles,
                implicit: (integrator == IntegratorKind::Implicit).then_some(IterationsJson {
                    iterations: stats.iterations,
                    capped_steps: stats.capped_steps,
                    evaluations: stats.evaluations,
                    factorizations: stats.factorizations,
                    factor_bytes: stats.factor_bytes,
                }),
                self_contact: driver.self_contact().map(|_| {
                    let deepest = driver.self_contact_deepest();
                    SelfContactJson {
                        pairs: driver.self_contact_last().pairs,
                        deepest: deepest.max_overlap,
                        deepest_share: deepest.max_overlap_share,
                    }
                }),
                load_work: driver.influences().get::<Loads>().map(Loads::work),
                peak_threshold_share: driver.peak_threshold_shares(),
            }),
        })
    }
}

/// Mass (kg) of each of `count` pieces.
fn piece_masses(piece_of_tet: &[u32], count: usize, masses: &[f64]) -> Vec<f64> {
    let mut m = vec![0.0; count];
    for (&p, &mass) in piece_of_tet.iter().zip(masses) {
        m[p as usize] += mass;
    }
    m
}

/// Bounds of the surface faces of the heaviest pieces that together reach
/// [`MAIN_MASS_SHARE`] of the total mass (ties broken by piece id, so it is deterministic).
fn main_bounds(surface: &Surface, piece_mass: &[f64]) -> Bounds {
    let total: f64 = piece_mass.iter().sum();
    let mut order: Vec<usize> = (0..piece_mass.len()).collect();
    order.sort_by(|&a, &b| piece_mass[b].total_cmp(&piece_mass[a]).then(a.cmp(&b)));
    let mut keep = vec![false; piece_mass.len()];
    let mut sum = 0.0;
    for p in order {
        keep[p] = true;
        sum += piece_mass[p];
        if sum >= MAIN_MASS_SHARE * total {
            break;
        }
    }
    let empty = Bounds {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };
    surface
        .faces
        .iter()
        .zip(&surface.piece)
        .filter(|(_, &p)| keep[p as usize])
        .flat_map(|(face, _)| face.map(|v| surface.vertices[v as usize]))
        .fold(empty, |b, p| Bounds {
            min: std::array::from_fn(|k| b.min[k].min(p[k])),
            max: std::array::from_fn(|k| b.max[k].max(p[k])),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn main_bounds_skip_light_debris() {
        // Piece 0 (heavy) spans the unit cube; piece 1 (1% of the mass) sits far away.
        let surface = Surface {
            vertices: vec![
                [0.0; 3],
                [1.0, 1.0, 1.0],
                [0.0, 1.0, 0.0],
                [9.0; 3],
                [9.5; 3],
                [9.0, 9.5, 9.0],
            ],
            vertex_ids: (0..6).collect(),
            faces: vec![[0, 1, 2], [3, 4, 5]],
            crack: vec![0, 1],
            piece: vec![0, 1],
            midpoints: Vec::new(),
        };
        let b = main_bounds(&surface, &[99.0, 1.0]);
        assert_eq!(
            b,
            Bounds {
                min: [0.0; 3],
                max: [1.0; 3]
            }
        );
        // With two equal pieces both are needed to reach 90%.
        let b = main_bounds(&surface, &[1.0, 1.0]);
        assert_eq!(b.max, [9.5; 3]);
    }
}
