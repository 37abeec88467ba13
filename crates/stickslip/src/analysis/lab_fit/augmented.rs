//! A parametric system and its forward sensitivities as one ODE system, for the methods that
//! have no sensitivity solver of their own (every method but CVODE's):
//!
//! ```text
//! dy/dt = f(y; p),   ds_j/dt = J(y) s_j + ∂f/∂p_j(y),   j = 1 … m,
//! ```
//!
//! the state `[y (n values), s_1, …, s_m (n values each)]`. Every method integrates it as any
//! other system, and its error control then covers the sensitivities as CVODES' does with
//! error control on.
//!
//! The Jacobian: J on y and on each s_j, and the coupling blocks ∂(J s_j + ∂f/∂p_j)/∂y.
//! - For a Newton iteration (radau5, arkode-dirk) the coupling is left out
//!   ([`Sensitized::for_newton`]), as [`crate::model::Variational::for_newton`] does: the
//!   s_j equations are linear given y, so the iteration still converges to the same stage
//!   values, and the iteration matrix is block diagonal with one repeated n × n block
//!   ([`OdeSystem::repeated_jacobian_block`]).
//! - Linearly implicit methods (rodas5p, extrapolation) use the Jacobian in the formula itself:
//!   [`Sensitized::exact`] adds the coupling blocks by central differences of J and ∂f/∂p in y
//!   (the lab model has no second derivatives), step 1e-5·max(1, |y_k|), error ~1e-10 relative.

use crate::integrate::{JacobianMatrix, OdeSystem, ParametricSystem};
use std::cell::RefCell;

/// A [`ParametricSystem`] with its sensitivity equations, as one [`OdeSystem`].
#[derive(Debug)]
pub struct Sensitized<P> {
    system: P,
    /// Whether the Jacobian includes the coupling blocks (see the module's doc).
    coupled: bool,
    /// Scratch: J (n × n, column-major) and ∂f/∂p (n × m).
    scratch: RefCell<(Vec<f64>, Vec<f64>)>,
}

impl<P: ParametricSystem> Sensitized<P> {
    /// With the Jacobian a Newton iteration needs (block diagonal, no coupling).
    ///
    /// # Panics
    /// If the system has no analytic Jacobian (a programming error: the sensitivity equations
    /// are built from it).
    pub fn for_newton(system: P) -> Self {
        assert!(system.has_jacobian(), "Sensitized needs the system's analytic Jacobian");
        let (n, m) = (system.dim(), system.n_params());
        Self { system, coupled: false, scratch: RefCell::new((vec![0.0; n * n], vec![0.0; n * m])) }
    }

    /// With the whole Jacobian (coupling blocks by central differences), for linearly
    /// implicit methods.
    ///
    /// # Panics
    /// As [`Sensitized::for_newton`].
    pub fn exact(system: P) -> Self {
        Self { coupled: true, ..Self::for_newton(system) }
    }

    /// The state's dimension n and the number of parameters m.
    fn sizes(&self) -> (usize, usize) {
        (self.system.dim(), self.system.n_params())
    }

    /// J s_j + ∂f/∂p_j at y for every j, into `out` (n·m values).
    fn sensitivity_rates(&self, t: f64, y: &[f64], s: &[f64], out: &mut [f64]) {
        let (n, m) = self.sizes();
        let mut scratch = self.scratch.borrow_mut();
        let (jac, dfdp) = &mut *scratch;
        jac.fill(0.0);
        dfdp.fill(0.0);
        self.system.jacobian(t, y, &mut JacobianMatrix::new(jac, n));
        self.system.param_jacobian(t, y, &mut JacobianMatrix::rectangular(dfdp, n, m));
        for j in 0..m {
            let (sj, oj) = (&s[j * n..(j + 1) * n], &mut out[j * n..(j + 1) * n]);
            for (i, o) in oj.iter_mut().enumerate() {
                *o = dfdp[j * n + i] + (0..n).map(|k| jac[k * n + i] * sj[k]).sum::<f64>();
            }
        }
    }
}

