//! The laboratory's spring-slider (rsfmodel's conventions; docs/lab.md): friction
//!
//!   μ = μ0 + a ln(V/V0) + Σ_i b_i ln(V0 θ_i / D_c,i)       (PRZ: D_c,i → 2 D_c,i)
//!
//! with one or more state variables θ_i, each with its own evolution law, and a quasi-static
//! machine of stiffness k (friction per unit displacement) driven at the load-point velocity
//! V_lp: dμ/dt = k (V_lp − V). Units are any consistent ones (µm, s and friction per µm in the
//! docs).
//!
//! The state is y = (ln V, ln θ_1, …, ln θ_n): V spans many decades in a hold (1e-5 of the
//! load rate and below) and goes to infinity in a finite-time blow-up on a soft machine;
//! logarithms keep its relative precision and positivity. With g_i = d ln θ_i/dt,
//!
//!   d ln V/dt = (k (V_lp − V) − Σ_i b_i g_i) / a.
//!
//! With inertia ([`LabParams::mass`] M = m/(σA), friction·s²/µm) the slider obeys
//! M dV/dt = τ − μ(V, θ), where τ = k (x_lp − δ) is the spring's load in friction units (what
//! the machine's load cell measures), and the state gains τ last: y = (ln V, ln θ_i…, τ) with
//!
//!   d ln V/dt = (τ − μ)/(M V),   dτ/dt = k (V_lp − V).
//!
//! [`LabSystem`] is the right-hand side at a fixed V_lp (one segment of the load-point
//! history: the run restarts at every jump). It is a pure function of (t, y, [`LabParams`],
//! V_lp), with an analytic Jacobian.

use crate::integrate::{ImexSystem, JacobianMatrix, OdeSystem, ParametricSystem};
use serde::Serialize;

/// An evolution law of one state variable.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum LabLaw {
    /// Ageing (Dieterich): dθ/dt = 1 − Vθ/D_c.
    Ageing,
    /// Slip (Ruina): dθ/dt = −(Vθ/D_c) ln(Vθ/D_c).
    Slip,
    /// Perrin–Rice–Zheng: dθ/dt = 1 − (Vθ/(2D_c))², friction term b ln(V0 θ/(2D_c)).
    Prz,
    /// Nagata et al. (2012): dθ/dt = 1 − Vθ/D_c − (c/b) θ dμ/dt.
    Nagata {
        /// The coefficient c (dimensionless).
        c: f64,
    },
}

impl LabLaw {
    /// The law's scene name.
    pub fn name(&self) -> &'static str {
        match self {
            LabLaw::Ageing => "ageing",
            LabLaw::Slip => "slip",
            LabLaw::Prz => "prz",
            LabLaw::Nagata { .. } => "nagata",
        }
    }
}

/// One state variable: its law, b and D_c.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LabState {
    /// The evolution law.
    #[serde(flatten)]
    pub law: LabLaw,
    /// b (dimensionless).
    pub b: f64,
    /// D_c (length, µm).
    pub d_c: f64,
}

impl LabState {
    /// The length in the friction term: 2 D_c for PRZ, D_c otherwise.
    fn friction_length(&self) -> f64 {
        match self.law {
            LabLaw::Prz => 2.0 * self.d_c,
            _ => self.d_c,
        }
    }

    /// θ at steady sliding at V: D_c/V (2 D_c/V for PRZ).
    pub fn steady_theta(&self, v: f64) -> f64 {
        self.friction_length() / v
    }

