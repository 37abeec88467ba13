//! The small-noise limit: linear response along the deterministic orbit.
//!
//! With the OU noises in the state, z = (x, η) obeys dz = a(z) dt + (0, √(2/τ) dW) with
//! a = (F(t, x) + B(x)η, −η/τ). Linearised about the deterministic orbit (x̄(t), η = 0), the
//! deviations δz are Gaussian with covariance C(t) solving the Lyapunov (covariance) equation
//!
//!   dC/dt = A C + C Aᵀ + Q,   A = [[J(x̄), B(x̄)], [0, −I/τ]],   Q = [[0, 0], [0, (2/τ) I]],
//!
//! from C(t_start) = [[0, 0], [0, I]] (deterministic start, stationary noise), and two-time
//! covariances C(t, s) = Φ(t, s) C(s) for t ≥ s, Φ the propagator of dδz/dt = A δz. A two-time
//! covariance of observables o_j = g_jᵀδz(t_j), o_k = g_kᵀδz(t_k) (k ≤ j) is μ_kᵀ C_k g_k with
//! μ_k = Φ(t_j, t_k)ᵀ g_j: the adjoint equation dμ/dt = −Aᵀ μ integrated backwards from
//! μ(t_j) = g_j. One backward integration gives a whole row Γ(t_j, t_j − t').
//!
//! The orbit is computed once (Rodas5P, rtol 1e-10) and read between its steps by cubic Hermite
//! interpolation; C (forwards) and each adjoint (backwards) are integrated along it by Radau5
//! (stiff: the fast variable relaxes at up to 1e7 per unit time in the DRR).
//!
//! **Alignment on each realisation's own event.** The event shifts by δt_c = pᵀ δz(t_c) with
//! p = −∇g/ġ for the event function g (g = dx_c/dt at a maximum, g = x_c − level at a
//! crossing). A realisation aligned on its own event deviates from the orbit at t_c + s by
//! δz(t) + ż(t) δt_c, so its covariances are
//!
//!   Cov(o_j, o_k) + (g_jᵀż_j) (g_kᵀC_k λ_k) + (g_jᵀC_j λ_j) (g_kᵀż_k) + (g_jᵀż_j)(g_kᵀż_k) pᵀC_K p,
//!
//! with λ_k = Φ(t_c, t_k)ᵀ p, the adjoint from the event (the observable's gradient is g = ∇o,
//! e.g. (0, v, 0) for v = e^w).

use super::models::{EventKind, NoiseModel};
use super::scheme::DeterministicRun;
use crate::analysis::AnalysisError;
use crate::integrate::{JacobianMatrix, OdeSystem, Options, SolverError, Task, Tolerance};
use crate::solver::{self, Method};

/// Largest augmented dimension (2 × the DRR's 3).
const MAX_BIG: usize = 6;

/// The deterministic orbit x̄(t) stored at the steps of one Rodas5P run (state and slope at
/// each step) and read between them by cubic Hermite interpolation: the path the covariance
/// and the adjoints are integrated along.
#[derive(Debug, Clone)]
pub struct HermiteOrbit {
    n: usize,
    t: Vec<f64>,
    x: Vec<f64>,
    f: Vec<f64>,
}

impl HermiteOrbit {
    /// The orbit of `det` from (t0, x0) to t1; derivatives from the integrator's interpolant
    /// (never from the right-hand side, which is noisy on a stiff slow manifold).
    pub fn compute(
        det: &DeterministicRun,
        t0: f64,
        x0: &[f64],
        t1: f64,
    ) -> Result<Self, SolverError> {
        let n = det.model.dim();
        let mut integ = det.integrator(t0, x0, Some(t1))?;
        let mut f0 = vec![0.0; n];
        det.model.rhs(t0, x0, &mut f0);
        let mut orbit = Self { n, t: vec![t0], x: x0.to_vec(), f: f0 };
        while integ.t() < t1 {
            let step = integ.advance(t1, Task::OneStep)?;
            let slope = integ.dense(step.t, 1)?.to_vec();
            orbit.t.push(step.t);
            orbit.x.extend_from_slice(integ.state());
            orbit.f.extend_from_slice(&slope);
        }
        Ok(orbit)
    }

