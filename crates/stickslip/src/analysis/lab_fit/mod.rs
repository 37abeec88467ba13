//! Fitting the lab model ([`crate::model::lab`]) to a friction record: a, b_i, D_c,i, k, μ0
//! and an optional linear trend, by Levenberg–Marquardt with the exact Jacobian from
//! forward sensitivities (CVODES', or the state and its sensitivity equations as one system).
//!
//! The residuals are r_i = μ_model(t_i) + trend·(x_lp(t_i) − x_lp(t_0)) − μ_data(t_i), the
//! model started at steady sliding at the first segment's velocity. ∂μ/∂p comes from the
//! sensitivities s_j = ∂(ln V, ln θ_i)/∂p_j ([`friction_sensitivities`]); D_c is fitted as
//! ln D_c (it varies over decades) and reported as D_c with its standard error by the delta
//! method.
//!
//! # Requirements
//! - The scene's lab model gives the starting values, the load-point history and the solver's
//!   tolerances; it starts at steady state (`"initial": "steady"`).
//! - The record's times lie inside the loading.
//!
//! # Reference
//! - The optimiser: the `levenberg-marquardt` crate (rust-cv), MINPACK's LMDER algorithm
//!   (J. J. Moré, "The Levenberg–Marquardt algorithm: implementation and theory", 1978).
//! - Standard errors: σ̂²(JᵀJ)⁻¹ with σ̂² = |r|²/(m − p) (e.g. Seber & Wild, *Nonlinear
//!   Regression*, 1989, ch. 2). They assume independent residuals: the outcome warns when the
//!   lag-1 autocorrelation exceeds [`statistics::AUTOCORRELATION_WARNING`].

mod augmented;
mod diagnosis;
pub mod record;
mod sensitivity;
pub mod statistics;
mod termination;
pub mod units;

pub use augmented::Sensitized;
pub use record::{ColumnNames, FrictionRecord};
pub use sensitivity::{
    friction_sensitivities, Budget, FrictionSensitivities, SensitivityError, SensitivityRoute,
};
pub use termination::Termination;

use crate::analysis::lab::LabSolver;
use crate::model::{LabParameter, LabParams, Loading};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use serde::Serialize;
use std::cell::{Cell, RefCell};
use std::time::{Duration, Instant};

/// A quantity a fit may vary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FitParameter {
    /// A parameter of the lab model.
    Model(LabParameter),
    /// The slope of a linear trend in μ against load-point displacement (slip hardening).
    Trend,
}

impl FitParameter {
    /// Parses a `--params` name: `a`, `b_1` … `b_n`, `d_c_1` … `d_c_n` (`b` and `d_c` for the
    /// first), `k`, `mu0` or `trend`, with `n_states` state variables.
    pub fn parse(name: &str, n_states: usize) -> Result<Self, String> {
        let state = |rest: &str| -> Result<usize, String> {
            match rest.parse::<usize>() {
                Ok(i) if (1..=n_states).contains(&i) => Ok(i - 1),
                _ => Err(format!(
                    "--params: \"{name}\": the scene has state variables 1 to {n_states}"
                )),
            }
        };
        Ok(match name {
            "a" => Self::Model(LabParameter::A),
            "b" => Self::Model(LabParameter::B(0)),
            "d_c" => Self::Model(LabParameter::LnDc(0)),
            "k" => Self::Model(LabParameter::K),
            "mu0" => Self::Model(LabParameter::Mu0),
            "trend" => Self::Trend,
            _ => {
                if let Some(rest) = name.strip_prefix("b_") {
                    Self::Model(LabParameter::B(state(rest)?))
                } else if let Some(rest) = name.strip_prefix("d_c_") {
                    Self::Model(LabParameter::LnDc(state(rest)?))
                } else {
                    return Err(format!("--params: unknown parameter \"{name}\"; choose from a, b_i, d_c_i, k, mu0 and trend"));
                }
            }
        })
    }

