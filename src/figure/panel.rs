//! One panel: axes (with units), series, reference lines, notes and a legend, drawn into a
//! rectangle of the figure.

use super::scale::{self, Scale, ScaleKind, Tick};
use super::series::{Marker, Series, Style};
use super::svg::{px, Svg};
use super::{text, FigureError};

/// Font size of tick labels (px).
const TICK_FONT: f64 = 11.0;
/// Font size of axis titles (px).
const LABEL_FONT: f64 = 13.0;
/// Font size of panel titles (px).
const TITLE_FONT: f64 = 13.0;
/// Font size of legend entries and notes (px).
const SMALL_FONT: f64 = 11.0;
/// Length of a labelled tick (px); unlabelled ones are 3/5 of it.
const TICK_LEN: f64 = 5.0;
/// Colour of frames, ticks and text.
const INK: &str = "#222222";

#[derive(Debug, Clone, PartialEq)]
enum Unit {
    Unset,
    Of(String),
    Dimensionless,
}

/// An axis: its quantity, its unit (required), its scale and optionally a fixed range.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    label: String,
    unit: Unit,
    /// Linear or log10.
    pub kind: ScaleKind,
    range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis for the quantity `label` (markup, e.g. `"v/γ"`).
    pub fn linear(label: impl Into<String>) -> Self {
        Self { label: label.into(), unit: Unit::Unset, kind: ScaleKind::Linear, range: None }
    }

    /// A log10 axis for the quantity `label`.
    pub fn log10(label: impl Into<String>) -> Self {
        Self { kind: ScaleKind::Log10, ..Self::linear(label) }
    }

    /// The quantity's unit (markup, e.g. `"D_{c}/v_{0}"`), shown as `label [unit]`.
    pub fn unit(mut self, unit: impl Into<String>) -> Self {
        self.unit = Unit::Of(unit.into());
        self
    }

    /// Declares the quantity dimensionless, shown as `label (dimensionless)`.
    pub fn dimensionless(mut self) -> Self {
        self.unit = Unit::Dimensionless;
        self
    }

    /// A fixed range instead of the data's (padded) range.
    pub fn range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some((lo, hi));
        self
    }

    /// The axis title as drawn: quantity and unit.
    pub fn title(&self) -> String {
        match &self.unit {
            Unit::Of(u) => format!("{} [{u}]", self.label),
            Unit::Dimensionless => format!("{} (dimensionless)", self.label),
            Unit::Unset => self.label.clone(),
        }
    }
}

/// A filled band between two curves lo(x) and hi(x) (e.g. mean ± σ of an ensemble), drawn
/// under the series.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Legend label (markup); empty for none.
    pub label: String,
    /// x values.
    pub x: Vec<f64>,
    /// Lower edge at each x.
    pub lo: Vec<f64>,
    /// Upper edge at each x.
    pub hi: Vec<f64>,
    /// Fill colour.
    pub colour: String,
    /// Fill opacity (0–1).
    pub opacity: f64,
}

impl Band {
    /// A band of the `i`-th palette colour at 25 % opacity.
    pub fn new(
        label: impl Into<String>,
        x: Vec<f64>,
        lo: Vec<f64>,
        hi: Vec<f64>,
        i: usize,
    ) -> Self {
        Self {
            label: label.into(),
            x,
            lo,
            hi,
            colour: super::series::colour(i).into(),
            opacity: 0.25,
        }
    }
}

/// A horizontal or vertical reference line across the panel (e.g. a threshold, an event time).
#[derive(Debug, Clone, PartialEq)]
pub struct RefLine {
    /// Vertical (at an x value) or horizontal (at a y value).
    pub vertical: bool,
    /// The x or y value.
    pub value: f64,
    /// Legend label (markup); empty for none.
    pub label: String,
    /// Drawing style (markers ignored).
    pub style: Style,
}

impl RefLine {
    /// A horizontal line at y = `value`.
    pub fn horizontal(value: f64, label: impl Into<String>, style: Style) -> Self {
        Self { vertical: false, value, label: label.into(), style }
    }

    /// A vertical line at x = `value`.
    pub fn vertical(value: f64, label: impl Into<String>, style: Style) -> Self {
        Self { vertical: true, value, label: label.into(), style }
    }
}

/// Horizontal alignment of a note.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    /// Text starts at the point.
    Start,
    /// Text is centred on the point.
    Middle,
    /// Text ends at the point.
    End,
}

/// Text at a data point (e.g. a parameter value next to a curve).
#[derive(Debug, Clone, PartialEq)]
pub struct Note {
    /// x (data units).
    pub x: f64,
    /// y (data units).
    pub y: f64,
    /// The text (markup).
    pub text: String,
    /// Alignment.
    pub anchor: Anchor,
    /// Colour.
    pub colour: String,
    /// Shift from the data point in px (right, down).
    pub offset: (f64, f64),
}

impl Note {
    /// A note in the ink colour.
    pub fn new(x: f64, y: f64, text: impl Into<String>, anchor: Anchor) -> Self {
        Self { x, y, text: text.into(), anchor, colour: INK.into(), offset: (0.0, 0.0) }
    }

    /// Shifts the note by (dx, dy) px from its data point (right, down).
    pub fn offset(mut self, dx: f64, dy: f64) -> Self {
        self.offset = (dx, dy);
        self
    }

