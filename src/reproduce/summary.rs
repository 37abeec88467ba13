//! The summary of a reproduce run: per figure its files and status; per claim of the paper
//! its value, ours and a verdict; the figures not yet reproduced. As JSON, Markdown and HTML.

use super::{Entry, Output, Pending, ReproduceError, PENDING};
use crate::figure::svg::escape;
use serde::Serialize;
use stickslip::paper::claims::{Claim, Source, Verdict};
use stickslip::paper::quoted;

/// One claim of the paper set beside ours.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// The figure that tests it (e.g. "Fig. 1c").
    pub figure: String,
    /// The claim, in words.
    pub claim: String,
    /// The paper's value (or statement).
    pub paper: String,
    /// Ours.
    pub ours: String,
    /// Agrees (within 5 %), roughly (within 20 %), disagrees; holds or does not hold for a
    /// qualitative claim.
    pub verdict: Verdict,
    /// How our value was obtained.
    pub note: String,
}

impl Row {
    /// A row from one of [`stickslip::paper::quoted`]'s claims (its value to four decimals and
    /// the relative difference; the criterion, 5 %, is the summary's).
    pub fn from_claim(figure: &str, c: &Claim) -> Self {
        let rel =
            c.relative_difference.map_or(String::new(), |r| format!(" ({:+.1} %)", 100.0 * r));
        Self {
            figure: figure.into(),
            claim: c.claim.clone(),
            paper: short(c.reference),
            ours: format!("{:.4}{rel}", c.ours),
            verdict: c.verdict,
            note: c.note.clone(),
        }
    }

    /// A row from a claim of the "asymptotics" or "lyapunov" analyses
    /// ([`stickslip::paper::claims`]), with its own verdict ("agrees", "roughly", "disagrees")
    /// and criterion (in the note).
    pub fn from_analysis(figure: &str, c: &Claim) -> Self {
        let source = match c.source {
            Source::Paper => "",
            Source::Prediction => " (predicted)",
            Source::Check => " (check)",
        };
        let rel =
            c.relative_difference.map_or(String::new(), |r| format!(" ({:+.1} %)", 100.0 * r));
        Self {
            figure: figure.into(),
            claim: c.claim.clone(),
            paper: format!("{}{source}", short_or_sci(c.reference)),
            ours: format!("{}{rel}", short_or_sci(c.ours)),
            verdict: c.verdict,
            note: format!("{} Criterion: {}.", c.note, c.criterion),
        }
    }

    /// A numerical claim, judged as [`quoted::claim`] judges.
    pub fn numeric(figure: &str, claim: &str, paper_value: f64, ours: f64, note: String) -> Self {
        Self::from_claim(figure, &quoted::claim(claim, paper_value, ours, note))
    }

    /// A qualitative claim: it holds or it does not.
    pub fn qualitative(
        figure: &str,
        claim: &str,
        paper: &str,
        ours: String,
        holds: bool,
        note: String,
    ) -> Self {
        Self {
            figure: figure.into(),
            claim: claim.into(),
            paper: paper.into(),
            ours,
            verdict: Verdict::holds(holds),
            note,
        }
    }
}

/// The outcome of one figure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigureResult {
    /// Its id (SVG stem).
    pub id: String,
    /// What it shows.
    pub what: String,
    /// Null when made; the error otherwise.
    pub error: Option<String>,
    /// Wall time (s).
    pub seconds: f64,
    /// Files, claims and notes.
    #[serde(flatten)]
    pub output: Output,
}

impl FigureResult {
    /// The result of `entry`'s run.
    pub fn new(entry: &Entry, outcome: Result<Output, ReproduceError>, seconds: f64) -> Self {
        let (output, error) = match outcome {
            Ok(o) => (o, None),
            Err(e) => (Output::default(), Some(e.to_string())),
        };
        Self { id: entry.id.into(), what: entry.what.into(), error, seconds, output }
    }
}

/// The whole run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// stickslip version.
    pub stickslip_version: &'static str,
    /// SUNDIALS version linked.
    pub sundials_version: String,
    /// Worker threads.
    pub threads: usize,
    /// Whether this was the reduced (test) run.
    pub reduced: bool,
    /// Wall time of the whole run (s).
    pub wall_time_s: f64,
    /// The figures made (or failed).
    pub figures: Vec<FigureResult>,
    /// The paper's figures not yet reproduced.
    pub pending: Vec<Pending>,
}

