//! Finite-time Lyapunov exponents of the cycle from the variational equations with QR
//! re-orthonormalisation, and their link to the Floquet multipliers.
//!
//! The state and a tangent frame Y (3×3, in (u, w = ln v, θ)) are integrated together
//! ([`Variational`], by Radau5 whatever the scene's method) from the cycle's v maximum, period
//! after period (a period ends at the next v maximum). At each cut the frame is replaced by
//! [f̂, q₂, q₃]: f̂ the flow direction (dy/dt from the interpolant) and q₂, q₃ the QR of the
//! other two columns projected orthogonally to f. The flow direction's log-growth is
//! ln(|f|/|f_previous cut|) exactly, so λ₁ = 0 over whole periods; ln |R₂₂| accumulates the
//! second exponent: over n periods λ₂ = Σ ln |R₂₂| / (n T) → ln |μ₂| / T, μ₂ the largest
//! non-trivial Floquet multiplier. Two things make the plain QR method fail here, both
//! measured at γ = 1e8:
//!
//! - the integrated first column cannot follow the flow: |f| falls by e^{35} from the slip
//!   arrest to the stick, far below the absolute tolerance on Y — hence f̂ from dy/dt;
//! - the other columns gain a large component along f (a timing shift) while their part
//!   orthogonal to f shrinks with μ₂ (≈ e^{−36} per period at γ = 1e8): their precision,
//!   relative to the whole column, is lost. Cuts are therefore also made wherever that
//!   orthogonal part falls below 1e-3 of its column ("drift" cuts), in the stick too: Radau5
//!   restarts on the slow manifold, where a restarted BDF fails at large γ.
//!
//! Fixed cuts: on the descent where v falls below γ (before the slip arrest, whose transient
//! growth along the fast direction must not enter the frame), and once the arrest is over
//! (v < 1), both where a restart is safe (the cycle analysis' criterion); no drift cut between
//! them. The third direction contracts like exp(−∫ γ² f'(v)/ξ dt), far below 1e-308 over a
//! stick, so its exponent comes from Liouville's formula: Σ λ_i = (1/nT) ∫ tr J dt with,
//! exactly along the computed trajectory, ∫ tr J dt = −Δw − Δu − Δt − (γ²/ξ) ∫ f'(v) dt
//! (J_ww = γ² e^{−w}(G − v f'/ξ) with γ² e^{−w} G = −dw/dt; J_θθ = −v = −(u' + 1)); ∫ f'(v) dt
//! by Simpson's rule on each step. Time restarts from 0 at every cut.
//!
//! Checked against finite differences of the Poincaré map (tests/lyapunov.rs): at γ = 1e4,
//! ξ = 0.8, ε = 1, ln |μ₂| = −17.65 both ways, where shooting's section Jacobian gives −16.2.

use super::VariationalFactory;
use crate::analysis::cycle::restart_safe;
use crate::analysis::shooting::{self, ShootingSettings};
use crate::analysis::AnalysisError;
use crate::integrate::{Clock, Time};
use crate::model::drr::{Drr, W};
use crate::model::DrrParams;
use crate::model::Variational;
use crate::numerics::events;
use crate::numerics::series::{decimate, pick};
use crate::paper::cycle_period::CyclePeriod;
use crate::solver::{Method, SolverSpec};
use nalgebra::{Matrix3x2, Vector3};
use serde::Serialize;

/// ln |R_ii| and the trace integral of one period.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeriodLogs {
    /// Length of the period (v maximum to v maximum).
    pub time: f64,
    /// Σ ln |R₁₁|, Σ ln |R₂₂| over the period's re-orthonormalisations.
    pub ln_r: [f64; 2],
    /// ∫ tr J dt over the period (Liouville).
    pub trace_integral: f64,
}

/// The cumulative logs along the last period (the data of finite-time exponents along the
/// cycle): the slopes of ln |R_ii| are the local exponents of the QR frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FtleSeries {
    /// t − t_c (t_c: the v maximum that ends the period).
    pub t: Vec<f64>,
    /// Σ ln |R₁₁| since the start of the period.
    pub ln_r11: Vec<f64>,
    /// Σ ln |R₂₂| since the start of the period.
    pub ln_r22: Vec<f64>,
}

