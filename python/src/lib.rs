//! `stickslip._core`: the compiled half of the Python package `stickslip` (python/stickslip/
//! is the other: argument checks, scipy's conventions, `OdeResult`, `OdeSolution`,
//! exceptions). Three entry points: `run` (a scene → its report as JSON text), `sweep` (a
//! scene and axes → rows as JSON text) and `solve_ivp` (the stepping loop of
//! `stickslip.solve_ivp`, see [`solve`]).
//!
//! `run` and `sweep` release the GIL: the work runs on a thread of its own while the calling
//! thread waits in slices of 50 ms and checks for signals. On Ctrl-C it cancels the work
//! ([`engine::Cancel`]: every integration stops at its next step, a sweep starts no new
//! point, a "noise" analysis starts no new realisation), waits for the thread to end, and
//! raises KeyboardInterrupt. A second Ctrl-C raises at once.

mod solve;
mod system;

use numpy::PyReadonlyArrayDyn;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::sync::mpsc;
use std::time::Duration;
use stickslip::analysis::time_series::SeriesCollector;
use stickslip::analysis::AnalysisError;
use stickslip::engine::{self, Cancel, EngineError, RunError, RunOptions};
use stickslip::integrate::ToleranceTransform;
use stickslip::scene::{self, AnyScene, SceneError};
use stickslip::solver::{Capabilities, Method, TableKind};
use stickslip::{parallel, sweep};

/// Instantiates `stickslip.errors.<class>` with `message` and keyword attributes.
fn python_error(
    py: Python<'_>,
    class: &str,
    message: String,
    attributes: Bound<'_, PyDict>,
) -> PyErr {
    let made = py
        .import("stickslip.errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call((message,), Some(&attributes)));
    match made {
        Ok(instance) => PyErr::from_value(instance),
        Err(e) => e,
    }
}

/// A scene error as `stickslip.SceneError` (also a ValueError), with its field path.
fn scene_error(py: Python<'_>, e: &SceneError) -> PyErr {
    let attributes = PyDict::new(py);
    let filled = attributes
        .set_item("field", &e.field)
        .and_then(|_| attributes.set_item("source", &e.source_name))
        .and_then(|_| attributes.set_item("detail", &e.message));
    match filled {
        Ok(()) => python_error(py, "SceneError", e.to_string(), attributes),
        Err(err) => err,
    }
}

/// A failed run as `stickslip.RunError`: the analysis, the state, and for an integration
/// failure its time, kind and integrator.
fn run_error(py: Python<'_>, name: &str, e: &EngineError) -> PyErr {
    let attributes = PyDict::new(py);
    let (t, solver) = match e.kind.as_ref() {
        AnalysisError::Solver(s) => (Some(s.t), Some(s.solver)),
        AnalysisError::Failed { t, .. } | AnalysisError::Budget { t, .. } => (Some(*t), None),
        _ => (None, None),
    };
    // The stress grid's one-word label: the integrator's error kind, or the variant's.
    let kind = e.kind.label();
    let filled = (|| -> PyResult<()> {
        attributes.set_item("analysis", e.analysis)?;
        attributes.set_item("state", numpy::PyArray1::from_slice(py, &e.state))?;
        attributes.set_item("t", t)?;
        attributes.set_item("kind", kind)?;
        attributes.set_item("solver", solver)?;
        attributes.set_item("bad_input", e.is_bad_input())?;
        Ok(())
    })();
    match filled {
        Ok(()) => python_error(py, "RunError", format!("scene {name}: {e}"), attributes),
        Err(err) => err,
    }
}

/// Runs `work` on a thread of its own without the GIL, checking for signals every 50 ms. On a
/// signal's exception (KeyboardInterrupt) `cancel` is set and, once the thread has ended, the
/// exception returned; a second one while waiting is returned at once.
fn off_the_gil<T: Send + 'static>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = mpsc::channel();
    // A Mutex makes the receiver shareable with the GIL-free closure below.
    let rx = std::sync::Mutex::new(rx);
    std::thread::Builder::new()
        .name("stickslip".into())
        .spawn(move || {
            let _ = tx.send(work());
        })
        .map_err(|e| PyValueError::new_err(format!("cannot start a thread: {e}")))?;
    let mut interrupted: Option<PyErr> = None;
    loop {
        let received = py.detach(|| {
            let rx = rx.lock().unwrap_or_else(|e| e.into_inner());
            rx.recv_timeout(Duration::from_millis(50))
        });
        match (received, interrupted.take()) {
            (Ok(_) | Err(mpsc::RecvTimeoutError::Disconnected), Some(e)) => return Err(e),
            (Ok(value), None) => return Ok(value),
            (Err(mpsc::RecvTimeoutError::Disconnected), None) => {
                return Err(PyValueError::new_err("the stickslip worker thread died (a bug)"));
            }
            (Err(mpsc::RecvTimeoutError::Timeout), first) => match (py.check_signals(), first) {
                (Err(again), Some(_)) => return Err(again),
                (Err(e), None) => {
                    cancel.cancel();
                    interrupted = Some(e);
                }
                (Ok(()), first) => interrupted = first,
            },
        }
    }
}