    /// Replaces the colour.
    pub fn colour(mut self, colour: &str) -> Self {
        self.colour = colour.into();
        self
    }
}

/// Where the legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegendPlace {
    /// The corner (or top/bottom centre) where it hides the fewest data.
    Auto,
    /// Top left corner.
    TopLeft,
    /// Top right corner.
    TopRight,
    /// Bottom left corner.
    BottomLeft,
    /// Bottom right corner.
    BottomRight,
    /// No legend.
    Hidden,
}

/// A panel of a figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Title (markup), e.g. "(a) limit cycle".
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Data series, drawn in order.
    pub series: Vec<Series>,
    /// Reference lines, drawn under the series.
    pub lines: Vec<RefLine>,
    /// Filled bands, drawn under everything else.
    pub bands: Vec<Band>,
    /// Text notes.
    pub notes: Vec<Note>,
    /// Legend placement.
    pub legend: LegendPlace,
    /// Light grid lines at the labelled ticks.
    pub grid: bool,
}

/// The plot area in figure pixels.
#[derive(Debug, Clone, Copy)]
struct Rect {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

impl Rect {
    fn contains(&self, p: (f64, f64), margin: f64) -> bool {
        p.0 >= self.x - margin
            && p.0 <= self.x + self.w + margin
            && p.1 >= self.y - margin
            && p.1 <= self.y + self.h + margin
    }
}

impl Panel {
    /// An empty panel with a title and its two axes.
    pub fn new(title: impl Into<String>, x: Axis, y: Axis) -> Self {
        Self {
            title: title.into(),
            x,
            y,
            series: Vec::new(),
            lines: Vec::new(),
            bands: Vec::new(),
            notes: Vec::new(),
            legend: LegendPlace::Auto,
            grid: true,
        }
    }

    /// Adds a series.
    pub fn series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Adds a filled band.
    pub fn band(mut self, b: Band) -> Self {
        self.bands.push(b);
        self
    }

    /// Adds a reference line.
    pub fn line(mut self, l: RefLine) -> Self {
        self.lines.push(l);
        self
    }

    /// Adds a note.
    pub fn note(mut self, n: Note) -> Self {
        self.notes.push(n);
        self
    }

    /// Sets the legend placement.
    pub fn legend(mut self, place: LegendPlace) -> Self {
        self.legend = place;
        self
    }

    /// Checks the point `index` (x, y) of the series or band labelled `label`: finite, and
    /// positive on a logarithmic axis.
    fn check_point(&self, label: &str, index: usize, x: f64, y: f64) -> Result<(), FigureError> {
        let (panel, series) = (|| text::plain(&self.title), || text::plain(label));
        if !x.is_finite() || !y.is_finite() {
            return Err(FigureError::NonFinite { panel: panel(), series: series(), index, x, y });
        }
        for (axis, a, value) in [("x", &self.x, x), ("y", &self.y, y)] {
            if a.kind == ScaleKind::Log10 && value <= 0.0 {
                let (panel, series) = (panel(), series());
                return Err(FigureError::NonPositiveOnLog { panel, series, axis, index, value });
            }
        }
        Ok(())
    }

    /// Checks the data: see [`FigureError`].
    pub fn validate(&self) -> Result<(), FigureError> {
        let panel = || text::plain(&self.title);
        for (axis, a) in [("x", &self.x), ("y", &self.y)] {
            if a.unit == Unit::Unset {
                return Err(FigureError::MissingUnit {
                    panel: panel(),
                    axis,
                    label: text::plain(&a.label),
                });
            }
            if let Some((lo, hi)) = a.range {
                if !(lo.is_finite() && hi.is_finite() && lo < hi)
                    || (a.kind == ScaleKind::Log10 && lo <= 0.0)
                {
                    return Err(FigureError::BadRange { panel: panel(), axis, lo, hi });
                }
            }
        }
        for b in &self.bands {
            let series = || text::plain(&b.label);
            if b.lo.len() != b.x.len() || b.hi.len() != b.x.len() {
                return Err(FigureError::LengthMismatch {
                    panel: panel(),
                    series: series(),
                    x: b.x.len(),
                    y: b.lo.len().min(b.hi.len()),
                });
            }
            for (index, ((&x, &lo), &hi)) in b.x.iter().zip(&b.lo).zip(&b.hi).enumerate() {
                for y in [lo, hi] {
                    self.check_point(&b.label, index, x, y)?;
                }
            }
        }
        if self.series.iter().all(|s| s.x.is_empty()) && self.bands.iter().all(|b| b.x.is_empty()) {
            return Err(FigureError::Empty { panel: panel() });
        }
        for s in &self.series {
            let series = || text::plain(&s.label);
            if s.x.len() != s.y.len() {
                return Err(FigureError::LengthMismatch {
                    panel: panel(),
                    series: series(),
                    x: s.x.len(),
                    y: s.y.len(),
                });
            }
            for (index, (&x, &y)) in s.x.iter().zip(&s.y).enumerate() {
                self.check_point(&s.label, index, x, y)?;
            }
        }
        for l in &self.lines {
            let (axis, a) = if l.vertical { ("x", &self.x) } else { ("y", &self.y) };
            if !l.value.is_finite() {
                return Err(FigureError::NonFinite {
                    panel: panel(),
                    series: text::plain(&l.label),
                    index: 0,
                    x: l.value,
                    y: l.value,
                });
            }
            if a.kind == ScaleKind::Log10 && l.value <= 0.0 {
                return Err(FigureError::NonPositiveOnLog {
                    panel: panel(),
                    series: text::plain(&l.label),
                    axis,
                    index: 0,
                    value: l.value,
                });
            }
        }
        Ok(())
    }