    /// Its unit in the lab's conventions: "" (dimensionless: a, b_i, μ0), "µm" (D_c),
    /// "friction/µm" (k), "1/µm" (the trend, friction per µm of load-point displacement).
    pub fn unit(&self) -> &'static str {
        match self {
            Self::Model(LabParameter::LnDc(_)) => "µm",
            Self::Model(LabParameter::K) => "friction/µm",
            Self::Trend => "1/µm",
            Self::Model(_) => "",
        }
    }

    /// The name in the report: `a`, `b_1`, `d_c_1`, `k`, `mu0`, `trend`.
    pub fn name(&self) -> String {
        match self {
            Self::Model(LabParameter::A) => "a".into(),
            Self::Model(LabParameter::B(i)) => format!("b_{}", i + 1),
            Self::Model(LabParameter::LnDc(i)) => format!("d_c_{}", i + 1),
            Self::Model(LabParameter::K) => "k".into(),
            Self::Model(LabParameter::Mu0) => "mu0".into(),
            Self::Trend => "trend".into(),
        }
    }
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedParameter {
    /// Its name (`a`, `b_1`, `d_c_1`, `k`, `mu0`, `trend`).
    pub name: String,
    /// The fitted value (D_c in length units, not its logarithm).
    pub value: f64,
    /// Its standard error from σ̂²(JᵀJ)⁻¹ (D_c: by the delta method, D_c·σ(ln D_c)); NaN
    /// (`null` in JSON) when a stopped fit's Jacobian cannot give one.
    pub standard_error: f64,
    /// The starting value.
    pub initial: f64,
    /// Its unit in the lab's conventions (docs/lab.md): "" (dimensionless), "µm",
    /// "friction/µm" or "1/µm".
    pub unit: &'static str,
}

/// a − Σ b_i of the fitted model, with its standard error from the covariance of the fitted
/// ones among a and the b_i (the others held at the scene's values).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AMinusB {
    /// The fitted a − Σ b_i.
    pub value: f64,
    /// Its standard error (0 when neither a nor any b_i was fitted).
    pub standard_error: f64,
    /// a − Σ b_i at the starting values.
    pub initial: f64,
}

/// What a fit found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitOutcome {
    /// The parameters, in the order asked for.
    pub parameters: Vec<FittedParameter>,
    /// a − Σ b_i (velocity weakening when negative).
    pub a_minus_b: AMinusB,
    /// Their correlation matrix, row by row.
    pub correlation: Vec<Vec<f64>>,
    /// Root-mean-square residual.
    pub residual_rms: f64,
    /// Number of samples fitted.
    pub samples: usize,
    /// Model evaluations (each one integration with sensitivities).
    pub evaluations: usize,
    /// Trial steps whose model could not be evaluated (a non-positive a or k, a failed
    /// integration): rejected, the trust region shrunk.
    pub rejected_trials: usize,
    /// Why the optimiser stopped (docs/lab.md lists the words).
    pub termination: Termination,
    /// Whether it stopped converged.
    pub converged: bool,
    /// Why a limit stopped the fit (`--max-evaluations`, `--max-time`, an evaluation far
    /// costlier than the first), with the parameter values; the parameters are then the best
    /// point reached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// The residuals' lag-1 autocorrelation.
    pub lag1_autocorrelation: f64,
    /// Warnings (autocorrelated residuals, b < 0, a − b changed sign).
    pub warnings: Vec<String>,
    /// The lab model with the fitted values, as a scene's `"model"` (with `"kind": "lab"`).
    #[serde(serialize_with = "scene_model")]
    pub model: LabParams,
    /// The record and the fit: t, μ_data, μ_fit (trend included), residual.
    #[serde(skip)]
    pub series: FitSeries,
}

/// Serialises the model as a scene's `"model"` block: `{"kind": "lab", …}`.
fn scene_model<S: serde::Serializer>(model: &LabParams, serializer: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct SceneModel<'a> {
        kind: &'static str,
        #[serde(flatten)]
        params: &'a LabParams,
    }
    SceneModel { kind: "lab", params: model }.serialize(serializer)
}

/// The record beside the fitted model, for figures and Python.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FitSeries {
    /// Times.
    pub t: Vec<f64>,
    /// Load-point displacement of the model's loading at those times (0 at its start).
    pub x_lp: Vec<f64>,
    /// The record's friction.
    pub mu_data: Vec<f64>,
    /// The fitted friction (trend included).
    pub mu_fit: Vec<f64>,
}

/// Why a fit could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    /// The request does not make sense (names the field and the fix).
    #[error("{0}")]
    BadInput(String),
    /// The model could not be integrated.
    #[error("the model at the {stage} values: {source}")]
    Solver {
        /// "starting" or "fitted".
        stage: &'static str,
        /// Where and why.
        source: Box<SensitivityError>,
    },
    /// The model at the starting values blows up in finite time (the message says when and
    /// what to change).
    #[error("{0}")]
    BlowUp(String),
    /// A limit stopped the fit before its first evaluation was done.
    #[error("{0}")]
    Stopped(String),
    /// The parameters cannot be told apart from this record.
    #[error("{0}")]
    NotIdentifiable(String),
}

