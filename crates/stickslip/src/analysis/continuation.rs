//! Natural-parameter continuation of the periodic orbit in ε, ξ or γ (γ in log steps).
//!
//! The orbit is first found by shooting at the scene's parameters; then for each point of the
//! requested grid the parameter is advanced in sub-steps: the predictor extrapolates the
//! section point linearly from the last two orbits (secant), the corrector is the shooting
//! Newton iteration. A failed corrector halves the sub-step, a quick one (≤ 3 iterations)
//! doubles it, up to the grid spacing; below 1/1024 of the spacing the continuation stops
//! and says why (e.g. the orbit shrinking onto the fixed point at the Hopf threshold ε_c, or a
//! fold where a multiplier reaches 1). A real multiplier crossing −1 between two points is
//! reported as a period doubling; an orbit whose multipliers are unresolved (withheld by
//! shooting) has none, so no flip is reported on it.
//!
//! Reference: E. L. Allgower, K. Georg, *Introduction to Numerical Continuation Methods*,
//! SIAM 2003, ch. 1–2 (natural-parameter continuation with step control).

use super::hopf;
use super::shooting::{self, NoOrbit, PeriodicOrbit, ShootingSettings};
use super::AnalysisError;
use crate::integrate::{Integrator, SolverError};
use crate::model::{Drr, DrrParams};
use serde::Serialize;

/// The parameter being continued.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    /// ε = (B − A)/A.
    Epsilon,
    /// ξ = k D_c/A.
    Xi,
    /// γ (stepped in log10 γ).
    Gamma,
    /// The radiation damping η (scene name "radiation_damping").
    Eta,
}

impl Parameter {
    /// Every parameter, in the order the errors list them.
    pub const ALL: [Parameter; 4] =
        [Parameter::Epsilon, Parameter::Xi, Parameter::Gamma, Parameter::Eta];

    /// The parameter by its scene name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The scene names of `parameters`, quoted and comma-separated, as errors list them.
    pub fn quoted_names(parameters: impl IntoIterator<Item = Parameter>) -> String {
        let names: Vec<String> =
            parameters.into_iter().map(|p| format!("\"{}\"", p.name())).collect();
        names.join(", ")
    }

    /// The scene name (the one place it is written: scenes, sweeps and errors read it here).
    pub fn name(self) -> &'static str {
        match self {
            Parameter::Epsilon => "epsilon",
            Parameter::Xi => "xi",
            Parameter::Gamma => "gamma",
            Parameter::Eta => "radiation_damping",
        }
    }

    /// The parameter's value in `p`.
    pub fn get(self, p: &DrrParams) -> f64 {
        match self {
            Parameter::Epsilon => p.epsilon,
            Parameter::Xi => p.xi,
            Parameter::Gamma => p.gamma,
            Parameter::Eta => p.eta,
        }
    }

    /// `p` with the parameter set to `value`.
    pub fn set(self, p: &DrrParams, value: f64) -> DrrParams {
        let mut q = *p;
        match self {
            Parameter::Epsilon => q.epsilon = value,
            Parameter::Xi => q.xi = value,
            Parameter::Gamma => q.gamma = value,
            Parameter::Eta => q.eta = value,
        }
        q
    }
}

/// How the continuation runs.
#[derive(Debug, Clone, PartialEq)]
pub struct ContinuationSettings {
    /// The parameter.
    pub parameter: Parameter,
    /// Its final value (the start is the scene's value).
    pub to: f64,
    /// Grid points, start and end included.
    pub points: usize,
    /// Whether the grid is uniform in log10 of the parameter.
    pub log: bool,
    /// Shooting settings at each point.
    pub shooting: ShootingSettings,
}

/// One orbit of the curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CurvePoint {
    /// The parameter's value.
    pub value: f64,
    /// The orbit found.
    #[serde(flatten)]
    pub orbit: PeriodicOrbit,
    /// Sub-steps taken from the previous grid point.
    pub substeps: usize,
}

/// Where and why the continuation stopped short of the last grid point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stop {
    /// The last parameter value with an orbit.
    pub last_value: f64,
    /// The value at which the corrector failed with the smallest sub-step.
    pub failed_at: f64,
    /// Why.
    pub reason: String,
}

/// A multiplier crossing −1 between two points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Flip {
    /// Parameter value before the crossing.
    pub from: f64,
    /// Parameter value after it.
    pub to: f64,
}

/// Least-squares line through (log10 γ, period).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DecadeSlope {
    /// First log10 γ of the fit.
    pub log10_gamma_from: f64,
    /// Last log10 γ of the fit.
    pub log10_gamma_to: f64,
    /// Period per decade of γ.
    pub slope: f64,
}