    /// The data range along x (`vertical` lines count) or y.
    fn data_range(&self, along_x: bool) -> (f64, f64) {
        let values = self
            .series
            .iter()
            .flat_map(|s| if along_x { s.x.iter() } else { s.y.iter() })
            .copied()
            .chain(self.lines.iter().filter(|l| l.vertical == along_x).map(|l| l.value))
            .chain(self.bands.iter().flat_map(|b| {
                if along_x {
                    b.x.clone()
                } else {
                    b.lo.iter().chain(&b.hi).copied().collect()
                }
            }));
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    }

    fn axis_range(&self, along_x: bool) -> (f64, f64) {
        let a = if along_x { &self.x } else { &self.y };
        a.range.unwrap_or_else(|| {
            let (lo, hi) = self.data_range(along_x);
            scale::padded(a.kind, lo, hi, 0.03)
        })
    }

    /// Draws the panel into the rectangle (x0, y0, w, h) of `svg`; `id` must be unique in
    /// the figure (it names the clip path).
    pub fn render(
        &self,
        svg: &mut Svg,
        x0: f64,
        y0: f64,
        w: f64,
        h: f64,
        id: &str,
    ) -> Result<(), FigureError> {
        self.validate()?;
        let (xlo, xhi) = self.axis_range(true);
        let (ylo, yhi) = self.axis_range(false);
        let title_h = if self.title.is_empty() { 0.0 } else { TITLE_FONT + 8.0 };
        let top = 10.0 + title_h;
        let bottom = TICK_LEN + 4.0 + TICK_FONT + 8.0 + LABEL_FONT + 6.0;
        let ph = h - top - bottom;
        let y_ticks = scale::ticks(self.y.kind, ylo, yhi, ((ph / 45.0) as usize).clamp(3, 8));
        let y_label_w = y_ticks
            .iter()
            .filter_map(|t| t.label.as_deref())
            .map(|l| text::width(l, TICK_FONT))
            .fold(0.0, f64::max);
        let left = TICK_LEN + 4.0 + y_label_w + 8.0 + LABEL_FONT + 4.0;
        let mut right = 14.0;
        let mut pw = w - left - right;
        let mut target = ((pw / 65.0) as usize).clamp(2, 8);
        let x_ticks = loop {
            let t = scale::ticks(self.x.kind, xlo, xhi, target);
            let sx = Scale { kind: self.x.kind, lo: xlo, hi: xhi, px_lo: 0.0, px_hi: pw };
            if target <= 2 || !labels_overlap(&t, &sx) {
                break t;
            }
            target -= 1;
        };
        // Room for the last x label's right half.
        if let Some(last) = x_ticks.iter().rev().find(|t| t.label.is_some()) {
            let sx = Scale { kind: self.x.kind, lo: xlo, hi: xhi, px_lo: 0.0, px_hi: pw };
            let overhang = text::width(last.label.as_deref().unwrap_or(""), TICK_FONT) / 2.0
                - (pw - sx.map(last.value));
            right = right.max(overhang + 4.0);
            pw = w - left - right;
        }
        let plot = Rect { x: x0 + left, y: y0 + top, w: pw, h: ph };
        let sx =
            Scale { kind: self.x.kind, lo: xlo, hi: xhi, px_lo: plot.x, px_hi: plot.x + plot.w };
        let sy =
            Scale { kind: self.y.kind, lo: ylo, hi: yhi, px_lo: plot.y + plot.h, px_hi: plot.y };

        svg.open("g", &[("class", "panel".into())]);
        // Title: shrunk to fit the panel's width if needed.
        if !self.title.is_empty() {
            let avail = w - 16.0;
            let size =
                (TITLE_FONT * (avail / text::width(&self.title, TITLE_FONT)).min(1.0)).max(8.0);
            svg.text_markup(
                &[
                    ("x", px(x0 + 8.0)),
                    ("y", px(y0 + 10.0 + TITLE_FONT)),
                    ("font-size", px(size)),
                    ("font-weight", "bold".into()),
                    ("fill", INK.into()),
                ],
                &text::to_svg(&self.title),
            );
        }
        if self.grid {
            for t in x_ticks.iter().filter(|t| t.label.is_some()) {
                let x = sx.map(t.value);
                svg.empty(
                    "line",
                    &[
                        ("x1", px(x)),
                        ("x2", px(x)),
                        ("y1", px(plot.y)),
                        ("y2", px(plot.y + plot.h)),
                        ("stroke", "#e3e3e3".into()),
                        ("stroke-width", "0.8".into()),
                    ],
                );
            }
            for t in y_ticks.iter().filter(|t| t.label.is_some()) {
                let y = sy.map(t.value);
                svg.empty(
                    "line",
                    &[
                        ("x1", px(plot.x)),
                        ("x2", px(plot.x + plot.w)),
                        ("y1", px(y)),
                        ("y2", px(y)),
                        ("stroke", "#e3e3e3".into()),
                        ("stroke-width", "0.8".into()),
                    ],
                );
            }
        }
        svg.open("defs", &[]);
        svg.open("clipPath", &[("id", id.into())]);
        svg.empty(
            "rect",
            &[("x", px(plot.x)), ("y", px(plot.y)), ("width", px(plot.w)), ("height", px(plot.h))],
        );
        svg.close();
        svg.close();
        // Pixel samples of everything drawn, to place the legend where it hides the least.
        let mut occupied: Vec<(f64, f64)> = Vec::new();
        svg.open("g", &[("clip-path", format!("url(#{id})"))]);
        for b in &self.bands {
            let upper = b.x.iter().zip(&b.hi).map(|(&x, &y)| (sx.map(x), sy.map(y)));
            let lower = b.x.iter().zip(&b.lo).rev().map(|(&x, &y)| (sx.map(x), sy.map(y)));
            for edge in [upper.clone().collect::<Vec<_>>(), lower.clone().collect()] {
                sample_runs(&clip_and_thin(&edge, &plot), &mut occupied);
            }
            let poly = clip_polygon(
                &upper.chain(lower).collect::<Vec<_>>(),
                &Rect { x: plot.x - 2.0, y: plot.y - 2.0, w: plot.w + 4.0, h: plot.h + 4.0 },
            );
            if poly.len() >= 3 {
                let mut d: String = poly
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        format!("{}{} {}", if i == 0 { "M" } else { "L" }, px(p.0), px(p.1))
                    })
                    .collect();
                d.push('Z');
                svg.empty(
                    "path",
                    &[
                        ("d", d),
                        ("fill", b.colour.clone()),
                        ("fill-opacity", format!("{}", b.opacity.clamp(0.0, 1.0))),
                        ("stroke", "none".into()),
                    ],
                );
            }
        }
        for l in &self.lines {
            let (a, b) = if l.vertical {
                let x = sx.map(l.value);
                ((x, plot.y), (x, plot.y + plot.h))
            } else {
                let y = sy.map(l.value);
                ((plot.x, y), (plot.x + plot.w, y))
            };
            draw_path(svg, &[vec![a, b]], &l.style);
        }
        for s in &self.series {
            let pts: Vec<(f64, f64)> =
                s.x.iter().zip(&s.y).map(|(&x, &y)| (sx.map(x), sy.map(y))).collect();
            if s.style.width > 0.0 {
                let runs = clip_and_thin(&pts, &plot);
                sample_runs(&runs, &mut occupied);
                draw_path(svg, &runs, &s.style);
            }
            if let Some(m) = s.style.marker {
                for &p in pts.iter().filter(|&&p| plot.contains(p, s.style.marker_size)) {
                    draw_marker(svg, p, m, &s.style);
                    occupied.extend([p; 4]);
                }
            }
        }
        svg.close();
        svg.empty(
            "rect",
            &[
                ("x", px(plot.x)),
                ("y", px(plot.y)),
                ("width", px(plot.w)),
                ("height", px(plot.h)),
                ("fill", "none".into()),
                ("stroke", INK.into()),
                ("stroke-width", "1".into()),
            ],
        );
        self.draw_ticks(svg, &plot, &sx, &sy, &x_ticks, &y_ticks);
        // Axis titles.
        svg.text_markup(
            &[
                ("x", px(plot.x + plot.w / 2.0)),
                ("y", px(y0 + h - 8.0)),
                ("text-anchor", "middle".into()),
                ("font-size", px(LABEL_FONT)),
                ("fill", INK.into()),
            ],
            &text::to_svg(&self.x.title()),
        );
        let (yx, yy) = (x0 + 4.0 + LABEL_FONT * 0.8, plot.y + plot.h / 2.0);
        svg.text_markup(
            &[
                ("x", px(yx)),
                ("y", px(yy)),
                ("transform", format!("rotate(-90 {} {})", px(yx), px(yy))),
                ("text-anchor", "middle".into()),
                ("font-size", px(LABEL_FONT)),
                ("fill", INK.into()),
            ],
            &text::to_svg(&self.y.title()),
        );
        for n in &self.notes {
            let p = (sx.map(n.x) + n.offset.0, sy.map(n.y) + n.offset.1);
            let anchor = match n.anchor {
                Anchor::Start => "start",
                Anchor::Middle => "middle",
                Anchor::End => "end",
            };
            let wd = text::width(&n.text, SMALL_FONT);
            let x_start = match n.anchor {
                Anchor::Start => p.0,
                Anchor::Middle => p.0 - wd / 2.0,
                Anchor::End => p.0 - wd,
            };
            let mut x = p.0;
            while x_start + (x - p.0) < x0 {
                x += 1.0;
            }
            occupied
                .extend((0..=(wd / 4.0) as usize).map(|i| (x_start + 4.0 * i as f64, p.1 - 4.0)));
            svg.text_markup(
                &[
                    ("x", px(x)),
                    ("y", px(p.1)),
                    ("text-anchor", anchor.into()),
                    ("font-size", px(SMALL_FONT)),
                    ("fill", n.colour.clone()),
                ],
                &text::to_svg(&n.text),
            );
        }
        self.draw_legend(svg, &plot, &occupied);
        svg.close();
        Ok(())
    }

    fn draw_ticks(
        &self,
        svg: &mut Svg,
        plot: &Rect,
        sx: &Scale,
        sy: &Scale,
        x_ticks: &[Tick],
        y_ticks: &[Tick],
    ) {
        let base = plot.y + plot.h;
        for t in x_ticks {
            let x = sx.map(t.value);
            let len = if t.label.is_some() { TICK_LEN } else { TICK_LEN * 0.6 };
            svg.empty(
                "line",
                &[
                    ("x1", px(x)),
                    ("x2", px(x)),
                    ("y1", px(base)),
                    ("y2", px(base + len)),
                    ("stroke", INK.into()),
                    ("stroke-width", "1".into()),
                ],
            );
            if let Some(l) = &t.label {
                svg.text_markup(
                    &[
                        ("x", px(x)),
                        ("y", px(base + TICK_LEN + 3.0 + TICK_FONT)),
                        ("text-anchor", "middle".into()),
                        ("font-size", px(TICK_FONT)),
                        ("fill", INK.into()),
                    ],
                    &text::to_svg(l),
                );
            }
        }
        for t in y_ticks {
            let y = sy.map(t.value);
            let len = if t.label.is_some() { TICK_LEN } else { TICK_LEN * 0.6 };
            svg.empty(
                "line",
                &[
                    ("x1", px(plot.x - len)),
                    ("x2", px(plot.x)),
                    ("y1", px(y)),
                    ("y2", px(y)),
                    ("stroke", INK.into()),
                    ("stroke-width", "1".into()),
                ],
            );
            if let Some(l) = &t.label {
                svg.text_markup(
                    &[
                        ("x", px(plot.x - TICK_LEN - 3.0)),
                        ("y", px(y + TICK_FONT * 0.35)),
                        ("text-anchor", "end".into()),
                        ("font-size", px(TICK_FONT)),
                        ("fill", INK.into()),
                    ],
                    &text::to_svg(l),
                );
            }
        }
    }

    fn draw_legend(&self, svg: &mut Svg, plot: &Rect, occupied: &[(f64, f64)]) {
        let entries: Vec<(&str, Swatch)> = self
            .series
            .iter()
            .map(|s| (s.label.as_str(), Swatch::Line(&s.style)))
            .chain(self.lines.iter().map(|l| (l.label.as_str(), Swatch::Line(&l.style))))
            .chain(
                self.bands.iter().map(|b| (b.label.as_str(), Swatch::Fill(&b.colour, b.opacity))),
            )
            .filter(|(l, _)| !l.is_empty())
            .collect();
        if entries.is_empty() || self.legend == LegendPlace::Hidden {
            return;
        }
        let line_h = SMALL_FONT + 5.0;
        let label_w = entries.iter().map(|(l, _)| text::width(l, SMALL_FONT)).fold(0.0, f64::max);
        let (lw, lh) =
            (8.0 + 24.0 + 6.0 + label_w + 8.0, 6.0 + entries.len() as f64 * line_h + 2.0);
        let pad = 6.0;
        let corner = |place: LegendPlace| -> (f64, f64) {
            let (l, r) = (plot.x + pad, plot.x + plot.w - pad - lw);
            let (t, b) = (plot.y + pad, plot.y + plot.h - pad - lh);
            let c = plot.x + (plot.w - lw) / 2.0;
            match place {
                LegendPlace::TopLeft => (l, t),
                LegendPlace::BottomLeft => (l, b),
                LegendPlace::BottomRight => (r, b),
                LegendPlace::Hidden => (c, t),
                LegendPlace::TopRight | LegendPlace::Auto => (r, t),
            }
        };
        let (x, y) = match self.legend {
            LegendPlace::Auto => {
                let c = plot.x + (plot.w - lw) / 2.0;
                let candidates = [
                    corner(LegendPlace::TopRight),
                    corner(LegendPlace::TopLeft),
                    corner(LegendPlace::BottomRight),
                    corner(LegendPlace::BottomLeft),
                    (c, plot.y + pad),
                    (c, plot.y + plot.h - pad - lh),
                ];
                let hidden = |&(x, y): &(f64, f64)| {
                    let r = Rect { x, y, w: lw, h: lh };
                    occupied.iter().filter(|&&p| r.contains(p, 3.0)).count()
                };
                // Fewest hidden samples; the first (top right) on ties.
                candidates.iter().copied().min_by_key(hidden).unwrap_or(candidates[0])
            }
            place => corner(place),
        };
        svg.open("g", &[("class", "legend".into())]);
        svg.empty(
            "rect",
            &[
                ("x", px(x)),
                ("y", px(y)),
                ("width", px(lw)),
                ("height", px(lh)),
                ("fill", "white".into()),
                ("fill-opacity", "0.88".into()),
                ("stroke", "#999999".into()),
                ("stroke-width", "0.8".into()),
            ],
        );
        for (i, (label, swatch)) in entries.iter().enumerate() {
            let cy = y + 6.0 + line_h * (i as f64 + 0.5);
            match swatch {
                Swatch::Line(style) => {
                    if style.width > 0.0 {
                        draw_path(svg, &[vec![(x + 8.0, cy), (x + 32.0, cy)]], style);
                    }
                    if let Some(m) = style.marker {
                        draw_marker(svg, (x + 20.0, cy), m, style);
                    }
                }
                Swatch::Fill(colour, opacity) => svg.empty(
                    "rect",
                    &[
                        ("x", px(x + 8.0)),
                        ("y", px(cy - 5.0)),
                        ("width", "24".into()),
                        ("height", "10".into()),
                        ("fill", colour.to_string()),
                        ("fill-opacity", format!("{}", opacity.clamp(0.0, 1.0))),
                    ],
                ),
            }
            svg.text_markup(
                &[
                    ("x", px(x + 38.0)),
                    ("y", px(cy + SMALL_FONT * 0.35)),
                    ("font-size", px(SMALL_FONT)),
                    ("fill", INK.into()),
                ],
                &text::to_svg(label),
            );
        }
        svg.close();
    }
}