/// Limits on a fit's work (`stickslip fit --max-evaluations`, `--max-time`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitLimits {
    /// At most this many model evaluations.
    pub max_evaluations: usize,
    /// At most this much wall time (checked during every evaluation).
    pub max_time: Duration,
    /// An evaluation that takes more than this many times the first's internal steps, and
    /// more than `min_step_budget`, ends the fit.
    pub cost_factor: u64,
    /// The smallest step budget of an evaluation after the first.
    pub min_step_budget: u64,
}

impl Default for FitLimits {
    /// 200 evaluations (a fit of six parameters converges in 20 to 100), 600 s, an
    /// evaluation 50× the first's steps and over 20 000.
    fn default() -> Self {
        Self {
            max_evaluations: 200,
            max_time: Duration::from_secs(600),
            cost_factor: 50,
            min_step_budget: 20_000,
        }
    }
}

/// How to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// The parameters to fit, in order (no repeats).
    pub params: Vec<FitParameter>,
    /// The integrator: the method ([`SensitivityRoute::for_method`] says how it gives the
    /// sensitivities) and its tolerances.
    pub solver: LabSolver,
    /// The limits.
    pub limits: FitLimits,
}

/// Fits the lab model `start` under `loading` to `record` (see the module's doc).
pub fn fit(
    start: &LabParams,
    loading: &Loading,
    record: &FrictionRecord,
    settings: &FitSettings,
) -> Result<FitOutcome, FitError> {
    check(start, loading, record, settings)?;
    let started = Instant::now();
    let x_lp = loading.displacements_at(&record.t);
    let model: Vec<LabParameter> = settings
        .params
        .iter()
        .filter_map(|p| if let FitParameter::Model(m) = p { Some(*m) } else { None })
        .collect();
    let initial: Vec<f64> = settings
        .params
        .iter()
        .map(|p| match p {
            FitParameter::Model(m) => start.get(*m),
            FitParameter::Trend => 0.0,
        })
        .collect();
    let problem = Problem {
        start,
        loading,
        record,
        settings,
        model,
        x_lp: &x_lp,
        x: DVector::from_vec(initial.clone()),
        cache: RefCell::new(None),
        best: RefCell::new(None),
        last_norm: RefCell::new(f64::NAN),
        rejected: RefCell::new(0),
        runs: Cell::new(0),
        first_steps: Cell::new(None),
        deadline: started + settings.limits.max_time,
        stop: RefCell::new(None),
    };
    let first = match problem.evaluate() {
        Ok(e) => e,
        Err(Failure::Stopped(stop)) => {
            return Err(FitError::Stopped(format!(
                "{}, before the first evaluation was done",
                stop.message
            )))
        }
        Err(Failure::Solver(source)) => {
            return Err(diagnosis::at_start(start, loading, &settings.solver, source))
        }
    };
    *problem.best.borrow_mut() = Some(first.clone());
    *problem.cache.borrow_mut() = Some(first);
    // The evaluations are counted and capped by the problem; the optimiser's own patience
    // stays out of the way.
    let lm = LevenbergMarquardt::new().with_patience(settings.limits.max_evaluations.max(1));
    let (problem, report) = lm.minimize(problem);
    let stopped = problem.stop.borrow_mut().take();
    let evaluation = if stopped.is_some() {
        problem.best.borrow_mut().take().expect("the first evaluation succeeded")
    } else {
        let x = problem.x.clone();
        let cached = problem.cache.borrow_mut().take();
        match cached {
            Some(e) if e.x == x => e,
            _ => problem.evaluate().map_err(|f| match f {
                Failure::Solver(source) => {
                    FitError::Solver { stage: "fitted", source: Box::new(source) }
                }
                Failure::Stopped(stop) => FitError::Stopped(stop.message),
            })?,
        }
    };
    let x = evaluation.x.clone();
    let names: Vec<String> = settings.params.iter().map(FitParameter::name).collect();
    let mut warnings = vec![];
    let uncertainty =
        match statistics::uncertainty(&evaluation.jacobian, &evaluation.residuals, &names) {
            Ok(u) => u,
            Err(why) if stopped.is_some() => {
                warnings
                    .push(format!("no standard errors at the point where the fit stopped: {why}"));
                let p = names.len();
                statistics::Uncertainty {
                    standard_errors: vec![f64::NAN; p],
                    correlation: vec![vec![f64::NAN; p]; p],
                }
            }
            Err(why) => return Err(FitError::NotIdentifiable(why)),
        };
    let fitted = problem.params_at(&x);
    let parameters: Vec<FittedParameter> = settings
        .params
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let (value, se, init) = match p {
                FitParameter::Model(LabParameter::LnDc(_)) => {
                    let dc = x[j].exp();
                    (dc, dc * uncertainty.standard_errors[j], initial[j].exp())
                }
                _ => (x[j], uncertainty.standard_errors[j], initial[j]),
            };
            FittedParameter {
                name: names[j].clone(),
                value,
                standard_error: se,
                initial: init,
                unit: p.unit(),
            }
        })
        .collect();
    let a_minus_b = a_minus_b(settings, start, &fitted, &uncertainty);
    let residuals: Vec<f64> = evaluation.residuals.iter().copied().collect();
    let m = residuals.len();
    let residual_rms = (evaluation.residuals.norm_squared() / m as f64).sqrt();
    let rho = statistics::lag1_autocorrelation(&residuals);
    if rho > statistics::AUTOCORRELATION_WARNING {
        warnings.push(format!(
            "the residuals are strongly autocorrelated (lag-1 autocorrelation {rho:.2}): the standard errors assume independent noise and are too small, by a factor of about {:.1} for AR(1) noise; the model misses part of the record or the noise is coloured",
            ((1.0 + rho) / (1.0 - rho)).sqrt()
        ));
    }
    warnings.extend(diagnosis::sign_warnings(&parameters, &a_minus_b));
    let rejected_trials = *problem.rejected.borrow();
    let mu_fit: Vec<f64> = residuals.iter().zip(&record.mu).map(|(r, mu)| mu + r).collect();
    let termination = match &stopped {
        Some(stop) => stop.termination,
        None => Termination::from_report(&report.termination),
    };
    Ok(FitOutcome {
        parameters,
        a_minus_b,
        correlation: uncertainty.correlation,
        residual_rms,
        samples: m,
        evaluations: problem.runs.get(),
        rejected_trials,
        termination,
        converged: termination.is_converged(),
        stopped: stopped.map(|s| s.message),
        lag1_autocorrelation: rho,
        warnings,
        model: fitted,
        series: FitSeries { t: record.t.clone(), x_lp, mu_data: record.mu.clone(), mu_fit },
    })
}