/// A number with at most 6 significant digits, without trailing zeros.
fn short(x: f64) -> String {
    if x == x.round() && x.abs() < 1e15 {
        return format!("{x}");
    }
    let digits = (5 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{x:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// [`short`], or 4 significant digits in scientific notation for |x| < 1e-3 or ≥ 1e6.
fn short_or_sci(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) {
        format!("{x:.3e}")
    } else {
        short(x)
    }
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

impl Summary {
    /// Assembles the summary.
    pub fn new(
        figures: Vec<FigureResult>,
        threads: usize,
        reduced: bool,
        wall_time_s: f64,
    ) -> Self {
        Self {
            stickslip_version: env!("CARGO_PKG_VERSION"),
            sundials_version: stickslip::sundials::version(),
            threads,
            reduced,
            wall_time_s,
            figures,
            pending: PENDING.to_vec(),
        }
    }

    /// Figures that failed.
    pub fn failed(&self) -> Vec<&FigureResult> {
        self.figures.iter().filter(|f| f.error.is_some()).collect()
    }

    /// Every claim row, in figure order.
    pub fn rows(&self) -> impl Iterator<Item = &Row> {
        self.figures.iter().flat_map(|f| &f.output.claims)
    }

    fn header(&self) -> String {
        format!(
            "stickslip {} with SUNDIALS {}; {} thread(s); {:.1} s{}",
            self.stickslip_version,
            self.sundials_version,
            self.threads,
            self.wall_time_s,
            if self.reduced { "; REDUCED run (fewer curve points, for tests)" } else { "" }
        )
    }

    /// The summary as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::from(
            "# Reproducing Pomeau & Le Berre, \"Critical speed-up vs critical slow-down\"\n\n",
        );
        s += &format!(
            "{}.\nThe paper's numbers are claims to test: nothing is tuned to them.\n\n",
            self.header()
        );
        s += "## Figures\n\n| figure | shows | files | status |\n|---|---|---|---|\n";
        for f in &self.figures {
            let status = match &f.error {
                None => format!("made in {:.1} s", f.seconds),
                Some(e) => format!("FAILED: {e}"),
            };
            s += &format!(
                "| {} | {} | {} | {} |\n",
                f.id,
                md_cell(&f.what),
                md_cell(&f.output.files.join(", ")),
                md_cell(&status)
            );
        }
        s += "\n## Claims\n\n| figure | claim | paper | ours | verdict | how |\n|---|---|---|---|---|---|\n";
        for r in self.rows() {
            s += &format!(
                "| {} | {} | {} | {} | **{}** | {} |\n",
                md_cell(&r.figure),
                md_cell(&r.claim),
                md_cell(&r.paper),
                md_cell(&r.ours),
                r.verdict,
                md_cell(&r.note)
            );
        }
        let notes: Vec<String> = self
            .figures
            .iter()
            .flat_map(|f| f.output.notes.iter().map(move |n| format!("- {}: {n}\n", f.id)))
            .collect();
        if !notes.is_empty() {
            s += "\n## Notes\n\n";
            s += &notes.concat();
        }
        s += "\n## Not yet reproduced\n\n";
        if self.pending.is_empty() {
            s += "- none: every figure of the paper is remade\n";
        }
        for p in &self.pending {
            s += &format!("- {}: {} (waits for {})\n", p.figure, p.what, p.waiting_for);
        }
        s
    }

    /// The summary as a self-contained HTML page showing the SVG figures (same directory).
    pub fn html(&self) -> String {
        let mut s = String::from(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>stickslip reproduce</title>\n<style>\n\
             body{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;max-width:1280px;margin:2em auto;padding:0 1em;color:#222}\n\
             table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.3em .5em;vertical-align:top;font-size:.9em}\n\
             th{background:#eee}.agrees,.holds{color:#006b3c;font-weight:bold}.roughly{color:#a05a00;font-weight:bold}\n\
             .disagrees,.does-not-hold,.failed{color:#b00020;font-weight:bold}img{max-width:100%;border:1px solid #ddd;margin:.5em 0}\n\
             </style></head><body>\n",
        );
        s += "<h1>Reproducing Pomeau &amp; Le Berre, “Critical speed-up vs critical slow-down”</h1>\n";
        s += &format!(
            "<p>{}. The paper's numbers are claims to test: nothing is tuned to them.</p>\n",
            escape(&self.header())
        );
        s += "<h2>Claims</h2>\n<table><tr><th>figure</th><th>claim</th><th>paper</th><th>ours</th><th>verdict</th><th>how</th></tr>\n";
        for r in self.rows() {
            s += &format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"{}\">{}</td><td>{}</td></tr>\n",
                escape(&r.figure),
                escape(&r.claim),
                escape(&r.paper),
                escape(&r.ours),
                r.verdict.as_str().replace(' ', "-"),
                escape(r.verdict.as_str()),
                escape(&r.note)
            );
        }
        s += "</table>\n<h2>Figures</h2>\n";
        for f in &self.figures {
            s += &format!("<h3>{}</h3>\n", escape(&f.what));
            match &f.error {
                Some(e) => s += &format!("<p class=\"failed\">FAILED: {}</p>\n", escape(e)),
                None => {
                    for file in &f.output.files {
                        if file.ends_with(".svg") {
                            s += &format!("<img src=\"{0}\" alt=\"{0}\">\n", escape(file));
                        }
                    }
                    let data: Vec<String> = f
                        .output
                        .files
                        .iter()
                        .filter(|x| !x.ends_with(".svg"))
                        .map(|x| format!("<a href=\"{0}\">{0}</a>", escape(x)))
                        .collect();
                    if !data.is_empty() {
                        s += &format!("<p>Data: {}</p>\n", data.join(", "));
                    }
                }
            }
            for n in &f.output.notes {
                s += &format!("<p>Note: {}</p>\n", escape(n));
            }
        }
        s += "<h2>Not yet reproduced</h2>\n<ul>\n";
        if self.pending.is_empty() {
            s += "<li>none: every figure of the paper is remade</li>\n";
        }
        for p in &self.pending {
            s += &format!(
                "<li>{}: {} (waits for {})</li>\n",
                escape(p.figure),
                escape(p.what),
                escape(p.waiting_for)
            );
        }
        s += "</ul>\n</body></html>\n";
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary() -> Summary {
        let entry = &super::super::FIGURES[0];
        let made = Output {
            files: vec!["fig1.svg".into(), "reports/fig1.json".into()],
            claims: vec![
                Row::numeric("Fig. 1a", "t0 ≅ 1", 1.0, 1.3, "a <note> | with a pipe".into()),
                Row::qualitative(
                    "Fig. 1b",
                    "grows with ε",
                    "increases",
                    "increases at 10/10 steps".into(),
                    true,
                    "n".into(),
                ),
            ],
            notes: vec!["one point did not converge".into()],
        };
        let failed = FigureResult::new(
            entry,
            Err(ReproduceError::Missing("no cycle & no luck".into())),
            0.5,
        );
        Summary::new(vec![FigureResult::new(entry, Ok(made), 1.0), failed], 2, true, 1.5)
    }

    #[test]
    fn markdown_lists_claims_verdicts_failures_and_pending_figures() {
        let s = summary();
        let md = s.markdown();
        assert!(md.contains("| Fig. 1a | t0 ≅ 1 | 1 | 1.3000 (+30.0 %) | **disagrees** | a <note> \\| with a pipe |"), "{md}");
        assert!(md.contains("**holds**"));
        assert!(md.contains("FAILED: no cycle & no luck"));
        assert!(md.contains("REDUCED"));
        for p in PENDING {
            assert!(md.contains(p.figure), "{} missing", p.figure);
        }
        assert_eq!(s.failed().len(), 1);
    }

    #[test]
    fn paper_values_are_short() {
        assert_eq!(short(28.0), "28");
        assert_eq!(short(7.509842836890551), "7.50984");
        assert_eq!(short(2.5), "2.5");
        assert_eq!(short(0.000123456789), "0.000123457");
    }

    #[test]
    fn html_escapes_and_embeds_the_svgs() {
        let html = summary().html();
        assert!(html.contains("<img src=\"fig1.svg\""));
        assert!(html.contains("<a href=\"reports/fig1.json\">"));
        assert!(html.contains("a &lt;note&gt; | with a pipe"));
        assert!(html.contains("no cycle &amp; no luck"));
        assert!(html.contains("class=\"does-not-hold\"") || html.contains("class=\"holds\""));
        assert!(html.contains("Not yet reproduced"));
    }
}
