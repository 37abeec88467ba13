//! From the rows to the committed results: the machine description, time at matched accuracy
//! (log time interpolated against log error on each method's Pareto front), the tables, the
//! stated targets, the SVG diagrams, data/work-precision/results.json and
//! docs/work-precision.md (whose hand-written notes, after NOTES_MARKER, are kept).

use crate::peers::{self, RUST_PEERS, SCIPY_PEERS};
use crate::{protocol, Reference, Row};
use serde::Serialize;
use serde_json::{json, Value};
use std::fmt::Write;
use std::process::Command;
use stickslip::scene::Method;
use stickslip_cli::figure::{self, Axis, Dash, Figure, LegendPlace, Marker, Panel, Series, Style};

/// Everything a run of the benchmark produced (data/work-precision/results.json).
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct Results {
    /// The machine, the toolchains and the peers' versions.
    pub machine: Value,
    /// The command line of the run.
    pub command: String,
    /// Timed runs per cell at most, and the seconds of timed runs after which a cell stops.
    pub runs: usize,
    pub budget_s: f64,
    /// The start and the reference at each γ.
    pub references: Vec<Reference>,
    /// Every cell of every method, failures included.
    pub rows: Vec<Row>,
    /// The wrapper against plain C, measured in alternating rounds.
    #[serde(default)]
    pub wrapper: Vec<crate::WrapperRow>,
}

/// What is printed and written besides the raw results.
pub struct Analysis {
    /// The targets, in a few lines.
    pub summary: String,
    /// The generated part of docs/work-precision.md.
    pub markdown: String,
    /// (file name, SVG) of the diagrams.
    pub svgs: Vec<(String, String)>,
}

/// Line that separates the generated part of docs/work-precision.md from the hand-written
/// notes the runner keeps.
pub const NOTES_MARKER: &str =
    "<!-- Hand-written notes below this line are kept when the benchmark rewrites this file. -->";

/// Homemade methods (issue #6's goal is about these).
const HOMEMADE: [&str; 3] = ["radau5", "rodas5p", "extrapolation"];

fn first_line(program: &str, args: &[&str]) -> String {
    Command::new(program)
        .args(args)
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|s| s.lines().next().map(String::from))
        .unwrap_or_else(|| format!("({program} not found)"))
}

/// The 1, 5 and 15 minute load averages.
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

/// The version of `package` in benches/peers/Cargo.lock.
fn locked_version(package: &str) -> Option<String> {
    let lock = std::fs::read_to_string(peers::root().join("benches/peers/Cargo.lock")).ok()?;
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line == format!("name = \"{package}\"") {
            return lines.next()?.strip_prefix("version = ")?.trim_matches('"').to_string().into();
        }
    }
    None
}

/// The machine and toolchains.
pub fn machine() -> Value {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        cpuinfo
            .lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
            .unwrap_or_default()
    };
    let os = std::fs::read_to_string("/etc/os-release")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("PRETTY_NAME="))
                .map(|l| l[12..].trim_matches('"').to_string())
        })
        .unwrap_or_default();
    json!({
        "cpu": field("model name"),
        "cpu_mhz": field("cpu MHz"),
        "hypervisor": cpuinfo.contains("hypervisor"),
        "cores_available": std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0),
        "kernel": std::fs::read_to_string("/proc/sys/kernel/osrelease").unwrap_or_default().trim(),
        "os": os,
        "date_utc": first_line("date", &["-u", "+%Y-%m-%dT%H:%MZ"]),
        "rustc": first_line("rustc", &["-V"]),
        "cc": first_line("cc", &["--version"]),
        "sundials": stickslip::sundials::version(),
        "stickslip_commit": first_line("git", &["-C", env!("CARGO_MANIFEST_DIR"), "rev-parse", "--short", "HEAD"]),
        "diffsol": locked_version("diffsol"),
        "differential_equations": locked_version("differential-equations"),
        "load_average_start": load_average(),
    })
}

/// Method names in table order: ours (scene names), then the peers.
fn method_order() -> Vec<String> {
    let mut names: Vec<String> = Method::ALL.iter().map(|(n, _)| n.to_string()).collect();
    names.push("c-cvode-bdf".into());
    names.extend(RUST_PEERS.iter().map(|m| m.to_string()));
    names.extend(SCIPY_PEERS.iter().map(|m| format!("scipy-{}", m.to_lowercase())));
    names
}

/// Which error a diagram or table is about.
#[derive(Debug, Clone, Copy)]
enum Quantity {
    Period,
    T0,
    LnVMax,
}

