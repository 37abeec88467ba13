//! `stickslip fit`'s engine: CVODES' sensitivities of the lab model against central
//! differences of independent forward runs, and fits of synthetic records made from known
//! parameters plus noise.

use nalgebra::{DMatrix, DVector};
use stickslip::analysis::lab::{self, LabSolver, Output};
use stickslip::analysis::lab_fit::{
    self, statistics, Budget, FitError, FitLimits, FitParameter, FitSettings, FrictionRecord,
    Termination,
};
use stickslip::analysis::noise::rng::Rng;
use stickslip::model::{LabLaw, LabParameter, LabParams, LabState, Loading, Segment};
use stickslip::solver::Method;

fn step_loading() -> Loading {
    let seg = |t_start, velocity| Segment { t_start, velocity };
    Loading::new(vec![seg(0.0, 1.0), seg(10.0, 10.0), seg(40.0, 3.0)], 80.0).unwrap()
}

fn params(states: Vec<LabState>) -> LabParams {
    LabParams { mu0: 0.6, a: 0.011, v0: 1.0, k: 3e-3, states, mass: None }
}

fn state(law: LabLaw, b: f64, d_c: f64) -> LabState {
    LabState { law, b, d_c }
}

/// μ at `times` by an ordinary forward run (cvode-bdf at rtol 1e-14), no sensitivities.
fn forward(p: &LabParams, loading: &Loading, times: &[f64]) -> Vec<f64> {
    let solver = LabSolver { method: Method::CvodeBdf, rtol: 1e-14, atol: 1e-14 };
    let y0 = p.steady_state(loading.segments[0].velocity);
    let mut mu = vec![];
    lab::run(p, loading, &y0, &solver, &Output::Times(times.to_vec()), &mut |r| mu.push(r[3]))
        .unwrap();
    mu
}

fn tight() -> LabSolver {
    LabSolver { method: Method::CvodeBdf, rtol: 1e-12, atol: 1e-12 }
}

#[test]
fn sensitivities_equal_central_differences() {
    let loading = step_loading();
    let times: Vec<f64> = (0..=160).map(|i| 0.5 * f64::from(i)).collect();
    for states in [
        vec![state(LabLaw::Ageing, 0.015, 5.0)],
        vec![state(LabLaw::Slip, 0.015, 5.0)],
        vec![state(LabLaw::Ageing, 0.012, 3.0), state(LabLaw::Slip, 0.006, 30.0)],
        vec![state(LabLaw::Prz, 0.014, 4.0)],
        vec![state(LabLaw::Nagata { c: 2.0 }, 0.016, 4.0)],
        vec![state(LabLaw::Ageing, 0.015, 5.0), state(LabLaw::Slip, 0.004, 20.0)],
    ] {
        // The last case with inertia (μ0 then moves the slider too).
        let inertial = states.len() == 2 && states[1].law == LabLaw::Slip && states[1].b == 0.004;
        let p = LabParams { mass: inertial.then_some(5e-4), ..params(states) };
        let varied = p.all_parameters();
        let s = lab_fit::friction_sensitivities(
            &p,
            &loading,
            &times,
            &varied,
            &LabSolver { rtol: 1e-13, atol: 1e-13, ..tight() },
            &Budget::default(),
        )
        .unwrap();
        let mu = forward(&p, &loading, &times);
        let mu_err = s.mu.iter().zip(&mu).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(mu_err < 1e-10, "μ differs from the forward run by {mu_err:e}");
        for (j, par) in varied.iter().enumerate() {
            // Fourth-order central differences with small steps: with inertia μ oscillates at
            // ω = √(k/M), and ∂μ/∂k grows like t·dω/dk, so larger steps are off by (h t dω/dk)⁴.
            let h = 1e-4 * p.get(*par).abs().max(1e-2);
            let at = |dp: f64| {
                let mut q = p.clone();
                q.set(*par, p.get(*par) + dp);
                forward(&q, &loading, &times)
            };
            let (m2, m1, p1, p2) = (at(-2.0 * h), at(-h), at(h), at(2.0 * h));
            let fd: Vec<f64> = (0..times.len())
                .map(|i| (m2[i] - 8.0 * m1[i] + 8.0 * p1[i] - p2[i]) / (12.0 * h))
                .collect();
            let scale = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let worst = (0..times.len())
                .map(|i| (s.dmu[i * varied.len() + j] - fd[i]).abs())
                .fold(0.0f64, f64::max);
            eprintln!(
                "{:?} {par:?}: |dμ/dp| up to {scale:.3e}, largest difference {:.1e} relative",
                p.states[0].law,
                worst / scale
            );
            assert!(worst <= 1e-6 * scale, "{par:?}: {worst:e} against {scale:e}");
        }
    }
}

