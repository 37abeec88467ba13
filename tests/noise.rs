//! The noise analysis: weak convergence on the linear OU problem (exact mean and variance),
//! ensembles against the linear response at small amplitude, reproducibility whatever the
//! number of threads, the shipped scenes in reduced form, scene validation.

use stickslip::analysis::noise::ensemble::{self, EnsembleSpec, Sampling};
use stickslip::analysis::noise::models::NoiseModel;
use stickslip::analysis::noise::options::NoiseOptions;
use stickslip::analysis::noise::scheme::{SchemeSettings, Start};
use stickslip::analysis::noise::{self, NoiseReport};
use stickslip::engine::RunOptions;
use stickslip::model::{
    Drr, DrrParams, Friction, SaddleNode, SaddleNodeParams, StateLaw, VanDerPol, VanDerPolParams,
};
use stickslip::scene::{self, AnyScene};

/// Var x(T) for dx/dt = −λx + σf, x(0) deterministic, f the stationary unit OU of correlation
/// time τ: 2σ²∫₀ᵀ∫₀ˢ e^{−λ(2T−s−s')} e^{−(s−s')/τ} ds' ds in closed form.
fn exact_variance(lambda: f64, sigma: f64, tau: f64, t: f64) -> f64 {
    let mu = 1.0 / tau;
    2.0 * sigma * sigma / (lambda + mu)
        * ((-(-2.0 * lambda * t).exp_m1()) / (2.0 * lambda)
            - ((-(lambda + mu) * t).exp() - (-2.0 * lambda * t).exp()) / (lambda - mu))
}

/// The scheme's own variance of x(T) for the same problem, computed independently of the code
/// under test: x(T) = x0 e^{−λT} + Σ_k w_k η_k is linear in the node values η_{−1}, …, η_{N+1}
/// (Catmull–Rom spline, exact integration of each interval), and Cov(η_k, η_l) = a^{|k−l|}.
fn scheme_variance(lambda: f64, sigma: f64, tau: f64, t: f64, h: f64) -> f64 {
    let n = (t / h).round() as usize;
    let c = lambda * h;
    // J_m = ∫₀¹ s^m e^{−c(1−s)} ds.
    let mut j = [0.0; 4];
    j[0] = -(-c).exp_m1() / c;
    for m in 1..4 {
        j[m] = 1.0 / c - m as f64 / c * j[m - 1];
    }
    let h00 = h * (2.0 * j[3] - 3.0 * j[2] + j[0]);
    let h10 = h * (j[3] - 2.0 * j[2] + j[1]);
    let h01 = h * (3.0 * j[2] - 2.0 * j[3]);
    let h11 = h * (j[3] - j[2]);
    // Node k has index k + 1 (η_{−1} at 0).
    let mut w = vec![0.0; n + 3];
    for k in 0..n {
        let e = sigma * (-lambda * (t - (k + 1) as f64 * h)).exp();
        let i = k + 1;
        w[i] += e * (h00 - 0.5 * h11);
        w[i + 1] += e * (h01 + 0.5 * h10);
        w[i - 1] -= e * 0.5 * h10;
        w[i + 2] += e * 0.5 * h11;
    }
    let a = (-h / tau).exp();
    let (mut total, mut running) = (0.0, 0.0);
    for wk in &w {
        total += wk * wk + 2.0 * wk * running;
        running = (running + wk) * a;
    }
    total
}