/// a − Σ b_i at the fit and its standard error from the covariance of the fitted a and b_i.
fn a_minus_b(
    settings: &FitSettings,
    start: &LabParams,
    fitted: &LabParams,
    uncertainty: &statistics::Uncertainty,
) -> AMinusB {
    // The gradient of a − Σ b_i: +1 on a, −1 on each b_i.
    let weights: Vec<(usize, f64)> = settings
        .params
        .iter()
        .enumerate()
        .filter_map(|(j, p)| match p {
            FitParameter::Model(LabParameter::A) => Some((j, 1.0)),
            FitParameter::Model(LabParameter::B(_)) => Some((j, -1.0)),
            _ => None,
        })
        .collect();
    let se = &uncertainty.standard_errors;
    let variance: f64 = weights
        .iter()
        .flat_map(|(i, wi)| {
            weights
                .iter()
                .map(move |(j, wj)| wi * wj * uncertainty.correlation[*i][*j] * se[*i] * se[*j])
        })
        .sum();
    AMinusB {
        value: fitted.a_minus_b(),
        standard_error: variance.max(0.0).sqrt(),
        initial: start.a_minus_b(),
    }
}

fn check(
    start: &LabParams,
    loading: &Loading,
    record: &FrictionRecord,
    settings: &FitSettings,
) -> Result<(), FitError> {
    let bad = |m: String| Err(FitError::BadInput(m));
    if settings.params.is_empty() {
        return bad("--params: give at least one parameter to fit, e.g. a,b_1,d_c_1".into());
    }
    for (i, p) in settings.params.iter().enumerate() {
        if settings.params[..i].contains(p) {
            return bad(format!("--params: {} is named twice", p.name()));
        }
    }
    if settings
        .params
        .iter()
        .all(|p| matches!(p, FitParameter::Trend | FitParameter::Model(LabParameter::Mu0)))
    {
        return bad("--params: fit at least one of a, b_i, d_c_i or k (mu0 and trend alone are a straight line)".into());
    }
    if settings.limits.max_evaluations == 0 {
        return bad("--max-evaluations: give at least 1".into());
    }
    SensitivityRoute::for_method(settings.solver.method).map_err(FitError::BadInput)?;
    let (t0, t1) = (record.t[0], record.t[record.t.len() - 1]);
    if t0 < loading.t_start() || t1 > loading.t_end {
        return bad(format!(
            "the record spans t = {t0} … {t1}, the scene's loading {} … {}: make the loading cover the record (same time origin)",
            loading.t_start(),
            loading.t_end
        ));
    }
    if let Some(x) = &record.x_lp {
        units::check_displacement(&record.t, x, loading).map_err(FitError::BadInput)?;
    }
    if start.a <= 0.0 || start.k <= 0.0 {
        return bad("the scene's a and k must be > 0".into());
    }
    Ok(())
}

