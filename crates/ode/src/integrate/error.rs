//! Typed integrator errors.

/// What went wrong, independent of the integrator.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ErrorKind {
    /// The step budget (`max_steps`) ran out before the output time.
    #[error("too much work: max_steps reached before the output time (raise max_steps)")]
    TooMuchWork,
    /// The requested accuracy is below what double precision allows at this state.
    #[error(
        "accuracy not attainable: tolerances too tight for double precision (loosen rtol/atol)"
    )]
    AccuracyNotAttainable,
    /// The local error test failed repeatedly, or with |h| = min_step.
    #[error("repeated local error-test failures (singularity or tolerances too tight?)")]
    ErrorTestFailures,
    /// The nonlinear (Newton) solver failed to converge repeatedly.
    #[error("repeated nonlinear convergence failures")]
    ConvergenceFailures,
    /// The linear solver failed (e.g. a singular iteration matrix).
    #[error("linear solver failure")]
    LinearSolver,
    /// The right-hand side failed (returned non-finite values) unrecoverably or repeatedly.
    #[error("right-hand side failure (non-finite values that a smaller step did not cure)")]
    RhsFailure,
    /// The root (event) function failed or returned non-finite values.
    #[error("root-function failure")]
    RootFunctionFailure,
    /// The step fell below the floating-point spacing of t ("t + h = t").
    #[error("step underflow: t + h = t (the step is below the spacing of t; re-base time)")]
    StepUnderflow,
    /// A user callback (right-hand side, Jacobian, root function) panicked; the panic message
    /// is the error's message. Every integrator catches the panic and returns this error at the
    /// last accepted step; the integrator can go on from there.
    #[error("a user callback panicked")]
    CallbackPanic,
    /// Invalid input (options, initial state, output time, dense-output request).
    #[error("invalid input")]
    InvalidInput,
    /// The caller stopped the integration (e.g. Ctrl-C): not a numerical failure. A caller's
    /// wrapper returns it once its cancel flag is set, and can then report that the run was
    /// cancelled instead of this error.
    #[error("cancelled by the caller")]
    Cancelled,
    /// The steps no longer move the solution: a run stopped because many steps in a row left
    /// the state unchanged although its derivative is not zero (the message says which
    /// component and why).
    #[error("no progress")]
    NoProgress,
    /// Any other failure reported by the integrator (the code is in the message).
    #[error("integrator failure")]
    Other,
}

/// A failed integration: what, where (t and state) and the integrator's own message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{solver} failed at t = {t:e} (state {}): {kind}{}", brief_state(.state), detail(.message))]
pub struct SolverError {
    /// The method's name, e.g. "cvode-bdf" or "radau5" ([`super::Integrator::name`]).
    pub solver: &'static str,
    /// Classification of the failure.
    pub kind: ErrorKind,
    /// Time reached when the failure occurred.
    pub t: f64,
    /// State at `t` (empty when no state was available).
    pub state: Vec<f64>,
    /// The integrator's return code (0 when the error was raised before calling it).
    pub flag: i32,
    /// The integrator's message, or ours.
    pub message: String,
}

/// A state for a message: every component of a short one; the first four, the number of
/// components and the largest magnitude of a long one.
pub fn brief_state(state: &[f64]) -> String {
    const SHOWN: usize = 4;
    if state.len() <= 2 * SHOWN {
        return format!("{state:?}");
    }
    let first: Vec<String> = state[..SHOWN].iter().map(|v| format!("{v:?}")).collect();
    let largest = state.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    format!("[{}, … ({} components, max |y_i| = {largest:e})]", first.join(", "), state.len())
}

fn detail(message: &str) -> String {
    if message.is_empty() {
        String::new()
    } else {
        format!(" — {message}")
    }
}

/// The text of a caught panic's payload (a `&str` or `String` message), for
/// [`ErrorKind::CallbackPanic`].
pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "non-string panic payload".to_string())
}
