//! Step 3 of the noise pipeline ([`super::run`]): the statistics of the realisations on the
//! grid beside the linear response (step 4), where the two agree, and the report. In named
//! steps: the rows of Γ that are needed ([`Rows`]), each observable's moments, correlation
//! times, agreement and Γ curves ([`observable`]), the event-time spread ([`event_spread`]),
//! the growth of σ_v ([`growth`]), and the report's settings, deterministic and work sections.

use super::ensemble::EnsembleData;
use super::linear_response::LinearResponse;
use super::models::{NoiseModel, Observable};
use super::options::Alignment;
use super::scheme::DeterministicRun;
use super::statistics::{self, Moments, Width};
use super::{
    Agreement, CorrelationCurve, CorrelationPoint, Deterministic, EventLinearity, Events, Growth,
    NoiseReport, Plan, Realisations, Series, Settings, SettledOrbit, Work, DET_RTOL,
    EVENT_LINEARITY_LIMIT, SCHEME,
};
use crate::analysis::AnalysisError;
use crate::integrate::{OdeSystem, SolverError};

/// Step 3, the statistics of the realisations on the grid, beside the linear response (step
/// 4) and where the two agree; the report.
pub(super) fn statistics(
    model: &NoiseModel,
    orbit: &SettledOrbit,
    plan: Plan,
    realisations: Realisations,
    linear: Option<LinearResponse>,
    det_atol: &[f64],
) -> Result<NoiseReport, AnalysisError> {
    let det = DeterministicRun { model, rtol: DET_RTOL, atol: det_atol };
    let path_orbit = det.states(orbit.start.t, &orbit.start.x, &plan.times)?;
    let rows = Rows::of(&plan);
    let observables = model.observables();
    let mut linear_steps = linear.as_ref().map_or(0, |l| l.steps);
    let mut series = Vec::new();
    let mut by_variable = Vec::new();
    let mut agreement = Vec::new();
    let mut correlation_functions = Vec::new();
    for (o, &(name, obs)) in observables.iter().enumerate() {
        let context = Context {
            model,
            plan: &plan,
            data: &realisations.data,
            linear: linear.as_ref(),
            rows: &rows,
            path_orbit: &path_orbit,
        };
        let stats = observable(&context, o, name, obs, o == 0, &mut linear_steps)?;
        agreement.extend(stats.agreement);
        correlation_functions.extend(stats.curves);
        by_variable.push((name.to_string(), stats.points));
        series.push(stats.series);
    }
    let growth = growth(model, orbit, &plan, &series);
    let linearity = linear
        .as_ref()
        .map(|l| event_linearity(l, plan.h, orbit.t_event - orbit.start.t, &mut linear_steps))
        .transpose()?;
    let events = event_spread(
        &realisations.data,
        orbit.t_event,
        plan.realisations,
        linear.as_ref(),
        linearity,
    );
    let work = work(&realisations, plan.realisations, linear.as_ref().map(|_| linear_steps));
    let deterministic = deterministic(model, orbit, realisations.event_time_without_noise);
    Ok(NoiseReport {
        model: model.kind(),
        t_before_event: plan.s.iter().map(|v| -v).collect(),
        settings: settings(model, orbit, plan, realisations.atol),
        scheme: SCHEME,
        deterministic,
        events,
        series,
        correlation_variable: observables[0].0,
        correlation_time: by_variable[0].1.clone(),
        correlation_time_by_variable: by_variable,
        correlation_functions,
        growth,
        agreement,
        work,
    })
}

/// The grid rows where Γ(t_j, ·) is needed: at the report times, at the Γ curves' times, and
/// both together (sorted, without repeats).
struct Rows {
    report: Vec<usize>,
    curves: Vec<usize>,
    all: Vec<usize>,
}

impl Rows {
    fn of(plan: &Plan) -> Self {
        let report: Vec<usize> =
            plan.report_times.iter().map(|t| statistics::nearest(&plan.s, -t)).collect();
        let curves: Vec<usize> =
            plan.curves_at.iter().map(|t| statistics::nearest(&plan.s, -t)).collect();
        let mut all: Vec<usize> = report.iter().chain(&curves).copied().collect();
        all.sort_unstable();
        all.dedup();
        Self { report, curves, all }
    }
}

