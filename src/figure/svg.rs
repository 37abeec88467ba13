//! A minimal SVG writer (escaping done here, once) and a well-formedness checker for what it
//! writes.

use std::collections::BTreeMap;
use std::fmt::Write;

/// Escapes text content and attribute values (`&`, `<`, `>`, `"`, `'`).
pub fn escape(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            '\'' => s.push_str("&apos;"),
            c => s.push(c),
        }
    }
    s
}

/// A coordinate in pixels, written with two decimals (`-0.00` written as `0`).
pub fn px(x: f64) -> String {
    let s = format!("{x:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() { "0".into() } else { s.into() }
}

/// An SVG document being written: elements are opened, filled and closed in order; attribute
/// values and text are escaped on the way in.
#[derive(Debug, Default)]
pub struct Svg {
    out: String,
    open: Vec<&'static str>,
}

impl Svg {
    /// A document of `width` × `height` pixels; `title` becomes its `<title>`.
    pub fn new(width: f64, height: f64, title: &str) -> Self {
        let mut svg = Self::default();
        svg.out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        svg.open(
            "svg",
            &[
                ("xmlns", "http://www.w3.org/2000/svg".into()),
                ("width", px(width)),
                ("height", px(height)),
                ("viewBox", format!("0 0 {} {}", px(width), px(height))),
                ("font-family", super::FONT_FAMILY.into()),
            ],
        );
        svg.open("title", &[]);
        svg.out.push_str(&escape(title));
        svg.close();
        svg
    }

    fn start_tag(&mut self, name: &str, attrs: &[(&str, String)]) {
        let _ = write!(self.out, "<{name}");
        for (k, v) in attrs {
            let _ = write!(self.out, " {k}=\"{}\"", escape(v));
        }
    }

    /// Opens an element; close it with [`Svg::close`].
    pub fn open(&mut self, name: &'static str, attrs: &[(&str, String)]) {
        self.start_tag(name, attrs);
        self.out.push_str(">\n");
        self.open.push(name);
    }

    /// Closes the innermost open element.
    pub fn close(&mut self) {
        if let Some(name) = self.open.pop() {
            let _ = writeln!(self.out, "</{name}>");
        }
    }

    /// An empty element, e.g. `<line .../>`.
    pub fn empty(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.start_tag(name, attrs);
        self.out.push_str("/>\n");
    }

    /// A `<text>` element whose content is already-escaped markup (from
    /// [`super::text::to_svg`]), so it may contain `<tspan>`s.
    pub fn text_markup(&mut self, attrs: &[(&str, String)], markup: &str) {
        self.start_tag("text", attrs);
        let _ = writeln!(self.out, ">{markup}</text>");
    }

    /// Closes every open element and returns the document.
    pub fn finish(mut self) -> String {
        while !self.open.is_empty() {
            self.close();
        }
        self.out
    }
}

/// Checks that `xml` is a well-formed XML document of the kind [`Svg`] writes (a prolog,
/// comments, elements with quoted attributes, text with only the predefined or numeric entity
/// references) with a single root element. Returns the number of elements of each name.
pub fn check_well_formed(xml: &str) -> Result<BTreeMap<String, usize>, String> {
    let mut counts = BTreeMap::new();
    let mut stack: Vec<&str> = Vec::new();
    let mut roots = 0;
    let mut rest = xml;
    let offset = |rest: &str| xml.len() - rest.len();
    if let Some(r) = rest.strip_prefix("<?xml") {
        let end = r.find("?>").ok_or("unterminated XML declaration")?;
        rest = &r[end + 2..];
    }
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("<!--") {
            let end = r.find("-->").ok_or_else(|| format!("unterminated comment at byte {}", offset(rest)))?;
            rest = &r[end + 3..];
        } else if let Some(r) = rest.strip_prefix("</") {
            let end = r.find('>').ok_or_else(|| format!("unterminated end tag at byte {}", offset(rest)))?;
            let name = r[..end].trim_end();
            match stack.pop() {
                Some(open) if open == name => {}
                Some(open) => return Err(format!("</{name}> at byte {} closes <{open}>", offset(rest))),
                None => return Err(format!("</{name}> at byte {} closes nothing", offset(rest))),
            }
            rest = &r[end + 1..];
        } else if let Some(r) = rest.strip_prefix('<') {
            let name_end = r.find(|c: char| c.is_whitespace() || c == '>' || c == '/').ok_or("unterminated start tag")?;
            let name = &r[..name_end];
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == ':' || c == '_') {
                return Err(format!("bad element name {name:?} at byte {}", offset(rest)));
            }
            let mut a = &r[name_end..];
            let mut seen = Vec::new();
            let self_closing = loop {
                a = a.trim_start();
                if let Some(t) = a.strip_prefix("/>") {
                    a = t;
                    break true;
                }
                if let Some(t) = a.strip_prefix('>') {
                    a = t;
                    break false;
                }
                let eq = a.find('=').ok_or_else(|| format!("attribute without value in <{name}>"))?;
                let key = a[..eq].trim();
                if key.is_empty() || key.contains(|c: char| c.is_whitespace() || c == '<' || c == '"') {
                    return Err(format!("bad attribute name {key:?} in <{name}>"));
                }
                if seen.contains(&key) {
                    return Err(format!("duplicate attribute {key} in <{name}>"));
                }
                seen.push(key);
                let v = a[eq + 1..].trim_start();
                let quote = v.chars().next().filter(|&c| c == '"' || c == '\'').ok_or_else(|| format!("unquoted value of {key} in <{name}>"))?;
                let close = v[1..].find(quote).ok_or_else(|| format!("unterminated value of {key} in <{name}>"))?;
                let value = &v[1..1 + close];
                if value.contains('<') {
                    return Err(format!("'<' in the value of {key} in <{name}>"));
                }
                check_entities(value)?;
                a = &v[close + 2..];
            };
            if stack.is_empty() {
                roots += 1;
                if roots > 1 {
                    return Err(format!("a second root element <{name}>"));
                }
            }
            *counts.entry(name.to_string()).or_insert(0) += 1;
            if !self_closing {
                stack.push(name);
            }
            rest = a;
        } else {
            let end = rest.find('<').unwrap_or(rest.len());
            let text = &rest[..end];
            if stack.is_empty() && !text.trim().is_empty() {
                return Err(format!("text outside the root element at byte {}", offset(rest)));
            }
            if text.contains('>') && text.contains("]]>") {
                return Err("']]>' in text".into());
            }
            check_entities(text)?;
            rest = &rest[end..];
        }
    }
    if let Some(open) = stack.last() {
        return Err(format!("<{open}> is never closed"));
    }
    if roots == 0 {
        return Err("no root element".into());
    }
    Ok(counts)
}

