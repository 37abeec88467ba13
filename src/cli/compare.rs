//! `stickslip compare`: methods against each other, or a user's trajectory or report against
//! a reference.

use super::{print_json, read_scene, Failure};
use std::path::PathBuf;
use stickslip::{compare, scene};

/// Runs `stickslip compare`: `--methods` against each other, or `--against` a user's file.
pub fn compare_command(
    path: PathBuf,
    methods: Vec<scene::Method>,
    against: Option<PathBuf>,
    tolerance: f64,
    reference_method: Option<scene::Method>,
    json: bool,
) -> Result<(), Failure> {
    let scene = read_scene(&path)?;
    if !scene.params.state_law.heals() {
        return Err(Failure(2, format!("scene {}: model.state_law: compare compares cycles and their events; the no-healing law (\"no_healing\") has none, its block runs away: run the scene (its report's runaway section gives the time v reaches the threshold), once per solver.method to compare methods", path.display())));
    }
    if scene.loading.is_some() {
        return Err(Failure(2, format!("{}: compare runs the unforced model (its methods' cycles, or a reference trajectory), and this scene is periodically loaded (model.periodic_loading or model.dimensional.periodic_loading); run it with `stickslip run` (time_series: the event catalogue and the locking to the forcing), or drop the loading", path.display())));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Failure(2, format!("--tolerance {tolerance} must be a finite number > 0")));
    }
    match against {
        Some(file) => compare_against(&scene, &file, tolerance, reference_method, json),
        None => compare_methods(&scene, &methods, json),
    }
}

/// `compare --against FILE`: a user's trajectory or report against our reference (exit 3 if
/// it disagrees).
fn compare_against(
    scene: &scene::Scene,
    file: &std::path::Path,
    tolerance: f64,
    reference_method: Option<scene::Method>,
    json: bool,
) -> Result<(), Failure> {
    let cannot = |e: std::io::Error| Failure(2, format!("cannot read {}: {e}", file.display()));
    let size = std::fs::metadata(file).map_err(cannot)?.len();
    if size > compare::input::MAX_FILE_BYTES {
        return Err(Failure(2, format!("{}: {size} bytes; at most {} are compared at once: compare a shorter stretch, or every k-th sample", file.display(), compare::input::MAX_FILE_BYTES)));
    }
    let text = std::fs::read_to_string(file).map_err(cannot)?;
    let named = |e: &dyn std::fmt::Display| Failure(2, format!("{}: {e}", file.display()));
    let data = compare::read_user_data(&text).map_err(|e| named(&e))?;
    drop(text);
    let verdict = match data {
        compare::UserData::Trajectory(t) => {
            trajectory_verdict(scene, &t, tolerance, reference_method, json, &named)?
        }
        compare::UserData::Qdyn(q) => {
            qdyn_notes(file, &q);
            let t = compare::qdyn::to_trajectory(scene, &q).map_err(|e| named(&e))?;
            trajectory_verdict(scene, &t, tolerance, reference_method, json, &named)?
        }
        compare::UserData::Report(r) => {
            let c = compare::against_report(scene, &r, tolerance, reference_method)
                .map_err(|e| Failure(1, e.to_string()))?;
            if json {
                print_json(&c);
            } else {
                let r = &c.reference;
                println!(
                    "reference: {} at rtol {:.0e}, checked by {} at rtol {:.0e}",
                    r.method, r.rtol, r.check_method, r.check_rtol
                );
                for row in &c.rows {
                    let flag = if row.beyond_tolerance { "  BEYOND TOLERANCE" } else { "" };
                    println!(
                        "{:<16} yours {:<22} ours {:<22} {:.1e} (ours ±{:.0e}){flag}",
                        row.quantity,
                        row.user,
                        row.reference,
                        row.deviation,
                        row.reference_accuracy
                    );
                }
            }
            c.verdict
        }
    };
    if !json {
        println!(
            "verdict: {} (tolerance {tolerance:.1e})",
            if verdict == compare::Verdict::Agrees { "agrees" } else { "disagrees" }
        );
    }
    match verdict {
        compare::Verdict::Agrees => Ok(()),
        compare::Verdict::Disagrees => Err(Failure(
            3,
            format!(
                "{} disagrees with the reference beyond the tolerance {tolerance:e}",
                file.display()
            ),
        )),
    }
}

