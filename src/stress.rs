//! The numerical stress suite: a grid of γ, ξ, ε (below and above threshold), tolerances,
//! starts far off the cycle, every method, and the state laws with and without radiation
//! damping.
//!
//! Each cell has an [`Expectation`]. In the physical region (clearly above threshold, a stiff
//! method, rtol 1e-4 … 1e-12, any start) the equations have a limit cycle, so the cell must
//! find it: a typed error or an unconverged run is a failure there, not an honest pass. Every
//! other cell is an expected limit with its reason (explicit methods at large γ, rtol below
//! what doubles allow, near or below threshold), where a finite report or a typed error is
//! fine. Everywhere a panic or a non-finite number is a defect, and where several methods find
//! a periodic orbit their periods must agree within 1e3·rtol.

use serde::Serialize;
use std::collections::BTreeMap;
use stickslip::analysis::cycle::CycleStatus;
use stickslip::analysis::hopf;
use stickslip::model::{Drr, DrrParams, Friction, StateLaw};
use stickslip::scene::{self, Method};
use stickslip::{engine, parallel};

/// One cell of the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cell {
    /// γ; +∞ for the quasi-dynamic model (no inertia, the limit γ → ∞ at fixed η > 0).
    pub gamma: f64,
    /// ξ.
    pub xi: f64,
    /// ε.
    pub epsilon: f64,
    /// rtol (atol = rtol/100).
    pub rtol: f64,
    /// Start: (u, v, θ); None for the default start on the slow manifold.
    pub start: Option<[f64; 3]>,
    /// The method.
    pub method: Method,
    /// The state law.
    pub state_law: StateLaw,
    /// Radiation damping η.
    pub eta: f64,
}

/// What a cell must give.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Expectation {
    /// The physical region: a converged limit cycle.
    Cycle,
    /// Below threshold (ε < 0.95 ε_c), a stiff method: the oscillation dies out (fixed point)
    /// or the run is honestly unconverged within the grid's time limit.
    Decay,
    /// An expected limit: a finite report or a typed error, for the reason given.
    Limit(&'static str),
}

impl Cell {
    /// What this cell must give (see the module documentation).
    pub fn expectation(&self) -> Expectation {
        let model = if self.is_quasi_dynamic() {
            DrrParams::quasi_dynamic(self.xi, self.epsilon, self.eta, Friction::Log)
        } else {
            DrrParams::new(self.gamma, self.xi, self.epsilon, Friction::Log)
        };
        let params = DrrParams { state_law: self.state_law, eta: self.eta, ..model };
        let eps_c = hopf::epsilon_c(&Drr::new(params));
        if !self.method.is_stiff() {
            Expectation::Limit("explicit method: its steps are stability-limited to ~1/γ², too much work at large γ")
        } else if !in_physical_region(self.method) {
            Expectation::Limit(
                "IMEX: only the plate drive is explicit; not part of the physical-region guarantee",
            )
        } else if self.rtol < 1e-12 {
            Expectation::Limit(
                "rtol below 1e-12: not attainable in double precision over the cycle's 17 decades",
            )
        } else if self.eta > 0.0 && self.below_damping_floor() {
            Expectation::Limit("arkode-dirk with radiation damping below rtol 1e-8: SDIRK-5-3-4 (stage order 1) falls to order 2 on the quasi-static slip that damping creates, so its steps grow as rtol^(-1/2), ~400 k per cycle at rtol 1e-10, beyond the grid's 2 M steps (docs/robustness.md)")
        } else if self.gamma < 10.0 {
            Expectation::Limit(
                "γ < 10: no relaxation oscillation; transients of thousands of time units",
            )
        } else if self.epsilon > 1.05 * eps_c {
            Expectation::Cycle
        } else if self.epsilon < 0.95 * eps_c {
            Expectation::Decay
        } else {
            Expectation::Limit("within 5 % of threshold: transients longer than the grid's limits")
        }
    }
}

