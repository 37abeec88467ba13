//! The `stickslip` command line. Subcommands are thin: parse, call the library, print.
//! Exit codes: 0 success, 1 failed computation, 2 bad input.

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use stickslip::model::robertson::{self, ExampleRun};
use stickslip::sundials;

#[derive(Parser)]
#[command(name = "stickslip", version, about = "Very stiff stick-slip dynamics with Debian's SUNDIALS")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Replay SUNDIALS' Robertson examples (cvRoberts_dns, ark_robertson_root) through the
    /// safe wrappers and print them as the C programs do, with solver statistics.
    Robertson,
    /// Print the SUNDIALS version linked at run time.
    Version,
}

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

fn robertson_command() -> Result<(), String> {
    println!("SUNDIALS {} (linked at run time)\n", sundials::version());
    let cvode = robertson::cvode_example().map_err(|e| e.to_string())?;
    println!("cvRoberts_dns through stickslip's CVODE wrapper (BDF, rtol 1e-4, analytic Jacobian):");
    for line in robertson::format_cvode_rows(&cvode.rows) {
        println!("{line}");
    }
    print_stats(&cvode);
    let arkode = robertson::arkode_example().map_err(|e| e.to_string())?;
    println!("\nark_robertson_root through stickslip's ARKStep wrapper (DIRK SDIRK_5_3_4, rtol 1e-4):");
    for line in robertson::format_arkode_rows(&arkode.rows) {
        println!("{line}");
    }
    print_stats(&arkode);
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Robertson => robertson_command(),
        Command::Version => {
            println!("stickslip {} with SUNDIALS {}", env!("CARGO_PKG_VERSION"), sundials::version());
            Ok(())
        }
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("stickslip: {message}");
            ExitCode::from(1)
        }
    }
}
