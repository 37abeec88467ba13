//! Fitting the lab model ([`crate::model::lab`]) to a friction record: a, b_i, D_c,i, k, μ0
//! and an optional linear trend, by Levenberg–Marquardt with the exact Jacobian from CVODES'
//! forward sensitivities.
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

pub mod record;
mod sensitivity;
pub mod statistics;

pub use record::{ColumnNames, FrictionRecord};
pub use sensitivity::{friction_sensitivities, FrictionSensitivities};

use crate::analysis::lab::LabSolver;
use crate::integrate::SolverError;
use crate::model::{LabParameter, LabParams, Loading};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use serde::Serialize;
use std::cell::RefCell;

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
    /// Its standard error from σ̂²(JᵀJ)⁻¹ (D_c: by the delta method, D_c·σ(ln D_c)).
    pub standard_error: f64,
    /// The starting value.
    pub initial: f64,
}

/// What a fit found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitOutcome {
    /// The parameters, in the order asked for.
    pub parameters: Vec<FittedParameter>,
    /// Their correlation matrix, row by row.
    pub correlation: Vec<Vec<f64>>,
    /// Root-mean-square residual.
    pub residual_rms: f64,
    /// Number of samples fitted.
    pub samples: usize,
    /// Model evaluations (each one run with sensitivities).
    pub evaluations: usize,
    /// Trial steps whose model could not be evaluated (a non-positive a or k, a failed
    /// integration): rejected, the trust region shrunk.
    pub rejected_trials: usize,
    /// Why the optimiser stopped.
    pub termination: String,
    /// Whether it stopped converged.
    pub converged: bool,
    /// The residuals' lag-1 autocorrelation.
    pub lag1_autocorrelation: f64,
    /// Warnings (autocorrelated residuals).
    pub warnings: Vec<String>,
    /// The lab model with the fitted values.
    pub model: LabParams,
    /// The record and the fit: t, μ_data, μ_fit (trend included), residual.
    #[serde(skip)]
    pub series: FitSeries,
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
    /// The model could not be integrated at the starting values.
    #[error("the model at the {stage} values: segment {segment}: {source}")]
    Solver {
        /// "starting" or "fitted".
        stage: &'static str,
        /// The load segment where it failed.
        segment: usize,
        /// The solver's error.
        source: SolverError,
    },
    /// The parameters cannot be told apart from this record.
    #[error("{0}")]
    NotIdentifiable(String),
}

/// How to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// The parameters to fit, in order (no repeats).
    pub params: Vec<FitParameter>,
    /// The integrator's tolerances (CVODES BDF with sensitivities; the method is not used).
    pub solver: LabSolver,
    /// Optimiser patience: at most `patience · (p + 1)` evaluations.
    pub patience: usize,
}

/// Fits the lab model `start` under `loading` to `record` (see the module's doc).
pub fn fit(
    start: &LabParams,
    loading: &Loading,
    record: &FrictionRecord,
    settings: &FitSettings,
) -> Result<FitOutcome, FitError> {
    check(start, loading, record, settings)?;
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
        last_norm: RefCell::new(f64::NAN),
        rejected: RefCell::new(0),
    };
    let first = problem.evaluate().map_err(|(segment, source)| FitError::Solver {
        stage: "starting",
        segment,
        source,
    })?;
    *problem.cache.borrow_mut() = Some(first);
    let lm = LevenbergMarquardt::new().with_patience(settings.patience);
    let (problem, report) = lm.minimize(problem);
    let x = problem.x.clone();
    let cached = problem.cache.borrow_mut().take();
    let evaluation = match cached {
        Some(e) if e.x == x => e,
        _ => problem.evaluate().map_err(|(segment, source)| FitError::Solver {
            stage: "fitted",
            segment,
            source,
        })?,
    };
    let names: Vec<String> = settings.params.iter().map(FitParameter::name).collect();
    let uncertainty = statistics::uncertainty(&evaluation.jacobian, &evaluation.residuals, &names)
        .map_err(FitError::NotIdentifiable)?;
    let fitted = problem.params_at(&x);
    let parameters = settings
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
            FittedParameter { name: names[j].clone(), value, standard_error: se, initial: init }
        })
        .collect();
    let residuals: Vec<f64> = evaluation.residuals.iter().copied().collect();
    let m = residuals.len();
    let residual_rms = (evaluation.residuals.norm_squared() / m as f64).sqrt();
    let rho = statistics::lag1_autocorrelation(&residuals);
    let mut warnings = vec![];
    if rho > statistics::AUTOCORRELATION_WARNING {
        warnings.push(format!(
            "the residuals are strongly autocorrelated (lag-1 autocorrelation {rho:.2}): the standard errors assume independent noise and are too small, by a factor of about {:.1} for AR(1) noise; the model misses part of the record or the noise is coloured",
            ((1.0 + rho) / (1.0 - rho)).sqrt()
        ));
    }
    let rejected_trials = *problem.rejected.borrow();
    let mu_fit: Vec<f64> = residuals.iter().zip(&record.mu).map(|(r, mu)| mu + r).collect();
    Ok(FitOutcome {
        parameters,
        correlation: uncertainty.correlation,
        residual_rms,
        samples: m,
        evaluations: report.number_of_evaluations,
        rejected_trials,
        termination: format!("{:?}", report.termination),
        converged: report.termination.was_successful(),
        lag1_autocorrelation: rho,
        warnings,
        model: fitted,
        series: FitSeries { t: record.t.clone(), x_lp, mu_data: record.mu.clone(), mu_fit },
    })
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
    let (t0, t1) = (record.t[0], record.t[record.t.len() - 1]);
    if t0 < loading.t_start() || t1 > loading.t_end {
        return bad(format!(
            "the record spans t = {t0} … {t1}, the scene's loading {} … {}: make the loading cover the record (same time origin)",
            loading.t_start(),
            loading.t_end
        ));
    }
    if start.a <= 0.0 || start.k <= 0.0 {
        return bad("the scene's a and k must be > 0".into());
    }
    Ok(())
}

/// The residuals and their Jacobian at one set of parameter values.
struct Evaluation {
    x: DVector<f64>,
    residuals: DVector<f64>,
    jacobian: DMatrix<f64>,
}

/// The least-squares problem handed to the optimiser; each evaluation is one CVODES run with
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
    /// The norm of the last successful residuals (sizes the rejection of a failed trial).
    last_norm: RefCell<f64>,
    rejected: RefCell<usize>,
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

    fn evaluate(&self) -> Result<Evaluation, (usize, SolverError)> {
        let params = self.params_at(&self.x);
        let trend = self.trend_at(&self.x);
        let f = friction_sensitivities(
            &params,
            self.loading,
            &self.record.t,
            &self.model,
            &self.settings.solver,
        )?;
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

    /// The evaluation at the current x, from the cache or a new run (None: it failed, or the
    /// parameters are outside the model's domain).
    fn current(&self) -> Option<std::cell::Ref<'_, Evaluation>> {
        let fresh = self.cache.borrow().as_ref().is_some_and(|e| e.x == self.x);
        if !fresh {
            let params = self.params_at(&self.x);
            let valid = params.a > 0.0
                && params.k > 0.0
                && params.states.iter().all(|s| s.d_c.is_finite() && s.d_c > 0.0);
            let evaluation = if valid { self.evaluate().ok() } else { None };
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