/// What was done to a QDYN file before it is compared, on stderr: which file it is, and the
/// rows left out (a repeated last row, rows that print the same time).
fn qdyn_notes(file: &std::path::Path, q: &compare::qdyn::QdynOutput) {
    let name = file.display();
    if q.file == compare::qdyn::QdynFile::Vmax {
        eprintln!("note: {name} is QDYN's output_vmax (the state at the velocity maximum): for a spring-block its one element, the same time series as output_ot_0");
    }
    if let Some(line) = &q.repeated_last {
        eprintln!("note: {name}: {line}, the last row, repeats the row before it at a later time (QDYN writes its last state again at TMAX when its solver stops); it is left out");
    }
    let tied = &q.tied;
    if let Some(first) = &tied.first {
        eprintln!(
            "note: {name}: {} rows left out: {} runs of rows print the same time (QDYN prints t with 14 digits, coarser than its fastest steps late in a run; the first at {first}); of each run the middle row is kept (docs/compare.md)",
            tied.rows_left_out, tied.runs
        );
    }
}

/// A trajectory against the reference: prints the comparison and returns its verdict.
fn trajectory_verdict(
    scene: &scene::Scene,
    t: &compare::Trajectory,
    tolerance: f64,
    reference_method: Option<scene::Method>,
    json: bool,
    named: &dyn Fn(&dyn std::fmt::Display) -> Failure,
) -> Result<compare::Verdict, Failure> {
    if reference_method.is_some() {
        return Err(Failure(
            2,
            "--reference-method applies to a report; a trajectory's reference is radau5 \
             checked by rodas5p (docs/compare.md)"
                .into(),
        ));
    }
    let c = compare::against_trajectory(scene, t, tolerance).map_err(|e| match e {
        e @ (compare::CompareError::Input(_)
        | compare::CompareError::UnresolvedReference(_)
        | compare::CompareError::Mismatch(_)) => named(&e),
        other => Failure(1, other.to_string()),
    })?;
    if json {
        print_json(&c);
    } else {
        print_trajectory_comparison(&c);
    }
    Ok(c.verdict)
}

/// The summary of a trajectory comparison.
fn print_trajectory_comparison(c: &compare::TrajectoryComparison) {
    println!(
        "{} samples; complete events: {} yours, {} the reference's, {} compared",
        c.samples, c.events[0], c.events[1], c.events[2]
    );
    let r = &c.reference;
    let accuracy: Vec<String> = r.accuracy.iter().map(|(q, a)| format!("{q} {a:.1e}")).collect();
    println!(
        "reference: radau5, rtol {:.0e}, re-based {} times; its own accuracy (against rodas5p at rtol {:.0e}): {}",
        r.rtol,
        r.rebases,
        r.check_rtol,
        accuracy.join(", ")
    );
    for q in &c.worst_per_quantity {
        println!(
            "{:<12} worst at event {:<4} yours {:<22} reference {:<22} {:.2e}",
            q.quantity, q.event, q.user, q.reference, q.deviation
        );
    }
    let m = &c.max_state_deviation;
    let u = m.u.map_or("- (from the force balance)".into(), |u| format!("{u:.2e}"));
    println!(
        "state between events ({} samples, in phase): max deviation u {u}, ln v {:.2e}, θ {:.2e}",
        c.state_samples, m.ln_v, m.theta
    );
    if let Some(w) = &c.worst_state {
        println!(
            "worst: {} at t = {} ({}, {} from the peak of event {}): yours {}, reference {}",
            w.quantity, w.t, w.at, w.phase, w.event, w.user, w.reference
        );
    }
    for reason in &c.reasons {
        println!("DISAGREES: {reason}");
    }
}

/// `compare --methods a,b,…`: the scene's cycle by several methods.
fn compare_methods(
    scene: &scene::Scene,
    methods: &[scene::Method],
    json: bool,
) -> Result<(), Failure> {
    if methods.is_empty() {
        return Err(Failure(2, "give --methods a,b,... or --against FILE".into()));
    }
    let c = compare::methods(scene, methods);
    if json {
        print_json(&c);
    } else {
        for ((m, status), (_, time)) in c.runs.iter().zip(&c.wall_time_s) {
            println!("{m:<12} {status} ({})", time.map_or("-".into(), |t| format!("{:.3} s", t)));
        }
        for row in &c.rows {
            let values: Vec<String> = row
                .values
                .iter()
                .map(|(m, v)| format!("{m}={}", v.map_or("-".into(), |v| format!("{v:.12}"))))
                .collect();
            let flag = if row.outliers.is_empty() {
                String::new()
            } else {
                format!("  OUTLIERS: {}", row.outliers.join(", "))
            };
            println!(
                "{:<16} spread {:<9} (allowed {:.0e}) {}{flag}",
                row.quantity,
                row.spread.map_or("-".into(), |s| format!("{s:.1e}")),
                row.allowed,
                values.join("  ")
            );
        }
    }
    Ok(())
}
