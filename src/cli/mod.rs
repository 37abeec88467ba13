//! The `stickslip` binary's own modules (not part of the library).

pub mod fit;
pub mod progress;
pub mod qdyn;

/// A failed command and its exit code: 2 for bad input, 1 for a failed computation, 4 for a
/// cycle analysis that did not converge.
pub struct Failure(pub u8, pub String);