/// The Floquet multipliers of the same orbit by shooting, beside the FTLE.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloquetLink {
    /// "shooting" (crate::analysis::shooting: Newton on the section v = 1).
    pub source: &'static str,
    /// ln |μ| of the non-trivial multipliers, by decreasing modulus (null where μ underflows
    /// to 0).
    pub ln_abs_nontrivial: Vec<Option<f64>>,
    /// |μ_trivial − 1| of the fixed-time monodromy (shooting's own check).
    pub trivial_multiplier_error: f64,
    /// λ_i T (T: the shooting period), to set beside ln |μ_i| (λ₁ T beside 0).
    pub ftle_times_period: [f64; 3],
    /// The last period's ln |R₁₁|, ln |R₂₂| and ∫ tr J − both (its ln |R₃₃|).
    pub last_period_logs: [f64; 3],
    /// Shooting period.
    pub period: f64,
}

/// The method of the variational equations, whatever the scene's (see the module's doc).
pub const VARIATIONAL_METHOD: Method = Method::Radau5;

/// The "ftle" part of the lyapunov section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FtleReport {
    /// The integration method of the variational equations ([`VARIATIONAL_METHOD`]).
    pub method: Method,
    /// Periods integrated.
    pub periods: usize,
    /// Total time integrated.
    pub time: f64,
    /// λ₁, λ₂ (QR) and λ₃ (Liouville), 1/time unit.
    pub exponents: [f64; 3],
    /// Per period.
    pub per_period: Vec<PeriodLogs>,
    /// Re-orthonormalisations (cuts) made.
    pub cuts: usize,
    /// Integrator steps.
    pub steps: u64,
    /// The link to the Floquet multipliers (null if shooting did not converge).
    pub floquet: Option<FloquetLink>,
    /// Why `floquet` is null, if it is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floquet_note: Option<String>,
    /// Figure data.
    pub along_cycle: FtleSeries,
}

fn first3(z: &[f64]) -> [f64; 3] {
    [z[0], z[1], z[2]]
}

/// One sample: local time, state and its interpolant derivative.
#[derive(Debug, Clone, Copy)]
struct Sample {
    t: f64,
    y: [f64; 3],
    d: [f64; 3],
}

/// The frame's logs at a point: ln(|f|/|f₀|) for the flow direction and, for the two other
/// columns projected orthogonally to f, ln |R₂₂|, ln |R₃₃| of their QR; with the augmented
/// state (y, [f̂, q₂, q₃]) to restart from.
fn reorthonormalise(z: &[f64], f: &[f64; 3], f0_norm: f64) -> ([f64; 3], Vec<f64>) {
    let phi = Variational::<Drr, 3>::matrix(z);
    let norm = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let fh = Vector3::new(f[0] / norm, f[1] / norm, f[2] / norm);
    let project = |col: usize| {
        let c = Vector3::new(phi[0][col], phi[1][col], phi[2][col]);
        c - fh * fh.dot(&c)
    };
    let m = Matrix3x2::from_columns(&[project(1), project(2)]);
    let qr = m.qr();
    let (q, r) = (qr.q(), qr.r());
    let mut out = z[..3].to_vec();
    out.extend(fh.iter());
    for col in 0..2 {
        out.extend((0..3).map(|row| q[(row, col)]));
    }
    ([(norm / f0_norm).ln(), r[(0, 0)].abs().ln(), r[(1, 1)].abs().ln()], out)
}