/// A record made from `truth` plus N(0, σ²) noise at 10 Hz over the step loading.
fn synthetic(truth: &LabParams, sigma: f64, seed: u64) -> FrictionRecord {
    let loading = step_loading();
    let t: Vec<f64> = (0..=800).map(|i| 0.1 * f64::from(i)).collect();
    let mut rng = Rng::for_realisation(seed, 0);
    let mu = forward(truth, &loading, &t).into_iter().map(|m| m + sigma * rng.normal()).collect();
    FrictionRecord { t, mu, x_lp: None }
}

/// σ̂²(JᵀJ)⁻¹ from a central-difference Jacobian of forward runs at `p`: an independent check
/// of the fit's standard errors.
fn finite_difference_errors(
    p: &LabParams,
    record: &FrictionRecord,
    varied: &[LabParameter],
) -> Vec<f64> {
    let loading = step_loading();
    let mu = forward(p, &loading, &record.t);
    let r = DVector::from_iterator(mu.len(), mu.iter().zip(&record.mu).map(|(a, b)| a - b));
    let mut jac = DMatrix::zeros(mu.len(), varied.len());
    for (j, par) in varied.iter().enumerate() {
        let h = 1e-5 * p.get(*par).abs().max(1e-2);
        let (mut up, mut down) = (p.clone(), p.clone());
        up.set(*par, p.get(*par) + h);
        down.set(*par, p.get(*par) - h);
        let (u, d) = (forward(&up, &loading, &record.t), forward(&down, &loading, &record.t));
        for i in 0..mu.len() {
            jac[(i, j)] = (u[i] - d[i]) / (2.0 * h);
        }
    }
    let names: Vec<String> = varied.iter().map(|v| format!("{v:?}")).collect();
    statistics::uncertainty(&jac, &r, &names).unwrap().standard_errors
}

#[test]
fn synthetic_fits_recover_the_parameters_within_three_standard_errors() {
    for law in [LabLaw::Ageing, LabLaw::Slip] {
        let truth = params(vec![state(law, 0.015, 5.0)]);
        let record = synthetic(&truth, 1e-4, 7);
        let mut start = truth.clone();
        start.a *= 1.3;
        start.states[0].b *= 0.8;
        start.states[0].d_c *= 2.0;
        let names = ["a", "b_1", "d_c_1"];
        let settings = FitSettings {
            params: names.iter().map(|n| FitParameter::parse(n, 1).unwrap()).collect(),
            solver: tight(),
            limits: FitLimits::default(),
        };
        let out = lab_fit::fit(&start, &step_loading(), &record, &settings).unwrap();
        assert!(out.converged, "{law:?}: {:?}", out.termination);
        let exact = [truth.a, truth.states[0].b, truth.states[0].d_c];
        for (fitted, exact) in out.parameters.iter().zip(exact) {
            let z = (fitted.value - exact) / fitted.standard_error;
            eprintln!(
                "{law:?} {}: {} ± {:.2e} (true {exact}, {z:+.2} σ)",
                fitted.name, fitted.value, fitted.standard_error
            );
            assert!(z.abs() < 3.0, "{law:?} {}: {z} standard errors off", fitted.name);
        }
        assert!((out.residual_rms / 1e-4 - 1.0).abs() < 0.1, "rms {}", out.residual_rms);
        // The standard errors against an independent finite-difference Jacobian (in ln D_c,
        // converted as the fit does).
        let varied = [LabParameter::A, LabParameter::B(0), LabParameter::LnDc(0)];
        let independent = finite_difference_errors(&out.model, &record, &varied);
        for (j, fitted) in out.parameters.iter().enumerate() {
            let other =
                if j == 2 { independent[j] * out.model.states[0].d_c } else { independent[j] };
            let ratio = fitted.standard_error / other;
            eprintln!(
                "{law:?} {}: standard error {:.3e}, finite differences {other:.3e}",
                fitted.name, fitted.standard_error
            );
            assert!((ratio - 1.0).abs() < 0.1, "{}: ratio {ratio}", fitted.name);
        }
        assert!(out.lag1_autocorrelation.abs() < 0.2);
        // The start (a 30 % high, b 20 % low) is velocity strengthening, the truth weakening:
        // the one warning is the flipped a − b.
        assert_eq!(out.warnings.len(), 1, "{:?}", out.warnings);
        assert!(out.warnings[0].contains("a − b changed sign"), "{:?}", out.warnings);
    }
}

