//! `Options::error_scales` in the homemade methods (Radau5, Rodas5P, Extrapolation): a
//! component that is a logarithm of size about 20, weighed absolutely, is integrated more
//! accurately than when weighed relative to its size; and scales that are all relative give
//! the same integration, bit for bit, as no scales.

use stickslip_ode::integrate::{
    ErrorScale, Extrapolation, Integrator, OdeSystem, Options, Radau5, Rodas5p, Task, Tolerance,
};

/// Logistic growth written for w = ln x: w' = 1 − e^(w − 20), from w(0) = 19 towards 20.
struct LogLogistic;

impl OdeSystem for LogLogistic {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = 1.0 - (y[0] - 20.0).exp();
    }
}

/// The exact w(t) = 20 − ln(1 + (e − 1)·e^(−t)).
fn exact_w(t: f64) -> f64 {
    20.0 - (1.0 + (1f64.exp() - 1.0) * (-t).exp()).ln()
}

const Y0: [f64; 1] = [19.0];
const RTOL: f64 = 1e-6;

/// The three homemade methods on `LogLogistic` with `options`.
fn integrators(options: &Options) -> Vec<(&'static str, Box<dyn Integrator>)> {
    vec![
        ("radau5", Box::new(Radau5::new(LogLogistic, 0.0, &Y0, options).unwrap())),
        ("rodas5p", Box::new(Rodas5p::new(LogLogistic, 0.0, &Y0, options).unwrap())),
        ("extrapolation", Box::new(Extrapolation::new(LogLogistic, 0.0, &Y0, options).unwrap())),
    ]
}

fn options(scales: Option<Vec<ErrorScale>>) -> Options {
    Options { error_scales: scales, ..Options::new(RTOL, Tolerance::Scalar(1e-12)) }
}

/// The largest error in w over the outputs t = 0.5, 1, …, 10, with the states at the outputs.
fn advance_to_10(solver: &mut dyn Integrator) -> (f64, Vec<f64>) {
    let (mut worst, mut states) = (0.0f64, Vec::new());
    for k in 1..=20 {
        let t = 0.5 * k as f64;
        solver.advance(t, Task::Normal).unwrap();
        worst = worst.max((solver.state()[0] - exact_w(t)).abs());
        states.extend_from_slice(solver.state());
    }
    (worst, states)
}

#[test]
fn an_absolute_scale_on_a_logarithm_tightens_its_error() {
    let relative = integrators(&options(None));
    let absolute = integrators(&options(Some(vec![ErrorScale::Absolute(1.0)])));
    for ((name, mut rel), (_, mut abs)) in relative.into_iter().zip(absolute) {
        let (err_rel, _) = advance_to_10(rel.as_mut());
        let (err_abs, _) = advance_to_10(abs.as_mut());
        // w ≈ 20: the relative weight allows 20·rtol, the absolute one rtol.
        assert!(
            err_abs < err_rel / 3.0,
            "{name}: error in w {err_abs:e} with Absolute(1), {err_rel:e} relative"
        );
    }
}

#[test]
fn relative_scales_everywhere_are_no_scales() {
    let none = integrators(&options(None));
    let relative = integrators(&options(Some(vec![ErrorScale::Relative])));
    for ((name, mut a), (_, mut b)) in none.into_iter().zip(relative) {
        let (_, states_a) = advance_to_10(a.as_mut());
        let (_, states_b) = advance_to_10(b.as_mut());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&states_a), bits(&states_b), "{name}");
        assert_eq!(a.stats(), b.stats(), "{name}");
    }
}