/// Integrates `periods` periods from the orbit's v maximum, on the model `p` with `solver`'s
/// tolerances; `variational` builds the integrators of the variational equations.
pub fn analyse(
    p: DrrParams,
    solver: &SolverSpec,
    variational: &mut VariationalFactory<'_>,
    orbit: &CyclePeriod,
    periods: usize,
    series_points: usize,
) -> Result<FtleReport, AnalysisError> {
    let drr = Drr::new(p);
    let start = orbit.state(orbit.peak);
    let spec = SolverSpec {
        method: VARIATIONAL_METHOD,
        table: None,
        explicit_table: None,
        ..solver.clone()
    };
    let mut integ = variational(drr, &spec, &start)?;
    let w_tol = (solver.rtol, solver.atol[1]);
    let floor = 1e-9f64.max(1e3 * (w_tol.0 + w_tol.1));
    let descent_level = p.gamma.ln();
    let mut d0 = [0.0; 3];
    crate::integrate::OdeSystem::rhs(&drr, 0.0, &start, &mut d0);
    let (_, first) = reorthonormalise(&Variational::<Drr, 3>::initial(&start), &d0, 1.0);
    integ.reinit(0.0, &first)?;
    let mut clock = Clock::new(integ.as_mut(), Time::new(0.0));
    let norm3 = |f: &[f64; 3]| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let mut f_norm = norm3(&d0);
    let mut prev = Sample { t: 0.0, y: start, d: d0 };
    let (mut steps, mut cuts) = (0u64, 0usize);
    let mut per_period = Vec::new();
    // Per period: its start on the global clock, logs so far; the state at its start; ∫ f'(v) dt.
    let (mut period_t0, mut logs, mut quad) = (Time::new(0.0), [0.0; 2], 0.0);
    let mut period_start = start;
    let mut down_seen = false;
    // 0: before the descent cut, 1: before the post-arrest cut, 2: stick and rise.
    let first_stage = |w: f64| if w > descent_level { 0u8 } else { 1 };
    let mut stage = first_stage(start[W]);
    let mut series: Vec<(f64, [f64; 2])> = Vec::new();
    let mut total_time = 0.0;
    let fprime = |w: f64| {
        let (_, vfp) = p.friction.eval(w);
        vfp * (-w).exp()
    };
    let failure = |clock: &Clock, message: String| AnalysisError::Failed {
        analysis: "the FTLE integration",
        t: clock.now().to_f64(),
        state: clock.state()[..3].to_vec(),
        message,
    };
    while per_period.len() < periods {
        let step = clock.step().map_err(|e| clock.at_global(e))?;
        prev.t = step.start;
        steps += 1;
        let z = clock.state().to_vec();
        let y = first3(&z);
        let d = first3(clock.integrator().dense(step.t, 1)?);
        if z.iter().chain(&d).any(|x| !x.is_finite()) {
            return Err(failure(
                &clock,
                "the state, the tangent frame or dy/dt became non-finite".into(),
            ));
        }
        if steps > 20_000_000 {
            return Err(failure(&clock, "2e7 steps without completing the FTLE periods".into()));
        }
        let mid = clock.integrator().dense(0.5 * (prev.t + step.t), 0)?[W];
        quad += (step.t - prev.t) / 6.0 * (fprime(prev.y[W]) + 4.0 * fprime(mid) + fprime(y[W]));
        let (now, _) = reorthonormalise(&z, &d, f_norm);
        if per_period.len() + 1 == periods {
            series.push((
                clock.global(step.t).since(period_t0),
                [logs[0] + now[0], logs[1] + now[1]],
            ));
        }
        if prev.y[W] >= 0.0 && y[W] < 0.0 {
            down_seen = true;
        }
        let phi = Variational::<Drr, 3>::matrix(&z);
        let column2 = (phi[0][1].powi(2) + phi[1][1].powi(2) + phi[2][1].powi(2)).sqrt();
        let drifting = now[1] - column2.ln() < -(1e3f64.ln());
        let safe = restart_safe(&drr, w_tol, &y, d[W].abs());
        // The period ends at the v maximum after a downward crossing of v = 1 (refined on the
        // interpolant); the other cuts are made at step ends.
        let cut = if down_seen && prev.d[W] > 0.0 && d[W] <= 0.0 && y[W] > floor {
            Some((events::refine(clock.integrator(), (prev.t, step.t), 1, W, 0.0)?, true))
        } else if (stage == 0 && y[W] <= descent_level && safe) || (stage == 1 && down_seen && safe)
        {
            stage += 1;
            Some((step.t, false))
        } else if stage == 2 && drifting {
            Some((step.t, false))
        } else {
            None
        };
        let Some((t, period_end)) = cut else {
            prev = Sample { t: step.t, y, d };
            continue;
        };
        let zc = clock.integrator().dense(t, 0)?.to_vec();
        let vc = first3(clock.integrator().dense(t, 1)?);
        let yc = first3(&zc);
        if t < step.t {
            // Simpson's sum ran to the step end: take back the part after t.
            let tail = clock.integrator().dense(0.5 * (t + step.t), 0)?[W];
            quad -= (step.t - t) / 6.0 * (fprime(yc[W]) + 4.0 * fprime(tail) + fprime(y[W]));
        }
        let (l, restart) = reorthonormalise(&zc, &vc, f_norm);
        f_norm = norm3(&vc);
        logs[0] += l[0];
        logs[1] += l[1];
        cuts += 1;
        let at = clock.global(t);
        let elapsed = at.since(period_t0);
        if per_period.len() + 1 == periods {
            series.pop();
            series.push((elapsed, logs));
        }
        if period_end {
            let (du, dw) = (yc[0] - period_start[0], yc[W] - period_start[W]);
            let trace_integral = -dw - du - elapsed - p.gamma * p.gamma / p.xi * quad;
            per_period.push(PeriodLogs { time: elapsed, ln_r: logs, trace_integral });
            total_time += elapsed;
            (period_t0, logs, quad, period_start, down_seen, stage) =
                (at, [0.0; 2], 0.0, yc, false, first_stage(yc[W]));
        }
        clock.reinit(at, &restart, None)?;
        prev = Sample { t: 0.0, y: yc, d: vc };
    }
    let sum = |f: &dyn Fn(&PeriodLogs) -> f64| per_period.iter().map(f).sum::<f64>();
    let (l1, l2, tr) = (sum(&|q| q.ln_r[0]), sum(&|q| q.ln_r[1]), sum(&|q| q.trace_integral));
    let exponents = [l1 / total_time, l2 / total_time, (tr - l1 - l2) / total_time];
    let last_elapsed = per_period.last().map_or(0.0, |q| q.time);
    let t: Vec<f64> = series.iter().map(|(t, _)| t - last_elapsed).collect();
    let r11: Vec<f64> = series.iter().map(|(_, l)| l[0]).collect();
    let r22: Vec<f64> = series.iter().map(|(_, l)| l[1]).collect();
    let keep = decimate(&t, &[&r11, &r22], series_points);
    let (floquet, floquet_note) =
        match floquet_link(solver, variational, &drr, orbit, &per_period, &exponents) {
            Ok(f) => (Some(f), None),
            Err(why) => (None, Some(why.into_note()?)),
        };
    Ok(FtleReport {
        method: VARIATIONAL_METHOD,
        periods: per_period.len(),
        time: total_time,
        exponents,
        per_period,
        cuts,
        steps,
        floquet,
        floquet_note,
        along_cycle: FtleSeries {
            t: pick(&t, &keep),
            ln_r11: pick(&r11, &keep),
            ln_r22: pick(&r22, &keep),
        },
    })
}