/// The load-point history taken from the record's displacement (`--loading data`) gives the
/// fit that the scene's loading gives when the displacement is exact.
#[test]
fn loading_from_the_records_displacement() {
    let truth = params(vec![state(LabLaw::Ageing, 0.015, 5.0)]);
    let mut record = synthetic(&truth, 1e-4, 11);
    let loading = step_loading();
    record.x_lp = Some(loading.displacements_at(&record.t));
    let scene_text = serde_json::json!({
        "name": "from-data",
        "model": {"kind": "lab", "mu0": 0.6, "a": 0.012, "v0": 1.0, "k": 3e-3,
                  "states": [{"law": "ageing", "b": 0.014, "d_c": 8.0}]},
        "loading": {"segments": [{"t_start": 0.0, "velocity": 1.0}, {"t_start": 10.0, "velocity": 10.0},
                                 {"t_start": 40.0, "velocity": 3.0}], "t_end": 80.0},
        "solver": {"method": "cvode-bdf", "rtol": 1e-12}
    })
    .to_string();
    let stickslip::scene::AnyScene::Lab(scene) =
        stickslip::scene::parse_any(&scene_text, "from-data").unwrap()
    else {
        panic!("a lab scene")
    };
    let params: Vec<FitParameter> =
        ["a", "b_1", "d_c_1"].iter().map(|n| FitParameter::parse(n, 1).unwrap()).collect();
    let fit = |loading| {
        stickslip::engine::lab::fit(
            &scene,
            &record,
            "synthetic",
            params.clone(),
            loading,
            FitLimits::default(),
        )
        .unwrap()
    };
    let (from_scene, from_data) = (
        fit(stickslip::engine::lab::FitLoading::Scene),
        fit(stickslip::engine::lab::FitLoading::Data),
    );
    assert_eq!(from_data.loading, "data");
    for (a, b) in from_scene.outcome.parameters.iter().zip(&from_data.outcome.parameters) {
        assert!(
            (a.value - b.value).abs() < 1e-3 * a.standard_error,
            "{}: {} vs {}",
            a.name,
            a.value,
            b.value
        );
    }
}

#[test]
fn autocorrelated_residuals_are_warned_about() {
    // Fit the ageing law to a record made by the slip law: the misfit is systematic.
    let truth = params(vec![state(LabLaw::Slip, 0.015, 5.0)]);
    let record = synthetic(&truth, 1e-5, 3);
    let start = params(vec![state(LabLaw::Ageing, 0.015, 5.0)]);
    let settings = FitSettings {
        params: ["a", "b_1", "d_c_1"].iter().map(|n| FitParameter::parse(n, 1).unwrap()).collect(),
        solver: tight(),
        limits: FitLimits::default(),
    };
    let out = lab_fit::fit(&start, &step_loading(), &record, &settings).unwrap();
    assert!(out.lag1_autocorrelation > 0.5, "{}", out.lag1_autocorrelation);
    assert!(out.warnings[0].contains("autocorrelated"), "{:?}", out.warnings);
}

#[test]
fn bad_requests_name_the_fix() {
    let p = params(vec![state(LabLaw::Ageing, 0.015, 5.0)]);
    let record = synthetic(&p, 1e-4, 1);
    let fit = |names: &[&str]| {
        let params =
            names.iter().map(|n| FitParameter::parse(n, 1)).collect::<Result<Vec<_>, _>>()?;
        let settings = FitSettings { params, solver: tight(), limits: FitLimits::default() };
        lab_fit::fit(&p, &step_loading(), &record, &settings).map(|_| ()).map_err(|e| e.to_string())
    };
    assert!(fit(&["b_2"]).unwrap_err().contains("state variables 1 to 1"));
    assert!(fit(&["alpha"]).unwrap_err().contains("choose from"));
    assert!(fit(&["a", "a"]).unwrap_err().contains("twice"));
    assert!(fit(&["mu0", "trend"]).unwrap_err().contains("at least one of"));
}