impl Quantity {
    fn of(self, e: &crate::Errors) -> f64 {
        match self {
            Quantity::Period => e.period,
            Quantity::T0 => e.t0,
            Quantity::LnVMax => e.ln_v_max,
        }
    }
    fn label(self) -> &'static str {
        match self {
            Quantity::Period => "period",
            Quantity::T0 => "t0",
            Quantity::LnVMax => "ln v_max",
        }
    }
}

/// A method's successful cells at γ: (rtol, error, seconds per cycle, RHS evaluations per
/// cycle), errors below the reference's accuracy raised to it.
fn points(
    rows: &[Row],
    method: &str,
    gamma: f64,
    q: Quantity,
    floor: f64,
) -> Vec<(f64, f64, f64, Option<f64>)> {
    let mut p: Vec<_> = rows
        .iter()
        .filter(|r| r.ok && r.method == method && r.gamma == gamma)
        .filter_map(|r| {
            let e = q.of(r.errors.as_ref()?).max(floor);
            Some((
                r.rtol,
                e,
                r.time_per_cycle_s?,
                r.counts.rhs.map(|n| n as f64 / protocol::CYCLES as f64),
            ))
        })
        .collect();
    p.sort_by(|a, b| b.0.total_cmp(&a.0));
    p
}

/// Time per cycle at error `target`: log time interpolated linearly in log error between the
/// points of the method's Pareto front (no point both more accurate and cheaper). Beyond its
/// cheapest point (already more accurate than `target`) that point's time, flagged as an
/// upper bound; None below its most accurate point.
fn time_at(points: &[(f64, f64, f64, Option<f64>)], target: f64) -> Option<(f64, bool)> {
    let mut sorted: Vec<(f64, f64)> = points.iter().map(|p| (p.1, p.2)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for (e, t) in sorted {
        if front.last().is_none_or(|&(_, best)| t < best) {
            front.push((e, t));
        }
    }
    let first = front.first()?;
    if target < first.0 {
        return None;
    }
    let last = front.last()?;
    if target >= last.0 {
        return Some((last.1, target > last.0));
    }
    let i = front.windows(2).position(|w| w[0].0 <= target && target < w[1].0)?;
    let ((e0, t0), (e1, t1)) = (front[i], front[i + 1]);
    let s = (target.log10() - e0.log10()) / (e1.log10() - e0.log10());
    Some((10f64.powf(t0.log10() + s * (t1.log10() - t0.log10())), false))
}

fn ms(t: f64) -> String {
    let ms = t * 1e3;
    if ms >= 100.0 {
        format!("{ms:.0}")
    } else if ms >= 10.0 {
        format!("{ms:.1}")
    } else if ms >= 1.0 {
        format!("{ms:.2}")
    } else {
        format!("{ms:.3}")
    }
}

/// The first line of a failure reason, shortened.
fn short(reason: &str) -> String {
    let line = reason.lines().next().unwrap_or("");
    let mut s: String = line.chars().take(160).collect();
    if line.chars().count() > 160 {
        s.push('…');
    }
    s.replace('|', "/")
}

fn gamma_label(g: f64) -> String {
    format!("1e{}", g.log10().round() as i32)
}

/// The targets of the matched-accuracy tables at γ: decades from 1e-3 down to 3× the
/// reference's accuracy.
fn targets(floor: f64) -> Vec<f64> {
    (3..=11).map(|k| 10f64.powi(-k)).filter(|&e| e >= 3.0 * floor).collect()
}

fn best_of<'a>(
    times: impl Iterator<Item = (&'a str, Option<(f64, bool)>)>,
) -> Option<(&'a str, f64)> {
    times.filter_map(|(m, t)| t.map(|t| (m, t.0))).min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The analysis: tables, targets, diagrams.
pub fn analyse(results: &Results) -> Analysis {
    let rows = &results.rows;
    let order = method_order();
    let mut md = String::new();
    let mut summary = String::new();
    let mut svgs = Vec::new();
    let methods_at = |gamma: f64| -> Vec<String> {
        order
            .iter()
            .filter(|m| rows.iter().any(|r| &r.method == *m && r.gamma == gamma))
            .cloned()
            .collect()
    };

    // Targets at γ = 1e8 first.
    let _ = writeln!(md, "## The targets at γ = 1e8\n");
    if let Some(r8) = results.references.iter().find(|r| r.gamma == 1e8) {
        let floor = r8.agreement.period.max(1e-16);
        // Wrapper against plain C.
        let _ = writeln!(
            md,
            "**Wrapper against plain C** (target: within 1.05×). `cvode-bdf` through the library against \
             `c-cvode-bdf`, the C replica of the engine, with the same steps and counters in every cell of the grid \
             (checked below). Times: the minimum per cycle over {} alternating rounds, each a process of the C \
             program and one of this benchmark (`--cell`), both doing one warm-up and {} timed runs, so that both \
             sides see the same machine load and the same process life cycle (timing the library in the \
             benchmark's own process right after each C child made it up to 1.6× slower). The grid's own cells \
             (minimum of ≤ {} runs taken minutes apart under a load average of 4–7 on 2 cores) scatter more.\n",
            crate::WRAPPER_ROUNDS_DOC.0,
            crate::WRAPPER_ROUNDS_DOC.1,
            results.runs
        );
        let when = &results.machine["wrapper_measured"];
        if let Some(date) = when["date_utc"].as_str() {
            let _ = writeln!(
                md,
                "Measured after the grid, on {date} (load average {} at the end), with `{}`.\n",
                when["load_average_end"].as_str().unwrap_or("?"),
                when["command"].as_str().unwrap_or("?")
            );
        }
        let _ = writeln!(
            md,
            "| rtol | library ms/cycle | plain C ms/cycle | ratio | grid cells: library / C | same steps and counters | largest relative difference in period, t0, ln v_max |\n|---|---|---|---|---|---|---|"
        );
        let mut ratios = Vec::new();
        for w in results.wrapper.iter().filter(|w| w.gamma == 1e8) {
            let find = |m: &str| {
                rows.iter().find(|r| r.gamma == 1e8 && r.method == m && r.rtol == w.rtol && r.ok)
            };
            let (grid, same, diff) = match (find("cvode-bdf"), find("c-cvode-bdf")) {
                (Some(a), Some(b)) => {
                    let grid = a.time_per_cycle_s.unwrap_or(f64::NAN)
                        / b.time_per_cycle_s.unwrap_or(f64::NAN);
                    let diff = match (a.measured, b.measured) {
                        (Some(x), Some(y)) => {
                            let e = crate::relative(&x, &y);
                            e.period.max(e.t0).max(e.ln_v_max)
                        }
                        _ => f64::NAN,
                    };
                    (
                        format!("{grid:.3}"),
                        if a.counts == b.counts { "yes" } else { "**no**" },
                        format!("{diff:.1e}"),
                    )
                }
                _ => ("—".into(), "—", "—".into()),
            };
            ratios.push(w.ratio);
            let _ = writeln!(
                md,
                "| {:.0e} | {} | {} | **{:.3}** | {grid} | {same} | {diff} |",
                w.rtol,
                ms(w.library_s),
                ms(w.c_s),
                w.ratio
            );
        }
        if !ratios.is_empty() {
            ratios.sort_by(f64::total_cmp);
            let median = ratios[ratios.len() / 2];
            let line = format!(
                "wrapper/plain C at γ = 1e8: median {median:.3}, range {:.3} … {:.3} over {} tolerances (target ≤ 1.05: {})",
                ratios[0],
                ratios[ratios.len() - 1],
                ratios.len(),
                if ratios[ratios.len() - 1] <= 1.05 {
                    "met at every tolerance"
                } else if median <= 1.05 {
                    "met by the median"
                } else {
                    "NOT met"
                }
            );
            let _ = writeln!(md, "\n{line}.\n");
            let _ = writeln!(summary, "{line}");
        }
        // Best stickslip method against LSODA at LSODA's own points.
        let ours: Vec<&str> = Method::ALL.iter().map(|(n, _)| *n).collect();
        let our_points: Vec<(&str, Vec<_>)> =
            ours.iter().map(|m| (*m, points(rows, m, 1e8, Quantity::Period, floor))).collect();
        let lsoda = points(rows, "scipy-lsoda", 1e8, Quantity::Period, floor);
        let _ = writeln!(
            md,
            "**Best stickslip method against scipy's LSODA at equal period error** (target: ≥ 20×). At each \
             tolerance where LSODA ran, the fastest of our methods at LSODA's period error:\n"
        );
        if lsoda.is_empty() {
            let _ = writeln!(
                md,
                "LSODA did not run at γ = 1e8 at any tolerance (see the failures below).\n"
            );
            let _ = writeln!(summary, "LSODA at γ = 1e8: no successful run");
        } else {
            let _ = writeln!(md, "| LSODA rtol | period error | LSODA ms/cycle | best stickslip | its ms/cycle | ratio |\n|---|---|---|---|---|---|");
            let mut lr = Vec::new();
            for &(rtol, e, t, _) in &lsoda {
                if let Some((m, tb)) = best_of(our_points.iter().map(|(m, p)| (*m, time_at(p, e))))
                {
                    lr.push(t / tb);
                    let _ = writeln!(
                        md,
                        "| {rtol:.0e} | {e:.1e} | {} | {m} | {} | {:.0}× |",
                        ms(t),
                        ms(tb),
                        t / tb
                    );
                }
            }
            if !lr.is_empty() {
                lr.sort_by(f64::total_cmp);
                let line = format!(
                    "best stickslip method vs scipy LSODA at γ = 1e8: {:.0}× … {:.0}× (median {:.0}×) at equal period error (target ≥ 20×: {})",
                    lr[0],
                    lr[lr.len() - 1],
                    lr[lr.len() / 2],
                    if lr[0] >= 20.0 { "met at every LSODA point" } else if lr[lr.len() / 2] >= 20.0 { "met at most points" } else { "NOT met" }
                );
                let _ = writeln!(md, "\n{line}.\n");
                let _ = writeln!(summary, "{line}");
            }
        }
        // Issue #6's goal.
        let _ = writeln!(
            md,
            "**Issue #6's goal: our best homemade method the fastest of all at every period error from 1e-5 to 1e-9, \
             with no special settings.** Time per cycle at matched period error (interpolated; ≤: the method's cheapest \
             run is already that accurate):\n"
        );
        let all: Vec<(String, Vec<_>)> = methods_at(1e8)
            .into_iter()
            .map(|m| {
                let p = points(rows, &m, 1e8, Quantity::Period, floor);
                (m, p)
            })
            .collect();
        let _ = writeln!(md, "| period error | best homemade | ms/cycle | fastest other | ms/cycle | other / homemade |\n|---|---|---|---|---|---|");
        let mut verdicts = Vec::new();
        for k in 5..=9 {
            let e = 10f64.powi(-k);
            let homemade = best_of(
                all.iter()
                    .filter(|(m, _)| HOMEMADE.contains(&m.as_str()))
                    .map(|(m, p)| (m.as_str(), time_at(p, e))),
            );
            let other = best_of(
                all.iter()
                    .filter(|(m, _)| !HOMEMADE.contains(&m.as_str()))
                    .map(|(m, p)| (m.as_str(), time_at(p, e))),
            );
            match (homemade, other) {
                (Some((hm, ht)), Some((om, ot))) => {
                    verdicts.push((e, ot / ht));
                    let _ = writeln!(
                        md,
                        "| {e:.0e} | {hm} | {} | {om} | {} | {:.2} |",
                        ms(ht),
                        ms(ot),
                        ot / ht
                    );
                }
                (Some((hm, ht)), None) => {
                    verdicts.push((e, f64::INFINITY));
                    let _ = writeln!(md, "| {e:.0e} | {hm} | {} | (none reaches it) | | |", ms(ht));
                }
                (None, _) => {
                    verdicts.push((e, 0.0));
                    let _ = writeln!(md, "| {e:.0e} | (none reaches it) | | | | |");
                }
            }
        }
        let met = verdicts.iter().all(|v| v.1 > 1.0);
        let worst = verdicts.iter().map(|v| v.1).fold(f64::INFINITY, f64::min);
        let line = format!(
            "issue #6 goal at γ = 1e8 (best homemade fastest at period errors 1e-5 … 1e-9): {} (smallest lead: fastest other / best homemade = {worst:.2})",
            if met { "met" } else { "NOT met" }
        );
        let _ = writeln!(md, "\n{line}.\n");
        let _ = writeln!(summary, "{line}");
    }

    // Matched-accuracy tables per γ.
    let _ = writeln!(md, "## Time per cycle at matched period error\n");
    let _ = writeln!(
        md,
        "Milliseconds per settled cycle at each period error, log time interpolated against log error along each \
         method's Pareto front; in brackets the ratio to the fastest stickslip method at that error (< 1: faster than \
         all of ours). ≤: the method's cheapest run is already that accurate, so the time is an upper bound. Blank: \
         not reached at any tolerance (or the method failed, see the failures). Only errors at least 3× the reference's \
         accuracy are shown.\n"
    );
    for r in &results.references {
        let g = r.gamma;
        let floor = r.agreement.period.max(1e-16);
        let ts = targets(floor);
        let methods = methods_at(g);
        let pts: Vec<(String, Vec<_>)> = methods
            .iter()
            .map(|m| (m.clone(), points(rows, m, g, Quantity::Period, floor)))
            .collect();
        let ours: Vec<&str> = Method::ALL.iter().map(|(n, _)| *n).collect();
        let _ = writeln!(md, "### γ = {}\n", gamma_label(g));
        let _ = write!(md, "| method |");
        for e in &ts {
            let _ = write!(md, " {e:.0e} |");
        }
        let _ = write!(md, "\n|---|");
        for _ in &ts {
            let _ = write!(md, "---|");
        }
        let _ = writeln!(md);
        for (m, p) in &pts {
            let _ = write!(md, "| {m} |");
            for &e in &ts {
                let best = best_of(
                    pts.iter()
                        .filter(|(n, _)| ours.contains(&n.as_str()))
                        .map(|(n, q)| (n.as_str(), time_at(q, e))),
                );
                match (time_at(p, e), best) {
                    (Some((t, bound)), Some((_, b))) => {
                        let _ = write!(
                            md,
                            " {}{} ({:.2}) |",
                            if bound { "≤" } else { "" },
                            ms(t),
                            t / b
                        );
                    }
                    (Some((t, bound)), None) => {
                        let _ = write!(md, " {}{} |", if bound { "≤" } else { "" }, ms(t));
                    }
                    (None, _) => {
                        let _ = write!(md, " |");
                    }
                }
            }
            let _ = writeln!(md);
        }
        let _ = writeln!(md);
        // Diagrams: time per cycle against each error, and RHS evaluations against the period
        // error; ours solid, the peers dashed; 7 palette colours × markers tell 17 series apart.
        let style = |i: usize, m: &str| {
            let marker = [Marker::Circle, Marker::Square, Marker::Triangle]
                [(i / figure::series::PALETTE.len()) % 3];
            let s = Style::line(i).marker(marker);
            if ours.contains(&m) {
                s
            } else {
                s.dash(Dash::Dashed)
            }
        };
        let mut panels = Vec::new();
        for (k, q) in [Quantity::Period, Quantity::T0, Quantity::LnVMax].into_iter().enumerate() {
            let floor_q = match q {
                Quantity::Period => r.agreement.period,
                Quantity::T0 => r.agreement.t0,
                Quantity::LnVMax => r.agreement.ln_v_max,
            }
            .max(1e-16);
            let mut panel = Panel::new(
                format!("({}) time per cycle vs error in {}", ["a", "b", "c"][k], q.label()),
                Axis::log10(format!(
                    "relative error in {} (reference accuracy {floor_q:.0e})",
                    q.label()
                ))
                .dimensionless(),
                Axis::log10("time per cycle").unit("s"),
            )
            .legend(if k == 0 { LegendPlace::Auto } else { LegendPlace::Hidden });
            for (i, m) in methods.iter().enumerate() {
                let p = points(rows, m, g, q, floor_q);
                if !p.is_empty() {
                    panel = panel.series(Series::new(
                        m.as_str(),
                        p.iter().map(|p| p.1).collect(),
                        p.iter().map(|p| p.2).collect(),
                        style(i, m),
                    ));
                }
            }
            panels.push(panel);
        }
        let mut panel = Panel::new(
            "(d) right-hand sides per cycle vs error in period",
            Axis::log10("relative error in period").dimensionless(),
            Axis::log10("RHS evaluations per cycle").dimensionless(),
        )
        .legend(LegendPlace::Hidden);
        for (i, m) in methods.iter().enumerate() {
            let p: Vec<(f64, f64)> = points(rows, m, g, Quantity::Period, floor)
                .iter()
                .filter_map(|p| Some((p.1, p.3?)))
                .collect();
            if !p.is_empty() {
                panel = panel.series(Series::new(
                    m.as_str(),
                    p.iter().map(|p| p.0).collect(),
                    p.iter().map(|p| p.1).collect(),
                    style(i, m),
                ));
            }
        }
        panels.push(panel);
        let name = format!("gamma-{}.svg", gamma_label(g));
        let _ =
            writeln!(md, "![work–precision at γ = {}](work-precision/{name})\n", gamma_label(g));
        let figure = panels.into_iter().fold(
            Figure::new(format!("Work against precision, γ = {}, ξ = 0.8, ε = 1", gamma_label(g)))
                .columns(2)
                .panel_size(620.0, 460.0),
            Figure::panel,
        );
        let figure = figure.caption(
            "Solid: stickslip's methods; dashed: the peers. One point per tolerance (rtol 1e-3 … 1e-12); errors below the \
             reference's accuracy are drawn at it. Failed runs have no point (docs/work-precision.md lists them).",
        );
        svgs.push((name, figure.to_svg().unwrap_or_else(|e| panic!("diagram at γ = {g:e}: {e}"))));
    }

    // Issue #6: each homemade method against cvode-bdf and the best Rust peer.
    let _ = writeln!(md, "## Homemade methods against cvode-bdf and the best Rust peer\n");
    let _ = writeln!(
        md,
        "Issue #6 asks for run time at equal period accuracy against cvode-bdf and against the best Rust peer \
         (the fastest of diffsol's and differential-equations' methods at that error). Each cell: ms per cycle, then \
         cvode-bdf's time / ours and the best Rust peer's time / ours (> 1: ours is faster; — where the other \
         does not reach that error).\n"
    );
    for r in &results.references {
        let g = r.gamma;
        if g < 1e3 {
            continue;
        }
        let floor = r.agreement.period.max(1e-16);
        let ts: Vec<f64> = targets(floor).into_iter().filter(|&e| e <= 1e-4).collect();
        let cvode = points(rows, "cvode-bdf", g, Quantity::Period, floor);
        let rust_peers: Vec<(&str, Vec<_>)> =
            RUST_PEERS.iter().map(|m| (*m, points(rows, m, g, Quantity::Period, floor))).collect();
        let _ = writeln!(md, "### γ = {}\n", gamma_label(g));
        let _ = write!(md, "| method |");
        for e in &ts {
            let _ = write!(md, " {e:.0e} |");
        }
        let _ = write!(md, "\n|---|");
        for _ in &ts {
            let _ = write!(md, "---|");
        }
        let _ = writeln!(md);
        for m in HOMEMADE {
            let p = points(rows, m, g, Quantity::Period, floor);
            let _ = write!(md, "| {m} |");
            for &e in &ts {
                let Some((t, bound)) = time_at(&p, e) else {
                    let _ = write!(md, " |");
                    continue;
                };
                let ratio =
                    |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{:.2}", x / t));
                let c = time_at(&cvode, e).map(|x| x.0);
                let peer = best_of(rust_peers.iter().map(|(n, q)| (*n, time_at(q, e))));
                let _ = write!(
                    md,
                    " {}{}; {}; {}{} |",
                    if bound { "≤" } else { "" },
                    ms(t),
                    ratio(c),
                    ratio(peer.map(|p| p.1)),
                    peer.map_or(String::new(), |p| format!(" ({})", p.0))
                );
            }
            let _ = writeln!(md);
        }
        let _ = writeln!(md);
    }

    // Failures.
    let _ = writeln!(md, "## Failures and tuned runs\n");
    let _ = writeln!(
        md,
        "Every failed cell with its reason (first line). A peer's defaults are tried first; where they fail, its tuned \
         setting is tried too (both rows are in results.json).\n"
    );
    let _ = writeln!(md, "| γ | method | setting | rtol | reason |\n|---|---|---|---|---|");
    for row in rows.iter().filter(|r| !r.ok) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.0e} | {} |",
            gamma_label(row.gamma),
            row.method,
            row.setting,
            row.rtol,
            short(row.error.as_deref().unwrap_or("?"))
        );
    }
    let tuned: Vec<&Row> = rows.iter().filter(|r| r.ok && r.setting == "tuned").collect();
    if !tuned.is_empty() {
        let _ = writeln!(md, "\nRuns that needed the tuned setting:\n");
        let _ = writeln!(md, "| γ | method | rtols | tuning |\n|---|---|---|---|");
        let mut seen: Vec<(f64, &str)> = Vec::new();
        for r in &tuned {
            if seen.contains(&(r.gamma, r.method.as_str())) {
                continue;
            }
            seen.push((r.gamma, &r.method));
            let rtols: Vec<String> = tuned
                .iter()
                .filter(|t| t.gamma == r.gamma && t.method == r.method)
                .map(|t| format!("{:.0e}", t.rtol))
                .collect();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                gamma_label(r.gamma),
                r.method,
                rtols.join(", "),
                r.tuning.as_deref().unwrap_or("")
            );
        }
    }
    let _ = writeln!(md);
    Analysis { summary, markdown: md, svgs }
}

