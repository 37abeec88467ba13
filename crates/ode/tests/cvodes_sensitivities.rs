//! CVODES' forward sensitivities through the safe wrapper (`sundials::SensitivitySolver`):
//!
//! - SUNDIALS' own example cvsRoberts_FSA_dns (Robertson's kinetics with p = (0.04, 1e4, 3e7),
//!   sensitivities to the three rates) reproduces every printed line of the expected outputs
//!   Debian's libsundials-dev ships (tests/expected/{6,7}/cvsRoberts_FSA_dns_-sensi_*_t.out):
//!   t, order, last step, step count, y and the three sensitivities to the printed digits, with
//!   the simultaneous and the staggered-1 corrector; the staggered corrector, which has no
//!   shipped output, agrees with the simultaneous one within the example's tolerances;
//! - on Robertson and on a small, stiff friction block with rate-and-state friction that is
//!   restarted at a load-point velocity step, the sensitivities agree with central
//!   differences of y within 1e-6 relative, with the simultaneous and the staggered corrector;
//! - failures are typed errors: no analytic Jacobian, wrong initial sensitivities, non-finite
//!   ∂f/∂p, a panic in ∂f/∂p.

use stickslip_ode::integrate::{
    ErrorKind, JacobianMatrix, OdeSystem, Options, ParametricSystem, SolverError, Task, Tolerance,
};
use stickslip_ode::robertson::examples::c_exponential;
use stickslip_ode::sundials::{
    self, CvodeSettings, SensitivityCorrector, SensitivitySettings, SensitivitySolver,
    SensitivityTolerance, Solver,
};

// ---------------------------------------------------------------------------------------------
// Robertson's kinetics with its three rates as parameters, coded as cvsRoberts_FSA_dns.c does.

#[derive(Debug, Clone)]
struct Robertson {
    p: [f64; 3],
    /// Form the sensitivity right-hand side as the C example's `fS` does (row 2 as minus the
    /// sum of rows 1 and 3) instead of the wrapper's dense J·s_j + ∂f/∂p_j.
    example_fs: bool,
}

impl Robertson {
    fn example() -> Self {
        Self { p: [0.04, 1.0e4, 3.0e7], example_fs: true }
    }

    fn generic() -> Self {
        Self { example_fs: false, ..Self::example() }
    }
}

impl OdeSystem for Robertson {
    fn dim(&self) -> usize {
        3
    }

    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let [p1, p2, p3] = self.p;
        let yd1 = -p1 * y[0] + p2 * y[1] * y[2];
        let yd3 = p3 * y[1] * y[1];
        dydt[0] = yd1;
        dydt[2] = yd3;
        dydt[1] = -yd1 - yd3;
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let [p1, p2, p3] = self.p;
        let (y2, y3) = (y[1], y[2]);
        jac.set(0, 0, -p1);
        jac.set(0, 1, p2 * y3);
        jac.set(0, 2, p2 * y2);
        jac.set(1, 0, p1);
        jac.set(1, 1, -p2 * y3 - 2.0 * p3 * y2);
        jac.set(1, 2, -p2 * y2);
        jac.set(2, 1, 2.0 * p3 * y2);
    }
}

impl ParametricSystem for Robertson {
    fn n_params(&self) -> usize {
        3
    }

    fn params(&self) -> Vec<f64> {
        self.p.to_vec()
    }

    fn set_params(&mut self, p: &[f64]) {
        self.p.copy_from_slice(p);
    }

    fn param_jacobian(&self, _t: f64, y: &[f64], dfdp: &mut JacobianMatrix<'_>) {
        let (y1, y2, y3) = (y[0], y[1], y[2]);
        dfdp.set(0, 0, -y1);
        dfdp.set(1, 0, y1);
        dfdp.set(0, 1, y2 * y3);
        dfdp.set(1, 1, -y2 * y3);
        dfdp.set(1, 2, -y2 * y2);
        dfdp.set(2, 2, y2 * y2);
    }

    fn has_sensitivity_rhs(&self) -> bool {
        self.example_fs
    }

