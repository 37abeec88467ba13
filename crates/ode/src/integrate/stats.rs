//! Integrator statistics.

/// Work counters and step information of one integrator, accumulated over its whole life
/// (re-initialisations included).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Accepted internal steps.
    pub steps: u64,
    /// Attempted internal steps (accepted + rejected).
    pub step_attempts: u64,
    /// Evaluations of the (implicit) right-hand side by the integrator, excluding those for
    /// finite-difference Jacobians.
    pub rhs_evals: u64,
    /// Evaluations of the explicit right-hand side f_E (ARKODE IMEX/ERK; 0 otherwise).
    pub rhs_evals_explicit: u64,
    /// Right-hand side evaluations spent on finite-difference Jacobians.
    pub rhs_evals_jacobian: u64,
    /// Jacobian evaluations (analytic or finite-difference).
    pub jac_evals: u64,
    /// Linear-solver setups (matrix factorisations).
    pub lin_setups: u64,
    /// Local error-test failures.
    pub err_test_fails: u64,
    /// Nonlinear (Newton) iterations.
    pub nonlin_iters: u64,
    /// Nonlinear convergence failures.
    pub nonlin_conv_fails: u64,
    /// Step attempts that failed in the nonlinear solver.
    pub step_solve_fails: u64,
    /// Root-function evaluations.
    pub root_evals: u64,
    /// Order reductions by BDF stability-limit detection.
    pub stab_lim_order_reductions: u64,
    /// "t + h = t" warnings: steps smaller than the floating-point spacing of t.
    pub step_underflow_warnings: u64,
    /// Right-hand side calls that returned a non-finite value (reported as recoverable).
    pub nonfinite_rhs: u64,
    /// Re-initialisations (restarts).
    pub reinits: u64,
    /// Size of the last successful step.
    pub last_step: f64,
    /// Step size to be tried next.
    pub current_step: f64,
    /// Actual size of the very first step.
    pub initial_step: f64,
    /// Order of the last step (for one-step methods, the order of the method).
    pub last_order: i32,
}

impl Stats {
    /// Adds the counters of `later` (a later run segment) to `self`; step information is
    /// taken from `later`.
    pub fn accumulate(&mut self, later: &Stats) {
        let initial_step = if self.steps == 0 { later.initial_step } else { self.initial_step };
        self.steps += later.steps;
        self.step_attempts += later.step_attempts;
        self.rhs_evals += later.rhs_evals;
        self.rhs_evals_explicit += later.rhs_evals_explicit;
        self.rhs_evals_jacobian += later.rhs_evals_jacobian;
        self.jac_evals += later.jac_evals;
        self.lin_setups += later.lin_setups;
        self.err_test_fails += later.err_test_fails;
        self.nonlin_iters += later.nonlin_iters;
        self.nonlin_conv_fails += later.nonlin_conv_fails;
        self.step_solve_fails += later.step_solve_fails;
        self.root_evals += later.root_evals;
        self.stab_lim_order_reductions += later.stab_lim_order_reductions;
        self.step_underflow_warnings += later.step_underflow_warnings;
        self.nonfinite_rhs += later.nonfinite_rhs;
        self.reinits += later.reinits;
        self.last_step = later.last_step;
        self.current_step = later.current_step;
        self.initial_step = initial_step;
        self.last_order = later.last_order;
    }
}
