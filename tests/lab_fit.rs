//! `stickslip fit`'s engine: CVODES' sensitivities of the lab model against central
//! differences of independent forward runs, and fits of synthetic records made from known
//! parameters plus noise.

use nalgebra::{DMatrix, DVector};
use stickslip::analysis::lab::{self, LabSolver, Output};
use stickslip::analysis::lab_fit::{self, statistics, FitParameter, FitSettings, FrictionRecord};
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
            patience: 100,
        };
        let out = lab_fit::fit(&start, &step_loading(), &record, &settings).unwrap();
        assert!(out.converged, "{law:?}: {}", out.termination);
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
        assert!(out.lag1_autocorrelation.abs() < 0.2 && out.warnings.is_empty());
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
        stickslip::engine::lab::fit(&scene, &record, "synthetic", params.clone(), loading).unwrap()
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
        patience: 100,
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
        let settings = FitSettings { params, solver: tight(), patience: 10 };
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
        )
        .unwrap();
        assert!(report.outcome.converged, "{law}: {}", report.outcome.termination);
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