impl Cell {
    /// Whether rtol is below the method's radiation-damping floor (the engine's method table,
    /// `damping_rtol_floor`).
    fn below_damping_floor(&self) -> bool {
        engine::EngineSettings::of(self.method)
            .damping_rtol_floor
            .is_some_and(|floor| self.rtol < floor)
    }

    /// A cell of the paper's model: the slip law without radiation damping.
    fn paper(
        gamma: f64,
        xi: f64,
        epsilon: f64,
        rtol: f64,
        start: Option<[f64; 3]>,
        method: Method,
    ) -> Self {
        Cell { gamma, xi, epsilon, rtol, start, method, state_law: StateLaw::Slip, eta: 0.0 }
    }

    /// Whether the cell runs the quasi-dynamic model (γ = +∞).
    pub fn is_quasi_dynamic(&self) -> bool {
        self.gamma == f64::INFINITY
    }

    /// A one-line key naming the cell, as in a known-failures file (the state law and η are
    /// named only when they are not the paper's slip law without damping).
    pub fn key(&self) -> String {
        let start = self
            .start
            .map_or("manifold".to_string(), |[u, v, t]| format!("u={u:e},v={v:e},theta={t:e}"));
        format!(
            "gamma={:e} xi={} epsilon={} rtol={:e} start={start} method={}{}",
            self.gamma,
            self.xi,
            self.epsilon,
            self.rtol,
            self.method.name(),
            self.law_key()
        )
    }

    /// " state_law=… eta=…" for a model other than the paper's, "" otherwise.
    fn law_key(&self) -> String {
        if self.state_law == StateLaw::Slip && self.eta == 0.0 {
            String::new()
        } else {
            format!(" state_law={} eta={:e}", self.state_law.name(), self.eta)
        }
    }
}

/// Physical cells (and below-threshold cells) that fail, against a list of known failures:
/// the new failures (not on the list) and the fixed ones (on the list but no longer failing).
/// Both must be empty for a run to pass, so the list only ever shrinks as failures are fixed
/// and no failure is ever counted as a pass.
pub fn against_known(
    cells: &[Cell],
    outcomes: &[Outcome],
    known: &str,
) -> (Vec<String>, Vec<String>) {
    let known: std::collections::BTreeSet<&str> =
        known.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')).collect();
    let failing: std::collections::BTreeSet<String> = cells
        .iter()
        .zip(outcomes)
        .filter(|(cell, outcome)| is_failure(cell, outcome))
        .map(|(cell, _)| cell.key())
        .collect();
    let new = failing.iter().filter(|k| !known.contains(k.as_str())).cloned().collect();
    let all: std::collections::BTreeSet<String> = cells.iter().map(Cell::key).collect();
    let fixed = known
        .iter()
        .filter(|k| all.contains(**k) && !failing.contains(**k))
        .map(|k| k.to_string())
        .collect();
    (new, fixed)
}

/// Whether a cell's outcome fails its expectation (see [`Expectation`]).
fn is_failure(cell: &Cell, outcome: &Outcome) -> bool {
    match cell.expectation() {
        Expectation::Cycle => !matches!(
            outcome,
            Outcome::Ok { status: CycleStatus::Periodic | CycleStatus::PeriodN, .. }
        ),
        Expectation::Decay => !matches!(
            outcome,
            Outcome::Ok { status: CycleStatus::FixedPoint | CycleStatus::NotConverged, .. }
        ),
        Expectation::Limit(_) => false,
    }
}

/// How a cell ended.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// A finite report: the cycle status and period (if periodic).
    Ok {
        /// The cycle analysis' status.
        status: CycleStatus,
        /// Period, when periodic.
        period: Option<f64>,
    },
    /// A typed error.
    Error {
        /// Its kind.
        kind: String,
        /// Its message.
        message: String,
    },
    /// A panic (a defect).
    Panic {
        /// The panic message.
        message: String,
    },
}

