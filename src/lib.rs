//! The `stickslip` command's application layer, over the stickslip library: the progress
//! line ([`cli`]), the stress grid ([`stress`]), the paper's reproduction ([`reproduce`]),
//! the SVG figures ([`figure`]) and the Robertson demonstration ([`robertson_examples`]).
//! src/main.rs parses the command line and calls these and the library.

#![deny(unsafe_code)]

pub mod cli;
pub mod figure;
pub mod reproduce;
pub mod robertson_examples;
pub mod stress;