    /// x̄(t) into `out` (t clamped to the orbit's span).
    pub fn at(&self, t: f64, out: &mut [f64]) {
        let n = self.n;
        let last = self.t.len() - 1;
        let k = match self.t.binary_search_by(|v| v.total_cmp(&t)) {
            Ok(i) => i.min(last.saturating_sub(1)),
            Err(i) => i.saturating_sub(1).min(last.saturating_sub(1)),
        };
        if last == 0 {
            out.copy_from_slice(&self.x[..n]);
            return;
        }
        let h = self.t[k + 1] - self.t[k];
        let s = ((t - self.t[k]) / h).clamp(0.0, 1.0);
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) =
            (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, 3.0 * s2 - 2.0 * s3, s3 - s2);
        for (i, o) in out.iter_mut().enumerate() {
            let (ya, yb) = (self.x[k * n + i], self.x[(k + 1) * n + i]);
            let (da, db) = (self.f[k * n + i] * h, self.f[(k + 1) * n + i] * h);
            *o = h00 * ya + h10 * da + h01 * yb + h11 * db;
        }
    }

    /// Steps of the orbit computation.
    pub fn steps(&self) -> usize {
        self.t.len() - 1
    }
}

/// A (N×N, row-major) at time t on the orbit.
fn matrix(model: &NoiseModel, orbit: &HermiteOrbit, tau: f64, t: f64, a: &mut [f64]) {
    let n = orbit.n;
    let nn = 2 * n;
    let mut x = [0.0; MAX_BIG / 2];
    orbit.at(t, &mut x[..n]);
    let mut jstore = [0.0; MAX_BIG * MAX_BIG / 4];
    let mut jac = JacobianMatrix::new(&mut jstore[..n * n], n);
    model.jacobian(t, &x[..n], &mut jac);
    let mut b = [0.0; MAX_BIG / 2];
    model.noise_diag(&x[..n], &mut b[..n]);
    a.iter_mut().for_each(|v| *v = 0.0);
    for i in 0..n {
        for j in 0..n {
            a[i * nn + j] = jac.get(i, j);
        }
        a[i * nn + n + i] = b[i];
        a[(n + i) * nn + n + i] = -1.0 / tau;
    }
}

/// The covariance equation dC/dt = AC + CAᵀ + Q along the orbit (C row-major, N×N).
#[derive(Clone, Copy)]
struct Lyapunov<'a> {
    model: &'a NoiseModel,
    orbit: &'a HermiteOrbit,
    tau: f64,
}

impl OdeSystem for Lyapunov<'_> {
    fn dim(&self) -> usize {
        4 * self.orbit.n * self.orbit.n
    }

    fn rhs(&self, t: f64, c: &[f64], dc: &mut [f64]) {
        let n = self.orbit.n;
        let nn = 2 * n;
        let mut astore = [0.0; MAX_BIG * MAX_BIG];
        let a = &mut astore[..nn * nn];
        matrix(self.model, self.orbit, self.tau, t, a);
        for i in 0..nn {
            for j in 0..nn {
                dc[i * nn + j] = (0..nn).map(|k| a[i * nn + k] * c[k * nn + j]).sum();
            }
        }
        // AC + (AC)ᵀ = AC + CAᵀ for symmetric C.
        for i in 0..nn {
            for j in 0..=i {
                let s = dc[i * nn + j] + dc[j * nn + i];
                dc[i * nn + j] = s;
                dc[j * nn + i] = s;
            }
        }
        for i in n..nn {
            dc[i * nn + i] += 2.0 / self.tau;
        }
    }
}

/// The adjoint equation dμ/dt = −Aᵀ μ along the orbit.
#[derive(Clone, Copy)]
struct Adjoint<'a> {
    model: &'a NoiseModel,
    orbit: &'a HermiteOrbit,
    tau: f64,
}

impl OdeSystem for Adjoint<'_> {
    fn dim(&self) -> usize {
        2 * self.orbit.n
    }

    fn rhs(&self, t: f64, mu: &[f64], dmu: &mut [f64]) {
        let nn = 2 * self.orbit.n;
        let mut astore = [0.0; MAX_BIG * MAX_BIG];
        let a = &mut astore[..nn * nn];
        matrix(self.model, self.orbit, self.tau, t, a);
        for j in 0..nn {
            dmu[j] = -(0..nn).map(|i| a[i * nn + j] * mu[i]).sum::<f64>();
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, _mu: &[f64], jac: &mut JacobianMatrix<'_>) {
        let nn = 2 * self.orbit.n;
        let mut astore = [0.0; MAX_BIG * MAX_BIG];
        let a = &mut astore[..nn * nn];
        matrix(self.model, self.orbit, self.tau, t, a);
        for j in 0..nn {
            for i in 0..nn {
                jac.set(j, i, -a[i * nn + j]);
            }
        }
    }
}

