//! stickslip-ode: stiff ODE integrators behind one contract.
//!
//! [`integrate`] holds the contract every integrator keeps (what a problem provides, the
//! options, the statistics, the typed errors) and the homemade methods (Radau5, Rodas5P,
//! extrapolation); [`sundials`] drives Debian's SUNDIALS (CVODE, ARKODE) through the same
//! contract; [`solver`] is the method table: each method by name with its dense-output order
//! (rows the integrators read too), what it can do ([`solver::Method::capabilities`]) and one
//! constructor for all; [`robertson`] is SUNDIALS' Robertson problem with its examples
//! replayed through the wrappers. A user who wants a stiff solver depends on this crate alone: it has
//! no scenes, no command line and no figures.
//!
//! All FFI lives in [`sundials`]; everywhere else the crate denies it (`deny(unsafe_code)`).

#![deny(unsafe_code)]

pub mod integrate;
mod method;
pub mod robertson;
pub mod solver;
pub mod sundials;
