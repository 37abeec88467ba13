//! MEDAKZO: the Medical Akzo Nobel problem (penetration of radio-labelled antibodies into
//! tumour tissue), a method-of-lines reaction–diffusion system with N = 200 grid points,
//! 400 equations, t ∈ [0, 20]; the boundary source φ switches from 2 to 0 at t = 5, so the
//! integration restarts there.
//!
//! Problem definition and reference solution: Test Set for IVP Solvers, release 2.4
//! (F. Mazzia, C. Magherini, Università di Bari, 2008), problem medakzo (subroutines `feval`,
//! `jeval` and `solut`). The reference ("computed at Cray C90 using Cray double precision,
//! solving Medical Akzo Nobel problem using PSIDE, rtol = atol = 1e-10") is stored in
//! data/test_set/medakzo.txt. Test Set tolerances: rtol = atol.

use super::problem::TestProblem;
use stickslip_ode::integrate::{JacobianMatrix, OdeSystem};

#[derive(Debug, Clone, Copy)]
pub struct Medakzo;

const N: usize = 200;
const KK: f64 = 100.0;
const CC: f64 = 4.0;
const DZETA: f64 = 1.0 / N as f64;

/// α and β/Δζ² of grid point j (1-based), as in medakzo.f.
fn coefficients(j: usize) -> (f64, f64) {
    let zeta = j as f64 * DZETA;
    let dum = (zeta - 1.0) * ((zeta - 1.0) / CC);
    let alpha = 2.0 * (zeta - 1.0) * (dum / CC);
    let beta = dum * dum;
    (alpha, beta / (DZETA * DZETA))
}

/// The boundary concentration φ(t).
fn phi(t: f64) -> f64 {
    if t <= 5.0 {
        2.0
    } else {
        0.0
    }
}

impl OdeSystem for Medakzo {
    fn dim(&self) -> usize {
        2 * N
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        for j in 1..=N {
            let i = 2 * (j - 1);
            let reaction = -KK * y[i] * y[i + 1];
            f[i + 1] = reaction;
            if j == N {
                // ζ = 1: α = β = 0, no transport.
                f[i] = reaction;
                continue;
            }
            let (alpha, bz) = coefficients(j);
            let left = if j == 1 { phi(t) } else { y[i - 2] };
            let right = y[i + 2];
            f[i] = (left - 2.0 * y[i] + right) * bz
                + alpha * (right - left) / (2.0 * DZETA)
                + reaction;
        }
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        for j in 1..=N {
            let i = 2 * (j - 1);
            jac.set(i + 1, i, -KK * y[i + 1]);
            jac.set(i + 1, i + 1, -KK * y[i]);
            jac.set(i, i + 1, -KK * y[i]);
            if j == N {
                jac.set(i, i, -KK * y[i + 1]);
                continue;
            }
            let (alpha, bz) = coefficients(j);
            jac.set(i, i, -2.0 * bz - KK * y[i + 1]);
            jac.set(i, i + 2, bz + alpha / (2.0 * DZETA));
            if j > 1 {
                jac.set(i, i - 2, bz - alpha / (2.0 * DZETA));
            }
        }
    }
}

impl TestProblem for Medakzo {
    const NAME: &'static str = "MEDAKZO";
    const T_END: f64 = 20.0;
    const BREAKPOINTS: &'static [f64] = &[5.0];
    fn new() -> Self {
        Medakzo
    }
    fn y0() -> Vec<f64> {
        (0..2 * N).map(|i| if i % 2 == 0 { 0.0 } else { 1.0 }).collect()
    }
    fn reference() -> Vec<f64> {
        let text = include_str!("../../../../data/test_set/medakzo.txt");
        let values: Vec<f64> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| {
                l.trim()
                    .replace('d', "e")
                    .parse()
                    .expect("data/test_set/medakzo.txt: a number per line")
            })
            .collect();
        assert_eq!(values.len(), 2 * N, "data/test_set/medakzo.txt must hold 400 values");
        values
    }
}
