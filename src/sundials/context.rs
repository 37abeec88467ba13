//! The SUNDIALS context (`SUNContext`), created first and freed last.

use super::ffi;
use std::ptr::NonNull;

/// Owns a `SUNContext`. Everything created with it must be freed before it (the solver types
/// guarantee this by field order).
#[derive(Debug)]
pub(crate) struct Context {
    raw: NonNull<ffi::_SUNContext>,
}

impl Context {
    /// Creates a context without MPI communicator.
    pub(crate) fn new() -> Option<Self> {
        let mut raw: ffi::SUNContext = std::ptr::null_mut();
        // SAFETY: SUNContext_Create writes a new context into `raw`; a null communicator is
        // the documented value for serial (non-MPI) use in SUNDIALS 6.
        let flag = unsafe { ffi::SUNContext_Create(std::ptr::null_mut(), &mut raw) };
        if flag != 0 {
            return None;
        }
        NonNull::new(raw).map(|raw| Self { raw })
    }

    pub(crate) fn raw(&self) -> ffi::SUNContext {
        self.raw.as_ptr()
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        let mut raw = self.raw.as_ptr();
        // SAFETY: `raw` came from SUNContext_Create and is freed exactly once, here; owners
        // drop every object created with the context before the context itself.
        unsafe { ffi::SUNContext_Free(&mut raw) };
    }
}
