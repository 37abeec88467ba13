//! Axis scales (linear and log10), their mapping to pixels, and "nice" ticks (1, 2, 5 × 10^k
//! steps; decades on log axes) with labels that carry no spurious digits.

/// How data values map to an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScaleKind {
    /// Linear.
    Linear,
    /// Base-10 logarithmic (data must be > 0).
    Log10,
}

/// A data range [lo, hi] mapped onto the pixel range [px_lo, px_hi] (px_hi < px_lo for a
/// y axis, whose pixels grow downwards).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// Linear or log10.
    pub kind: ScaleKind,
    /// Data value at `px_lo`.
    pub lo: f64,
    /// Data value at `px_hi`.
    pub hi: f64,
    /// Pixel of `lo`.
    pub px_lo: f64,
    /// Pixel of `hi`.
    pub px_hi: f64,
}

impl Scale {
    fn linearise(&self, x: f64) -> f64 {
        match self.kind {
            ScaleKind::Linear => x,
            ScaleKind::Log10 => x.log10(),
        }
    }

    /// The pixel of data value `x`.
    pub fn map(&self, x: f64) -> f64 {
        let (a, b) = (self.linearise(self.lo), self.linearise(self.hi));
        self.px_lo + (self.linearise(x) - a) / (b - a) * (self.px_hi - self.px_lo)
    }

    /// The data value at pixel `p` (inverse of [`Scale::map`]).
    pub fn unmap(&self, p: f64) -> f64 {
        let (a, b) = (self.linearise(self.lo), self.linearise(self.hi));
        let v = a + (p - self.px_lo) / (self.px_hi - self.px_lo) * (b - a);
        match self.kind {
            ScaleKind::Linear => v,
            ScaleKind::Log10 => 10f64.powf(v),
        }
    }
}

/// A tick: its value, and its label (markup, see [`super::text`]) if it is a labelled one.
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    /// Data value.
    pub value: f64,
    /// Label markup; `None` for a minor (unlabelled) tick.
    pub label: Option<String>,
}

/// The "nice" step (1, 2 or 5 × 10^k) that divides `span` into about `target` intervals.
pub fn nice_step(span: f64, target: usize) -> f64 {
    let raw = span / target.max(1) as f64;
    let exp = raw.log10().floor();
    let base = 10f64.powf(exp);
    let m = raw / base;
    let nice = if m < 1.5 {
        1.0
    } else if m < 3.0 {
        2.0
    } else if m < 7.0 {
        5.0
    } else {
        10.0
    };
    nice * base
}

/// Widens an empty or degenerate range so that it can be drawn.
pub fn widen(kind: ScaleKind, lo: f64, hi: f64) -> (f64, f64) {
    match kind {
        ScaleKind::Linear if hi > lo => (lo, hi),
        ScaleKind::Linear => {
            let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            (lo - d, hi + d)
        }
        ScaleKind::Log10 if hi > lo => (lo, hi),
        ScaleKind::Log10 => (lo / 10f64.sqrt(), hi * 10f64.sqrt()),
    }
}

/// The automatic range of data spanning [lo, hi]: padded by `pad` (a fraction of the span, in
/// log space for a log axis).
pub fn padded(kind: ScaleKind, lo: f64, hi: f64, pad: f64) -> (f64, f64) {
    let (lo, hi) = widen(kind, lo, hi);
    match kind {
        ScaleKind::Linear => {
            let d = pad * (hi - lo);
            (lo - d, hi + d)
        }
        ScaleKind::Log10 => {
            let f = 10f64.powf(pad * (hi / lo).log10());
            (lo / f, hi * f)
        }
    }
}

/// Ticks of an axis over [lo, hi] (lo < hi), about `target` labelled ones on a linear axis.
pub fn ticks(kind: ScaleKind, lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    match kind {
        ScaleKind::Linear => linear_ticks(lo, hi, target),
        ScaleKind::Log10 => log_ticks(lo, hi, target),
    }
}

fn in_range(v: f64, lo: f64, hi: f64) -> bool {
    let tol = 1e-9 * (hi - lo).abs().max(f64::MIN_POSITIVE);
    v >= lo - tol && v <= hi + tol
}

/// Linear ticks: labelled multiples of a nice step, with one unlabelled tick between two
/// labelled ones.
pub fn linear_ticks(lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    let step = nice_step(hi - lo, target);
    let minor = step / 2.0;
    let first = (lo / minor - 1e-9).ceil() as i64;
    let last = (hi / minor + 1e-9).floor() as i64;
    (first..=last)
        .map(|i| {
            // Multiples computed from integers: no accumulated rounding, and exact zero.
            let v = i as f64 * minor;
            let labelled = i.rem_euclid(2) == 0;
            Tick { value: v, label: labelled.then(|| format_linear(v, step)) }
        })
        .filter(|t| in_range(t.value, lo, hi))
        .collect()
}