/// Which grid to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Grid {
    /// The small grid that CI runs (far-off starts, every method, ε/ξ up to 25 at γ = 1e8).
    Quick,
    /// The full grid of docs/robustness.md.
    Full,
    /// The physical region of issue #13: every stiff method from the default start at rtol
    /// 1e-6, 1e-8, 1e-10 over γ = 10 … 1e12 and (ξ, ε) with 1.05 ξ < ε ≤ 25 ξ.
    Physical,
    /// The physical region under the ageing and PRZ laws, without and with radiation damping
    /// (η = 0.1): the stiff methods of `physical` from the default start at rtol 1e-6 and
    /// 1e-10 over γ = 10, 1e2, 1e4, … 1e12 and (ξ, ε) with ξ ∈ {0.2, 0.7, 2}, ε ∈ {1, 2, 3, 5,
    /// 10}, ε above 1.05 ε_c(η) and at most 25 ξ.
    Laws,
}

/// The stiff methods the physical region guarantees (issue #13).
fn physical_methods() -> impl Iterator<Item = Method> {
    Method::ALL.into_iter().map(|(_, m)| m).filter(|m| in_physical_region(*m))
}

/// Whether the physical-region guarantee covers `method` (issue #13): the stiff methods,
/// except arkode-imex, whose explicit plate drive is not part of it. One `match` without a
/// wildcard arm, so that a new method does not compile until it is placed.
const fn in_physical_region(method: Method) -> bool {
    match method {
        Method::CvodeBdf
        | Method::ArkodeDirk
        | Method::Radau5
        | Method::Rodas5p
        | Method::Extrapolation => true,
        Method::CvodeAdams | Method::ArkodeImex | Method::ArkodeErk => false,
    }
}
/// The models besides the paper's that the `laws` grid and the quick grid cover: (state law, η).
const OTHER_LAWS: [(StateLaw, f64); 4] =
    [(StateLaw::Ageing, 0.0), (StateLaw::Ageing, 0.1), (StateLaw::Prz, 0.0), (StateLaw::Prz, 0.1)];

/// The cells of a grid.
pub fn grid(kind: Grid) -> Vec<Cell> {
    match kind {
        Grid::Physical => return physical_grid(),
        Grid::Laws => return laws_grid(),
        Grid::Quick | Grid::Full => {}
    }
    let (gammas, xis, epsilons, rtols): (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) =
        if kind == Grid::Quick {
            (vec![1.0, 1e4, 1e8], vec![0.2, 2.0], vec![0.1, 3.0, 5.0], vec![1e-4, 1e-10])
        } else {
            (
                vec![1.0, 10.0, 1e2, 1e3, 1e4, 1e5, 1e6, 1e8, 1e10, 1e12],
                vec![0.2, 0.7, 2.0],
                vec![0.1, 0.72, 1.0, 3.0],
                vec![1e-3, 1e-6, 1e-8, 1e-10, 1e-12, 1e-13],
            )
        };
    let starts: Vec<Option<[f64; 3]>> =
        vec![None, Some([0.0, 1e-30, 0.0]), Some([0.0, 1e30, 0.0]), Some([1e3, 1.0, -1e3])];
    let mut cells = Vec::new();
    for &gamma in &gammas {
        for &xi in &xis {
            for &epsilon in &epsilons {
                for &rtol in &rtols {
                    for start in &starts {
                        for (_, method) in Method::ALL {
                            cells.push(Cell::paper(gamma, xi, epsilon, rtol, *start, method));
                        }
                    }
                }
            }
        }
    }
    if kind == Grid::Quick {
        cells.extend(quick_law_cells());
        cells.extend(quick_quasi_dynamic_cells());
    }
    cells
}

/// The quick grid's other laws: ageing and PRZ, η = 0 and 0.1, at γ = 1e4 and 1e8 and two
/// points far above threshold, from the slow manifold and from v = 1e30, with cvode-bdf,
/// radau5 and rodas5p at rtol 1e-6 (every one a physical cell).
fn quick_law_cells() -> Vec<Cell> {
    let mut cells = Vec::new();
    for (state_law, eta) in OTHER_LAWS {
        for gamma in [1e4, 1e8] {
            cells.extend(far_above_threshold(state_law, eta, gamma, 1e30));
        }
    }
    cells
}