/// The header of docs/work-precision.md: machine, commands, protocol, reference.
fn header(results: &Results) -> String {
    let m = &results.machine;
    let s = |v: &Value| v.as_str().map(String::from).unwrap_or_else(|| v.to_string());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Work–precision: stickslip against the solvers a user would otherwise pick\n\n\
         Generated by `cargo run --release --example work_precision` (tools/work_precision/); the raw data, every cell \
         including failures, is [data/work-precision/results.json](../data/work-precision/results.json). Issues #6 and #7.\n"
    );
    let _ = writeln!(md, "## Machine and versions\n");
    let _ = writeln!(
        md,
        "- CPU: {} ({} MHz{}), {} cores available to this process, shared with other jobs (load average {} at the \
         start, {} at the end)\n- {}, Linux {}; {}; {}; SUNDIALS {} (Debian)\n- peers: diffsol {}, differential-equations {}, \
         python {} with scipy {} and numpy {}\n- stickslip commit {}, run {} (wall time {:.0} s)\n",
        s(&m["cpu"]),
        s(&m["cpu_mhz"]),
        if m["hypervisor"].as_bool() == Some(true) { ", under a hypervisor" } else { "" },
        s(&m["cores_available"]),
        s(&m["load_average_start"]),
        s(&m["load_average_end"]),
        s(&m["os"]),
        s(&m["kernel"]),
        s(&m["rustc"]),
        s(&m["cc"]),
        s(&m["sundials"]),
        s(&m["diffsol"]),
        s(&m["differential_equations"]),
        s(&m["python"]["python"]),
        s(&m["python"]["scipy"]),
        s(&m["python"]["numpy"]),
        s(&m["stickslip_commit"]),
        s(&m["date_utc"]),
        m["wall_time_s"].as_f64().unwrap_or(0.0),
    );
    let _ = writeln!(md, "## Commands\n");
    let _ = writeln!(
        md,
        "```\ncargo run --release --example work_precision             # everything below, ~1 h; rewrites this file\n\
         cargo run --release --example work_precision -- --quick  # 2 γ × 3 tolerances, to try it\n```\n\n\
         This run: `{}`. The runner builds and calls the peers itself: `cc -O3 -ffp-contract=off \
         benches/c/earthquake_cvode.c` (mode `wp`), `cargo build --release --locked --manifest-path \
         benches/peers/Cargo.toml --target-dir target/peers`, and `python3 benches/scipy_peer.py` (which installs \
         scipy into target/scipy-venv with pip if python3 lacks it). Each peer can be run by hand with the \
         arguments documented at the top of its source.\n",
        results.command
    );
    let _ = writeln!(md, "## What is measured\n");
    let _ = writeln!(
        md,
        "- The problem: the DRR spring-slider in (u, w = ln v, θ), ξ = {}, ε = {}, f = ln v, at γ = 1e1, 1e3, 1e5, \
         1e8; rtol 1e-3 … 1e-12 and atol = rtol·1e-2 on each component (the scene default), the analytic Jacobian \
         everywhere.\n\
         - The start: the settled limit cycle (radau5, rtol 1e-12, to the engine's convergence rule), at its last step \
         end {}·P before an upward crossing of v = 1 (in the stick phase). Every method starts there at t = 0 and \
         integrates through {} cycles; the peers integrate to t_end = ({} + {} + {})·P.\n\
         - Measured per cycle (between upward crossings of v = 1): the period, t0 (crossing to the cycle's highest v \
         maximum) and ln v_max; reported: their means over the {} cycles, and the relative error of each against the \
         reference.\n\
         - Time: the minimum over timed runs of one whole run (solver creation, integration, event location) divided \
         by {}; one warm-up run first; up to {} timed runs, stopping once they add up to {} s (a warm-up longer \
         than that is the only, timed, run). Counters (steps, RHS, Jacobians, LU factorisations) are those of one run \
         (the {} cycles plus the lead-in).\n\
         - stickslip's methods run through the library exactly as `stickslip run` does (`engine::integrator` with the \
         scene's settings, `analysis::cycle::analyse` with its defaults; the convergence rule is switched off and the \
         run stops after {} closed cycles); their event location uses the integrator's dense output and its \
         derivative. The peers locate the same events with what each offers (see the sources): the crossing of w = 0 \
         on their interpolant, the maximum as a root of the model's dw/dt along their interpolant (scipy: its event \
         function for the crossing; brentq or a bounded maximisation on its dense output for the maximum).\n\
         - Peers: their defaults first; where a run fails, their tuned setting (the least change found that makes it \
         run; stated in the failure table and in results.json). The plain-C CVODE program (`c-cvode-bdf`) replicates \
         the engine's stepping and events step for step, with the engine's solver settings.\n",
        protocol::XI,
        protocol::EPSILON,
        protocol::LEAD,
        protocol::CYCLES,
        protocol::LEAD,
        protocol::CYCLES,
        protocol::TAIL,
        protocol::CYCLES,
        protocol::CYCLES,
        results.runs,
        results.budget_s,
        protocol::CYCLES,
        protocol::CYCLES,
    );
    let _ = writeln!(md, "## Reference\n");
    let _ = writeln!(
        md,
        "At each γ, radau5 at rtol 1e-14 and rodas5p at rtol 1e-13 from the same start (1–2 digits tighter than the \
         tightest grid tolerance; rodas5p fails at 1e-14 at γ = 1e5 and 1e8 and radau5 at 1e-15 at γ = 1e8). The \
         reference is their mean, and their relative difference is its accuracy: errors below it are shown as that \
         floor. The last column compares with data/reference/drr_cycles.json (CVODE and ARKStep at rtol 1e-11, the \
         engine's converged cycle), whose own accuracy is ~1e-8.\n"
    );
    let _ = writeln!(
        md,
        "| γ | start (u, ln v, θ) | period | t0 | ln v_max | agreement: period, t0, ln v_max | drr_cycles.json − ours: period, ln v_max |\n|---|---|---|---|---|---|---|"
    );
    for r in &results.references {
        let d = r
            .drr_cycles_table
            .map_or("—".to_string(), |d| format!("{:.1e}, {:.1e}", d.period, d.ln_v_max));
        let _ = writeln!(
            md,
            "| {} | ({:.6}, {:.6}, {:.6}) | {:.13} | {:.10} | {:.12} | {:.1e}, {:.1e}, {:.1e} | {} |",
            gamma_label(r.gamma),
            r.start.y0[0],
            r.start.y0[1],
            r.start.y0[2],
            r.values.period,
            r.values.t0,
            r.values.ln_v_max,
            r.agreement.period,
            r.agreement.t0,
            r.agreement.ln_v_max,
            d
        );
    }
    let _ = writeln!(md);
    md
}