    /// g = d ln θ/dt and its partial derivatives (∂g/∂ln V, ∂g/∂ln θ) at V = e^w, θ = e^ψ,
    /// with dμ/dt = `dmu` (∂(dμ/dt)/∂ln V = −kV enters Nagata's law through `k`).
    fn rate(&self, w: f64, psi: f64, dmu: f64, k: f64) -> (f64, f64, f64) {
        let v = w.exp();
        let inv_theta = (-psi).exp();
        let v_dc = v / self.d_c;
        match self.law {
            LabLaw::Ageing => (inv_theta - v_dc, -v_dc, -inv_theta),
            LabLaw::Slip => {
                let l = w + psi - self.d_c.ln();
                (-v_dc * l, -v_dc * (l + 1.0), -v_dc)
            }
            LabLaw::Prz => {
                let q = (psi + 2.0 * w).exp() / (4.0 * self.d_c * self.d_c);
                (inv_theta - q, -2.0 * q, -inv_theta - q)
            }
            LabLaw::Nagata { c } => {
                let r = c / self.b;
                (inv_theta - v_dc - r * dmu, -v_dc + r * k * v, -inv_theta)
            }
        }
    }
    /// ∂g/∂ln D_c, ∂g/∂b and ∂g/∂k of g = d ln θ/dt at V = e^w, θ = e^ψ, with dμ/dt = `dmu`
    /// and ∂(dμ/dt)/∂k = `dmu_dk` (only Nagata's law has b and k in g).
    fn rate_parameter_derivatives(&self, w: f64, psi: f64, dmu: f64, dmu_dk: f64) -> [f64; 3] {
        let v_dc = w.exp() / self.d_c;
        match self.law {
            LabLaw::Ageing => [v_dc, 0.0, 0.0],
            LabLaw::Slip => [v_dc * (w + psi - self.d_c.ln() + 1.0), 0.0, 0.0],
            LabLaw::Prz => [2.0 * (psi + 2.0 * w).exp() / (4.0 * self.d_c * self.d_c), 0.0, 0.0],
            LabLaw::Nagata { c } => {
                let r = c / self.b;
                [v_dc, r / self.b * dmu, -r * dmu_dk]
            }
        }
    }
}

/// A parameter of the lab model that a fit or a sensitivity analysis may vary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LabParameter {
    /// a.
    A,
    /// b of state variable i (0-based).
    B(usize),
    /// ln D_c of state variable i (0-based): D_c varies over decades, its logarithm is the
    /// natural scale.
    LnDc(usize),
    /// The machine stiffness k.
    K,
    /// μ0 (enters μ only, not the dynamics in (ln V, ln θ)).
    Mu0,
}

/// The parameters of the laboratory model: everything a fit may vary, in one place.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabParams {
    /// μ0, the steady-state friction at V0.
    pub mu0: f64,
    /// a (dimensionless).
    pub a: f64,
    /// The reference velocity V0 (µm/s).
    pub v0: f64,
    /// The machine stiffness k (friction per µm: stiffness / normal stress).
    pub k: f64,
    /// The state variables.
    pub states: Vec<LabState>,
    /// The slider's inertia M = m/(σA) (friction·s²/µm): None for the quasi-static model
    /// (dμ/dt = k (V_lp − V)), as in rsfmodel.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
}

/// Index of ln V in the state.
pub const LN_V: usize = 0;

impl LabParams {
    /// Dimension of the state (ln V, ln θ_1, …, ln θ_n, and τ with inertia).
    pub fn dim(&self) -> usize {
        1 + self.states.len() + usize::from(self.mass.is_some())
    }

    /// Index of the spring's load τ in the state (with inertia only).
    pub fn tau_index(&self) -> Option<usize> {
        self.mass.map(|_| 1 + self.states.len())
    }

    /// The friction the machine measures at y: the spring's load τ with inertia, μ(V, θ)
    /// without (the two are equal in the quasi-static model).
    pub fn measured_friction(&self, y: &[f64]) -> f64 {
        match self.tau_index() {
            Some(i) => y[i],
            None => self.friction(y),
        }
    }

    /// μ(V, θ) at the state y = (ln V, ln θ_i…): the interface's friction.
    pub fn friction(&self, y: &[f64]) -> f64 {
        let mut mu = self.mu0 + self.a * (y[LN_V] - self.v0.ln());
        for (s, psi) in self.states.iter().zip(&y[1..]) {
            mu += s.b * (psi + (self.v0 / s.friction_length()).ln());
        }
        mu
    }

