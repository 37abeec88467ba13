//! What a problem provides to an integrator.

/// An ODE system dy/dt = f(t, y) of fixed dimension.
///
/// Requirements: `rhs` must be a pure function of `(t, y)`. Writing a non-finite value is
/// allowed: the integrator treats it as a recoverable failure and retries with a smaller step,
/// and reports a typed error if that does not help.
pub trait OdeSystem {
    /// Number of components of y.
    fn dim(&self) -> usize;

    /// Writes f(t, y) into `dydt`.
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]);

    /// Whether [`OdeSystem::jacobian`] is implemented. When false, implicit solvers build the
    /// Jacobian by finite differences.
    fn has_jacobian(&self) -> bool {
        false
    }

    /// Writes ∂f/∂y at (t, y) into `jac` (which arrives zeroed). Called only when
    /// [`OdeSystem::has_jacobian`] returns true.
    fn jacobian(&self, _t: f64, _y: &[f64], _jac: &mut JacobianMatrix<'_>) {}

    /// Whether [`OdeSystem::jacobian_derivative`] is implemented (used by variational
    /// equations; central differences of the Jacobian otherwise).
    fn has_jacobian_derivative(&self) -> bool {
        false
    }

    /// Writes ∂J/∂y_k at (t, y) into `out` (which arrives zeroed), J = ∂f/∂y. Called only
    /// when [`OdeSystem::has_jacobian_derivative`] returns true.
    fn jacobian_derivative(&self, _t: f64, _y: &[f64], _k: usize, _out: &mut JacobianMatrix<'_>) {}

    /// The size m of the blocks when the analytic Jacobian ([`OdeSystem::jacobian`]) is block
    /// diagonal with dim/m identical m × m blocks, as the Newton Jacobian of variational
    /// equations is (J on y and on each column of Φ). Radau5 then factors and solves with one
    /// block instead of the whole matrix: the same numbers (partial pivoting on such a matrix
    /// repeats the block's factorisation, and the zeros add nothing to the solves) for a
    /// fraction of the work. `None` (the default): no such structure. Radau5 checks the
    /// structure on every Jacobian and uses the whole matrix where it does not hold, so a
    /// wrong answer here costs time, never accuracy.
    fn repeated_jacobian_block(&self) -> Option<usize> {
        None
    }

    /// Whether f may have linear invariants (conserved combinations c·y, such as a mass
    /// balance) that rodas5p must keep to working accuracy. When true, each of its stage
    /// solves is refined once with a compensated residual (+43 % instructions on the
    /// 3-component friction model of docs/test-set.md; see its E5), without which a balance drifts
    /// by u·h‖J‖ relative per step. (Extrapolation always refines: its extrapolation weights
    /// amplify the stage solves' rounding.) The default is true, so that no system silently
    /// loses its invariants; return false only for a system without any whose accuracy has
    /// been shown not to depend on the refinement.
    fn has_linear_invariants(&self) -> bool {
        true
    }

    /// Whether rodas5p may solve the stages of a 3-component system without linear
    /// invariants with the explicit inverse of its iteration matrix (the adjugate over the
    /// determinant, formed once per step): a matrix–vector product per stage instead of LU
    /// substitutions with three dependent divisions, so a shorter chain of dependent
    /// operations (measured: 15 % of a noise ensemble's CPU time, issue #30), with results
    /// that differ from the LU solves' in the last bits. The default is false, which keeps
    /// every deterministic run's numbers as they are.
    fn allows_explicit_inverse(&self) -> bool {
        false
    }

    /// Whether [`OdeSystem::time_derivative`] is implemented (Rodas5P, which needs ∂f/∂t at
    /// every step of a non-autonomous system, takes a forward difference in t otherwise: one
    /// more right-hand side per step and an error ~1e-8 relative).
    fn has_time_derivative(&self) -> bool {
        false
    }

    /// Writes ∂f/∂t at (t, y) into `out`. Called only when
    /// [`OdeSystem::has_time_derivative`] returns true.
    fn time_derivative(&self, _t: f64, _y: &[f64], _out: &mut [f64]) {}
}

/// A system split as f = f_E + f_I for implicit–explicit (IMEX) methods: f_E is integrated
/// explicitly (non-stiff part), f_I implicitly (stiff part).
pub trait ImexSystem: OdeSystem {
    /// Writes the explicit (non-stiff) part f_E(t, y).
    fn rhs_explicit(&self, t: f64, y: &[f64], dydt: &mut [f64]);

    /// Writes the implicit (stiff) part f_I(t, y).
    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]);

    /// Whether [`ImexSystem::implicit_jacobian`] is implemented (finite differences otherwise).
    fn has_implicit_jacobian(&self) -> bool {
        false
    }

    /// Writes ∂f_I/∂y into `jac` (which arrives zeroed).
    fn implicit_jacobian(&self, _t: f64, _y: &[f64], _jac: &mut JacobianMatrix<'_>) {}
}