/// The folder of the generated data, data/work-precision/ (kept out of docs/, which holds only
/// the page and its diagrams).
fn data_dir() -> std::path::PathBuf {
    peers::root().join("data/work-precision")
}

/// Reads data/work-precision/results.json back, with the wrapper measurement of
/// data/work-precision/wrapper.json in place of the run's own when that file exists (see
/// [`write_wrapper`]). Numbers read back may differ from the written ones in the last bit
/// (serde_json's float parsing is not exact), so results.json is only ever written by a full
/// run, from the measured values.
pub fn read() -> Result<Results, String> {
    let dir = data_dir();
    let parse = |name: &str| -> Result<Option<String>, String> {
        let path = dir.join(name);
        match std::fs::read_to_string(&path) {
            Ok(text) => Ok(Some(text)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && name == "wrapper.json" => {
                Ok(None)
            }
            Err(e) => Err(format!("{}: {e}", path.display())),
        }
    };
    let text = parse("results.json")?.unwrap_or_default();
    let mut results: Results =
        serde_json::from_str(&text).map_err(|e| format!("results.json: {e}"))?;
    if let Some(text) = parse("wrapper.json")? {
        let w: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("wrapper.json: {e}"))?;
        results.wrapper = serde_json::from_value(w["wrapper"].clone())
            .map_err(|e| format!("wrapper.json: {e}"))?;
        results.machine["wrapper_measured"] = w["measured"].clone();
    }
    Ok(results)
}

