//! The stepping loop behind `stickslip.solve_ivp`: one internal step at a time with any
//! stickslip method, scipy's rules for outputs (`t_eval`), events (sign changes at step ends,
//! roots by Brent's method on the step's dense output, `terminal` counts, `direction`) and the
//! samples of each step's interpolant from which Python builds `sol`.

use crate::system::{Jacobian, PySystem, SystemRef};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use stickslip::integrate::{
    ErrorKind, Integrator, OdeSystem as _, Options, SolverError, Task, Tolerance,
    ToleranceTransform,
};
use stickslip::solver::{self, Method, MethodSettings};

/// Samples of each step's interpolant handed to Python's `OdeSolution`: Chebyshev–Lobatto
/// points, so the polynomial through them reproduces every interpolant of degree ≤ 7 (CVODE's
/// of order ≤ 5, Radau5's collocation cubic, Rodas5P's and ARKODE's) to round-off.
pub const DENSE_NODES: usize = 8;

/// One event function and scipy's attributes.
pub struct Event<'py> {
    /// `event(t, y)`.
    pub function: Bound<'py, PyAny>,
    /// +1: only rising zeros, −1: only falling ones, 0: both.
    pub direction: f64,
    /// The integration stops at this occurrence (infinity: never).
    pub max_events: f64,
}

/// What `solve_ivp` asked for, already checked and normalised by the Python side.
pub struct Problem<'py> {
    pub fun: Bound<'py, PyAny>,
    pub jac: Jacobian<'py>,
    pub method: String,
    pub table: Option<String>,
    /// How radau5 reads rtol and atol (None: RADAU5's transform).
    pub tolerance_transform: Option<ToleranceTransform>,
    pub t0: f64,
    pub t_bound: f64,
    pub y0: Vec<f64>,
    pub rtol: f64,
    pub atol: Vec<f64>,
    pub t_eval: Option<Vec<f64>>,
    pub dense_output: bool,
    pub events: Vec<Event<'py>>,
    pub first_step: Option<f64>,
    pub max_step: Option<f64>,
    pub min_step: Option<f64>,
    /// Most internal steps of the whole integration (None: no limit, as in scipy).
    pub max_steps: Option<i64>,
    pub max_order: Option<i32>,
    pub jacobian_max_age: Option<i64>,
}

