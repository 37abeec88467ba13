//! `stickslip reproduce`: the paper's figures remade from our numerics, the JSON reports
//! behind them, and a summary (Markdown and HTML) that sets each claim of the paper beside
//! our value with a verdict.
//!
//! The registry [`FIGURES`] lists the figures made today, one module each; [`PENDING`] lists
//! the paper's figures that wait for analyses being built elsewhere (they are printed in the
//! summary as "not yet reproduced", never drawn with placeholder data). Adding a figure: a
//! module with a `make(&Context) -> Result<Output, ReproduceError>`, an entry in `FIGURES`,
//! and its removal from `PENDING`.

pub mod cases;
pub mod fig1;
pub mod fig2;
pub mod fig3;
pub mod fig4;
pub mod fig5;
pub mod fig6;
pub mod fig7;
pub mod fig8;
pub mod fig9;
pub mod laws;
pub mod noise_cases;
pub mod summary;

use crate::figure::FigureError;
use std::path::{Path, PathBuf};
use stickslip::engine::RunError;
pub use summary::{Row, Summary};

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    /// A scene built by reproduce did not validate (a bug: the message says where).
    #[error("bad scene: {0}")]
    Scene(String),
    /// A run failed.
    #[error("scene {case}: {source}")]
    Run {
        /// The scene's name.
        case: String,
        /// The engine's error.
        source: RunError,
    },
    /// A run ended without what the figure needs (e.g. no periodic cycle).
    #[error("{0}")]
    Missing(String),
    /// The figure could not be drawn or written.
    #[error(transparent)]
    Figure(#[from] FigureError),
    /// An output file could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
}

/// Progress of a reproduce run (the CLI prints it on stderr).
pub trait Progress: Sync {
    /// Figure `index` (1-based) of `total` starts.
    fn stage(&self, index: usize, total: usize, what: &str);
    /// Within a figure: `done` of `total` runs finished.
    fn points(&self, done: usize, total: usize);
}

/// Progress that reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn stage(&self, _: usize, _: usize, _: &str) {}
    fn points(&self, _: usize, _: usize) {}
}

/// What every figure gets: where to write, how many threads, and whether to run the reduced
/// (test) version with fewer curve points.
pub struct Context<'a> {
    /// Output directory (exists).
    pub out: PathBuf,
    /// Worker threads for the runs of one figure.
    pub threads: usize,
    /// Fewer points per curve and fewer γ (for tests); the figures are otherwise the same.
    pub reduced: bool,
    /// Progress sink.
    pub progress: &'a dyn Progress,
}

impl Context<'_> {
    /// Writes `text` to `name` under the output directory (atomically); returns `name`.
    pub fn write(&self, name: &str, text: &str) -> Result<String, ReproduceError> {
        let path = self.out.join(name);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)
                .map_err(|source| ReproduceError::Io { path: dir.display().to_string(), source })?;
        }
        stickslip::report::write_atomic(&path, text)
            .map_err(|source| ReproduceError::Io { path: path.display().to_string(), source })?;
        Ok(name.to_string())
    }

    /// Writes a figure as `name` (SVG) under the output directory; returns `name`.
    pub fn write_figure(
        &self,
        name: &str,
        figure: &crate::figure::Figure,
    ) -> Result<String, ReproduceError> {
        let svg = figure.to_svg()?;
        self.write(name, &svg)
    }

    /// Writes a JSON value as `reports/name` and returns that path.
    pub fn write_json(
        &self,
        name: &str,
        value: &impl serde::Serialize,
    ) -> Result<String, ReproduceError> {
        let text = serde_json::to_string_pretty(value).expect("reproduce outputs serialise");
        self.write(&format!("reports/{name}"), &text)
    }
}

/// What a figure produced.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Output {
    /// Files written (relative to the output directory): SVG first, then JSON reports.
    pub files: Vec<String>,
    /// The paper's claims this figure tests, with our values and verdicts.
    pub claims: Vec<Row>,
    /// Remarks for the summary (e.g. points of a curve that did not converge).
    pub notes: Vec<String>,
}