/// Writes a new wrapper measurement to data/work-precision/wrapper.json (results.json is left
/// as the full run wrote it).
pub fn write_wrapper(wrapper: &[crate::WrapperRow], measured: Value) -> std::io::Result<()> {
    let path = data_dir().join("wrapper.json");
    let json = json!({ "measured": measured, "wrapper": wrapper });
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&json).map_err(std::io::Error::other)? + "\n",
    )?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Writes data/work-precision/results.json (when `with_results`: after a full run), the SVGs
/// in docs/work-precision/ and docs/work-precision.md (keeping its notes after NOTES_MARKER).
pub fn write(results: &Results, analysis: &Analysis, with_results: bool) -> std::io::Result<()> {
    let docs = peers::root().join("docs");
    let dir = docs.join("work-precision");
    std::fs::create_dir_all(&dir)?;
    if with_results {
        let data = data_dir();
        std::fs::create_dir_all(&data)?;
        std::fs::write(
            data.join("results.json"),
            serde_json::to_string_pretty(results).map_err(std::io::Error::other)? + "\n",
        )?;
        // A full run measures the wrapper itself: an older separate measurement is stale.
        match std::fs::remove_file(data.join("wrapper.json")) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e),
            _ => {}
        }
    }
    for (name, svg) in &analysis.svgs {
        std::fs::write(dir.join(name), svg)?;
    }
    let path = docs.join("work-precision.md");
    let notes = std::fs::read_to_string(&path)
        .ok()
        .and_then(|old| old.split_once(NOTES_MARKER).map(|(_, notes)| notes.to_string()))
        .unwrap_or_else(|| "\n\n## Notes\n\n(none yet)\n".into());
    let text = format!("{}{}{NOTES_MARKER}{notes}", header(results), analysis.markdown);
    std::fs::write(&path, text)?;
    eprintln!(
        "wrote {} and {} diagrams{}",
        path.display(),
        analysis.svgs.len(),
        if with_results { " and results.json" } else { "" }
    );
    Ok(())
}
