//! Cross-checking a scene across methods and a user's trajectory or report against the
//! reference.

use stickslip::compare::{self, UserData};
use stickslip::scene::{self, Method};

fn fig1() -> scene::Scene {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes/fig1.json")).unwrap();
    scene::parse(&text, "fig1").unwrap()
}

#[test]
fn methods_agree_on_fig1_and_the_table_flags_nothing() {
    let c = compare::methods(&fig1(), &[Method::CvodeBdf, Method::ArkodeDirk, Method::Radau5]);
    assert!(c.runs.iter().all(|(_, status)| status == "Periodic"), "{:?}", c.runs);
    let period = c.rows.iter().find(|r| r.quantity == "period").unwrap();
    assert!(period.spread.unwrap() < period.allowed && period.outliers.is_empty(), "{period:?}");
}

#[test]
fn a_failing_method_is_reported_not_averaged() {
    let mut s = fig1();
    s.analyses.cycle.as_mut().unwrap().max_steps = Some(5000);
    let c = compare::methods(&s, &[Method::CvodeBdf, Method::ArkodeErk]);
    assert!(c.runs[1].1.starts_with("error:"), "{:?}", c.runs);
    let period = c.rows.iter().find(|r| r.quantity == "period").unwrap();
    assert_eq!(period.values[1].1, None);
    assert_eq!(period.spread, None, "one value has no spread");
}

fn own_trajectory_csv() -> String {
    // Our own fig1 cycle (every step), written as a user would.
    let s = fig1();
    let report = stickslip::engine::run(&s, serde_json::Value::Null).unwrap();
    let c = report.cycle.unwrap();
    let t = c.trajectory.last().unwrap();
    let mut csv = String::from("# our own fig1 cycle\nt,u,v,theta\n");
    for i in (0..t.t.len()).step_by(7).take(200) {
        csv += &format!("{:e},{:e},{:e},{:e}\n", t.t[i], t.u[i], t.v[i], t.theta[i]);
    }
    csv
}

#[test]
fn an_accurate_user_trajectory_agrees_and_a_wrong_one_is_located() {
    let csv = own_trajectory_csv();
    let UserData::Trajectory(good) = compare::read_user_data(&csv).unwrap() else { panic!("a trajectory") };
    // Our rtol 1e-10 cycle against the rtol 1e-11 reference: within 1e-5 everywhere (the
    // largest gap, 8e-6 in ln v, is at the slip peak, where dw/dt turns phase into amplitude).
    let c = compare::against_trajectory(&fig1(), &good, 1e-5).unwrap();
    assert!(c.first_divergence.is_none(), "{c:?}");
    // Perturb θ by 1e-4 from the 100th sample on: the first divergence is found there.
    let mut bad = good.clone();
    for y in bad.y.iter_mut().skip(100) {
        y[2] += 1e-4;
    }
    let c = compare::against_trajectory(&fig1(), &bad, 1e-5).unwrap();
    let (t, quantity, _, _) = c.first_divergence.unwrap();
    assert_eq!(t, bad.t[100]);
    assert_eq!(quantity, "theta");
}

#[test]
fn user_files_are_validated() {
    assert!(compare::read_user_data("t,u,v\n0,1,1\n").unwrap_err().contains("theta"));
    assert!(compare::read_user_data("t,u,v,theta\n0,1,1,0\n1,1,x,0\n").unwrap_err().contains("line 3"));
    assert!(compare::read_user_data("t,u,v,theta\n1,1,1,0\n0,1,1,0\n").unwrap_err().contains("increase"));
    assert!(compare::read_user_data("t,u,v,theta\n0,1,-1,0\n1,1,1,0\n").unwrap_err().contains("v > 0"));
    let json = r#"{"t": [0, 1], "u": [0, 0.1], "v": [0.5, 0.6], "theta": [0, 0]}"#;
    assert!(matches!(compare::read_user_data(json).unwrap(), UserData::Trajectory(_)));
}

#[test]
fn a_user_report_is_checked_key_by_key() {
    let s = fig1();
    let ours = stickslip::engine::run(&s, serde_json::Value::Null).unwrap();
    let mut user: serde_json::Value = serde_json::from_str(&ours.to_json()).unwrap();
    user["cycle"]["period"] = serde_json::json!(18.1);
    let c = compare::against_report(&s, &user, 1e-6).unwrap();
    let beyond: Vec<&str> = c.rows.iter().filter(|r| r.4).map(|r| r.0.as_str()).collect();
    assert_eq!(beyond, vec!["period"]);
}
