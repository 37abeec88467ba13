//! The numerics the analyses share: event location on dense output and Hermite knots, the
//! check that a report holds finite numbers only, small linear least-squares fits, and the
//! reduction of a computed series for figures. Nothing here knows a scene or an analysis.

pub mod events;
pub mod finite;
pub mod fit;
pub mod series;