/// What every observable's statistics read.
struct Context<'a> {
    model: &'a NoiseModel,
    plan: &'a Plan,
    data: &'a EnsembleData,
    linear: Option<&'a LinearResponse>,
    rows: &'a Rows,
    /// The deterministic states at the grid times.
    path_orbit: &'a [Vec<f64>],
}

/// One observable's statistics.
struct ObservableStats {
    series: Series,
    points: Vec<CorrelationPoint>,
    agreement: Option<Agreement>,
    curves: Vec<CorrelationCurve>,
}

/// Observable number `o`: the ensemble's moments, the linear response's, the correlation times
/// at the report rows, their agreement and (`with_curves`) the Γ curves. The linear response's
/// adjoint steps are added to `linear_steps`.
fn observable(
    c: &Context<'_>,
    o: usize,
    name: &'static str,
    obs: Observable,
    with_curves: bool,
    linear_steps: &mut u64,
) -> Result<ObservableStats, SolverError> {
    let (s, k_n) = (&c.plan.s, c.plan.s.len());
    let stride = c.model.observables().len() * k_n;
    let m = Moments::from_samples(
        &c.data.samples,
        c.plan.realisations,
        stride,
        o * k_n,
        k_n,
        &c.rows.all,
    );
    let deterministic: Vec<f64> = c.path_orbit.iter().map(|x| obs.value(x)).collect();
    let lin =
        c.linear.map(|l| linear_moments(c, l, obs, &deterministic, linear_steps)).transpose()?;
    let tau_of = |m: &Moments, j: usize, width: Width| {
        statistics::correlation_time(&row_of(m, j), &m.var, s, j, width)
    };
    let sigma = m.sigma();
    let sigma_lin = lin.as_ref().map(|l| l.sigma());
    let points: Vec<CorrelationPoint> = c
        .rows
        .report
        .iter()
        .map(|&j| CorrelationPoint {
            t_before_event: -s[j],
            tau: tau_of(&m, j, Width::HalfHeight),
            tau_linear_response: lin.as_ref().and_then(|l| tau_of(l, j, Width::HalfHeight)),
            tau_coefficient: tau_of(&m, j, Width::Coefficient),
            tau_coefficient_linear_response: lin
                .as_ref()
                .and_then(|l| tau_of(l, j, Width::Coefficient)),
        })
        .collect();
    let agreement = sigma_lin
        .as_ref()
        .map(|sl| agreement_of(name, &sigma, sl, &points, &c.rows.report, s, c.plan.realisations));
    let curves = if with_curves {
        c.rows
            .curves
            .iter()
            .map(|&j| CorrelationCurve {
                t_before_event: -s[j],
                lag: (0..=j).rev().map(|k| s[j] - s[k]).collect(),
                gamma: row_of(&m, j).into_iter().rev().collect(),
                gamma_linear_response: lin
                    .as_ref()
                    .map(|l| row_of(l, j).into_iter().rev().collect()),
            })
            .collect()
    } else {
        Vec::new()
    };
    let series =
        Series { name, mean: m.mean, deterministic, sigma, sigma_linear_response: sigma_lin };
    Ok(ObservableStats { series, points, agreement, curves })
}

/// The linear response of an observable, δo = ∇o(x̄)·δx: its variances and the covariance
/// rows at every needed row, with the deterministic values as its mean.
fn linear_moments(
    c: &Context<'_>,
    l: &LinearResponse,
    obs: Observable,
    deterministic: &[f64],
    linear_steps: &mut u64,
) -> Result<Moments, SolverError> {
    let n = c.model.dim();
    let own = c.plan.alignment == Alignment::OwnEvent;
    let grads: Vec<Vec<f64>> = l
        .orbit
        .iter()
        .map(|x| {
            let mut g = vec![0.0; l.big];
            obs.gradient(x, &mut g[..n]);
            g
        })
        .collect();
    let var = l.variances(&grads, own);
    let rows = c
        .rows
        .all
        .iter()
        .map(|&j| {
            let (row, steps) = l.row(&grads, own, j)?;
            *linear_steps += steps;
            Ok((j, row))
        })
        .collect::<Result<Vec<(usize, Vec<f64>)>, SolverError>>()?;
    Ok(Moments { mean: deterministic.to_vec(), var, rows })
}