/// Log ticks: labelled decades (every n-th decade over a wide range, unlabelled ticks at the
/// others); over a range of less than about two decades, ticks at 1–9 × 10^k with 1, 2, 5
/// labelled (or all of them over less than a decade).
pub fn log_ticks(lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    let (a, b) = (lo.log10(), hi.log10());
    let first = a.ceil() as i64;
    let last = b.floor() as i64;
    let decades = last - first + 1;
    if b - a >= 2.5 {
        let every = (nice_step((b - a).max(1.0), target.max(2)).round() as i64).max(1);
        return (first..=last)
            .map(|k| Tick {
                value: 10f64.powi(k as i32),
                label: (k.rem_euclid(every) == 0).then(|| power_of_ten(k)),
            })
            .collect();
    }
    let label_all = decades <= 0 || b - a < 1.0;
    let mut out = Vec::new();
    for k in (a.floor() as i64)..=(b.ceil() as i64) {
        for m in 1..=9 {
            let v = m as f64 * 10f64.powi(k as i32);
            if !in_range(v, lo, hi) {
                continue;
            }
            let labelled = label_all || m == 1 || m == 2 || m == 5;
            out.push(Tick { value: v, label: labelled.then(|| format_log_value(m, k)) });
        }
    }
    if out.iter().filter(|t| t.label.is_some()).count() < 2 {
        // Less than a decade and too few multiples inside: fall back to linear ticks.
        return linear_ticks(lo, hi, target).into_iter().filter(|t| t.value > 0.0).collect();
    }
    out
}

/// `10^{k}` markup.
pub fn power_of_ten(k: i64) -> String {
    match k {
        0 => "1".into(),
        1 => "10".into(),
        k => format!("10^{{{}}}", minus(&k.to_string())),
    }
}

fn format_log_value(m: i64, k: i64) -> String {
    if (-3..=4).contains(&k) {
        format_linear(m as f64 * 10f64.powi(k as i32), 10f64.powi(k as i32))
    } else if m == 1 {
        power_of_ten(k)
    } else {
        format!("{m}×{}", power_of_ten(k))
    }
}

/// Uses the typographic minus sign (U+2212).
fn minus(s: &str) -> String {
    s.replace('-', "−")
}

/// The label of `v`, a multiple of `step`: as many decimals as the step needs, and
/// `m×10^{k}` markup for very large or very small magnitudes.
pub fn format_linear(v: f64, step: f64) -> String {
    let v = if v.abs() < 1e-9 * step.abs() { 0.0 } else { v };
    let step_exp = step.abs().log10().floor() as i32;
    let mag = if v == 0.0 { 0 } else { v.abs().log10().floor() as i32 };
    if !(-3..5).contains(&mag) {
        // m × 10^mag with the digits the step needs.
        let decimals = (mag - step_exp).clamp(0, 6) as usize;
        let mantissa = v / 10f64.powi(mag);
        let m = format!("{mantissa:.decimals$}");
        let m = trim_decimals(&m);
        return if m == "1" {
            power_of_ten(mag as i64)
        } else if m == "-1" {
            minus(&format!("-{}", power_of_ten(mag as i64)))
        } else {
            format!("{}×{}", minus(&m), power_of_ten(mag as i64))
        };
    }
    // Decimals needed by the step (e.g. 0.25 needs 2).
    let mut decimals = (-step_exp).max(0) as usize;
    while decimals < 12
        && ((step * 10f64.powi(decimals as i32)).round() - step * 10f64.powi(decimals as i32)).abs()
            > 1e-6
    {
        decimals += 1;
    }
    minus(&format!("{v:.decimals$}"))
}

