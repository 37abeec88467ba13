//! Claims set beside our numbers: {claim, reference (the paper's value or a prediction), ours,
//! difference, verdict}, with the criterion stated in the claim itself. The one claim type of
//! the crate: the "paper" comparison, the "asymptotics" and "lyapunov" analyses and
//! `reproduce`'s summary use it. Nothing is tuned to a reference: a criterion is fixed by what
//! the claim says (e.g. "about", "→", "γ-independent"), never by our result.

use serde::Serialize;

/// Where a claim's reference value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// A number quoted (or a formula printed) in the paper.
    Paper,
    /// A prediction of the asymptotic theory (the paper's or the singular-limit picture of
    /// issue 5), not a number the paper quotes.
    Prediction,
    /// A consistency check between two independent computations of ours.
    Check,
}

/// How our value stands against a claim. Serialised (and displayed) as "agrees", "roughly",
/// "disagrees", "holds" and "does not hold".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Verdict {
    /// Within the claim's tolerance.
    #[serde(rename = "agrees")]
    Agrees,
    /// Within four times the tolerance.
    #[serde(rename = "roughly")]
    Roughly,
    /// Beyond it (or the wrong sign or side).
    #[serde(rename = "disagrees")]
    Disagrees,
    /// A qualitative claim that holds.
    #[serde(rename = "holds")]
    Holds,
    /// A qualitative claim that does not hold.
    #[serde(rename = "does not hold")]
    DoesNotHold,
}