/// The worker threads for `threads` (None: every core).
fn worker_threads(threads: Option<usize>) -> PyResult<usize> {
    match threads {
        Some(0) => {
            Err(PyValueError::new_err("threads = 0: give at least 1 (or None for every core)"))
        }
        Some(n) => Ok(n),
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

/// A report as JSON text and the rows of its "time_series" analysis, column by column (empty
/// when the scene asks for none).
type RunOutput = (String, Vec<(String, Vec<f64>)>);

/// The time series' columns handed to Python: (name, numpy array).
type Columns<'py> = Vec<(String, Bound<'py, numpy::PyArray1<f64>>)>;

/// Runs a scene (JSON text; `source` names it in errors) as `stickslip run --json` does and
/// returns the report as JSON text with the rows of its "time_series" analysis (the rows
/// `stickslip run --series FILE` writes), kept in memory.
#[pyfunction]
#[pyo3(signature = (text, source, threads=None))]
fn run(
    py: Python<'_>,
    text: String,
    source: String,
    threads: Option<usize>,
) -> PyResult<(String, Columns<'_>)> {
    let threads = worker_threads(threads)?;
    let scene = scene::parse_any(&text, &source).map_err(|e| scene_error(py, &e))?;
    let echo: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let name = scene.name().to_string();
    let cancel = Cancel::new();
    let stop = cancel.clone();
    let outcome = off_the_gil(py, &cancel, move || -> Result<RunOutput, RunError> {
        let mut series = SeriesCollector::default();
        let options = RunOptions::echoing(echo).threads(threads).series(&mut series).cancel(&stop);
        let report = engine::run(&scene, options)?;
        let columns = series.names.iter().map(|n| n.to_string()).zip(series.columns).collect();
        Ok((report.to_json(), columns))
    })?;
    let (json, columns) = outcome.map_err(|e| match e {
        RunError::Lab(e) => {
            python_error(py, "RunError", format!("scene {name}: {e}"), PyDict::new(py))
        }
        RunError::Failed(e) => run_error(py, &name, &e),
        // Only set on a signal, whose exception off_the_gil has returned instead.
        RunError::Cancelled => pyo3::exceptions::PyKeyboardInterrupt::new_err("cancelled"),
    })?;
    let columns = columns.into_iter().map(|(n, c)| (n, numpy::PyArray1::from_vec(py, c))).collect();
    Ok((json, columns))
}

/// Runs a sweep of the scene (JSON text) over `axes` ((name, values or "START:STOP:COUNT[:log]")
/// pairs, the first varying slowest) on `threads` threads; returns the rows as a JSON array.
#[pyfunction(name = "sweep")]
#[pyo3(signature = (text, source, axes, threads=None))]
fn sweep_scene(
    py: Python<'_>,
    text: String,
    source: String,
    axes: Vec<(String, Bound<'_, PyAny>)>,
    threads: Option<usize>,
) -> PyResult<String> {
    let threads = worker_threads(threads)?;
    scene::parse(&text, &source).map_err(|e| scene_error(py, &e))?;
    let base: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let mut parsed = Vec::with_capacity(axes.len());
    for (name, values) in &axes {
        let bad = |e: sweep::SweepError| PyValueError::new_err(format!("params: {e}"));
        if let Ok(spec) = values.extract::<String>() {
            parsed.push(sweep::parse_axis(&format!("{name}={spec}")).map_err(bad)?);
            continue;
        }
        // The name is checked by the one parser of axes; the values are the user's.
        let mut axis = sweep::parse_axis(&format!("{name}=1:1:1")).map_err(bad)?;
        axis.values = values.extract::<Vec<f64>>().map_err(|_| {
            PyTypeError::new_err(format!(
                "params[{name:?}] must be a sequence of numbers or a string \"START:STOP:COUNT[:log]\""
            ))
        })?;
        if let Some(v) = axis.values.iter().find(|v| !v.is_finite()) {
            return Err(PyValueError::new_err(format!("params[{name:?}]: {v} is not finite")));
        }
        parsed.push(axis);
    }
    sweep::check_base(&base, &parsed)
        .map_err(|e| PyValueError::new_err(format!("{source}: {e}")))?;
    let points = sweep::points(&parsed);
    let cancel = Cancel::new();
    let stop = cancel.clone();
    let rows = off_the_gil(py, &cancel, move || {
        let rows = parallel::map(points.len(), threads, &|_, _| {}, |i| {
            sweep::run_point_cancellable(&base, i, &points[i], &stop)
        });
        serde_json::to_string(&rows.into_iter().flatten().collect::<Vec<_>>())
    })?;
    rows.map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The stepping loop of `stickslip.solve_ivp` (see python/stickslip/_ivp.py, which checks
/// and normalises the arguments first).
#[pyfunction]
#[pyo3(signature = (fun, jac, method, table, tolerances, t0, t_bound, y0, rtol, atol, t_eval, dense_output, events, options))]
#[allow(clippy::too_many_arguments)]
fn solve_ivp<'py>(
    py: Python<'py>,
    fun: Bound<'py, PyAny>,
    jac: Bound<'py, PyAny>,
    method: String,
    table: Option<String>,
    tolerances: Option<String>,
    t0: f64,
    t_bound: f64,
    y0: Vec<f64>,
    rtol: f64,
    atol: Vec<f64>,
    t_eval: Option<Vec<f64>>,
    dense_output: bool,
    events: Vec<Bound<'py, PyTuple>>,
    options: Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let n = y0.len();
    let tolerance_transform = match tolerances.as_deref() {
        None => None,
        Some("as_given") => Some(ToleranceTransform::AsGiven),
        Some("hairer") => Some(ToleranceTransform::Hairer),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "tolerances = {other:?}: use \"as_given\" or \"hairer\""
            )))
        }
    };
    let jac = if jac.is_none() {
        system::Jacobian::None
    } else if jac.is_callable() {
        system::Jacobian::Callable(jac)
    } else {
        let m: PyReadonlyArrayDyn<f64> = jac.extract()?;
        let m = m.as_array();
        if m.shape() != [n, n] {
            return Err(PyValueError::new_err(format!(
                "`jac` is expected to have shape ({n}, {n}), but actually has {:?}",
                m.shape()
            )));
        }
        system::Jacobian::Constant(m.iter().copied().collect())
    };
    let events = events
        .iter()
        .map(|e| {
            Ok(solve::Event {
                function: e.get_item(0)?,
                direction: e.get_item(1)?.extract()?,
                max_events: e.get_item(2)?.extract()?,
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let get = |key: &str| -> PyResult<Option<Bound<'py, PyAny>>> {
        Ok(options.get_item(key)?.filter(|v| !v.is_none()))
    };
    let float = |key: &str| -> PyResult<Option<f64>> { get(key)?.map(|v| v.extract()).transpose() };
    let int = |key: &str| -> PyResult<Option<i64>> { get(key)?.map(|v| v.extract()).transpose() };
    let problem = solve::Problem {
        fun,
        jac,
        method,
        table,
        tolerance_transform,
        t0,
        t_bound,
        y0,
        rtol,
        atol,
        t_eval,
        dense_output,
        events,
        first_step: float("first_step")?,
        max_step: float("max_step")?,
        min_step: float("min_step")?,
        max_steps: match int("max_steps")? {
            Some(m) if m < 1 => {
                return Err(PyValueError::new_err(format!("max_steps = {m} must be ≥ 1")))
            }
            other => other,
        },
        max_order: int("max_order")?.map(|v| v as i32),
        jacobian_max_age: int("jacobian_max_age")?,
    };
    solve::solve(py, problem)
}

/// The SUNDIALS version the package runs with.
/// Fits the lab scene (JSON text) to the record in `data` (`stickslip fit`); returns the report
/// as JSON and the columns t, x_lp, mu_data, mu_fit. `loading` is "scene" or "data".
#[pyfunction(name = "fit")]
#[pyo3(signature = (text, source, data, params, columns, loading))]
fn fit_scene(
    py: Python<'_>,
    text: String,
    source: String,
    data: String,
    params: String,
    columns: String,
    loading: String,
) -> PyResult<(String, Columns<'_>)> {
    let AnyScene::Lab(scene) = scene::parse_any(&text, &source).map_err(|e| scene_error(py, &e))?
    else {
        return Err(PyValueError::new_err(format!(
            "scene {source}: fit takes a lab scene (\"model\": {{\"kind\": \"lab\", ...}}, docs/lab.md)"
        )));
    };
    let loading = match loading.as_str() {
        "scene" => engine::lab::FitLoading::Scene,
        "data" => engine::lab::FitLoading::Data,
        other => {
            return Err(PyValueError::new_err(format!(
                "loading = {other:?}: choose \"scene\" (the scene's loading) or \"data\" (the record's x_lp column)"
            )))
        }
    };
    let cancel = Cancel::new();
    let name = scene.name.clone();
    let outcome = off_the_gil(py, &cancel, move || {
        engine::lab::fit_file(
            &scene,
            std::path::Path::new(&data),
            &params,
            &columns,
            loading,
            stickslip::analysis::lab_fit::FitLimits::default(),
        )
        .map_err(Box::new)
    })?;
    let report = outcome.map_err(|e| match *e {
        stickslip::analysis::lab_fit::FitError::BadInput(m) => PyValueError::new_err(m),
        other => {
            python_error(py, "RunError", format!("fit of scene {name}: {other}"), PyDict::new(py))
        }
    })?;
    let s = &report.outcome.series;
    let columns = [("t", &s.t), ("x_lp", &s.x_lp), ("mu_data", &s.mu_data), ("mu_fit", &s.mu_fit)]
        .into_iter()
        .map(|(n, c)| (n.to_string(), numpy::PyArray1::from_slice(py, c)))
        .collect();
    Ok((report.to_json(), columns))
}

#[pyfunction]
fn sundials_version() -> String {
    stickslip::sundials::version()
}

/// The compiled part of the `stickslip` package.
/// The scene names of the method table's methods whose row satisfies `keep`, in the table's
/// order: `_core.METHODS` (all) and `_core.EXPLICIT_METHODS` (those run by an explicit Butcher
/// table, which use no Jacobian), read by python/stickslip/_ivp.py.
fn method_names(keep: impl Fn(&Capabilities) -> bool) -> Vec<&'static str> {
    Method::ALL.iter().filter(|(_, m)| keep(&m.capabilities())).map(|(name, _)| *name).collect()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_scene, m)?)?;
    m.add_function(wrap_pyfunction!(fit_scene, m)?)?;
    m.add_function(wrap_pyfunction!(solve_ivp, m)?)?;
    m.add_function(wrap_pyfunction!(sundials_version, m)?)?;
    m.add("DENSE_NODES", solve::DENSE_NODES)?;
    m.add("METHODS", method_names(|_| true))?;
    m.add("EXPLICIT_METHODS", method_names(|c| c.accepts.table == Some(TableKind::Explicit)))?;
    Ok(())
}
