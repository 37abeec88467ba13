//! Test problems and helpers shared by the integrator tests (tests/methods.rs, tests/radau5.rs,
//! tests/rodas5p.rs, tests/extrapolation.rs, tests/wrappers.rs), the reference tables'
//! check ([`reference`]), a scene run through the library ([`run_scene`], [`run_scene_file`])
//! and through the CLI ([`cli_run`], [`compare_cli`]).
#![allow(dead_code)]

pub mod reference;

/// The text of the shipped scene data/scenes/`name`.
pub fn scene_file_text(name: &str) -> String {
    let path = format!("{}/data/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The report of the scene `text` (JSON) through the library, as `stickslip run` computes it:
/// `scene::parse`, then `engine::run` with the text echoed; panics with the error's message.
pub fn run_scene(text: &str) -> stickslip::report::Report {
    let s = stickslip::scene::parse(text, "test").unwrap_or_else(|e| panic!("{e}"));
    stickslip::engine::run(
        &s,
        stickslip::engine::RunOptions::echoing(serde_json::from_str(text).unwrap()),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// [`run_scene`] on the shipped scene data/scenes/`name`.
pub fn run_scene_file(name: &str) -> stickslip::report::Report {
    run_scene(&scene_file_text(name))
}

/// `stickslip run FILE` with `extra` options, FILE a temporary copy of the scene `text` named
/// after `tag` (unique per test process, removed afterwards): the process's output.
pub fn cli_run(text: &str, tag: &str, extra: &[&str]) -> std::process::Output {
    let path =
        std::env::temp_dir().join(format!("stickslip-test-{}-{tag}.json", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("run")
        .arg(&path)
        .args(extra)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&path);
    out
}

/// `stickslip compare SCENE --against FILE` with `extra` options: (exit code, stdout, stderr).
pub fn compare_cli(
    scene: &std::path::Path,
    file: &std::path::Path,
    extra: &[&str],
) -> (Option<i32>, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args(["compare", scene.to_str().unwrap(), "--against", file.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

use stickslip::integrate::{ImexSystem, Integrator, JacobianMatrix, OdeSystem, Task};

/// y' = 1 + y², y(0) = 0: y = tan t (nonlinear, non-stiff; finite-difference Jacobian).
pub struct Tan;

impl OdeSystem for Tan {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = 1.0 + y[0] * y[0];
    }
}

/// Harmonic oscillator x' = v, v' = −x from (0, 1): x = sin t, v = cos t.
pub struct Oscillator;

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[1];
        dydt[1] = -y[0];
    }
}

/// y' = k·y with an analytic Jacobian.
pub struct Linear(pub f64);

impl OdeSystem for Linear {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = self.0 * y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, self.0);
    }
}

/// Van der Pol in the Test Set's scaled form: y1' = y2, y2' = ((1 − y1²) y2 − y1)/ε.
#[derive(Clone, Copy)]
pub struct VanDerPol(pub f64);

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[1];
        dydt[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.0;
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 1, 1.0);
        jac.set(1, 0, (-2.0 * y[0] * y[1] - 1.0) / self.0);
        jac.set(1, 1, (1.0 - y[0] * y[0]) / self.0);
    }
}

/// A right-hand side that returns NaN once t passes `from`.
pub struct NanAfter(pub f64);

impl OdeSystem for NanAfter {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = if t > self.0 { f64::NAN } else { -y[0] };
    }
}

/// Prothero–Robinson y' = −λ (y − cos t) − sin t, exact y = cos t from y(0) = 1 (analytic
/// Jacobian).
pub struct ProtheroRobinson(pub f64);

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * (y[0] - t.cos()) - t.sin();
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.0);
    }
}

/// y' = −k y, exact solution y0·e^{−kt} (analytic Jacobian); as an IMEX system all of it is
/// implicit.
pub struct Decay(pub f64);

impl OdeSystem for Decay {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.0);
    }
}

impl ImexSystem for Decay {
    fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt[0] = 0.0;
    }
    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.rhs(t, y, dydt);
    }
}

/// A nonlinear system with every elementary differential of order ≤ 5 independent:
/// y = φ(z) with z' = M z (rotation in (z1, z2), decay of z3) and φ(z) = (z1, z2 + z1²,
/// z3 + z1 z2), so f(y) = Dφ(φ⁻¹(y)) M φ⁻¹(y) (finite-difference Jacobian).
pub struct Warped;

impl Warped {
    fn z(y: &[f64]) -> [f64; 3] {
        let z1 = y[0];
        let z2 = y[1] - z1 * z1;
        [z1, z2, y[2] - z1 * z2]
    }

    /// The solution at t from z(0) = (0.3, 0.8, 1).
    pub fn exact(t: f64) -> [f64; 3] {
        // z1 = 0.3 cos t + 0.8 sin t, z2 = −0.3 sin t + 0.8 cos t.
        let (s, c) = t.sin_cos();
        let z = [0.3 * c + 0.8 * s, -0.3 * s + 0.8 * c, (-0.5 * t).exp()];
        [z[0], z[1] + z[0] * z[0], z[2] + z[0] * z[1]]
    }
}

impl OdeSystem for Warped {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let z = Self::z(y);
        let dz = [z[1], -z[0], -0.5 * z[2]];
        dydt[0] = dz[0];
        dydt[1] = dz[1] + 2.0 * z[0] * dz[0];
        dydt[2] = dz[2] + dz[0] * z[1] + z[0] * dz[1];
    }
}

/// y' = y cos t, y(0) = 1: y = e^{sin t} (non-autonomous: needs ∂f/∂t).
pub struct Forced;

impl OdeSystem for Forced {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[0] * t.cos();
    }
}

/// Numbers in scientific notation with 16 digits.
pub fn sci(v: &[f64]) -> String {
    v.iter().map(|x| format!("{x:.16e}")).collect::<Vec<_>>().join(", ")
}

/// Observed orders log2(e(h)/e(h/2)) for successive halvings.
pub fn observed_orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// OneStep integration of the DRR model from `y0` to total time `tend`, re-basing time (a
/// restart at local t = 0) at the first step end after each slip peak, as the cycle engine
/// does. Returns (steps, peak times).
pub fn drr_cycles(
    integ: &mut dyn Integrator,
    tend: f64,
) -> Result<(u64, Vec<f64>), stickslip::integrate::SolverError> {
    let (mut elapsed, mut steps, mut peaks) = (0.0, 0u64, Vec::new());
    let mut prev_dw = integ.dense(integ.t(), 1)?[1];
    let mut rebase_pending = false;
    while elapsed + integ.t() < tend {
        let step = integ.advance(1e6, Task::OneStep)?;
        steps += 1;
        let y = integ.state().to_vec();
        let dw = integ.dense(step.t, 1)?[1];
        if prev_dw > 0.0 && dw <= 0.0 && y[1] > 5.0 {
            peaks.push(elapsed + step.t);
            rebase_pending = true;
        } else if rebase_pending {
            integ.reinit(0.0, &y)?;
            elapsed += step.t;
            rebase_pending = false;
        }
        prev_dw = dw;
    }
    Ok((steps, peaks))
}
