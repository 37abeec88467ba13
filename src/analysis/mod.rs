//! Analyses of a scene: what `analyses` asks for, and nothing else.

pub mod cycle;
pub mod events;
pub mod hopf;
pub mod paper;
pub mod asymptotics;
pub mod claims;
pub mod finite;
pub mod fit;
pub mod orbit;
pub mod series;