/// Brent's root finder as scipy's `brentq` (same iteration, tolerances given), for a bracket
/// [xa, xb]. Where round-off leaves no sign change, the end nearer zero.
fn brentq(
    mut f: impl FnMut(f64) -> PyResult<f64>,
    xa: f64,
    xb: f64,
    xtol: f64,
    rtol: f64,
) -> PyResult<f64> {
    let (mut xpre, mut xcur) = (xa, xb);
    let (mut fpre, mut fcur) = (f(xpre)?, f(xcur)?);
    if fpre == 0.0 {
        return Ok(xpre);
    }
    if fcur == 0.0 {
        return Ok(xcur);
    }
    if fpre.signum() == fcur.signum() {
        return Ok(if fpre.abs() < fcur.abs() { xpre } else { xcur });
    }
    let (mut xblk, mut fblk, mut spre, mut scur) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..100 {
        if fpre != 0.0 && fcur != 0.0 && fpre.signum() != fcur.signum() {
            xblk = xpre;
            fblk = fpre;
            spre = xcur - xpre;
            scur = spre;
        }
        if fblk.abs() < fcur.abs() {
            xpre = xcur;
            xcur = xblk;
            xblk = xpre;
            fpre = fcur;
            fcur = fblk;
            fblk = fpre;
        }
        let delta = (xtol + rtol * xcur.abs()) / 2.0;
        let sbis = (xblk - xcur) / 2.0;
        if fcur == 0.0 || sbis.abs() < delta {
            return Ok(xcur);
        }
        if spre.abs() > delta && fcur.abs() < fpre.abs() {
            let stry = if xpre == xblk {
                -fcur * (xcur - xpre) / (fcur - fpre)
            } else {
                let dpre = (fpre - fcur) / (xpre - xcur);
                let dblk = (fblk - fcur) / (xblk - xcur);
                -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            };
            if 2.0 * stry.abs() < spre.abs().min(3.0 * sbis.abs() - delta) {
                spre = scur;
                scur = stry;
            } else {
                spre = sbis;
                scur = sbis;
            }
        } else {
            spre = sbis;
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        xcur += if scur.abs() > delta {
            scur
        } else if sbis > 0.0 {
            delta
        } else {
            -delta
        };
        fcur = f(xcur)?;
    }
    Ok(xcur)
}

/// `event(t, y)` as a float.
fn call_event(event: &Event<'_>, t: f64, y: &[f64]) -> PyResult<f64> {
    let py = event.function.py();
    let value = event.function.call1((t, PyArray1::from_slice(py, y)))?;
    value.extract::<f64>().map_err(|_| {
        PyValueError::new_err(format!(
            "an event function returned {}; it must return a real number",
            value.repr().map(|r| r.to_string()).unwrap_or_else(|_| "?".into())
        ))
    })
}

/// scipy's `find_active_events`: which events changed sign in the allowed direction.
fn active(g: &[f64], g_new: &[f64], events: &[Event<'_>]) -> Vec<usize> {
    (0..g.len())
        .filter(|&i| {
            let up = g[i] <= 0.0 && g_new[i] >= 0.0;
            let down = g[i] >= 0.0 && g_new[i] <= 0.0;
            let d = events[i].direction;
            (up && d > 0.0) || (down && d < 0.0) || ((up || down) && d == 0.0)
        })
        .collect()
}

/// The outputs gathered while stepping.
struct Outputs {
    n: usize,
    ts: Vec<f64>,
    ys: Vec<f64>,
    /// Step boundaries of `sol` (t0, then each step's end or terminal event).
    sol_ts: Vec<f64>,
    /// Per step: its start and end (the interpolant's interval) and the node values.
    sol_spans: Vec<f64>,
    sol_values: Vec<f64>,
    t_events: Vec<Vec<f64>>,
    y_events: Vec<Vec<f64>>,
}

/// The integrator's statistics and the failure as a Python dict for `stickslip.SolverError`.
fn error_dict<'py>(py: Python<'py>, e: &SolverError) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("solver", e.solver)?;
    d.set_item("kind", format!("{:?}", e.kind))?;
    d.set_item("t", e.t)?;
    d.set_item("y", PyArray1::from_slice(py, &e.state))?;
    d.set_item("flag", e.flag)?;
    d.set_item("message", e.to_string())?;
    Ok(d)
}

