//! Models: ODE systems with their Jacobians.

pub mod drr;
pub mod friction;
pub mod robertson;

pub use drr::{Drr, DrrParams};
pub use friction::Friction;
