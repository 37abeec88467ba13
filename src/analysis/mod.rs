//! Analyses of a scene: what `analyses` asks for, and nothing else.

pub mod continuation;
pub mod cycle;
pub mod events;
pub mod hopf;
pub mod paper;
pub mod period_map;
pub mod shooting;
