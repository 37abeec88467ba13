//! The variational (tangent) equations of a system: the state y and the fundamental matrix Φ
//! integrated together,
//!
//! ```text
//! dy/dt = f(y),   dΦ/dt = J(y) Φ,   Φ(t₀) = I,
//! ```
//!
//! so that Φ(t) = ∂y(t)/∂y(t₀). Over one period of a cycle Φ is the monodromy matrix (Floquet
//! multipliers, shooting); along an orbit it gives finite-time Lyapunov exponents.
//!
//! The augmented state is `[y (N values), Φ column-major (N·N values)]`. Its Jacobian is exact:
//! J itself on each column block of Φ, and ∂(JΦ)/∂y from the system's derivatives of J
//! ([`OdeSystem::jacobian_derivative`]). Systems without them get central differences of J
//! (relative error ~1e-10) — enough for Newton iterations, but not for Rosenbrock methods,
//! which need the exact Jacobian: at γ = 1e8 the absolute error (~1e6 against entries ~γ²)
//! made Rodas5P take 0.5 M steps per period.
//!
//! For methods that use the Jacobian only in a Newton iteration (Radau5), [`Variational::for_newton`]
//! leaves the coupling block ∂(JΦ)/∂y out: the iteration matrix is then block diagonal (J on y
//! and on each column of Φ). The iteration still converges (Φ's equations are linear given y,
//! so Φ follows y's iterates) to the same stage values, to the Newton tolerance. The block must go in
//! a stiff stick: its entries are (∂J/∂y)Φ ≈ γ²e^(−w)Φ_w/ξ, 7e29 at the ageing law's
//! earthquake stick (γ = 1e8, ln v = −31.7), where Radau5's Newton iteration failed with it
//! ("Newton failed 10 times in one step", h ≈ 1e-5) and converges without it (docs/shooting.md).
//!
//! Reference: E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
//! §I.14 (variational equations).

use crate::integrate::{ImexSystem, JacobianMatrix, OdeSystem};

/// A system S (dimension N, with an analytic Jacobian) and its variational equations.
///
/// Requirements: `S::has_jacobian()` is true and `S::dim() == N`.
#[derive(Debug, Clone, Copy)]
pub struct Variational<S, const N: usize> {
    system: S,
    /// Whether the Jacobian includes ∂(JΦ)/∂y (false: [`Variational::for_newton`]).
    coupled: bool,
}

impl<S: OdeSystem, const N: usize> Variational<S, N> {
    /// Wraps `system`.
    ///
    /// # Panics
    /// If the system's dimension is not N or it has no analytic Jacobian (a programming error).
    pub fn new(system: S) -> Self {
        assert_eq!(system.dim(), N, "Variational<_, N>: the system's dimension must be N");
        assert!(system.has_jacobian(), "Variational needs the system's analytic Jacobian");
        Self { system, coupled: true }
    }

    /// Wraps `system` with a Jacobian for Newton iterations only: without the block
    /// ∂(JΦ)/∂y (see the module documentation). Not for Rosenbrock or linearly implicit
    /// methods, whose results depend on the exact Jacobian.
    ///
    /// # Panics
    /// As [`Variational::new`].
    pub fn for_newton(system: S) -> Self {
        Self { coupled: false, ..Self::new(system) }
    }

    /// The wrapped system.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// The augmented initial state (y0, I).
    pub fn initial(y0: &[f64; N]) -> Vec<f64> {
        let mut z = vec![0.0; N + N * N];
        z[..N].copy_from_slice(y0);
        for i in 0..N {
            z[N + i * N + i] = 1.0;
        }
        z
    }

    /// The fundamental matrix Φ from an augmented state, as rows (`Φ[row][col]`).
    pub fn matrix(z: &[f64]) -> [[f64; N]; N] {
        let mut phi = [[0.0; N]; N];
        for (row, r) in phi.iter_mut().enumerate() {
            for (col, entry) in r.iter_mut().enumerate() {
                *entry = z[N + col * N + row];
            }
        }
        phi
    }

    fn jac(&self, t: f64, y: &[f64]) -> [[f64; N]; N] {
        let mut columns = [[0.0; N]; N];
        self.system.jacobian(t, y, &mut JacobianMatrix::new(columns.as_flattened_mut(), N));
        transpose(columns)
    }
}

/// Rows from column-major storage (columns[col][row]), as JacobianMatrix fills it.
fn transpose<const N: usize>(columns: [[f64; N]; N]) -> [[f64; N]; N] {
    std::array::from_fn(|row| std::array::from_fn(|col| columns[col][row]))
}

impl<S: OdeSystem, const N: usize> OdeSystem for Variational<S, N> {
    fn dim(&self) -> usize {
        N + N * N
    }

