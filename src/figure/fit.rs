//! The fit figure (`stickslip fit … --figure FILE.svg`): the friction record with the fitted
//! model against time, and the residuals below. Every curve is drawn from at most
//! [`MAX_DRAWN`] points (the fit itself uses every sample): consecutive samples are binned and
//! each bin's lowest and highest points kept, so the drawing keeps the record's envelope and
//! spikes while the file stays small.

use super::{Axis, Figure, Marker, Panel, Series, Style};
use stickslip::analysis::lab_fit::FitOutcome;

/// Most points drawn per curve.
pub const MAX_DRAWN: usize = 1500;

/// Two panels: μ data (points) and fit (line) against time; residual (μ_fit − μ_data, the
/// fit's r_i) against time.
pub fn data_fit_and_residuals(name: &str, outcome: &FitOutcome) -> Figure {
    let s = &outcome.series;
    let t0 = s.t[0];
    let t: Vec<f64> = s.t.iter().map(|t| t - t0).collect();
    let residual: Vec<f64> = s.mu_fit.iter().zip(&s.mu_data).map(|(f, d)| f - d).collect();
    let time = || Axis::linear(format!("t − {t0}")).unit("s");
    let drawn = |y: &[f64]| decimate(&t, y, MAX_DRAWN);
    let (td, data) = drawn(&s.mu_data);
    let (tf, fit) = drawn(&s.mu_fit);
    let (tr, residual) = drawn(&residual);
    let data = Panel::new("friction record and fit", time(), Axis::linear("μ").dimensionless())
        .series(Series::new("data", td, data, Style::markers(0, Marker::Circle).marker_size(2.0)))
        .series(Series::new("fit", tf, fit, Style::line(1)));
    let residuals = Panel::new(
        format!("residuals (rms {:.2e})", outcome.residual_rms),
        time(),
        Axis::linear("μ_{fit} − μ_{data}").dimensionless(),
    )
    .series(Series::new("", tr, residual, Style::markers(0, Marker::Circle).marker_size(2.0)));
    Figure::new(name).panel(data).panel(residuals).columns(1)
}

/// At most `max` points of (t, y): all of them if they fit, else for each of max/2 runs of
/// consecutive samples its lowest and highest point, in time order.
fn decimate(t: &[f64], y: &[f64], max: usize) -> (Vec<f64>, Vec<f64>) {
    if y.len() <= max {
        return (t.to_vec(), y.to_vec());
    }
    let bins = max / 2;
    let (mut td, mut yd) = (Vec::with_capacity(max), Vec::with_capacity(max));
    for b in 0..bins {
        let (lo, hi) = (b * y.len() / bins, (b + 1) * y.len() / bins);
        let (mut imin, mut imax) = (lo, lo);
        for i in lo..hi {
            if y[i] < y[imin] {
                imin = i;
            }
            if y[i] > y[imax] {
                imax = i;
            }
        }
        for i in if imin <= imax { [imin, imax] } else { [imax, imin] } {
            td.push(t[i]);
            yd.push(y[i]);
        }
    }
    (td, yd)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A long record is cut to `max` points keeping its extremes; a short one is kept whole.
    #[test]
    fn decimation_keeps_the_extremes() {
        let t: Vec<f64> = (0..10_000).map(f64::from).collect();
        let mut y: Vec<f64> = t.iter().map(|t| (t / 300.0).sin()).collect();
        y[4321] = 5.0;
        let (td, yd) = decimate(&t, &y, 1000);
        assert_eq!(td.len(), 1000);
        assert!(yd.contains(&5.0) && td.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(decimate(&t[..10], &y[..10], 1000).0.len(), 10);
    }
}
