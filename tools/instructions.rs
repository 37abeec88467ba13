//! The test-set cases of the instruction-count guard (tools/instructions.sh,
//! docs/benchmarks.md): `instructions CASE` runs one method on one problem of the Test Set for
//! IVP Solvers (the problems of crates/ode/tests/test_set/, compiled in from there) at rtol
//! 1e-7 and prints the mixed-error significant correct digits, so that a run which stops
//! converging shows. The scene cases of the guard run the `stickslip` binary itself.
//!
//! Cases: hires-radau5, hires-rodas5p, orego-radau5, orego-rodas5p.

#[allow(dead_code)]
#[path = "../crates/ode/tests/test_set/hires.rs"]
mod hires;
#[allow(dead_code)]
#[path = "../crates/ode/tests/test_set/orego.rs"]
mod orego;
#[allow(dead_code)]
#[path = "../crates/ode/tests/test_set/problem.rs"]
mod problem;

use problem::{run, scd_of, TestProblem};
use stickslip::solver::Method;

/// Relative tolerance of every case (the test set's middle one).
const RTOL: f64 = 1e-7;

/// Runs `P` with `method` and prints its steps and digits; exit code 1 on a solver error.
fn case<P: TestProblem>(method: Method) -> i32 {
    match run::<P>(method, RTOL) {
        Ok(r) => {
            println!(
                "{} {}: {} steps, scd {:.2}",
                P::NAME,
                method.name(),
                r.stats.steps,
                scd_of::<P>(&r.y, RTOL)
            );
            0
        }
        Err(e) => {
            eprintln!("{} {}: {e}", P::NAME, method.name());
            1
        }
    }
}

fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    let code = match name.as_str() {
        "hires-radau5" => case::<hires::Hires>(Method::Radau5),
        "hires-rodas5p" => case::<hires::Hires>(Method::Rodas5p),
        "orego-radau5" => case::<orego::Orego>(Method::Radau5),
        "orego-rodas5p" => case::<orego::Orego>(Method::Rodas5p),
        _ => {
            eprintln!(
                "instructions: unknown case '{name}'; give one of hires-radau5, hires-rodas5p, \
                 orego-radau5, orego-rodas5p"
            );
            2
        }
    };
    std::process::exit(code);
}
