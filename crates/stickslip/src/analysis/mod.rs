//! The analyses a scene asks for (`analyses`), and nothing else: the linear analysis, the
//! cycle, shooting and continuation, the time series and its events, the response to periodic
//! loading and to noise, and the laboratory's run and fit. The numerics they share live in
//! [`crate::numerics`]; the analyses that exist to test the paper, and its claims, in
//! [`crate::paper`].

pub mod continuation;
pub mod cycle;
pub mod error;
pub mod hopf;
pub mod lab;
pub mod lab_fit;
pub mod locking;
pub mod noise;
pub mod period_map;
pub mod shooting;
pub mod time_series;

pub use error::{AnalysisError, InvalidOption};