/// Γ(t_j, t_k), k = 0..=j, of a requested row j.
fn row_of(m: &Moments, j: usize) -> Vec<f64> {
    m.rows.iter().find(|(r, _)| *r == j).map(|(_, row)| row.clone()).expect("a requested row")
}

/// The realisations' event times against the deterministic one: mean shift and spread, with
/// the linear response's spread.
fn event_spread(
    data: &EnsembleData,
    t_event: f64,
    realisations: usize,
    linear: Option<&LinearResponse>,
    linearity: Option<EventLinearity>,
) -> Events {
    let r_n = realisations as f64;
    let shifts: Vec<f64> = data.event_times.iter().map(|t| t - t_event).collect();
    let mean_shift = shifts.iter().sum::<f64>() / r_n;
    let std = (shifts.iter().map(|d| (d - mean_shift).powi(2)).sum::<f64>() / (r_n - 1.0)).sqrt();
    Events { mean_shift, std, std_linear_response: linear.map(|l| l.event_time_std), linearity }
}

/// Lags per decade at which the event function's correlation ρ_g is sampled.
const LAGS_PER_DECADE: f64 = 8.0;

/// The validity of the linearised event time: the own-frame deviation of the event function
/// at the lag σ_tc (the linear event-time spread), and ρ_g's half-height width on log-spaced
/// lags from 1e-4 · min(σ_tc, h) to min(0.9 · `span`, 1e3 · max(σ_tc, h)), h the noise step;
/// `span` = t_c − t_start. The steps are added to `linear_steps`.
fn event_linearity(
    l: &LinearResponse,
    h: f64,
    span: f64,
    linear_steps: &mut u64,
) -> Result<EventLinearity, SolverError> {
    let sigma = l.event_time_std;
    let shortest = if sigma > 0.0 { sigma.min(h) } else { h };
    let (lo, hi) = (1e-4 * shortest, (0.9 * span).min(1e3 * sigma.max(h)));
    let count = (LAGS_PER_DECADE * (hi / lo).log10()).ceil().max(1.0) as usize;
    let mut lags: Vec<f64> =
        (0..=count).map(|i| lo * (hi / lo).powf(i as f64 / count as f64)).collect();
    let at_spread = sigma.clamp(lo, hi);
    lags.push(at_spread);
    lags.sort_by(|a, b| a.total_cmp(b));
    lags.dedup();
    let (e, steps) = l.event_function_at_lags(&lags)?;
    *linear_steps += steps;
    let rho = &e.correlation;
    // The first lag where ρ_g has fallen to one half, log-linearly interpolated.
    let width = (rho[0] > 0.5).then(|| rho.iter().position(|r| *r <= 0.5)).flatten().map(|i| {
        let (r0, r1) = (rho[i - 1], rho[i]);
        let (a, b) = (lags[i - 1].ln(), lags[i].ln());
        (a + (r0 - 0.5) / (r0 - r1) * (b - a)).exp()
    });
    let own_frame_deviation =
        e.own_frame[lags.iter().position(|s| *s == at_spread).expect("an examined lag")];
    Ok(EventLinearity {
        own_frame_deviation,
        event_function_correlation_time: width,
        valid: own_frame_deviation <= EVENT_LINEARITY_LIMIT,
    })
}

/// The settings as used.
fn settings(model: &NoiseModel, orbit: &SettledOrbit, plan: Plan, atol: Vec<f64>) -> Settings {
    Settings {
        amplitudes: model.amplitudes(),
        correlation_time: plan.tau,
        noise_step: plan.h,
        steps_per_correlation_time: plan.steps_per_tau,
        realisations: plan.realisations,
        seed: plan.seed,
        start_before_event: orbit.before,
        window: plan.window,
        alignment: plan.alignment,
        grid_points: plan.grid_points,
        report_points: plan.report_count,
        rtol: plan.rtol,
        atol,
        linear_response: plan.want_linear,
        correlation_curves_at: plan.curves_at,
        event: plan.event_words,
    }
}