/// A dense matrix in column-major storage, as handed to a Jacobian callback: square for ∂f/∂y
/// ([`JacobianMatrix::new`]), n × n_params for ∂f/∂p ([`JacobianMatrix::rectangular`], in
/// [`ParametricSystem::param_jacobian`](super::ParametricSystem::param_jacobian)).
#[derive(Debug)]
pub struct JacobianMatrix<'a> {
    data: &'a mut [f64],
    /// Rows (and the column stride).
    n: usize,
    cols: usize,
}

impl<'a> JacobianMatrix<'a> {
    /// Wraps column-major storage of an `n`×`n` matrix.
    ///
    /// # Panics
    /// If `data.len() != n * n`.
    pub fn new(data: &'a mut [f64], n: usize) -> Self {
        assert_eq!(data.len(), n * n, "JacobianMatrix storage must hold n*n values");
        Self { data, n, cols: n }
    }

    /// Wraps column-major storage of a `rows`×`cols` matrix (entry (row, col) at
    /// `data[col * rows + row]`).
    ///
    /// # Panics
    /// If `data.len() != rows * cols`.
    pub fn rectangular(data: &'a mut [f64], rows: usize, cols: usize) -> Self {
        assert_eq!(data.len(), rows * cols, "JacobianMatrix storage must hold rows*cols values");
        Self { data, n: rows, cols }
    }

    /// Number of rows n (the dimension of a square matrix).
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of columns (n for ∂f/∂y, n_params for ∂f/∂p).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Sets entry (row, col) = ∂f_row/∂y_col (∂f_row/∂p_col in ∂f/∂p).
    pub fn set(&mut self, row: usize, col: usize, value: f64) {
        self.data[col * self.n + row] = value;
    }

    /// Entry (row, col).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.data[col * self.n + row]
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.data.iter().all(|v| v.is_finite())
    }
}

/// A vector-valued root (event) function g(t, y): writes one value per root into its last
/// argument. A root is located where a component changes sign.
pub type RootFunction = Box<dyn FnMut(f64, &[f64], &mut [f64])>;

/// Root functions and the crossing directions to report.
pub struct Roots {
    /// Number of components of g.
    pub count: usize,
    /// Per component: `+1` report only rising crossings, `-1` only falling ones, `0` both.
    /// Empty means "both" for every component.
    pub directions: Vec<i32>,
    /// The root function g(t, y).
    pub function: RootFunction,
}

impl Roots {
    /// Root functions reporting crossings in both directions.
    pub fn new(count: usize, function: impl FnMut(f64, &[f64], &mut [f64]) + 'static) -> Self {
        Self { count, directions: Vec::new(), function: Box::new(function) }
    }

    /// Restricts the reported crossing directions (one entry per component).
    pub fn with_directions(mut self, directions: Vec<i32>) -> Self {
        self.directions = directions;
        self
    }
}

impl std::fmt::Debug for Roots {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Roots")
            .field("count", &self.count)
            .field("directions", &self.directions)
            .finish()
    }
}

/// Where an analytic Jacobian disagrees with central differences of the right-hand side:
/// the worst entry ([`check_jacobian`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the analytic Jacobian disagrees with central differences of f at t = {t:e}: J[{row}][{col}] = {analytic:e}, differences give {differences:e} (check OdeSystem::jacobian: entry (row, col) is ∂f_row/∂y_col)")]
pub struct JacobianMismatch {
    /// Time of the check.
    pub t: f64,
    /// Row (component of f).
    pub row: usize,
    /// Column (component of y).
    pub col: usize,
    /// The analytic entry.
    pub analytic: f64,
    /// The central difference.
    pub differences: f64,
}

/// Checks `system`'s analytic Jacobian at (t, y) against central differences of its
/// right-hand side, column by column with the step h = 1e-6·max(|y_j|, 1e-3·max|y|, 1e-150)
/// and again with h/8. An entry passes within 1e-3 of its own size plus 1e-6 of the largest
/// entry of its row (what the differences resolve); the worst failing entry is the error.
/// An entry whose two differences disagree by more than that is not resolved by differences
/// (f changes too much over h, e.g. e^w far from its usual range) and is not judged: a
/// Jacobian is blamed only on evidence. `Ok` when the system has no analytic Jacobian. 4n
/// right-hand-side calls.
pub fn check_jacobian<S: OdeSystem + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
) -> Result<(), JacobianMismatch> {
    if !system.has_jacobian() {
        return Ok(());
    }
    compare(t, y, |t, y, jac| system.jacobian(t, y, jac), |t, y, f| system.rhs(t, y, f))
}

/// [`check_jacobian`] for the implicit part of an IMEX system: ∂f_I/∂y against differences
/// of f_I.
pub fn check_implicit_jacobian<S: ImexSystem + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
) -> Result<(), JacobianMismatch> {
    if !system.has_implicit_jacobian() {
        return Ok(());
    }
    compare(
        t,
        y,
        |t, y, jac| system.implicit_jacobian(t, y, jac),
        |t, y, f| system.rhs_implicit(t, y, f),
    )
}

