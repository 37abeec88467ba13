//! A user's crate: the six small problems of the stiff test set built through
//! `solver::build` with `MethodSettings::default()`, the one path users and the test set take,
//! by every stiff method at rtol 1e-4, 1e-7 and 1e-10 (108 cells). Every cell must succeed
//! with at least −log10(rtol) − 3 mixed-error significant correct digits: no typed error is
//! accepted, and no success far off (issue #28, "The library").

use crate::e5::E5;
use crate::hires::Hires;
use crate::orego::Orego;
use crate::pollu::Pollu;
use crate::problem::{run, scd_of, AllImplicit, TestProblem};
use crate::rober::Rober;
use crate::vdpol::Vdpol;
use crate::RTOLS;
use stickslip_ode::integrate::{Integrator, Options, Task, Tolerance};
use stickslip_ode::solver::{self, Method, MethodSettings};

/// The cells of `P` with `method` that miss the bound, as lines naming them.
fn misses<P: TestProblem>(method: Method) -> Vec<String> {
    let mut misses = Vec::new();
    for rtol in RTOLS {
        let minimum = -rtol.log10() - 3.0;
        match run::<P>(method, rtol) {
            Ok(r) => {
                let scd = scd_of::<P>(&r.y, rtol);
                if scd < minimum {
                    misses.push(format!(
                        "{} {method} rtol {rtol:e}: scd {scd:.2} < {minimum} ({} steps)",
                        P::NAME,
                        r.stats.steps
                    ));
                }
            }
            Err(e) => misses.push(format!("{} {method} rtol {rtol:e}: {e}", P::NAME)),
        }
    }
    misses
}

/// Every problem with `method`; panics with the cells that missed.
fn check(method: Method) {
    let mut all = Vec::new();
    all.extend(misses::<Hires>(method));
    all.extend(misses::<Orego>(method));
    all.extend(misses::<Rober>(method));
    all.extend(misses::<E5>(method));
    all.extend(misses::<Pollu>(method));
    all.extend(misses::<Vdpol>(method));
    assert!(all.is_empty(), "{} cells off:\n{}", all.len(), all.join("\n"));
}

#[test]
fn a_users_crate_with_cvode_bdf() {
    check(Method::CvodeBdf);
}

#[test]
fn a_users_crate_with_arkode_dirk() {
    check(Method::ArkodeDirk);
}

#[test]
fn a_users_crate_with_arkode_imex() {
    check(Method::ArkodeImex);
}

#[test]
fn a_users_crate_with_radau5() {
    check(Method::Radau5);
}

#[test]
fn a_users_crate_with_rodas5p() {
    check(Method::Rodas5p);
}

#[test]
fn a_users_crate_with_extrapolation() {
    check(Method::Extrapolation);
}

/// Every stiff method is in the cells above.
#[test]
fn the_cells_cover_every_stiff_method() {
    let stiff: Vec<Method> = Method::ALL.iter().map(|(_, m)| *m).filter(|m| m.is_stiff()).collect();
    assert_eq!(
        stiff,
        [
            Method::CvodeBdf,
            Method::ArkodeDirk,
            Method::ArkodeImex,
            Method::Radau5,
            Method::Rodas5p,
            Method::Extrapolation
        ]
    );
}

/// The scd of each cell of `P` with `method`, or its error.
fn row<P: TestProblem>(method: Method) -> String {
    let cells: Vec<String> = RTOLS
        .iter()
        .map(|&rtol| match run::<P>(method, rtol) {
            Ok(r) => format!("{:.2} ({} steps)", scd_of::<P>(&r.y, rtol), r.stats.steps),
            Err(e) => format!("{:?}", e.kind),
        })
        .collect();
    format!("| {} | {method} | {} |", P::NAME, cells.join(" | "))
}

/// Prints the 108 cells' digits (docs/test-set.md, "Through solver::build"):
/// `cargo test --release -p stickslip-ode --test test_set -- --ignored --nocapture print_library_cells`.
#[test]
#[ignore = "prints the table; run with --ignored --nocapture"]
fn print_library_cells() {
    println!("| problem | method | rtol 1e-4 | 1e-7 | 1e-10 |");
    println!("|---|---|---|---|---|");
    for (_, method) in Method::ALL.into_iter().filter(|(_, m)| m.is_stiff()) {
        println!("{}", row::<Hires>(method));
        println!("{}", row::<Orego>(method));
        println!("{}", row::<Rober>(method));
        println!("{}", row::<E5>(method));
        println!("{}", row::<Pollu>(method));
        println!("{}", row::<Vdpol>(method));
    }
}

/// The scd of `P` by `method` at `rtol` in one `advance(T_END)` call without a stop time: the
/// one-step methods step past T_END and interpolate back.
fn without_stop_time<P: TestProblem>(method: Method, rtol: f64) -> f64 {
    let options = Options::new(rtol, Tolerance::Scalar(P::atol(rtol)));
    let system = AllImplicit(P::new());
    let built = solver::build(method, &MethodSettings::default(), system, 0.0, &P::y0(), &options);
    let mut integ: Box<dyn Integrator> = built.unwrap().integrator;
    integ.advance(P::T_END, Task::Normal).unwrap();
    scd_of::<P>(integ.state(), rtol)
}

/// Prints what a run without the stop time loses (docs/library.md, "Integrate"):
/// `cargo test --release -p stickslip-ode --test test_set -- --ignored --nocapture print_without_stop_time`.
#[test]
#[ignore = "prints the table; run with --ignored --nocapture"]
fn print_without_stop_time() {
    for method in [Method::Radau5, Method::Rodas5p, Method::Extrapolation, Method::CvodeBdf] {
        for rtol in RTOLS {
            let with = |scd: f64| format!("{scd:.2}");
            let rober = (
                run::<Rober>(method, rtol).map(|r| scd_of::<Rober>(&r.y, rtol)).unwrap(),
                without_stop_time::<Rober>(method, rtol),
            );
            let vdpol = (
                run::<Vdpol>(method, rtol).map(|r| scd_of::<Vdpol>(&r.y, rtol)).unwrap(),
                without_stop_time::<Vdpol>(method, rtol),
            );
            println!(
                "| {method} | {rtol:.0e} | ROBER {} → {} | VDPOL {} → {} |",
                with(rober.0),
                with(rober.1),
                with(vdpol.0),
                with(vdpol.1)
            );
        }
    }
}