    /// cvsRoberts_FSA_dns.c's `fS`, operation for operation.
    fn sensitivity_rhs(&self, _t: f64, y: &[f64], j: usize, s: &[f64], out: &mut [f64]) {
        let [p1, p2, p3] = self.p;
        let (y1, y2, y3) = (y[0], y[1], y[2]);
        let mut sd1 = -p1 * s[0] + p2 * y3 * s[1] + p2 * y2 * s[2];
        let mut sd3 = 2.0 * p3 * y2 * s[1];
        let mut sd2 = -sd1 - sd3;
        match j {
            0 => {
                sd1 += -y1;
                sd2 += y1;
            }
            1 => {
                sd1 += y2 * y3;
                sd2 += -y2 * y3;
            }
            _ => {
                sd2 += -y2 * y2;
                sd3 += y2 * y2;
            }
        }
        out.copy_from_slice(&[sd1, sd2, sd3]);
    }
}

// ---------------------------------------------------------------------------------------------
// cvsRoberts_FSA_dns, replayed.

/// The linked SUNDIALS major version, which selects the expected outputs.
fn expected(name: &str) -> String {
    let version = sundials::version();
    let major = version.split('.').next().unwrap_or("?");
    let path = format!("{}/tests/expected/{major}/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path} (SUNDIALS {version}): {e}"))
}

/// The printed lines of the output blocks: from the table header's closing rule to the final
/// statistics, without the separators.
fn printed_lines(out: &str) -> Vec<String> {
    out.lines()
        .skip_while(|l| !l.starts_with("====="))
        .skip(1)
        .skip_while(|l| !l.starts_with("====="))
        .skip(1)
        .take_while(|l| !l.starts_with("Final Statistics"))
        .filter(|l| !l.trim().is_empty() && !l.starts_with("-----"))
        .map(str::to_string)
        .collect()
}

/// The number after `label` in the final statistics.
fn counter(out: &str, label: &str) -> f64 {
    let line = out.lines().find(|l| l.starts_with(label)).unwrap_or_else(|| panic!("no {label}"));
    line.split('=').nth(1).and_then(|v| v.trim().parse().ok()).expect("a number")
}

struct Replay {
    lines: Vec<String>,
    /// (t, y, s) at each output time.
    rows: Vec<(f64, Vec<f64>, Vec<f64>)>,
    steps: u64,
    rhs_evals: u64,
    jac_evals: u64,
    sens_rhs_evals: u64,
}

/// cvsRoberts_FSA_dns with `-sensi <corrector> t`: BDF, rtol 1e-4, atol (1e-8, 1e-14, 1e-6),
/// analytic Jacobian, p̄ = p, estimated sensitivity tolerances with full error control,
/// outputs at 0.4·10^k, k = 0..11, printed as the C program prints them.
fn replay(system: Robertson, corrector: SensitivityCorrector) -> Replay {
    let options = Options::new(1.0e-4, Tolerance::PerComponent(vec![1.0e-8, 1.0e-14, 1.0e-6]));
    let settings = SensitivitySettings { corrector, ..SensitivitySettings::default() };
    let mut solver =
        SensitivitySolver::new(system, &settings, 0.0, &[1.0, 0.0, 0.0], &[0.0; 9], &options)
            .expect("the example's settings are valid");
    let (mut lines, mut rows) = (Vec::new(), Vec::new());
    let row = |v: &[f64]| -> String {
        v.iter().map(|x| format!("{:>12} ", c_exponential(*x, 4))).collect()
    };
    let mut tout = 0.4;
    for _ in 0..12 {
        let step = solver.advance(tout, Task::Normal).expect("the example runs");
        let stats = solver.stats();
        lines.push(format!(
            "{} {:>2}  {} {:>5}",
            c_exponential(step.t, 3),
            stats.last_order,
            c_exponential(stats.last_step, 3),
            stats.steps
        ));
        lines.push(format!("                  Solution       {}", row(solver.state())));
        for j in 0..3 {
            let s = row(solver.sensitivity(j));
            lines.push(format!("                  Sensitivity {}  {s}", j + 1));
        }
        rows.push((step.t, solver.state().to_vec(), solver.sensitivities().to_vec()));
        tout *= 10.0;
    }
    let stats = solver.stats();
    Replay {
        lines,
        rows,
        steps: stats.steps,
        rhs_evals: stats.rhs_evals,
        jac_evals: stats.jac_evals,
        sens_rhs_evals: solver.sensitivity_stats().rhs_evals,
    }
}

