//! The "lyapunov" analysis: the paper's transition times where they hold, and the
//! finite-time exponents against an independent reference, finite differences of the
//! Poincaré map.

use stickslip::integrate::{Options, Radau5, Task, Tolerance};
use stickslip::model::{Drr, DrrParams, Friction};
use stickslip::numerics::events;
use stickslip::paper::cycle_period::CyclePeriod;

mod common;
use common::{run_scene, run_scene_file};

#[test]
fn fig5_transitions_and_the_eigenvalues_two_ways() {
    let r = run_scene_file("fig1-asymptotics.json");
    let l = r.lyapunov.unwrap();
    // The paper: complex at t_c − 4.6, real part through zero at t_c − 2.3 (both within 5 %).
    let (onset, zero) = (l.complex_onset_before_tc.unwrap(), l.zero_crossing_before_tc.unwrap());
    assert!(
        (onset - 4.6).abs() < 0.05 * 4.6 && (zero - 2.3).abs() < 0.05 * 2.3,
        "onset {onset}, zero {zero}"
    );
    assert!(zero > l.t0.unwrap(), "inside the stick, before v = 1");
    // The quasi-static formula is the large-γ limit; the polynomial agrees with the matrix.
    let q = l.quasi_static.as_ref().unwrap();
    assert!(q.max_relative_difference_on_stick < 1e-5, "{q:?}");
    assert!((q.zero_crossing_before_tc.unwrap() - zero).abs() < 1e-3);
    let m = l.matrix_check.as_ref().unwrap();
    assert!(m.samples > 1000 && m.max_difference.unwrap() < 1e-7, "{m:?}");
    assert!(l.fast_eigenvalue_max.unwrap() < 0.0);
    // Fig. 5 data.
    let f = l.along_cycle.as_ref().unwrap();
    assert!(f.t.len() > 100 && f.t.len() <= 2000 && f.t.windows(2).all(|w| w[0] < w[1]));
    // FTLE: converged, and λ₂ T = ln |μ₂| of shooting here (|μ₂| = 8.6e-3 is well resolved).
    let ftle = l.ftle.as_ref().unwrap();
    let link = ftle.floquet.as_ref().unwrap();
    let mu2 = link.ln_abs_nontrivial[0].unwrap();
    assert!((link.last_period_logs[1] - mu2).abs() < 1e-3, "{} vs {mu2}", link.last_period_logs[1]);
    assert!(ftle.exponents[2] < -1e6, "the fast exponent, from Liouville: {:?}", ftle.exponents);
}

#[test]
fn power_law_zero_crossing() {
    let l = run_scene_file("power-law-lyapunov.json").lyapunov.unwrap();
    let zero = l.zero_crossing_before_tc.unwrap();
    assert!((zero - 2.45).abs() < 0.05 * 2.45, "{zero}");
}

/// The Poincaré map on v = 1 (upward), by a separate Radau5 integration at rtol 1e-12: the
/// return after a slip (v > e) and a downward crossing.
fn poincare(drr: Drr, x: [f64; 2]) -> [f64; 2] {
    let y0 = [x[0], 0.0, x[1]];
    let options = Options { max_step: Some(0.5), ..Options::new(1e-12, Tolerance::Scalar(1e-14)) };
    let mut integ = Radau5::new(drr, 0.0, &y0, &options).unwrap();
    let (mut t, mut y) = (0.0, y0);
    let (mut slipped, mut down) = (false, false);
    loop {
        let step = integ.advance(t + 1e6, Task::OneStep).unwrap();
        let w = integ.state()[1];
        slipped |= w > 1.0;
        down |= slipped && y[1] >= 0.0 && w < 0.0;
        if down && y[1] < 0.0 && w >= 0.0 {
            let tc = events::refine(&mut integ, (t, step.t), 0, 1, 0.0).unwrap();
            let z = integ.dense(tc, 0).unwrap();
            return [z[0], z[2]];
        }
        t = step.t;
        y = [integ.state()[0], w, integ.state()[2]];
    }
}

/// ln of the largest eigenvalue of the map's Jacobian by central differences of step δ.
fn ln_mu2_by_differences(drr: Drr, x: [f64; 2], delta: f64) -> f64 {
    let mut dp = [[0.0; 2]; 2];
    for j in 0..2 {
        let (mut a, mut b) = (x, x);
        a[j] += delta;
        b[j] -= delta;
        let (pa, pb) = (poincare(drr, a), poincare(drr, b));
        for i in 0..2 {
            dp[i][j] = (pa[i] - pb[i]) / (2.0 * delta);
        }
    }
    let (tr, det) = (dp[0][0] + dp[1][1], dp[0][0] * dp[1][1] - dp[0][1] * dp[1][0]);
    let disc = tr * tr - 4.0 * det;
    assert!(disc >= 0.0, "{dp:?}");
    (0.5 * (tr + tr.signum() * disc.sqrt())).abs().ln()
}

#[test]
fn ftle_matches_finite_differences_of_the_poincare_map() {
    // ξ = 0.8, ε = 1 at γ = 1e4: |μ₂| ≈ 2e-8, below the resolution of shooting's section
    // Jacobian at rtol 1e-10 (it gives ln |μ₂| = −16.2) but not of the FTLE.
    let text = r#"{"name": "t", "model": {"gamma": 1e4, "xi": 0.8, "epsilon": 1}, "solver": {"rtol": 1e-10, "atol": 1e-12},
                   "analyses": ["cycle", {"trajectory": {"cycles": 1}}, {"lyapunov": {"ftle_periods": 3}}]}"#;
    let r = run_scene(text);
    let ftle = r.lyapunov.as_ref().unwrap().ftle.as_ref().unwrap();
    let ours = ftle.per_period.last().unwrap().ln_r[1];
    let orbit = CyclePeriod::from_cycle(r.cycle.as_ref().unwrap()).unwrap();
    let x = [orbit.u[orbit.up], orbit.theta[orbit.up]];
    let drr = Drr::new(DrrParams::new(1e4, 0.8, 1.0, Friction::Log));
    // δ = 1e-2: nonlinear error O(δ); δ = 1e-3: the return moves by ~2e-11, near the
    // integration noise. Their spread bounds the reference's own error.
    let (a, b) = (ln_mu2_by_differences(drr, x, 1e-2), ln_mu2_by_differences(drr, x, 1e-3));
    assert!((a - b).abs() < 0.15, "finite differences disagree: {a}, {b}");
    assert!(
        (ours - a).abs() < 0.05,
        "FTLE ln |μ₂| = {ours}, finite differences {a} (δ = 1e-2), {b} (δ = 1e-3)"
    );
}
