//! Solver selection: the methods by name ([`Method`]), a scene's solver settings
//! ([`SolverSpec`]) and one constructor for every method ([`build`]).
//!
//! It sits between the integrators ([`crate::integrate`], [`crate::sundials`]) and their users
//! (analyses, the engine, library users): whoever needs an integrator names a method and gets
//! a boxed [`Integrator`] of the same shape, whatever implements it.

use crate::integrate::{
    ErrorKind, Extrapolation, ImexSystem, Integrator, OdeSystem, Options, Radau5, Rodas5p,
    SolverError,
};
use crate::sundials::{
    self, ArkMethod, ArkSettings, CvodeMethod, CvodeSettings, DirkTable, ErkTable, Solver,
};
use serde::Serialize;

/// Integration methods a scene can ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// CVODE, variable-order BDF (stiff).
    CvodeBdf,
    /// CVODE, Adams–Moulton (non-stiff).
    CvodeAdams,
    /// ARKStep, diagonally implicit Runge–Kutta (stiff).
    ArkodeDirk,
    /// ARKStep, implicit–explicit: drive explicit, friction implicit (stiff).
    ArkodeImex,
    /// ARKStep, explicit Runge–Kutta (non-stiff).
    ArkodeErk,
    /// stickslip's own Radau IIA of order 5 (stiff, pure Rust).
    Radau5,
    /// stickslip's own Rosenbrock method Rodas5P (stiff, pure Rust).
    Rodas5p,
    /// stickslip's own extrapolation with stiffness switching (linearly implicit Euler /
    /// modified midpoint, the family the paper used; pure Rust).
    Extrapolation,
}

impl Method {
    /// Every method with its scene name.
    pub const ALL: [(&'static str, Method); 8] = [
        ("cvode-bdf", Method::CvodeBdf),
        ("cvode-adams", Method::CvodeAdams),
        ("arkode-dirk", Method::ArkodeDirk),
        ("arkode-imex", Method::ArkodeImex),
        ("arkode-erk", Method::ArkodeErk),
        ("radau5", Method::Radau5),
        ("rodas5p", Method::Rodas5p),
        ("extrapolation", Method::Extrapolation),
    ];

    /// The scene name, e.g. "cvode-bdf".
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(_, m)| *m == self).map(|(n, _)| *n).unwrap_or("?")
    }
}

impl std::fmt::Display for Method {
    /// The scene name (padded to a width if one is given).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = MethodError;

    /// The method by its scene name (the one parser of method names: scenes and the CLI); the
    /// error names the valid ones.
    fn from_str(name: &str) -> Result<Self, MethodError> {
        Self::ALL
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, m)| *m)
            .ok_or_else(|| MethodError::UnknownMethod { name: name.into() })
    }
}

/// A method name or Butcher table that solver selection refuses; each message names the
/// field at fault and lists what is accepted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MethodError {
    /// Not the scene name of any method.
    #[error("\"{name}\" is not a method; use one of {}", Method::ALL.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "))]
    UnknownMethod {
        /// The name as given.
        name: String,
    },
    /// `field` names no implicit (DIRK) table.
    #[error("{field}: unknown implicit table \"{name}\"; available: {}", DirkTable::names().collect::<Vec<_>>().join(", "))]
    UnknownImplicitTable {
        /// The settings field: table.
        field: &'static str,
        /// The name as given.
        name: String,
    },
    /// `field` names no explicit (ERK) table.
    #[error("{field}: unknown explicit table \"{name}\"; available: {}", ErkTable::names().collect::<Vec<_>>().join(", "))]
    UnknownExplicitTable {
        /// The settings field: table or explicit_table.
        field: &'static str,
        /// The name as given.
        name: String,
    },
    /// explicit_table for a method other than arkode-imex.
    #[error("explicit_table: {} takes no explicit table (only arkode-imex does)", method.name())]
    NoExplicitTable {
        /// The method.
        method: Method,
    },
    /// table for a method that is not an ARKODE one.
    #[error("table: {} takes no Butcher table (only the arkode methods do)", method.name())]
    NoTable {
        /// The method.
        method: Method,
    },
}

impl Method {
    /// Whether the method is meant for stiff problems.
    pub fn is_stiff(self) -> bool {
        matches!(
            self,
            Method::CvodeBdf
                | Method::ArkodeDirk
                | Method::ArkodeImex
                | Method::Radau5
                | Method::Rodas5p
                | Method::Extrapolation
        )
    }
}