/// What a legend entry shows: a line (and marker) or a filled swatch.
enum Swatch<'a> {
    Line(&'a Style),
    Fill(&'a str, f64),
}

/// Clips a polygon to `r` (Sutherland–Hodgman): the visible part, edges inside unchanged.
fn clip_polygon(poly: &[(f64, f64)], r: &Rect) -> Vec<(f64, f64)> {
    type Edge = (fn(&(f64, f64), &Rect) -> bool, fn((f64, f64), (f64, f64), &Rect) -> (f64, f64));
    let edges: [Edge; 4] = [
        (|p, r| p.0 >= r.x, |a, b, r| (r.x, a.1 + (b.1 - a.1) * (r.x - a.0) / (b.0 - a.0))),
        (
            |p, r| p.0 <= r.x + r.w,
            |a, b, r| (r.x + r.w, a.1 + (b.1 - a.1) * (r.x + r.w - a.0) / (b.0 - a.0)),
        ),
        (|p, r| p.1 >= r.y, |a, b, r| (a.0 + (b.0 - a.0) * (r.y - a.1) / (b.1 - a.1), r.y)),
        (
            |p, r| p.1 <= r.y + r.h,
            |a, b, r| (a.0 + (b.0 - a.0) * (r.y + r.h - a.1) / (b.1 - a.1), r.y + r.h),
        ),
    ];
    let mut out = poly.to_vec();
    for (inside, cross) in edges {
        let input = std::mem::take(&mut out);
        for (i, &p) in input.iter().enumerate() {
            let prev = input[(i + input.len() - 1) % input.len()];
            match (inside(&prev, r), inside(&p, r)) {
                (true, true) => out.push(p),
                (true, false) => out.push(cross(prev, p, r)),
                (false, true) => {
                    out.push(cross(prev, p, r));
                    out.push(p);
                }
                (false, false) => {}
            }
        }
    }
    out
}

/// Whether neighbouring labelled x ticks would print over each other.
fn labels_overlap(ticks: &[Tick], sx: &Scale) -> bool {
    let labelled: Vec<(f64, f64)> = ticks
        .iter()
        .filter_map(|t| t.label.as_ref().map(|l| (sx.map(t.value), text::width(l, TICK_FONT))))
        .collect();
    labelled.windows(2).any(|w| (w[1].0 - w[0].0).abs() < (w[0].1 + w[1].1) / 2.0 + 10.0)
}

/// Clips the segment a–b to `r` (Liang–Barsky); `None` if it lies outside.
fn clip_segment(a: (f64, f64), b: (f64, f64), r: &Rect) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, a.0 - r.x), (dx, r.x + r.w - a.0), (-dy, a.1 - r.y), (dy, r.y + r.h - a.1)]
    {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return None;
            }
        }
    }
    // Unclipped ends are returned exactly (not recomputed), so callers can compare them.
    let start = if t0 > 0.0 { (a.0 + t0 * dx, a.1 + t0 * dy) } else { a };
    let end = if t1 < 1.0 { (a.0 + t1 * dx, a.1 + t1 * dy) } else { b };
    Some((start, end))
}