/// The numbers printed on a line (after its label).
fn numbers(line: &str) -> Vec<&str> {
    line.split_whitespace().filter(|w| w.contains('e') && w.parse::<f64>().is_ok()).collect()
}

/// How many units of its last printed digit (the 5th significant one of `%12.4e`) the printed
/// number `ours` is from `theirs`.
fn units_apart(ours: &str, theirs: &str) -> f64 {
    let exponent: i32 = theirs.split_once('e').and_then(|(_, e)| e.parse().ok()).expect("%e");
    let (a, b): (f64, f64) = (ours.parse().expect("a number"), theirs.parse().expect("a number"));
    ((a - b) / 10f64.powi(exponent - 4)).abs()
}

/// Replays the example with `corrector` against the shipped output `file`: the header lines
/// (t, order, last step, steps) exactly, every printed y and s_j to within `slack` units of
/// its last printed digit, and the final counts exactly.
fn assert_reproduces(corrector: SensitivityCorrector, file: &str, slack: f64) {
    let out = expected(file);
    let run = replay(Robertson::example(), corrector);
    let expected_lines = printed_lines(&out);
    assert_eq!(run.lines.len(), expected_lines.len(), "number of printed lines");
    let mut off_by_one = 0;
    for (ours, theirs) in run.lines.iter().zip(&expected_lines) {
        if ours.trim_end() == theirs.trim_end() {
            continue;
        }
        let (o, e) = (numbers(ours), numbers(theirs));
        let values_line = ours.contains("Solution") || ours.contains("Sensitivity");
        let label = |l: &str| l.split_whitespace().take(2).collect::<Vec<_>>().join(" ");
        let close = values_line
            && label(ours) == label(theirs)
            && o.len() == e.len()
            && o.iter().zip(&e).all(|(a, b)| units_apart(a, b) <= slack);
        assert!(close, "{file}:\n ours:   {ours}\n theirs: {theirs}");
        off_by_one += 1;
    }
    println!("{file}: {off_by_one} of {} lines within {slack} unit(s) of the last digit, the rest identical", run.lines.len());
    assert_eq!(run.steps as f64, counter(&out, "Steps"), "steps");
    assert_eq!(run.rhs_evals as f64, counter(&out, "RHS fn evals"), "RHS evaluations");
    assert_eq!(run.jac_evals as f64, counter(&out, "Jac fn evals"), "Jacobian evaluations");
    assert_eq!(run.sens_rhs_evals as f64, counter(&out, "Sens fn evals"), "sensitivity RHS");
}

#[test]
fn cvodes_reproduces_cvs_roberts_fsa_dns_simultaneous() {
    assert_reproduces(
        SensitivityCorrector::Simultaneous,
        "cvsRoberts_FSA_dns_-sensi_sim_t.out",
        0.0,
    );
}

/// The shipped stg1 output was printed on LLNL's machine: its last block (t = 4e10) differs in
/// the last digit of four numbers from what the C example prints when built here against
/// Debian's own libsundials_cvodes (`gcc cvsRoberts_FSA_dns.c -lsundials_cvodes
/// -lsundials_nvecserial -lsundials_sunmatrixdense -lsundials_sunlinsoldense -lm`, then
/// `./a.out -sensi stg1 t`), and the wrapper prints exactly what that build prints. Hence one
/// unit of slack in the last digit; every other line is identical.
#[test]
fn cvodes_reproduces_cvs_roberts_fsa_dns_staggered1() {
    assert_reproduces(
        SensitivityCorrector::Staggered1,
        "cvsRoberts_FSA_dns_-sensi_stg1_t.out",
        1.0,
    );
}