/// Validated solver settings of a scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolverSpec {
    /// The method.
    pub method: Method,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerances of (u, ln v, θ).
    pub atol: [f64; 3],
    /// Butcher table (implicit one for DIRK/IMEX, explicit one for ERK), None = default.
    pub table: Option<String>,
    /// Explicit table of an IMEX pair, None = default.
    pub explicit_table: Option<String>,
}

/// Choices beyond [`Options`] that only some methods have.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MethodSettings {
    /// ARKStep Butcher table by ARKODE name (the implicit one for arkode-dirk and arkode-imex,
    /// the explicit one for arkode-erk); None = the default. An error for other methods.
    pub table: Option<String>,
    /// Explicit table of an arkode-imex pair; None = the partner of `table` (its `_DIRK_`
    /// replaced by `_ERK_`) if there is one, else the default. An error for other methods.
    pub explicit_table: Option<String>,
    /// The system does not depend on t explicitly: rodas5p then skips its ∂f/∂t evaluations.
    /// A property of the system, not an option: the other methods do not need it.
    pub autonomous: bool,
}

impl MethodSettings {
    /// The Butcher tables of a scene's solver settings, for a system that is or is not
    /// autonomous.
    pub fn of(spec: &SolverSpec, autonomous: bool) -> Self {
        MethodSettings {
            table: spec.table.clone(),
            explicit_table: spec.explicit_table.clone(),
            autonomous,
        }
    }
}

/// An integrator built by [`build`].
pub struct Built<'s> {
    /// The integrator, at (t0, y0).
    pub integrator: Box<dyn Integrator + 's>,
    /// The Butcher tables it uses (ARKStep; empty for the other methods).
    pub tables: Vec<String>,
}

/// Builds `method` on `system` starting at (`t0`, `y0`) with `options`: the one constructor
/// shape for every method. An option the method does not support is an error (the
/// integrators' own checks), and so is a Butcher table it cannot use or does not know.
///
/// ARKStep methods deduce their implicit stage derivatives from the Newton solution (SUNDIALS'
/// `ARKodeSetDeduceImplicitRhs`): evaluating f_I at converged stages re-amplifies the Newton
/// residual by the stiffness in ARKStep's error estimate, which makes it fail on very stiff
/// problems (at γ ≥ 1e3 on the DRR system). CVODE runs without stability-limit detection.
///
/// For a system that is not split into explicit and implicit parts, use [`build_ode`].
pub fn build<'s, S: ImexSystem + 's>(
    method: Method,
    settings: &MethodSettings,
    system: S,
    t0: f64,
    y0: &[f64],
    options: &Options,
) -> Result<Built<'s>, SolverError> {
    if method != Method::ArkodeImex {
        return build_ode(method, settings, system, t0, y0, options);
    }
    let tables =
        check_tables(method, settings).map_err(|e| invalid(method, t0, y0, e.to_string()))?;
    let (default_i, default_e) = sundials::default_imex_tables();
    let (implicit, explicit) =
        (tables.implicit.unwrap_or(default_i), tables.explicit.unwrap_or(default_e));
    let integrator = Box::new(Solver::arkstep_imex(
        system,
        implicit,
        explicit,
        ark_settings(),
        t0,
        y0,
        options,
    )?);
    Ok(Built { integrator, tables: vec![implicit.name().into(), explicit.name().into()] })
}

/// [`build`] for a system without an explicit/implicit split: every method except
/// arkode-imex, which is an [`ErrorKind::InvalidInput`] error here.
pub fn build_ode<'s, S: OdeSystem + 's>(
    method: Method,
    settings: &MethodSettings,
    system: S,
    t0: f64,
    y0: &[f64],
    options: &Options,
) -> Result<Built<'s>, SolverError> {
    let tables =
        check_tables(method, settings).map_err(|e| invalid(method, t0, y0, e.to_string()))?;
    let cvode = |method| CvodeSettings { method, stability_limit_detection: false };
    let (dirk, erk) = (tables.implicit.unwrap_or_default(), tables.explicit.unwrap_or_default());
    let integrator: Box<dyn Integrator + 's> = match method {
        Method::CvodeBdf => {
            Box::new(Solver::cvode(system, cvode(CvodeMethod::Bdf), t0, y0, options)?)
        }
        Method::CvodeAdams => {
            Box::new(Solver::cvode(system, cvode(CvodeMethod::Adams), t0, y0, options)?)
        }
        Method::ArkodeDirk => Box::new(Solver::arkstep(
            system,
            ArkMethod::Dirk(dirk),
            dirk_settings(options),
            t0,
            y0,
            options,
        )?),
        Method::ArkodeErk => {
            Box::new(Solver::arkstep(system, ArkMethod::Erk(erk), ark_settings(), t0, y0, options)?)
        }
        Method::ArkodeImex => {
            let message = "arkode-imex needs a system split into explicit and implicit parts: implement ImexSystem and use solver::build";
            return Err(invalid(method, t0, y0, message.into()));
        }
        Method::Radau5 => Box::new(Radau5::new(system, t0, y0, options)?),
        Method::Rodas5p if settings.autonomous => {
            Box::new(Rodas5p::new(system, t0, y0, options)?.autonomous())
        }
        Method::Rodas5p => Box::new(Rodas5p::new(system, t0, y0, options)?),
        Method::Extrapolation => Box::new(Extrapolation::new(system, t0, y0, options)?),
    };
    let tables = match method {
        Method::ArkodeDirk => vec![dirk.name().into()],
        Method::ArkodeErk => vec![erk.name().into()],
        _ => vec![],
    };
    Ok(Built { integrator, tables })
}

