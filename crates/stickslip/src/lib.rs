//! stickslip: very stiff stick-slip (Dieterich–Ruina rate-and-state friction) dynamics
//! integrated with Debian's SUNDIALS.
//!
//! Data flow: [`scene`] (JSON, validated) → [`model`] (the DRR system and its relatives) →
//! integrator (the [`integrate`] contract, implemented over SUNDIALS in [`sundials`] and by
//! the homemade methods; [`solver`] picks one by name) → [`analysis`] (what a scene asks for,
//! over the shared [`numerics`]; the paper's claims tested in [`paper`]) → [`report`] (JSON).
//! [`engine`] wires them; [`sweep`] maps a scene over a parameter grid and [`compare`] checks
//! a trajectory from elsewhere against a scene. The integrators live in the `stickslip-ode`
//! crate and are re-exported here under their old paths ([`solver`] adds a scene's solver
//! settings to the ODE crate's method table).

#![deny(unsafe_code)]

pub use stickslip_ode::{integrate, robertson, sundials};

pub mod analysis;
pub mod compare;
pub mod engine;
pub mod model;
pub mod numerics;
pub mod paper;
pub mod parallel;
pub mod report;
pub mod scene;
pub mod series_file;
pub mod solver;
pub mod sweep;
