//! Peer Rust ODE solvers on stickslip's work-precision problem (tools/work_precision): the
//! crates a user would pick instead — diffsol (BDF, ESDIRK34, TR-BDF2) and
//! differential-equations (Radau5, BDF) — each with its defaults, or with the least tuning
//! that makes it run ("tuned", stated in the output).
//!
//! Usage:
//!
//!     stickslip-peers METHOD SETTING GAMMA XI EPSILON RTOL ATOL U0 W0 THETA0 T_END CYCLES RUNS BUDGET_S
//!
//! METHOD: diffsol-bdf, diffsol-esdirk34, diffsol-tr-bdf2, de-radau5, de-bdf; SETTING: default
//! or tuned. Integrates the DRR spring-slider in (u, w = ln v, θ) from (U0, W0, THETA0) at
//! t = 0 to T_END with rtol RTOL and atol ATOL on every component, and measures the first
//! CYCLES cycles (src/meter.rs). One untimed warm-up run, then up to RUNS timed runs, stopping
//! once they add up to BUDGET_S seconds (a warm-up longer than that is the only, timed, run).
//! Prints one JSON line: the means over the cycles of the period, t0 and ln v_max, the minimum
//! time per cycle and the counters of one run, or `"ok": false` with the failure's reason
//! (solver errors and panics alike). Exit status 64 on bad usage.

mod de_peer;
mod diffsol_peer;
mod meter;
mod model;

use serde_json::json;
use std::time::Instant;

/// Defaults, or the least tuning that makes the method run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    /// The crate's defaults (tolerances apart).
    Default,
    /// The stated tuning.
    Tuned,
}

/// One benchmark run's problem.
#[derive(Debug, Clone, Copy)]
pub struct Run {
    drr: model::Drr,
    rtol: f64,
    atol: f64,
    y0: [f64; 3],
    t_end: f64,
    cycles: usize,
}

/// Work counters of one run; None where the crate does not count.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counts {
    steps: Option<u64>,
    rhs: Option<u64>,
    jac: Option<u64>,
    lu: Option<u64>,
    rejected: Option<u64>,
}

const METHODS: [&str; 5] =
    ["diffsol-bdf", "diffsol-esdirk34", "diffsol-tr-bdf2", "de-radau5", "de-bdf"];

/// What the tuned setting of a method changes.
fn tuning(method: &str) -> String {
    if method.starts_with("diffsol") {
        format!(
            "min_timestep {:e} (default 1e-13), max_error_test_failures and max_nonlinear_solver_failures {} (defaults 40, 50)",
            diffsol_peer::TUNED_MIN_TIMESTEP,
            diffsol_peer::TUNED_MAX_FAILURES
        )
    } else {
        format!(
            "max_steps {:e} (default 1e5 for radau5, 1e4 for BDF)",
            de_peer::TUNED_MAX_STEPS as f64
        )
    }
}

fn run_one(method: &str, setting: Setting, run: &Run) -> Result<(meter::Measured, Counts), String> {
    let attempt = std::panic::catch_unwind(|| match method {
        "diffsol-bdf" => diffsol_peer::run(diffsol_peer::Method::Bdf, setting, run),
        "diffsol-esdirk34" => diffsol_peer::run(diffsol_peer::Method::Esdirk34, setting, run),
        "diffsol-tr-bdf2" => diffsol_peer::run(diffsol_peer::Method::TrBdf2, setting, run),
        "de-radau5" => de_peer::run(de_peer::Method::Radau5, setting, run),
        "de-bdf" => de_peer::run(de_peer::Method::Bdf, setting, run),
        other => Err(format!("unknown method {other}")),
    });
    match attempt {
        Ok(result) => result,
        Err(payload) => {
            let what = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "(no message)".into());
            Err(format!("panic: {what}"))
        }
    }
}

fn usage() -> ! {
    eprintln!(
        "usage: stickslip-peers METHOD default|tuned GAMMA XI EPSILON RTOL ATOL U0 W0 THETA0 T_END CYCLES RUNS BUDGET_S\n\
         METHOD: {}",
        METHODS.join(", ")
    );
    std::process::exit(64);
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 14 || !METHODS.contains(&args[0].as_str()) {
        usage();
    }
    let method = args[0].as_str();
    let setting = match args[1].as_str() {
        "default" => Setting::Default,
        "tuned" => Setting::Tuned,
        _ => usage(),
    };
    let num = |i: usize| -> f64 {
        args[i].parse().ok().filter(|x: &f64| x.is_finite()).unwrap_or_else(|| usage())
    };
    let int =
        |i: usize| -> usize { args[i].parse().ok().filter(|&n| n >= 1).unwrap_or_else(|| usage()) };
    let (gamma, rtol, atol) = (num(2), num(5), num(6));
    let run = Run {
        drr: model::Drr::new(gamma, num(3), num(4)),
        rtol,
        atol,
        y0: [num(7), num(8), num(9)],
        t_end: num(10),
        cycles: int(11),
    };
    let (runs, budget) = (int(12), num(13));
    let mut line = json!({
        "method": method,
        "setting": if setting == Setting::Tuned { "tuned" } else { "default" },
        "gamma": gamma,
        "rtol": rtol,
        "atol": atol,
    });
    if setting == Setting::Tuned {
        line["tuning"] = json!(tuning(method));
    }
    // Silence the default panic message: a panic is reported in the JSON line.
    std::panic::set_hook(Box::new(|_| {}));
    let mut timed = Vec::new();
    let clock = Instant::now();
    let mut outcome = run_one(method, setting, &run);
    let warm_up = clock.elapsed().as_secs_f64();
    if outcome.is_ok() {
        if warm_up > budget {
            timed.push(warm_up);
        } else {
            while timed.len() < runs && timed.iter().sum::<f64>() < budget {
                let clock = Instant::now();
                outcome = run_one(method, setting, &run);
                timed.push(clock.elapsed().as_secs_f64());
                if outcome.is_err() {
                    break;
                }
            }
        }
    }
    match outcome {
        Ok((m, c)) => {
            let best = timed.iter().copied().fold(f64::INFINITY, f64::min);
            line["ok"] = json!(true);
            line["cycles"] = json!(run.cycles);
            line["period"] = json!(m.period);
            line["t0"] = json!(m.t0);
            line["ln_v_max"] = json!(m.ln_v_max);
            line["time_per_cycle_s"] = json!(best / run.cycles as f64);
            line["runs"] = json!(timed.len());
            line["steps"] = json!(c.steps);
            line["rhs"] = json!(c.rhs);
            line["jac"] = json!(c.jac);
            line["lu"] = json!(c.lu);
            line["rejected"] = json!(c.rejected);
        }
        Err(e) => {
            line["ok"] = json!(false);
            line["error"] = json!(e);
        }
    }
    println!("{line}");
}