/// Sample mean and variance of x(T) over `count` realisations of the scheme.
fn ensemble_moments(
    lambda: f64,
    sigma: f64,
    tau: f64,
    t: f64,
    h: f64,
    x0: f64,
    count: usize,
) -> (f64, f64) {
    let model = NoiseModel::Linear { rate: lambda, amplitude: sigma };
    let start = Start { t: 0.0, x: vec![x0] };
    let scheme = SchemeSettings { h, tau, rtol: 1e-9, atol: vec![1e-12] };
    let spec = EnsembleSpec {
        model: &model,
        start: &start,
        scheme: &scheme,
        event: None,
        record_until: t,
        t_max: 2.0 * t,
        seed: 7,
    };
    let s = [t];
    let data = ensemble::run(
        &spec,
        &Sampling { s: &s, fixed_reference: Some(0.0) },
        count,
        ensemble::Workers { threads: 2, progress: &|_, _| {}, stop: &|| false },
    )
    .unwrap();
    let n = count as f64;
    let mean = data.samples.iter().sum::<f64>() / n;
    let var = data.samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

#[test]
fn weak_convergence_on_the_linear_ou_problem() {
    // The scheme's exact variance against the true one: second order in h/τ for a response
    // slower than the nodes (λτ = 1/2) ...
    let (lambda, tau, t) = (1.0, 0.5, 2.0);
    let exact = exact_variance(lambda, 1.0, tau, t);
    let errors: Vec<f64> = [2, 4, 8, 16, 32]
        .iter()
        .map(|m| (scheme_variance(lambda, 1.0, tau, t, tau / *m as f64) - exact) / exact)
        .collect();
    for pair in errors.windows(2) {
        let order = (pair[0] / pair[1]).abs().log2();
        assert!((1.8..2.3).contains(&order), "order {order} from {errors:?}");
    }
    // ... and at most 0.5 % anywhere at the default h = τ/10 (λ = 1/τ, where the formula
    // divides by zero, is skipped), the worst being a response on
    // the time scale of the nodes (λh ≈ 3), where it converges at first order.
    for lh in [0.011, 0.12, 0.3, 1.01, 3.0, 10.0, 30.0, 100.0, 1000.0] {
        let (tau, h) = (1.0, 0.1);
        let lambda = lh / h;
        let t = ((20.0f64).max(5.0 / lambda) / h).round() * h;
        let exact = exact_variance(lambda, 1.0, tau, t);
        let rel = (scheme_variance(lambda, 1.0, tau, t, h) - exact) / exact;
        assert!(rel.abs() < 5e-3, "λh = {lh}: relative variance error {rel:e}");
    }
    let band: Vec<f64> = [5.0, 10.0, 20.0]
        .iter()
        .map(|m| {
            let (tau, h) = (1.0, 1.0 / m);
            let lambda = 3.0 / h;
            let exact = exact_variance(lambda, 1.0, tau, 20.0);
            ((scheme_variance(lambda, 1.0, tau, 20.0, h) - exact) / exact).abs()
        })
        .collect();
    for pair in band.windows(2) {
        let order = (pair[0] / pair[1]).log2();
        assert!((0.8..1.3).contains(&order), "first order in the band λh ≈ 3: {band:?}");
    }
}

#[test]
fn ensembles_reproduce_the_exact_mean_and_the_scheme_variance() {
    // The Monte Carlo check that the code is the scheme analysed above: sample moments against
    // the exact mean x0 e^{−λT} and the scheme's variance, within 4 standard errors. At h = τ/2
    // the scheme's variance differs from the true one by 1.6 %, at τ/10 by 0.1 %.
    let count = 40_000;
    for (lambda, tau, t, m) in [(1.0, 0.5, 1.0, 10.0), (6.0, 1.0, 2.0, 2.0), (1e4, 0.5, 1.0, 10.0)]
    {
        let (x0, h) = (1.0, tau / m);
        let (mean, var) = ensemble_moments(lambda, 1.0, tau, t, h, x0, count);
        let scheme = scheme_variance(lambda, 1.0, tau, t, h);
        let se_mean = (scheme / count as f64).sqrt();
        let se_var = scheme * (2.0 / (count as f64 - 1.0)).sqrt();
        let exact_mean = x0 * (-lambda * t).exp();
        assert!(
            (mean - exact_mean).abs() < 4.0 * se_mean,
            "λ = {lambda}: mean {mean} vs {exact_mean} (s.e. {se_mean:e})"
        );
        assert!(
            (var - scheme).abs() < 4.0 * se_var,
            "λ = {lambda}, h = τ/{m}: variance {var} vs scheme {scheme} (s.e. {se_var:e})"
        );
        let exact = exact_variance(lambda, 1.0, tau, t);
        if m >= 10.0 {
            assert!(
                (var - exact).abs() < 4.0 * se_var + 5e-3 * exact,
                "λ = {lambda}: variance {var} vs exact {exact}"
            );
        }
    }
}

fn fig1_drr(amplitudes: [f64; 3]) -> (NoiseModel, Vec<f64>) {
    let drr = Drr::new(DrrParams::new(1e3, 0.7, 0.72, Friction::Log));
    let w = 0.5f64.ln();
    let theta = drr.fixed_point()[2];
    (NoiseModel::Drr { system: drr, amplitudes }, vec![drr.manifold_u(w, theta), w, theta])
}

fn options(json: &str) -> NoiseOptions {
    serde_json::from_str(json).unwrap()
}

/// At small amplitude the ensemble's σ agrees with the linear response within the sampling
/// error at (almost) every reported time, and so do the correlation times.
fn assert_agreement(report: &NoiseReport) {
    assert!(!report.agreement.is_empty());
    for a in &report.agreement {
        let reported = report.correlation_time.len();
        assert!(
            a.sigma_disagree_at.len() * 20 <= reported,
            "{}: σ beyond 4 standard errors at {:?} (max relative difference {})",
            a.name,
            a.sigma_disagree_at,
            a.sigma_max_relative_difference
        );
        // A half-height crossing read off a sampled Γ moves by ~1/√R of its lag scale: ~0.1
        // to 0.2 at R = 300 (measured: 0.04 at R = 2000, 0.15 at R = 300 for the saddle-node).
        if let Some(m) = a.tau_median_relative_difference {
            assert!(m < 0.3, "{}: median relative difference of τ {m}", a.name);
        }
    }
}

#[test]
fn drr_ensemble_agrees_with_the_linear_response_at_small_noise() {
    let (model, initial) = fig1_drr([1e-3, 1e3, 1e-3]);
    let o = options(
        r#"{"amplitudes": [1e-3, 1e3, 1e-3], "realisations": 300, "start_before_event": 2.5, "window": [1.5, 0.03], "grid_points": 400}"#,
    );
    let r = noise::run(&model, &initial, &o, 2, &|_, _| {}).unwrap();
    assert_eq!(stickslip::numerics::finite::first_non_finite(&r, "noise"), None);
    assert_agreement(&r);
    // The event time of the deterministic start and of the scheme without noise agree.
    assert!(r.deterministic.scheme_event_time_error.abs() < 1e-6, "{:?}", r.deterministic);
    assert!((r.deterministic.event_time - 2.5).abs() < 1e-6);
    // Event-time spread: ensemble against linear response.
    let lin = r.events.std_linear_response.unwrap();
    assert!((r.events.std / lin - 1.0).abs() < 0.25, "{} vs {lin}", r.events.std);
    // ... as its validity says: in each realisation's own frame the event function (d ln v/dt)
    // stays the orbit's over the spread (measured deviation 0.002: the slip arrives early or
    // late as a whole).
    let linearity = r.events.linearity.as_ref().unwrap();
    assert!(linearity.valid && linearity.own_frame_deviation < 0.02, "{linearity:?}");
    // The correlation time of u shrinks towards the slip (speed-up), in both: the last one
    // (30/γ before the slip) is below half the largest one in the window.
    let last = r.correlation_time.last().unwrap();
    let largest = |f: fn(&noise::CorrelationPoint) -> Option<f64>| {
        r.correlation_time.iter().filter_map(f).fold(0.0, f64::max)
    };
    assert!(
        last.tau_linear_response.unwrap() < 0.5 * largest(|p| p.tau_linear_response),
        "{:?}",
        r.correlation_time
    );
    assert!(last.tau.unwrap() < 0.5 * largest(|p| p.tau), "{:?}", r.correlation_time);
    let g = r.growth.as_ref().unwrap();
    assert!(
        (g.sigma_v_growth / g.sigma_v_growth_linear_response.unwrap() - 1.0).abs() < 0.3,
        "{g:?}"
    );
}

/// The noise analysis under the ageing law and under PRZ with radiation damping: the scheme
/// without noise finds the event of the deterministic orbit (computed with Drr's own
/// right-hand side, so the realisations' drift is the law's), the ensemble agrees with the
/// linear response, and the scene is accepted. With damping the linearised event time is
/// outside its validity at these amplitudes (`damped_slip_peak_is_outside_the_linearised_event_time`),
/// so that case is aligned on the deterministic event.
#[test]
fn drr_noise_runs_under_the_ageing_law_and_under_prz_with_damping() {
    for (law, eta, epsilon, alignment) in
        [(StateLaw::Ageing, 0.0, 0.72, "own_event"), (StateLaw::Prz, 0.05, 0.85, "deterministic")]
    {
        let drr = Drr::new(DrrParams {
            state_law: law,
            eta,
            ..DrrParams::new(1e3, 0.7, epsilon, Friction::Log)
        });
        let w = 0.5f64.ln();
        let theta = drr.fixed_point()[2];
        let model = NoiseModel::Drr { system: drr, amplitudes: [1e-3, 1e3, 1e-3] };
        let o = options(&format!(
            r#"{{"amplitudes": [1e-3, 1e3, 1e-3], "realisations": 200, "start_before_event": 2.5, "window": [1.5, 0.03], "grid_points": 400, "alignment": "{alignment}"}}"#
        ));
        let r =
            noise::run(&model, &[drr.manifold_u(w, theta), w, theta], &o, 2, &|_, _| {}).unwrap();
        let name = law.name();
        assert_eq!(stickslip::numerics::finite::first_non_finite(&r, "noise"), None, "{name}");
        assert!(
            r.deterministic.scheme_event_time_error.abs() < 1e-6,
            "{name}: {:?}",
            r.deterministic
        );
        assert_agreement(&r);
        if alignment == "own_event" {
            let lin = r.events.std_linear_response.unwrap();
            assert!((r.events.std / lin - 1.0).abs() < 0.25, "{name}: {} vs {lin}", r.events.std);
            assert!(r.events.linearity.as_ref().unwrap().valid, "{name}: {:?}", r.events.linearity);
        }
        let scene = format!(
            r#"{{"name": "t", "model": {{"gamma": 1e3, "xi": 0.7, "epsilon": {epsilon}, "state_law": "{name}", "radiation_damping": {eta}}}, "analyses": [{{"noise": {{"amplitudes": [0, 1e-3, 0]}}}}]}}"#
        );
        assert!(scene::parse(&scene, "test").is_ok(), "{name}");
    }
}

fn prz_damped(amplitudes: [f64; 3]) -> (Drr, NoiseModel, Vec<f64>) {
    let drr = Drr::new(DrrParams {
        state_law: StateLaw::Prz,
        eta: 0.05,
        ..DrrParams::new(1e3, 0.7, 0.85, Friction::Log)
    });
    let w = 0.5f64.ln();
    let theta = drr.fixed_point()[2];
    (drr, NoiseModel::Drr { system: drr, amplitudes }, vec![drr.manifold_u(w, theta), w, theta])
}

/// With radiation damping the slip peak is slaved to the slow manifold: ln v relaxes onto it at
/// λ = γ²(1 + ηv)/(ξv) ≈ 1.1e5, so d ln v/dt, the event function, fluctuates with the part of
/// the noise faster than λ, and decorrelates within ln 2/λ ≈ 6e-6, while the linearised event
/// time would move by 4.6e-3 (docs/noise.md): the report says that the linearisation is not
/// valid (and the ensemble's spread is far from it), and the event function's correlation time
/// is that of the fast relaxation, computed here from the model's closed form.
#[test]
fn damped_slip_peak_is_outside_the_linearised_event_time() {
    let amplitudes = [1e-3, 1e3, 1e-3];
    let (drr, model, initial) = prz_damped(amplitudes);
    let o = options(
        r#"{"amplitudes": [1e-3, 1e3, 1e-3], "realisations": 100, "start_before_event": 1, "window": [0.8, 0.03], "correlation_curves_at": [0.5, 0.03], "grid_points": 300}"#,
    );
    let r = noise::run(&model, &initial, &o, 2, &|_, _| {}).unwrap();
    assert_eq!(stickslip::numerics::finite::first_non_finite(&r, "noise"), None);
    let l = r.events.linearity.as_ref().unwrap();
    assert!(!l.valid, "{l:?}");
    // In each realisation's own frame the event function has lost its relation to the orbit's
    // one spread before the event (~√2: δg decorrelated; measured 1.48).
    assert!(l.own_frame_deviation > 1.0, "{l:?}");
    let xc = &r.deterministic.event_state;
    let v = xc[1].exp();
    let p = drr.params();
    let rate = p.gamma * p.gamma * (1.0 + p.eta * v) / (p.xi * v);
    let width = l.event_function_correlation_time.unwrap();
    assert!(
        (width * rate / std::f64::consts::LN_2 - 1.0).abs() < 0.05,
        "{width} vs ln 2/λ = {}",
        std::f64::consts::LN_2 / rate
    );
    // What the flag warns of: the ensemble's event times spread far less (measured 5.7e-4 vs
    // 4.6e-3 linear, the same 5.4e-4 and 5.5e-4 at h = τ/10 and τ/40).
    let lin = r.events.std_linear_response.unwrap();
    assert!(r.events.std < 0.25 * lin, "{} vs {lin}", r.events.std);
    // Without damping (the Fig. 1 case) the same check passes: drr_ensemble_agrees_with_the_linear_response_at_small_noise.
}

/// A start inside a broad damped slip (v > 1 already, 1 before the peak under the slip law at
/// η = 0.05) is an error naming `start_before_event`: the deterministic event search, armed
/// only after v < 1, found the next slip a period later while the realisations aligned on this
/// one (before: a silent mean event shift of −9.6).
#[test]
fn a_start_inside_the_slip_is_an_error_naming_start_before_event() {
    let drr = Drr::new(DrrParams { eta: 0.05, ..DrrParams::new(1e3, 0.7, 0.85, Friction::Log) });
    let (w, theta) = (0.5f64.ln(), drr.fixed_point()[2]);
    let model = NoiseModel::Drr { system: drr, amplitudes: [1e-3, 1e3, 1e-3] };
    let o =
        options(r#"{"amplitudes": [1e-3, 1e3, 1e-3], "realisations": 2, "start_before_event": 1}"#);
    match noise::run(&model, &[drr.manifold_u(w, theta), w, theta], &o, 2, &|_, _| {}) {
        Err(stickslip::analysis::AnalysisError::InvalidOption(e)) => {
            assert_eq!(e.field, "start_before_event", "{e}")
        }
        other => {
            panic!("expected an error naming start_before_event, got {:?}", other.map(|r| r.events))
        }
    }
}

/// The small-noise limit of the damped case (amplitudes 1e-4 of the above): there the
/// linearisation holds better (own-frame deviation 0.32 over σ_tc = 4.6e-7), and the
/// ensemble's event-time spread converges to the linear response's as the noise step h
/// resolves the fast relaxation (λh = 27 at the default h = τ/10): measured ratio 0.19, 0.46,
/// 0.79, 0.87 at h = τ/10, τ/40, τ/160, τ/640 (200 realisations). ~30 s of CPU.
#[test]
#[ignore]
fn damped_event_time_converges_to_the_linear_response_as_the_noise_step_resolves_the_fast_relaxation(
) {
    let amplitudes = [1e-7, 0.1, 1e-7];
    let (_, model, initial) = prz_damped(amplitudes);
    let ratio = |steps: f64| {
        let o = options(&format!(
            r#"{{"amplitudes": [1e-7, 0.1, 1e-7], "realisations": 200, "start_before_event": 1, "window": [0.8, 0.03], "correlation_curves_at": [0.5, 0.03], "grid_points": 300, "rtol": 1e-9, "steps_per_correlation_time": {steps}}}"#
        ));
        let r = noise::run(&model, &initial, &o, 2, &|_, _| {}).unwrap();
        r.events.std / r.events.std_linear_response.unwrap()
    };
    let (coarse, fine) = (ratio(10.0), ratio(160.0));
    assert!(coarse < 0.3 && fine > 0.65, "{coarse} {fine}");
}

#[test]
fn saddle_node_and_van_der_pol_agree_with_their_linear_response() {
    let sn = NoiseModel::SaddleNode {
        system: SaddleNode::new(SaddleNodeParams { mu0: 1.0, r: 0.01 }),
        amplitude: 1e-3,
    };
    let o = options(
        r#"{"amplitudes": [1e-3], "realisations": 300, "start_before_event": 40, "grid_points": 1500}"#,
    );
    let r = noise::run(&sn, &[1.0], &o, 2, &|_, _| {}).unwrap();
    assert_agreement(&r);
    // Slowing down: the correlation time of x grows towards the fold, peaks shortly before the
    // escape and then drops.
    let tau: Vec<f64> = r.correlation_time.iter().filter_map(|p| p.tau_linear_response).collect();
    let peak = tau.iter().cloned().fold(0.0, f64::max);
    assert!(peak > 1.5 * tau[0] && peak > 1.5 * *tau.last().unwrap(), "{tau:?}");
    let vdp = NoiseModel::VanDerPol {
        system: VanDerPol::new(VanDerPolParams { beta: 30.0, a: 0.0 }),
        amplitudes: [1e-3, 1e-4],
    };
    let o = options(r#"{"amplitudes": [1e-3, 1e-4], "realisations": 300}"#);
    let r = noise::run(&vdp, &[2.0, -2.0 / 3.0], &o, 2, &|_, _| {}).unwrap();
    assert_agreement(&r);
    assert!(r.events.linearity.as_ref().unwrap().valid, "{:?}", r.events.linearity);
    assert_eq!(r.correlation_time_by_variable.len(), 3);
}

fn without_wall_times(report: &NoiseReport) -> serde_json::Value {
    let mut v = serde_json::to_value(report).unwrap();
    v["work"]["ensemble_wall_time_s"] = serde_json::Value::Null;
    v
}

#[test]
fn results_are_bit_identical_whatever_the_thread_count() {
    let sn = NoiseModel::SaddleNode {
        system: SaddleNode::new(SaddleNodeParams { mu0: 1.0, r: 0.01 }),
        amplitude: 1e-2,
    };
    let o = options(
        r#"{"amplitudes": [1e-2], "realisations": 24, "start_before_event": 20, "grid_points": 200, "linear_response": false}"#,
    );
    let one = noise::run(&sn, &[1.0], &o, 1, &|_, _| {}).unwrap();
    let three = noise::run(&sn, &[1.0], &o, 3, &|_, _| {}).unwrap();
    assert_eq!(without_wall_times(&one), without_wall_times(&three));
    let other_seed = options(
        r#"{"amplitudes": [1e-2], "realisations": 24, "start_before_event": 20, "grid_points": 200, "linear_response": false, "seed": 2}"#,
    );
    let two = noise::run(&sn, &[1.0], &other_seed, 3, &|_, _| {}).unwrap();
    assert_ne!(one.series[0].sigma, two.series[0].sigma);
}

#[test]
fn shipped_noise_scenes_run_in_reduced_form() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes");
    let mut ran = 0;
    for name in ["noise-drr", "noise-power-law", "noise-saddle-node", "noise-van-der-pol"] {
        let path = format!("{dir}/{name}.json");
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        // Reduced: 16 realisations, a coarser grid; the saddle-node from 40 before the escape.
        let noise = &mut json["analyses"][0]["noise"];
        noise["realisations"] = 16.into();
        noise["grid_points"] = 300.into();
        noise["report_points"] = 12.into();
        if name == "noise-saddle-node" {
            noise["start_before_event"] = 40.into();
        }
        let text = json.to_string();
        let scene = scene::parse_any(&text, &path).unwrap();
        assert!(!matches!(scene, AnyScene::Lab(_)), "{name}: a noise scene, not a lab one");
        let options = RunOptions::echoing(json.clone()).threads(2);
        let report =
            serde_json::to_value(stickslip::engine::run(&scene, options).unwrap()).unwrap();
        let points = report["noise"]["correlation_time"].as_array().unwrap();
        assert_eq!(points.len(), 12, "{name}");
        assert!(
            points.iter().all(|p| p["t_before_event"].is_f64() && p.get("tau").is_some()),
            "{name}"
        );
        assert!(points.iter().any(|p| p["tau"].is_f64()), "{name}: no correlation time at all");
        // No shipped scene is damped: each one's linearised event time holds (noise-drr 0.003,
        // its σ_tc 2.8e-3 longer than the event function's correlation time 1.8e-3: the slip
        // moves as a whole, which a mere decorrelation test would have taken for a failure).
        let linearity = &report["noise"]["events"]["linearity"];
        assert_eq!(linearity["valid"], true, "{name}: {linearity}");
        ran += 1;
    }
    assert_eq!(ran, 4);
}

#[test]
fn the_cli_runs_a_noise_scene_and_bad_noise_options_name_the_field() {
    let exe = env!("CARGO_BIN_EXE_stickslip");
    let dir = std::env::temp_dir().join(format!("stickslip-noise-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("vdp.json");
    std::fs::write(
        &scene,
        r#"{"name": "vdp", "model": {"kind": "van_der_pol", "beta": 30}, "analyses": [{"noise": {"amplitudes": [0.1, 0.01], "realisations": 8, "grid_points": 200}}]}"#,
    )
    .unwrap();
    let out = std::process::Command::new(exe)
        .args(["run", scene.to_str().unwrap(), "--json", "--threads", "2"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["noise"]["correlation_time"].as_array().is_some_and(|a| !a.is_empty()));
    // noise-curves collects the correlation-time curves of reports; a report without a noise
    // section is bad input (exit 2).
    let report_file = dir.join("vdp-report.json");
    std::fs::write(&report_file, &out.stdout).unwrap();
    let curves = dir.join("curves.json");
    let out = std::process::Command::new(exe)
        .args([
            "noise-curves",
            "--out",
            curves.to_str().unwrap(),
            report_file.to_str().unwrap(),
            report_file.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let combined: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&curves).unwrap()).unwrap();
    assert_eq!(combined["curves"].as_array().unwrap().len(), 2);
    assert_eq!(combined["curves"][0]["model"], "van_der_pol");
    assert_eq!(combined["curves"][0]["correlation_time"], report["noise"]["correlation_time"]);
    std::fs::write(dir.join("plain.json"), r#"{"name": "x"}"#).unwrap();
    let out = std::process::Command::new(exe)
        .args([
            "noise-curves",
            "--out",
            curves.to_str().unwrap(),
            dir.join("plain.json").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no \"noise\" section"));
    let cases = [
        (
            r#"{"kind": "van_der_pol", "beta": 30}"#,
            r#"{"amplitudes": [0.1]}"#,
            "analyses[0].noise.amplitudes",
            "give 2",
        ),
        (
            r#"{"kind": "van_der_pol", "beta": 30, "a": 1.5}"#,
            r#"{"amplitudes": [0.1, 0.1]}"#,
            "model.a",
            "< 1",
        ),
        (r#"{"kind": "saddle_node", "mu0": 1}"#, r#"{"amplitudes": [0.1]}"#, "model.r", "missing"),
        (
            r#"{"kind": "saddle_node", "mu0": 1, "r": 0.01}"#,
            r#"{"amplitudes": [0.1], "event_level": 0.5}"#,
            "analyses[0].noise.event_level",
            "< 0",
        ),
        (
            r#"{"kind": "saddle_node", "mu0": 1, "r": 0.01}"#,
            r#"{"amplitudes": [0.1], "window": [1, 2]}"#,
            "analyses[0].noise.window",
            "from > to",
        ),
        (
            r#"{"kind": "saddle_node", "mu0": 1, "r": 0.01, "gamma": 3}"#,
            r#"{"amplitudes": [0.1]}"#,
            "model.gamma",
            "takes no",
        ),
        (r#"{"kind": "pendulum"}"#, r#"{"amplitudes": [0.1]}"#, "model.kind", "saddle_node"),
        (
            r#"{"gamma": 1e3, "xi": 0.7, "epsilon": 0.72}"#,
            r#"{"amplitudes": [0.1, 2e6, 0.1]}"#,
            "analyses[0].noise.amplitudes[1]",
            "below γ²",
        ),
        (
            r#"{"gamma": 1e3, "xi": 0.7, "epsilon": 0.72}"#,
            r#"{"amplitudes": [0.1, 1, 0.1], "alignment": "sideways"}"#,
            "analyses[0].noise.alignment",
            "own_event",
        ),
        (
            r#"{"gamma": 1e3, "xi": 0.7, "epsilon": 0.72, "beta": 3}"#,
            r#"{"amplitudes": [0.1, 1, 0.1]}"#,
            "model.beta",
            "takes no",
        ),
    ];
    for (model, noise, field, hint) in cases {
        let text =
            format!(r#"{{"name": "t", "model": {model}, "analyses": [{{"noise": {noise}}}]}}"#);
        let e = scene::parse_any(&text, "test").expect_err(&text);
        assert_eq!(e.field, field, "{e}");
        assert!(e.message.contains(hint), "{e} should mention {hint}");
    }
    // Below the Hopf threshold there is no event: a typed error, exit 1.
    let stable = dir.join("stable.json");
    std::fs::write(&stable, r#"{"name": "t", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.5}, "analyses": [{"noise": {"amplitudes": [0.1, 1, 0.1], "realisations": 2}}]}"#).unwrap();
    let out =
        std::process::Command::new(exe).args(["run", stable.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("fixed point is stable"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Sweeps refuse the noise analysis (its ensembles use every core for one point).
    let base: serde_json::Value = serde_json::from_str(r#"{"name": "t", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.72}, "analyses": ["hopf", {"noise": {"amplitudes": [0.1, 1, 0.1]}}]}"#).unwrap();
    let e = stickslip::sweep::check_base(
        &base,
        &[stickslip::sweep::parse_axis("gamma=1e2:1e3:2:log").unwrap()],
    )
    .unwrap_err();
    assert_eq!(e, stickslip::sweep::SweepError::Noise);
    assert!(e.to_string().contains("noise"), "{e}");
    // Other commands take DRR scenes only, and say so.
    let e = scene::parse(r#"{"name": "t", "model": {"kind": "saddle_node", "mu0": 1, "r": 0.01}, "analyses": [{"noise": {"amplitudes": [0.1]}}]}"#, "test").unwrap_err();
    assert_eq!(e.field, "model.kind");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, r#"{"name": "t", "model": {"kind": "saddle_node", "mu0": 1}, "analyses": [{"noise": {"amplitudes": [0.1]}}]}"#).unwrap();
    let out =
        std::process::Command::new(exe).args(["run", bad.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}
