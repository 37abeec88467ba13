//! `stickslip robertson`: SUNDIALS' Robertson examples replayed through the safe wrappers.

use super::Failure;
use stickslip::robertson::examples::{self as robertson, ExampleRun};
use stickslip::sundials;

fn print_stats(run: &ExampleRun) {
    let s = &run.stats;
    println!(
        "  steps {} (attempted {}), RHS evals {} (+{} explicit, +{} for FD Jacobians), Jacobian evals {},\n  \
         linear setups {}, error-test fails {}, Newton iterations {} (convergence fails {}), root evals {},\n  \
         last step {:e}, last order {}, t + h = t warnings {}",
        s.steps,
        s.step_attempts,
        s.rhs_evals,
        s.rhs_evals_explicit,
        s.rhs_evals_jacobian,
        s.jac_evals,
        s.lin_setups,
        s.err_test_fails,
        s.nonlin_iters,
        s.nonlin_conv_fails,
        s.root_evals,
        s.last_step,
        s.last_order,
        s.step_underflow_warnings
    );
}

/// Runs `stickslip robertson`: SUNDIALS' Robertson examples through the wrappers.
pub fn robertson_command() -> Result<(), Failure> {
    println!("SUNDIALS {} (linked at run time)\n", sundials::version());
    let cvode = robertson::cvode_example().map_err(|e| Failure(1, e.to_string()))?;
    println!(
        "cvRoberts_dns through stickslip's CVODE wrapper (BDF, rtol 1e-4, analytic Jacobian):"
    );
    for line in robertson::format_cvode_rows(&cvode.rows) {
        println!("{line}");
    }
    print_stats(&cvode);
    let arkode = robertson::arkode_example().map_err(|e| Failure(1, e.to_string()))?;
    println!(
        "\nark_robertson_root through stickslip's ARKStep wrapper (DIRK SDIRK_5_3_4, rtol 1e-4):"
    );
    for line in robertson::format_arkode_rows(&arkode.rows) {
        println!("{line}");
    }
    print_stats(&arkode);
    Ok(())
}