/// [`build_ode`] with the method's defaults (no Butcher table; the system is not assumed
/// autonomous): the integrator alone. How the analyses that fix their own method (noise,
/// the slow flow, the fast system) get theirs.
pub fn build_default<'s, S: OdeSystem + 's>(
    method: Method,
    system: S,
    t0: f64,
    y0: &[f64],
    options: &Options,
) -> Result<Box<dyn Integrator + 's>, SolverError> {
    Ok(build_ode(method, &MethodSettings::default(), system, t0, y0, options)?.integrator)
}

/// ARKStep's settings for every ARKStep method (see [`build`]).
fn ark_settings() -> ArkSettings {
    ArkSettings { deduce_implicit_rhs: true, ..ArkSettings::default() }
}

/// ARKStep DIRK's settings: [`ark_settings`], and, when the Jacobian is fresh at every step
/// (`jacobian_max_age` = 1, as the engine sets it), every step-size change applied
/// ([`ArkSettings::resize_every_step`]) with the Newton matrix rebuilt at every stage
/// ([`ArkSettings::setup_every_stage`]); docs/robustness.md, "Why the damped cells fail with
/// every step change applied".
///
/// The window: ARKODE keeps h while the proposed growth lies in [1, 1.5] to reuse its Newton
/// matrix, which saves nothing when that matrix is rebuilt anyway; and in the arrest after a
/// slip, where the error estimate sits on a floor that does not fall with h, h stalled there:
/// the DRR work–precision cell γ = 1e8, rtol 1e-11 held h = 3.08e-13 for 192 523 accepted
/// steps of one cycle (270 214 steps in 3 cycles; 29 576 with these settings).
///
/// The stages: SDIRK-5-3-4's embedded solution has R̂(∞) = 10/3 (the solution R(∞) = 0), so
/// an offset δ of y_n's stiff component from the slow manifold shows in every attempt of the
/// next step as an estimate of 10/3 δ, whatever h. A stage whose Newton iteration stopped far
/// from its solution leaves such an offset, and where it exceeds 0.3 of the error weight no
/// step from there passes: with the window alone two damped laws-grid cells ended in 20
/// error-test failures at an estimate constant to 5 digits from h = 0.13 to 4.9e-11, 10/3 of
/// the offset measured at y_n (PRZ, γ = 1e6, ξ = 0.7, ε = 10, η = 0.1, rtol 1e-6: w 5.4e-6,
/// 0.56 of its weight, off the manifold after a step over which w fell by 0.8, so that the
/// stiff rate γ²e^(−w) at its last stage was 2.3× the one of the Jacobian taken at the step's
/// start). A Newton matrix per stage, with ARKODE's convergence rate measured afresh in each
/// stage, keeps those stages honest. Not with ARKODE's Jacobian reuse (library defaults):
/// there the window saves setups, and applying every change made examples/own_system.rs's
/// Prothero–Robinson run less accurate (error 1.6e-9 → 6.8e-6 at rtol 1e-8).
fn dirk_settings(options: &Options) -> ArkSettings {
    let fresh_jacobian = options.jacobian_max_age == Some(1);
    ArkSettings {
        resize_every_step: fresh_jacobian,
        setup_every_stage: fresh_jacobian,
        ..ark_settings()
    }
}

