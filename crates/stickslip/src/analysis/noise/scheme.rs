//! One realisation: the random ODE dx/dt = F(t, x) + B(x) η(t) driven by an exactly sampled
//! OU path, integrated node by node with stickslip's Rodas5P.
//!
//! **Scheme.** The noise η is sampled exactly at the nodes t_k = t_start + k·h (see
//! [`super::ou`]) and interpolated between them by the C¹ cubic Hermite (Catmull–Rom) spline:
//! values η_k, η_{k+1} and slopes (η_{k+1} − η_{k−1})/2h, (η_{k+2} − η_k)/2h. On each interval
//! [t_k, t_{k+1}] the forcing is then a cubic in t and the equation an ordinary smooth ODE; that
//! ODE is integrated by Rodas5P (Rosenbrock, order 5, L-stable, stiffly accurate: the
//! deterministic part is linearly implicit and stiff-stable) with its own error control,
//! stopping exactly at every node (no step straddles the jump of the forcing's second
//! derivative); inside an interval it takes as many steps as its tolerance needs (one on the
//! stick at the defaults, more in the slip). A merely continuous (linear) interpolant would put
//! a kink in the forcing at every node, and the stiff fast variable (the DRR's ln v, relaxing at
//! γ²/(ξv)) a thin layer after it that the error control then resolves: measured 25 % rejected
//! steps at the DRR defaults, none with the C¹ spline.
//!
//! **Order.** For a given noise path the deterministic error is Rodas5P's (order 5, controlled by
//! rtol/atol). The only noise discretisation error is the interpolation of η between nodes,
//! which replaces the rough OU bridge by a smooth curve. Its weak error (in means and
//! covariances), computed exactly for the linear test problem dx/dt = −λx + f (tests/noise.rs):
//! second order in h/τ for responses much slower than h (they see ∫η dt) and O(1/(λτ)) for
//! quasi-static ones much faster than h (they see η at the node, which is exact); first order in
//! the band λh ≈ 1–30, at most 0.46 % of the variance at the default h = τ/10 (0.93 % at τ/5,
//! 0.23 % at τ/20). h = τ/steps_per_correlation_time.
//!
//! The path is recorded at the nodes (state and dx/dt there) and read between them by cubic
//! Hermite interpolation; the event time t_c is located on that interpolant (the maximum of a
//! component, or a downward crossing of a level).

use super::models::{EventKind, NoiseModel, MAX_DIM};
use super::ou::{self, OuStep};
use super::rng::Rng;
use crate::analysis::AnalysisError;
use crate::integrate::{
    Integrator, JacobianMatrix, OdeSystem, Options, SolverError, Stats, Task, Tolerance,
};
use crate::solver::{self, Method};
use std::cell::Cell;

/// The OU values around the current interval [t_k, t_{k+1}]: η_{k−1}, η_k, η_{k+1}, η_{k+2}.
#[derive(Debug, Clone, Copy, Default)]
struct Segment {
    t0: f64,
    t1: f64,
    eta: [[f64; MAX_DIM]; 4],
}

/// The model with the noise of the current interval, a cubic in t. The interval lives in a
/// cell the caller keeps (and moves from node to node), so that the integrator can own the
/// system behind the crate's solver selection ([`solver::build_default`]).
struct Forced<'a> {
    model: &'a NoiseModel,
    segment: &'a Cell<Segment>,
}

impl Forced<'_> {
    /// dη/dt at t: the derivative of [`Forced::eta`]'s cubic.
    fn eta_rate(&self, t: f64) -> [f64; MAX_DIM] {
        let seg = self.segment.get();
        let span = seg.t1 - seg.t0;
        let s = (t - seg.t0) / span;
        let s2 = s * s;
        let (d00, d10, d01, d11) =
            (6.0 * s2 - 6.0 * s, 3.0 * s2 - 4.0 * s + 1.0, 6.0 * s - 6.0 * s2, 3.0 * s2 - 2.0 * s);
        let [em, e0, e1, e2] = seg.eta;
        std::array::from_fn(|i| {
            (d00 * e0[i] + d01 * e1[i] + 0.5 * (d10 * (e1[i] - em[i]) + d11 * (e2[i] - e0[i])))
                / span
        })
    }

    fn eta(&self, t: f64) -> [f64; MAX_DIM] {
        let seg = self.segment.get();
        // s = 1 exactly at t = t1 (and 0 at t0), where the Hermite weights are exactly
        // (0, 0, 1, 0) (and (1, 0, 0, 0)): the forcing is continuous bit for bit across a node.
        let s = (t - seg.t0) / (seg.t1 - seg.t0);
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) =
            (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, 3.0 * s2 - 2.0 * s3, s3 - s2);
        let [em, e0, e1, e2] = seg.eta;
        std::array::from_fn(|i| {
            h00 * e0[i] + h01 * e1[i] + 0.5 * (h10 * (e1[i] - em[i]) + h11 * (e2[i] - e0[i]))
        })
    }
}

