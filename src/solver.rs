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
    /// Whether the method is meant for stiff problems ([`Capabilities::stiff`]).
    pub fn is_stiff(self) -> bool {
        self.capabilities().stiff
    }

    /// What the method is, accepts and gives, and how the engine runs it: the one table of
    /// per-method facts. One `match` without a wildcard arm, so that a new method does not
    /// compile until its row is written.
    pub fn capabilities(self) -> Capabilities {
        // The options of a Newton iteration (CVODE, ARKStep's implicit methods, Radau5).
        let newton = Accepts {
            max_order: false,
            max_nonlin_iters: true,
            max_conv_fails: true,
            nonlin_conv_coef: true,
            jacobian_max_age: true,
            error_scales: false,
            table: false,
            explicit_table: false,
        };
        // SUNDIALS takes user error weights; the homemade methods weigh by size only.
        let cvode = Accepts { max_order: true, error_scales: true, ..newton };
        let dirk = Accepts { table: true, error_scales: true, ..newton };
        let plain = EngineSettings {
            jacobian_max_age: None,
            deduce_implicit_rhs: false,
            dirk_newton: false,
            absolute_ln_v: None,
        };
        // A fresh Jacobian at every step, see `engine`.
        let fresh = EngineSettings { jacobian_max_age: Some(1), ..plain };
        match self {
            Method::CvodeBdf => Capabilities {
                stiff: true,
                needs_imex: false,
                dense_order: 5,
                family: "CVODE",
                accepts: cvode,
                engine: EngineSettings { absolute_ln_v: Some(0.1), ..fresh },
                physical_region: true,
            },
            Method::CvodeAdams => Capabilities {
                stiff: false,
                needs_imex: false,
                dense_order: 12,
                family: "CVODE",
                accepts: cvode,
                engine: plain,
                physical_region: false,
            },
            Method::ArkodeDirk => Capabilities {
                stiff: true,
                needs_imex: false,
                dense_order: 5,
                family: "ARKStep",
                accepts: dirk,
                engine: EngineSettings {
                    deduce_implicit_rhs: true,
                    dirk_newton: true,
                    absolute_ln_v: Some(1.0),
                    ..fresh
                },
                physical_region: true,
            },
            Method::ArkodeImex => Capabilities {
                stiff: true,
                needs_imex: true,
                dense_order: 3,
                family: "ARKStep",
                accepts: Accepts { explicit_table: true, ..dirk },
                engine: EngineSettings { deduce_implicit_rhs: true, ..fresh },
                physical_region: false,
            },
            Method::ArkodeErk => Capabilities {
                stiff: false,
                needs_imex: false,
                dense_order: 5,
                family: "ARKStep",
                accepts: Accepts {
                    max_nonlin_iters: false,
                    max_conv_fails: false,
                    nonlin_conv_coef: false,
                    jacobian_max_age: false,
                    ..dirk
                },
                engine: plain,
                physical_region: false,
            },
            Method::Radau5 => Capabilities {
                stiff: true,
                needs_imex: false,
                dense_order: 3,
                family: "Radau5",
                accepts: newton,
                engine: fresh,
                physical_region: true,
            },
            Method::Rodas5p => Capabilities {
                stiff: true,
                needs_imex: false,
                dense_order: 4,
                family: "Rodas5P",
                accepts: Accepts {
                    max_nonlin_iters: false,
                    max_conv_fails: false,
                    nonlin_conv_coef: false,
                    ..newton
                },
                engine: plain,
                physical_region: true,
            },
            Method::Extrapolation => Capabilities {
                stiff: true,
                needs_imex: false,
                dense_order: 3,
                family: "Extrapolation",
                accepts: Accepts {
                    max_order: true,
                    max_nonlin_iters: false,
                    nonlin_conv_coef: false,
                    jacobian_max_age: false,
                    ..newton
                },
                engine: plain,
                physical_region: true,
            },
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
    /// The largest k that `dense(t, k)` can accept after a step (CVODE: up to the order of
    /// the last step, at most this; before the first step every method takes k ≤ 1 only).
    /// [`Integrator::max_dense_order`] gives the bound in force.
    pub dense_order: u32,
    /// The integrator family that runs it, as the report's `solver.integrator` names it.
    pub family: &'static str,
    /// The optional [`Options`] it accepts; [`build`] refuses the others.
    pub accepts: Accepts,
    /// How the engine runs it on the spring-slider.
    pub engine: EngineSettings,
    /// Whether the stress grid's physical-region guarantee covers it (src/stress.rs; issue
    /// #13): the stiff methods, except arkode-imex, whose explicit plate drive is not part of
    /// it.
    pub physical_region: bool,
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
    /// [`Options::error_scales`] (SUNDIALS' user error weights).
    pub error_scales: bool,
    /// [`MethodSettings::table`].
    pub table: bool,
    /// [`MethodSettings::explicit_table`].
    pub explicit_table: bool,
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

/// The engine's per-method settings on the spring-slider (src/engine.rs gives the reasons and
/// measurements).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineSettings {
    /// [`Options::jacobian_max_age`]: `Some(1)`, a fresh Jacobian at every step, for the
    /// stiff methods with a Newton iteration whose Jacobian would otherwise age.
    pub jacobian_max_age: Option<i64>,
    /// [`MethodSettings::deduce_implicit_rhs`] (ARKStep's implicit methods).
    pub deduce_implicit_rhs: bool,
    /// ARKStep DIRK's tighter Newton iteration: `nonlin_conv_coef` = 1000 u / rtol within
    /// [1e-3, 0.1] and `max_nonlin_iters` = 5.
    pub dirk_newton: bool,
    /// ln v's error weighed absolutely at this fraction of rtol ([`Options::error_scales`]),
    /// with 20 convergence failures per step ([`Options::max_conv_fails`]): CVODE BDF at a
    /// tenth of rtol, ARKStep DIRK at rtol; see `engine`.
    pub absolute_ln_v: Option<f64>,
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
    /// ARKStep's implicit methods (arkode-dirk, arkode-imex) deduce each implicit stage
    /// derivative from the stage equation instead of evaluating f_I there
    /// ([`ArkSettings::deduce_implicit_rhs`]), and then keep ARKODE's own Newton defaults.
    /// The engine's setting for the spring-slider ([`EngineSettings::deduce_implicit_rhs`]):
    /// at γ ≥ 1e3 the evaluated f_I carries the Newton residual times the stiffness into
    /// ARKStep's error estimate. Off by default, which gives the tight Newton iteration of
    /// SUNDIALS' ark_robertson example (`nonlin_conv_coef` 1e-7, predictor 1, 20 error-test
    /// failures): with deduced derivatives arkode-dirk fails OREGO and E5 of the stiff test
    /// set at rtol 1e-4 and 1e-7 and reports HIRES and VDPOL at 1e-7 about 2000 × rtol off
    /// (docs/test-set.md). An error for the other methods.
    pub deduce_implicit_rhs: bool,
}

impl MethodSettings {
    /// The Butcher tables of a scene's solver settings, for a system that is or is not
    /// autonomous.
    pub fn of(spec: &SolverSpec, autonomous: bool) -> Self {
        MethodSettings {
            table: spec.table.clone(),
            explicit_table: spec.explicit_table.clone(),
            autonomous,
            deduce_implicit_rhs: false,
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
    if method != Method::ArkodeImex {
        return build_ode(method, settings, system, t0, y0, options);
    }
    reject_unsupported(method, settings, options).map_err(|m| invalid(method, t0, y0, m))?;
    let tables =
        check_tables(method, settings).map_err(|e| invalid(method, t0, y0, e.to_string()))?;
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
    reject_unsupported(method, settings, options).map_err(|m| invalid(method, t0, y0, m))?;
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
fn ark_settings(settings: &MethodSettings) -> ArkSettings {
    ArkSettings { deduce_implicit_rhs: settings.deduce_implicit_rhs, ..ArkSettings::default() }
}

/// The options and settings `method` does not take ([`Method::capabilities`]), as the message
/// of an [`ErrorKind::InvalidInput`] error naming the first one set; the Butcher tables are
/// checked by `check_tables`.
fn reject_unsupported(
    method: Method,
    settings: &MethodSettings,
    options: &Options,
) -> Result<(), String> {
    let accepts = method.capabilities().accepts;
    if let Some((name, _, _)) =
        accepts.options(options).into_iter().find(|(_, set, ok)| *set && !ok)
    {
        let takers: Vec<&str> = Method::ALL
            .iter()
            .filter(|(_, m)| {
                m.capabilities().accepts.options(options).iter().any(|(n, _, ok)| *n == name && *ok)
            })
            .map(|(n, _)| *n)
            .collect();
        return Err(format!(
            "{name} is not an option of {method}: leave it unset (None); the methods that take it: {}",
            takers.join(", ")
        ));
    }
    let ark_implicit = matches!(method, Method::ArkodeDirk | Method::ArkodeImex);
    if settings.deduce_implicit_rhs && !ark_implicit {
        return Err(format!(
            "deduce_implicit_rhs applies to arkode-dirk and arkode-imex only, not {method}: leave it false"
        ));
    }
    Ok(())
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
    use crate::integrate::{ErrorScale, JacobianMatrix, Task, Tolerance};

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
                let built = build(method, &default, Decay, 0.0, &[1.0], &o);
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
                    Method::Radau5 => Some(Radau5::new(Decay, 0.0, &[1.0], &o).is_ok()),
                    Method::Rodas5p => Some(Rodas5p::new(Decay, 0.0, &[1.0], &o).is_ok()),
                    Method::Extrapolation => {
                        Some(Extrapolation::new(Decay, 0.0, &[1.0], &o).is_ok())
                    }
                    _ => None,
                };
                if let Some(own) = own {
                    assert_eq!(own, accepted, "{name}'s own check of {option} against the table");
                }
            }
            let table = MethodSettings { table: Some("X".into()), ..MethodSettings::default() };
            let error = build(method, &table, Decay, 0.0, &[1.0], &options()).err().unwrap();
            let unknown = error.message.contains("unknown");
            assert_eq!(unknown, caps.accepts.table, "{name}: {}", error.message);
            let explicit =
                MethodSettings { explicit_table: Some("X".into()), ..MethodSettings::default() };
            let error = build(method, &explicit, Decay, 0.0, &[1.0], &options()).err().unwrap();
            let unknown = error.message.contains("unknown");
            assert_eq!(unknown, caps.accepts.explicit_table, "{name}: {}", error.message);
            let ode = build_ode(method, &MethodSettings::default(), Decay, 0.0, &[1.0], &options());
            assert_eq!(ode.is_err(), caps.needs_imex, "{name}");
        }
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