/// The largest difference between two replays, in units of the example's tolerances
/// (rtol·|x| + atol, with atol_i/p̄_j for s_j as the estimated tolerances give).
fn worst_difference(a: &Replay, b: &Replay) -> f64 {
    let atol = [1.0e-8, 1.0e-14, 1.0e-6];
    let p = Robertson::example().p;
    let mut worst: f64 = 0.0;
    for ((t, y, s), (t2, y2, s2)) in a.rows.iter().zip(&b.rows) {
        assert_eq!(t, t2);
        for i in 0..3 {
            worst = worst.max((y[i] - y2[i]).abs() / (1e-4 * y[i].abs() + atol[i]));
            for (j, pj) in p.iter().enumerate() {
                let k = j * 3 + i;
                worst = worst.max((s[k] - s2[k]).abs() / (1e-4 * s[k].abs() + atol[i] / pj));
            }
        }
    }
    worst
}

/// The staggered corrector (no shipped output) and the wrapper's own sensitivity right-hand
/// side (the dense J·s_j + ∂f/∂p_j, which rounds row 2 differently from the example's `fS`
/// and so takes other steps after t ≈ 400) against the example's simultaneous run: all are
/// accurate to the example's tolerances, so they agree within a few of them.
#[test]
fn staggered_and_the_dense_product_agree_with_the_example() {
    let reference = replay(Robertson::example(), SensitivityCorrector::Simultaneous);
    for (name, run) in [
        ("staggered", replay(Robertson::example(), SensitivityCorrector::Staggered)),
        ("dense J·s", replay(Robertson::generic(), SensitivityCorrector::Simultaneous)),
        ("dense J·s, staggered", replay(Robertson::generic(), SensitivityCorrector::Staggered)),
    ] {
        let worst = worst_difference(&reference, &run);
        println!("{name}: worst difference {worst:.2} tolerances");
        assert!(worst < 10.0, "{name} differs from the example by {worst} tolerances");
    }
}

// ---------------------------------------------------------------------------------------------
// Central differences.

/// Central differences of `run` (y at the output times) in each parameter, of fourth order
/// (y(p − 2h) − 8 y(p − h) + 8 y(p + h) − y(p + 2h))/(12 h) with h = `h_rel`·|p_j|: per
/// output time, column-major as the solver's sensitivities.
fn central_differences(
    p: &[f64],
    h_rel: f64,
    run: impl Fn(&[f64]) -> Vec<Vec<f64>>,
) -> Vec<Vec<f64>> {
    let shifted = |j: usize, steps: f64| {
        let mut q = p.to_vec();
        q[j] += steps * h_rel * p[j].abs();
        run(&q)
    };
    let (outputs, n) = {
        let base = run(p);
        (base.len(), base[0].len())
    };
    let mut cd = vec![vec![0.0; n * p.len()]; outputs];
    for j in 0..p.len() {
        let h = h_rel * p[j].abs();
        let [m2, m1, p1, p2] = [-2.0, -1.0, 1.0, 2.0].map(|steps| shifted(j, steps));
        for (k, out) in cd.iter_mut().enumerate() {
            for i in 0..n {
                out[j * n + i] =
                    (m2[k][i] - 8.0 * m1[k][i] + 8.0 * p1[k][i] - p2[k][i]) / (12.0 * h);
            }
        }
    }
    cd
}