    /// The state at steady sliding at V: (ln V, ln θ_ss,i(V)…, and τ = μ_ss with inertia).
    pub fn steady_state(&self, v: f64) -> Vec<f64> {
        let mut y: Vec<f64> = std::iter::once(v.ln())
            .chain(self.states.iter().map(|s| s.steady_theta(v).ln()))
            .collect();
        if self.mass.is_some() {
            y.push(self.friction(&y));
        }
        y
    }

    /// The state with friction `mu` and state variables `theta`: ln V solved from μ (with
    /// inertia the spring's load τ = μ too: the slider starts in force balance).
    pub fn state_from(&self, mu: f64, theta: &[f64]) -> Vec<f64> {
        let mut y: Vec<f64> = std::iter::once(0.0).chain(theta.iter().map(|t| t.ln())).collect();
        let mu_at_v1 = self.friction(&y);
        y[LN_V] = (mu - mu_at_v1) / self.a;
        if self.mass.is_some() {
            y.push(mu);
        }
        y
    }

    /// Every parameter of the model: a, then b_i and ln D_c,i of each state variable, k, μ0.
    pub fn all_parameters(&self) -> Vec<LabParameter> {
        let mut all = vec![LabParameter::A];
        for i in 0..self.states.len() {
            all.extend([LabParameter::B(i), LabParameter::LnDc(i)]);
        }
        all.extend([LabParameter::K, LabParameter::Mu0]);
        all
    }

    /// The value of `p` (ln D_c for [`LabParameter::LnDc`]).
    pub fn get(&self, p: LabParameter) -> f64 {
        match p {
            LabParameter::A => self.a,
            LabParameter::B(i) => self.states[i].b,
            LabParameter::LnDc(i) => self.states[i].d_c.ln(),
            LabParameter::K => self.k,
            LabParameter::Mu0 => self.mu0,
        }
    }

    /// Sets `p` to `value` (ln D_c for [`LabParameter::LnDc`]).
    pub fn set(&mut self, p: LabParameter, value: f64) {
        match p {
            LabParameter::A => self.a = value,
            LabParameter::B(i) => self.states[i].b = value,
            LabParameter::LnDc(i) => self.states[i].d_c = value.exp(),
            LabParameter::K => self.k = value,
            LabParameter::Mu0 => self.mu0 = value,
        }
    }

    /// ∂μ/∂p at the state y (explicit dependence: the state held fixed).
    pub fn friction_parameter_derivative(&self, y: &[f64], p: LabParameter) -> f64 {
        match p {
            LabParameter::A => y[LN_V] - self.v0.ln(),
            LabParameter::B(i) => {
                let s = &self.states[i];
                y[1 + i] + (self.v0 / s.friction_length()).ln()
            }
            LabParameter::LnDc(i) => -self.states[i].b,
            LabParameter::K => 0.0,
            LabParameter::Mu0 => 1.0,
        }
    }

    /// ∂y_ss/∂p of the steady state at V ([`LabParams::steady_state`]): ln V does not depend
    /// on the parameters; ln θ_ss,i = ln D_c,i − ln V (+ ln 2 for PRZ); with inertia
    /// τ_ss = μ0 + (a − Σ b_i) ln(V/V0).
    pub fn steady_state_parameter_derivative(&self, v: f64, p: LabParameter, out: &mut [f64]) {
        out.fill(0.0);
        if let LabParameter::LnDc(i) = p {
            out[1 + i] = 1.0;
        }
        if let Some(it) = self.tau_index() {
            let l = (v / self.v0).ln();
            out[it] = match p {
                LabParameter::A => l,
                LabParameter::B(_) => -l,
                LabParameter::Mu0 => 1.0,
                LabParameter::LnDc(_) | LabParameter::K => 0.0,
            };
        }
    }

    /// a − Σ b_i: the steady-state friction change per unit of ln V.
    pub fn a_minus_b(&self) -> f64 {
        self.a - self.states.iter().map(|s| s.b).sum::<f64>()
    }