/// Splits a polyline into runs inside the plot area (slightly enlarged, so that clipping by
/// the clip path, not here, draws the edge) and drops points within 0.3 px of the previous
/// kept one (the drawing moves by less than that).
fn clip_and_thin(pts: &[(f64, f64)], plot: &Rect) -> Vec<Vec<(f64, f64)>> {
    let r = Rect { x: plot.x - 2.0, y: plot.y - 2.0, w: plot.w + 4.0, h: plot.h + 4.0 };
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    let close = |p: (f64, f64), q: (f64, f64)| (p.0 - q.0).hypot(p.1 - q.1) < 0.3;
    for w in pts.windows(2) {
        match clip_segment(w[0], w[1], &r) {
            Some((a, b)) => {
                if current.last().is_none_or(|&l| !close(l, a)) {
                    if current.len() > 1 {
                        runs.push(std::mem::take(&mut current));
                    }
                    current = vec![a];
                }
                if !close(*current.last().unwrap_or(&a), b) || b != w[1] {
                    current.push(b);
                }
            }
            None => {
                if current.len() > 1 {
                    runs.push(std::mem::take(&mut current));
                }
                current.clear();
            }
        }
    }
    if let (Some(&last), Some(&end)) = (pts.last(), current.last()) {
        if r.contains(last, 0.0) && end != last {
            current.push(last);
        }
    }
    if current.len() > 1 {
        runs.push(current);
    }
    runs
}

