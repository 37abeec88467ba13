//! Models: ODE systems with their Jacobians and events.

pub mod robertson;
