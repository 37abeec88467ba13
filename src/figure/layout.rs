//! A figure: a title, panels on a grid, and caption lines (parameters, units, method).

use super::panel::Panel;
use super::svg::{px, Svg};
use super::{text, FigureError};
use std::path::Path;

/// Font size of the figure title (px).
const TITLE_FONT: f64 = 15.0;
/// Font size of the caption (px).
const CAPTION_FONT: f64 = 11.0;

/// A figure of one or more panels laid out in rows of `columns`.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title (markup).
    pub title: String,
    /// Panels, row by row.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
    /// Size of each panel in px (width, height).
    pub panel_size: (f64, f64),
    /// Caption paragraphs under the panels (markup), wrapped to the figure's width.
    pub caption: Vec<String>,
}

impl Figure {
    /// An empty figure with a title; one column of 480 × 340 px panels.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            panels: Vec::new(),
            columns: 1,
            panel_size: (480.0, 340.0),
            caption: Vec::new(),
        }
    }

    /// Adds a panel.
    pub fn panel(mut self, p: Panel) -> Self {
        self.panels.push(p);
        self
    }

    /// Sets the number of panels per row.
    pub fn columns(mut self, n: usize) -> Self {
        self.columns = n.max(1);
        self
    }

    /// Sets the size of each panel (px).
    pub fn panel_size(mut self, w: f64, h: f64) -> Self {
        self.panel_size = (w, h);
        self
    }

    /// Adds a caption paragraph.
    pub fn caption(mut self, line: impl Into<String>) -> Self {
        self.caption.push(line.into());
        self
    }

    /// The SVG document; checked to be well-formed before it is returned.
    pub fn to_svg(&self) -> Result<String, FigureError> {
        if self.panels.is_empty() {
            return Err(FigureError::Empty {
                panel: format!("{} (the figure has no panel)", text::plain(&self.title)),
            });
        }
        let cols = self.columns.min(self.panels.len());
        let rows = self.panels.len().div_ceil(cols);
        let (pw, ph) = self.panel_size;
        let width = cols as f64 * pw;
        let title_h = if self.title.is_empty() { 0.0 } else { TITLE_FONT + 14.0 };
        let caption_lines: Vec<String> =
            self.caption.iter().flat_map(|c| wrap(c, width - 24.0, CAPTION_FONT)).collect();
        let caption_h = if caption_lines.is_empty() {
            0.0
        } else {
            8.0 + caption_lines.len() as f64 * (CAPTION_FONT + 4.0)
        };
        let height = title_h + rows as f64 * ph + caption_h + 6.0;
        let mut doc = Svg::new(width, height, &text::plain(&self.title));
        doc.empty(
            "rect",
            &[
                ("x", "0".into()),
                ("y", "0".into()),
                ("width", px(width)),
                ("height", px(height)),
                ("fill", "white".into()),
            ],
        );
        if !self.title.is_empty() {
            let size = (TITLE_FONT
                * ((width - 24.0) / text::width(&self.title, TITLE_FONT)).min(1.0))
            .max(9.0);
            doc.text_markup(
                &[
                    ("x", px(width / 2.0)),
                    ("y", px(8.0 + TITLE_FONT)),
                    ("text-anchor", "middle".into()),
                    ("font-size", px(size)),
                    ("font-weight", "bold".into()),
                    ("fill", "#222222".into()),
                ],
                &text::to_svg(&self.title),
            );
        }
        for (i, p) in self.panels.iter().enumerate() {
            let (r, c) = (i / cols, i % cols);
            p.render(
                &mut doc,
                c as f64 * pw,
                title_h + r as f64 * ph,
                pw,
                ph,
                &format!("clip{i}"),
            )?;
        }
        let y0 = title_h + rows as f64 * ph + 8.0;
        for (k, line) in caption_lines.iter().enumerate() {
            doc.text_markup(
                &[
                    ("x", "12".into()),
                    ("y", px(y0 + CAPTION_FONT + k as f64 * (CAPTION_FONT + 4.0))),
                    ("font-size", px(CAPTION_FONT)),
                    ("fill", "#444444".into()),
                ],
                &text::to_svg(line),
            );
        }
        Ok(doc.finish())
    }

    /// Writes the SVG to `path` (atomically: see [`stickslip::report::write_atomic`]).
    pub fn write(&self, path: &Path) -> Result<(), FigureError> {
        let svg = self.to_svg()?;
        stickslip::report::write_atomic(path, &svg)
            .map_err(|source| FigureError::Io { path: path.display().to_string(), source })
    }
}

/// Splits `text` into lines of at most `width` px at `font` px (at word boundaries; markup
/// groups are never split).
fn wrap(text: &str, width: f64, font: f64) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let candidate = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
        if !line.is_empty() && text::width(&candidate, font) > width {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        } else {
            line = candidate;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figure::Axis;

    #[test]
    fn errors_name_the_panel() {
        let f = Figure::new("bad").panel(Panel::new(
            "(c) empty",
            Axis::linear("x").unit("m"),
            Axis::linear("y").unit("m"),
        ));
        let e = f.to_svg().unwrap_err();
        assert!(e.to_string().contains("(c) empty"), "{e}");
        assert!(Figure::new("none").to_svg().is_err());
    }

    #[test]
    fn captions_wrap_at_word_boundaries() {
        let lines = wrap("one two three four five six", 60.0, 10.0);
        assert!(lines.len() > 1);
        assert_eq!(lines.join(" "), "one two three four five six");
        assert!(lines.iter().all(|l| text::width(l, 10.0) <= 60.0 || !l.contains(' ')));
    }
}