    fn rhs(&self, t: f64, z: &[f64], dz: &mut [f64]) {
        self.system.rhs(t, &z[..N], &mut dz[..N]);
        let j = self.jac(t, &z[..N]);
        for col in 0..N {
            let phi_col = &z[N + col * N..N + (col + 1) * N];
            for row in 0..N {
                dz[N + col * N + row] = (0..N).map(|k| j[row][k] * phi_col[k]).sum();
            }
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    /// Without the coupling block ([`Variational::for_newton`]) the Jacobian is J repeated on
    /// the diagonal, N + 1 times.
    fn repeated_jacobian_block(&self) -> Option<usize> {
        (!self.coupled).then_some(N)
    }

    fn jacobian(&self, t: f64, z: &[f64], jac: &mut JacobianMatrix<'_>) {
        let y = &z[..N];
        let j = self.jac(t, y);
        for (row, r) in j.iter().enumerate() {
            for (col, &entry) in r.iter().enumerate() {
                // ∂f/∂y, and ∂(JΦ)/∂Φ: J on each column block.
                jac.set(row, col, entry);
                for block in 0..N {
                    jac.set(N + block * N + row, N + block * N + col, entry);
                }
            }
        }
        if !self.coupled {
            return;
        }
        // ∂(JΦ)/∂y_k: the system's ∂J/∂y_k, or central differences of J.
        let mut yk = [0.0; N];
        yk.copy_from_slice(y);
        for k in 0..N {
            let dj = if self.system.has_jacobian_derivative() {
                let mut columns = [[0.0; N]; N];
                self.system.jacobian_derivative(
                    t,
                    y,
                    k,
                    &mut JacobianMatrix::new(columns.as_flattened_mut(), N),
                );
                transpose(columns)
            } else {
                let h = 1e-5 * (1.0 + y[k].abs());
                yk[k] = y[k] + h;
                let jp = self.jac(t, &yk);
                yk[k] = y[k] - h;
                let jm = self.jac(t, &yk);
                yk[k] = y[k];
                let mut dj = [[0.0; N]; N];
                for (row, r) in dj.iter_mut().enumerate() {
                    for (col, entry) in r.iter_mut().enumerate() {
                        *entry = (jp[row][col] - jm[row][col]) / (2.0 * h);
                    }
                }
                dj
            };
            for block in 0..N {
                let phi_col = &z[N + block * N..N + (block + 1) * N];
                for (row, r) in dj.iter().enumerate() {
                    let d: f64 = r.iter().zip(phi_col).map(|(a, b)| a * b).sum();
                    jac.set(N + block * N + row, k, d);
                }
            }
        }
    }
}

/// IMEX split: the system's explicit part on y, everything else (the tangent equations
/// included) implicit.
impl<S: ImexSystem, const N: usize> ImexSystem for Variational<S, N> {
    fn rhs_explicit(&self, t: f64, z: &[f64], dz: &mut [f64]) {
        self.system.rhs_explicit(t, &z[..N], &mut dz[..N]);
        dz[N..].fill(0.0);
    }

    fn rhs_implicit(&self, t: f64, z: &[f64], dz: &mut [f64]) {
        self.rhs(t, z, dz);
        let mut explicit = [0.0; N];
        self.system.rhs_explicit(t, &z[..N], &mut explicit);
        for (d, e) in dz[..N].iter_mut().zip(explicit) {
            *d -= e;
        }
    }

    fn has_implicit_jacobian(&self) -> bool {
        true
    }

    fn implicit_jacobian(&self, t: f64, z: &[f64], jac: &mut JacobianMatrix<'_>) {
        // The explicit part of the systems used here (a constant drive) has zero Jacobian.
        self.jacobian(t, z, jac);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;
    use crate::model::{Drr, DrrParams, Friction, StateLaw};

    #[test]
    fn augmented_jacobian_matches_central_differences() {
        for (_, state_law) in StateLaw::ALL {
            for eta in [0.0, 0.37] {
                let drr = Drr::new(DrrParams {
                    state_law,
                    eta,
                    ..DrrParams::new(10.0, 0.7, 0.72, Friction::Log)
                });
                let var = Variational::<_, 3>::new(drr);
                let mut z = Variational::<Drr, 3>::initial(&[0.3, -0.4, 0.2]);
                for (i, v) in z.iter_mut().enumerate().skip(3) {
                    *v += 0.1 * (i as f64).sin();
                }
                for (row, col, exact, fd) in
                    jacobian_against_differences(&var, &z, |x| 1e-6 * (1.0 + x.abs()))
                {
                    assert!(
                        (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                        "{state_law:?} η={eta} ({row},{col}): {exact} vs {fd}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_newton_jacobian_is_the_exact_one_without_the_coupling_block() {
        for (_, state_law) in StateLaw::ALL {
            let drr =
                Drr::new(DrrParams { state_law, ..DrrParams::new(1e8, 0.8, 1.0, Friction::Log) });
            let mut z = Variational::<Drr, 3>::initial(&[37.0, -31.6, 1.9]);
            z[4] = -0.8;
            let n = 12;
            let (mut exact, mut newton) = (vec![0.0; n * n], vec![0.0; n * n]);
            Variational::<_, 3>::new(drr).jacobian(
                0.0,
                &z,
                &mut JacobianMatrix::new(&mut exact, n),
            );
            Variational::<_, 3>::for_newton(drr).jacobian(
                0.0,
                &z,
                &mut JacobianMatrix::new(&mut newton, n),
            );
            let mut coupling = 0.0f64;
            for col in 0..n {
                for row in 0..n {
                    let (e, w) = (exact[col * n + row], newton[col * n + row]);
                    if row >= 3 && col < 3 {
                        assert_eq!(w, 0.0, "{state_law:?} ({row},{col})");
                        coupling = coupling.max(e.abs());
                    } else {
                        assert_eq!(w, e, "{state_law:?} ({row},{col})");
                    }
                }
            }
            // What is left out: entries ~γ²e^(−w)Φ_w/ξ in this stick.
            assert!(coupling > 1e28, "{state_law:?}: {coupling:e}");
        }
    }
}
