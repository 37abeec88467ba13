//! Models: ODE systems with their Jacobians.

pub mod drr;
pub mod friction;
pub mod robertson;
pub mod variational;

pub use drr::{Drr, DrrParams};
pub use friction::Friction;
pub use variational::Variational;
