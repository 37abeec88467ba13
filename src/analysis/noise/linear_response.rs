//! The small-noise limit: linear response along the deterministic orbit.
//!
//! With the OU noises in the state, z = (x, η) obeys dz = a(z) dt + (0, √(2/τ) dW) with
//! a = (F(t, x) + B(x)η, −η/τ). Linearised about the deterministic orbit (x̄(t), η = 0), the
//! deviations δz are Gaussian with covariance C(t) solving the Lyapunov (covariance) equation
//!
//!   dC/dt = A C + C Aᵀ + Q,   A = [[J(x̄), B(x̄)], [0, −I/τ]],   Q = [[0, 0], [0, (2/τ) I]],
//!
//! from C(t_start) = [[0, 0], [0, I]] (deterministic start, stationary noise), and two-time
//! covariances C(t, s) = Φ(t, s) C(s) for t ≥ s, Φ the propagator of dδz/dt = A δz. Along the
//! output grid t_0 < … < t_K = t_c the orbit, C and the propagator of each piece
//! P_k = Φ(t_k, t_{k−1}) are integrated together by Radau5 (restarted at each grid point with
//! P = I); propagators between any two grid points are products of pieces.
//!
//! **Alignment on each realisation's own event.** The event shifts by δt_c = pᵀ δz(t_c) with
//! p = −∇g/ġ for the event function g (g = dx_c/dt at a maximum, g = x_c − level at a
//! crossing). A realisation aligned on its own event deviates from the orbit at t_c + s by
//! δz(t) + ż(t) δt_c, so its covariances are
//!
//!   Cov(δz_a(t_j), δz_b(t_k)) + ż_a(t_j) (C_k λ_k)_b + (C_j λ_j)_a ż_b(t_k) + ż_a(t_j) ż_b(t_k) pᵀC_K p,
//!
//! with λ_k = Φ(t_c, t_k)ᵀ p obtained backwards from λ_K = p by λ_{k−1} = P_kᵀ λ_k (the
//! adjoint of the linearised flow). An observable o(x) (e.g. v = e^w) varies by o'(x̄) δx.

use super::models::{EventKind, NoiseModel};
use crate::integrate::{ErrorKind, JacobianMatrix, OdeSystem, Options, Radau5, SolverError, Stats, Task, Tolerance};

/// Largest augmented dimension (2 × the DRR's 3).
const MAX_BIG: usize = 6;

/// The orbit, its propagator piece and the covariance, as one ODE.
#[derive(Clone, Copy)]
struct Augmented<'a> {
    model: &'a NoiseModel,
    n: usize,
    tau: f64,
}

impl Augmented<'_> {
    fn big(&self) -> usize {
        2 * self.n
    }

    /// A (N×N, row-major) at (t, x̄).
    fn matrix(&self, t: f64, x: &[f64], a: &mut [f64]) {
        let (n, nn) = (self.n, self.big());
        let mut jstore = [0.0; MAX_BIG * MAX_BIG / 4];
        let mut jac = JacobianMatrix::new(&mut jstore[..n * n], n);
        self.model.jacobian(t, x, &mut jac);
        let mut b = [0.0; MAX_BIG / 2];
        self.model.noise_diag(x, &mut b[..n]);
        a.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..n {
            for j in 0..n {
                a[i * nn + j] = jac.get(i, j);
            }
            a[i * nn + n + i] = b[i];
            a[(n + i) * nn + n + i] = -1.0 / self.tau;
        }
    }
}

impl OdeSystem for Augmented<'_> {
    fn dim(&self) -> usize {
        self.n + 2 * self.big() * self.big()
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let (n, nn) = (self.n, self.big());
        let x = &y[..n];
        self.model.rhs(t, x, &mut dydt[..n]);
        let mut astore = [0.0; MAX_BIG * MAX_BIG];
        let a = &mut astore[..nn * nn];
        self.matrix(t, x, a);
        let phi = &y[n..n + nn * nn];
        let c = &y[n + nn * nn..];
        let (dphi, dc) = dydt[n..].split_at_mut(nn * nn);
        for i in 0..nn {
            for j in 0..nn {
                let (mut p, mut ac) = (0.0, 0.0);
                for k in 0..nn {
                    p += a[i * nn + k] * phi[k * nn + j];
                    ac += a[i * nn + k] * c[k * nn + j];
                }
                dphi[i * nn + j] = p;
                dc[i * nn + j] = ac;
            }
        }
        // dC = AC + (AC)ᵀ + Q.
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
    /// P_k = Φ(t_k, t_{k−1}) (P_0 = Φ(t_0, t_start)), N×N row-major.
    pub pieces: Vec<Vec<f64>>,
    /// λ_k = Φ(t_c, t_k)ᵀ p.
    pub adjoint: Vec<Vec<f64>>,
    /// p: δt_c = pᵀ δz(t_c).
    pub event_gradient: Vec<f64>,
    /// Standard deviation of the event time, √(pᵀ C_K p).
    pub event_time_std: f64,
    /// Radau5's statistics.
    pub stats: Stats,
}

