//! Options common to all integrators.

/// Absolute tolerance: one value for every component, or one per component.
#[derive(Debug, Clone, PartialEq)]
pub enum Tolerance {
    /// The same absolute tolerance for every component.
    Scalar(f64),
    /// One absolute tolerance per component (length = system dimension).
    PerComponent(Vec<f64>),
}

impl Tolerance {
    /// One absolute tolerance per component of a system of dimension `n` (a per-component
    /// tolerance is assumed to have length `n`, as [`Options::validate`] checks).
    pub fn to_vec(&self, n: usize) -> Vec<f64> {
        match self {
            Tolerance::Scalar(a) => vec![*a; n],
            Tolerance::PerComponent(v) => v.clone(),
        }
    }
}

/// How one component's local error is weighed: the error test asks each component's error to
/// stay below rtol·s_i + atol_i, where the scale s_i is the component's size (the usual, and
/// SUNDIALS' only, rule) or a fixed number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ErrorScale {
    /// s_i = |y_i|: the error relative to the component's size.
    Relative,
    /// s_i = the given number (> 0), whatever |y_i|: for a component that is a logarithm,
    /// such as w = log x, whose absolute error is the relative error of x and whose size says
    /// nothing about the accuracy wanted (|w| = 20 would loosen x's relative accuracy
    /// twentyfold). The tolerance is kept above 100 units of round-off of y_i, so
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
    /// systems whose stiff rates change by large factors within a few steps (e.g. a rate
    /// exponential in one component), where a Newton iteration with an older Jacobian leaves an
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
    /// homemade integrators use it wherever they form error weights (Radau5 with the rtol' its
    /// [`crate::integrate::ToleranceTransform`] gives: an absolute scale c weighs rtol'·c; Rodas5P and
    /// Extrapolation's explicit scheme, which weigh by the larger of |y| at the step's two
    /// ends, weigh rtol·c instead). Every scale [`ErrorScale::Relative`] is the same
    /// integration, bit for bit, as `None`.
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
    pub fn validate(&self, dim: usize) -> Result<(), OptionsError> {
        if !(self.rtol.is_finite() && self.rtol > 0.0) {
            return Err(OptionsError::Rtol { rtol: self.rtol });
        }
        match &self.atol {
            Tolerance::Scalar(a) if !(a.is_finite() && *a >= 0.0) => {
                return Err(OptionsError::Atol { atol: *a });
            }
            Tolerance::PerComponent(v) if v.len() != dim => {
                return Err(OptionsError::AtolLength { len: v.len(), dim });
            }
            Tolerance::PerComponent(v) if v.iter().any(|a| !(a.is_finite() && *a >= 0.0)) => {
                return Err(OptionsError::AtolComponent { atol: v.clone() });
            }
            _ => {}
        }
        if let Some(scales) = &self.error_scales {
            if scales.len() != dim {
                return Err(OptionsError::ErrorScalesLength { len: scales.len(), dim });
            }
            let bad = |s: &ErrorScale| matches!(s, ErrorScale::Absolute(c) if !(c.is_finite() && *c > 0.0));
            if let Some(index) = scales.iter().position(bad) {
                return Err(OptionsError::ErrorScale { index, scale: scales[index] });
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
                    return Err(OptionsError::NotPositive { name, value: v });
                }
            }
        }
        if let Some(t) = self.stop_time {
            if !t.is_finite() {
                return Err(OptionsError::StopTime { stop_time: t });
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
                    return Err(OptionsError::CountBelowOne { name, value: v });
                }
            }
        }
        Ok(())
    }
}

/// Why [`Options::validate`] refuses the options; each message names the field and what would
/// be valid. Integrators report it as [`crate::integrate::ErrorKind::InvalidInput`] with this
/// message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptionsError {
    /// `rtol` is not finite or not > 0.
    #[error("rtol = {rtol} must be finite and > 0 (e.g. 1e-8)")]
    Rtol {
        /// The value given.
        rtol: f64,
    },
    /// A scalar `atol` is not finite or is negative.
    #[error("atol = {atol} must be finite and ≥ 0")]
    Atol {
        /// The value given.
        atol: f64,
    },
    /// A per-component `atol` whose length is not the system's dimension.
    #[error("atol has {len} components; the system has {dim}")]
    AtolLength {
        /// Components given.
        len: usize,
        /// The system's dimension.
        dim: usize,
    },
    /// A per-component `atol` with a component not finite or negative.
    #[error("atol = {atol:?}: every component must be finite and ≥ 0")]
    AtolComponent {
        /// The values given.
        atol: Vec<f64>,
    },
    /// `error_scales` whose length is not the system's dimension.
    #[error("error_scales has {len} components; the system has {dim}")]
    ErrorScalesLength {
        /// Components given.
        len: usize,
        /// The system's dimension.
        dim: usize,
    },
    /// An absolute error scale not finite or not > 0.
    #[error("error_scales[{index}] = {scale:?}: an absolute scale must be finite and > 0")]
    ErrorScale {
        /// The component.
        index: usize,
        /// The scale given.
        scale: ErrorScale,
    },
    /// A step size or coefficient (`initial_step`, `min_step`, `max_step`,
    /// `nonlin_conv_coef`) not finite or not > 0.
    #[error("{name} = {value} must be finite and > 0")]
    NotPositive {
        /// The field.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// `stop_time` is not finite.
    #[error("stop_time = {stop_time} must be finite")]
    StopTime {
        /// The value given.
        stop_time: f64,
    },
    /// A count (`max_order`, `max_steps`, `jacobian_max_age`, …) below 1.
    #[error("{name} = {value} must be ≥ 1")]
    CountBelowOne {
        /// The field.
        name: &'static str,
        /// The value given.
        value: i64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each refusal is its own variant, and its message is the one the integrators have always
    /// reported (tests/contract.rs matches on some of them).
    #[test]
    fn validate_names_the_field_with_a_typed_error() {
        let ok = Options::new(1e-8, Tolerance::Scalar(1e-10));
        assert_eq!(ok.validate(3), Ok(()));
        let rtol = Options::new(0.0, Tolerance::Scalar(1e-10)).validate(3).unwrap_err();
        assert_eq!(rtol, OptionsError::Rtol { rtol: 0.0 });
        assert_eq!(rtol.to_string(), "rtol = 0 must be finite and > 0 (e.g. 1e-8)");
        let short = Options::new(1e-8, Tolerance::PerComponent(vec![1e-10; 2])).validate(3);
        assert_eq!(short.unwrap_err().to_string(), "atol has 2 components; the system has 3");
        let negative = Options::new(1e-8, Tolerance::PerComponent(vec![1e-10, -1.0]));
        assert_eq!(
            negative.validate(2).unwrap_err().to_string(),
            "atol = [1e-10, -1.0]: every component must be finite and ≥ 0"
        );
        let max_step = Options { max_step: Some(f64::NAN), ..ok.clone() }.validate(3);
        assert_eq!(max_step.unwrap_err().to_string(), "max_step = NaN must be finite and > 0");
        let stop = Options { stop_time: Some(f64::INFINITY), ..ok.clone() }.validate(3);
        assert_eq!(stop.unwrap_err(), OptionsError::StopTime { stop_time: f64::INFINITY });
        let age = Options { jacobian_max_age: Some(0), ..ok }.validate(3).unwrap_err();
        assert_eq!(age, OptionsError::CountBelowOne { name: "jacobian_max_age", value: 0 });
        assert_eq!(age.to_string(), "jacobian_max_age = 0 must be ≥ 1");
    }
}
