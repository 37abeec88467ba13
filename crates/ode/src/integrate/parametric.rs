//! What a problem provides for forward sensitivities: its parameters and ∂f/∂p.

use super::{JacobianMatrix, OdeSystem};

/// An [`OdeSystem`] whose right-hand side depends on parameters p = (p_0, …, p_{m−1}),
/// dy/dt = f(t, y; p), and which supplies ∂f/∂p, so that the forward sensitivities
/// s_j(t) = ∂y(t)/∂p_j can be integrated beside y (CVODES,
/// [`SensitivitySolver`](crate::sundials::SensitivitySolver)):
///
/// s_j' = (∂f/∂y) s_j + ∂f/∂p_j,   s_j(t0) = ∂y0/∂p_j.
///
/// # Requirements
/// - [`OdeSystem::has_jacobian`] returns true and [`OdeSystem::jacobian`] is exact: the
///   sensitivity equations are built from it (check it with
///   [`check_jacobian`](super::check_jacobian)), unless the system supplies them itself
///   ([`ParametricSystem::sensitivity_rhs`]).
/// - `rhs`, `jacobian` and [`ParametricSystem::param_jacobian`] all use the parameters last
///   given to [`ParametricSystem::set_params`] (or the system's own), and are pure functions of
///   (t, y) in between.
/// - [`ParametricSystem::params`] returns [`ParametricSystem::n_params`] values, and
///   `set_params(&params())` leaves the system as it was.
/// - A parameter whose initial state depends on it (a steady start) is the caller's business:
///   pass ∂y0/∂p_j as the initial sensitivity.
///
/// # Reference
/// A. C. Hindmarsh, R. Serban et al., *User Documentation for CVODES*, "Forward sensitivity
/// analysis" (the sensitivity equations, the simultaneous and staggered correctors, the error
/// control of s_j); R. Serban and A. C. Hindmarsh, "CVODES: the sensitivity-enabled ODE
/// solver in SUNDIALS", Proc. IDETC/CIE 2005.
pub trait ParametricSystem: OdeSystem {
    /// Number of parameters m (≥ 1 for sensitivities).
    fn n_params(&self) -> usize;

    /// The current parameter values p_0, …, p_{m−1}.
    fn params(&self) -> Vec<f64>;

    /// Replaces the parameters (`p.len()` = [`ParametricSystem::n_params`]). Used between
    /// integrations (a fit's iterations, central differences), never during one.
    fn set_params(&mut self, p: &[f64]);

    /// Writes ∂f/∂p at (t, y) into `dfdp`, an n × m matrix (entry (i, j) = ∂f_i/∂p_j, set with
    /// `dfdp.set(i, j, value)`) that arrives zeroed.
    fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut JacobianMatrix<'_>);

    /// Whether [`ParametricSystem::sensitivity_rhs`] is implemented. When false (the default)
    /// the sensitivity right-hand side is the dense product (∂f/∂y) s_j plus column j of
    /// ∂f/∂p, both evaluated once per (t, y) and shared by every parameter.
    fn has_sensitivity_rhs(&self) -> bool {
        false
    }

    /// Writes (∂f/∂y) s_j + ∂f/∂p_j at (t, y) into `out`, for parameter `j` with the
    /// sensitivity `s`: for a system that forms it more cheaply than the dense product (a
    /// sparse Jacobian) or rounds it as a reference does (cvsRoberts_FSA_dns computes the
    /// second row as minus the sum of the other two, its conservation law). Called only when
    /// [`ParametricSystem::has_sensitivity_rhs`] returns true; it must equal the dense product
    /// up to rounding.
    fn sensitivity_rhs(&self, _t: f64, _y: &[f64], _j: usize, _s: &[f64], _out: &mut [f64]) {}
}