/// Runs the problem; returns the raw result dict that Python turns into an `OdeResult`.
pub fn solve<'py>(py: Python<'py>, p: Problem<'py>) -> PyResult<Bound<'py, PyDict>> {
    let n = p.y0.len();
    let method: Method = p.method.parse().map_err(|e| PyValueError::new_err(format!("{e}")))?;
    let system = PySystem::new(py, n, p.fun.clone(), p.jac)?;
    let atol = if p.atol.len() == 1 {
        Tolerance::Scalar(p.atol[0])
    } else {
        Tolerance::PerComponent(p.atol.clone())
    };
    let mut options = Options::new(p.rtol, atol);
    options.initial_step = p.first_step;
    options.max_step = p.max_step;
    options.min_step = p.min_step;
    options.max_order = p.max_order;
    options.jacobian_max_age = p.jacobian_max_age;
    if p.t_bound != p.t0 {
        options.stop_time = Some(p.t_bound);
    }
    let settings = MethodSettings {
        table: p.table.clone(),
        tolerance_transform: p.tolerance_transform,
        ..MethodSettings::default()
    };
    let mut out = Outputs {
        n,
        ts: Vec::new(),
        ys: Vec::new(),
        sol_ts: vec![p.t0],
        sol_spans: Vec::new(),
        sol_values: Vec::new(),
        t_events: vec![Vec::new(); p.events.len()],
        y_events: vec![Vec::new(); p.events.len()],
    };
    let built = solver::build_ode(method, &settings, SystemRef(&system), p.t0, &p.y0, &options);
    let mut integ = match built {
        Ok(b) => b.integrator,
        Err(e) if e.kind == ErrorKind::InvalidInput => {
            return Err(PyValueError::new_err(e.message.clone()))
        }
        Err(e) => return finish(py, &system, None, out, -1, Some(e)),
    };
    let mut g: Vec<f64> =
        p.events.iter().map(|e| call_event(e, p.t0, &p.y0)).collect::<PyResult<_>>()?;
    let mut counts = vec![0usize; p.events.len()];
    let forward = p.t_bound >= p.t0;
    if p.t_eval.is_none() {
        out.ts.push(p.t0);
        out.ys.extend_from_slice(&p.y0);
    }
    let mut t_eval_i = 0;
    let mut status = if p.t_bound == p.t0 { 0 } else { 2 };
    let mut failure = None;
    let mut steps: i64 = 0;
    while status == 2 {
        let t_old = integ.t();
        // max_steps bounds the whole integration (the integrator's own budget is per call,
        // and each call here is one step).
        if p.max_steps.is_some_and(|m| steps >= m) {
            let message = format!(
                "max_steps = {} internal steps taken before t_bound = {:e} (raise max_steps)",
                steps, p.t_bound
            );
            failure = Some(SolverError {
                solver: method.name(),
                kind: ErrorKind::TooMuchWork,
                t: t_old,
                state: integ.state().to_vec(),
                flag: 0,
                message,
            });
            status = -1;
            break;
        }
        steps += 1;
        let step = match integ.advance(p.t_bound, Task::OneStep) {
            Ok(s) => s,
            Err(e) => {
                if let Some(raised) = system.take_error() {
                    return Err(raised);
                }
                failure = Some(e);
                status = -1;
                break;
            }
        };
        let mut t = step.t;
        let mut y = integ.state().to_vec();
        if !p.events.is_empty() {
            let g_new: Vec<f64> =
                p.events.iter().map(|e| call_event(e, t, &y)).collect::<PyResult<_>>()?;
            let mut hits = active(&g, &g_new, &p.events);
            if !hits.is_empty() {
                let mut roots = Vec::with_capacity(hits.len());
                for &i in &hits {
                    let event = &p.events[i];
                    let mut at = |s: f64| -> PyResult<f64> {
                        let ys =
                            integ.dense(s, 0).map_err(|e| PyValueError::new_err(e.to_string()))?;
                        call_event(event, s, ys)
                    };
                    let eps4 = 4.0 * f64::EPSILON;
                    roots.push(brentq(&mut at, t_old, t, eps4, eps4)?);
                }
                for &i in &hits {
                    counts[i] += 1;
                }
                let terminal = hits.iter().any(|&i| counts[i] as f64 >= p.events[i].max_events);
                if terminal {
                    let mut order: Vec<usize> = (0..hits.len()).collect();
                    order.sort_by(|&a, &b| {
                        let (ra, rb) = (roots[a], roots[b]);
                        if forward {
                            ra.total_cmp(&rb)
                        } else {
                            rb.total_cmp(&ra)
                        }
                    });
                    let hits_sorted: Vec<usize> = order.iter().map(|&k| hits[k]).collect();
                    let roots_sorted: Vec<f64> = order.iter().map(|&k| roots[k]).collect();
                    let stop = hits_sorted
                        .iter()
                        .position(|&i| counts[i] as f64 >= p.events[i].max_events)
                        .unwrap_or(hits_sorted.len() - 1);
                    hits = hits_sorted[..=stop].to_vec();
                    roots = roots_sorted[..=stop].to_vec();
                }
                for (&i, &root) in hits.iter().zip(&roots) {
                    let yr = dense(integ.as_mut(), root)?;
                    out.t_events[i].push(root);
                    out.y_events[i].extend_from_slice(&yr);
                }
                if terminal {
                    status = 1;
                    t = *roots.last().expect("a terminal event has a root");
                    y = dense(integ.as_mut(), t)?;
                }
            }
            g = g_new;
        }
        if status == 2
            && (t == p.t_bound || step.event == stickslip::integrate::StepEvent::StopTime)
        {
            status = 0;
        }
        match &p.t_eval {
            None => {
                out.ts.push(t);
                out.ys.extend_from_slice(&y);
            }
            Some(t_eval) => {
                let end = if forward {
                    t_eval.partition_point(|&s| s <= t)
                } else {
                    t_eval.partition_point(|&s| s >= t)
                };
                for &s in &t_eval[t_eval_i..end] {
                    let ys = if s == t { y.clone() } else { dense(integ.as_mut(), s)? };
                    out.ts.push(s);
                    out.ys.extend_from_slice(&ys);
                }
                t_eval_i = end;
            }
        }
        if p.dense_output {
            let end_of_step = step.t;
            out.sol_ts.push(t);
            out.sol_spans.extend_from_slice(&[t_old, end_of_step]);
            for j in 0..DENSE_NODES {
                let x = (std::f64::consts::PI * j as f64 / (DENSE_NODES - 1) as f64).cos();
                // x = 1 is the step's start, x = −1 its end, each hit exactly.
                let s = if j == 0 {
                    t_old
                } else if j == DENSE_NODES - 1 {
                    end_of_step
                } else {
                    0.5 * (t_old + end_of_step) - 0.5 * x * (end_of_step - t_old)
                };
                out.sol_values.extend_from_slice(&dense(integ.as_mut(), s)?);
            }
        }
    }
    finish(py, &system, Some(integ.as_ref()), out, status, failure)
}

