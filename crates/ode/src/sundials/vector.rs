//! Serial `N_Vector`s with RAII.

use super::context::Context;
use super::ffi;
use std::ptr::NonNull;

/// An owned serial `N_Vector` of fixed length.
#[derive(Debug)]
pub(crate) struct SerialVector {
    raw: NonNull<ffi::_generic_N_Vector>,
    len: usize,
}

impl SerialVector {
    /// A new vector holding a copy of `values`.
    pub(crate) fn from_slice(values: &[f64], ctx: &Context) -> Option<Self> {
        let len = values.len();
        // sunindextype is 32-bit on Debian 13 (64-bit on 12): refuse lengths it cannot hold.
        let n = ffi::sunindextype::try_from(len).ok()?;
        // SAFETY: N_VNew_Serial allocates a vector of `len` reals owned by the returned
        // handle; `ctx` is a live context.
        let raw = unsafe { ffi::N_VNew_Serial(n, ctx.raw()) };
        let mut vector = Self { raw: NonNull::new(raw)?, len };
        vector.as_mut_slice().copy_from_slice(values);
        Some(vector)
    }

    pub(crate) fn raw(&self) -> ffi::N_Vector {
        self.raw.as_ptr()
    }

    pub(crate) fn as_slice(&self) -> &[f64] {
        // SAFETY: a serial vector owns a contiguous array of `len` reals that lives as long as
        // the vector; the shared borrow of `self` prevents concurrent mutation through us.
        unsafe { std::slice::from_raw_parts(data(self.raw()), self.len) }
    }

    pub(crate) fn as_mut_slice(&mut self) -> &mut [f64] {
        // SAFETY: as in `as_slice`, with exclusive access through `&mut self`.
        unsafe { std::slice::from_raw_parts_mut(data(self.raw()), self.len) }
    }
}

impl Drop for SerialVector {
    fn drop(&mut self) {
        // SAFETY: the vector was created by N_VNew_Serial and is destroyed exactly once.
        unsafe { ffi::N_VDestroy(self.raw()) };
    }
}

/// The data array of a serial vector, read from its content as nvector_serial.h's NV_DATA_S
/// does. N_VGetArrayPointer gives the same pointer through two calls (the generic function and
/// the vector's operation), ~20 instructions on each of the two or three per callback: 2 % of
/// an ERK cycle (issue #17).
///
/// # Safety
/// `v` must be a valid serial `N_Vector` (made by N_VNew_Serial, or cloned from one, as every
/// vector SUNDIALS hands the callbacks here is).
unsafe fn data(v: ffi::N_Vector) -> *mut f64 {
    // SAFETY: a serial vector's content is an `_N_VectorContent_Serial` (caller's guarantee).
    unsafe { (*((*v).content as *const ffi::_N_VectorContent_Serial)).data }
}

/// Views a SUNDIALS-owned serial vector as a slice for the duration of a callback.
///
/// # Safety
/// `v` must be a valid serial `N_Vector` of length `len` that outlives `'a` and is not
/// accessed through another path while the slice is alive.
pub(crate) unsafe fn slice<'a>(v: ffi::N_Vector, len: usize) -> &'a [f64] {
    // SAFETY: guaranteed by the caller (see above).
    unsafe { std::slice::from_raw_parts(data(v), len) }
}

/// Mutable counterpart of [`slice`].
///
/// # Safety
/// As for [`slice`], with exclusive access.
pub(crate) unsafe fn slice_mut<'a>(v: ffi::N_Vector, len: usize) -> &'a mut [f64] {
    // SAFETY: guaranteed by the caller (see above).
    unsafe { std::slice::from_raw_parts_mut(data(v), len) }
}