/// The Floquet multipliers by shooting from the orbit, set beside the FTLE
/// ([`AnalysisError::NotConverged`] when shooting does not converge: a note in the report).
fn floquet_link(
    solver: &SolverSpec,
    variational: &mut VariationalFactory<'_>,
    drr: &Drr,
    orbit: &CyclePeriod,
    per_period: &[PeriodLogs],
    exponents: &[f64; 3],
) -> Result<FloquetLink, AnalysisError> {
    let settings = ShootingSettings::defaults(solver.rtol, solver.atol[1]);
    let y0 = orbit.state(orbit.up);
    let mut integ = variational(*drr, solver, &y0)?;
    let report = shooting::analyse(integ.as_mut(), drr, y0, &settings)?;
    let Some(o) = report.orbit else {
        return Err(AnalysisError::NotConverged {
            what: "shooting",
            reason: report.failure.map_or(String::new(), |why| why.to_string()),
        });
    };
    let last = per_period.last().copied().unwrap_or(PeriodLogs {
        time: 0.0,
        ln_r: [0.0; 2],
        trace_integral: 0.0,
    });
    Ok(FloquetLink {
        source: "shooting",
        ln_abs_nontrivial: o
            .nontrivial()
            .iter()
            .map(|m| (m.modulus > 0.0).then(|| m.modulus.ln()).filter(|x| x.is_finite()))
            .collect(),
        trivial_multiplier_error: o.trivial_multiplier_error,
        ftle_times_period: exponents.map(|l| l * o.period),
        last_period_logs: [
            last.ln_r[0],
            last.ln_r[1],
            last.trace_integral - last.ln_r[0] - last.ln_r[1],
        ],
        period: o.period,
    })
}
