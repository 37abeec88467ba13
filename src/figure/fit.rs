//! The fit figure (`stickslip fit … --figure FILE.svg`): the friction record with the fitted
//! model against time, and the residuals below.

use super::{Axis, Figure, Marker, Panel, Series, Style};
use stickslip::analysis::lab_fit::FitOutcome;

/// Two panels: μ data (points) and fit (line) against time; residual against time.
pub fn data_fit_and_residuals(name: &str, outcome: &FitOutcome) -> Figure {
    let s = &outcome.series;
    let t0 = s.t[0];
    let t: Vec<f64> = s.t.iter().map(|t| t - t0).collect();
    let residual: Vec<f64> = s.mu_fit.iter().zip(&s.mu_data).map(|(f, d)| d - f).collect();
    let time = || Axis::linear(format!("t − {t0}")).unit("s");
    let data = Panel::new("friction record and fit", time(), Axis::linear("μ").dimensionless())
        .series(Series::new(
            "data",
            t.clone(),
            s.mu_data.clone(),
            Style::markers(0, Marker::Circle).marker_size(2.0),
        ))
        .series(Series::new("fit", t.clone(), s.mu_fit.clone(), Style::line(1)));
    let residuals = Panel::new(
        format!("residuals (rms {:.2e})", outcome.residual_rms),
        time(),
        Axis::linear("μ_{data} − μ_{fit}").dimensionless(),
    )
    .series(Series::new("", t, residual, Style::markers(0, Marker::Circle).marker_size(2.0)));
    Figure::new(name).panel(data).panel(residuals).columns(1)
}
