//! The integration contract shared by every integrator (SUNDIALS' CVODE and ARKODE today, the
//! homemade methods later): what a problem provides, which options a solver takes, the
//! statistics it reports and the typed errors it returns.

mod clock;
mod error;
mod extrapolation;
mod integrator;
mod linalg;
mod options;
mod parametric;
mod problem;
mod radau5;
mod rodas5p;
mod stats;
mod stepper;

pub use clock::{Clock, ClockStep, Time};
pub(crate) use error::panic_message;
pub use error::{brief_state, ErrorKind, SolverError};
pub use extrapolation::Extrapolation;
pub use integrator::Integrator;
pub use options::{ErrorScale, Options, OptionsError, Tolerance, DEFAULT_MAX_STEPS};
pub use parametric::ParametricSystem;
pub use problem::{
    check_implicit_jacobian, check_jacobian, jacobian_against_differences, ImexSystem,
    JacobianMatrix, JacobianMismatch, OdeSystem, RootFunction, Roots,
};
pub(crate) use problem::{implicit_jacobian_hint, jacobian_hint};
pub use radau5::{Radau5, ToleranceTransform};
pub use rodas5p::Rodas5p;
pub use stats::Stats;
pub(crate) use stepper::ErrorWeights;

/// How far one call to a solver's `advance` goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Task {
    /// Integrate past `tout` internally and return the solution interpolated at `tout`.
    Normal,
    /// Take one internal step and return.
    OneStep,
}

/// Why a call to `advance` returned.
#[derive(Debug, Clone, PartialEq)]
pub enum StepEvent {
    /// `tout` (task [`Task::Normal`]) or the end of one internal step (task [`Task::OneStep`]).
    Reached,
    /// The stop time was reached exactly.
    StopTime,
    /// One or more root functions changed sign. For each root function: `0` no root,
    /// `+1` rising through zero, `-1` falling through zero.
    Root(Vec<i32>),
}

/// The outcome of one successful call to `advance`.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Time of the returned state.
    pub t: f64,
    /// Why the call returned.
    pub event: StepEvent,
}
