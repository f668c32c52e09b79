//! Chen plasticity: the per-bond return map (docs/model.md section 2, Plasticity).

/// Returns the new plastic extension of one bond (m) after the return map.
///
/// `trial` is the trial `A_dev = 4 omega b (ed - ep)`, `ep` the current plastic extension (m),
/// `four_wb = 4 omega b`, `psi0` the yield limit and `cap = gamma_ratio * r` (m). When
/// `trial^2 / 2 > psi0`, the increment `(A_dev - A_c) / (4 omega b)` with
/// `A_c = sqrt(2 psi0) sign(A_dev)` puts `A_dev` exactly on the yield surface; the result is then
/// capped at `|ep| <= cap`.
#[inline(always)]
pub fn return_map_bond(trial: f64, ep: f64, four_wb: f64, psi0: f64, cap: f64) -> f64 {
    if 0.5 * trial * trial <= psi0 {
        return ep;
    }
    let ac = (2.0 * psi0).sqrt().copysign(trial);
    let new = ep + (trial - ac) / four_wb;
    if new.abs() > cap {
        cap.copysign(new)
    } else {
        new
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// For any trial state: inside the yield surface nothing changes; outside, the new
        /// `A_dev = four_wb (ed - ep_new)` lies on the surface to rounding unless the cap binds,
        /// and the cap always holds.
        #[test]
        fn return_map_property(
            ed in -1e-2f64..1e-2,
            ep in -1e-3f64..1e-3,
            four_wb in 1e9f64..1e15,
            yield_strain in 1e-5f64..1e-2,
            cap in 1e-4f64..1e-2,
        ) {
            let ep = ep.clamp(-cap, cap);
            let psi0 = 0.5 * (four_wb * yield_strain).powi(2);
            let trial = four_wb * (ed - ep);
            let new = return_map_bond(trial, ep, four_wb, psi0, cap);
            prop_assert!(new.abs() <= cap);
            let limit = (2.0 * psi0).sqrt();
            if 0.5 * trial * trial <= psi0 {
                prop_assert_eq!(new, ep);
            } else if new.abs() < cap {
                let a_dev = four_wb * (ed - new);
                // ed - new cancels to |yield_strain| from |ed| <= 1e-2: relative rounding
                // ~ 1e-16 * 1e-2 / 1e-5 = 1e-13
                prop_assert!((a_dev.abs() - limit).abs() <= 1e-12 * limit, "{} vs {}", a_dev, limit);
                prop_assert!(a_dev * trial > 0.0);
            }
        }
    }

    #[test]
    fn return_map_lands_on_the_yield_surface_and_respects_the_cap() {
        let (four_wb, psi0): (f64, f64) = (3.7e12, 2.5e9);
        let ac = (2.0 * psi0).sqrt();
        for &ed in &[1e-3, -1e-3, 4e-4, -2.2e-3] {
            for &ep0 in &[0.0, 1e-4, -3e-4] {
                let trial = four_wb * (ed - ep0);
                let ep = return_map_bond(trial, ep0, four_wb, 2.5e9, f64::INFINITY);
                let a_dev = four_wb * (ed - ep);
                if 0.5 * trial * trial > psi0 {
                    // one subtraction and a division: a few ulps of |A_dev| ~ 7e4
                    assert!((a_dev.abs() - ac).abs() < 1e-10 * ac, "{a_dev} vs {ac}");
                } else {
                    assert_eq!(ep, ep0);
                }
                let capped = return_map_bond(trial, ep0, four_wb, psi0, 1e-4);
                assert!(capped.abs() <= 1e-4);
            }
        }
    }
}
