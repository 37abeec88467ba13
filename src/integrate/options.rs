//! Options common to all integrators.

/// Absolute tolerance: one value for every component, or one per component.
#[derive(Debug, Clone, PartialEq)]
pub enum Tolerance {
    /// The same absolute tolerance for every component.
    Scalar(f64),
    /// One absolute tolerance per component (length = system dimension).
    PerComponent(Vec<f64>),
}

/// How one component's local error is weighed: the error test asks each component's error to
/// stay below rtol·s_i + atol_i, where the scale s_i is the component's size (the usual, and
/// SUNDIALS' only, rule) or a fixed number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ErrorScale {
    /// s_i = |y_i|: the error relative to the component's size.
    Relative,
    /// s_i = the given number (> 0), whatever |y_i|: for a component that is a logarithm, such
    /// as w = ln v, whose absolute error is the relative error of v and whose size says nothing
    /// about the accuracy wanted (|ln v| = 20 at a slip's peak would loosen v's relative
    /// accuracy twentyfold). The tolerance is kept above 100 units of round-off of y_i, so
    /// that it stays attainable where |y_i| is far out of its usual range.
    Absolute(f64),
}

/// Default step budget per call to `advance` ([`Options::max_steps`]). SUNDIALS' own default,
/// 500, stops long stiff runs part-way (VDPOL to t = 2 at rtol 1e-8 needs thousands of steps),
/// while an unlimited budget would let a run whose step size stagnates above the round-off
/// floor go on for ever; one million steps completes every problem of the stiff test set
/// (docs/test-set.md) and still bounds a runaway run to seconds for small systems.
pub const DEFAULT_MAX_STEPS: i64 = 1_000_000;

/// Integrator options. `None` keeps the integrator's own default.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Relative tolerance (> 0).
    pub rtol: f64,
    /// Absolute tolerance (≥ 0, finite).
    pub atol: Tolerance,
    /// Maximum number of internal steps per call to `advance` (as SUNDIALS' `mxstep`): a call
    /// that needs more fails with [`crate::integrate::ErrorKind::TooMuchWork`] at the last
    /// step reached, from where a further call may go on. `None` is [`DEFAULT_MAX_STEPS`] for
    /// every integrator, so that a whole integration finishes in one call; pass `Some(500)`
    /// for SUNDIALS' own default.
    pub max_steps: Option<i64>,
    /// Maximum method order. Only CVODE (≤ 5 for BDF, ≤ 12 for Adams) and Extrapolation (4 to
    /// 12 tableau rows) have one; the other integrators reject it with
    /// [`crate::integrate::ErrorKind::InvalidInput`].
    pub max_order: Option<i32>,
    /// First step size to try.
    pub initial_step: Option<f64>,
    /// Lower bound on |h|.
    pub min_step: Option<f64>,
    /// Upper bound on |h|.
    pub max_step: Option<f64>,
    /// Time the integrator must not step past.
    pub stop_time: Option<f64>,
    /// Maximum error-test failures in one step.
    pub max_err_test_fails: Option<i32>,
    /// Maximum nonlinear iterations per step attempt.
    pub max_nonlin_iters: Option<i32>,
    /// Maximum nonlinear convergence failures in one step.
    pub max_conv_fails: Option<i32>,
    /// Safety factor in the nonlinear convergence test.
    pub nonlin_conv_coef: Option<f64>,
    /// Most steps between two Jacobian evaluations (1: a fresh Jacobian at every step). For
    /// systems whose stiff rates change by large factors within a few steps (the DRR's
    /// γ²e^(−ln v)/ξ on the stick), where a Newton iteration with an older Jacobian leaves an
    /// error in the stiff components that the next steps amplify. CVODE and ARKStep (implicit)
    /// set their linear-solver setup and Jacobian frequencies to it; Radau5 evaluates a new one
    /// after that many accepted steps even when its Newton contraction allows reuse; Rodas5P
    /// evaluates the Jacobian at every step anyway; Extrapolation (reuse by its stability
    /// checks) and ARKStep ERK (no Jacobian) reject it.
    pub jacobian_max_age: Option<i64>,
    /// When true, a step below the spacing of t ("t + h = t") makes `advance` fail with
    /// [`crate::integrate::ErrorKind::StepUnderflow`]; when false it is counted in
    /// [`crate::integrate::Stats::step_underflow_warnings`] and integration goes on.
    pub fail_on_step_underflow: bool,
    /// One [`ErrorScale`] per component; `None` weighs every component relative to its size.
    /// CVODE and ARKStep take it through a user error-weight function (`*WFtolerances`); the
    /// homemade integrators reject it with [`crate::integrate::ErrorKind::InvalidInput`].
    pub error_scales: Option<Vec<ErrorScale>>,
}

