//! stickslip: very stiff stick-slip (Dieterich–Ruina rate-and-state friction) dynamics
//! integrated with Debian's SUNDIALS.
//!
//! Data flow: [`scene`] (JSON, validated) → [`model`] (the DRR system) → integrator (the
//! [`integrate`] contract, implemented over SUNDIALS in [`sundials`]) → [`analysis`] (hopf,
//! cycle, paper) → [`report`] (JSON). [`engine`] wires them. All FFI lives in [`sundials`];
//! everywhere else the crate denies it (`deny(unsafe_code)`).

#![deny(unsafe_code)]

pub mod analysis;
pub mod compare;
pub mod engine;
pub mod figure;
pub mod integrate;
pub mod model;
pub mod parallel;
pub mod report;
pub mod reproduce;
pub mod robertson_examples;
pub mod scene;
pub mod series_file;
pub mod solver;
pub mod stress;
pub mod sundials;
pub mod sweep;
