//! The lab model's friction at the record's times and its exact derivatives with respect to
//! the varied parameters, segment by segment, with the scene's method: CVODES' forward
//! sensitivities for cvode-bdf and cvode-adams, the state and its sensitivity equations
//! integrated as one system ([`super::augmented`]) for the others.

use super::augmented::Sensitized;
use crate::analysis::lab::LabSolver;
use crate::integrate::{ErrorKind, Integrator, Options, SolverError, Task, Tolerance};
use crate::model::lab::LN_V;
use crate::model::{LabParameter, LabParametric, LabParams, Loading};
use crate::solver::{self, Method, MethodSettings};
use crate::sundials::{CvodeMethod, CvodeSettings, SensitivitySettings, SensitivitySolver};
use std::time::Instant;

/// μ at each time and ∂μ/∂p_j (row-major: `dmu[i * m + j]`, m = `varied.len()`).
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionSensitivities {
    /// μ(t_i).
    pub mu: Vec<f64>,
    /// ∂μ(t_i)/∂p_j, row-major.
    pub dmu: Vec<f64>,
    /// Internal steps taken (the evaluation's cost).
    pub steps: u64,
}

/// How the sensitivities are integrated for a method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensitivityRoute {
    /// CVODES' forward sensitivities (simultaneous corrector, estimated tolerances, error
    /// control), with CVODE's BDF or Adams method.
    Cvodes,
    /// The state and the sensitivity equations as one system, integrated by the method.
    OneSystem,
}

impl SensitivityRoute {
    /// The route for `method`, or why the fit cannot use it.
    pub fn for_method(method: Method) -> Result<Self, String> {
        match method {
            Method::CvodeBdf | Method::CvodeAdams => Ok(Self::Cvodes),
            Method::ArkodeImex => Err("solver.method: arkode-imex needs the model split into explicit and implicit parts, which the fit's sensitivity system has none of (the lab model is all implicit); use arkode-dirk, the same ARKStep fully implicit, or radau5".into()),
            _ => Ok(Self::OneSystem),
        }
    }

    /// Its name in the report: "cvodes" or "one-system".
    pub fn name(self) -> &'static str {
        match self {
            Self::Cvodes => "cvodes",
            Self::OneSystem => "one-system",
        }
    }
}

/// Limits on one evaluation's work.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Budget {
    /// At most about this many internal steps (checked after each output time; each call is
    /// also limited to it). None: `FIRST_EVALUATION_STEPS_PER_CALL` (100 000) per call, no total.
    pub steps: Option<u64>,
    /// Stop when this instant has passed (checked after each output time).
    pub deadline: Option<Instant>,
}

/// The per-call step limit of an evaluation without a step budget (the fit's first): more
/// steps between two samples of a lab record means the model is not what the record shows.
pub const FIRST_EVALUATION_STEPS_PER_CALL: u64 = 100_000;

/// Why an evaluation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    /// The integration failed.
    #[error("segment {} of {segments} (V_lp = {v_lp}, from t = {t_start}): {source}", segment + 1)]
    Solver {
        /// The segment (0-based; shown from 1).
        segment: usize,
        /// How many segments the loading has.
        segments: usize,
        /// Its load-point velocity.
        v_lp: f64,
        /// Its start (the record's time origin).
        t_start: f64,
        /// The solver's error.
        source: SolverError,
    },
    /// More steps than the budget.
    #[error("more than {limit} internal steps")]
    Steps {
        /// The budget.
        limit: u64,
    },
    /// The deadline passed.
    #[error("the time limit passed")]
    Deadline,
    /// A method the fit cannot use ([`SensitivityRoute::for_method`]).
    #[error("{0}")]
    Method(String),
}