/// The deterministic orbit's section, with the scheme's own event-time error.
fn deterministic(
    model: &NoiseModel,
    orbit: &SettledOrbit,
    event_time_without_noise: f64,
) -> Deterministic {
    Deterministic {
        period: orbit.period,
        burn_in_events: orbit.burn_in_events,
        t0: orbit.t0,
        start_time: orbit.start.t,
        start_state: orbit.start.x.clone(),
        components: model.component_names().to_vec(),
        event_time: orbit.t_event,
        event_state: orbit.x_event.clone(),
        event_time_without_noise,
        scheme_event_time_error: event_time_without_noise - orbit.t_event,
    }
}

/// The work done by the ensemble and the linear response.
fn work(realisations: &Realisations, count: usize, linear_response_steps: Option<u64>) -> Work {
    let data = &realisations.data;
    Work {
        steps: data.stats.steps,
        step_attempts: data.stats.step_attempts,
        rhs_evals: data.stats.rhs_evals + data.stats.rhs_evals_jacobian,
        jac_evals: data.stats.jac_evals,
        nodes_per_realisation: data.nodes as f64 / count as f64,
        linear_response_steps,
        ensemble_wall_time_s: realisations.wall_time_s,
    }
}

/// Ensemble against linear response for one observable over the report rows: σ's largest
/// relative difference and where it exceeds 4 standard errors, τ's median and largest.
fn agreement_of(
    name: &'static str,
    sigma: &[f64],
    sigma_lin: &[f64],
    points: &[CorrelationPoint],
    report_rows: &[usize],
    s: &[f64],
    realisations: usize,
) -> Agreement {
    let se = 1.0 / (2.0 * (realisations as f64 - 1.0)).sqrt();
    let mut max_rel = 0.0f64;
    let mut disagree = Vec::new();
    for &j in report_rows {
        if sigma_lin[j] > 0.0 {
            let rel = sigma[j] / sigma_lin[j] - 1.0;
            max_rel = max_rel.max(rel.abs());
            if rel.abs() > 4.0 * se {
                disagree.push(-s[j]);
            }
        }
    }
    let mut rels: Vec<f64> = points
        .iter()
        .filter_map(|p| match (p.tau, p.tau_linear_response) {
            (Some(a), Some(b)) if b > 0.0 => Some((a / b - 1.0).abs()),
            _ => None,
        })
        .collect();
    rels.sort_by(|a, b| a.total_cmp(b));
    Agreement {
        name,
        sigma_standard_error: se,
        sigma_max_relative_difference: max_rel,
        sigma_disagree_at: disagree,
        tau_median_relative_difference: (!rels.is_empty()).then(|| rels[rels.len() / 2]),
        tau_max_relative_difference: rels.last().copied(),
    }
}

/// DRR: the growth of σ_v against v over (t_f − t0, t_f), t_f = t_c − 0.1, from the series.
fn growth(
    model: &NoiseModel,
    orbit: &SettledOrbit,
    plan: &Plan,
    series: &[Series],
) -> Option<Growth> {
    match (model, orbit.t0) {
        (NoiseModel::Drr { .. }, Some(t0)) if !plan.growth_points.is_empty() => {
            let (jf, j0) =
                (statistics::nearest(&plan.s, -0.1), statistics::nearest(&plan.s, -(0.1 + t0)));
            let v = &series[1];
            let v_growth = v.mean[jf] / v.mean[j0];
            let sigma_v_growth = v.sigma[jf] / v.sigma[j0];
            let lin = v
                .sigma_linear_response
                .as_ref()
                .map(|sl| (v.deterministic[jf] / v.deterministic[j0], sl[jf] / sl[j0]));
            Some(Growth {
                t_f_before_event: 0.1,
                interval: t0,
                v_growth,
                sigma_v_growth,
                ratio: sigma_v_growth / v_growth,
                log10_ratio: (sigma_v_growth / v_growth).log10(),
                v_growth_linear_response: lin.map(|l| l.0),
                sigma_v_growth_linear_response: lin.map(|l| l.1),
                ratio_linear_response: lin.map(|l| l.1 / l.0),
            })
        }
        _ => None,
    }
}