/// The event function g's fluctuation at lags s before the deterministic event
/// ([`LinearResponse::event_function_at_lags`]).
#[derive(Debug, Clone, PartialEq)]
pub struct EventFunctionLags {
    /// ρ_g(s): the correlation coefficient of δg(t_c) and δg(t_c − s).
    pub correlation: Vec<f64>,
    /// σ(δg̃(t_c − s))/(|ġ| σ_tc), δg̃(t) = δg(t) + ġ(t) δt_c the event function's deviation
    /// in each realisation's own frame (read at t + δt_c; zero at t_c by construction): how far
    /// g departs, one lag before the event, from the orbit's own g shifted by the linear δt_c,
    /// relative to the change ġσ_tc that defines the event. A coherent time shift of the orbit
    /// leaves it at zero; a fluctuation of δg faster than the lag makes it ~√2.
    pub own_frame: Vec<f64>,
}

/// The linear response on a grid of times t_0 < … < t_K = t_c (deterministic event).
#[derive(Debug, Clone)]
pub struct LinearResponse {
    /// Augmented dimension N = 2n.
    pub big: usize,
    /// Orbit x̄(t_k).
    pub orbit: Vec<Vec<f64>>,
    /// dz̄/dt at t_k ((F, 0)).
    pub velocity: Vec<Vec<f64>>,
    /// C(t_k), N×N row-major.
    pub covariance: Vec<Vec<f64>>,
    /// λ_k = Φ(t_c, t_k)ᵀ p.
    pub adjoint: Vec<Vec<f64>>,
    /// p: δt_c = pᵀ δz(t_c).
    pub event_gradient: Vec<f64>,
    /// Standard deviation of the event time, √(pᵀ C_K p).
    pub event_time_std: f64,
    /// Steps of the orbit (Rodas5P), the covariance and the adjoints (Radau5).
    pub steps: u64,
    model: NoiseModel,
    path: HermiteOrbit,
    times: Vec<f64>,
    tau: f64,
    rtol: f64,
    event: EventKind,
    /// ġ, the event function's slope at t_c on the orbit.
    event_slope: f64,
    /// The covariance's absolute tolerances (second pass).
    covariance_atol: Vec<f64>,
}

fn failure(t: f64, message: String) -> AnalysisError {
    AnalysisError::Failed { analysis: "the linear response", t, state: vec![], message }
}

/// ∇g at (t, x̄) over the augmented state (x, η) for the event function g: g = dx_c/dt =
/// F_c(t, x) + b_c(x) η_c at a maximum (∇g = (J_c·, b_c e_c); ∂b_c/∂x·η vanishes at η = 0),
/// g = x_c − level at a crossing (∇g = e_c).
fn event_function_gradient(model: &NoiseModel, event: EventKind, t: f64, x: &[f64]) -> Vec<f64> {
    let n = model.dim();
    let mut grad = vec![0.0; 2 * n];
    match event {
        EventKind::Maximum { component: c, .. } => {
            let mut jstore = vec![0.0; n * n];
            let mut jac = JacobianMatrix::new(&mut jstore, n);
            model.jacobian(t, x, &mut jac);
            let mut b = vec![0.0; n];
            model.noise_diag(x, &mut b);
            for (j, gj) in grad.iter_mut().take(n).enumerate() {
                *gj = jac.get(c, j);
            }
            grad[n + c] = b[c];
        }
        EventKind::CrossDown { component: c, .. } | EventKind::CrossUp { component: c, .. } => {
            grad[c] = 1.0
        }
    }
    grad
}