impl Verdict {
    /// The verdict in words, as serialised.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Agrees => "agrees",
            Verdict::Roughly => "roughly",
            Verdict::Disagrees => "disagrees",
            Verdict::Holds => "holds",
            Verdict::DoesNotHold => "does not hold",
        }
    }

    /// A qualitative claim's verdict.
    pub fn holds(holds: bool) -> Self {
        if holds {
            Verdict::Holds
        } else {
            Verdict::DoesNotHold
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

impl PartialEq<&str> for Verdict {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// One claim and our value for it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Claim {
    /// The claim, in words.
    pub claim: String,
    /// Where the reference comes from.
    pub source: Source,
    /// The reference value (the paper's number or the predicted one).
    pub reference: f64,
    /// Ours.
    pub ours: f64,
    /// ours − reference.
    pub difference: f64,
    /// (ours − reference)/|reference|; null when the reference is 0.
    pub relative_difference: Option<f64>,
    /// The rule behind the verdict, in words.
    pub criterion: String,
    /// Agrees, roughly or disagrees.
    pub verdict: Verdict,
    /// What our number is and how it was obtained (finite-γ corrections, caveats).
    pub note: String,
}

impl Claim {
    fn new(
        claim: &str,
        source: Source,
        reference: f64,
        ours: f64,
        criterion: String,
        verdict: Verdict,
        note: String,
    ) -> Self {
        let difference = ours - reference;
        let relative_difference = (reference != 0.0).then(|| difference / reference.abs());
        Claim {
            claim: claim.into(),
            source,
            reference,
            ours,
            difference,
            relative_difference,
            criterion,
            verdict,
            note,
        }
    }

    /// Agrees within `tol` relative, roughly within 4·`tol`, disagrees otherwise.
    pub fn relative(
        claim: &str,
        source: Source,
        reference: f64,
        ours: f64,
        tol: f64,
        note: String,
    ) -> Self {
        let d = ((ours - reference) / reference).abs();
        let verdict = grade(d, tol);
        let criterion = format!(
            "agrees if |ours − reference| ≤ {} % of |reference|, roughly if ≤ {} %",
            pct(tol),
            pct(4.0 * tol)
        );
        Self::new(claim, source, reference, ours, criterion, verdict, note)
    }

    /// Agrees within `tol` absolute, roughly within 4·`tol`, disagrees otherwise. `why` says
    /// where the tolerance comes from.
    pub fn absolute(
        claim: &str,
        source: Source,
        reference: f64,
        ours: f64,
        tol: f64,
        why: &str,
        note: String,
    ) -> Self {
        let verdict = grade((ours - reference).abs(), tol);
        let criterion = format!(
            "agrees if |ours − reference| ≤ {tol:.3e} ({why}), roughly if ≤ {:.3e}",
            4.0 * tol
        );
        Self::new(claim, source, reference, ours, criterion, verdict, note)
    }

    /// A sign claim: agrees if ours < 0 (reference 0), disagrees otherwise.
    pub fn negative(claim: &str, source: Source, ours: f64, note: String) -> Self {
        let verdict = if ours < 0.0 { Verdict::Agrees } else { Verdict::Disagrees };
        Self::new(claim, source, 0.0, ours, "agrees if ours < 0".into(), verdict, note)
    }

    /// A lower bound: agrees if ours ≥ reference, disagrees otherwise.
    pub fn at_least(claim: &str, source: Source, reference: f64, ours: f64, note: String) -> Self {
        let verdict = if ours >= reference { Verdict::Agrees } else { Verdict::Disagrees };
        Self::new(
            claim,
            source,
            reference,
            ours,
            "agrees if ours ≥ reference".into(),
            verdict,
            note,
        )
    }

    /// Every real number of the claim (for the finiteness check).
    pub fn numbers(&self) -> impl Iterator<Item = f64> + '_ {
        [self.reference, self.ours, self.difference].into_iter().chain(self.relative_difference)
    }
}

fn grade(deviation: f64, tol: f64) -> Verdict {
    if deviation <= tol {
        Verdict::Agrees
    } else if deviation <= 4.0 * tol {
        Verdict::Roughly
    } else {
        Verdict::Disagrees
    }
}

/// A relative tolerance `x` in percent, to three significant digits without trailing zeros:
/// positional from 0.001 % up ("5", "0.25", "3.47"), in exponent form below ("1e-4" for a
/// relative 1e-6), never a binary-to-decimal artefact such as 0.00009999999999999999.
fn pct(x: f64) -> String {
    let p = 100.0 * x;
    if !(p.is_finite() && p > 0.0) {
        return format!("{p}");
    }
    // Rounded to three significant digits first: the exponent is the rounded value's.
    let e = format!("{p:.2e}");
    let (mantissa, exponent) = e.split_once('e').expect("{:e} has an exponent");
    let exponent: i32 = exponent.parse().expect("{:e}'s exponent is an integer");
    let trim = |s: &str| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if exponent >= -3 {
        let rounded: f64 = e.parse().expect("{:e} parses back");
        trim(&format!("{rounded:.*}", (2 - exponent).max(0) as usize))
    } else {
        format!("{}e{exponent}", trim(mantissa))
    }
}

/// One line per claim for the CLI summary.
pub fn summary_lines(claims: &[Claim]) -> String {
    claims
        .iter()
        .map(|c| {
            let rel =
                c.relative_difference.map_or(String::new(), |r| format!(", {:+.1} %", 100.0 * r));
            format!(
                "  {:<9} {} — {} {}, ours {} (Δ {:+.3e}{rel})\n",
                c.verdict,
                c.claim,
                match c.source {
                    Source::Paper => "paper",
                    Source::Prediction => "predicted",
                    Source::Check => "reference",
                },
                short(c.reference),
                short(c.ours),
                c.difference
            )
        })
        .collect()
}

fn short(x: f64) -> String {
    if x != 0.0 && (x.abs() >= 1e5 || x.abs() < 1e-3) {
        format!("{x:.4e}")
    } else {
        format!("{x:.5}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_stated_tolerance() {
        assert_eq!(
            Claim::relative("x", Source::Paper, 2.5, 2.55, 0.05, String::new()).verdict,
            "agrees"
        );
        assert_eq!(
            Claim::relative("x", Source::Paper, 2.5, 2.106, 0.05, String::new()).verdict,
            "roughly"
        );
        assert_eq!(
            Claim::relative("x", Source::Paper, 28.0, 56.4, 0.05, String::new()).verdict,
            "disagrees"
        );
        assert_eq!(
            Claim::absolute("x", Source::Prediction, 0.0, 0.3, 0.1, "test", String::new()).verdict,
            "roughly"
        );
        assert_eq!(
            Claim::absolute("x", Source::Prediction, 0.0, 0.5, 0.1, "test", String::new()).verdict,
            "disagrees"
        );
        let n = Claim::negative("c < 0", Source::Paper, -0.2, String::new());
        assert_eq!((n.verdict.as_str(), n.relative_difference), ("agrees", None));
        assert_eq!(
            Claim::negative("c < 0", Source::Paper, 0.0, String::new()).verdict,
            "disagrees"
        );
        assert_eq!(
            Claim::at_least("v ≥ 10", Source::Paper, 10.0, 46.7, String::new()).verdict,
            "agrees"
        );
        assert_eq!(
            Claim::at_least("v ≥ 10", Source::Paper, 10.0, 1.3, String::new()).verdict,
            "disagrees"
        );
    }

    #[test]
    fn percentages_print_as_clean_numbers() {
        // The tolerances reproduce uses (0.05: paper, asymptotics, lyapunov; 1e-6: the state
        // laws' periods) and their 4× "roughly", and computed ones (a spread, 1/v).
        let cases = [
            (0.05, "5"),
            (0.2, "20"),
            (1e-6, "1e-4"),
            (4e-6, "4e-4"),
            (1e-5, "0.001"),
            (0.0347, "3.47"),
            (0.014, "1.4"),
            (0.0123456, "1.23"),
            (0.00999999, "1"),
            (2.5e-3, "0.25"),
            (3.14159e-9, "3.14e-7"),
            (1.0, "100"),
            (12.345, "1230"),
        ];
        for (x, want) in cases {
            assert_eq!(pct(x), want, "{x}");
        }
        let c = Claim::relative("x", Source::Check, 2.0, 2.0, 1e-6, String::new());
        assert_eq!(
            c.criterion,
            "agrees if |ours − reference| ≤ 1e-4 % of |reference|, roughly if ≤ 4e-4 %"
        );
    }
}
