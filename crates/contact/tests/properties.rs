//! Property tests of one particle against one ball: never attractive, friction bounded by
//! Coulomb and against the sliding, reaction exactly opposite.

use perifrac_contact::{BallDesc, BallMotion, Colliders, ContactParams};
use proptest::prelude::*;

proptest! {
    #[test]
    fn single_contact_force_is_physical(
        off in prop::array::uniform3(-0.06..0.06f64),
        v in prop::array::uniform3(-5.0..5.0f64),
        vb in prop::array::uniform3(-5.0..5.0f64),
        zeta in 0.0..2.0f64,
        mu in 0.0..1.5f64,
        dt in 1e-7..1e-4f64,
    ) {
        let params = ContactParams::from_material(1e7, 0.01, 1.0, zeta, mu);
        let ball = BallDesc {
            center: [0.0; 3],
            radius: 0.05,
            // Kinematic: the surface velocity used is exactly vb.
            motion: BallMotion::Kinematic { velocity: vb },
            params,
        };
        let mut col = Colliders::new(vec![], vec![ball], [0.0; 3]).unwrap();
        let mut f = vec![[0.0; 3]];
        // The ball drifts by vb dt before the contact is evaluated.
        col.step(dt, &[off], &[v], &[1e-3], &[0.01], &mut f);
        let b = col.ball(0);
        let f = f[0];
        prop_assert!(f.iter().all(|x| x.is_finite()));
        prop_assert_eq!(b.reaction, [-f[0], -f[1], -f[2]]);
        let dx = [off[0] - b.center[0], off[1] - b.center[1], off[2] - b.center[2]];
        let dist = (dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]).sqrt();
        if dist >= 0.06 {
            prop_assert_eq!(f, [0.0; 3]);
            return Ok(());
        }
        let n = if dist > 0.0 { dx.map(|x| x / dist) } else { [0.0, 0.0, 1.0] };
        let fnorm = f[0] * n[0] + f[1] * n[1] + f[2] * n[2];
        let ft = [f[0] - fnorm * n[0], f[1] - fnorm * n[1], f[2] - fnorm * n[2]];
        let ft_len = (ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]).sqrt();
        let scale = 1e-12 * (1.0 + fnorm.abs());
        // Never attractive; friction within the Coulomb cone.
        prop_assert!(fnorm >= -scale, "{}", fnorm);
        prop_assert!(ft_len <= mu * fnorm + scale, "{} > {} * {}", ft_len, mu, fnorm);
        // Friction opposes the relative sliding and never exceeds what stops it in one step.
        let vr = [v[0] - vb[0], v[1] - vb[1], v[2] - vb[2]];
        let vn = vr[0] * n[0] + vr[1] * n[1] + vr[2] * n[2];
        let vt = [vr[0] - vn * n[0], vr[1] - vn * n[1], vr[2] - vn * n[2]];
        let vt_len = (vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]).sqrt();
        prop_assert!(ft[0] * vt[0] + ft[1] * vt[1] + ft[2] * vt[2] <= scale * (1.0 + vt_len));
        prop_assert!(ft_len <= 1e-3 * vt_len / dt * (1.0 + 1e-9) + scale, "{} {}", ft_len, vt_len);
    }
}

/// A particle's stiffness scale multiplies its penalty spring and nothing else: at rest on a
/// ground (no damping or friction force), twice the scale gives twice the force, and the
/// ball-ground reference mass follows the particle that rings fastest.
#[test]
fn stiffness_scale_is_per_particle() {
    use perifrac_contact::GroundDesc;
    let params = ContactParams::from_material(1e7, 0.01, 1.0, 0.3, 0.5);
    let ground = GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params,
    };
    let mut col = Colliders::new(vec![ground], vec![], [0.0; 3]).unwrap();
    assert!(col.set_stiffness_scale(vec![1.0, f64::NAN]).is_err());
    col.set_stiffness_scale(vec![1.0, 2.0, 0.0]).unwrap();
    // Each 1 mm into the ground.
    let y = [[0.0, 0.0, 0.009], [0.1, 0.0, 0.009], [0.2, 0.0, 0.009]];
    let mut f = vec![[0.0; 3]; 3];
    col.step(
        1e-6,
        &y,
        &[[0.0; 3]; 3],
        &[1e-3, 1e-3, 1e-3],
        &[0.01; 3],
        &mut f,
    );
    let k = params.stiffness;
    assert!((f[0][2] - k * 1e-3).abs() <= 1e-12 * k, "{f:?}");
    assert_eq!(f[1][2], 2.0 * f[0][2]);
    assert_eq!(f[2], [0.0; 3]);
    // m / s: 1e-3 / 1, 1e-3 / 2, and nothing for the particle of zero scale.
    assert_eq!(col.reference_mass(), Some(5e-4));
}