/// The "continuation" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContinuationReport {
    /// The parameter.
    pub parameter: Parameter,
    /// Start value (the scene's).
    pub from: f64,
    /// Requested end value.
    pub to: f64,
    /// Whether the curve reached `to`.
    pub completed: bool,
    /// The orbits at the grid points reached.
    pub points: Vec<CurvePoint>,
    /// Why it stopped short, if it did.
    pub stopped: Option<Stop>,
    /// Period doublings detected (a real multiplier crossing −1).
    pub flips: Vec<Flip>,
    /// For γ: period per decade fitted over the whole curve, and over each of its decades.
    pub period_per_decade: Vec<DecadeSlope>,
}

impl ContinuationReport {
    /// The report of a continuation that could not start: no orbit at the scene's parameters,
    /// for the reason shooting gave (`why`).
    pub fn not_started(
        settings: &ContinuationSettings,
        base: &DrrParams,
        why: Option<&NoOrbit>,
    ) -> Self {
        let from = settings.parameter.get(base);
        let why = why.map_or(String::new(), ToString::to_string);
        ContinuationReport {
            parameter: settings.parameter,
            from,
            to: settings.to,
            completed: false,
            points: Vec::new(),
            stopped: Some(Stop {
                last_value: from,
                failed_at: from,
                reason: format!("no periodic orbit at the start: {why}"),
            }),
            flips: Vec::new(),
            period_per_decade: Vec::new(),
        }
    }
}

/// Builds an integrator of the variational equations for the given parameters.
pub type Factory<'a> = dyn FnMut(Drr, [f64; 3]) -> Result<Box<dyn Integrator>, SolverError> + 'a;

fn grid(from: f64, to: f64, points: usize, log: bool) -> Vec<f64> {
    let n = points.max(2);
    (0..n)
        .map(|i| {
            let s = i as f64 / (n - 1) as f64;
            if log {
                10f64.powf(from.log10() + s * (to.log10() - from.log10()))
            } else {
                from + s * (to - from)
            }
        })
        .collect()
}

/// Why a corrector attempt was rejected (its text goes into the report's `stopped.reason`
/// when the sub-step can shrink no further).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum Rejected {
    /// Building the integrator or integrating failed.
    #[error(transparent)]
    Failed(#[from] AnalysisError),
    /// Newton found no orbit.
    #[error(transparent)]
    NoOrbit(#[from] NoOrbit),
    /// The corrected orbit is not the continuation of the last one: a period change above 10 %
    /// or an ln v range change above 10 % in one sub-step means the corrector jumped to
    /// another branch (or the branch turns: a fold, a canard explosion).
    #[error(
        "the orbit changes abruptly (period {:.6} → {:.6}, ln v range {:.4} → {:.4}): the branch ends or turns here (fold of cycles or canard explosion)",
        .period.0, .period.1, .range.0, .range.1
    )]
    Jump {
        /// The period before and after.
        period: (f64, f64),
        /// The ln v range before and after.
        range: (f64, f64),
    },
}

/// One corrector attempt at `value` from the predicted section point.
fn correct(
    factory: &mut Factory<'_>,
    base: &DrrParams,
    settings: &ContinuationSettings,
    value: f64,
    x: [f64; 2],
) -> Result<PeriodicOrbit, Rejected> {
    let drr = Drr::new(settings.parameter.set(base, value));
    let y0 = [x[0], 0.0, x[1]];
    let mut integ = factory(drr, y0).map_err(AnalysisError::from)?;
    Ok(shooting::newton(integ.as_mut(), &drr, x, 1, &settings.shooting)?.orbit?)
}