/// The quick grid's quasi-dynamic cells (key `gamma=inf`): every state law with η = 0.1, two
/// points far above threshold (ε_c = ξ + η), from the slow manifold and from v = 1e-30 (u then
/// from the force balance: a stick of ~70/ξ time units), with cvode-bdf, radau5 and rodas5p at
/// rtol 1e-6. Not from v = 1e30: the force balance would put u at −ηv/ξ ≈ −1e29, a transient
/// of 1e29 time units.
fn quick_quasi_dynamic_cells() -> Vec<Cell> {
    let mut cells = Vec::new();
    for state_law in [StateLaw::Slip, StateLaw::Ageing, StateLaw::Prz] {
        cells.extend(far_above_threshold(state_law, 0.1, f64::INFINITY, 1e-30));
    }
    cells
}

/// The quick grid's cells of one law and γ: two points far above threshold, from the slow
/// manifold and from v = `v_start`, with cvode-bdf, radau5 and rodas5p at rtol 1e-6.
fn far_above_threshold(state_law: StateLaw, eta: f64, gamma: f64, v_start: f64) -> Vec<Cell> {
    let mut cells = Vec::new();
    for (xi, epsilon) in [(0.2, 3.0), (2.0, 5.0)] {
        for start in [None, Some([0.0, v_start, 0.0])] {
            for method in [Method::CvodeBdf, Method::Radau5, Method::Rodas5p] {
                let rtol = 1e-6;
                cells.push(Cell { gamma, xi, epsilon, rtol, start, method, state_law, eta });
            }
        }
    }
    cells
}

/// The `laws` grid (see [`Grid::Laws`]).
fn laws_grid() -> Vec<Cell> {
    let mut cells = Vec::new();
    for (state_law, eta) in OTHER_LAWS {
        for k in [1, 2, 4, 6, 8, 10, 12] {
            let gamma = 10f64.powi(k);
            for xi in [0.2, 0.7, 2.0] {
                for epsilon in [1.0, 2.0, 3.0, 5.0, 10.0] {
                    for rtol in [1e-6, 1e-10] {
                        for method in physical_methods() {
                            let cell = Cell {
                                gamma,
                                xi,
                                epsilon,
                                rtol,
                                start: None,
                                method,
                                state_law,
                                eta,
                            };
                            // A point of the physical region (where radau5 must find the cycle);
                            // a method's own limit there stays in the grid as its own row.
                            let reference = Cell { method: Method::Radau5, ..cell };
                            if epsilon <= 25.0 * xi && reference.expectation() == Expectation::Cycle
                            {
                                cells.push(cell);
                            }
                        }
                    }
                }
            }
        }
    }
    cells
}

/// The physical-region grid (see [`Grid::Physical`]).
fn physical_grid() -> Vec<Cell> {
    let mut cells = Vec::new();
    for k in 1..=12 {
        let gamma = 10f64.powi(k);
        for xi in [0.1, 0.2, 0.5, 0.7, 1.0, 2.0, 5.0] {
            for epsilon in [0.5, 1.0, 2.0, 3.0, 5.0, 10.0] {
                if epsilon <= 1.05 * xi || epsilon > 25.0 * xi {
                    continue;
                }
                for rtol in [1e-6, 1e-8, 1e-10] {
                    for method in physical_methods() {
                        cells.push(Cell::paper(gamma, xi, epsilon, rtol, None, method));
                    }
                }
            }
        }
    }
    cells
}

