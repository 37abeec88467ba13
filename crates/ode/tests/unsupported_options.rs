//! Options a method does not have are typed InvalidInput errors naming the option (never
//! silently ignored), and the default step budget lets a whole stiff integration finish in one
//! `advance` call for every stiff method.

use stickslip_ode::integrate::{
    ErrorKind, Extrapolation, Integrator, Options, Radau5, Rodas5p, SolverError, Task, Tolerance,
};
use stickslip_ode::sundials::{ArkMethod, ArkSettings, CvodeSettings, Solver};

mod common;
use common::VanDerPol;

fn rejects(result: Result<impl Sized, SolverError>, option: &str) {
    match result {
        Ok(_) => panic!("{option} must be rejected"),
        Err(e) => {
            assert_eq!(e.kind, ErrorKind::InvalidInput, "{e}");
            assert!(e.message.contains(option), "the message must name {option}: {e}");
        }
    }
}

#[test]
fn options_a_method_does_not_have_are_errors() {
    let base = Options::new(1e-6, Tolerance::Scalar(1e-6));
    let y0 = [2.0, 0.0];
    let with = |f: fn(&mut Options)| {
        let mut o = base.clone();
        f(&mut o);
        o
    };
    let max_order = with(|o| o.max_order = Some(3));
    rejects(Radau5::new(VanDerPol(1e-3), 0.0, &y0, &max_order), "max_order");
    rejects(Rodas5p::new(VanDerPol(1e-3), 0.0, &y0, &max_order), "max_order");
    rejects(Extrapolation::new(VanDerPol(1e-3), 0.0, &y0, &max_order), "max_order");
    for (name, options) in [
        ("max_nonlin_iters", with(|o| o.max_nonlin_iters = Some(4))),
        ("max_conv_fails", with(|o| o.max_conv_fails = Some(4))),
        ("nonlin_conv_coef", with(|o| o.nonlin_conv_coef = Some(0.1))),
    ] {
        rejects(Rodas5p::new(VanDerPol(1e-3), 0.0, &y0, &options), name);
    }
    for (name, options) in [
        ("max_nonlin_iters", with(|o| o.max_nonlin_iters = Some(4))),
        ("nonlin_conv_coef", with(|o| o.nonlin_conv_coef = Some(0.1))),
    ] {
        rejects(Extrapolation::new(VanDerPol(1e-3), 0.0, &y0, &options), name);
    }
    // What each method does have is accepted.
    assert!(Extrapolation::new(VanDerPol(1e-3), 0.0, &y0, &with(|o| o.max_order = Some(8))).is_ok());
    assert!(
        Radau5::new(VanDerPol(1e-3), 0.0, &y0, &with(|o| o.max_nonlin_iters = Some(10))).is_ok()
    );
}

/// VDPOL (ε = 1e-6) to t = 2 at rtol 1e-8 in one call: thousands of steps, more than SUNDIALS'
/// own budget of 500 per call, within the default; an explicit budget still applies.
#[test]
fn the_default_step_budget_finishes_a_whole_stiff_integration() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-8));
    let y0 = [2.0, 0.0];
    let system = || VanDerPol(1e-6);
    let mut solvers: Vec<Box<dyn Integrator>> = vec![
        Box::new(Solver::cvode(system(), CvodeSettings::default(), 0.0, &y0, &options).unwrap()),
        Box::new(
            Solver::arkstep(
                system(),
                ArkMethod::default(),
                ArkSettings::default(),
                0.0,
                &y0,
                &options,
            )
            .unwrap(),
        ),
        Box::new(Radau5::new(system(), 0.0, &y0, &options).unwrap()),
        Box::new(Rodas5p::new(system(), 0.0, &y0, &options).unwrap()),
        Box::new(Extrapolation::new(system(), 0.0, &y0, &options).unwrap()),
    ];
    for solver in &mut solvers {
        solver.advance(2.0, Task::Normal).unwrap_or_else(|e| panic!("{}: {e}", solver.name()));
        let reference = [0.1706167732170483e1, -0.8928097010247975e0];
        let error = (solver.state()[0] - reference[0]).abs() / reference[0].abs();
        assert!(
            error < 1e-5,
            "{}: y1 = {} against the Test Set's {}",
            solver.name(),
            solver.state()[0],
            reference[0]
        );
    }
    // CVODE, Radau5 and Rodas5P take more than SUNDIALS' 500 steps.
    for solver in &solvers[..4] {
        if solver.name() != "arkode-dirk" {
            assert!(
                solver.stats().steps > 500,
                "{}: {} steps",
                solver.name(),
                solver.stats().steps
            );
        }
    }
    let limited = Options { max_steps: Some(500), ..options };
    let mut radau = Radau5::new(system(), 0.0, &y0, &limited).unwrap();
    let error = radau.advance(2.0, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::TooMuchWork, "{error}");
}
