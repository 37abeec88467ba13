//! A user's crate: the six small problems of the stiff test set built through
//! `solver::build` with `MethodSettings::default()`, the one path users and the test set take,
//! by every stiff method at rtol 1e-4, 1e-7 and 1e-10 (108 cells). Every cell must succeed
//! with at least −log10(rtol) − 3 mixed-error significant correct digits: no typed error is
//! accepted, and no success far off (issue #28, "The library").

use crate::e5::E5;
use crate::hires::Hires;
use crate::orego::Orego;
use crate::pollu::Pollu;
use crate::problem::{run, scd_of, TestProblem};
use crate::rober::Rober;
use crate::vdpol::Vdpol;
use crate::RTOLS;
use stickslip::solver::Method;

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