/// Runs the continuation from `start`, the orbit at the scene's parameters `base`.
pub fn run(
    factory: &mut Factory<'_>,
    base: &DrrParams,
    start: PeriodicOrbit,
    settings: &ContinuationSettings,
) -> ContinuationReport {
    let par = settings.parameter;
    let from = par.get(base);
    let to_coordinate = |v: f64| if settings.log { v.log10() } else { v };
    let from_coordinate = |c: f64| if settings.log { 10f64.powf(c) } else { c };
    let targets = grid(from, settings.to, settings.points, settings.log);
    let spacing =
        (to_coordinate(settings.to) - to_coordinate(from)).abs() / (targets.len() - 1) as f64;
    let mut points = vec![CurvePoint { value: from, orbit: start, substeps: 0 }];
    let mut flips = Vec::new();
    let mut stopped = None;
    // Current and previous orbit, as (coordinate, section point).
    let section = |o: &PeriodicOrbit| [o.section_point[0], o.section_point[2]];
    let mut previous: Option<(f64, [f64; 2])> = None;
    let mut current = (to_coordinate(from), section(&points[0].orbit));
    let mut step = spacing;
    // The last orbit accepted (grid point or sub-step).
    let mut last = points[0].orbit.clone();
    'grid: for &target in &targets[1..] {
        let goal = to_coordinate(target);
        let mut substeps = 0;
        loop {
            let remaining = goal - current.0;
            let h = remaining.signum() * step.min(remaining.abs());
            let next = if (remaining.abs() - h.abs()).abs() <= 1e-12 * spacing {
                goal
            } else {
                current.0 + h
            };
            let predicted = match previous {
                Some((c, x)) if (current.0 - c).abs() > 0.0 => {
                    let r = (next - current.0) / (current.0 - c);
                    [
                        current.1[0] + r * (current.1[0] - x[0]),
                        current.1[1] + r * (current.1[1] - x[1]),
                    ]
                }
                _ => current.1,
            };
            let value = if next == goal { target } else { from_coordinate(next) };
            let attempt = correct(factory, base, settings, value, predicted).and_then(|orbit| {
                match jump(&last, &orbit) {
                    Some(why) => Err(why),
                    None => Ok(orbit),
                }
            });
            match attempt {
                Ok(orbit) => {
                    substeps += 1;
                    let quick = orbit.newton_iterations <= 3;
                    if let (Some(a), Some(b)) =
                        (last.negative_real_multiplier(), orbit.negative_real_multiplier())
                    {
                        // Both near −1 (multipliers ~0 at large γ are noise, not a flip).
                        if (a + 1.0).signum() != (b + 1.0).signum() && a.abs().min(b.abs()) > 0.5 {
                            flips.push(Flip { from: from_coordinate(current.0), to: value });
                        }
                    }
                    previous = Some(current);
                    current = (next, section(&orbit));
                    last = orbit.clone();
                    if quick {
                        step = (2.0 * step).min(spacing);
                    }
                    if next == goal {
                        points.push(CurvePoint { value: target, orbit, substeps });
                        break;
                    }
                }
                Err(why) => {
                    step *= 0.5;
                    if step < spacing / 1024.0 {
                        let near_threshold = par != Parameter::Gamma;
                        let hint = if near_threshold {
                            let eps_c = hopf::analyse(&Drr::new(par.set(base, value))).epsilon_c;
                            format!(" (Hopf threshold there: ε_c = {eps_c:.9})")
                        } else {
                            String::new()
                        };
                        stopped = Some(Stop {
                            last_value: from_coordinate(current.0),
                            failed_at: value,
                            reason: format!("{why}{hint}"),
                        });
                        break 'grid;
                    }
                }
            }
        }
    }
    let period_per_decade =
        if par == Parameter::Gamma { decade_slopes(&points) } else { Vec::new() };
    ContinuationReport {
        parameter: par,
        from,
        to: settings.to,
        completed: stopped.is_none(),
        points,
        stopped,
        flips,
        period_per_decade,
    }
}

/// [`Rejected::Jump`] when `next` is not the continuation of `last`.
fn jump(last: &PeriodicOrbit, next: &PeriodicOrbit) -> Option<Rejected> {
    let range = |o: &PeriodicOrbit| o.ln_v_max - o.ln_v_min;
    let dt = (next.period - last.period).abs() / last.period;
    let dr = (range(next) - range(last)).abs() / range(last);
    (dt > 0.1 || dr > 0.1).then(|| Rejected::Jump {
        period: (last.period, next.period),
        range: (range(last), range(next)),
    })
}

/// Least-squares slope of period against log10 γ.
fn slope(points: &[&CurvePoint]) -> Option<DecadeSlope> {
    if points.len() < 2 {
        return None;
    }
    let xs: Vec<f64> = points.iter().map(|p| p.value.log10()).collect();
    let ys: Vec<f64> = points.iter().map(|p| p.orbit.period).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| DecadeSlope {
        log10_gamma_from: xs.iter().copied().fold(f64::INFINITY, f64::min),
        log10_gamma_to: xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        slope: sxy / sxx,
    })
}

/// The slope over the whole curve, then over each whole decade of γ it spans.
fn decade_slopes(points: &[CurvePoint]) -> Vec<DecadeSlope> {
    let all: Vec<&CurvePoint> = points.iter().collect();
    let mut out: Vec<DecadeSlope> = slope(&all).into_iter().collect();
    let lo = points.iter().map(|p| p.value.log10()).fold(f64::INFINITY, f64::min).ceil() as i64;
    let hi =
        points.iter().map(|p| p.value.log10()).fold(f64::NEG_INFINITY, f64::max).floor() as i64;
    for d in lo..hi {
        let within: Vec<&CurvePoint> = points
            .iter()
            .filter(|p| (d as f64 - 1e-9..=(d + 1) as f64 + 1e-9).contains(&p.value.log10()))
            .collect();
        out.extend(slope(&within));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_include_both_ends() {
        let g = grid(10.0, 1e8, 71, true);
        assert_eq!(g.len(), 71);
        assert!((g[0] - 10.0).abs() < 1e-12 && (g[70] - 1e8).abs() < 1e-4);
        assert!((g[10] - 100.0).abs() < 1e-9, "{}", g[10]);
        let l = grid(1.2, 0.7, 51, false);
        assert!((l[50] - 0.7).abs() < 1e-15 && (l[25] - 0.95).abs() < 1e-12);
    }
}
