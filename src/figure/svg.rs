//! A minimal SVG writer (escaping done here, once). The tests check that what it writes is
//! well-formed XML (tests/xml/, tests/figures.rs).

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
    if s == "-0" || s.is_empty() {
        "0".into()
    } else {
        s.into()
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_coordinates_are_short_and_never_negative_zero() {
        assert_eq!(px(1.0), "1");
        assert_eq!(px(1.256), "1.26");
        assert_eq!(px(-0.001), "0");
        assert_eq!(px(12.5), "12.5");
    }
}