/// The largest relative difference |s − cd|/max(|s|, |cd|) over every entry and output time,
/// and where. `zeros` lists the entries (j·n + i) that are identically zero (∂y_i/∂p_j = 0 for
/// every t: a parameter that cannot move that component); central differences give them their
/// rounding noise, so instead of a relative difference the solver's value must be zero to
/// within 1e-12 there.
fn worst_relative(s: &[Vec<f64>], cd: &[Vec<f64>], n: usize, zeros: &[usize]) -> (f64, String) {
    let mut worst = (0.0, String::new());
    for (k, (a, b)) in s.iter().zip(cd).enumerate() {
        for (e, (x, y)) in a.iter().zip(b).enumerate() {
            let rel = if zeros.contains(&e) {
                x.abs() / 1.0e-12 * 1.0e-6
            } else {
                (x - y).abs() / x.abs().max(y.abs())
            };
            if rel > worst.0 {
                worst =
                    (rel, format!("output {k}, ∂y_{}/∂p_{}: {x:e} against {y:e}", e % n, e / n));
            }
        }
    }
    worst
}

const ROBERTSON_TIMES: [f64; 8] = [0.4, 4.0, 40.0, 400.0, 4.0e3, 4.0e4, 4.0e5, 4.0e6];

/// Robertson's y at [`ROBERTSON_TIMES`] by plain CVODE at rtol 1e-13 with the rates `p` (at
/// 1e-12 or 1e-11 second-order differences with h = 1e-4·p_j carried up to 1e-5 of the runs'
/// error).
fn robertson_y(p: &[f64]) -> Vec<Vec<f64>> {
    let mut system = Robertson::generic();
    system.set_params(p);
    let options = Options::new(1.0e-13, Tolerance::Scalar(1.0e-30));
    let mut solver =
        Solver::cvode(system, CvodeSettings::default(), 0.0, &[1.0, 0.0, 0.0], &options)
            .expect("valid settings");
    ROBERTSON_TIMES
        .iter()
        .map(|t| {
            solver.advance(*t, Task::Normal).expect("Robertson runs");
            solver.state().to_vec()
        })
        .collect()
}

/// Robertson's sensitivities at [`ROBERTSON_TIMES`] through the wrapper's dense J·s_j + ∂f/∂p_j.
fn robertson_s(corrector: SensitivityCorrector) -> Vec<Vec<f64>> {
    let options = Options::new(1.0e-10, Tolerance::Scalar(1.0e-30));
    let settings = SensitivitySettings { corrector, ..SensitivitySettings::default() };
    let mut solver = SensitivitySolver::new(
        Robertson::generic(),
        &settings,
        0.0,
        &[1.0, 0.0, 0.0],
        &[0.0; 9],
        &options,
    )
    .expect("valid settings");
    ROBERTSON_TIMES
        .iter()
        .map(|t| {
            solver.advance(*t, Task::Normal).expect("Robertson runs");
            solver.sensitivities().to_vec()
        })
        .collect()
}

#[test]
fn robertson_sensitivities_equal_central_differences() {
    let cd = central_differences(&Robertson::example().p, 1.0e-3, robertson_y);
    for corrector in [SensitivityCorrector::Simultaneous, SensitivityCorrector::Staggered] {
        let (worst, at) = worst_relative(&robertson_s(corrector), &cd, 3, &[]);
        println!("Robertson, {corrector:?}: worst relative difference {worst:.2e} ({at})");
        assert!(worst < 1.0e-6, "{corrector:?}: {worst:e} at {at}");
    }
}

/// A stiff friction block with rate-and-state friction (ageing law) driven at a load-point
/// velocity that steps: y = (μ, ln θ), p = (a, b, d_c, k, μ0), V0 = 1 µm/s,
/// μ = μ0 + a ln(V/V0) + b ln(V0 θ/d_c), dμ/dt = k (V_lp − V), dθ/dt = 1 − V θ/d_c. With
/// a = 0.005, b = 0.008, d_c = 10 µm and k = 0.1 per µm (330 k_c) the machine's rate k V/a is
/// 200 times the state's V/d_c at 10 µm/s. A test system defined here.
#[derive(Debug, Clone)]
struct FrictionBlock {
    p: [f64; 5],
    v_lp: f64,
}

impl FrictionBlock {
    const P: [f64; 5] = [0.005, 0.008, 10.0, 0.1, 0.6];

