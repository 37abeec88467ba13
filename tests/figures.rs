//! The figures' SVG is well-formed XML with every part (test code kept out of production:
//! the checker lives in tests/xml/).

mod xml;

use stickslip_cli::figure::svg::{escape, px, Svg};
use stickslip_cli::figure::{
    Anchor, Axis, Dash, Figure, LegendPlace, Marker, Note, Panel, RefLine, Series, Style,
};
use xml::check_well_formed;

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
    assert!(check_well_formed(
        "<?xml version=\"1.0\"?>\n<!-- c --><svg a='1'>&#955;&#x3bb;<g/></svg>\n"
    )
    .is_ok());
}

fn example() -> Figure {
    let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
    let v: Vec<f64> = t.iter().map(|t| (-t).exp() + 1e-3).collect();
    let a = Panel::new(
        "(a) decay & <growth>",
        Axis::linear("t").unit("D_{c}/v_{0}"),
        Axis::log10("v").unit("v_{0}"),
    )
    .series(Series::new("e^{−t} + 10^{−3}", t.clone(), v, Style::line(0)))
    .series(Series::new(
        "points",
        vec![1.0, 2.0, 3.0],
        vec![0.5, 0.2, 0.05],
        Style::markers(1, Marker::Circle),
    ))
    .line(RefLine::horizontal(1e-3, "floor", Style::line(3)))
    .note(Note::new(5.0, 0.1, "a \"note\"", Anchor::Start));
    let b =
        Panel::new("(b) sine", Axis::linear("u").unit("D_{c}"), Axis::linear("θ").dimensionless())
            .series(
                Series::new("sin", t.clone(), t.iter().map(|t| t.sin()).collect(), Style::line(2))
                    .dash(Dash::Dashed),
            )
            .legend(LegendPlace::BottomLeft);
    Figure::new("Test figure").columns(2).panel(a).panel(b).caption("γ = 10^{3}, ξ = 0.7; a caption long enough to wrap onto a second line when the figure is narrow, which this one is not really")
}

#[test]
fn a_figure_is_well_formed_svg_with_every_part() {
    let svg = example().to_svg().unwrap();
    let counts = check_well_formed(&svg).unwrap();
    assert_eq!(counts["svg"], 1);
    assert_eq!(counts["clipPath"], 2, "one clip path per panel");
    assert_eq!(counts["circle"], 4, "three data markers and one in the legend");
    assert!(counts["text"] > 20, "titles, tick labels, axis titles, legend, note, caption");
    assert!(svg.contains("[D<tspan"), "units with subscripts");
    assert!(svg.contains("θ (dimensionless)"));
    assert!(svg.contains("(a) decay &amp; &lt;growth&gt;"), "escaped title");
    assert!(svg.contains("a &quot;note&quot;"));
    assert!(svg.contains("stroke-dasharray"));
    assert!(svg.contains("font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\""));
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
}
