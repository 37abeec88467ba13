//! Data series (lines, markers, both), their style, and a palette that stays readable in
//! print and for colour-blind readers.

/// The Okabe–Ito palette without its yellow (too pale on paper), ordered so that neighbours
/// differ in lightness as well as hue: blue, vermillion, bluish green, black, reddish purple,
/// orange, sky blue.
pub const PALETTE: [&str; 7] =
    ["#0072B2", "#D55E00", "#009E73", "#000000", "#CC79A7", "#E69F00", "#56B4E9"];

/// The `i`-th palette colour (cycling).
pub fn colour(i: usize) -> &'static str {
    PALETTE[i % PALETTE.len()]
}

/// Line pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Dash {
    /// Solid.
    #[default]
    Solid,
    /// Long dashes.
    Dashed,
    /// Dots.
    Dotted,
    /// Dash-dot.
    DashDot,
}

impl Dash {
    /// The `i`-th pattern (cycling), to tell series apart in black and white.
    pub fn nth(i: usize) -> Self {
        [Dash::Solid, Dash::Dashed, Dash::DashDot, Dash::Dotted][i % 4]
    }

    /// The SVG `stroke-dasharray` for a line of width `w`, if not solid.
    pub fn dasharray(self, w: f64) -> Option<String> {
        let w = w.max(1.0);
        match self {
            Dash::Solid => None,
            Dash::Dashed => Some(format!("{} {}", 5.0 * w, 3.0 * w)),
            Dash::Dotted => Some(format!("{} {}", w, 2.0 * w)),
            Dash::DashDot => Some(format!("{} {} {} {}", 6.0 * w, 2.5 * w, w, 2.5 * w)),
        }
    }
}

/// Marker shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle, point up.
    Triangle,
    /// Open circle.
    OpenCircle,
    /// A cross (×).
    Cross,
}

/// How a series is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Style {
    /// Stroke/fill colour (CSS colour).
    pub colour: String,
    /// Line width in px; 0 draws no line.
    pub width: f64,
    /// Line pattern.
    pub dash: Dash,
    /// Marker at each point, if any.
    pub marker: Option<Marker>,
    /// Marker size (diameter) in px.
    pub marker_size: f64,
}

impl Style {
    /// A solid line of the `i`-th palette colour.
    pub fn line(i: usize) -> Self {
        Self {
            colour: colour(i).into(),
            width: 1.6,
            dash: Dash::Solid,
            marker: None,
            marker_size: 6.0,
        }
    }

    /// Markers only, of the `i`-th palette colour.
    pub fn markers(i: usize, marker: Marker) -> Self {
        Self { width: 0.0, marker: Some(marker), ..Self::line(i) }
    }

    /// Replaces the line pattern.
    pub fn dash(mut self, dash: Dash) -> Self {
        self.dash = dash;
        self
    }

    /// Replaces the line width (px).
    pub fn width(mut self, width: f64) -> Self {
        self.width = width;
        self
    }

    /// Adds a marker at each point.
    pub fn marker(mut self, marker: Marker) -> Self {
        self.marker = Some(marker);
        self
    }

    /// Replaces the marker size (diameter, px).
    pub fn marker_size(mut self, px: f64) -> Self {
        self.marker_size = px;
        self
    }
}

/// A named set of (x, y) points drawn in one style. Points are joined in order; a line breaks
/// where the data jumps out of the panel's range.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label (markup, see [`super::text`]); empty for no legend entry.
    pub label: String,
    /// x values.
    pub x: Vec<f64>,
    /// y values (same length as x).
    pub y: Vec<f64>,
    /// Drawing style.
    pub style: Style,
}

impl Series {
    /// A series from x and y values and a style.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, style: Style) -> Self {
        Self { label: label.into(), x, y, style }
    }

    /// Replaces the line pattern.
    pub fn dash(mut self, dash: Dash) -> Self {
        self.style.dash = dash;
        self
    }

    /// Replaces the line width.
    pub fn width(mut self, width: f64) -> Self {
        self.style.width = width;
        self
    }

    /// Adds markers.
    pub fn marker(mut self, marker: Marker) -> Self {
        self.style.marker = Some(marker);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn palette_and_dashes_cycle() {
        assert_eq!(colour(0), colour(PALETTE.len()));
        assert_ne!(colour(0), colour(1));
        assert!(PALETTE.iter().all(|c| c.len() == 7 && c.starts_with('#')));
        assert_eq!(Dash::nth(4), Dash::Solid);
        assert_eq!(Dash::Solid.dasharray(2.0), None);
        assert_eq!(Dash::Dashed.dasharray(2.0).as_deref(), Some("10 6"));
    }
}