/// The residuals and their Jacobian at one set of parameter values.
#[derive(Clone)]
struct Evaluation {
    x: DVector<f64>,
    residuals: DVector<f64>,
    jacobian: DMatrix<f64>,
}

/// Why an evaluation gave nothing.
enum Failure {
    /// The integration failed.
    Solver(SensitivityError),
    /// A limit stopped it.
    Stopped(Stop),
}

/// A limit that stopped the fit.
struct Stop {
    termination: Termination,
    message: String,
}

/// The least-squares problem handed to the optimiser; each evaluation is one integration with
/// sensitivities, cached for the Jacobian call that follows a successful residual call.
struct Problem<'a> {
    start: &'a LabParams,
    loading: &'a Loading,
    record: &'a FrictionRecord,
    settings: &'a FitSettings,
    /// The model parameters among the fitted ones, in order.
    model: Vec<LabParameter>,
    /// Load-point displacement at the record's times.
    x_lp: &'a [f64],
    x: DVector<f64>,
    cache: RefCell<Option<Evaluation>>,
    /// The evaluation with the smallest residuals so far (the result of a stopped fit).
    best: RefCell<Option<Evaluation>>,
    /// The norm of the last successful residuals (sizes the rejection of a failed trial).
    last_norm: RefCell<f64>,
    rejected: RefCell<usize>,
    /// Model evaluations started.
    runs: Cell<usize>,
    /// The first evaluation's internal steps (sizes the later ones' budget).
    first_steps: Cell<Option<u64>>,
    deadline: Instant,
    /// Set when a limit stops the fit.
    stop: RefCell<Option<Stop>>,
}