fn compare(
    t: f64,
    y: &[f64],
    jacobian: impl Fn(f64, &[f64], &mut JacobianMatrix<'_>),
    rhs: impl Fn(f64, &[f64], &mut [f64]),
) -> Result<(), JacobianMismatch> {
    let n = y.len();
    let mut storage = vec![0.0; n * n];
    let mut jac = JacobianMatrix::new(&mut storage, n);
    jacobian(t, y, &mut jac);
    let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let step = |col: usize| 1e-6 * y[col].abs().max(1e-3 * scale).max(1e-150);
    let differences = central_differences(t, y, &rhs, step);
    let finer = central_differences(t, y, &rhs, |col| step(col) / 8.0);
    let mut worst: Option<(f64, JacobianMismatch)> = None;
    for row in 0..n {
        let entry = |col: usize| (jac.get(row, col), differences[col * n + row]);
        let row_scale = (0..n).map(|c| entry(c).0.abs().max(entry(c).1.abs())).fold(0.0, f64::max);
        let resolution = |a: f64, b: f64| 1e-3 * a.abs().max(b.abs()) + 1e-6 * row_scale;
        for col in 0..n {
            let (analytic, fd) = entry(col);
            let fd_finer = finer[col * n + row];
            if !(analytic.is_finite() && fd.is_finite() && fd_finer.is_finite()) {
                continue;
            }
            if (fd - fd_finer).abs() > resolution(fd, fd_finer) {
                continue;
            }
            let excess = (analytic - fd).abs() / (resolution(analytic, fd) + f64::MIN_POSITIVE);
            if excess > 1.0 && worst.as_ref().is_none_or(|(w, _)| excess > *w) {
                let mismatch = JacobianMismatch { t, row, col, analytic, differences: fd };
                worst = Some((excess, mismatch));
            }
        }
    }
    worst.map_or(Ok(()), |(_, m)| Err(m))
}

/// Central differences of `rhs` at (t, y), column `col` with the step `step(col)`, column-major.
fn central_differences(
    t: f64,
    y: &[f64],
    rhs: impl Fn(f64, &[f64], &mut [f64]),
    step: impl Fn(usize) -> f64,
) -> Vec<f64> {
    let n = y.len();
    let mut differences = vec![0.0; n * n];
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    for col in 0..n {
        let h = step(col);
        let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
        yp[col] += h;
        ym[col] -= h;
        rhs(t, &yp, &mut fp);
        rhs(t, &ym, &mut fm);
        for row in 0..n {
            differences[col * n + row] = (fp[row] - fm[row]) / (yp[col] - ym[col]);
        }
    }
    differences
}

/// The kinds of failure a wrong Jacobian shows as: the Newton iteration stalls, the steps
/// shrink.
fn may_be_jacobian(kind: &super::ErrorKind) -> bool {
    use super::ErrorKind::*;
    matches!(kind, TooMuchWork | ErrorTestFailures | ConvergenceFailures | StepUnderflow)
}

/// Appends to `error` the Jacobian's disagreement with differences at the failure point,
/// where the failure is one a wrong Jacobian causes and the check finds one.
pub(crate) fn jacobian_hint<S: OdeSystem + ?Sized>(
    system: &S,
    mut error: super::SolverError,
) -> super::SolverError {
    if may_be_jacobian(&error.kind) && error.state.len() == system.dim() {
        if let Err(m) = check_jacobian(system, error.t, &error.state) {
            error.message.push_str(&format!(" [likely cause: {m}]"));
        }
    }
    error
}

/// [`jacobian_hint`] for the implicit part of an IMEX system.
pub(crate) fn implicit_jacobian_hint<S: ImexSystem + ?Sized>(
    system: &S,
    mut error: super::SolverError,
) -> super::SolverError {
    if may_be_jacobian(&error.kind) && error.state.len() == system.dim() {
        if let Err(m) = check_implicit_jacobian(system, error.t, &error.state) {
            error.message.push_str(&format!(" [likely cause: {m}]"));
        }
    }
    error
}

/// The system's analytic Jacobian beside central differences of its right-hand side at y (t = 0),
/// with step `step(y_col)` per column, as (row, col, analytic, difference): the raw table a
/// model's unit tests judge with their own bounds ([`check_jacobian`] gives a verdict instead).
pub fn jacobian_against_differences(
    system: &impl OdeSystem,
    y: &[f64],
    step: impl Fn(f64) -> f64,
) -> Vec<(usize, usize, f64, f64)> {
    let n = system.dim();
    let mut storage = vec![0.0; n * n];
    let mut jac = JacobianMatrix::new(&mut storage, n);
    system.jacobian(0.0, y, &mut jac);
    let mut out = Vec::with_capacity(n * n);
    for col in 0..n {
        let h = step(y[col]);
        let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
        yp[col] += h;
        ym[col] -= h;
        let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
        system.rhs(0.0, &yp, &mut fp);
        system.rhs(0.0, &ym, &mut fm);
        for row in 0..n {
            out.push((row, col, jac.get(row, col), (fp[row] - fm[row]) / (2.0 * h)));
        }
    }
    out
}
