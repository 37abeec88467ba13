//! The `stickslip` binary's own modules (not part of the library).

pub mod progress;
pub mod qdyn;