fn scene_text(cell: &Cell) -> String {
    // A physical cell must find its cycle: room for slow transients and long periods far from
    // threshold (~900 at ε/ξ = 25). Elsewhere the grid's own limits bound the work.
    let (time, max_steps) = if cell.expectation() == Expectation::Cycle {
        (30_000.0, 2_000_000)
    } else {
        (3000.0, 200_000)
    };
    // A far-off start adds its own transient: launched at v0 the block slides ~v0/γ, and the
    // stick that follows lasts about as long as the plate takes to catch up (u0 likewise).
    let transient = cell.start.map_or(0.0, |[u, v, _]| u.abs() + v / cell.gamma);
    let max_time = time + 10.0 * transient;
    let initial = cell.start.map_or(String::new(), |[u, v, theta]| {
        if cell.is_quasi_dynamic() {
            // Without inertia the force balance gives u from v and θ.
            format!(r#""initial": {{"v": {v:e}, "theta": {theta:e}}},"#)
        } else {
            format!(r#""initial": {{"u": {u:e}, "v": {v:e}, "theta": {theta:e}}},"#)
        }
    });
    let inertia = if cell.is_quasi_dynamic() {
        r#""inertia": false"#.to_string()
    } else {
        format!(r#""gamma": {:e}"#, cell.gamma)
    };
    format!(
        r#"{{"name": "stress", "model": {{{inertia}, "xi": {}, "epsilon": {}, "state_law": "{}", "radiation_damping": {:e}}}, {initial}
            "solver": {{"method": "{}", "rtol": {:e}, "atol": {:e}}},
            "analyses": [{{"cycle": {{"max_cycles": 60, "max_time": {max_time:e}, "max_steps": {max_steps}}}}}]}}"#,
        cell.xi,
        cell.epsilon,
        cell.state_law.name(),
        cell.eta,
        cell.method.name(),
        cell.rtol,
        cell.rtol * 1e-2
    )
}

/// Runs one cell, catching panics.
pub fn run_cell(cell: &Cell) -> Outcome {
    let text = scene_text(cell);
    let outcome = std::panic::catch_unwind(|| {
        let scene = scene::parse(&text, "stress")
            .map_err(|e| ("invalid_scene".to_string(), e.to_string()))?;
        engine::run(&scene, engine::RunOptions::default()).map_err(|e| (e.label(), e.to_string()))
    });
    match outcome {
        Ok(Ok(report)) => {
            let c = report.cycle.expect("the stress scene asks for the cycle");
            Outcome::Ok { status: c.status, period: c.values.map(|v| v.main.period) }
        }
        Ok(Err((kind, message))) => Outcome::Error { kind, message },
        Err(payload) => Outcome::Panic {
            message: payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default(),
        },
    }
}

/// Counts over the grid.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Summary {
    /// Cells run.
    pub cells: usize,
    /// Cells of the physical region ([`Expectation::Cycle`]).
    pub physical: usize,
    /// Physical cells that found a converged cycle.
    pub physical_ok: usize,
    /// Physical cells that did not (typed errors and unconverged runs): failures.
    pub physical_failures: usize,
    /// Below-threshold cells that ended in a typed error or a cycle: failures.
    pub decay_failures: usize,
    /// Cells of each expected limit (reason → cells, of which typed errors).
    pub limits: BTreeMap<String, (usize, usize)>,
    /// Cells with a finite report.
    pub ok: usize,
    /// Typed errors by kind.
    pub typed_errors: BTreeMap<String, usize>,
    /// Panics (defects).
    pub panics: usize,
    /// Reports refused for a non-finite number (defects).
    pub nan: usize,
    /// Parameter points where periodic methods disagree on the period beyond tolerance.
    pub inconsistent: usize,
    /// The defective cells (panics, non-finite numbers) and inconsistent points, described.
    pub defects: Vec<String>,
    /// The cells that fail their expectation (physical cells without a cycle, below-threshold
    /// cells that do not decay), described.
    pub failures: Vec<String>,
}

/// Runs the grid on `threads` threads; `progress` is called after each cell.
pub fn run(
    cells: &[Cell],
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (Vec<Outcome>, Summary) {
    let outcomes = parallel::map(cells.len(), threads, progress, |i| run_cell(&cells[i]));
    let summary = summarise(cells, &outcomes);
    (outcomes, summary)
}

/// An outcome in a few words, for a defect line.
fn describe(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Ok { status, period } => format!("{status:?}, period {period:?}"),
        Outcome::Error { kind, message } => format!("{kind}: {message}"),
        Outcome::Panic { message } => format!("panic: {message}"),
    }
}

