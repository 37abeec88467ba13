//! stickslip: very stiff stick-slip (Dieterich–Ruina rate-and-state friction) dynamics
//! integrated with Debian's SUNDIALS.
//!
//! Data flow: scene → model → integrator → analysis → report. This crate currently provides
//! the integration contract ([`integrate`]) and its SUNDIALS implementation ([`sundials`]).
//! All `unsafe` code lives in [`sundials`].

#![deny(unsafe_code)]

pub mod analysis;
pub mod integrate;
pub mod model;
pub mod sundials;
