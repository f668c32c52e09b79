//! Forces at rest: what [`ForceModel::forces_vanish_at`] vouches for holds, and the
//! evaluations it lets the stable-step estimate and the explicit start skip change no result.

mod support;

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_physics::{
    stable_frequency, ChenMaterial, ChenModel, ChenOptions, Damage, Discretization, Explicit,
    ExplicitConfig, ForceModel, FractureParams, Loads, TimeStep, Vec3, YieldParams,
};
use support::{block, steel};

/// Chen's model under every option set the scenes can pick, with each material path.
fn models() -> Vec<(String, ChenModel)> {
    let (disc, _, _) = block([0.04, 0.03, 0.03], [4, 3, 3], 1.5);
    let fracture = Some(FractureParams {
        s_crit: 0.002,
        alpha: 0.0,
    });
    // a yield limit a small stretch passes (Psi0 in (N/m^6)^2 for this horizon)
    let plasticity = Some(YieldParams {
        psi0: 1e20,
        gamma_ratio: 0.2,
        from_strain: false,
    });
    let paths = [
        ("elastic", steel()),
        (
            "brittle",
            ChenMaterial {
                fracture,
                ..steel()
            },
        ),
        (
            "plastic",
            ChenMaterial {
                plasticity,
                ..steel()
            },
        ),
        (
            "ductile",
            ChenMaterial {
                plasticity,
                fracture,
                ..steel()
            },
        ),
    ];
    let mut out = Vec::new();
    for (name, mat) in paths {
        for (fitted, calibrated, energy_consistent) in [
            (true, true, true),
            (false, true, true),
            (false, false, true),
            (true, true, false),
        ] {
            let options = ChenOptions {
                energy_consistent,
                calibrated,
                fitted_dilatation: fitted,
            };
            let m = ChenModel::with_options(disc.clone(), std::slice::from_ref(&mat), options)
                .expect("model");
            out.push((format!("{name} {options:?}"), m));
        }
    }
    out
}

#[test]
fn chen_vouches_for_zero_forces_only_at_its_own_rest_with_nothing_stored() {
    for (name, mut m) in models() {
        let x = m.discretization().rest_positions().to_vec();
        assert!(m.forces_vanish_at(&x), "{name}");
        let mut f = vec![[1.0; 3]; x.len()];
        m.trial_forces(&x, &mut f);
        // every component exactly zero (either sign), not merely small
        assert!(f.iter().flatten().all(|&c| c == 0.0), "{name}");
        // one coordinate one ulp away: no longer the rest positions
        let mut y = x.clone();
        y[3][1] = f64::from_bits(y[3][1].to_bits() + 1);
        assert!(!m.forces_vanish_at(&y), "{name}");
        assert!(!m.forces_vanish_at(&x[1..]), "{name}");
        // a guard pulls towards its own fitted gradients: it vouches for nothing
        let guarded = m.clone().with_inversion_guard(1.0).expect("guard");
        assert!(!guarded.forces_vanish_at(&x), "{name}");
    }
    // a stored plastic extension stresses the rest state
    let (_, mut m) = models().swap_remove(8);
    let x = m.discretization().rest_positions().to_vec();
    let mut own = vec![0.0; m.discretization().family().num_bonds()];
    own[5] = 1e-6;
    m.set_plastic_extensions(&own).expect("plastic");
    assert!(!m.forces_vanish_at(&x));
    let mut f = vec![[0.0; 3]; x.len()];
    m.trial_forces(&x, &mut f);
    assert!(f.iter().flatten().any(|&c| c != 0.0));
}

/// A model that vouches for nothing: every call but [`ForceModel::forces_vanish_at`] goes to
/// the model inside.
#[derive(Clone)]
struct Unvouched(ChenModel);