fn summarise(cells: &[Cell], outcomes: &[Outcome]) -> Summary {
    let mut s = Summary { cells: cells.len(), ..Summary::default() };
    let mut periods: BTreeMap<String, Vec<(Method, f64)>> = BTreeMap::new();
    for (cell, outcome) in cells.iter().zip(outcomes) {
        let failure = |what: &str| format!("{what}: {}: {}", cell.key(), describe(outcome));
        match cell.expectation() {
            Expectation::Cycle => {
                s.physical += 1;
                if is_failure(cell, outcome) {
                    s.physical_failures += 1;
                    s.failures.push(failure("physical cell without a cycle"));
                } else {
                    s.physical_ok += 1;
                }
            }
            Expectation::Decay => {
                if is_failure(cell, outcome) {
                    s.decay_failures += 1;
                    s.failures.push(failure("below threshold, no decay"));
                }
            }
            Expectation::Limit(reason) => {
                let entry = s.limits.entry(reason.to_string()).or_default();
                entry.0 += 1;
                entry.1 += usize::from(matches!(outcome, Outcome::Error { .. }));
            }
        }
        match outcome {
            Outcome::Ok { period, .. } => {
                s.ok += 1;
                if let Some(p) = period {
                    let key = format!(
                        "γ={:e} ξ={} ε={} rtol={:e} start={:?}{}",
                        cell.gamma,
                        cell.xi,
                        cell.epsilon,
                        cell.rtol,
                        cell.start,
                        cell.law_key()
                    );
                    periods.entry(key).or_default().push((cell.method, *p));
                }
            }
            Outcome::Error { kind, message } => {
                if kind == "NonFinite" {
                    s.nan += 1;
                    s.defects.push(format!("{cell:?}: {message}"));
                }
                *s.typed_errors.entry(kind.clone()).or_default() += 1;
            }
            Outcome::Panic { message } => {
                s.panics += 1;
                s.defects.push(format!("{cell:?}: panic: {message}"));
            }
        }
    }
    for (point, found) in periods {
        let rtol: f64 = point
            .split("rtol=")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|r| r.parse().ok())
            .unwrap_or(1e-8);
        let allowed = (1e3 * rtol).clamp(1e-7, 0.05);
        let (lo, hi) =
            found.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), (_, p)| (lo.min(*p), hi.max(*p)));
        if found.len() > 1 && (hi - lo) > allowed * hi {
            s.inconsistent += 1;
            s.defects.push(format!(
                "{point}: periods {found:?} differ by {:.1e} (allowed {allowed:.0e})",
                (hi - lo) / hi
            ));
        }
    }
    s
}