/// A figure of the paper that `reproduce` makes.
pub struct Entry {
    /// Short id, also the SVG file's stem (e.g. "fig1").
    pub id: &'static str,
    /// What the paper's figure shows.
    pub what: &'static str,
    /// Makes it.
    pub make: fn(&Context) -> Result<Output, ReproduceError>,
}

/// The figures made today, in the paper's order, then the comparisons beyond the paper.
pub const FIGURES: [Entry; 10] = [
    Entry { id: "fig1", what: "Fig. 1: the limit cycle at γ = 10³, ξ = 0.7, ε = 0.72 (a); its period against ε (b) and against log₁₀ γ (c)", make: fig1::make },
    Entry { id: "fig2", what: "Fig. 2: the slip in fast units T = γ(t − t_c), V = v/γ, for several γ", make: fig2::make },
    Entry { id: "fig3", what: "Fig. 3: v/γ of the 2D flow on the slow manifold and of the 3D flow near t_c (a, b); the (u, θ) plane with the cycle, the 2D flow, the matching curves, the zero-acceleration lines and the adiabatic limit (c)", make: fig3::make },
    Entry { id: "fig4", what: "Fig. 4: the trajectory leaving and landing on the slow manifold ξu + θ + ln v = 0", make: fig4::make },
    Entry { id: "fig5", what: "Fig. 5: the Jacobian's eigenvalues (the paper's Lyapunov exponents) along the stick: the fast one (a), real (b) and imaginary (c) parts of the slow pair, with the quasi-static formula", make: fig5::make },
    Entry { id: "fig6", what: "Fig. 6: response to noise: σ_v against v before the event; correlation functions Γ_u(t, t − t′)", make: fig6::make },
    Entry { id: "fig7", what: "Fig. 7: correlation time before the event: saddle-node (slowing-down), stick-slip (speed-up), van der Pol", make: fig7::make },
    Entry { id: "fig8", what: "Fig. 8: power-law friction g_α(v) = (v^α − 1)/α against ln v", make: fig8::make },
    Entry { id: "fig9", what: "Fig. 9: correlation time before the event with power-law friction (α = 0.15, γ = 10³, ε = 0.78, ξ = 0.7)", make: fig9::make },
    Entry { id: "laws", what: "Beyond the paper: the slip, ageing and PRZ state laws: period against γ (ξ = 0.8, ε = 1) with the reference tables, and one cycle of each", make: laws::make },
];

/// A figure of the paper not reproduced yet, and what it waits for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Pending {
    /// The paper's figure.
    pub figure: &'static str,
    /// What it shows.
    pub what: &'static str,
    /// The analysis it needs.
    pub waiting_for: &'static str,
}

/// The paper's figures still to come (listed in the summary as "not yet reproduced").
pub const PENDING: [Pending; 0] = [];

/// Runs every figure into `out` (created if needed), then writes `summary.json`,
/// `summary.md` and `summary.html`. A figure that fails is reported in the summary (and in
/// the returned [`Summary`]) and the others still run.
pub fn run(
    out: &Path,
    threads: usize,
    reduced: bool,
    progress: &dyn Progress,
) -> Result<Summary, ReproduceError> {
    std::fs::create_dir_all(out)
        .map_err(|source| ReproduceError::Io { path: out.display().to_string(), source })?;
    let ctx = Context { out: out.to_path_buf(), threads: threads.max(1), reduced, progress };
    let started = std::time::Instant::now();
    let mut results = Vec::new();
    for (i, entry) in FIGURES.iter().enumerate() {
        progress.stage(i + 1, FIGURES.len(), entry.what);
        let t = std::time::Instant::now();
        let outcome = (entry.make)(&ctx);
        results.push(summary::FigureResult::new(entry, outcome, t.elapsed().as_secs_f64()));
    }
    let summary = Summary::new(results, threads, reduced, started.elapsed().as_secs_f64());
    ctx.write(
        "summary.json",
        &serde_json::to_string_pretty(&summary).expect("the summary serialises"),
    )?;
    ctx.write("summary.md", &summary.markdown())?;
    ctx.write("summary.html", &summary.html())?;
    Ok(summary)
}
