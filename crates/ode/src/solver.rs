//! Solver selection: the methods ([`Method`]: their names and dense-output orders, defined
//! below the integrators, which read them; what each can do, [`Method::capabilities`]), the
//! choices only some methods have ([`MethodSettings`]) and one constructor for every method
//! ([`build`]).
//!
//! It sits between the integrators ([`crate::integrate`], [`crate::sundials`]) and their
//! users: whoever needs an integrator names a method and gets a boxed [`Integrator`] of the
//! same shape, whatever implements it. How a user runs each method on its own problem (which
//! [`Options`] it sets per method) is the user's table, not this crate's.

use crate::integrate::{
    ErrorKind, Extrapolation, ImexSystem, Integrator, OdeSystem, Options, Radau5, Rodas5p,
    SolverError, ToleranceTransform,
};
use crate::sundials::{
    self, ArkMethod, ArkSettings, CvodeMethod, CvodeSettings, DirkTable, ErkTable, Solver,
};

pub use crate::method::Method;

impl std::str::FromStr for Method {
    type Err = MethodError;

    /// The method by its name (the one parser of method names); the
    /// error names the valid ones.
    fn from_str(name: &str) -> Result<Self, MethodError> {
        Self::ALL
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, m)| *m)
            .ok_or_else(|| MethodError::UnknownMethod { name: name.into() })
    }
}

/// A method name, Butcher table or setting that solver selection refuses; each message names the
/// field at fault and lists what is accepted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MethodError {
    /// Not the name of any method.
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
    /// explicit_table for a method that takes none ([`Accepts::explicit_table`]).
    #[error("explicit_table: {} takes no explicit table (only {} does)", method.name(), takers.join(", "))]
    NoExplicitTable {
        /// The method.
        method: Method,
        /// The names of the methods that take one.
        takers: Vec<&'static str>,
    },
    /// An optional setting the method does not take ([`Method::capabilities`]).
    #[error(
        "{name} is not an option of {method}: leave it unset (None); the methods that take it: \
         {}",
        takers.join(", ")
    )]
    UnsupportedOption {
        /// The option, e.g. "max_order".
        name: &'static str,
        /// The method.
        method: Method,
        /// The names of the methods that take it.
        takers: Vec<&'static str>,
    },
    /// deduce_implicit_rhs for a method that does not take it ([`Accepts::deduce_implicit_rhs`]).
    #[error(
        "deduce_implicit_rhs applies to {} only, not {method}: leave it false",
        takers.join(" and ")
    )]
    NoDeducedImplicitRhs {
        /// The method.
        method: Method,
        /// The names of the methods that take it.
        takers: Vec<&'static str>,
    },
    /// table for a method that is not an ARKODE one.
    #[error("table: {} takes no Butcher table (only the arkode methods do)", method.name())]
    NoTable {
        /// The method.
        method: Method,
    },
    /// An implicit table for an IMEX method, without explicit_table, that has no explicit
    /// partner of the same pair.
    #[error("table: \"{table}\" has no explicit partner; use an ARK pair (e.g. ARK436L2SA_DIRK_6_3_4) or give explicit_table")]
    NoExplicitPartner {
        /// The implicit table's name.
        table: String,
    },
    /// tolerance_transform for a method other than radau5.
    #[error(
        "tolerance_transform applies to radau5 only, not {method}: leave it unset (None); \
         {method} uses rtol and atol as given"
    )]
    NoToleranceTransform {
        /// The method.
        method: Method,
    },
}

impl MethodError {
    /// The settings field a table error is about ("table" or "explicit_table"), and the
    /// message without it; None for the other errors.
    pub fn setting(&self) -> Option<(&'static str, String)> {
        let field = match self {
            Self::UnknownImplicitTable { field, .. } | Self::UnknownExplicitTable { field, .. } => {
                *field
            }
            Self::NoExplicitTable { .. } => "explicit_table",
            Self::NoTable { .. } | Self::NoExplicitPartner { .. } => "table",
            _ => return None,
        };
        let text = self.to_string();
        let message = text.strip_prefix(&format!("{field}: ")).unwrap_or(&text).to_string();
        Some((field, message))
    }
}