/// The full table as Markdown: outcomes per γ and method (ok cells by cycle status, typed
/// errors by kind), then per start and per state law (with η), then the summary.
pub fn table(cells: &[Cell], outcomes: &[Outcome], summary: &Summary) -> String {
    let label = |o: &Outcome| match o {
        Outcome::Ok { status, .. } => format!(
            "ok:{}",
            serde_json::to_value(status)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default()
        ),
        Outcome::Error { kind, .. } => kind.clone(),
        Outcome::Panic { .. } => "PANIC".into(),
    };
    let mut columns: Vec<String> = outcomes.iter().map(label).collect();
    columns.sort();
    columns.dedup();
    let mut rows: BTreeMap<(u64, usize), BTreeMap<String, usize>> = BTreeMap::new();
    let method_index = |m: Method| Method::ALL.iter().position(|(_, x)| *x == m).unwrap_or(0);
    for (cell, outcome) in cells.iter().zip(outcomes) {
        *rows
            .entry((cell.gamma.to_bits(), method_index(cell.method)))
            .or_default()
            .entry(label(outcome))
            .or_default() += 1;
    }
    let mut out = format!(
        "| γ | method | {} |\n|---|---|{}\n",
        columns.join(" | "),
        "---|".repeat(columns.len())
    );
    let mut keys: Vec<&(u64, usize)> = rows.keys().collect();
    keys.sort_by(|a, b| f64::from_bits(a.0).total_cmp(&f64::from_bits(b.0)).then(a.1.cmp(&b.1)));
    for key in keys {
        let counts = &rows[key];
        let cells: Vec<String> = columns
            .iter()
            .map(|c| counts.get(c).map_or(String::new(), |n| n.to_string()))
            .collect();
        out += &format!(
            "| {:e} | {} | {} |\n",
            f64::from_bits(key.0),
            Method::ALL[key.1].0,
            cells.join(" | ")
        );
    }
    let start_of = |cell: &Cell| {
        cell.start.map_or("on the slow manifold (v = 0.5)".to_string(), |[u, v, t]| {
            format!("u = {u:e}, v = {v:e}, θ = {t:e}")
        })
    };
    out += &counts_by("start", cells, outcomes, &columns, &label, start_of);
    out += &counts_by("state law", cells, outcomes, &columns, &label, |cell| {
        format!("{}, η = {}", cell.state_law.name(), cell.eta)
    });
    out += &format!(
        "\nCells {}, ok {}, typed errors {:?}, panics {}, non-finite {}, inconsistent {}.\n\
         Physical region: {} cells, {} converged cycles, {} failures. Below threshold: {} failures.\n",
        summary.cells,
        summary.ok,
        summary.typed_errors,
        summary.panics,
        summary.nan,
        summary.inconsistent,
        summary.physical,
        summary.physical_ok,
        summary.physical_failures,
        summary.decay_failures
    );
    out += "\n| expected limit | cells | typed errors |\n|---|---|---|\n";
    for (reason, (n, errors)) in &summary.limits {
        out += &format!("| {reason} | {n} | {errors} |\n");
    }
    out
}

/// A Markdown table of outcome counts (columns) per group of cells (`group_of`, rows).
fn counts_by(
    title: &str,
    cells: &[Cell],
    outcomes: &[Outcome],
    columns: &[String],
    label: &impl Fn(&Outcome) -> String,
    group_of: impl Fn(&Cell) -> String,
) -> String {
    let mut groups: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    for (cell, outcome) in cells.iter().zip(outcomes) {
        *groups.entry(group_of(cell)).or_default().entry(label(outcome)).or_default() += 1;
    }
    let mut out =
        format!("\n| {title} | {} |\n|---|{}\n", columns.join(" | "), "---|".repeat(columns.len()));
    for (group, counts) in groups {
        let row: Vec<String> = columns
            .iter()
            .map(|c| counts.get(c).map_or(String::new(), |n| n.to_string()))
            .collect();
        out += &format!("| {group} | {} |\n", row.join(" | "));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_laws_grid_keeps_a_methods_limits_as_their_own_rows() {
        let cells = grid(Grid::Laws);
        assert_eq!(cells.len(), 3360);
        let limits: Vec<&Cell> =
            cells.iter().filter(|c| matches!(c.expectation(), Expectation::Limit(_))).collect();
        assert!(!limits.is_empty());
        assert!(
            limits.iter().all(|c| c.eta > 0.0 && c.below_damping_floor()),
            "{}",
            limits[0].key()
        );
    }

    #[test]
    fn every_cell_of_every_grid_is_a_valid_scene() {
        for kind in [Grid::Quick, Grid::Full, Grid::Physical, Grid::Laws] {
            for cell in grid(kind) {
                let text = scene_text(&cell);
                let scene = scene::parse(&text, "stress")
                    .unwrap_or_else(|e| panic!("{}: {e}\n{text}", cell.key()));
                assert_eq!(scene.params.inertia, !cell.is_quasi_dynamic(), "{}", cell.key());
            }
        }
    }
}