/// Integrates the lab model (quasi-static or with inertia) from steady sliding at the first
/// segment's velocity through `loading` with the sensitivities to `varied` (any of a, b_i,
/// ln D_c,i, k, μ0), with `solver`'s method and tolerances, and returns μ and ∂μ/∂p at
/// `times` (non-decreasing, inside the loading). At least one varied parameter other than μ0
/// is required (μ0 alone has no sensitivity equation). Every segment is integrated on its own
/// in local time, with the state and sensitivities carried across the jump.
///
pub fn friction_sensitivities(
    params: &LabParams,
    loading: &Loading,
    times: &[f64],
    varied: &[LabParameter],
    solver: &LabSolver,
    budget: &Budget,
) -> Result<FrictionSensitivities, SensitivityError> {
    let n = params.dim();
    let m = varied.len();
    // Quasi-static, μ0 has no sensitivity equation: ∂μ/∂μ0 = 1 is added where μ is formed.
    // With inertia the measured friction is the state τ and μ0 moves the slider.
    let inertial = params.mass.is_some();
    let dynamic: Vec<LabParameter> =
        varied.iter().copied().filter(|p| inertial || *p != LabParameter::Mu0).collect();
    let md = dynamic.len();
    let v_first = loading.segments[0].velocity;
    let mut y = params.steady_state(v_first);
    let mut s = vec![0.0; n * md];
    for (j, p) in dynamic.iter().enumerate() {
        params.steady_state_parameter_derivative(v_first, *p, &mut s[j * n..(j + 1) * n]);
    }
    let mut out = FrictionSensitivities {
        mu: Vec::with_capacity(times.len()),
        dmu: Vec::with_capacity(times.len() * m),
        steps: 0,
    };
    let record = |y: &[f64], s: &[f64], out: &mut FrictionSensitivities| {
        out.mu.push(params.measured_friction(y));
        if let Some(it) = params.tau_index() {
            out.dmu.extend((0..md).map(|j| s[j * n + it]));
            return;
        }
        let mut jd = 0;
        for p in varied {
            let mut d = params.friction_parameter_derivative(y, *p);
            if *p != LabParameter::Mu0 {
                let column = &s[jd * n..(jd + 1) * n];
                d += params.a * column[LN_V];
                for (i, state) in params.states.iter().enumerate() {
                    d += state.b * column[1 + i];
                }
                jd += 1;
            }
            out.dmu.push(d);
        }
    };
    let system =
        |v_lp: f64| LabParametric { params: params.clone(), v_lp, varied: dynamic.clone() };
    let per_call = budget.steps.unwrap_or(FIRST_EVALUATION_STEPS_PER_CALL);
    let options = Options {
        max_steps: Some(i64::try_from(per_call).unwrap_or(i64::MAX)),
        ..Options::new(solver.rtol, Tolerance::Scalar(solver.atol))
    };
    let segments = loading.segments.len();
    let solver_error = |j: usize, source: SolverError| {
        let seg = &loading.segments[j];
        if source.kind == ErrorKind::TooMuchWork && budget.steps.is_some() {
            return SensitivityError::Steps { limit: per_call };
        }
        SensitivityError::Solver {
            segment: j,
            segments,
            v_lp: seg.velocity,
            t_start: seg.t_start,
            source,
        }
    };
    let route = SensitivityRoute::for_method(solver.method).map_err(SensitivityError::Method)?;
    let mut stepper = match route {
        SensitivityRoute::Cvodes => {
            let method = if solver.method == Method::CvodeAdams {
                CvodeMethod::Adams
            } else {
                CvodeMethod::Bdf
            };
            let settings = SensitivitySettings {
                cvode: CvodeSettings { method, ..CvodeSettings::default() },
                ..SensitivitySettings::default()
            };
            let cvodes = SensitivitySolver::new(system(v_first), &settings, 0.0, &y, &s, &options)
                .map_err(|e| solver_error(0, e))?;
            Stepper::Cvodes(Box::new(cvodes))
        }
        SensitivityRoute::OneSystem => Stepper::OneSystem { integrator: None, n, steps_before: 0 },
    };
    // The sensitivities' absolute tolerances as CVODES estimates them: atol / |p̄_j|.
    let scales: Vec<f64> = dynamic
        .iter()
        .map(|p| {
            let v = params.get(*p).abs();
            if v > 0.0 {
                v
            } else {
                1.0
            }
        })
        .collect();
    let mut next = 0;
    for (j, seg) in loading.segments.iter().enumerate() {
        let fail = |e| solver_error(j, e);
        let t0 = seg.t_start;
        let t1 = loading.segment_end(j);
        match &mut stepper {
            Stepper::Cvodes(cvodes) => {
                if j > 0 {
                    // A jump of V_lp: CVODE and the sensitivities restart from the carried state.
                    cvodes
                        .reinit_with(0.0, &y, &s, |system| system.v_lp = seg.velocity)
                        .map_err(fail)?;
                }
                cvodes.set_stop_time(t1 - t0).map_err(fail)?;
            }
            Stepper::OneSystem { integrator, steps_before, .. } => {
                if let Some(old) = integrator.take() {
                    *steps_before += old.stats().steps;
                }
                let mut z = y.clone();
                z.extend_from_slice(&s);
                let mut atol = vec![solver.atol; n];
                for scale in &scales {
                    atol.extend(std::iter::repeat_n(solver.atol / scale, n));
                }
                let options = Options {
                    stop_time: Some(t1 - t0),
                    max_err_test_fails: Some(20),
                    atol: Tolerance::PerComponent(atol),
                    ..options.clone()
                };
                let settings = MethodSettings { autonomous: true, ..MethodSettings::default() };
                let linearly_implicit =
                    matches!(solver.method, Method::Rodas5p | Method::Extrapolation);
                let built = if linearly_implicit {
                    solver::build_ode(
                        solver.method,
                        &settings,
                        Sensitized::exact(system(seg.velocity)),
                        0.0,
                        &z,
                        &options,
                    )
                } else {
                    solver::build_ode(
                        solver.method,
                        &settings,
                        Sensitized::for_newton(system(seg.velocity)),
                        0.0,
                        &z,
                        &options,
                    )
                };
                *integrator = Some(built.map_err(fail)?.integrator);
            }
        }
        let last = j + 1 == loading.segments.len();
        let in_segment = |t: f64| t >= t0 && (t < t1 || (last && t <= t1));
        let check = |stepper: &Stepper| -> Result<(), SensitivityError> {
            let steps = stepper.steps();
            if let Some(limit) = budget.steps {
                if steps > limit {
                    return Err(SensitivityError::Steps { limit });
                }
            }
            if budget.deadline.is_some_and(|d| Instant::now() > d) {
                return Err(SensitivityError::Deadline);
            }
            Ok(())
        };
        while next < times.len() && in_segment(times[next]) {
            let local = times[next] - t0;
            if local > 0.0 {
                stepper.advance(local).map_err(fail)?;
                let (ys, ss) = stepper.state();
                record(ys, ss, &mut out);
                check(&stepper)?;
            } else {
                record(&y, &s, &mut out);
            }
            next += 1;
        }
        if stepper.t() < t1 - t0 {
            stepper.advance(t1 - t0).map_err(fail)?;
            check(&stepper)?;
        }
        let (ys, ss) = stepper.state();
        y.copy_from_slice(ys);
        s.copy_from_slice(ss);
    }
    out.steps = stepper.steps();
    Ok(out)
}