impl OdeSystem for Forced<'_> {
    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.model.forced_rhs(t, y, &self.eta(t), dydt);
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.model.forced_jacobian(t, y, &self.eta(t), jac);
    }

    /// ∂f/∂t = B(x) dη/dt exactly (the drift F does not depend on t for the periodic
    /// models; the saddle-node's does, so it keeps Rodas5P's forward difference).
    fn has_time_derivative(&self) -> bool {
        self.model.drift_is_autonomous()
    }

    fn time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        self.model.add_forcing(y, &self.eta_rate(t), out);
    }

    /// The model's answer: the additive forcing B(x)η conserves no combination of the state
    /// that the drift does not already break (for the DRR, none, and Rodas5P's stage solves
    /// need no refinement; they cost an ensemble 30 % of its instructions, issue #30).
    fn has_linear_invariants(&self) -> bool {
        self.model.has_linear_invariants()
    }

    /// Yes: a realisation's statistics do not depend on the last bits of its stage solves
    /// (the ensemble's sampling error is some 1e6 times larger), and the explicit inverse
    /// shortens every step's chain of dependent operations (issue #30).
    fn allows_explicit_inverse(&self) -> bool {
        true
    }
}

/// Settings of the scheme.
#[derive(Debug, Clone, PartialEq)]
pub struct SchemeSettings {
    /// Node spacing h.
    pub h: f64,
    /// OU correlation time τ.
    pub tau: f64,
    /// Rodas5P's relative tolerance.
    pub rtol: f64,
    /// Rodas5P's absolute tolerances, one per component.
    pub atol: Vec<f64>,
}

impl SchemeSettings {
    fn options(&self) -> Options {
        Options {
            max_steps: Some(100_000),
            max_err_test_fails: Some(20),
            ..Options::new(self.rtol, Tolerance::PerComponent(self.atol.clone()))
        }
    }
}

/// A realisation recorded at the nodes.
#[derive(Debug, Clone, Default)]
pub struct Path {
    n: usize,
    t0: f64,
    h: f64,
    /// States at the nodes, node-major.
    x: Vec<f64>,
    /// dx/dt at the nodes (noise included), node-major.
    f: Vec<f64>,
    /// The event time t_c.
    pub t_event: f64,
    /// Rodas5P's statistics for this realisation.
    pub stats: Stats,
}

impl Path {
    /// Number of recorded nodes.
    pub fn nodes(&self) -> usize {
        self.x.len() / self.n.max(1)
    }

    /// Time of node k.
    pub fn node_time(&self, k: usize) -> f64 {
        self.t0 + k as f64 * self.h
    }

    /// First and last recorded times.
    pub fn span(&self) -> (f64, f64) {
        (self.t0, self.node_time(self.nodes().saturating_sub(1)))
    }

    fn push(&mut self, x: &[f64], f: &[f64]) {
        self.x.extend_from_slice(x);
        self.f.extend_from_slice(f);
    }

    /// Component i at node k.
    fn at(&self, k: usize, i: usize) -> f64 {
        self.x[k * self.n + i]
    }

    /// Cubic Hermite interpolant of component i on [t_k, t_{k+1}] at local s ∈ [0, 1]: value
    /// and d/dt.
    fn hermite(&self, k: usize, i: usize, s: f64) -> (f64, f64) {
        let n = self.n;
        let (ya, yb) = (self.x[k * n + i], self.x[(k + 1) * n + i]);
        let (da, db) = (self.f[k * n + i] * self.h, self.f[(k + 1) * n + i] * self.h);
        let (s2, s3) = (s * s, s * s * s);
        let value = (2.0 * s3 - 3.0 * s2 + 1.0) * ya
            + (s3 - 2.0 * s2 + s) * da
            + (3.0 * s2 - 2.0 * s3) * yb
            + (s3 - s2) * db;
        let slope = (6.0 * s2 - 6.0 * s) * ya
            + (3.0 * s2 - 4.0 * s + 1.0) * da
            + (6.0 * s - 6.0 * s2) * yb
            + (3.0 * s2 - 2.0 * s) * db;
        (value, slope / self.h)
    }