fn trim_decimals(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(ticks: &[Tick]) -> Vec<String> {
        ticks.iter().filter_map(|t| t.label.clone()).collect()
    }

    #[test]
    fn nice_steps_are_1_2_5_times_a_power_of_ten() {
        assert_eq!(nice_step(10.0, 5), 2.0);
        assert_eq!(nice_step(1.0, 5), 0.2);
        assert_eq!(nice_step(100.0, 4), 20.0);
        assert_eq!(nice_step(7.0, 5), 1.0);
        assert_eq!(nice_step(0.003, 6), 5e-4);
        assert_eq!(nice_step(3.5e6, 5), 1e6);
        for span in [0.013, 0.7, 1.0, 3.3, 47.0, 1e5, 6.1e-7] {
            for target in [3, 5, 8] {
                let s = nice_step(span, target);
                let m = s / 10f64.powf(s.log10().floor());
                assert!(
                    [1.0, 2.0, 5.0, 10.0].iter().any(|n| (m - n).abs() < 1e-9),
                    "{span} {target} → {s}"
                );
                let n = span / s;
                assert!(
                    n > target as f64 / 3.0 && n < target as f64 * 2.5,
                    "{span} {target} → {n} intervals"
                );
            }
        }
    }

    #[test]
    fn linear_ticks_are_exact_multiples_with_clean_labels() {
        let t = linear_ticks(-0.3, 1.3, 5);
        assert_eq!(labels(&t), ["0.0", "0.5", "1.0"].map(String::from));
        let t = linear_ticks(0.0, 10.0, 5);
        assert_eq!(labels(&t), ["0", "2", "4", "6", "8", "10"].map(String::from));
        assert_eq!(t.len(), 11, "a minor tick between labelled ones");
        let t = linear_ticks(-23.0, -1.0, 4);
        assert_eq!(labels(&t), ["−20", "−15", "−10", "−5"].map(String::from));
        // 0.1 + 0.2 style rounding never shows up in labels.
        let t = linear_ticks(0.0, 0.7, 7);
        assert_eq!(
            labels(&t),
            ["0.0", "0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7"].map(String::from)
        );
        // Large magnitudes: m×10^k markup.
        let t = linear_ticks(0.0, 3e6, 3);
        assert_eq!(labels(&t), ["0", "10^{6}", "2×10^{6}", "3×10^{6}"].map(String::from));
        let t = linear_ticks(1.5e-5, 3.5e-5, 4);
        assert_eq!(
            labels(&t),
            ["1.5×10^{−5}", "2×10^{−5}", "2.5×10^{−5}", "3×10^{−5}", "3.5×10^{−5}"]
                .map(String::from)
        );
        // Every tick is inside the range, including its ends.
        for t in linear_ticks(0.2, 0.8, 6) {
            assert!(t.value >= 0.2 - 1e-12 && t.value <= 0.8 + 1e-12);
        }
        assert_eq!(linear_ticks(0.2, 0.8, 6).first().unwrap().value, 0.2);
    }

    #[test]
    fn log_ticks_label_decades_and_thin_them_over_wide_ranges() {
        let t = log_ticks(1.0, 1e8, 5);
        assert_eq!(t.len(), 9, "a tick at every decade");
        assert_eq!(labels(&t), ["1", "10^{2}", "10^{4}", "10^{6}", "10^{8}"].map(String::from));
        let t = log_ticks(0.5, 2e3, 6);
        assert_eq!(labels(&t), ["1", "10", "10^{2}", "10^{3}"].map(String::from));
        let t = log_ticks(1e-30, 1e10, 5);
        assert!(labels(&t).contains(&"10^{−30}".to_string()), "{:?}", labels(&t));
        assert!(labels(&t).len() <= 9);
        // Less than two decades: 1, 2, 5 labelled, other multiples as minor ticks.
        let t = log_ticks(0.8, 30.0, 6);
        assert_eq!(labels(&t), ["1", "2", "5", "10", "20"].map(String::from));
        assert!(t.iter().any(|t| t.value == 3.0 && t.label.is_none()));
        // Less than a decade: every multiple labelled.
        let t = log_ticks(2.5, 9.5, 6);
        assert_eq!(labels(&t), ["3", "4", "5", "6", "7", "8", "9"].map(String::from));
        // Inside one multiple: linear ticks.
        let t = log_ticks(3.1, 3.9, 4);
        assert_eq!(labels(&t), ["3.2", "3.4", "3.6", "3.8"].map(String::from));
        let t = log_ticks(2e5, 9e5, 4);
        assert!(labels(&t).iter().all(|l| l.contains("×10^{5}")), "{:?}", labels(&t));
    }

    #[test]
    fn mapping_is_linear_or_logarithmic_and_inverts() {
        let s = Scale { kind: ScaleKind::Linear, lo: -1.0, hi: 3.0, px_lo: 100.0, px_hi: 500.0 };
        assert_eq!(s.map(-1.0), 100.0);
        assert_eq!(s.map(3.0), 500.0);
        assert_eq!(s.map(1.0), 300.0);
        assert!((s.unmap(s.map(0.37)) - 0.37).abs() < 1e-12);
        let y = Scale { kind: ScaleKind::Log10, lo: 1e-2, hi: 1e6, px_lo: 400.0, px_hi: 0.0 };
        assert_eq!(y.map(1e-2), 400.0);
        assert!((y.map(1e6) - 0.0).abs() < 1e-9);
        assert!((y.map(1e2) - 200.0).abs() < 1e-9, "the middle decade in the middle");
        assert!((y.unmap(y.map(3.7e4)) / 3.7e4 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn automatic_ranges_are_padded_and_never_empty() {
        assert_eq!(padded(ScaleKind::Linear, 0.0, 10.0, 0.05), (-0.5, 10.5));
        let (lo, hi) = padded(ScaleKind::Log10, 1.0, 1e4, 0.25);
        assert!((lo - 0.1).abs() < 1e-12 && (hi - 1e5).abs() < 1e-6);
        assert_eq!(widen(ScaleKind::Linear, 2.0, 2.0), (1.8, 2.2));
        assert_eq!(widen(ScaleKind::Linear, 0.0, 0.0), (-1.0, 1.0));
        let (lo, hi) = widen(ScaleKind::Log10, 5.0, 5.0);
        assert!(lo < 5.0 && hi > 5.0);
    }
}
