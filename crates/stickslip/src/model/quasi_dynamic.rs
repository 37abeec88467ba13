//! The quasi-dynamic limit of the DRR model (no inertia, radiation damping η > 0): the force
//! balance G = u + (θ + f(v) + η v)/ξ = 0 determines v at each instant.
//!
//! The state stays (u, w = ln v, θ), so that events, cycles, shooting and continuation work
//! unchanged; the inertial w equation dw/dt = −γ² e^{−w} G is replaced by the index-reduced,
//! stabilised one. Differentiating G along the flow gives
//! dG/dt = (v − 1) + (dθ/dt + S dw/dt)/ξ with S = v f'(v) + η v = ξ ∂G/∂w, and
//!
//! ```text
//! dw/dt = −(ξ (v − 1) + dθ/dt + κ_G ξ G) / S
//! ```
//!
//! makes dG/dt = −κ_G G exactly: the force balance G = 0 is invariant and attracts at the rate
//! κ_G = [`CONSTRAINT_RELAXATION_RATE`]. On G = 0 this is the quasi-dynamic model; the only
//! trace of the stabilisation is a Floquet multiplier e^{−κ_G T} and a linearisation eigenvalue
//! −κ_G (docs/state-laws.md). η > 0 keeps S ≥ η v > 0 for f = ln v (η = 0 lets v blow up in
//! finite time: the force balance has no solution once the stress outruns f).

/// κ_G, the rate at which the stabilised quasi-dynamic w equation relaxes the force-balance
/// residual G (dG/dt = −κ_G G), in 1/(D_c/v0).
///
/// On the manifold G = 0 the solution does not depend on κ_G; off it (a start or a solver's
/// error) G decays like e^{−κ_G t}. κ_G = 1, the plate-loading rate, adds no time scale faster
/// than the model's own. Measured
/// (docs/state-laws.md, ξ = 0.8, ε = 1, η = 0.05, rtol 1e-10): κ_G = 0.1, 1 and 10 give the
/// same period to 1e-10 with radau5 (steps 5169, 5171, 5175) and to the methods' own error
/// with rodas5p and cvode-bdf.
pub const CONSTRAINT_RELAXATION_RATE: f64 = 1.0;

/// D = −N/S with its gradient and Hessian in (u, w, θ), given N's and S's: the quasi-dynamic
/// dw/dt and its derivatives.
///
/// `n_grad` and `n_hess` are N's first and second derivatives; `s` = (S, ∇S, ∇²S).
pub(super) fn quotient(
    n: f64,
    n_grad: [f64; 3],
    n_hess: [[f64; 3]; 3],
    s: (f64, [f64; 3], [[f64; 3]; 3]),
) -> (f64, [f64; 3], [[f64; 3]; 3]) {
    let (s0, ds, d2s) = s;
    let value = -n / s0;
    // Plain loops, not nested `array::from_fn` closures: the same arithmetic, but the closures
    // were left uninlined across the workspace's crates (8 % more instructions on the
    // quasi-dynamic scene).
    let mut grad = [0.0; 3];
    let mut hess = [[0.0; 3]; 3];
    for k in 0..3 {
        grad[k] = -n_grad[k] / s0 + n * ds[k] / (s0 * s0);
        for j in 0..3 {
            hess[j][k] = -n_hess[j][k] / s0 + (n_grad[j] * ds[k] + n_grad[k] * ds[j]) / (s0 * s0)
                - 2.0 * n * ds[j] * ds[k] / (s0 * s0 * s0)
                + n * d2s[j][k] / (s0 * s0);
        }
    }
    (value, grad, hess)
}