impl<P: ParametricSystem> OdeSystem for Sensitized<P> {
    fn dim(&self) -> usize {
        let (n, m) = self.sizes();
        n * (1 + m)
    }

    fn rhs(&self, t: f64, z: &[f64], dzdt: &mut [f64]) {
        let n = self.system.dim();
        let (y, s) = z.split_at(n);
        let (dy, ds) = dzdt.split_at_mut(n);
        self.system.rhs(t, y, dy);
        self.sensitivity_rates(t, y, s, ds);
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, z: &[f64], out: &mut JacobianMatrix<'_>) {
        let (n, m) = self.sizes();
        let y = &z[..n];
        let mut jac = vec![0.0; n * n];
        self.system.jacobian(t, y, &mut JacobianMatrix::new(&mut jac, n));
        for block in 0..=m {
            for c in 0..n {
                for r in 0..n {
                    out.set(block * n + r, block * n + c, jac[c * n + r]);
                }
            }
        }
        if !self.coupled {
            return;
        }
        let s = &z[n..];
        let (mut up, mut down) = (vec![0.0; n * m], vec![0.0; n * m]);
        let mut yk = y.to_vec();
        for k in 0..n {
            let h = 1e-5 * y[k].abs().max(1.0);
            yk[k] = y[k] + h;
            self.sensitivity_rates(t, &yk, s, &mut up);
            yk[k] = y[k] - h;
            self.sensitivity_rates(t, &yk, s, &mut down);
            yk[k] = y[k];
            for (row, (u, d)) in up.iter().zip(&down).enumerate() {
                out.set(n + row, k, (u - d) / (2.0 * h));
            }
        }
    }

    fn repeated_jacobian_block(&self) -> Option<usize> {
        (!self.coupled).then(|| self.system.dim())
    }

    fn has_linear_invariants(&self) -> bool {
        self.system.has_linear_invariants()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;
    use crate::model::{LabLaw, LabParameter, LabParametric, LabParams, LabState};

    fn system() -> LabParametric {
        let params = LabParams {
            mu0: 0.6,
            a: 0.011,
            v0: 1.0,
            k: 3e-3,
            states: vec![LabState { law: LabLaw::Slip, b: 0.015, d_c: 5.0 }],
            mass: None,
        };
        LabParametric {
            params,
            v_lp: 10.0,
            varied: vec![LabParameter::A, LabParameter::B(0), LabParameter::LnDc(0)],
        }
    }

    /// The exact Jacobian against central differences of the right-hand side; the Newton one
    /// is its block diagonal.
    #[test]
    fn the_exact_jacobian_is_the_derivative_of_the_right_hand_side() {
        let z = [0.3, -0.8, 12.0, -40.0, 3.0, 0.5, -2.0, 7.0];
        let exact = Sensitized::exact(system());
        let table = jacobian_against_differences(&exact, &z, |y| 1e-6 * y.abs().max(1.0));
        let scale = table.iter().fold(0.0f64, |m, e| m.max(e.2.abs()));
        for (row, col, analytic, difference) in table {
            let off = (analytic - difference).abs();
            assert!(off < 1e-6 * scale, "({row}, {col}): {analytic} vs {difference}");
        }
        let (mut full, mut newton) = (vec![0.0; 64], vec![0.0; 64]);
        exact.jacobian(0.0, &z, &mut JacobianMatrix::new(&mut full, 8));
        Sensitized::for_newton(system()).jacobian(
            0.0,
            &z,
            &mut JacobianMatrix::new(&mut newton, 8),
        );
        for c in 0..8 {
            for r in 0..8 {
                let same_block = r / 2 == c / 2;
                let expected = if same_block { full[c * 8 + r] } else { 0.0 };
                assert_eq!(newton[c * 8 + r], expected, "({r}, {c})");
            }
        }
    }
}