/// C at the ascending `times` (all ≥ t0) from C(t0) = c0, Radau5 at (rtol, atol); also the steps.
fn integrate_covariance(
    sys: Lyapunov<'_>,
    t0: f64,
    c0: &[f64],
    times: &[f64],
    rtol: f64,
    atol: &[f64],
) -> Result<(Vec<Vec<f64>>, u64), SolverError> {
    let options = Options {
        max_steps: Some(1_000_000),
        ..Options::new(rtol, Tolerance::PerComponent(atol.to_vec()))
    };
    let mut integ = solver::build_default(Method::Radau5, sys, t0, c0, &options)?;
    let mut out = Vec::with_capacity(times.len());
    for &t in times {
        if t > integ.t() {
            integ.set_stop_time(t)?;
            integ.advance(t, Task::Normal)?;
        }
        out.push(integ.state().to_vec());
    }
    Ok((out, integ.stats().steps))
}

/// The bilinear form aᵀ C b (C row-major, N×N).
fn form(a: &[f64], c: &[f64], b: &[f64]) -> f64 {
    let nn = a.len();
    (0..nn).map(|i| a[i] * (0..nn).map(|j| c[i * nn + j] * b[j]).sum::<f64>()).sum()
}

/// μ_k = Φ(t_j, t_k)ᵀ μ_j for k = j, j−1, …, 0 (backwards along the orbit).
fn adjoint_sweep(
    model: &NoiseModel,
    orbit: &HermiteOrbit,
    tau: f64,
    times: &[f64],
    j: usize,
    mu_j: &[f64],
    rtol: f64,
) -> Result<(Vec<Vec<f64>>, u64), SolverError> {
    let scale = mu_j.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let options = Options {
        max_steps: Some(1_000_000),
        ..Options::new(rtol, Tolerance::PerComponent(vec![1e-12 * scale; mu_j.len()]))
    };
    let sys = Adjoint { model, orbit, tau };
    let mut integ = solver::build_default(Method::Radau5, sys, times[j], mu_j, &options)?;
    let mut out = vec![Vec::new(); j + 1];
    out[j] = mu_j.to_vec();
    for k in (0..j).rev() {
        integ.set_stop_time(times[k])?;
        integ.advance(times[k], Task::Normal)?;
        out[k] = integ.state().to_vec();
    }
    Ok((out, integ.stats().steps))
}