/// The real basalt step b819 fitted under the slip and the ageing law (a, b, D_c, k, μ0,
/// trend) agrees with scipy's least_squares over an independent Radau model
/// (data/reference/lab/fit_reference.json, made by benches/lab_fit_scipy.py): values within
/// 1 % of a standard error, standard errors within 2 %.
#[test]
fn basalt_step_fits_agree_with_an_independent_scipy_fit() {
    let reference: serde_json::Value =
        serde_json::from_str(include_str!("../data/reference/lab/fit_reference.json")).unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/data/scenes/lab-basalt-b819.json")).unwrap();
    let data =
        std::path::PathBuf::from(format!("{root}/data/lab/velstep4_BRAVA_expb819_basalt.txt"));
    for law in ["slip", "ageing"] {
        let text = text.replace("\"law\": \"slip\"", &format!("\"law\": \"{law}\""));
        let stickslip::scene::AnyScene::Lab(scene) =
            stickslip::scene::parse_any(&text, "b819").unwrap()
        else {
            panic!("a lab scene")
        };
        let report = stickslip::engine::lab::fit_file(
            &scene,
            &data,
            "a,b_1,d_c_1,k,mu0,trend",
            "t=Time(s),x_lp=Displ(microns),mu=Friction",
            stickslip::engine::lab::FitLoading::Scene,
            FitLimits::default(),
        )
        .unwrap();
        assert!(report.outcome.converged, "{law}: {:?}", report.outcome.termination);
        let scipy = &reference["cases"][format!("basalt_{law}")]["scipy"];
        for p in &report.outcome.parameters {
            let value = scipy["values"][&p.name].as_f64().unwrap();
            let se = scipy["standard_errors"][&p.name].as_f64().unwrap();
            let off = (p.value - value) / se;
            eprintln!(
                "{law} {}: {} ± {:.3e}; scipy {value} ± {se:.3e} ({off:+.1e} σ)",
                p.name, p.value, p.standard_error
            );
            assert!(off.abs() < 0.01, "{law} {}: {off} standard errors from scipy's", p.name);
            assert!((p.standard_error / se - 1.0).abs() < 0.02, "{law} {}: standard error", p.name);
        }
        assert!(report.outcome.warnings.iter().any(|w| w.contains("autocorrelated")));
    }
}

