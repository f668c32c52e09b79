//! A load written outside the scene crate plugs into the driver's list of influences: a
//! uniform force on every particle changes the body's momentum by exactly its impulse, in an
//! explicit step and in an implicit one, and the scene's own colliders stay first.

use std::any::Any;

use perifrac_physics::math::{add, dot, sub, Vec3};
use perifrac_physics::External;
use perifrac_scene::environment::{CollidersInfluence, Influence};
use perifrac_scene::{Scene, Setup};

/// The same force (N) on every particle.
struct Push {
    force: Vec3,
}

impl Influence for Push {
    fn name(&self) -> &'static str {
        "push"
    }

    fn add_forces(&mut self, ext: &mut External<'_>) {
        for f in ext.forces.iter_mut() {
            *f = add(*f, self.force);
        }
    }

    fn potential(
        &mut self,
        q: &[Vec3],
        _c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        if let Some((gq, _)) = grad {
            for g in gq.iter_mut() {
                *g = sub(*g, self.force);
            }
        }
        -q.iter().map(|&p| dot(p, self.force)).sum::<f64>()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A small free cube, with a ground far below so the list has the scene's own collider too.
fn cube(model: &str) -> String {
    let integrator = if model == "xu" {
        "implicit"
    } else {
        "explicit"
    };
    format!(
        "[mesh]\nprimitive = \"box\"\nsize = [0.04, 0.04, 0.04]\ncells = [3, 3, 3]\n\n\
         [[material]]\nmodel = \"{model}\"\nyoung = 1e6\npoisson = 0.25\ndensity = 1000.0\n\n\
         [simulation]\nduration = 1e-3\nintegrator = \"{integrator}\"\n\n\
         [[ground]]\npoint = [0.0, 0.0, -1.0]\n"
    )
}

/// Momentum (kg m/s) of the particles.
fn momentum(setup: &Setup) -> Vec3 {
    let s = setup.driver.solver();
    let mut p = [0.0; 3];
    for (v, m) in s.velocities().iter().zip(setup.driver.masses()) {
        for k in 0..3 {
            p[k] += m * v[k];
        }
    }
    p
}

#[test]
fn a_uniform_push_gives_the_body_its_impulse() {
    let force = [0.0, 2e-3, -1e-3];
    for model in ["chen", "xu"] {
        let path = std::path::Path::new("cube.toml");
        let scene = Scene::parse(&cube(model), path).unwrap();
        let mut setup = Setup::new(&scene, Some(1)).unwrap();
        setup.driver.add_influence(Box::new(Push { force }));
        let list = setup.driver.influences();
        assert!(list.get::<CollidersInfluence>().is_some() && list.get::<Push>().is_some());
        let steps = 5;
        for _ in 0..steps {
            setup.driver.step().unwrap();
        }
        let n = setup.driver.masses().len() as f64;
        let (t, dt) = (setup.driver.solver().time(), setup.driver.solver().dt());
        let p = momentum(&setup);
        for k in 0..3 {
            // The bonds' forces cancel pair by pair and the ground is out of reach, so the
            // momentum is the push's impulse. Velocity Verlet's first half kick uses the forces
            // at rest, before any environment acts: the push acts for t - dt/2 there.
            let acting = if model == "xu" { t } else { t - 0.5 * dt };
            let want = n * force[k] * acting;
            // The explicit step meets it to rounding (measured 2.3e-16 relative), the implicit
            // one to its solver's stopping rule, a relative decrease of 1e-4 (measured 5.6e-5).
            let tol = if model == "xu" { 1e-3 } else { 1e-9 };
            assert!(
                (p[k] - want).abs() <= tol * want.abs().max(1e-12),
                "{model}: momentum {p:?} against {want} along {k}"
            );
        }
    }
}