/// Computes orbit, covariances at `times` (ascending, after t_start, the last one the
/// deterministic event of kind `event`) and the event's adjoint, for OU noises of correlation
/// time `tau`: Radau5 at `rtol`, the orbit by Rodas5P at 1e-10 with absolute tolerances
/// `atol_x`.
#[allow(clippy::too_many_arguments)]
pub fn compute(
    model: &NoiseModel,
    t_start: f64,
    x_start: &[f64],
    times: &[f64],
    event: EventKind,
    tau: f64,
    rtol: f64,
    atol_x: &[f64],
) -> Result<LinearResponse, AnalysisError> {
    let n = model.dim();
    let nn = 2 * n;
    if model.amplitudes().iter().all(|a| *a == 0.0) {
        return Err(failure(
            t_start,
            "every noise amplitude is zero: nothing to respond to".into(),
        ));
    }
    let tc = *times.last().ok_or_else(|| failure(t_start, "an empty grid".into()))?;
    let det = DeterministicRun { model, rtol: 1e-10, atol: atol_x };
    let path = HermiteOrbit::compute(&det, t_start, x_start, tc)?;
    let mut steps = path.steps() as u64;
    let orbit: Vec<Vec<f64>> = times
        .iter()
        .map(|&t| {
            let mut x = vec![0.0; n];
            path.at(t, &mut x);
            x
        })
        .collect();
    // The covariance: a first pass measures each variance's scale, the second one integrates
    // with absolute tolerances 1e-9 of the scales.
    let sys = Lyapunov { model, orbit: &path, tau };
    let mut c0 = vec![0.0; nn * nn];
    (n..nn).for_each(|i| c0[i * nn + i] = 1.0);
    let mut scales = vec![1.0; nn];
    let mut covariance = Vec::new();
    let mut covariance_atol = Vec::new();
    for pass in 0..2 {
        let factor = if pass == 0 { 1e-12 } else { 1e-9 };
        covariance_atol =
            (0..nn * nn).map(|ij| factor * scales[ij / nn] * scales[ij % nn]).collect();
        let pass_rtol = if pass == 0 { rtol.max(1e-4) } else { rtol };
        let (c, pass_steps) =
            integrate_covariance(sys, t_start, &c0, times, pass_rtol, &covariance_atol)?;
        covariance = c;
        steps += pass_steps;
        scales = (0..nn)
            .map(|i| {
                covariance.iter().fold(0.0f64, |m, c| m.max(c[i * nn + i].abs())).sqrt().max(1e-300)
            })
            .collect();
    }
    if covariance.iter().any(|m| m.iter().any(|v| !v.is_finite())) {
        return Err(failure(tc, "the covariance is not finite".into()));
    }
    let velocity: Vec<Vec<f64>> = times
        .iter()
        .zip(&orbit)
        .map(|(&t, x)| {
            let mut v = vec![0.0; nn];
            model.rhs(t, x, &mut v[..n]);
            v
        })
        .collect();
    // The event gradient p = −∇g/ġ at t_c.
    let xc = orbit.last().expect("a grid");
    let mut f = vec![0.0; n];
    model.rhs(tc, xc, &mut f);
    let grad = event_function_gradient(model, event, tc, xc);
    let gdot = match event {
        EventKind::Maximum { component: c, .. } => {
            // ġ = d/dt F_c(t, x̄): J_c· F (+ ∂F_c/∂t by a central difference; 0 when autonomous).
            let dt = 1e-6 * (1.0 + tc.abs());
            let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
            model.rhs(tc + dt, xc, &mut fp);
            model.rhs(tc - dt, xc, &mut fm);
            let gdot: f64 =
                (0..n).map(|j| grad[j] * f[j]).sum::<f64>() + (fp[c] - fm[c]) / (2.0 * dt);
            if gdot.is_nan() || gdot >= 0.0 {
                return Err(failure(
                    tc,
                    format!("the event is not a strict maximum (d²x/dt² = {gdot:e})"),
                ));
            }
            gdot
        }
        EventKind::CrossDown { component: c, .. } | EventKind::CrossUp { component: c, .. } => {
            if f[c] == 0.0 {
                return Err(failure(tc, "the event crossing is tangential (dx/dt = 0)".into()));
            }
            f[c]
        }
    };
    let p: Vec<f64> = grad.iter().map(|g| -g / gdot).collect();
    let k_last = times.len() - 1;
    let (adjoint, adjoint_steps) = adjoint_sweep(model, &path, tau, times, k_last, &p, rtol)?;
    steps += adjoint_steps;
    let var_tc = form(&p, &covariance[k_last], &p);
    Ok(LinearResponse {
        big: nn,
        orbit,
        velocity,
        covariance,
        adjoint,
        event_gradient: p,
        event_time_std: var_tc.max(0.0).sqrt(),
        steps,
        model: *model,
        path,
        times: times.to_vec(),
        tau,
        rtol,
        event,
        event_slope: gdot,
        covariance_atol,
    })
}