fn mat_vec(m: &[f64], v: &[f64], out: &mut [f64]) {
    let nn = v.len();
    for i in 0..nn {
        out[i] = (0..nn).map(|k| m[i * nn + k] * v[k]).sum();
    }
}

fn mat_t_vec(m: &[f64], v: &[f64], out: &mut [f64]) {
    let nn = v.len();
    for j in 0..nn {
        out[j] = (0..nn).map(|i| m[i * nn + j] * v[i]).sum();
    }
}

fn failure(t: f64, message: String) -> SolverError {
    SolverError { solver: "stickslip linear response", kind: ErrorKind::Other, t, state: vec![], flag: 0, message }
}

/// Integrates orbit, covariance and propagator pieces from (t_start, x_start) through the grid
/// `times` (ascending, all after t_start, the last one the deterministic event of kind
/// `event`), for OU noises of correlation time `tau`, with Radau5 at `rtol` (absolute
/// tolerances `atol_x` on the orbit, scaled ones on covariance and propagator).
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
) -> Result<LinearResponse, SolverError> {
    let n = model.dim();
    if model.amplitudes().iter().all(|a| *a == 0.0) {
        return Err(failure(t_start, "every noise amplitude is zero: nothing to respond to".into()));
    }
    let sys = Augmented { model, n, tau };
    let nn = sys.big();
    // Pass 1 with rough scales, pass 2 with absolute tolerances from the covariance's range.
    let mut scales = vec![1.0; nn];
    let mut result = None;
    for _pass in 0..2 {
        let mut atol = atol_x.to_vec();
        for i in 0..nn {
            for j in 0..nn {
                atol.push(1e-9 * scales[i] / scales[j]);
            }
        }
        for i in 0..nn {
            for j in 0..nn {
                atol.push(1e-9 * scales[i] * scales[j]);
            }
        }
        let mut y0 = x_start.to_vec();
        let mut identity = vec![0.0; nn * nn];
        (0..nn).for_each(|i| identity[i * nn + i] = 1.0);
        y0.extend_from_slice(&identity);
        let mut c0 = vec![0.0; nn * nn];
        (n..nn).for_each(|i| c0[i * nn + i] = 1.0);
        y0.extend_from_slice(&c0);
        let options = Options { max_steps: Some(1_000_000), ..Options::new(rtol, Tolerance::PerComponent(atol)) };
        let mut integ = Radau5::new(sys, t_start, &y0, &options)?;
        let (mut orbit, mut covariance, mut pieces) = (Vec::new(), Vec::new(), Vec::new());
        let mut max_var = vec![0.0f64; nn];
        for &t in times {
            integ.set_stop_time(Some(t));
            integ.advance(t, Task::Normal)?;
            let y = integ.state().to_vec();
            orbit.push(y[..n].to_vec());
            pieces.push(y[n..n + nn * nn].to_vec());
            let c = y[n + nn * nn..].to_vec();
            for i in 0..nn {
                max_var[i] = max_var[i].max(c[i * nn + i].abs());
            }
            covariance.push(c);
            let mut restart = y.clone();
            restart[n..n + nn * nn].copy_from_slice(&identity);
            integ.reinit(t, &restart)?;
        }
        for i in 0..nn {
            scales[i] = max_var[i].sqrt().max(1e-300);
        }
        result = Some((orbit, covariance, pieces, integ.stats()));
    }
    let (orbit, covariance, pieces, stats) = result.expect("two passes ran");
    if covariance.iter().chain(&pieces).any(|m| m.iter().any(|v| !v.is_finite())) {
        return Err(failure(*times.last().unwrap_or(&t_start), "the covariance or propagator is not finite".into()));
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
    let (tc, xc) = (*times.last().expect("a grid"), orbit.last().expect("a grid"));
    let mut p = vec![0.0; nn];
    let mut f = vec![0.0; n];
    model.rhs(tc, xc, &mut f);
    match event {
        EventKind::Maximum { component: c, .. } => {
            let mut jstore = vec![0.0; n * n];
            let mut jac = JacobianMatrix::new(&mut jstore, n);
            model.jacobian(tc, xc, &mut jac);
            // ġ = d/dt F_c(t, x̄): J_c· F (+ ∂F_c/∂t by a central difference; 0 when autonomous).
            let dt = 1e-6 * (1.0 + tc.abs());
            let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
            model.rhs(tc + dt, xc, &mut fp);
            model.rhs(tc - dt, xc, &mut fm);
            let gdot: f64 = (0..n).map(|j| jac.get(c, j) * f[j]).sum::<f64>() + (fp[c] - fm[c]) / (2.0 * dt);
            let mut b = vec![0.0; n];
            model.noise_diag(xc, &mut b);
            for (j, pj) in p.iter_mut().take(n).enumerate() {
                *pj = -jac.get(c, j) / gdot;
            }
            p[n + c] = -b[c] / gdot;
            if gdot.is_nan() || gdot >= 0.0 {
                return Err(failure(tc, format!("the event is not a strict maximum (d²x/dt² = {gdot:e})")));
            }
        }
        EventKind::CrossDown { component: c, .. } | EventKind::CrossUp { component: c, .. } => {
            if f[c] == 0.0 {
                return Err(failure(tc, "the event crossing is tangential (dx/dt = 0)".into()));
            }
            p[c] = -1.0 / f[c];
        }
    }
    let k_last = times.len() - 1;
    let mut adjoint = vec![vec![0.0; nn]; times.len()];
    adjoint[k_last] = p.clone();
    for k in (0..k_last).rev() {
        let (next, cur) = adjoint.split_at_mut(k + 1);
        mat_t_vec(&pieces[k + 1], &cur[0], &mut next[k]);
    }
    let mut cp = vec![0.0; nn];
    mat_vec(&covariance[k_last], &p, &mut cp);
    let var_tc: f64 = p.iter().zip(&cp).map(|(a, b)| a * b).sum();
    Ok(LinearResponse {
        big: nn,
        orbit,
        velocity,
        covariance,
        pieces,
        adjoint,
        event_gradient: p,
        event_time_std: var_tc.max(0.0).sqrt(),
        stats,
    })
}

impl LinearResponse {
    /// Cov(gᵀδz(t_k), δt_c) at every grid time for gradients g_k.
    fn with_event_time(&self, grads: &[Vec<f64>]) -> Vec<f64> {
        let nn = self.big;
        (0..self.covariance.len())
            .map(|k| {
                let (c, l, g) = (&self.covariance[k], &self.adjoint[k], &grads[k]);
                (0..nn).map(|a| g[a] * (0..nn).map(|m| c[a * nn + m] * l[m]).sum::<f64>()).sum()
            })
            .collect()
    }

    /// gᵀ ż at every grid time: the observable's rate of change along the orbit.
    fn rates(&self, grads: &[Vec<f64>]) -> Vec<f64> {
        grads.iter().zip(&self.velocity).map(|(g, z)| g.iter().zip(z).map(|(a, b)| a * b).sum()).collect()
    }

    /// Var(g_kᵀ δz(t_k)) at every grid time for the observable gradients g_k (of length N, zero
    /// on the noise components), aligned on each realisation's event when `own`.
    pub fn variances(&self, grads: &[Vec<f64>], own: bool) -> Vec<f64> {
        let nn = self.big;
        let with_tc = self.with_event_time(grads);
        let rate = self.rates(grads);
        let var_tc = self.event_time_std * self.event_time_std;
        (0..self.covariance.len())
            .map(|k| {
                let (c, g) = (&self.covariance[k], &grads[k]);
                let mut v: f64 = (0..nn).map(|a| g[a] * (0..nn).map(|b| c[a * nn + b] * g[b]).sum::<f64>()).sum();
                if own {
                    v += 2.0 * rate[k] * with_tc[k] + rate[k] * rate[k] * var_tc;
                }
                v
            })
            .collect()
    }

    /// Cov(g_jᵀδz(t_j), g_kᵀδz(t_k)) for k = 0..=j, aligned on each realisation's event when
    /// `own` (through the adjoint μ_k = Φ(t_j, t_k)ᵀ g_j, μ_{k−1} = P_kᵀ μ_k).
    pub fn row(&self, grads: &[Vec<f64>], own: bool, j: usize) -> Vec<f64> {
        let nn = self.big;
        let with_tc = self.with_event_time(grads);
        let rate = self.rates(grads);
        let var_tc = self.event_time_std * self.event_time_std;
        let mut row = vec![0.0; j + 1];
        let mut mu = grads[j].clone();
        let mut next = vec![0.0; nn];
        for k in (0..=j).rev() {
            if k < j {
                mat_t_vec(&self.pieces[k + 1], &mu, &mut next);
                std::mem::swap(&mut mu, &mut next);
            }
            let (c, g) = (&self.covariance[k], &grads[k]);
            let mut v: f64 = (0..nn).map(|a| mu[a] * (0..nn).map(|b| c[a * nn + b] * g[b]).sum::<f64>()).sum();
            if own {
                v += rate[j] * with_tc[k] + with_tc[j] * rate[k] + rate[j] * rate[k] * var_tc;
            }
            row[k] = v;
        }
        row
    }
}
