//! The `stickslip` command's application layer, over the stickslip library: the progress
//! line ([`cli`]), the stress grid ([`stress`]), the paper's reproduction ([`reproduce`]),
//! and the SVG figures ([`figure`]).
//! src/main.rs parses the command line and calls these and the library.

#![deny(unsafe_code)]

pub mod cli;
pub mod figure;
pub mod reproduce;
pub mod stress;
