//! A minimal, self-contained SVG writer for the work–precision diagrams: panels with log10
//! axes (decade ticks), one polyline with markers per series, and a shared legend.
//! (stickslip's plotting module src/figure/ is on another branch; this bench does not depend
//! on it.)

use std::fmt::Write;

/// One series: a name, a colour, solid (ours) or dashed (peers), and its points (x, y > 0).
pub struct Series {
    pub name: String,
    pub colour: &'static str,
    pub dashed: bool,
    pub points: Vec<(f64, f64)>,
}

/// One panel: a title, axis labels and its series.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

const PANEL_W: f64 = 520.0;
const PANEL_H: f64 = 380.0;
const MARGIN_L: f64 = 70.0;
const MARGIN_B: f64 = 50.0;
const MARGIN_T: f64 = 30.0;
const MARGIN_R: f64 = 20.0;
const LEGEND_W: f64 = 230.0;

/// Distinct colours, cycled.
pub const COLOURS: [&str; 12] =
    ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f", "#000000", "#6b8e23"];

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The decade range [10^lo, 10^hi] covering the positive values.
fn decades(values: impl Iterator<Item = f64>) -> (i32, i32) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        return (0, 1);
    }
    let (lo, hi) = (lo.floor() as i32, hi.ceil() as i32);
    (lo, if hi > lo { hi } else { lo + 1 })
}

/// Writes the panels in a grid of `columns`, with a legend of every series name on the right.
pub fn write(title: &str, panels: &[Panel], columns: usize) -> String {
    let rows = panels.len().div_ceil(columns);
    let width = columns as f64 * PANEL_W + LEGEND_W;
    let height = rows as f64 * PANEL_H + 40.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{}" y="22" font-size="16" text-anchor="middle">{}</text>"#, width / 2.0, escape(title));
    for (k, panel) in panels.iter().enumerate() {
        let (ox, oy) = ((k % columns) as f64 * PANEL_W, 40.0 + (k / columns) as f64 * PANEL_H);
        panel_svg(&mut s, panel, ox, oy);
    }
    // Legend: every series name once, in order of first appearance.
    let mut seen: Vec<(&str, &str, bool)> = Vec::new();
    for series in panels.iter().flat_map(|p| &p.series) {
        if !seen.iter().any(|(n, _, _)| *n == series.name) {
            seen.push((&series.name, series.colour, series.dashed));
        }
    }
    let lx = columns as f64 * PANEL_W + 10.0;
    for (i, (name, colour, dashed)) in seen.iter().enumerate() {
        let y = 60.0 + 18.0 * i as f64;
        let dash = if *dashed { r#" stroke-dasharray="5,3""# } else { "" };
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="{y}" x2="{}" y2="{y}" stroke="{colour}" stroke-width="2"{dash}/><circle cx="{}" cy="{y}" r="3" fill="{colour}"/><text x="{}" y="{}">{}</text>"#,
            lx + 30.0,
            lx + 15.0,
            lx + 36.0,
            y + 4.0,
            escape(name)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn panel_svg(s: &mut String, p: &Panel, ox: f64, oy: f64) {
    let points = || p.series.iter().flat_map(|c| c.points.iter());
    let (x0, x1) = decades(points().map(|q| q.0));
    let (y0, y1) = decades(points().map(|q| q.1));
    let (left, right) = (ox + MARGIN_L, ox + PANEL_W - MARGIN_R);
    let (top, bottom) = (oy + MARGIN_T, oy + PANEL_H - MARGIN_B);
    let px = |x: f64| left + (x.log10() - x0 as f64) / (x1 - x0) as f64 * (right - left);
    let py = |y: f64| bottom - (y.log10() - y0 as f64) / (y1 - y0) as f64 * (bottom - top);
    let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle" font-size="13">{}</text>"#, (left + right) / 2.0, oy + 18.0, escape(&p.title));
    let _ = writeln!(s, r##"<rect x="{left}" y="{top}" width="{}" height="{}" fill="none" stroke="#444"/>"##, right - left, bottom - top);
    for d in x0..=x1 {
        let x = px(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{x}" y1="{top}" x2="{x}" y2="{bottom}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">1e{d}</text>"##,
            bottom + 16.0
        );
    }
    for d in y0..=y1 {
        let y = py(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{left}" y1="{y}" x2="{right}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e{d}</text>"##,
            left - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#, (left + right) / 2.0, bottom + 36.0, escape(&p.x_label));
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle" transform="rotate(-90 {} {})">{}</text>"#,
        ox + 18.0,
        (top + bottom) / 2.0,
        ox + 18.0,
        (top + bottom) / 2.0,
        escape(&p.y_label)
    );
    for c in &p.series {
        let pts: Vec<String> =
            c.points.iter().filter(|q| q.0 > 0.0 && q.1 > 0.0).map(|q| format!("{:.1},{:.1}", px(q.0), py(q.1))).collect();
        if pts.is_empty() {
            continue;
        }
        let dash = if c.dashed { r#" stroke-dasharray="5,3""# } else { "" };
        let _ = writeln!(s, r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.5"{dash}/>"#, pts.join(" "), c.colour);
        for q in &pts {
            let (x, y) = q.split_once(',').unwrap_or(("0", "0"));
            let _ = writeln!(s, r#"<circle cx="{x}" cy="{y}" r="2.5" fill="{}"/>"#, c.colour);
        }
    }
}