impl Method {
    /// Whether the method is meant for stiff problems ([`Capabilities::stiff`]).
    pub fn is_stiff(self) -> bool {
        self.capabilities().stiff
    }

    /// What the method is, accepts and gives: the one table of per-method facts. One `match`
    /// without a wildcard arm, so that a new method does not compile until its row is written.
    pub fn capabilities(self) -> Capabilities {
        // The options of a Newton iteration (CVODE, ARKStep's implicit methods, Radau5), and
        // the error scales every method takes (SUNDIALS through a user error-weight function).
        let newton = Accepts {
            max_order: false,
            max_nonlin_iters: true,
            max_conv_fails: true,
            nonlin_conv_coef: true,
            jacobian_max_age: true,
            error_scales: true,
            deduce_implicit_rhs: false,
            table: None,
            explicit_table: false,
        };
        let cvode = Accepts { max_order: true, ..newton };
        let dirk =
            Accepts { deduce_implicit_rhs: true, table: Some(TableKind::Implicit), ..newton };
        // Rodas5P and extrapolation solve linear systems only: no Newton iteration to limit.
        let linearly_implicit =
            Accepts { max_nonlin_iters: false, nonlin_conv_coef: false, ..newton };
        match self {
            Method::CvodeBdf => Capabilities::sundials(true, "CVODE", cvode),
            Method::CvodeAdams => Capabilities::sundials(false, "CVODE", cvode),
            Method::ArkodeDirk => Capabilities::sundials(true, "ARKStep", dirk),
            Method::ArkodeImex => Capabilities {
                needs_imex: true,
                ..Capabilities::sundials(true, "ARKStep", Accepts { explicit_table: true, ..dirk })
            },
            Method::ArkodeErk => Capabilities::sundials(
                false,
                "ARKStep",
                Accepts {
                    max_nonlin_iters: false,
                    max_conv_fails: false,
                    nonlin_conv_coef: false,
                    jacobian_max_age: false,
                    deduce_implicit_rhs: false,
                    table: Some(TableKind::Explicit),
                    ..dirk
                },
            ),
            Method::Radau5 => Capabilities::own_stiff("Radau5", newton),
            Method::Rodas5p => Capabilities::own_stiff(
                "Rodas5P",
                Accepts { max_conv_fails: false, ..linearly_implicit },
            ),
            Method::Extrapolation => Capabilities::own_stiff(
                "Extrapolation",
                Accepts { max_order: true, jacobian_max_age: false, ..linearly_implicit },
            ),
        }
    }
}

/// One row of [`Method::capabilities`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capabilities {
    /// Meant for stiff problems.
    pub stiff: bool,
    /// Needs a system split into explicit and implicit parts ([`ImexSystem`], built by
    /// [`build`]; [`build_ode`] refuses it).
    pub needs_imex: bool,
    /// The integrator family that runs it, e.g. "CVODE" or "Radau5".
    pub family: &'static str,
    /// The optional [`Options`] it accepts; [`build`] refuses the others.
    pub accepts: Accepts,
}

impl Capabilities {
    /// The row of a SUNDIALS method on a system without an IMEX split: whether it is `stiff`,
    /// its `family` and what it `accepts`.
    fn sundials(stiff: bool, family: &'static str, accepts: Accepts) -> Self {
        Capabilities { stiff, needs_imex: false, family, accepts }
    }

    /// The row of one of this crate's own stiff methods (pure Rust, no IMEX split): its
    /// `family` and what it `accepts`.
    fn own_stiff(family: &'static str, accepts: Accepts) -> Self {
        Capabilities { stiff: true, needs_imex: false, family, accepts }
    }
}