    /// The critical stiffness k_c = (Σ b_i − a)/D_c of a single state variable (None with
    /// several, where it has no one formula).
    pub fn critical_stiffness(&self) -> Option<f64> {
        match self.states.as_slice() {
            [s] => Some((s.b - self.a) / s.d_c),
            _ => None,
        }
    }
}

/// The laboratory model at a constant load-point velocity (one segment).
#[derive(Debug, Clone, PartialEq)]
pub struct LabSystem<'p> {
    /// The parameters.
    pub params: &'p LabParams,
    /// The load-point velocity V_lp of the segment (µm/s).
    pub v_lp: f64,
}

impl LabSystem<'_> {
    /// dμ/dt = k (V_lp − V) at ln V = w.
    pub fn friction_rate(&self, w: f64) -> f64 {
        self.params.k * (self.v_lp - w.exp())
    }
}

impl LabSystem<'_> {
    /// ∂f/∂p at (t, y): the right-hand side's derivative with respect to the parameter `p`
    /// (the state held fixed), written to `out` (length [`LabParams::dim`]).
    pub fn parameter_derivative(&self, y: &[f64], p: LabParameter, out: &mut [f64]) {
        let params = self.params;
        let w = y[LN_V];
        let dmu = self.friction_rate(w);
        let dmu_dk = self.v_lp - w.exp();
        out.fill(0.0);
        // d ln V/dt = (dμ/dt − Σ b_i g_i)/a; the sum's derivative collects here.
        let mut numerator = 0.0;
        for (i, s) in params.states.iter().enumerate() {
            let [g_dc, g_b, g_k] = s.rate_parameter_derivatives(w, y[1 + i], dmu, dmu_dk);
            let dg = match p {
                LabParameter::LnDc(j) if j == i => g_dc,
                LabParameter::B(j) if j == i => g_b,
                LabParameter::K => g_k,
                _ => 0.0,
            };
            out[1 + i] = dg;
            numerator -= s.b * dg;
        }
        if let (Some(m), Some(it)) = (params.mass, params.tau_index()) {
            // d ln V/dt = (τ − μ)/(M V): only μ's explicit dependence enters; dτ/dt = k (V_lp − V).
            out[LN_V] = -params.friction_parameter_derivative(y, p) / (m * w.exp());
            out[it] = if p == LabParameter::K { dmu_dk } else { 0.0 };
            return;
        }
        match p {
            LabParameter::A => {
                let mut f = vec![0.0; params.dim()];
                self.rhs(0.0, y, &mut f);
                out[LN_V] = -f[LN_V] / params.a;
                return;
            }
            LabParameter::B(i) => {
                let (g, _, _) = params.states[i].rate(w, y[1 + i], dmu, params.k);
                numerator -= g;
            }
            LabParameter::K => numerator += dmu_dk,
            LabParameter::LnDc(_) | LabParameter::Mu0 => {}
        }
        out[LN_V] = numerator / params.a;
    }
}

impl OdeSystem for LabSystem<'_> {
    fn dim(&self) -> usize {
        self.params.dim()
    }

    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let p = self.params;
        let w = y[LN_V];
        let dmu = self.friction_rate(w);
        let mut state_part = 0.0;
        for (i, s) in p.states.iter().enumerate() {
            let (g, _, _) = s.rate(w, y[1 + i], dmu, p.k);
            dydt[1 + i] = g;
            state_part += s.b * g;
        }
        match (p.mass, p.tau_index()) {
            (Some(m), Some(it)) => {
                dydt[LN_V] = (y[it] - p.friction(y)) / (m * w.exp());
                dydt[it] = dmu;
            }
            _ => dydt[LN_V] = (dmu - state_part) / p.a,
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let p = self.params;
        let w = y[LN_V];
        let dmu = self.friction_rate(w);
        if let (Some(m), Some(it)) = (p.mass, p.tau_index()) {
            let inv = 1.0 / (m * w.exp());
            let f = (y[it] - p.friction(y)) * inv;
            for (i, s) in p.states.iter().enumerate() {
                let (_, g_w, g_psi) = s.rate(w, y[1 + i], dmu, p.k);
                jac.set(1 + i, LN_V, g_w);
                jac.set(1 + i, 1 + i, g_psi);
                jac.set(LN_V, 1 + i, -s.b * inv);
            }
            jac.set(LN_V, LN_V, -p.a * inv - f);
            jac.set(LN_V, it, inv);
            jac.set(it, LN_V, -p.k * w.exp());
            return;
        }
        let mut d_w = -p.k * w.exp();
        for (i, s) in p.states.iter().enumerate() {
            let (_, g_w, g_psi) = s.rate(w, y[1 + i], dmu, p.k);
            jac.set(1 + i, LN_V, g_w);
            jac.set(1 + i, 1 + i, g_psi);
            jac.set(LN_V, 1 + i, -s.b * g_psi / p.a);
            d_w -= s.b * g_w;
        }
        jac.set(LN_V, LN_V, d_w / p.a);
    }

    fn has_linear_invariants(&self) -> bool {
        false
    }
}