impl Options {
    /// Options with the given tolerances and every other setting at its default.
    pub fn new(rtol: f64, atol: Tolerance) -> Self {
        Self {
            rtol,
            atol,
            max_steps: None,
            max_order: None,
            initial_step: None,
            min_step: None,
            max_step: None,
            stop_time: None,
            max_err_test_fails: None,
            max_nonlin_iters: None,
            max_conv_fails: None,
            nonlin_conv_coef: None,
            jacobian_max_age: None,
            fail_on_step_underflow: true,
            error_scales: None,
        }
    }

    /// Checks the options against a system of dimension `dim`; the error names the field.
    pub fn validate(&self, dim: usize) -> Result<(), String> {
        if !(self.rtol.is_finite() && self.rtol > 0.0) {
            return Err(format!("rtol = {} must be finite and > 0 (e.g. 1e-8)", self.rtol));
        }
        match &self.atol {
            Tolerance::Scalar(a) if !(a.is_finite() && *a >= 0.0) => {
                return Err(format!("atol = {a} must be finite and ≥ 0"));
            }
            Tolerance::PerComponent(v) if v.len() != dim => {
                return Err(format!("atol has {} components; the system has {dim}", v.len()));
            }
            Tolerance::PerComponent(v) if v.iter().any(|a| !(a.is_finite() && *a >= 0.0)) => {
                return Err(format!("atol = {v:?}: every component must be finite and ≥ 0"));
            }
            _ => {}
        }
        if let Some(scales) = &self.error_scales {
            if scales.len() != dim {
                return Err(format!(
                    "error_scales has {} components; the system has {dim}",
                    scales.len()
                ));
            }
            if let Some(i) = scales
                .iter()
                .position(|s| matches!(s, ErrorScale::Absolute(c) if !(c.is_finite() && *c > 0.0)))
            {
                return Err(format!(
                    "error_scales[{i}] = {:?}: an absolute scale must be finite and > 0",
                    scales[i]
                ));
            }
        }
        let positive = [
            ("initial_step", self.initial_step),
            ("min_step", self.min_step),
            ("max_step", self.max_step),
            ("nonlin_conv_coef", self.nonlin_conv_coef),
        ];
        for (name, value) in positive {
            if let Some(v) = value {
                if !(v.is_finite() && v > 0.0) {
                    return Err(format!("{name} = {v} must be finite and > 0"));
                }
            }
        }
        if let Some(t) = self.stop_time {
            if !t.is_finite() {
                return Err(format!("stop_time = {t} must be finite"));
            }
        }
        let counts = [
            ("max_order", self.max_order.map(i64::from)),
            ("max_err_test_fails", self.max_err_test_fails.map(i64::from)),
            ("max_nonlin_iters", self.max_nonlin_iters.map(i64::from)),
            ("max_conv_fails", self.max_conv_fails.map(i64::from)),
            ("max_steps", self.max_steps),
            ("jacobian_max_age", self.jacobian_max_age),
        ];
        for (name, value) in counts {
            if let Some(v) = value {
                if v < 1 {
                    return Err(format!("{name} = {v} must be ≥ 1"));
                }
            }
        }
        Ok(())
    }
}