/// Which optional settings a method takes: a set one it does not take is an
/// [`ErrorKind::InvalidInput`] error naming it, never ignored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepts {
    /// [`Options::max_order`].
    pub max_order: bool,
    /// [`Options::max_nonlin_iters`].
    pub max_nonlin_iters: bool,
    /// [`Options::max_conv_fails`].
    pub max_conv_fails: bool,
    /// [`Options::nonlin_conv_coef`].
    pub nonlin_conv_coef: bool,
    /// [`Options::jacobian_max_age`].
    pub jacobian_max_age: bool,
    /// [`Options::error_scales`] (SUNDIALS' user error weights, the homemade methods' own).
    pub error_scales: bool,
    /// [`MethodSettings::deduce_implicit_rhs`] (ARKStep's implicit methods).
    pub deduce_implicit_rhs: bool,
    /// [`MethodSettings::table`], and which kind of Butcher table it names; None: no table.
    pub table: Option<TableKind>,
    /// [`MethodSettings::explicit_table`].
    pub explicit_table: bool,
}

/// The kind of Butcher table a method's [`MethodSettings::table`] names ([`Accepts::table`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableKind {
    /// An implicit (DIRK) table, [`DirkTable`] (arkode-dirk; arkode-imex's implicit part).
    Implicit,
    /// An explicit (ERK) table, [`ErkTable`] (arkode-erk).
    Explicit,
}