    /// Slip rate V and ln(V/V0) = z at y.
    fn velocity(&self, y: &[f64]) -> (f64, f64) {
        let [a, b, d_c, _, mu0] = self.p;
        let z = (y[0] - mu0 - b * ((1.0 / d_c).ln() + y[1])) / a;
        (z.exp(), z)
    }

    /// The steady state sliding at `v` and its sensitivities (column-major 2 × 5).
    fn steady(&self, v: f64) -> ([f64; 2], Vec<f64>) {
        let [a, b, d_c, _, mu0] = self.p;
        let l = v.ln();
        let y = [mu0 + (a - b) * l, (d_c / v).ln()];
        //       ∂/∂a        ∂/∂b        ∂/∂d_c          ∂/∂k        ∂/∂μ0
        let s = vec![l, 0.0, -l, 0.0, 0.0, 1.0 / d_c, 0.0, 0.0, 1.0, 0.0];
        (y, s)
    }
}

impl OdeSystem for FrictionBlock {
    fn dim(&self) -> usize {
        2
    }

    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let (v, _) = self.velocity(y);
        dydt[0] = self.p[3] * (self.v_lp - v);
        dydt[1] = (-y[1]).exp() - v / self.p[2];
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let [a, b, d_c, k, _] = self.p;
        let (v, _) = self.velocity(y);
        jac.set(0, 0, -k * v / a);
        jac.set(0, 1, k * b * v / a);
        jac.set(1, 0, -v / (a * d_c));
        jac.set(1, 1, -(-y[1]).exp() + b * v / (a * d_c));
    }
}

impl ParametricSystem for FrictionBlock {
    fn n_params(&self) -> usize {
        5
    }

    fn params(&self) -> Vec<f64> {
        self.p.to_vec()
    }

    fn set_params(&mut self, p: &[f64]) {
        self.p.copy_from_slice(p);
    }

    fn param_jacobian(&self, _t: f64, y: &[f64], dfdp: &mut JacobianMatrix<'_>) {
        let [a, b, d_c, k, _] = self.p;
        let (v, z) = self.velocity(y);
        // ∂z/∂p for (a, b, d_c, k, μ0).
        let dz = [-z / a, -((1.0 / d_c).ln() + y[1]) / a, b / (a * d_c), 0.0, -1.0 / a];
        for (j, dzj) in dz.iter().enumerate() {
            dfdp.set(0, j, -k * v * dzj);
            dfdp.set(1, j, -v / d_c * dzj);
        }
        dfdp.set(0, 3, self.v_lp - v);
        dfdp.set(1, 2, -v / d_c * dz[2] + v / (d_c * d_c));
    }
}

/// The load point: 3 µm/s before t = 0 (the start is steady there), 10 µm/s on (0, 5], then
/// 1 µm/s on (5, 25]; outputs on both sides of the step at t = 5, within the transients (the
/// sensitivities that decay to zero at steady state are still well above the differences'
/// noise).
const BLOCK_SEGMENTS: [(f64, f64); 2] = [(5.0, 10.0), (25.0, 1.0)];
const BLOCK_TIMES: [f64; 8] = [0.5, 2.0, 5.0, 5.5, 7.0, 10.0, 15.0, 25.0];

/// y at [`BLOCK_TIMES`] by plain CVODE at rtol 1e-13 with the parameters `p`, a new solver
/// per segment (started where the last ended).
fn block_y(p: &[f64]) -> Vec<Vec<f64>> {
    let mut system = FrictionBlock { p: FrictionBlock::P, v_lp: 3.0 };
    system.set_params(p);
    let (y, _) = system.steady(3.0);
    let mut y = y.to_vec();
    let (mut t0, mut out) = (0.0, Vec::new());
    for (t_end, v_lp) in BLOCK_SEGMENTS {
        let system = FrictionBlock { v_lp, ..system.clone() };
        let mut options = Options::new(1.0e-13, Tolerance::Scalar(1.0e-15));
        options.stop_time = Some(t_end);
        let mut solver = Solver::cvode(system, CvodeSettings::default(), t0, &y, &options)
            .expect("valid settings");
        for t in BLOCK_TIMES.iter().filter(|t| **t > t0 && **t <= t_end) {
            solver.advance(*t, Task::Normal).expect("the block runs");
            out.push(solver.state().to_vec());
        }
        (t0, y) = (t_end, solver.state().to_vec());
    }
    out
}

