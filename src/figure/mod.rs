//! Figures as SVG, without dependencies: multi-panel figures of line and marker series on
//! linear or log10 axes with "nice" ticks, labelled axes with units, legends placed where they
//! hide the least data, reference lines and text notes.
//!
//! ```
//! use stickslip_cli::figure::{Axis, Figure, Panel, Series, Style};
//! let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
//! let v: Vec<f64> = t.iter().map(|t| (-t).exp()).collect();
//! let panel = Panel::new("(a) decay", Axis::linear("t").unit("D_{c}/v_{0}"), Axis::log10("v").unit("v_{0}"))
//!     .series(Series::new("e^{−t}", t, v, Style::line(0)));
//! let svg = Figure::new("Example").panel(panel).to_svg().unwrap();
//! assert!(svg.contains("<svg"));
//! ```
//!
//! Text is plain `<text>` in a generic sans-serif font, so every SVG viewer renders it; labels
//! accept `_{sub}` and `^{sup}` markup ([`text`]). Data are never silently dropped: a
//! non-finite value, a value ≤ 0 on a log axis, x and y of different lengths, an empty panel
//! or an axis without a unit is a [`FigureError`] naming the panel and the series.

pub mod fit;
pub mod lab;
pub mod layout;
pub mod panel;
pub mod scale;
pub mod series;
pub mod svg;
pub mod text;

pub use layout::Figure;
pub use panel::{Anchor, Axis, Band, LegendPlace, Note, Panel, RefLine};
pub use scale::ScaleKind;
pub use series::{Dash, Marker, Series, Style};

/// The font list of every figure: common sans-serif fonts, then the generic family.
pub const FONT_FAMILY: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// A panel has no series with points.
    #[error("panel {panel:?} has no data to draw (add a series with at least one point)")]
    Empty {
        /// Panel title.
        panel: String,
    },
    /// x and y of a series differ in length.
    #[error("panel {panel:?}, series {series:?}: {x} x values but {y} y values")]
    LengthMismatch {
        /// Panel title.
        panel: String,
        /// Series label.
        series: String,
        /// Number of x values.
        x: usize,
        /// Number of y values.
        y: usize,
    },
    /// A value is NaN or infinite.
    #[error("panel {panel:?}, series {series:?}: point {index} ({x}, {y}) is not finite; filter or fix the data")]
    NonFinite {
        /// Panel title.
        panel: String,
        /// Series label.
        series: String,
        /// Index of the point.
        index: usize,
        /// Its x.
        x: f64,
        /// Its y.
        y: f64,
    },
    /// A value ≤ 0 on a log axis.
    #[error("panel {panel:?}, series {series:?}: {axis} value {value} of point {index} is ≤ 0 on a log axis; use a linear axis or plot a positive quantity")]
    NonPositiveOnLog {
        /// Panel title.
        panel: String,
        /// Series label.
        series: String,
        /// "x" or "y".
        axis: &'static str,
        /// Index of the point.
        index: usize,
        /// The value.
        value: f64,
    },
    /// An axis says nothing about its unit.
    #[error("panel {panel:?}: the {axis} axis {label:?} has no unit; call .unit(\"…\") or .dimensionless()")]
    MissingUnit {
        /// Panel title.
        panel: String,
        /// "x" or "y".
        axis: &'static str,
        /// Axis label.
        label: String,
    },
    /// An explicit axis range is empty, reversed, not finite, or ≤ 0 on a log axis.
    #[error("panel {panel:?}: the {axis} range [{lo}, {hi}] is not usable (need finite lo < hi, and lo > 0 on a log axis)")]
    BadRange {
        /// Panel title.
        panel: String,
        /// "x" or "y".
        axis: &'static str,
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// Writing the file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
}