impl Problem<'_> {
    fn params_at(&self, x: &DVector<f64>) -> LabParams {
        let mut p = self.start.clone();
        for (value, which) in x.iter().zip(&self.settings.params) {
            if let FitParameter::Model(m) = which {
                p.set(*m, *value);
            }
        }
        p
    }

    fn trend_at(&self, x: &DVector<f64>) -> f64 {
        self.settings.params.iter().position(|p| *p == FitParameter::Trend).map_or(0.0, |j| x[j])
    }

    /// The parameter values at x, for a message: `a = 0.01, b_1 = 0.012, d_c_1 = 5 µm`.
    fn describe(&self, x: &DVector<f64>) -> String {
        self.settings
            .params
            .iter()
            .zip(x.iter())
            .map(|(p, v)| {
                let value = if matches!(p, FitParameter::Model(LabParameter::LnDc(_))) {
                    v.exp()
                } else {
                    *v
                };
                let unit = p.unit();
                format!(
                    "{} = {value:.6e}{}{unit}",
                    p.name(),
                    if unit.is_empty() { "" } else { " " }
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn evaluate(&self) -> Result<Evaluation, Failure> {
        let limits = &self.settings.limits;
        let runs = self.runs.get();
        if runs >= limits.max_evaluations {
            return Err(Failure::Stopped(Stop {
                termination: Termination::MaxEvaluations,
                message: format!("--max-evaluations {} reached", limits.max_evaluations),
            }));
        }
        self.runs.set(runs + 1);
        let params = self.params_at(&self.x);
        let trend = self.trend_at(&self.x);
        let budget = Budget {
            steps: self
                .first_steps
                .get()
                .map(|s| (limits.cost_factor * s).max(limits.min_step_budget)),
            deadline: Some(self.deadline),
        };
        let f = match friction_sensitivities(
            &params,
            self.loading,
            &self.record.t,
            &self.model,
            &self.settings.solver,
            &budget,
        ) {
            Ok(f) => f,
            Err(SensitivityError::Deadline) => {
                return Err(Failure::Stopped(Stop {
                    termination: Termination::MaxTime,
                    message: format!(
                        "--max-time {} s passed during the evaluation at {}",
                        limits.max_time.as_secs_f64(),
                        self.describe(&self.x)
                    ),
                }))
            }
            Err(SensitivityError::Steps { limit }) => {
                return Err(Failure::Stopped(Stop {
                    termination: Termination::ExpensiveEvaluation,
                    message: format!(
                        "the evaluation at {} took more than {limit} internal steps (the first took {}): the model there is far stiffer than at the start; check the scene's loading and starting values, or fit fewer parameters",
                        self.describe(&self.x),
                        self.first_steps.get().unwrap_or(0)
                    ),
                }))
            }
            Err(e) => return Err(Failure::Solver(e)),
        };
        if self.first_steps.get().is_none() {
            self.first_steps.set(Some(f.steps.max(1)));
        }
        let (m, p, mm) = (self.record.t.len(), self.settings.params.len(), self.model.len());
        let x0 = self.x_lp[0];
        let residuals =
            DVector::from_fn(m, |i, _| f.mu[i] + trend * (self.x_lp[i] - x0) - self.record.mu[i]);
        let mut jacobian = DMatrix::zeros(m, p);
        let mut jm = 0;
        for (j, which) in self.settings.params.iter().enumerate() {
            match which {
                FitParameter::Model(_) => {
                    for i in 0..m {
                        jacobian[(i, j)] = f.dmu[i * mm + jm];
                    }
                    jm += 1;
                }
                FitParameter::Trend => {
                    for i in 0..m {
                        jacobian[(i, j)] = self.x_lp[i] - x0;
                    }
                }
            }
        }
        Ok(Evaluation { x: self.x.clone(), residuals, jacobian })
    }

    /// The evaluation at the current x, from the cache or a new run (None: it failed, the
    /// parameters are outside the model's domain, or a limit stopped the fit).
    fn current(&self) -> Option<std::cell::Ref<'_, Evaluation>> {
        if self.stop.borrow().is_some() {
            return None;
        }
        let fresh = self.cache.borrow().as_ref().is_some_and(|e| e.x == self.x);
        if !fresh {
            let params = self.params_at(&self.x);
            let valid = params.a > 0.0
                && params.k > 0.0
                && params.states.iter().all(|s| s.d_c.is_finite() && s.d_c > 0.0);
            let evaluation = if valid {
                match self.evaluate() {
                    Ok(e) => {
                        let better = self
                            .best
                            .borrow()
                            .as_ref()
                            .is_none_or(|b| e.residuals.norm() < b.residuals.norm());
                        if better {
                            *self.best.borrow_mut() = Some(e.clone());
                        }
                        Some(e)
                    }
                    Err(Failure::Solver(_)) => None,
                    Err(Failure::Stopped(stop)) => {
                        *self.stop.borrow_mut() = Some(stop);
                        return None;
                    }
                }
            } else {
                None
            };
            *self.cache.borrow_mut() = evaluation;
        }
        let cached = self.cache.borrow();
        if cached.is_none() {
            return None;
        }
        Some(std::cell::Ref::map(cached, |c| c.as_ref().expect("checked above")))
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        match self.current() {
            Some(e) => {
                *self.last_norm.borrow_mut() = e.residuals.norm();
                Some(e.residuals.clone())
            }
            // A limit stopped the fit: None ends the optimiser.
            None if self.stop.borrow().is_some() => None,
            None => {
                // A trial the model cannot evaluate: far worse residuals than the last good
                // ones, so the optimiser rejects the step and shrinks its trust region.
                *self.rejected.borrow_mut() += 1;
                let m = self.record.t.len();
                let norm = *self.last_norm.borrow();
                let level = 1e3 * if norm.is_finite() { norm + 1e-300 } else { 1.0 };
                Some(DVector::from_element(m, level / (m as f64).sqrt()))
            }
        }
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.current().map(|e| e.jacobian.clone())
    }
}