impl ImexSystem for LabSystem<'_> {
    /// Nothing is explicit: every term can be stiff (a stiff machine, a fast state variable).
    fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt.fill(0.0);
    }

    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.rhs(t, y, dydt)
    }

    fn has_implicit_jacobian(&self) -> bool {
        true
    }

    fn implicit_jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.jacobian(t, y, jac)
    }
}

/// The lab model at a constant load-point velocity with some of its parameters varied: an
/// owned [`LabSystem`] that supplies ∂f/∂p for forward sensitivities (CVODES).
#[derive(Debug, Clone, PartialEq)]
pub struct LabParametric {
    /// The parameters (those in `varied` are the sensitivity parameters).
    pub params: LabParams,
    /// The load-point velocity of the segment.
    pub v_lp: f64,
    /// The parameters varied, in the order of the sensitivities. In the quasi-static model μ0
    /// has none (it enters μ only): leave it out and add ∂μ/∂μ0 = 1 where μ is formed.
    pub varied: Vec<LabParameter>,
}

impl LabParametric {
    fn system(&self) -> LabSystem<'_> {
        LabSystem { params: &self.params, v_lp: self.v_lp }
    }
}

impl OdeSystem for LabParametric {
    fn dim(&self) -> usize {
        self.params.dim()
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.system().rhs(t, y, dydt)
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.system().jacobian(t, y, jac)
    }

    fn has_linear_invariants(&self) -> bool {
        false
    }
}

impl ParametricSystem for LabParametric {
    fn n_params(&self) -> usize {
        self.varied.len()
    }

    fn params(&self) -> Vec<f64> {
        self.varied.iter().map(|p| self.params.get(*p)).collect()
    }

    fn set_params(&mut self, p: &[f64]) {
        for (which, value) in self.varied.iter().zip(p) {
            self.params.set(*which, *value);
        }
    }