/// The interpolated state at `t` inside the last step.
fn dense(integ: &mut dyn Integrator, t: f64) -> PyResult<Vec<f64>> {
    integ.dense(t, 0).map(<[f64]>::to_vec).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The raw result: arrays, counters, status and the failure if any.
fn finish<'py>(
    py: Python<'py>,
    system: &PySystem<'py>,
    integ: Option<&dyn Integrator>,
    out: Outputs,
    status: i32,
    failure: Option<SolverError>,
) -> PyResult<Bound<'py, PyDict>> {
    let n = out.n;
    let d = PyDict::new(py);
    let m = out.ts.len();
    d.set_item("t", PyArray1::from_vec(py, out.ts))?;
    // Stored per point (m × n); scipy's y is n × m.
    let ys = PyArray1::from_vec(py, out.ys).reshape([m, n])?;
    d.set_item("y", ys.transpose()?.call_method0("copy")?)?;
    let t_events = PyList::empty(py);
    let y_events = PyList::empty(py);
    for (te, ye) in out.t_events.into_iter().zip(out.y_events) {
        let k = te.len();
        t_events.append(PyArray1::from_vec(py, te))?;
        y_events.append(PyArray1::from_vec(py, ye).reshape([k, n])?)?;
    }
    d.set_item("t_events", t_events)?;
    d.set_item("y_events", y_events)?;
    let steps = out.sol_ts.len() - 1;
    d.set_item("sol_ts", PyArray1::from_vec(py, out.sol_ts))?;
    d.set_item("sol_spans", PyArray1::from_vec(py, out.sol_spans).reshape([steps, 2])?)?;
    d.set_item(
        "sol_values",
        PyArray1::from_vec(py, out.sol_values).reshape([steps, DENSE_NODES, n])?,
    )?;
    let stats = integ.map(|i| i.stats()).unwrap_or_default();
    d.set_item("nfev", system.nfev.get())?;
    let njev = match system.has_jacobian() {
        true => system.njev.get(),
        false => stats.jac_evals,
    };
    d.set_item("njev", njev)?;
    d.set_item("nlu", stats.lin_setups)?;
    d.set_item("nsteps", stats.steps)?;
    d.set_item("status", status)?;
    d.set_item(
        "error",
        match &failure {
            Some(e) => Some(error_dict(py, e)?),
            None => None,
        },
    )?;
    Ok(d)
}