/// The integration of one segment after another, by either route.
enum Stepper {
    Cvodes(Box<SensitivitySolver<LabParametric>>),
    OneSystem {
        /// The current segment's integrator of (y, s_1, …, s_m).
        integrator: Option<Box<dyn Integrator>>,
        /// The state's dimension.
        n: usize,
        /// Steps of the segments before it.
        steps_before: u64,
    },
}

impl Stepper {
    fn integrator(&mut self) -> &mut dyn Integrator {
        match self {
            Self::OneSystem { integrator: Some(i), .. } => i.as_mut(),
            _ => unreachable!("the one-system route builds its integrator before stepping"),
        }
    }

    fn advance(&mut self, t: f64) -> Result<(), SolverError> {
        match self {
            Self::Cvodes(c) => c.advance(t, Task::Normal).map(|_| ()),
            other => other.integrator().advance(t, Task::Normal).map(|_| ()),
        }
    }

    fn t(&mut self) -> f64 {
        match self {
            Self::Cvodes(c) => c.t(),
            other => other.integrator().t(),
        }
    }

    /// (y, s) at the last return.
    fn state(&self) -> (&[f64], &[f64]) {
        match self {
            Self::Cvodes(c) => (c.state(), c.sensitivities()),
            Self::OneSystem { integrator: Some(i), n, .. } => i.state().split_at(*n),
            Self::OneSystem { .. } => unreachable!("built before stepping"),
        }
    }

    fn steps(&self) -> u64 {
        match self {
            Self::Cvodes(c) => c.stats().steps,
            Self::OneSystem { integrator, steps_before, .. } => {
                steps_before + integrator.as_ref().map_or(0, |i| i.stats().steps)
            }
        }
    }
}