/// Invalid input to [`build`], at the start.
fn invalid(method: Method, t0: f64, y0: &[f64], message: String) -> SolverError {
    SolverError {
        solver: method.name(),
        kind: ErrorKind::InvalidInput,
        t: t0,
        state: y0.to_vec(),
        flag: 0,
        message,
    }
}

/// The Butcher tables a method asked for by name (None: its default).
struct Tables {
    implicit: Option<DirkTable>,
    explicit: Option<ErkTable>,
}

/// Resolves the table names of `settings` for `method`; an unknown name, or a table for a
/// method that takes none, is an error naming the field (made an
/// [`ErrorKind::InvalidInput`] by [`build`]).
fn check_tables(method: Method, settings: &MethodSettings) -> Result<Tables, MethodError> {
    let dirk = |field: &'static str, name: &str| {
        DirkTable::from_name(name)
            .ok_or_else(|| MethodError::UnknownImplicitTable { field, name: name.into() })
    };
    let erk = |field: &'static str, name: &str| {
        ErkTable::from_name(name)
            .ok_or_else(|| MethodError::UnknownExplicitTable { field, name: name.into() })
    };
    let (table, explicit_table) = (settings.table.as_deref(), settings.explicit_table.as_deref());
    if explicit_table.is_some() && method != Method::ArkodeImex {
        return Err(MethodError::NoExplicitTable { method });
    }
    match method {
        Method::ArkodeDirk => {
            Ok(Tables { implicit: table.map(|n| dirk("table", n)).transpose()?, explicit: None })
        }
        Method::ArkodeErk => {
            Ok(Tables { implicit: None, explicit: table.map(|n| erk("table", n)).transpose()? })
        }
        Method::ArkodeImex => {
            let implicit = table.map(|n| dirk("table", n)).transpose()?;
            let paired = table.and_then(|n| ErkTable::from_name(&n.replace("_DIRK_", "_ERK_")));
            let explicit = match explicit_table {
                Some(n) => Some(erk("explicit_table", n)?),
                None => paired,
            };
            Ok(Tables { implicit, explicit })
        }
        _ if table.is_some() => Err(MethodError::NoTable { method }),
        _ => Ok(Tables { implicit: None, explicit: None }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::{JacobianMatrix, Task, Tolerance};

    /// y' = −y (all of it implicit in the IMEX split), y(0) = 1: y(1) = e^(−1).
    struct Decay;

    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
            dydt[0] = -y[0];
        }
        fn has_jacobian(&self) -> bool {
            true
        }
        fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
            jac.set(0, 0, -1.0);
        }
    }

    impl ImexSystem for Decay {
        fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
            dydt[0] = 0.0;
        }
        fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
            self.rhs(t, y, dydt);
        }
    }

    fn options() -> Options {
        Options::new(1e-9, Tolerance::Scalar(1e-12))
    }

    #[test]
    fn every_method_by_name_builds_and_integrates_the_decay() {
        for (name, method) in Method::ALL {
            assert_eq!(name.parse::<Method>(), Ok(method));
            assert_eq!(format!("{method}"), name);
            let mut integ =
                build(method, &MethodSettings::default(), Decay, 0.0, &[1.0], &options())
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
            build(Method::ArkodeImex, &MethodSettings::default(), Decay, 0.0, &[1.0], &options())
                .unwrap();
        assert_eq!(built.tables.len(), 2);
        let table =
            |name: &str| MethodSettings { table: Some(name.into()), ..MethodSettings::default() };
        let error = |method, settings: MethodSettings| {
            build(method, &settings, Decay, 0.0, &[1.0], &options())
                .err()
                .map(|e| (e.kind, e.message))
        };
        let (kind, message) = error(Method::ArkodeDirk, table("NO_SUCH_TABLE")).unwrap();
        assert_eq!(kind, ErrorKind::InvalidInput);
        assert!(
            message.starts_with("table: unknown implicit table \"NO_SUCH_TABLE\""),
            "{message}"
        );
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
            Decay,
            0.0,
            &[1.0],
            &options(),
        )
        .unwrap();
        assert_eq!(pair.tables, ["ARK436L2SA_DIRK_6_3_4", "ARK436L2SA_ERK_6_3_4"]);
    }

    #[test]
    fn build_ode_refuses_imex() {
        let error = build_ode(
            Method::ArkodeImex,
            &MethodSettings::default(),
            Decay,
            0.0,
            &[1.0],
            &options(),
        )
        .err()
        .unwrap();
        assert_eq!(error.kind, ErrorKind::InvalidInput);
        assert_eq!(error.solver, "arkode-imex");
    }
}