impl Accepts {
    /// The optional [`Options`] as (name, whether it is set in `options`, whether it is
    /// accepted).
    pub fn options(&self, options: &Options) -> [(&'static str, bool, bool); 6] {
        [
            ("max_order", options.max_order.is_some(), self.max_order),
            ("max_nonlin_iters", options.max_nonlin_iters.is_some(), self.max_nonlin_iters),
            ("max_conv_fails", options.max_conv_fails.is_some(), self.max_conv_fails),
            ("nonlin_conv_coef", options.nonlin_conv_coef.is_some(), self.nonlin_conv_coef),
            ("jacobian_max_age", options.jacobian_max_age.is_some(), self.jacobian_max_age),
            ("error_scales", options.error_scales.is_some(), self.error_scales),
        ]
    }
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
    /// ARKStep's implicit methods (arkode-dirk, arkode-imex) deduce each implicit stage
    /// derivative from the stage equation instead of evaluating f_I there
    /// ([`ArkSettings::deduce_implicit_rhs`]), and then keep ARKODE's own Newton defaults:
    /// on a very stiff system the evaluated f_I carries the Newton residual times the stiffness
    /// into ARKStep's error estimate. Off by default, which gives the tight Newton iteration of
    /// SUNDIALS' ark_robertson example (`nonlin_conv_coef` 1e-7, predictor 1, 20 error-test
    /// failures): with deduced derivatives arkode-dirk fails OREGO and E5 of the stiff test
    /// set at rtol 1e-4 and 1e-7 and reports HIRES and VDPOL at 1e-7 about 2000 × rtol off
    /// (docs/test-set.md). An error for the other methods.
    pub deduce_implicit_rhs: bool,
    /// What radau5 makes of rtol and atol ([`ToleranceTransform`]); None is RADAU5's own
    /// transform ([`ToleranceTransform::Hairer`]). The other methods use the tolerances as
    /// given and have no such setting: an error for them.
    pub tolerance_transform: Option<ToleranceTransform>,
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
/// Every method gets the configuration the stiff test set measures (tests/test_set,
/// docs/test-set.md): ARKStep's implicit methods evaluate their stage derivatives with the
/// tight Newton iteration of [`ArkSettings::default`] unless
/// [`MethodSettings::deduce_implicit_rhs`] asks otherwise, and with `jacobian_max_age = 1`
/// arkode-dirk applies every step-size change and rebuilds its Newton matrix at every stage
/// (see `dirk_settings`). CVODE runs without stability-limit detection. The options are
/// checked against [`Method::capabilities`] first: one the method does not take is an
/// [`ErrorKind::InvalidInput`] error naming it.
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
    if !method.capabilities().needs_imex {
        return build_ode(method, settings, system, t0, y0, options);
    }
    let tables = checked_tables(method, settings, options)
        .map_err(|e| invalid(method, t0, y0, e.to_string()))?;
    let (default_i, default_e) = sundials::default_imex_tables();
    let (implicit, explicit) =
        (tables.implicit.unwrap_or(default_i), tables.explicit.unwrap_or(default_e));
    let integrator = Box::new(Solver::arkstep_imex(
        system,
        implicit,
        explicit,
        ark_settings(settings),
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
    let tables = checked_tables(method, settings, options)
        .map_err(|e| invalid(method, t0, y0, e.to_string()))?;
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
            dirk_settings(settings, options),
            t0,
            y0,
            options,
        )?),
        Method::ArkodeErk => {
            let settings = ark_settings(settings);
            Box::new(Solver::arkstep(system, ArkMethod::Erk(erk), settings, t0, y0, options)?)
        }
        Method::ArkodeImex => {
            let message = "arkode-imex needs a system split into explicit and implicit parts: implement ImexSystem and use solver::build";
            return Err(invalid(method, t0, y0, message.into()));
        }
        Method::Radau5 => {
            let transform = settings.tolerance_transform.unwrap_or_default();
            Box::new(Radau5::with_tolerances(system, t0, y0, options, transform)?)
        }
        Method::Rodas5p if settings.autonomous => {
            Box::new(Rodas5p::new(system, t0, y0, options)?.autonomous())
        }
        Method::Rodas5p => Box::new(Rodas5p::new(system, t0, y0, options)?),
        Method::Extrapolation => Box::new(Extrapolation::new(system, t0, y0, options)?),
    };
    let tables = match method.capabilities().accepts.table {
        Some(TableKind::Implicit) => vec![dirk.name().into()],
        Some(TableKind::Explicit) => vec![erk.name().into()],
        None => vec![],
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
fn ark_settings(settings: &MethodSettings) -> ArkSettings {
    ArkSettings { deduce_implicit_rhs: settings.deduce_implicit_rhs, ..ArkSettings::default() }
}

/// The options and settings `method` does not take ([`Method::capabilities`]): the first one
/// set, made an [`ErrorKind::InvalidInput`] error by [`build`]; the Butcher tables are
/// checked by `check_tables`.
fn reject_unsupported(
    method: Method,
    settings: &MethodSettings,
    options: &Options,
) -> Result<(), MethodError> {
    let accepts = method.capabilities().accepts;
    if let Some((name, _, _)) =
        accepts.options(options).into_iter().find(|(_, set, ok)| *set && !ok)
    {
        let takers = Method::ALL
            .iter()
            .filter(|(_, m)| {
                m.capabilities().accepts.options(options).iter().any(|(n, _, ok)| *n == name && *ok)
            })
            .map(|(n, _)| *n)
            .collect();
        return Err(MethodError::UnsupportedOption { name, method, takers });
    }
    if settings.deduce_implicit_rhs && !accepts.deduce_implicit_rhs {
        let takers = Method::ALL
            .iter()
            .filter(|(_, m)| m.capabilities().accepts.deduce_implicit_rhs)
            .map(|(n, _)| *n)
            .collect();
        return Err(MethodError::NoDeducedImplicitRhs { method, takers });
    }
    if settings.tolerance_transform.is_some() && method != Method::Radau5 {
        return Err(MethodError::NoToleranceTransform { method });
    }
    Ok(())
}

/// ARKStep DIRK's settings: [`ark_settings`], and, when the Jacobian is fresh at every step
/// (`jacobian_max_age` = 1), every step-size change applied
/// ([`ArkSettings::resize_every_step`]) with the Newton matrix rebuilt at every stage
/// ([`ArkSettings::setup_every_stage`]). The measurements behind both are the stickslip
/// library's (its engine's method table, arkode-dirk's row; docs/robustness.md, "Why the
/// damped cells fail with every step change applied").
///
/// The window: ARKODE keeps h while the proposed growth lies in [1, 1.5] to reuse its Newton
/// matrix, which saves nothing when that matrix is rebuilt anyway; and where the error
/// estimate sits on a floor that does not fall with h, h stalls there for as long as the
/// proposed growth stays in the window (hundreds of thousands of steps measured).
///
/// The stages: SDIRK-5-3-4's embedded solution has R̂(∞) = 10/3 (the solution R(∞) = 0), so
/// an offset δ of y_n's stiff component from the slow manifold shows in every attempt of the
/// next step as an estimate of 10/3 δ, whatever h. A stage whose Newton iteration stopped far
/// from its solution leaves such an offset, and where it exceeds 0.3 of the error weight no
/// step from there passes: the run ends in repeated error-test failures at an estimate that
/// does not change with h. That happens where the stiff rate changes by a large factor
/// within a step, so that the Jacobian taken at the step's start misjudges the last stages.
/// A Newton matrix per stage, with ARKODE's convergence rate measured afresh in each
/// stage, keeps those stages honest. Not with ARKODE's Jacobian reuse (library defaults):
/// there the window saves setups, and applying every change made examples/own_system.rs's
/// Prothero–Robinson run less accurate (error 1.6e-9 → 6.8e-6 at rtol 1e-8).
fn dirk_settings(settings: &MethodSettings, options: &Options) -> ArkSettings {
    let fresh_jacobian = options.jacobian_max_age == Some(1);
    ArkSettings {
        resize_every_step: fresh_jacobian,
        setup_every_stage: fresh_jacobian,
        ..ark_settings(settings)
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

/// The Butcher tables `settings` name for `method`, once the method is known to take every
/// option and setting given ([`reject_unsupported`], [`check_tables`]).
fn checked_tables(
    method: Method,
    settings: &MethodSettings,
    options: &Options,
) -> Result<Tables, MethodError> {
    reject_unsupported(method, settings, options)?;
    check_tables(method, settings)
}

/// The Butcher tables a method asked for by name (None: its default).
struct Tables {
    implicit: Option<DirkTable>,
    explicit: Option<ErkTable>,
}

/// Checks the Butcher table names of `table` and `explicit_table` for `method`, as [`build`]
/// does: the one check of table names, for a caller that checks its input before building. The error names the setting
/// ([`MethodError::setting`]).
pub fn check_table_names(
    method: Method,
    table: Option<&str>,
    explicit_table: Option<&str>,
) -> Result<(), MethodError> {
    let settings = MethodSettings {
        table: table.map(str::to_string),
        explicit_table: explicit_table.map(str::to_string),
        ..MethodSettings::default()
    };
    check_tables(method, &settings).map(|_| ())
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
    let accepts = method.capabilities().accepts;
    if explicit_table.is_some() && !accepts.explicit_table {
        let takers = Method::ALL
            .iter()
            .filter(|(_, m)| m.capabilities().accepts.explicit_table)
            .map(|(n, _)| *n)
            .collect();
        return Err(MethodError::NoExplicitTable { method, takers });
    }
    match accepts.table {
        Some(TableKind::Implicit) if accepts.explicit_table => {
            let implicit = table.map(|n| dirk("table", n)).transpose()?;
            let paired = table.and_then(|n| ErkTable::from_name(&n.replace("_DIRK_", "_ERK_")));
            let explicit = match (explicit_table, table) {
                (Some(n), _) => Some(erk("explicit_table", n)?),
                (None, Some(n)) if paired.is_none() => {
                    return Err(MethodError::NoExplicitPartner { table: n.into() })
                }
                (None, _) => paired,
            };
            Ok(Tables { implicit, explicit })
        }
        Some(TableKind::Implicit) => {
            Ok(Tables { implicit: table.map(|n| dirk("table", n)).transpose()?, explicit: None })
        }
        Some(TableKind::Explicit) => {
            Ok(Tables { implicit: None, explicit: table.map(|n| erk("table", n)).transpose()? })
        }
        None if table.is_some() => Err(MethodError::NoTable { method }),
        None => Ok(Tables { implicit: None, explicit: None }),
    }
}