impl ForceModel for Unvouched {
    fn num_particles(&self) -> usize {
        self.0.num_particles()
    }
    fn discretization(&self) -> &Discretization {
        self.0.discretization()
    }
    fn masses(&self) -> &[f64] {
        self.0.masses()
    }
    fn update_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.0.update_forces(y, forces)
    }
    fn trial_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.0.trial_forces(y, forces)
    }
    fn elastic_energy(&mut self, y: &[Vec3]) -> f64 {
        self.0.elastic_energy(y)
    }
    fn break_bonds(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        self.0.break_bonds(y, broken)
    }
    fn break_bonds_and_update_forces(
        &mut self,
        y: &[Vec3],
        broken: &mut Vec<(u32, u32)>,
        forces: &mut [Vec3],
    ) {
        self.0.break_bonds_and_update_forces(y, broken, forces)
    }
    fn silling_askari_step(&self) -> f64 {
        self.0.silling_askari_step()
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn damage(&self) -> Option<&Damage> {
        self.0.damage()
    }
    fn break_overshoot(&self) -> f64 {
        self.0.break_overshoot()
    }
    fn save_state(&self, w: &mut Writer) {
        self.0.save_state(w)
    }
    fn restore_state(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.0.restore_state(r)
    }
}

#[test]
fn skipping_the_evaluations_at_rest_changes_no_bit() {
    for (name, m) in models() {
        let x = m.discretization().rest_positions().to_vec();
        let delta = m.discretization().horizon();
        let mut plain = Unvouched(m.clone());
        let mut vouched = m;
        // the stable step: one evaluation fewer, the same estimate
        let (omega, est) = stable_frequency(&mut vouched, &x, delta);
        let (omega_plain, est_plain) = stable_frequency(&mut plain, &x, delta);
        assert_eq!(omega.to_bits(), omega_plain.to_bits(), "{name}");
        assert_eq!(est.iterations, est_plain.iterations, "{name}");
        assert_eq!(est.evaluations + 1, est_plain.evaluations, "{name}");
        // the explicit start: no evaluation, then the same steps bit for bit under a stretch
        // that yields and breaks bonds (asserted below) on the plastic and brittle paths
        let dt = 0.5 / omega;
        let cfg = ExplicitConfig {
            dt: TimeStep::Fixed(dt),
            guard_fraction: 0.5,
        };
        let loads = || Loads::new(x.len());
        let mut a = Explicit::new(vouched, &x, delta, loads(), cfg).expect("vouched");
        let mut b = Explicit::new(plain, &x, delta, loads(), cfg).expect("plain");
        // a strain rate that would reach 0.01 along x in 10 steps: enough to break and yield
        // (asserted below)
        let rate = 0.01 / (10.0 * dt);
        for s in [&mut a.velocities_mut(), &mut b.velocities_mut()] {
            for (v, p) in s.iter_mut().zip(&x) {
                *v = [rate * (p[0] - 0.02), -0.25 * rate * (p[1] - 0.015), 0.0];
            }
        }
        let mut broken = 0;
        for _ in 0..40 {
            let ba = a.step().expect("vouched step").to_vec();
            let bb = b.step().expect("plain step").to_vec();
            assert_eq!(ba, bb, "{name}");
            broken += ba.len();
        }
        let bits = |p: &[Vec3]| -> Vec<u64> { p.iter().flatten().map(|c| c.to_bits()).collect() };
        assert_eq!(bits(a.positions()), bits(b.positions()), "{name}");
        assert_eq!(bits(a.velocities()), bits(b.velocities()), "{name}");
        let mut f = [vec![[0.0; 3]; x.len()], vec![[0.0; 3]; x.len()]];
        let y = a.positions().to_vec();
        a.model_mut().trial_forces(&y, &mut f[0]);
        b.model_mut().trial_forces(&y, &mut f[1]);
        assert_eq!(bits(&f[0]), bits(&f[1]), "{name}");
        if name.starts_with("brittle") || name.starts_with("ductile") {
            assert!(broken > 0, "{name}: nothing broke");
        }
        if name.starts_with("plastic") {
            let m = a.model();
            let x = m.discretization().rest_positions();
            assert!(!m.forces_vanish_at(x), "{name}: nothing yielded");
        }
    }
}
