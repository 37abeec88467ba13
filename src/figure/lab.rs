//! The lab figure: friction against load-point displacement (`stickslip run LAB-SCENE
//! --figure FILE.svg`).

use super::{Axis, Figure, Panel, Series, Style};
use stickslip::report::lab::LabReport;

/// μ against the load-point displacement x_lp, one line over the whole record.
pub fn friction_against_displacement(report: &LabReport) -> Figure {
    let col = |name: &str| {
        let i = report.series.columns.iter().position(|c| *c == name).expect("a lab column");
        report.series.rows.iter().map(|r| r[i]).collect::<Vec<f64>>()
    };
    let panel = Panel::new(
        "friction against load-point displacement",
        Axis::linear("x_{lp}").unit("µm"),
        Axis::linear("μ").dimensionless(),
    )
    .series(Series::new("μ", col("x_lp"), col("mu"), Style::line(0)));
    Figure::new(&report.name).panel(panel)
}