    /// Component i at time t (cubic Hermite between nodes); None outside the recorded span.
    pub fn value(&self, t: f64, i: usize) -> Option<f64> {
        let (a, b) = self.span();
        if !(t >= a && t <= b) || self.nodes() < 2 {
            return None;
        }
        let k = (((t - self.t0) / self.h).floor() as usize).min(self.nodes() - 2);
        let s = ((t - self.node_time(k)) / self.h).clamp(0.0, 1.0);
        Some(self.hermite(k, i, s).0)
    }

    /// The maximum of component i near node b: the largest value of the Hermite pieces on
    /// [t_{b−1}, t_{b+1}] (candidates: nodes and the pieces' critical points).
    fn locate_maximum(&self, b: usize, i: usize) -> f64 {
        let mut best = (self.at(b, i), self.node_time(b));
        let pieces = [b.checked_sub(1), (b + 1 < self.nodes()).then_some(b)];
        for k in pieces.into_iter().flatten() {
            // d/ds of the cubic: A s² + B s + C.
            let n = self.n;
            let (ya, yb) = (self.x[k * n + i], self.x[(k + 1) * n + i]);
            let (da, db) = (self.f[k * n + i] * self.h, self.f[(k + 1) * n + i] * self.h);
            let (qa, qb, qc) = (
                6.0 * ya + 3.0 * da - 6.0 * yb + 3.0 * db,
                -6.0 * ya - 4.0 * da + 6.0 * yb - 2.0 * db,
                da,
            );
            let mut roots = Vec::with_capacity(2);
            if qa.abs() > 1e-300 {
                let disc = qb * qb - 4.0 * qa * qc;
                if disc >= 0.0 {
                    let q = -0.5 * (qb + qb.signum() * disc.sqrt());
                    roots.push(q / qa);
                    if q != 0.0 {
                        roots.push(qc / q);
                    }
                }
            } else if qb != 0.0 {
                roots.push(-qc / qb);
            }
            for s in roots.into_iter().filter(|s| (0.0..=1.0).contains(s)) {
                let v = self.hermite(k, i, s).0;
                if v > best.0 {
                    best = (v, self.node_time(k) + s * self.h);
                }
            }
        }
        best.1
    }

    /// The crossing of `level` by component i inside [t_k, t_{k+1}] (bisection on the Hermite
    /// interpolant): downward with `sign` = 1 (value ≥ level at s = 0, < level at s = 1),
    /// upward with `sign` = −1.
    fn locate_crossing(&self, k: usize, i: usize, level: f64, sign: f64) -> f64 {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if sign * (self.hermite(k, i, mid).0 - level) >= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.node_time(k) + 0.5 * (lo + hi) * self.h
    }
}

/// Whether a crossing search starting at x is armed at once (the component is beyond its
/// arming level); a maximum search arms later.
fn initially_armed(event: EventKind, x: &[f64]) -> bool {
    match event {
        EventKind::Maximum { .. } => false,
        EventKind::CrossDown { component, arm, .. } => x[component] > arm,
        EventKind::CrossUp { component, arm, .. } => x[component] < arm,
    }
}

/// Where a realisation starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Start {
    /// Start time (model time).
    pub t: f64,
    /// Start state.
    pub x: Vec<f64>,
}

fn no_event(t: f64, x: &[f64], what: String) -> AnalysisError {
    AnalysisError::Failed { analysis: "noise", t, state: x.to_vec(), message: what }
}

