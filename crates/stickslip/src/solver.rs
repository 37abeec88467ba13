//! Solver selection as the library uses it: stickslip-ode's method table and its one
//! constructor for every method (re-exported here, so `stickslip::solver` keeps its paths),
//! and a scene's validated solver settings ([`SolverSpec`]). How the engine runs each method
//! is its own table, [`crate::engine::EngineSettings`].

use serde::Serialize;

pub use stickslip_ode::solver::*;

/// Validated solver settings of a scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolverSpec {
    /// The method.
    pub method: Method,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerances of (u, ln v, θ).
    pub atol: [f64; 3],
    /// Butcher table (implicit one for DIRK/IMEX, explicit one for ERK), None = default.
    pub table: Option<String>,
    /// Explicit table of an IMEX pair, None = default.
    pub explicit_table: Option<String>,
}

impl SolverSpec {
    /// The Butcher tables of these solver settings as the method's [`MethodSettings`], for a
    /// system that is or is not autonomous.
    pub fn method_settings(&self, autonomous: bool) -> MethodSettings {
        MethodSettings {
            table: self.table.clone(),
            explicit_table: self.explicit_table.clone(),
            autonomous,
            deduce_implicit_rhs: false,
            tolerance_transform: None,
        }
    }
}