    fn param_jacobian(&self, _t: f64, y: &[f64], dfdp: &mut JacobianMatrix<'_>) {
        let mut column = vec![0.0; self.dim()];
        for (j, p) in self.varied.iter().enumerate() {
            self.system().parameter_derivative(y, *p, &mut column);
            for (i, value) in column.iter().enumerate() {
                dfdp.set(i, j, *value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;

    /// The quasi-static model and the same with inertia.
    fn both() -> [LabParams; 2] {
        let p = params();
        let inertial = LabParams { mass: Some(2e-3), ..p.clone() };
        [p, inertial]
    }

    /// A state of `p`'s dimension (τ last with inertia).
    fn state(p: &LabParams, y: [f64; 5]) -> Vec<f64> {
        let mut y = y.to_vec();
        if p.mass.is_some() {
            y.push(0.57);
        }
        y
    }

    fn params() -> LabParams {
        let st = |law, b, d_c| LabState { law, b, d_c };
        LabParams {
            mass: None,
            mu0: 0.6,
            a: 0.011,
            v0: 1.0,
            k: 3e-3,
            states: vec![
                st(LabLaw::Ageing, 0.01, 5.0),
                st(LabLaw::Slip, 0.004, 20.0),
                st(LabLaw::Prz, 0.003, 3.0),
                st(LabLaw::Nagata { c: 2.0 }, 0.02, 7.0),
            ],
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        for p in both() {
            let m = LabSystem { params: &p, v_lp: 3.0 };
            for y in
                [[0.3, 1.2, 2.0, 0.7, 1.9], [-4.0, 6.0, 1.0, 3.0, -0.5], [2.5, -2.0, 0.1, 0.2, 0.3]]
            {
                let y = state(&p, y);
                for (row, col, exact, fd) in jacobian_against_differences(&m, &y, |_| 1e-6) {
                    assert!(
                        (fd - exact).abs() < 1e-6 * (1.0 + fd.abs()),
                        "({row},{col}) {:?}",
                        p.mass
                    );
                }
            }
        }
    }

    #[test]
    fn parameter_derivatives_match_central_differences() {
        for p in both() {
            parameter_derivatives_of(&p);
        }
    }

    fn parameter_derivatives_of(p: &LabParams) {
        let p = p.clone();
        let y = state(&p, [0.3, 1.2, 2.0, 0.7, 1.9]);
        let rhs = |q: &LabParams| {
            let mut f = vec![0.0; q.dim()];
            LabSystem { params: q, v_lp: 3.0 }.rhs(0.0, &y, &mut f);
            f
        };
        for par in p.all_parameters() {
            let mut exact = vec![0.0; p.dim()];
            LabSystem { params: &p, v_lp: 3.0 }.parameter_derivative(&y, par, &mut exact);
            let h = 1e-6 * p.get(par).abs().max(1e-3);
            let (mut up, mut down) = (p.clone(), p.clone());
            up.set(par, p.get(par) + h);
            down.set(par, p.get(par) - h);
            let (fu, fd) = (rhs(&up), rhs(&down));
            for i in 0..p.dim() {
                let diff = (fu[i] - fd[i]) / (2.0 * h);
                assert!(
                    (diff - exact[i]).abs() < 1e-6 * (1.0 + diff.abs()),
                    "{par:?}[{i}]: {diff} vs {}",
                    exact[i]
                );
            }
            let mu_diff = (up.friction(&y) - down.friction(&y)) / (2.0 * h);
            let mu_exact = p.friction_parameter_derivative(&y, par);
            assert!((mu_diff - mu_exact).abs() < 1e-8 * (1.0 + mu_diff.abs()), "{par:?}: mu");
            let v = 3.0;
            let ss_diff: Vec<f64> = up
                .steady_state(v)
                .iter()
                .zip(down.steady_state(v))
                .map(|(u, d)| (u - d) / (2.0 * h))
                .collect();
            let mut ss_exact = vec![0.0; p.dim()];
            p.steady_state_parameter_derivative(v, par, &mut ss_exact);
            for (a, b) in ss_diff.iter().zip(&ss_exact) {
                assert!((a - b).abs() < 1e-8 * (1.0 + a.abs()), "{par:?}: steady state");
            }
        }
    }

    #[test]
    fn steady_state_is_a_fixed_point_with_steady_friction() {
        for p in both() {
            steady_state_of(&p);
        }
    }

    fn steady_state_of(p: &LabParams) {
        let v = 7.0;
        let y = p.steady_state(v);
        let mut f = vec![0.0; p.dim()];
        LabSystem { params: p, v_lp: v }.rhs(0.0, &y, &mut f);
        assert!(f.iter().all(|x| x.abs() < 1e-15), "{f:?}");
        let mu = p.friction(&y);
        assert!((mu - (0.6 + p.a_minus_b() * v.ln())).abs() < 1e-15);
        assert_eq!(p.measured_friction(&y), mu);
        let theta: Vec<f64> = y[1..=p.states.len()].iter().map(|l| l.exp()).collect();
        let back = p.state_from(mu, &theta);
        assert!((back[LN_V] - v.ln()).abs() < 1e-12);
    }
}