/// Runs one realisation from `start` until its event has been located and `record_until` is
/// reached (recorded into `path`); an error if no event happens before `t_max`. Without an
/// event it runs to `record_until` (and `path.t_event` is that time).
#[allow(clippy::too_many_arguments)]
pub fn realisation(
    model: &NoiseModel,
    start: &Start,
    settings: &SchemeSettings,
    event: Option<EventKind>,
    record_until: f64,
    t_max: f64,
    rng: &mut Rng,
    path: &mut Path,
) -> Result<(), AnalysisError> {
    let n = model.dim();
    let segment = Cell::new(Segment::default());
    let forced = Forced { model, segment: &segment };
    let mut integ =
        solver::build_default(Method::Rodas5p, forced, start.t, &start.x, &settings.options())?;
    let ou_step = OuStep::new(settings.h, settings.tau);
    // The path η_{−1}, η_0, η_1, η_2 (η_{−1} stationary), then one node further per interval.
    let mut eta = [[0.0; MAX_DIM]; 4];
    ou::stationary(&mut eta[0][..n], rng);
    for j in 1..4 {
        eta[j] = eta[j - 1];
        ou_step.advance(&mut eta[j][..n], rng);
    }
    *path = Path {
        n,
        t0: start.t,
        h: settings.h,
        x: std::mem::take(&mut path.x),
        f: std::mem::take(&mut path.f),
        ..Path::default()
    };
    path.x.clear();
    path.f.clear();
    let mut f = [0.0; MAX_DIM];
    let derivative = |t: f64, x: &[f64], eta: &[f64], f: &mut [f64]| model.forced_rhs(t, x, eta, f);
    derivative(start.t, &start.x, &eta[1], &mut f[..n]);
    path.push(&start.x, &f[..n]);
    // Event search state: armed, and the running maximum (index, value) once armed.
    let mut armed = event.is_some_and(|e| initially_armed(e, &start.x));
    let mut below_arm = match event {
        Some(EventKind::Maximum { component, arm, .. }) => start.x[component] <= arm,
        _ => false,
    };
    let mut best: Option<(usize, f64)> = None;
    let mut found = false;
    let mut k = 0usize;
    loop {
        let (t0, t1) = (start.t + k as f64 * settings.h, start.t + (k + 1) as f64 * settings.h);
        if t1 > t_max {
            let x = integ.state().to_vec();
            return Err(no_event(t0, &x, format!("no event before t = {t_max:e} (the noise is too strong, or the start is not before an event)")));
        }
        segment.set(Segment { t0, t1, eta });
        integ.set_stop_time(t1)?;
        integ.advance(t1, Task::Normal)?;
        let x = integ.state();
        derivative(t1, x, &eta[2], &mut f[..n]);
        path.push(x, &f[..n]);
        k += 1;
        match event {
            None => {
                if start.t + k as f64 * settings.h >= record_until {
                    path.t_event = record_until;
                    break;
                }
            }
            Some(EventKind::Maximum { component, arm, drop }) => {
                let v = x[component];
                below_arm |= v <= arm;
                match best {
                    None if below_arm && v > arm => best = Some((k, v)),
                    Some((_, b)) if v > b => best = Some((k, v)),
                    Some((b, bv))
                        if v < bv - drop && k as f64 * settings.h + start.t >= record_until =>
                    {
                        path.t_event = path.locate_maximum(b, component);
                        break;
                    }
                    _ => {}
                }
            }
            Some(EventKind::CrossDown { component, level, arm }) => {
                let before = path.at(k - 1, component);
                if armed && before >= level && x[component] < level {
                    path.t_event = path.locate_crossing(k - 1, component, level, 1.0);
                    found = true;
                }
                armed |= x[component] > arm || before > arm;
            }
            Some(EventKind::CrossUp { component, level, arm }) => {
                let before = path.at(k - 1, component);
                if armed && before <= level && x[component] > level {
                    path.t_event = path.locate_crossing(k - 1, component, level, -1.0);
                    found = true;
                }
                armed |= x[component] < arm || before < arm;
            }
        }
        if found && start.t + k as f64 * settings.h >= record_until {
            break;
        }
        eta.copy_within(1..4, 0);
        ou_step.advance(&mut eta[3][..n], rng);
    }
    path.stats = integ.stats();
    Ok(())
}

/// The noise-free integration of a noise model, Rodas5P at fixed tolerances: the burn-in, the
/// start, the orbit the realisations are compared with and the one the linear response follows.
#[derive(Debug, Clone, Copy)]
pub struct DeterministicRun<'a> {
    /// The model.
    pub model: &'a NoiseModel,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per component.
    pub atol: &'a [f64],
}

