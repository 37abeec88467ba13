//! Safe wrappers over Debian's SUNDIALS (CVODE, with CVODES' forward sensitivities, and
//! ARKODE's ARKStep). This module is the only home of `unsafe` code in the crate; every unsafe
//! block carries a SAFETY comment.
//!
//! One type, [`Solver`], drives either family through the contract of
//! [`crate::integrate`]: tolerances and options, analytic dense Jacobians, root finding with
//! directions (changeable between calls), dense output, restarts and full statistics. Failures
//! come back as [`SolverError`](crate::integrate::SolverError) with t, state and SUNDIALS'
//! message; panics in callbacks never cross into C. [`SensitivitySolver`] adds CVODES' forward
//! sensitivities s_j = ∂y/∂p_j for a [`ParametricSystem`](crate::integrate::ParametricSystem).

#![allow(unsafe_code)]

mod arkode;
mod callbacks;
mod context;
mod cvode;
mod cvodes;
mod dense;
mod ffi;
mod solver;
mod vector;

pub use arkode::{default_imex_tables, ArkMethod, ArkSettings, DirkTable, ErkTable};
pub use cvode::{CvodeMethod, CvodeSettings};
pub use cvodes::{
    SensitivityCorrector, SensitivitySettings, SensitivitySolver, SensitivityStats,
    SensitivityTolerance,
};
pub use solver::Solver;

/// Version of the SUNDIALS library linked at run time, e.g. "6.4.1".
pub fn version() -> String {
    let mut buffer = [0 as std::ffi::c_char; 64];
    // SAFETY: SUNDIALSGetVersion writes a NUL-terminated string of at most `len` bytes.
    let flag =
        unsafe { ffi::SUNDIALSGetVersion(buffer.as_mut_ptr(), buffer.len() as std::ffi::c_int) };
    if flag != 0 {
        return "unknown".into();
    }
    // SAFETY: the buffer now holds a NUL-terminated string (and is zero-initialised anyway).
    unsafe { std::ffi::CStr::from_ptr(buffer.as_ptr()) }.to_string_lossy().into_owned()
}

/// SUNDIALS version of the headers stickslip was compiled against.
pub const HEADER_VERSION: &str = env!("STICKSLIP_SUNDIALS_HEADER_VERSION");
