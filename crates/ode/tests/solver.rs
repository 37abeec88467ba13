//! Solver selection (src/solver.rs): every method by name builds and integrates, Butcher
//! tables are named and checked, and the capability table agrees with what the integrators
//! accept.

use stickslip_ode::integrate::{
    ErrorKind, ErrorScale, Extrapolation, Options, Radau5, Rodas5p, Task, Tolerance,
    ToleranceTransform,
};
use stickslip_ode::solver::{build, build_ode, Method, MethodError, MethodSettings};

mod common;
use common::Decay;

/// The options of every build here.
fn options() -> Options {
    Options::new(1e-9, Tolerance::Scalar(1e-12))
}

#[test]
fn every_method_by_name_builds_and_integrates_the_decay() {
    for (name, method) in Method::ALL {
        assert_eq!(name.parse::<Method>(), Ok(method));
        assert_eq!(format!("{method}"), name);
        let mut integ =
            build(method, &MethodSettings::default(), Decay(1.0), 0.0, &[1.0], &options())
                .unwrap()
                .integrator;
        let step = integ.advance(1.0, Task::Normal).unwrap();
        assert_eq!(step.t, 1.0, "{name}");
        let error = (integ.state()[0] - (-1f64).exp()).abs();
        assert!(error < 1e-6, "{name}: error {error:e}");
    }
}

#[test]
fn a_bad_method_name_lists_the_valid_ones() {
    let error = "radau".parse::<Method>().unwrap_err();
    assert_eq!(error, MethodError::UnknownMethod { name: "radau".into() });
    let message = error.to_string();
    assert!(Method::ALL.iter().all(|(n, _)| message.contains(n)), "{message}");
}

#[test]
fn tables_are_named_and_checked() {
    let built =
        build(Method::ArkodeImex, &MethodSettings::default(), Decay(1.0), 0.0, &[1.0], &options())
            .unwrap();
    assert_eq!(built.tables.len(), 2);
    let table =
        |name: &str| MethodSettings { table: Some(name.into()), ..MethodSettings::default() };
    let error = |method, settings: MethodSettings| {
        build(method, &settings, Decay(1.0), 0.0, &[1.0], &options())
            .err()
            .map(|e| (e.kind, e.message))
    };
    let (kind, message) = error(Method::ArkodeDirk, table("NO_SUCH_TABLE")).unwrap();
    assert_eq!(kind, ErrorKind::InvalidInput);
    assert!(message.starts_with("table: unknown implicit table \"NO_SUCH_TABLE\""), "{message}");
    let (kind, message) = error(Method::Radau5, table("ARK436L2SA_DIRK_6_3_4")).unwrap();
    assert_eq!(kind, ErrorKind::InvalidInput);
    assert!(message.contains("radau5 takes no Butcher table"), "{message}");
    let explicit = MethodSettings {
        explicit_table: Some("ARK436L2SA_ERK_6_3_4".into()),
        ..MethodSettings::default()
    };
    assert_eq!(error(Method::ArkodeDirk, explicit).map(|e| e.0), Some(ErrorKind::InvalidInput));
    let pair = build(
        Method::ArkodeImex,
        &table("ARK436L2SA_DIRK_6_3_4"),
        Decay(1.0),
        0.0,
        &[1.0],
        &options(),
    )
    .unwrap();
    assert_eq!(pair.tables, ["ARK436L2SA_DIRK_6_3_4", "ARK436L2SA_ERK_6_3_4"]);
}

/// The options a method accepts in [`Method::capabilities`] are those [`build`] accepts,
/// and, for the homemade methods, those their own constructors accept (their
/// `reject_unsupported`); likewise the Butcher tables and the IMEX split.
#[test]
fn the_capability_table_agrees_with_the_integrators() {
    type Setter = fn(&mut Options);
    let set: [(&str, Setter); 6] = [
        ("max_order", |o| o.max_order = Some(4)),
        ("max_nonlin_iters", |o| o.max_nonlin_iters = Some(4)),
        ("max_conv_fails", |o| o.max_conv_fails = Some(4)),
        ("nonlin_conv_coef", |o| o.nonlin_conv_coef = Some(0.1)),
        ("jacobian_max_age", |o| o.jacobian_max_age = Some(1)),
        ("error_scales", |o| o.error_scales = Some(vec![ErrorScale::Absolute(1.0)])),
    ];
    for (name, method) in Method::ALL {
        let caps = method.capabilities();
        for (option, apply) in set {
            let mut o = options();
            apply(&mut o);
            let accepted =
                caps.accepts.options(&o).iter().any(|(n, s, ok)| *n == option && *s && *ok);
            let default = MethodSettings::default();
            let built = build(method, &default, Decay(1.0), 0.0, &[1.0], &o);
            match &built {
                Ok(_) => assert!(accepted, "{name} builds with {option}"),
                Err(e) => {
                    assert!(!accepted, "{name} refuses {option}: {e}");
                    assert_eq!(e.kind, ErrorKind::InvalidInput, "{name} {option}");
                    assert!(e.message.contains(option), "{name} {option}: {e}");
                    assert_eq!(e.solver, name);
                }
            }
            let own = match method {
                Method::Radau5 => Some(Radau5::new(Decay(1.0), 0.0, &[1.0], &o).is_ok()),
                Method::Rodas5p => Some(Rodas5p::new(Decay(1.0), 0.0, &[1.0], &o).is_ok()),
                Method::Extrapolation => {
                    Some(Extrapolation::new(Decay(1.0), 0.0, &[1.0], &o).is_ok())
                }
                _ => None,
            };
            if let Some(own) = own {
                assert_eq!(own, accepted, "{name}'s own check of {option} against the table");
            }
        }
        let table = MethodSettings { table: Some("X".into()), ..MethodSettings::default() };
        let error = build(method, &table, Decay(1.0), 0.0, &[1.0], &options()).err().unwrap();
        let unknown = error.message.contains("unknown");
        assert_eq!(unknown, caps.accepts.table.is_some(), "{name}: {}", error.message);
        let explicit =
            MethodSettings { explicit_table: Some("X".into()), ..MethodSettings::default() };
        let error = build(method, &explicit, Decay(1.0), 0.0, &[1.0], &options()).err().unwrap();
        let unknown = error.message.contains("unknown");
        assert_eq!(unknown, caps.accepts.explicit_table, "{name}: {}", error.message);
        let ode =
            build_ode(method, &MethodSettings::default(), Decay(1.0), 0.0, &[1.0], &options());
        assert_eq!(ode.is_err(), caps.needs_imex, "{name}");
        // Only radau5 transforms its tolerances; the others refuse either reading.
        for transform in [ToleranceTransform::Hairer, ToleranceTransform::AsGiven] {
            let settings = MethodSettings {
                tolerance_transform: Some(transform),
                ..MethodSettings::default()
            };
            match build(method, &settings, Decay(1.0), 0.0, &[1.0], &options()) {
                Ok(_) => assert_eq!(method, Method::Radau5),
                Err(e) => {
                    assert_ne!(method, Method::Radau5, "{e}");
                    assert_eq!(e.kind, ErrorKind::InvalidInput);
                    assert!(e.message.contains("tolerance_transform applies to radau5"), "{e}");
                }
            }
        }
    }
}

#[test]
fn build_ode_refuses_imex() {
    let error = build_ode(
        Method::ArkodeImex,
        &MethodSettings::default(),
        Decay(1.0),
        0.0,
        &[1.0],
        &options(),
    )
    .err()
    .unwrap();
    assert_eq!(error.kind, ErrorKind::InvalidInput);
    assert_eq!(error.solver, "arkode-imex");
}