/// `stickslip fit` on the command line: the real record with its figure and report; a bad
/// request exits 2 naming the fix, and writes nothing.
#[test]
fn the_cli_fits_the_basalt_step_and_refuses_bad_requests() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = std::env::temp_dir().join(format!("stickslip-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (svg, json) = (dir.join("b819.svg"), dir.join("b819.json"));
    let fit = |params: &str, columns: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
            .current_dir(root)
            .args(["fit", "data/scenes/lab-basalt-b819.json", "--data"])
            .arg("data/lab/velstep4_BRAVA_expb819_basalt.txt")
            .args(["--params", params, "--columns", columns, "--figure"])
            .arg(&svg)
            .arg("--out")
            .arg(&json)
            .output()
            .unwrap()
    };
    let columns = "t=Time(s),x_lp=Displ(microns),mu=Friction";
    let ok = fit("a,b_1,d_c_1,k,mu0,trend", columns);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["parameters"].as_array().unwrap().len(), 6);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    std::fs::remove_file(&svg).unwrap();
    std::fs::remove_file(&json).unwrap();
    for (params, columns, says) in [
        ("a,b_2", columns, "state variables 1 to 1"),
        ("a", "t=Time,mu=Friction", "no column \"Time\""),
        ("a", "t=Time(s),mu=Friction,x_lp=Displ(microns),v=V", "unknown key \"v\""),
    ] {
        let out = fit(params, columns);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
        assert!(!svg.exists() && !json.exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The basalt scene (`data/scenes/lab-basalt-b819.json`) with `law` and `solver` replaced.
fn basalt_scene(law: &str, solver: &str) -> stickslip::scene::lab::LabScene {
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/data/scenes/lab-basalt-b819.json")).unwrap();
    let text = text
        .replace("\"law\": \"slip\"", &format!("\"law\": \"{law}\""))
        .replace("{\"method\": \"cvode-bdf\", \"rtol\": 1e-10}", solver);
    let stickslip::scene::AnyScene::Lab(scene) =
        stickslip::scene::parse_any(&text, "b819").unwrap()
    else {
        panic!("a lab scene")
    };
    *scene
}

fn fit_basalt(
    scene: &stickslip::scene::lab::LabScene,
    limits: FitLimits,
) -> Result<stickslip::report::lab_fit::FitReport, FitError> {
    let root = env!("CARGO_MANIFEST_DIR");
    let data =
        std::path::PathBuf::from(format!("{root}/data/lab/velstep4_BRAVA_expb819_basalt.txt"));
    stickslip::engine::lab::fit_file(
        scene,
        &data,
        "a,b_1,d_c_1,k,mu0,trend",
        "t=Time(s),x_lp=Displ(microns),mu=Friction",
        stickslip::engine::lab::FitLoading::Scene,
        limits,
    )
}

/// The fit integrates with the scene's method and says which: radau5 and rodas5p (the state
/// and its sensitivity equations as one system) agree with cvode-bdf (CVODES' sensitivities)
/// within 0.01 standard errors on every parameter of the basalt step; arkode-imex is refused
/// with the reason.
#[test]
fn the_fit_runs_the_scenes_method() {
    let default = fit_basalt(
        &basalt_scene("slip", "{\"method\": \"cvode-bdf\", \"rtol\": 1e-10}"),
        FitLimits::default(),
    )
    .unwrap();
    assert_eq!(default.sensitivities, "cvodes");
    for method in ["radau5", "rodas5p"] {
        let scene = basalt_scene("slip", &format!("{{\"method\": \"{method}\", \"rtol\": 1e-10}}"));
        let report = fit_basalt(&scene, FitLimits::default()).unwrap();
        assert_eq!(report.solver.method.name(), method);
        assert_eq!(report.sensitivities, "one-system");
        assert!(report.outcome.converged);
        for (a, b) in default.outcome.parameters.iter().zip(&report.outcome.parameters) {
            let off = (a.value - b.value) / a.standard_error;
            eprintln!("{method} {}: {:+.1e} standard errors from cvode-bdf's", a.name, off);
            assert!(off.abs() < 0.01, "{method} {}: {off} standard errors", a.name);
            assert!((a.standard_error / b.standard_error - 1.0).abs() < 1e-3);
        }
    }
    let imex = basalt_scene("slip", "{\"method\": \"arkode-imex\"}");
    match fit_basalt(&imex, FitLimits::default()) {
        Err(FitError::BadInput(m)) => {
            assert!(m.contains("arkode-imex") && m.contains("arkode-dirk"), "{m}")
        }
        other => panic!("{other:?}"),
    }
}

/// The limits end a fit: `max_evaluations` is obeyed, an evaluation far costlier than the
/// first stops it naming the parameter values, and a time limit stops even the first.
#[test]
fn limits_stop_the_fit() {
    let scene = basalt_scene("ageing", "{\"method\": \"cvode-bdf\", \"rtol\": 1e-10}");
    let five = FitLimits { max_evaluations: 5, ..FitLimits::default() };
    let o = fit_basalt(&scene, five).unwrap().outcome;
    assert_eq!(
        (o.evaluations, o.termination, o.converged),
        (5, Termination::MaxEvaluations, false)
    );
    assert!(o.stopped.unwrap().contains("--max-evaluations 5"));
    // Any evaluation costlier than the first (some are: the ageing fit's steps vary).
    let strict = FitLimits { cost_factor: 1, min_step_budget: 1, ..FitLimits::default() };
    let o = fit_basalt(&scene, strict).unwrap().outcome;
    assert_eq!(o.termination, Termination::ExpensiveEvaluation);
    let why = o.stopped.unwrap();
    assert!(why.contains("a = ") && why.contains("d_c_1 = ") && why.contains("µm"), "{why}");
    let instant =
        FitLimits { max_time: std::time::Duration::from_nanos(1), ..FitLimits::default() };
    match fit_basalt(&scene, instant) {
        Err(FitError::Stopped(m)) => assert!(m.contains("--max-time"), "{m}"),
        other => panic!("{other:?}"),
    }
}

/// A blow-up at the starting values is said as such, with what to change.
#[test]
fn a_blow_up_at_the_start_says_what_to_change() {
    let mut scene = basalt_scene("slip", "{\"method\": \"cvode-bdf\", \"rtol\": 1e-10}");
    scene.params.a = 0.005;
    scene.params.k = 1e-4;
    match fit_basalt(&scene, FitLimits::default()) {
        Err(FitError::BlowUp(m)) => {
            assert!(m.contains("blows up in finite time") && m.contains("segment 2 of 2"), "{m}");
            assert!(m.contains("critical stiffness"), "{m}");
        }
        other => panic!("{other:?}"),
    }
}

/// The report's `model` pastes back into a scene; `termination` is a documented word.
#[test]
fn the_reports_model_is_a_scene_model() {
    let scene = basalt_scene("slip", "{\"method\": \"cvode-bdf\", \"rtol\": 1e-10}");
    let report = fit_basalt(&scene, FitLimits::default()).unwrap();
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    assert_eq!(json["termination"], "converged");
    assert_eq!(json["model"]["kind"], "lab");
    let text = serde_json::json!({
        "name": "refit",
        "model": json["model"],
        "loading": {"segments": [{"t_start": 0, "velocity": 1}], "t_end": 10}
    })
    .to_string();
    let stickslip::scene::AnyScene::Lab(again) =
        stickslip::scene::parse_any(&text, "refit").unwrap()
    else {
        panic!("a lab scene")
    };
    assert_eq!(again.params, report.outcome.model);
    let d = &report.outcome.a_minus_b;
    assert!((d.value - (report.outcome.model.a - report.outcome.model.states[0].b)).abs() < 1e-15);
    assert!(d.standard_error > 0.0 && d.standard_error < 1e-4);
}

/// On the command line: the basalt scene with its second velocity typed 10× too large ends at
/// once (exit 2, naming the segment); a record in metres against the scene's µm exits 2
/// naming the units; `--max-evaluations 5` exits 4 with the report; `--series` writes the
/// record beside the fit.
#[test]
fn the_cli_refuses_inconsistent_units_and_obeys_its_limits() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = std::env::temp_dir().join(format!("stickslip-fit-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene =
        std::fs::read_to_string(format!("{root}/data/scenes/lab-basalt-b819.json")).unwrap();
    let typo = dir.join("typo.json");
    std::fs::write(&typo, scene.replace("\"velocity\": 10.0308", "\"velocity\": 100.308")).unwrap();
    let record =
        std::fs::read_to_string(format!("{root}/data/lab/velstep4_BRAVA_expb819_basalt.txt"))
            .unwrap();
    let metres = dir.join("metres.txt");
    let converted: Vec<String> = record
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut f: Vec<String> = l.split('\t').map(String::from).collect();
            if i > 0 {
                f[1] = format!("{:e}", f[1].parse::<f64>().unwrap() * 1e-6);
            }
            f.join("\t")
        })
        .collect();
    std::fs::write(&metres, converted.join("\n")).unwrap();
    let fit = |scene: &std::path::Path, data: &std::path::Path, extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
            .current_dir(root)
            .arg("fit")
            .arg(scene)
            .arg("--data")
            .arg(data)
            .args(["--params", "a,b_1,d_c_1,k,mu0,trend", "--columns"])
            .arg("t=Time(s),x_lp=Displ(microns),mu=Friction")
            .args(extra)
            .output()
            .unwrap()
    };
    let basalt = std::path::Path::new("data/scenes/lab-basalt-b819.json");
    let record = std::path::Path::new("data/lab/velstep4_BRAVA_expb819_basalt.txt");
    let out = fit(&typo, record, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("segment 2 of 2") && stderr.contains("100.308"), "{stderr}");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .current_dir(root)
        .args(["fit", "data/scenes/lab-basalt-b819.json", "--data"])
        .arg(&metres)
        .args(["--params", "a,b_1,d_c_1", "--columns", "t=Time(s),x_lp=Displ(microns),mu=Friction"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("metres") && stderr.contains("µm"), "{stderr}");
    let (series, report) = (dir.join("fit.csv"), dir.join("fit.json"));
    let out = fit(
        basalt,
        record,
        &[
            "--max-evaluations",
            "5",
            "--series",
            series.to_str().unwrap(),
            "--out",
            report.to_str().unwrap(),
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("--max-evaluations 5"), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(
        (json["evaluations"].as_u64(), json["termination"].as_str()),
        (Some(5), Some("max_evaluations"))
    );
    let csv = std::fs::read_to_string(&series).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,mu_measured,mu_fitted,residual"));
    let rows: Vec<Vec<f64>> =
        lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 5849);
    assert!(rows.iter().all(|r| (r[3] - (r[2] - r[1])).abs() < 1e-15));
    assert_eq!(rows[0][0], 11607.7);
    std::fs::remove_dir_all(&dir).unwrap();
}