/// The sensitivities at [`BLOCK_TIMES`] through the wrapper, restarted at the step with
/// `reinit_with` (y and s go on; only V_lp changes).
fn block_s(corrector: SensitivityCorrector) -> Vec<Vec<f64>> {
    let system = FrictionBlock { p: FrictionBlock::P, v_lp: BLOCK_SEGMENTS[0].1 };
    let (y0, s0) = system.steady(3.0);
    let mut options = Options::new(1.0e-10, Tolerance::Scalar(1.0e-13));
    options.stop_time = Some(BLOCK_SEGMENTS[0].0);
    let settings = SensitivitySettings { corrector, ..SensitivitySettings::default() };
    let mut solver =
        SensitivitySolver::new(system, &settings, 0.0, &y0, &s0, &options).expect("valid settings");
    let mut out = Vec::new();
    let mut t0 = 0.0;
    for (segment, (t_end, v_lp)) in BLOCK_SEGMENTS.into_iter().enumerate() {
        if segment > 0 {
            let (y, s) = (solver.state().to_vec(), solver.sensitivities().to_vec());
            solver.reinit_with(t0, &y, &s, |system| system.v_lp = v_lp).expect("a valid restart");
            solver.set_stop_time(t_end).expect("a valid stop time");
        }
        for t in BLOCK_TIMES.iter().filter(|t| **t > t0 && **t <= t_end) {
            solver.advance(*t, Task::Normal).expect("the block runs");
            out.push(solver.sensitivities().to_vec());
        }
        t0 = t_end;
    }
    assert_eq!(solver.stats().reinits, 1);
    out
}

#[test]
fn friction_block_sensitivities_equal_central_differences_across_a_velocity_step() {
    // μ hardly depends on k while the block follows the load point (∂μ/∂k·k/μ ≈ 8e-6 at
    // t = 2), so the differences need a large step to rise above the runs' own error (with
    // h = 1e-4·k they miss ∂μ/∂k by 4e-5, with 1e-3·k by 2e-6); the fourth-order formula
    // keeps the truncation error of h = 1e-2·p_j near (1e-2)^4.
    let cd = central_differences(&FrictionBlock::P, 1.0e-2, block_y);
    for corrector in [SensitivityCorrector::Simultaneous, SensitivityCorrector::Staggered] {
        let (worst, at) = worst_relative(&block_s(corrector), &cd, 2, &[9]);
        // ∂ln θ/∂μ0 = 0: μ0 shifts μ and leaves V, hence θ, alone.
        println!("friction block, {corrector:?}: worst relative difference {worst:.2e} ({at})");
        assert!(worst < 1.0e-6, "{corrector:?}: {worst:e} at {at}");
    }
}

// ---------------------------------------------------------------------------------------------
// Failures are typed errors.

/// Robertson whose ∂f/∂p turns bad after `t_bad`: non-finite, or a panic.
#[derive(Debug, Clone)]
struct Faulty {
    inner: Robertson,
    t_bad: f64,
    panic: bool,
    jacobian: bool,
}

impl OdeSystem for Faulty {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.inner.rhs(t, y, dydt);
    }
    fn has_jacobian(&self) -> bool {
        self.jacobian
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.inner.jacobian(t, y, jac);
    }
}

impl ParametricSystem for Faulty {
    fn n_params(&self) -> usize {
        3
    }
    fn params(&self) -> Vec<f64> {
        self.inner.params()
    }
    fn set_params(&mut self, p: &[f64]) {
        self.inner.set_params(p);
    }
    fn param_jacobian(&self, t: f64, y: &[f64], dfdp: &mut JacobianMatrix<'_>) {
        self.inner.param_jacobian(t, y, dfdp);
        if t > self.t_bad {
            assert!(!self.panic, "∂f/∂p refuses t = {t}");
            dfdp.set(0, 0, f64::NAN);
        }
    }
}

