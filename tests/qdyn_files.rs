//! QDYN's own files: `stickslip run qdyn.in` on pyqdyn-written input files (data/qdyn/) agrees
//! with QDYN's runs of the same files (data/reference/qdyn_spring_block.json), refuses what it
//! does not support naming the line and field, `--print-scene` round-trips, and
//! `--qdyn-output` writes QDYN's files in QDYN's format (data/reference/qdyn_output/, written by
//! QDYN) with the run's values, which pyqdyn's `read_output` reads (when its venv is present).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use stickslip::scene::{self, qdyn_input};

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(path)
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stickslip-qdyn-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stickslip(args: &[&str]) -> Output {
    Command::new(EXE).args(args).output().unwrap()
}

fn json_of(out: &Output) -> serde_json::Value {
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

const CASES: [&str; 8] = [
    "classic_ageing",
    "classic_slip",
    "cut_a_ageing",
    "cut_a_slip",
    "cut_b_ageing",
    "cut_b_slip",
    "reg_ageing",
    "reg_slip",
];

/// tests/qdyn_laws.rs's tolerances against QDYN's runs of the same files (ACC = 1e-11, printed
/// with 17 digits): the period and event slip to 1e-10, v_max to 1e-8 (measured at most
/// 2.8e-11, 3.6e-12 and 1.2e-9).
#[test]
fn pyqdyn_written_files_run_directly_and_agree_with_qdyns_runs() {
    let text = std::fs::read_to_string(data("reference/qdyn_spring_block.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let reports: Vec<serde_json::Value> = std::thread::scope(|s| {
        let runs: Vec<_> = CASES
            .iter()
            .map(|case| {
                s.spawn(move || {
                    let file = data(&format!("qdyn/{case}.in"));
                    json_of(&stickslip(&["run", file.to_str().unwrap(), "--json"]))
                })
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    for (case, report) in CASES.iter().zip(&reports) {
        let theirs = reference["cases"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["case"] == *case)
            .unwrap_or_else(|| panic!("{case} not in the reference"));
        let ours = &report["cycle"]["physical"];
        for (key, their_key, tolerance) in [
            ("period", "period_s", 1e-10),
            ("v_max", "v_max_m_per_s", 1e-8),
            ("slip", "event_slip_m", 1e-10),
        ] {
            let (a, b) = (ours[key].as_f64().unwrap(), theirs[their_key].as_f64().unwrap());
            assert!((a - b).abs() <= tolerance * b, "{case}: {key} {a} vs QDYN {b}");
        }
        // The event catalogue runs to TMAX (40 periods): 40 events, the last one's
        // recurrence the period.
        let series = &report["time_series"];
        let period = ours["period"].as_f64().unwrap();
        let t_max = series["t_max_physical"].as_f64().unwrap();
        assert!((t_max / period - 40.0).abs() < 1e-6, "{case}: t_max {t_max}");
        let events = report["events"].as_array().unwrap();
        assert!((39..=40).contains(&events.len()), "{case}: {} events", events.len());
        let last = events.last().unwrap()["physical"]["recurrence"].as_f64().unwrap();
        assert!((last - period).abs() < 1e-8 * period, "{case}: recurrence {last}");
        assert_eq!(report["solver"]["rtol"], 1e-11, "{case}: ACC is the rtol");
    }
}

/// `THETA_LAW = 0` (no healing) has no cycle: the run stops where V reaches 1 m/s and reports
/// the time (exit 0), where QDYN runs on until its solver fails. Against QDYN's run of the same
/// file (data/reference/qdyn_no_healing.json: its output interpolated in ln V, so good to
/// ~1e-11 at its sample spacing there) and the quasi-dynamic closed form
/// (docs/state-laws.md; tests/state_laws.rs).
#[test]
fn a_no_healing_file_reports_its_runaway_time_as_qdyn_reaches_it() {
    let file = data("qdyn/classic_no_healing.in");
    let report = json_of(&stickslip(&["run", file.to_str().unwrap(), "--json"]));
    assert_eq!(report["model"]["state_law"], "no_healing");
    assert!(report.get("cycle").is_none(), "no cycle analysis");
    let runaway = &report["runaway"];
    assert_eq!(runaway["reached"], true, "{runaway}");
    let threshold = runaway["physical"]["velocity_threshold"].as_f64().unwrap();
    assert!((threshold - qdyn_input::NO_HEALING_RUNAWAY_VELOCITY).abs() < 1e-15);
    // ξ = 0.25, ε = 0.5, η = 5e-8, v from 0.5 to 1e9, time unit D_c/V_pl = 1e5 s.
    let (xi, c, eta) = (0.25f64, 1.25f64, 5e-8);
    let exact =
        1e5 * ((2e9f64).ln() / xi + (eta - c / xi) / c * ((c * 1e9 + xi) / (c * 0.5 + xi)).ln());
    let t = runaway["physical"]["t"].as_f64().unwrap();
    assert!((t - exact).abs() < 1e-11 * exact, "{t} vs the closed form {exact}");
    // QDYN's crossings of 1e-3, 1e-2 and 1 m/s, the first two by a scene kept from the file with
    // its threshold changed.
    let text = std::fs::read_to_string(data("reference/qdyn_no_healing.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mapped = qdyn_input::to_scene(&std::fs::read_to_string(&file).unwrap(), "f", "f").unwrap();
    for crossing in reference["crossings"].as_array().unwrap() {
        let velocity = crossing["velocity_m_per_s"].as_f64().unwrap();
        let theirs = crossing["t_s"].as_f64().unwrap();
        let mut scene: serde_json::Value = serde_json::from_str(&mapped).unwrap();
        scene["analyses"][0]["time_series"]["runaway_velocity"] = velocity.into();
        let s = scene::parse(&scene.to_string(), "kept").unwrap();
        let r = stickslip::engine::run(&s, stickslip::engine::RunOptions::echoing(scene)).unwrap();
        let ours = r.runaway.unwrap().physical.unwrap().t.unwrap();
        assert!((ours - theirs).abs() < 1e-10 * theirs, "V = {velocity}: {ours} vs QDYN {theirs}");
    }
}

#[test]
fn printed_scene_runs_to_the_identical_report() {
    let file = data("qdyn/cut_a_slip.in");
    let printed = stickslip(&["run", file.to_str().unwrap(), "--print-scene"]);
    assert!(printed.status.success(), "{}", String::from_utf8_lossy(&printed.stderr));
    let kept = temp_dir("print").join("cut_a_slip.json");
    std::fs::write(&kept, &printed.stdout).unwrap();
    let without_time = |mut r: serde_json::Value| {
        r.as_object_mut().unwrap().remove("wall_time_s");
        r
    };
    let direct = without_time(json_of(&stickslip(&["run", file.to_str().unwrap(), "--json"])));
    let from_kept = without_time(json_of(&stickslip(&["run", kept.to_str().unwrap(), "--json"])));
    assert_eq!(direct, from_kept);
    // The mapping as docs/from-qdyn.md states it.
    let s: serde_json::Value = serde_json::from_slice(&printed.stdout).unwrap();
    let d = &s["model"]["dimensional"];
    assert_eq!((d["length"].as_f64(), d["shear_modulus"].as_f64()), (Some(120.0), Some(3e10)));
    assert_eq!(s["model"]["friction"]["cut_off"]["velocity_1"], 1e-6);
    assert_eq!(s["model"]["friction"]["cut_off"]["mu_star"], 0.6);
    assert_eq!(s["initial"]["state"], 1e5);
    assert_eq!(s["model"]["inertia"], false);
}

#[test]
fn qdyn_files_are_recognised_by_extension_or_first_line() {
    let text = std::fs::read_to_string(data("qdyn/classic_slip.in")).unwrap();
    assert!(qdyn_input::is_qdyn_input(Path::new("a/qdyn.in"), ""));
    assert!(qdyn_input::is_qdyn_input(Path::new("case.txt"), &text));
    assert!(!qdyn_input::is_qdyn_input(Path::new("scene.json"), "{\"name\": \"x\"}"));
    // A hand-written file: Fortran d exponents, commas, no comments.
    let hand = text
        .replace("0.1 0 191168042.37512 1e-11", "0.1, 0, 1.9116804237512d8, 1d-11")
        .replace("     L, W", "");
    let scene_text = qdyn_input::to_scene(&hand, "hand", "hand").unwrap();
    let s = scene::parse(&scene_text, "hand").unwrap();
    assert_eq!(s.solver.rtol, 1e-11);
    assert!((s.params.xi - 0.25).abs() < 1e-14 && (s.params.eta - 5e-8).abs() < 1e-20);
}

#[test]
fn unsupported_or_bad_files_exit_2_naming_the_line_and_field() {
    let text = std::fs::read_to_string(data("qdyn/classic_ageing.in")).unwrap();
    let with_line = |n: usize, line: &str| {
        let mut lines: Vec<&str> = text.lines().collect();
        lines[n - 1] = line;
        lines.join("\n")
    };
    let cases = [
        (with_line(1, "1 meshdim"), 1, "MESHDIM", "MESHDIM = 0"),
        (with_line(4, "3 itheta_law"), 4, "THETA_LAW", "not a QDYN state law"),
        (with_line(5, "3 i_rns_law"), 5, "RNS_LAW", "CNS"),
        (with_line(6, "1 i_sigma_law"), 6, "SIGMA_CPL", "not supported"),
        (with_line(7, "1 0 0"), 7, "FEAT_STRESS_COUPL", "not supported"),
        (with_line(7, "0 1 0"), 7, "FEAT_TP", "thermal pressurisation"),
        (with_line(9, "0 3e10 3e10 0 0 0.01"), 9, "VS", "radiation damping"),
        (with_line(10, "0 40000"), 10, "TPER", "periodic loading"),
        (with_line(11, "0.1 0 1e8 0"), 11, "ACC", "> 0"),
        (with_line(12, "3 nstop"), 12, "NSTOP", "TMAX"),
        (with_line(13, "1 0"), 13, "DYN_FLAG", "not supported"),
        (
            with_line(16, "1e7 5e-10 1e5 0.01 0.015 1e-4 0.01 1e-7 0.6 1e-6 1 0 5e5 1e-9"),
            16,
            "CO",
            "cohesion",
        ),
        (
            with_line(16, "abc 5e-10 1e5 0.01 0.015 1e-4 0.01 1e-7 0.6 1e-6 1 0 0 1e-9"),
            16,
            "SIGMA",
            "not a finite number",
        ),
        (with_line(16, "1e7 5e-10 1e5"), 16, "A", "14 values"),
        (
            text.lines().take(10).collect::<Vec<_>>().join("\n"),
            11,
            "DTTRY, DTMAX, TMAX, ACC",
            "missing",
        ),
    ];
    for (bad, line, field, says) in &cases {
        let e = qdyn_input::to_scene(bad, "bad.in", "bad").unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (*line, *field), "{e}");
        assert!(e.to_string().contains(says), "{e}");
    }
    // Through the command line: exit 2 with the line and field on stderr.
    let file = temp_dir("bad").join("aper.in");
    std::fs::write(&file, &cases[7].0).unwrap();
    let out = stickslip(&["run", file.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("line 10: TPER") && stderr.contains("periodic loading"), "{stderr}");
}

/// The fields of a QDYN output line (blank-separated).
fn fields(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

/// The header lines of a QDYN output file.
fn headers(text: &str) -> Vec<&str> {
    text.lines().filter(|l| l.starts_with('#')).collect()
}

/// The data lines of a QDYN output file (not the `#` headers).
fn data_lines(text: &str) -> Vec<&str> {
    text.lines().filter(|l| !l.starts_with('#')).collect()
}

/// Writes `case`'s QDYN output and CSV series in a fresh directory (one per `test`); returns
/// it.
fn qdyn_output_of(case: &str, test: &str) -> PathBuf {
    let dir = temp_dir(&format!("out-{case}-{test}"));
    let file = data(&format!("qdyn/{case}.in"));
    let csv = dir.join("series.csv");
    let out = stickslip(&[
        "run",
        file.to_str().unwrap(),
        "--qdyn-output",
        dir.join("qdyn").to_str().unwrap(),
        "--series",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    dir
}

#[test]
fn qdyn_output_has_qdyns_headers_columns_and_format() {
    let dir = qdyn_output_of("cut_a_slip", "format");
    for (name, skip, width) in [
        ("output_ot_0", 6, 24 + 8 * 15),
        ("output_vmax", 5, 24 + 15 + 6 * 15),
        ("output_ox", 7, 2 * 24 + 8 * 15),
    ] {
        let theirs =
            std::fs::read_to_string(data(&format!("reference/qdyn_output/{name}"))).unwrap();
        let ours = std::fs::read_to_string(dir.join("qdyn").join(name)).unwrap();
        assert_eq!(headers(&ours)[..2], headers(&theirs)[..2], "{name}");
        // Both start from the same state: the first row is QDYN's, field for field, except
        // dtau_dt (QDYN writes 0 there).
        let (a, b) = (fields(data_lines(&ours)[0]), fields(data_lines(&theirs)[0]));
        assert_eq!(a.len(), b.len(), "{name}");
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            if i != skip {
                assert_eq!(x, y, "{name} field {}", i + 1);
            }
        }
        // Every row has QDYN's fixed-width layout.
        for line in data_lines(&ours) {
            assert_eq!(line.len(), width, "{name}: {line}");
        }
        assert_eq!(data_lines(&theirs)[0].len(), width, "{name} (QDYN's)");
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("qdyn/output_ot_0"))
            .unwrap()
            .lines()
            .take(4)
            .collect::<Vec<_>>(),
        std::fs::read_to_string(data("reference/qdyn_output/output_ot_0"))
            .unwrap()
            .lines()
            .take(4)
            .collect::<Vec<_>>()
    );
}

/// The run's own series (CSV, every step) in QDYN's units: t, V, Θ, τ and slip per row.
fn expected_columns(dir: &Path, case: &str) -> Vec<[f64; 5]> {
    let file = data(&format!("qdyn/{case}.in"));
    let text = std::fs::read_to_string(&file).unwrap();
    let scene_text = qdyn_input::to_scene(&text, case, case).unwrap();
    let s = scene::parse(&scene_text, case).unwrap();
    let scales = s.scales.unwrap();
    let level = scales.friction_level(&s.params.friction).unwrap();
    let csv = std::fs::read_to_string(dir.join("series.csv")).unwrap();
    let mut lines = csv.lines();
    let names: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| names.iter().position(|c| *c == n).unwrap();
    let (t, theta, v, stress, slip) =
        (col("t_phys"), col("theta"), col("v_phys"), col("stress_phys"), col("slip_phys"));
    lines
        .map(|l| {
            let r: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            let tau = scales.sigma.unwrap() * level + r[stress];
            [r[t], r[v], scales.state_from_theta(r[theta]), tau, r[slip]]
        })
        .collect()
}

/// Agreement to QDYN's printed digits: 14 for t, 7 for the rest (half a unit in the last).
fn assert_printed(ours: f64, expected: f64, digits: i32, what: &str) {
    let tolerance = 0.51 * 10f64.powi(1 - digits) * expected.abs().max(1e-300);
    assert!((ours - expected).abs() <= tolerance, "{what}: file {ours} vs run {expected}");
}

#[test]
fn qdyn_output_holds_the_runs_series() {
    for case in ["cut_a_slip", "reg_ageing"] {
        let dir = qdyn_output_of(case, "values");
        let expected = expected_columns(&dir, case);
        let ot = std::fs::read_to_string(dir.join("qdyn/output_ot_0")).unwrap();
        let rows = data_lines(&ot);
        assert_eq!(rows.len(), expected.len(), "{case}: one row per series row");
        for (line, e) in rows.iter().zip(&expected) {
            let f: Vec<f64> = fields(line).iter().map(|x| x.parse().unwrap()).collect();
            assert_printed(f[0], e[0], 14, "t");
            for (k, i) in [(1, 3), (2, 4), (3, 5), (4, 7)] {
                assert_printed(f[i], e[k], 7, &format!("{case} column {}", i + 1));
            }
            assert_printed(f[1], e[4] * 120.0, 7, "potency");
            assert_printed(f[8], 1e7, 7, "sigma");
        }
    }
}

/// pyqdyn's `read_output` (QDYN's src/pyqdyn.py; set QDYN_SRC, default /work/qdyn-ref/src)
/// in a Python with pandas < 3 (QDYN_PYTHON, default /work/venvs/qdyn/bin/python) reads a
/// `--qdyn-output` directory unchanged: its t, V, Θ, τ and slip equal the run's series.
/// Skipped, saying so, where that Python or pyqdyn is missing.
#[test]
fn pyqdyn_read_output_reads_the_files() {
    let python = std::env::var("QDYN_PYTHON").unwrap_or("/work/venvs/qdyn/bin/python".into());
    let src = std::env::var("QDYN_SRC").unwrap_or("/work/qdyn-ref/src".into());
    if !Path::new(&python).exists() || !Path::new(&src).join("pyqdyn.py").exists() {
        eprintln!(
            "SKIPPED pyqdyn_read_output_reads_the_files: no {python} or {src}/pyqdyn.py \
             (set QDYN_PYTHON to a Python with numpy and pandas < 3, QDYN_SRC to QDYN's src)"
        );
        return;
    }
    let case = "cut_a_slip";
    let dir = qdyn_output_of(case, "pyqdyn");
    let script = r#"
import os, sys, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, sys.argv[1])
from pyqdyn import qdyn
p = qdyn()
p.settings({"MESHDIM": 0})
p.render_mesh()
os.chdir(sys.argv[2])
p.read_output()
for frame in (p.ot[0], p.ot_vmax):
    print(frame[["t", "v", "theta", "tau", "slip"]].to_csv(index=False, float_format="%.17g"), end="")
    print("--")
print(p.ox[["t", "v", "theta", "tau", "slip"]].to_csv(index=False, float_format="%.17g"), end="")
"#;
    let out = Command::new(&python)
        .args(["-c", script, &src, dir.join("qdyn").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "pyqdyn: {}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let expected = expected_columns(&dir, case);
    let tables: Vec<&str> = text.split("--\n").collect();
    assert_eq!(tables.len(), 3, "{text:.300}");
    let parse = |table: &str| -> Vec<Vec<f64>> {
        let mut lines = table.lines();
        assert_eq!(lines.next(), Some("t,v,theta,tau,slip"));
        lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect()
    };
    for (name, table) in [("ot", tables[0]), ("vmax", tables[1])] {
        let rows = parse(table);
        assert_eq!(rows.len(), expected.len(), "{name}");
        for (r, e) in rows.iter().zip(&expected) {
            assert_printed(r[0], e[0], 14, name);
            for k in 1..5 {
                assert_printed(r[k], e[k], 7, &format!("pyqdyn {name} column {k}"));
            }
        }
    }
    let ox = parse(tables[2]);
    assert_eq!(ox.len(), 2, "ox: the first and last rows");
    for (r, e) in ox.iter().zip([expected[0], *expected.last().unwrap()]) {
        for k in 0..5 {
            assert_printed(r[k], e[k], if k == 0 { 14 } else { 7 }, "pyqdyn ox");
        }
    }
}

#[test]
fn cut_off_mu_star_makes_stresses_absolute_and_needs_a_dimensional_scene() {
    let dimensionless = r#"{"name": "q", "model": {"inertia": false, "xi": 0.25,
        "epsilon": 0.5, "radiation_damping": 5e-8,
        "friction": {"cut_off": {"v1": 1e3, "v2": 1e2, "mu_star": 0.6}}},
        "analyses": ["hopf"]}"#;
    let e = scene::parse(dimensionless, "test").unwrap_err();
    assert_eq!(e.field, "model.friction.cut_off.mu_star", "{e}");
    // The mapped cut-off scene: τ = σ(μ* + aΦ) is absolute, in the report and the series.
    let file = data("qdyn/cut_a_slip.in");
    let report = json_of(&stickslip(&["run", file.to_str().unwrap(), "--json"]));
    let physical = &report["cycle"]["physical"];
    let reference = physical["shear_stress_reference"].as_str().unwrap();
    assert!(reference.starts_with("absolute"), "{reference}");
    let mu = physical["friction_before"].as_f64().unwrap();
    assert!((physical["shear_stress_before"].as_f64().unwrap() - 1e7 * mu).abs() < 1e-6);
    let columns = report["time_series"]["columns"].as_array().unwrap();
    assert!(columns.iter().any(|c| c == "tau_phys"), "{columns:?}");
}

#[test]
fn qdyn_output_refuses_a_scene_it_cannot_express() {
    // A dimensionless scene has no physical units; exit 2 naming the option and the field.
    let dir = temp_dir("refuse");
    let scene = dir.join("s.json");
    std::fs::write(
        &scene,
        r#"{"name": "q", "model": {"inertia": false, "xi": 0.25, "epsilon": 0.5,
            "radiation_damping": 5e-8}, "analyses": [{"time_series": {"t_max": 10}}]}"#,
    )
    .unwrap();
    let out = stickslip(&[
        "run",
        scene.to_str().unwrap(),
        "--qdyn-output",
        dir.join("out").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--qdyn-output") && stderr.contains("model.dimensional"), "{stderr}");
}