impl LinearResponse {
    /// The event function's fluctuation δg = ∇gᵀδz at t_c − s for the ascending positive
    /// `lags` s (each below t_c − t_start), and the steps taken. The linearised event time
    /// δt_c = −δg(t_c)/ġ assumes that g stays linear in time around t_c in each realisation's
    /// own frame; [`EventFunctionLags`] measures how far that holds.
    pub fn event_function_at_lags(
        &self,
        lags: &[f64],
    ) -> Result<(EventFunctionLags, u64), SolverError> {
        let nn = self.big;
        let n = nn / 2;
        let tc = *self.times.last().expect("a grid");
        let state = |t: f64| {
            let mut x = vec![0.0; n];
            self.path.at(t, &mut x);
            x
        };
        let grad_at = |t: f64| event_function_gradient(&self.model, self.event, t, &state(t));
        // Local times, ascending, ending at t_c: the adjoint μ = Φ(t_c, t)ᵀ∇g(t_c) backwards
        // through them (the event's adjoint λ = −μ/ġ).
        let mut local: Vec<f64> = lags.iter().rev().map(|s| tc - s).collect();
        local.push(tc);
        let last = local.len() - 1;
        let grad_c = grad_at(tc);
        let (mu, adjoint_steps) =
            adjoint_sweep(&self.model, &self.path, self.tau, &local, last, &grad_c, self.rtol)?;
        // C there, forwards from the last grid time at or before the earliest local time.
        let (t0, c0) = match self.times.iter().rposition(|t| *t <= local[0]) {
            Some(k) => (self.times[k], self.covariance[k].clone()),
            None => {
                let mut c0 = vec![0.0; nn * nn];
                (n..nn).for_each(|i| c0[i * nn + i] = 1.0);
                (self.path.t[0], c0)
            }
        };
        let sys = Lyapunov { model: &self.model, orbit: &self.path, tau: self.tau };
        let (cov, cov_steps) =
            integrate_covariance(sys, t0, &c0, &local[..last], self.rtol, &self.covariance_atol)?;
        let var_c = form(&grad_c, self.covariance.last().expect("a grid"), &grad_c);
        let var_tc = self.event_time_std * self.event_time_std;
        let (mut correlation, mut own_frame) = (Vec::new(), Vec::new());
        for l in (0..last).rev() {
            let (t, g, c) = (local[l], grad_at(local[l]), &cov[l]);
            let var = form(&g, c, &g);
            correlation.push(form(&mu[l], c, &g) / (var_c * var).sqrt());
            // ġ(t) = ∇g(t)·ż(t) on the orbit, and Cov(δg(t), δt_c) = ∇g(t)ᵀ C λ.
            let mut f = vec![0.0; n];
            self.model.rhs(t, &state(t), &mut f);
            let slope: f64 = g[..n].iter().zip(&f).map(|(a, b)| a * b).sum();
            let with_tc = -form(&g, c, &mu[l]) / self.event_slope;
            let aligned = var + 2.0 * slope * with_tc + slope * slope * var_tc;
            own_frame
                .push(aligned.max(0.0).sqrt() / (self.event_slope.abs() * self.event_time_std));
        }
        Ok((EventFunctionLags { correlation, own_frame }, adjoint_steps + cov_steps))
    }

    /// Cov(gᵀδz(t_k), δt_c) at every grid time for gradients g_k.
    fn with_event_time(&self, grads: &[Vec<f64>]) -> Vec<f64> {
        (0..self.covariance.len())
            .map(|k| form(&grads[k], &self.covariance[k], &self.adjoint[k]))
            .collect()
    }

    /// gᵀ ż at every grid time: the observable's rate of change along the orbit.
    fn rates(&self, grads: &[Vec<f64>]) -> Vec<f64> {
        grads
            .iter()
            .zip(&self.velocity)
            .map(|(g, z)| g.iter().zip(z).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// Var(g_kᵀ δz(t_k)) at every grid time for the observable gradients g_k (of length N, zero
    /// on the noise components), aligned on each realisation's event when `own`.
    pub fn variances(&self, grads: &[Vec<f64>], own: bool) -> Vec<f64> {
        let with_tc = self.with_event_time(grads);
        let rate = self.rates(grads);
        let var_tc = self.event_time_std * self.event_time_std;
        (0..self.covariance.len())
            .map(|k| {
                let mut v = form(&grads[k], &self.covariance[k], &grads[k]);
                if own {
                    v += 2.0 * rate[k] * with_tc[k] + rate[k] * rate[k] * var_tc;
                }
                v
            })
            .collect()
    }

    /// Cov(g_jᵀδz(t_j), g_kᵀδz(t_k)) for k = 0..=j, aligned on each realisation's event when
    /// `own` (through the adjoint μ_k = Φ(t_j, t_k)ᵀ g_j, integrated backwards from t_j); also
    /// the adjoint's steps.
    pub fn row(
        &self,
        grads: &[Vec<f64>],
        own: bool,
        j: usize,
    ) -> Result<(Vec<f64>, u64), SolverError> {
        let with_tc = self.with_event_time(grads);
        let rate = self.rates(grads);
        let var_tc = self.event_time_std * self.event_time_std;
        let (mu, steps) =
            adjoint_sweep(&self.model, &self.path, self.tau, &self.times, j, &grads[j], self.rtol)?;
        let row = (0..=j)
            .map(|k| {
                let mut v = form(&mu[k], &self.covariance[k], &grads[k]);
                if own {
                    v += rate[j] * with_tc[k] + with_tc[j] * rate[k] + rate[j] * rate[k] * var_tc;
                }
                v
            })
            .collect();
        Ok((row, steps))
    }
}
