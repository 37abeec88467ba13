//! Labels with a tiny markup: `_{...}` for a subscript and `^{...}` for a superscript, e.g.
//! `"D_{c}/v_{0}"` or `"10^{−3}"`. Everything else is literal text (escaped for SVG). Also a
//! width estimate, which is all the layout needs to keep labels from overlapping.

/// A piece of a label: normal, subscript or superscript text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Shift {
    Normal,
    Sub,
    Super,
}

fn pieces(label: &str) -> Vec<(Shift, &str)> {
    let mut out = Vec::new();
    let mut rest = label;
    while !rest.is_empty() {
        let next = [rest.find("_{"), rest.find("^{")].into_iter().flatten().min();
        let Some(i) = next else {
            out.push((Shift::Normal, rest));
            break;
        };
        let Some(close) = rest[i + 2..].find('}') else {
            out.push((Shift::Normal, rest));
            break;
        };
        if i > 0 {
            out.push((Shift::Normal, &rest[..i]));
        }
        let shift = if rest[i..].starts_with('_') { Shift::Sub } else { Shift::Super };
        out.push((shift, &rest[i + 2..i + 2 + close]));
        rest = &rest[i + 3 + close..];
    }
    out
}

/// The label as SVG text content: escaped, with `<tspan>`s for sub- and superscripts (shifted
/// with `dy` and shifted back, so the rest of the label stays on the baseline). Spaces next to
/// a tspan boundary would be dropped by SVG's whitespace rules (librsvg drops even no-break
/// spaces there), so they become a horizontal shift `dx` of 0.32 em per space instead.
pub fn to_svg(label: &str) -> String {
    let mut s = String::new();
    let mut shift_em = 0.0f64;
    let mut spaces = 0usize;
    for (kind, text) in pieces(label) {
        let target = match kind {
            Shift::Normal => 0.0,
            Shift::Sub => 0.3,
            Shift::Super => -0.45,
        };
        // dy and dx are in units of the tspan's own (possibly smaller) font size.
        let size = if kind == Shift::Normal { 1.0 } else { 0.72 };
        let dy = (target - shift_em) / size;
        shift_em = target;
        let trimmed = text.trim_start_matches(' ');
        spaces += text.len() - trimmed.len();
        let core = trimmed.trim_end_matches(' ');
        let dx = if s.is_empty() { 0.0 } else { 0.32 * spaces as f64 / size };
        spaces = trimmed.len() - core.len();
        let text = super::svg::escape(core);
        let mut attrs = String::new();
        if dx != 0.0 {
            attrs.push_str(&format!(" dx=\"{dx:.3}em\""));
        }
        if dy != 0.0 {
            attrs.push_str(&format!(" dy=\"{dy:.3}em\""));
        }
        if kind != Shift::Normal {
            attrs.push_str(" font-size=\"72%\"");
        }
        if attrs.is_empty() {
            s.push_str(&text);
        } else {
            s.push_str(&format!("<tspan{attrs}>{text}</tspan>"));
        }
    }
    s
}

/// The label without markup (for titles and plain-text output).
pub fn plain(label: &str) -> String {
    pieces(label)
        .into_iter()
        .map(|(k, t)| match k {
            Shift::Normal => t.to_string(),
            Shift::Sub => format!("_{t}"),
            Shift::Super => format!("^{t}"),
        })
        .collect()
}

/// Approximate width in pixels of the label at `font_size` px in a sans-serif font (a
/// generous average advance of 0.6 em per character; sub/superscripts at 72 %).
pub fn width(label: &str, font_size: f64) -> f64 {
    pieces(label)
        .into_iter()
        .map(|(k, t)| {
            let scale = if k == Shift::Normal { 1.0 } else { 0.72 };
            t.chars().map(|c| if c == ' ' || c == '.' || c == ',' { 0.3 } else { 0.6 }).sum::<f64>()
                * scale
        })
        .sum::<f64>()
        * font_size
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_becomes_shifted_tspans_and_returns_to_the_baseline() {
        assert_eq!(to_svg("u"), "u");
        let s = to_svg("D_{c}/v_{0} & x");
        assert!(s.starts_with("D<tspan dy=\"0.417em\" font-size=\"72%\">c</tspan><tspan dy=\"-0.300em\">/v</tspan>"), "{s}");
        assert!(s.ends_with("<tspan dx=\"0.320em\" dy=\"-0.300em\">&amp; x</tspan>"), "{s}");
        assert_eq!(to_svg("e^{−t} + 1"), "e<tspan dy=\"-0.625em\" font-size=\"72%\">−t</tspan><tspan dx=\"0.320em\" dy=\"0.450em\">+ 1</tspan>");
        assert_eq!(to_svg("a b"), "a b");
        let s = to_svg("10^{−3}");
        assert_eq!(s, "10<tspan dy=\"-0.625em\" font-size=\"72%\">−3</tspan>");
        // Unbalanced markup stays literal.
        assert_eq!(to_svg("a_{b"), "a_{b");
        assert_eq!(plain("ξu + θ + ln v = 0, t_{c}"), "ξu + θ + ln v = 0, t_c");
    }

    #[test]
    fn width_grows_with_length_and_shrinks_for_scripts() {
        assert!(width("abcd", 10.0) > width("ab", 10.0));
        assert!(width("a_{bc}", 10.0) < width("abc", 10.0));
        assert_eq!(width("", 10.0), 0.0);
    }
}