impl DeterministicRun<'_> {
    /// The integrator from (t0, x0), stopping exactly at `stop_time` if one is given.
    pub(super) fn integrator(
        &self,
        t0: f64,
        x0: &[f64],
        stop_time: Option<f64>,
    ) -> Result<Box<dyn Integrator>, SolverError> {
        let options = Options {
            max_steps: Some(10_000_000),
            max_err_test_fails: Some(20),
            stop_time,
            ..Options::new(self.rtol, Tolerance::PerComponent(self.atol.to_vec()))
        };
        solver::build_default(Method::Rodas5p, *self.model, t0, x0, &options)
    }

    /// The event after (t0, x0): its time and the state there, and the solver statistics.
    /// For a maximum, the first local maximum of the component after it exceeds the arming
    /// level; for a crossing, the first downward one.
    pub fn event(
        &self,
        t0: f64,
        x0: &[f64],
        event: EventKind,
        t_max: f64,
    ) -> Result<(f64, Vec<f64>, Stats), AnalysisError> {
        let mut integ = self.integrator(t0, x0, None)?;
        let mut prev_x = x0.to_vec();
        // The sign of d x_c/dt is read on the integrator's interpolant (never on the right-hand
        // side, which on the DRR's slow manifold is solver noise times γ²).
        let mut prev_end_slope = f64::NAN;
        let mut armed = initially_armed(event, x0);
        let mut below_arm = match event {
            EventKind::Maximum { component, arm, .. } => x0[component] <= arm,
            _ => false,
        };
        loop {
            let t_prev = integ.t();
            let step = integ.advance(t_max, Task::OneStep)?;
            let t = step.t;
            let x = integ.state().to_vec();
            let found = match event {
                EventKind::Maximum { component: c, arm, .. } => {
                    below_arm |= x[c] <= arm;
                    armed |= below_arm && x[c] > arm;
                    let start_slope = integ.dense(t_prev, 1)?[c];
                    let end_slope = integ.dense(t, 1)?[c];
                    let found = if armed && prev_end_slope > 0.0 && start_slope <= 0.0 {
                        Some(t_prev)
                    } else if armed && start_slope > 0.0 && end_slope <= 0.0 {
                        Some(bisect(t_prev, t, |s| {
                            integ.dense(s, 1).map(|d| d[c] > 0.0).unwrap_or(false)
                        }))
                    } else {
                        None
                    };
                    prev_end_slope = end_slope;
                    found
                }
                EventKind::CrossDown { component: c, level, arm } => {
                    let found = (armed && prev_x[c] >= level && x[c] < level).then(|| {
                        bisect(t_prev, t, |s| {
                            integ.dense(s, 0).map(|d| d[c] >= level).unwrap_or(false)
                        })
                    });
                    armed |= prev_x[c] > arm || x[c] > arm;
                    found
                }
                EventKind::CrossUp { component: c, level, arm } => {
                    let found = (armed && prev_x[c] <= level && x[c] > level).then(|| {
                        bisect(t_prev, t, |s| {
                            integ.dense(s, 0).map(|d| d[c] <= level).unwrap_or(false)
                        })
                    });
                    armed |= prev_x[c] < arm || x[c] < arm;
                    found
                }
            };
            if let Some(tc) = found {
                let xc = integ.dense(tc, 0)?.to_vec();
                return Ok((tc, xc, integ.stats()));
            }
            if t >= t_max {
                return Err(no_event(
                    t,
                    &x,
                    format!("the deterministic orbit has no event before t = {t_max:e}"),
                ));
            }
            prev_x = x;
        }
    }

    /// The states at the ascending `times` (all ≥ t0) from (t0, x0).
    pub fn states(&self, t0: f64, x0: &[f64], times: &[f64]) -> Result<Vec<Vec<f64>>, SolverError> {
        let mut integ = self.integrator(t0, x0, None)?;
        let mut out = Vec::with_capacity(times.len());
        for &t in times {
            if t > integ.t() {
                integ.advance(t, Task::Normal)?;
            }
            out.push(integ.state().to_vec());
        }
        Ok(out)
    }

    /// The state at time t1 from (t0, x0).
    pub fn state(&self, t0: f64, x0: &[f64], t1: f64) -> Result<Vec<f64>, SolverError> {
        let mut integ = self.integrator(t0, x0, None)?;
        if t1 > t0 {
            integ.advance(t1, Task::Normal)?;
        }
        Ok(integ.state().to_vec())
    }
}

/// The point in [a, b] where `before` turns false (true at a, false at b), by bisection to the
/// spacing of doubles.
fn bisect(mut a: f64, mut b: f64, mut before: impl FnMut(f64) -> bool) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        if before(mid) {
            a = mid;
        } else {
            b = mid;
        }
    }
    0.5 * (a + b)
}