fn check_entities(text: &str) -> Result<(), String> {
    let mut rest = text;
    while let Some(i) = rest.find('&') {
        let r = &rest[i + 1..];
        let end = r.find(';').ok_or_else(|| format!("'&' without ';' in {text:?}"))?;
        let name = &r[..end];
        let ok = matches!(name, "amp" | "lt" | "gt" | "quot" | "apos")
            || name.strip_prefix("#x").is_some_and(|h| !h.is_empty() && h.chars().all(|c| c.is_ascii_hexdigit()))
            || name.strip_prefix('#').is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()));
        if !ok {
            return Err(format!("unknown entity &{name}; in {text:?}"));
        }
        rest = &r[end + 1..];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaping_round_trips_through_the_checker() {
        assert_eq!(escape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
        let mut svg = Svg::new(100.0, 50.0, "<title> & more");
        svg.empty("rect", &[("x", px(1.0)), ("fill", "a\"b<c>&".into())]);
        svg.text_markup(&[("x", "3".into())], &escape("1 < 2 & 3 > 2"));
        let doc = svg.finish();
        let counts = check_well_formed(&doc).unwrap();
        assert_eq!(counts["svg"], 1);
        assert_eq!(counts["rect"], 1);
        assert_eq!(counts["text"], 1);
        assert_eq!(counts["title"], 1);
    }

    #[test]
    fn the_checker_rejects_malformed_documents() {
        for bad in [
            "<svg><g></svg>",
            "<svg><g></g>",
            "<svg a=\"1\" a=\"2\"/>",
            "<svg a=1/>",
            "<svg>1 & 2</svg>",
            "<svg>&nbsp;</svg>",
            "<svg/><svg/>",
            "<svg b=\"<\"/>",
            "text<svg/>",
            "",
        ] {
            assert!(check_well_formed(bad).is_err(), "{bad:?} passed");
        }
        assert!(check_well_formed("<?xml version=\"1.0\"?>\n<!-- c --><svg a='1'>&#955;&#x3bb;<g/></svg>\n").is_ok());
    }

    #[test]
    fn pixel_coordinates_are_short_and_never_negative_zero() {
        assert_eq!(px(1.0), "1");
        assert_eq!(px(1.256), "1.26");
        assert_eq!(px(-0.001), "0");
        assert_eq!(px(12.5), "12.5");
    }
}
