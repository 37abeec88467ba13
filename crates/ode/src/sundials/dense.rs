//! Dense matrix plus dense direct linear solver, as used by the implicit methods.

use super::context::Context;
use super::ffi;
use super::vector::SerialVector;
use std::ptr::NonNull;

/// An owned dense `SUNMatrix` and the `SUNLinearSolver` that factors it. Must be dropped
/// after the solver memory that uses it and before the context.
#[derive(Debug)]
pub(crate) struct DenseLinearSolver {
    matrix: NonNull<ffi::_generic_SUNMatrix>,
    solver: NonNull<ffi::_generic_SUNLinearSolver>,
}

impl DenseLinearSolver {
    pub(crate) fn new(template: &SerialVector, n: usize, ctx: &Context) -> Option<Self> {
        // sunindextype is 32-bit on Debian 13: refuse sizes it cannot hold.
        let n = ffi::sunindextype::try_from(n).ok()?;
        // SAFETY: creates an n×n dense matrix owned by the returned handle.
        let matrix = NonNull::new(unsafe { ffi::SUNDenseMatrix(n, n, ctx.raw()) })?;
        // SAFETY: `template` and `matrix` are live objects of matching size from `ctx`.
        let solver = unsafe { ffi::SUNLinSol_Dense(template.raw(), matrix.as_ptr(), ctx.raw()) };
        match NonNull::new(solver) {
            Some(solver) => Some(Self { matrix, solver }),
            None => {
                // SAFETY: the matrix was created above and is not referenced elsewhere.
                unsafe { ffi::SUNMatDestroy(matrix.as_ptr()) };
                None
            }
        }
    }

    pub(crate) fn matrix(&self) -> ffi::SUNMatrix {
        self.matrix.as_ptr()
    }

    pub(crate) fn solver(&self) -> ffi::SUNLinearSolver {
        self.solver.as_ptr()
    }
}

impl Drop for DenseLinearSolver {
    fn drop(&mut self) {
        // SAFETY: both objects were created in `new`, are freed exactly once, and the solver
        // memory that referenced them has already been freed by the owner.
        unsafe {
            ffi::SUNLinSolFree(self.solver.as_ptr());
            ffi::SUNMatDestroy(self.matrix.as_ptr());
        }
    }
}
