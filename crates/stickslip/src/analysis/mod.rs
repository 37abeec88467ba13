//! Analyses of a scene: what `analyses` asks for, and nothing else.

pub mod asymptotics;
pub mod claims;
pub mod continuation;
pub mod cycle;
pub mod cycle_period;
pub mod error;
pub mod events;
pub mod finite;
pub mod fit;
pub mod hopf;
pub mod lab;
pub mod lab_fit;
pub mod locking;
pub mod lyapunov;
pub mod noise;
pub mod paper;
pub mod period_map;
pub mod series;
pub mod shooting;
pub mod time_series;

pub use error::{AnalysisError, InvalidOption};