fn faulty(
    t_bad: f64,
    panic: bool,
    jacobian: bool,
) -> Result<SensitivitySolver<Faulty>, SolverError> {
    let system = Faulty { inner: Robertson::generic(), t_bad, panic, jacobian };
    let options = Options::new(1.0e-6, Tolerance::Scalar(1.0e-12));
    SensitivitySolver::new(
        system,
        &SensitivitySettings::default(),
        0.0,
        &[1.0, 0.0, 0.0],
        &[0.0; 9],
        &options,
    )
}

#[test]
fn bad_input_is_an_invalid_input_error() {
    let e = faulty(1.0, false, false).expect_err("no Jacobian");
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    assert!(e.message.contains("analytic Jacobian"), "{e}");

    let options = Options::new(1.0e-6, Tolerance::Scalar(1.0e-12));
    let settings = SensitivitySettings::default();
    let y0 = [1.0, 0.0, 0.0];
    let e = SensitivitySolver::new(Robertson::generic(), &settings, 0.0, &y0, &[0.0; 6], &options)
        .expect_err("s0 of the wrong length");
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    assert!(e.message.contains("3 × 3"), "{e}");

    let scales =
        SensitivitySettings { param_scales: Some(vec![1.0, 0.0, 1.0]), ..settings.clone() };
    let e = SensitivitySolver::new(Robertson::generic(), &scales, 0.0, &y0, &[0.0; 9], &options)
        .expect_err("a zero parameter scale");
    assert!(e.kind == ErrorKind::InvalidInput && e.message.contains("param_scales"), "{e}");

    let tolerance = SensitivityTolerance::Scalar { rtol: 1.0e-6, atol: vec![1.0e-8; 2] };
    let bad = SensitivitySettings { tolerance, ..settings.clone() };
    let e = SensitivitySolver::new(Robertson::generic(), &bad, 0.0, &y0, &[0.0; 9], &options)
        .expect_err("two absolute tolerances for three parameters");
    assert!(e.kind == ErrorKind::InvalidInput && e.message.contains("atol"), "{e}");

    let mut solver = faulty(f64::INFINITY, false, true).expect("valid");
    solver.advance(1.0, Task::Normal).expect("runs");
    let (y, s) = (solver.state().to_vec(), solver.sensitivities().to_vec());
    let mut s_bad = s.clone();
    s_bad[4] = f64::NAN;
    let e = solver.reinit_with(1.0, &y, &s_bad, |_| panic!("not called")).expect_err("NaN in s0");
    assert!(e.kind == ErrorKind::InvalidInput && e.message.contains("∂y_1/∂p_1"), "{e}");
    solver.reinit(1.0, &y, &s).expect("a valid restart");
    solver.advance(2.0, Task::Normal).expect("goes on");
}

#[test]
fn non_finite_sensitivity_derivatives_are_a_typed_error_at_the_last_good_point() {
    let mut solver = faulty(1.0, false, true).expect("valid");
    let e = solver.advance(10.0, Task::Normal).expect_err("∂f/∂p is NaN after t = 1");
    println!("{e}");
    assert_eq!(e.kind, ErrorKind::RhsFailure, "{e}");
    assert!(e.t > 0.5 && e.t <= 1.0, "the last good point, at t = {}", e.t);
    assert!(e.message.contains("sensitivity right-hand side"), "{e}");
}

#[test]
fn a_panic_in_the_parameter_jacobian_is_a_callback_panic() {
    let mut solver = faulty(1.0, true, true).expect("valid");
    let e = solver.advance(10.0, Task::Normal).expect_err("∂f/∂p panics after t = 1");
    println!("{e}");
    assert_eq!(e.kind, ErrorKind::CallbackPanic, "{e}");
    assert!(e.message.contains("∂f/∂p refuses"), "{e}");
    assert!(e.t <= 1.0, "the last good point, at t = {}", e.t);
}
