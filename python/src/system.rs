//! A user's Python right-hand side (and Jacobian) as an [`OdeSystem`].
//!
//! The integrators call `rhs`/`jacobian` through `&self` and cannot be told "stop with this
//! Python exception". So a callback that raises (or returns the wrong shape, or sees a
//! pending Ctrl-C) stashes the exception and unwinds with `resume_unwind`, which runs no panic
//! hook (nothing is printed). Every integrator catches the unwind at its boundary and returns
//! `ErrorKind::CallbackPanic` at the last accepted step; the caller then takes the stashed
//! exception and raises it unchanged.

use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::cell::{Cell, RefCell};
use stickslip::integrate::{JacobianMatrix, OdeSystem};

/// The Jacobian as the user gave it.
pub enum Jacobian<'py> {
    /// None: the implicit methods difference the right-hand side.
    None,
    /// A callable `jac(t, y)` returning an (n, n) array (dense, or sparse with `toarray`).
    Callable(Bound<'py, PyAny>),
    /// A constant (n, n) matrix, row-major.
    Constant(Vec<f64>),
}

/// A shape as Python writes it: (3,) or (3, 3).
fn python_shape(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

/// The payload of the unwind that stops an integrator after a Python exception.
struct PythonRaised;

/// `fun(t, y)` (and `jac`) of a Python user as an [`OdeSystem`].
pub struct PySystem<'py> {
    py: Python<'py>,
    n: usize,
    fun: Bound<'py, PyAny>,
    jac: Jacobian<'py>,
    asarray: Bound<'py, PyAny>,
    /// The first exception a callback raised; once set, every callback unwinds at once.
    error: RefCell<Option<PyErr>>,
    /// Calls of `fun` and of a callable `jac`.
    pub nfev: Cell<u64>,
    /// Calls of a callable `jac`.
    pub njev: Cell<u64>,
}

impl<'py> PySystem<'py> {
    /// The system of `fun` and `jac` of dimension `n`.
    pub fn new(
        py: Python<'py>,
        n: usize,
        fun: Bound<'py, PyAny>,
        jac: Jacobian<'py>,
    ) -> PyResult<Self> {
        let asarray = py.import("numpy")?.getattr("asarray")?;
        Ok(Self {
            py,
            n,
            fun,
            jac,
            asarray,
            error: RefCell::new(None),
            nfev: Cell::new(0),
            njev: Cell::new(0),
        })
    }

    /// The exception a callback raised, if any (taken: a second call returns None).
    pub fn take_error(&self) -> Option<PyErr> {
        self.error.borrow_mut().take()
    }

    /// Stashes `e` and unwinds out of the integrator (see the module comment).
    fn raise(&self, e: PyErr) -> ! {
        self.error.borrow_mut().get_or_insert(e);
        std::panic::resume_unwind(Box::new(PythonRaised))
    }

    /// `values` as a float64 array of exactly `len` elements and the given shape (for the
    /// message), copied into `out`.
    fn copy_result(
        &self,
        what: &str,
        value: Bound<'py, PyAny>,
        shape: &[usize],
        out: &mut [f64],
    ) -> PyResult<()> {
        // The common case first: a contiguous float64 array of the right shape, copied
        // without numpy.asarray (a Python call per evaluation).
        if let Ok(array) = value.cast::<numpy::PyArrayDyn<f64>>() {
            if array.shape() == shape {
                if let Ok(s) = array.readonly().as_slice() {
                    out.copy_from_slice(s);
                    return Ok(());
                }
            }
        }
        let value = if shape.len() == 2 && value.hasattr("toarray")? {
            value.call_method0("toarray")?
        } else {
            value
        };
        let array = self.asarray.call1((value, "float64"))?;
        let array = array.cast_into::<numpy::PyArrayDyn<f64>>().map_err(PyErr::from)?;
        if array.shape() != shape {
            return Err(PyValueError::new_err(format!(
                "{what} returned an array of shape {}; expected {}",
                python_shape(array.shape()),
                python_shape(shape)
            )));
        }
        let readonly = array.readonly();
        match readonly.as_slice() {
            Ok(s) => out.copy_from_slice(s),
            Err(_) => {
                for (o, v) in out.iter_mut().zip(readonly.as_array().iter()) {
                    *o = *v;
                }
            }
        }
        Ok(())
    }

    fn call_fun(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> PyResult<()> {
        self.py.check_signals()?;
        self.nfev.set(self.nfev.get() + 1);
        let y = PyArray1::from_slice(self.py, y);
        let value = self.fun.call1((t, y))?;
        self.copy_result("fun", value, &[self.n], dydt)
    }

    fn call_jac(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) -> PyResult<()> {
        let n = self.n;
        let mut rows = vec![0.0; n * n];
        match &self.jac {
            Jacobian::None => return Ok(()),
            Jacobian::Constant(m) => rows.copy_from_slice(m),
            Jacobian::Callable(f) => {
                self.py.check_signals()?;
                self.njev.set(self.njev.get() + 1);
                let y = PyArray1::from_slice(self.py, y);
                let value = f.call1((t, y))?;
                self.copy_result("jac", value, &[n, n], &mut rows)?;
            }
        }
        for r in 0..n {
            for c in 0..n {
                jac.set(r, c, rows[r * n + c]);
            }
        }
        Ok(())
    }
}

impl OdeSystem for PySystem<'_> {
    fn dim(&self) -> usize {
        self.n
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        if self.error.borrow().is_some() {
            std::panic::resume_unwind(Box::new(PythonRaised));
        }
        if let Err(e) = self.call_fun(t, y, dydt) {
            self.raise(e);
        }
    }

    fn has_jacobian(&self) -> bool {
        !matches!(self.jac, Jacobian::None)
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        if self.error.borrow().is_some() {
            std::panic::resume_unwind(Box::new(PythonRaised));
        }
        if let Err(e) = self.call_jac(t, y, jac) {
            self.raise(e);
        }
    }
}

/// A borrowed [`PySystem`] as an [`OdeSystem`], so that the caller keeps the system (its
/// stashed exception and counters) while an integrator owns this handle.
pub struct SystemRef<'a, 'py>(pub &'a PySystem<'py>);

impl OdeSystem for SystemRef<'_, '_> {
    fn dim(&self) -> usize {
        self.0.dim()
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.0.rhs(t, y, dydt)
    }

    fn has_jacobian(&self) -> bool {
        self.0.has_jacobian()
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.0.jacobian(t, y, jac)
    }
}
