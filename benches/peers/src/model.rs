//! The DRR spring-slider in y = (u, w = ln v, θ), with the formulas and the order of
//! operations of stickslip's src/model/drr.rs (f = ln v):
//!
//!   du/dt = e^w − 1,  dw/dt = −γ² e^{−w} (u + (θ + w)/ξ),  dθ/dt = −e^w (θ + (1+ε) w).

/// Index of u.
pub const U: usize = 0;
/// Index of w = ln v.
pub const W: usize = 1;
/// Index of θ.
pub const TH: usize = 2;

/// The model's parameters.
#[derive(Debug, Clone, Copy)]
pub struct Drr {
    gamma2: f64,
    xi: f64,
    epsilon: f64,
}

impl Drr {
    /// The model at (γ, ξ, ε).
    pub fn new(gamma: f64, xi: f64, epsilon: f64) -> Self {
        Self { gamma2: gamma * gamma, xi, epsilon }
    }

    /// dy/dt at y.
    pub fn rhs(&self, y: &[f64], d: &mut [f64]) {
        let w = y[W];
        let g = y[U] + (y[TH] + w) / self.xi;
        d[U] = w.exp_m1();
        d[W] = -self.gamma2 * (-w).exp() * g;
        d[TH] = -w.exp() * (y[TH] + (1.0 + self.epsilon) * w);
    }

    /// dw/dt at y.
    pub fn dw(&self, y: &[f64]) -> f64 {
        let mut d = [0.0; 3];
        self.rhs(y, &mut d);
        d[W]
    }

    /// The Jacobian ∂f_i/∂y_k as rows j[i][k].
    pub fn jacobian(&self, y: &[f64]) -> [[f64; 3]; 3] {
        let w = y[W];
        let v = w.exp();
        let g = y[U] + (y[TH] + w) / self.xi;
        let a = self.gamma2 * (-w).exp();
        let mut j = [[0.0; 3]; 3];
        j[U][W] = v;
        j[W][U] = -a;
        j[W][W] = a * (g - 1.0 / self.xi);
        j[W][TH] = -a / self.xi;
        j[TH][W] = -v * (y[TH] + (1.0 + self.epsilon) * w) - v * (1.0 + self.epsilon);
        j[TH][TH] = -v;
        j
    }
}