/// Points every 3 px along the runs.
fn sample_runs(runs: &[Vec<(f64, f64)>], out: &mut Vec<(f64, f64)>) {
    for run in runs {
        for w in run.windows(2) {
            let n = ((w[1].0 - w[0].0).hypot(w[1].1 - w[0].1) / 3.0).ceil().max(1.0) as usize;
            out.extend((0..n).map(|i| {
                let f = i as f64 / n as f64;
                (w[0].0 + f * (w[1].0 - w[0].0), w[0].1 + f * (w[1].1 - w[0].1))
            }));
        }
    }
}

fn draw_path(svg: &mut Svg, runs: &[Vec<(f64, f64)>], style: &Style) {
    let mut d = String::new();
    for run in runs {
        for (i, p) in run.iter().enumerate() {
            d.push_str(if i == 0 { "M" } else { "L" });
            d.push_str(&px(p.0));
            d.push(' ');
            d.push_str(&px(p.1));
        }
    }
    if d.is_empty() {
        return;
    }
    let mut attrs = vec![
        ("d", d),
        ("fill", "none".to_string()),
        ("stroke", style.colour.clone()),
        ("stroke-width", px(style.width)),
        ("stroke-linejoin", "round".into()),
        ("stroke-linecap", "round".into()),
    ];
    if let Some(a) = style.dash.dasharray(style.width) {
        attrs.push(("stroke-dasharray", a));
        attrs[5].1 = "butt".into();
    }
    svg.empty("path", &attrs);
}

