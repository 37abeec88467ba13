//! `stickslip reproduce --reduced`: every figure, report and summary is written, the SVGs are
//! well-formed with one plot area per panel, nothing is NaN, and the figures still to come are
//! listed as not yet reproduced.

mod xml;

use xml::check_well_formed;

use std::path::PathBuf;
use std::process::Command;
use stickslip_cli::reproduce::{FIGURES, PENDING};

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

fn dir() -> PathBuf {
    std::env::temp_dir().join(format!("stickslip-reproduce-{}", std::process::id()))
}

#[test]
fn reduced_reproduce_writes_well_formed_figures_reports_and_summary() {
    let out = dir();
    let run = Command::new(EXE)
        .args(["reproduce", "--reduced", "--threads", "2", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success(),
        "exit {:?}\n{stderr}\n{}",
        run.status,
        String::from_utf8_lossy(&run.stdout)
    );
    // Progress: one line per figure on stderr.
    for i in 1..=FIGURES.len() {
        assert!(stderr.contains(&format!("reproduce [{i}/{}]", FIGURES.len())), "{stderr}");
    }

    // Panels per figure: each has its own clip path.
    let panels = [
        ("fig1", 6),
        ("fig2", 4),
        ("fig3", 3),
        ("fig4", 2),
        ("fig5", 3),
        ("fig6", 2),
        ("fig7", 3),
        ("fig8", 4),
        ("fig9", 1),
        ("laws", 2),
    ];
    assert_eq!(panels.len(), FIGURES.len());
    for (id, n) in panels {
        let svg = std::fs::read_to_string(out.join(format!("{id}.svg"))).unwrap();
        let counts = check_well_formed(&svg).unwrap_or_else(|e| panic!("{id}.svg: {e}"));
        assert_eq!(counts.get("clipPath"), Some(&n), "{id}: panels");
        assert!(counts["text"] > 10 * n, "{id}: tick labels, axis titles, titles");
        assert!(counts["path"] > n, "{id}: data drawn");
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{id}: non-finite coordinates");
    }

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["reduced"], true);
    let figures = summary["figures"].as_array().unwrap();
    assert_eq!(figures.len(), FIGURES.len());
    let mut claims = 0;
    for f in figures {
        assert!(f["error"].is_null(), "{f}");
        for file in f["files"].as_array().unwrap() {
            let path = out.join(file.as_str().unwrap());
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            if path.extension().is_some_and(|e| e == "json") {
                let v: serde_json::Value = serde_json::from_str(&text)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                // Curves: every point says what the cycle analysis found there.
                for p in v["points"].as_array().into_iter().flatten() {
                    assert!(
                        p.get("status").is_some() || p.get("period_ratio").is_some(),
                        "{}: {p}",
                        path.display()
                    );
                }
            }
        }
        for c in f["claims"].as_array().unwrap() {
            claims += 1;
            let verdict = c["verdict"].as_str().unwrap();
            assert!(
                ["agrees", "roughly", "disagrees", "holds", "does not hold"].contains(&verdict),
                "{c}"
            );
        }
    }
    assert!(claims >= 10, "{claims} claims");
    // The state-law comparison: our periods match both reference tables and the three laws
    // share ε_c and ω_c (every claim agrees).
    let laws = figures.iter().find(|f| f["id"] == "laws").unwrap();
    let law_claims = laws["claims"].as_array().unwrap();
    assert!(law_claims.len() >= 2 * 3 + 2, "{laws}");
    assert!(law_claims.iter().all(|c| c["verdict"] == "agrees"), "{laws}");

    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    let html = std::fs::read_to_string(out.join("summary.html")).unwrap();
    assert!(md.contains("## Not yet reproduced") && html.contains("Not yet reproduced"));
    for p in PENDING {
        assert!(md.contains(p.figure) && html.contains(p.figure), "{} not listed", p.figure);
    }
    for (id, _) in panels {
        assert!(html.contains(&format!("<img src=\"{id}.svg\"")), "{id} not shown in the HTML");
    }
    std::fs::remove_dir_all(&out).unwrap();
}
