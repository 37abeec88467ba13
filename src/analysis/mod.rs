//! Analyses of a scene: what `analyses` asks for, and nothing else.

pub mod continuation;
pub mod cycle;
pub mod error;
pub mod events;
pub mod hopf;
pub mod noise;
pub mod paper;
pub mod asymptotics;
pub mod claims;
pub mod finite;
pub mod fit;
pub mod lyapunov;
pub mod cycle_period;
pub mod series;
pub mod period_map;
pub mod shooting;

pub use error::{AnalysisError, InvalidOption};