fn draw_marker(svg: &mut Svg, p: (f64, f64), m: Marker, style: &Style) {
    let r = style.marker_size / 2.0;
    let c = style.colour.clone();
    match m {
        Marker::Circle => {
            svg.empty("circle", &[("cx", px(p.0)), ("cy", px(p.1)), ("r", px(r)), ("fill", c)])
        }
        Marker::OpenCircle => svg.empty(
            "circle",
            &[
                ("cx", px(p.0)),
                ("cy", px(p.1)),
                ("r", px(r)),
                ("fill", "white".into()),
                ("stroke", c),
                ("stroke-width", "1.2".into()),
            ],
        ),
        Marker::Square => svg.empty(
            "rect",
            &[
                ("x", px(p.0 - r * 0.9)),
                ("y", px(p.1 - r * 0.9)),
                ("width", px(1.8 * r)),
                ("height", px(1.8 * r)),
                ("fill", c),
            ],
        ),
        Marker::Triangle => svg.empty(
            "path",
            &[
                (
                    "d",
                    format!(
                        "M{} {}L{} {}L{} {}Z",
                        px(p.0),
                        px(p.1 - 1.2 * r),
                        px(p.0 + 1.05 * r),
                        px(p.1 + 0.65 * r),
                        px(p.0 - 1.05 * r),
                        px(p.1 + 0.65 * r)
                    ),
                ),
                ("fill", c),
            ],
        ),
        Marker::Cross => svg.empty(
            "path",
            &[
                (
                    "d",
                    format!(
                        "M{} {}L{} {}M{} {}L{} {}",
                        px(p.0 - r),
                        px(p.1 - r),
                        px(p.0 + r),
                        px(p.1 + r),
                        px(p.0 - r),
                        px(p.1 + r),
                        px(p.0 + r),
                        px(p.1 - r)
                    ),
                ),
                ("stroke", c),
                ("stroke-width", "1.4".into()),
                ("fill", "none".into()),
            ],
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect() -> Rect {
        Rect { x: 0.0, y: 0.0, w: 100.0, h: 50.0 }
    }

    #[test]
    fn segments_are_clipped_to_the_plot() {
        let r = rect();
        assert_eq!(
            clip_segment((10.0, 10.0), (20.0, 20.0), &r),
            Some(((10.0, 10.0), (20.0, 20.0)))
        );
        assert_eq!(
            clip_segment((-10.0, 10.0), (10.0, 10.0), &r),
            Some(((0.0, 10.0), (10.0, 10.0)))
        );
        assert_eq!(clip_segment((-10.0, -10.0), (-1.0, 60.0), &r), None);
        // A segment from far away keeps its direction.
        let (a, b) = clip_segment((50.0, 25.0), (50.0 + 1e12, 25.0 + 1e12), &r).unwrap();
        assert_eq!(a, (50.0, 25.0));
        assert!((b.0 - 75.0).abs() < 1e-6 && (b.1 - 50.0).abs() < 1e-6, "{b:?}");
    }

    #[test]
    fn polylines_break_where_they_leave_and_thin_dense_points() {
        let plot = rect();
        // Out and back in: two runs.
        let pts = [(10.0, 10.0), (20.0, 10.0), (30.0, 200.0), (40.0, 10.0), (50.0, 10.0)];
        let runs = clip_and_thin(&pts, &plot);
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[0][0], (10.0, 10.0));
        assert_eq!(*runs[1].last().unwrap(), (50.0, 10.0));
        // 10 000 points on a 100 px line: far fewer kept, both ends kept.
        let dense: Vec<(f64, f64)> = (0..=10_000).map(|i| (i as f64 * 0.01, 20.0)).collect();
        let runs = clip_and_thin(&dense, &plot);
        assert_eq!(runs.len(), 1);
        assert!(runs[0].len() < 400, "{}", runs[0].len());
        assert_eq!(runs[0][0], (0.0, 20.0));
        assert_eq!(*runs[0].last().unwrap(), (100.0, 20.0));
        // Kept points are about 0.3 px apart (a dropped point is within 0.3 px of a kept one).
        for w in runs[0].windows(2) {
            assert!(w[1].0 - w[0].0 <= 0.3 + 0.01 + 1e-9, "{w:?}");
        }
    }

    #[test]
    fn bad_data_is_a_typed_error_naming_panel_and_series() {
        let p = |x: Vec<f64>, y: Vec<f64>, yaxis: Axis| {
            Panel::new("(a) test", Axis::linear("t").unit("s"), yaxis).series(Series::new(
                "data",
                x,
                y,
                Style::line(0),
            ))
        };
        let e = p(vec![1.0, 2.0], vec![1.0, f64::NAN], Axis::linear("v").dimensionless())
            .validate()
            .unwrap_err();
        assert!(matches!(e, FigureError::NonFinite { index: 1, .. }), "{e}");
        assert!(e.to_string().contains("(a) test") && e.to_string().contains("data"));
        let e = p(vec![1.0, 2.0], vec![1.0, 0.0], Axis::log10("v").dimensionless())
            .validate()
            .unwrap_err();
        assert!(matches!(e, FigureError::NonPositiveOnLog { axis: "y", index: 1, .. }), "{e}");
        let e =
            p(vec![1.0], vec![1.0, 2.0], Axis::linear("v").dimensionless()).validate().unwrap_err();
        assert!(matches!(e, FigureError::LengthMismatch { x: 1, y: 2, .. }), "{e}");
        let e = p(vec![1.0], vec![1.0], Axis::linear("v")).validate().unwrap_err();
        assert!(matches!(e, FigureError::MissingUnit { axis: "y", .. }), "{e}");
        let e = p(vec![], vec![], Axis::linear("v").dimensionless()).validate().unwrap_err();
        assert!(matches!(e, FigureError::Empty { .. }), "{e}");
        let e = p(vec![1.0], vec![1.0], Axis::log10("v").dimensionless().range(0.0, 1.0))
            .validate()
            .unwrap_err();
        assert!(matches!(e, FigureError::BadRange { .. }), "{e}");
        assert!(p(vec![1.0], vec![1.0], Axis::log10("v").dimensionless()).validate().is_ok());
    }

    #[test]
    fn polygons_are_clipped_to_the_plot() {
        let r = rect();
        // Inside: unchanged.
        let inside = [(10.0, 10.0), (20.0, 10.0), (20.0, 20.0)];
        assert_eq!(clip_polygon(&inside, &r), inside.to_vec());
        // A square sticking out to the right is cut at x = 100, keeping its edges' directions.
        let out = clip_polygon(&[(90.0, 10.0), (1e9, 10.0), (1e9, 20.0), (90.0, 20.0)], &r);
        assert!(out.iter().all(|p| p.0 <= 100.0 && p.0 >= 90.0), "{out:?}");
        assert!(out.contains(&(100.0, 10.0)) && out.contains(&(100.0, 20.0)), "{out:?}");
        // Entirely outside: nothing.
        assert!(clip_polygon(&[(200.0, 10.0), (300.0, 10.0), (300.0, 20.0)], &r).is_empty());
    }

    #[test]
    fn bands_are_drawn_validated_and_in_the_legend() {
        let x: Vec<f64> = (0..20).map(f64::from).collect();
        let mid: Vec<f64> = x.iter().map(|x| x.sin() + 2.0).collect();
        let p = Panel::new("(a) band", Axis::linear("t").unit("s"), Axis::log10("v").unit("m/s"))
            .band(Band::new(
                "mean ± σ",
                x.clone(),
                mid.iter().map(|m| m - 0.5).collect(),
                mid.iter().map(|m| m + 0.5).collect(),
                0,
            ))
            .series(Series::new("mean", x.clone(), mid.clone(), Style::line(0)));
        let mut svg = Svg::new(400.0, 300.0, "t");
        p.render(&mut svg, 0.0, 0.0, 400.0, 300.0, "c0").unwrap();
        let doc = svg.finish();
        assert!(doc.contains("fill-opacity=\"0.25\""), "band drawn");
        assert!(doc.contains("mean ± σ"), "band in the legend");
        let bad = Panel::new("(b) bad", Axis::linear("t").unit("s"), Axis::log10("v").unit("m/s"))
            .band(Band::new("σ", x.clone(), vec![0.0; 20], mid.clone(), 0));
        assert!(matches!(bad.validate(), Err(FigureError::NonPositiveOnLog { .. })));
        let short =
            Panel::new("(c) short", Axis::linear("t").unit("s"), Axis::linear("v").unit("m/s"))
                .band(Band::new("σ", x, vec![0.0; 3], mid, 0));
        assert!(matches!(short.validate(), Err(FigureError::LengthMismatch { .. })));
    }

    #[test]
    fn axis_titles_state_the_unit() {
        assert_eq!(Axis::linear("t").unit("D_{c}/v_{0}").title(), "t [D_{c}/v_{0}]");
        assert_eq!(Axis::log10("θ").dimensionless().title(), "θ (dimensionless)");
    }
}
