//! Solver selection: the methods by name ([`Method`]), a scene's solver settings
//! ([`SolverSpec`]) and one constructor for every method ([`build`]).
//!
//! It sits between the integrators ([`crate::integrate`], [`crate::sundials`]) and their users
//! (analyses, the engine, library users): whoever needs an integrator names a method and gets
//! a boxed [`Integrator`] of the same shape, whatever implements it.

use crate::integrate::{ErrorKind, Extrapolation, ImexSystem, Integrator, Options, Radau5, Rodas5p, SolverError};
use crate::sundials::{self, ArkMethod, ArkSettings, CvodeMethod, CvodeSettings, DirkTable, ErkTable, Solver};
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

impl std::str::FromStr for Method {
    type Err = String;

    /// The method by its scene name (the one parser of method names: scenes and the CLI); the
    /// error names the valid ones.
    fn from_str(name: &str) -> Result<Self, String> {
        Self::ALL.iter().find(|(n, _)| *n == name).map(|(_, m)| *m).ok_or_else(|| {
            let names: Vec<&str> = Self::ALL.iter().map(|(n, _)| *n).collect();
            format!("\"{name}\" is not a method; use one of {}", names.join(", "))
        })
    }
}

impl Method {
    /// Whether the method is meant for stiff problems.
    pub fn is_stiff(self) -> bool {
        matches!(self, Method::CvodeBdf | Method::ArkodeDirk | Method::ArkodeImex | Method::Radau5 | Method::Rodas5p | Method::Extrapolation)
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
        MethodSettings { table: spec.table.clone(), explicit_table: spec.explicit_table.clone(), autonomous }
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
pub fn build<'s, S: ImexSystem + 's>(
    method: Method,
    settings: &MethodSettings,
    system: S,
    t0: f64,
    y0: &[f64],
    options: &Options,
) -> Result<Built<'s>, SolverError> {
    let ark = ArkSettings { deduce_implicit_rhs: true, ..ArkSettings::default() };
    let cvode = |method| CvodeSettings { method, stability_limit_detection: false };
    let tables = check_tables(method, settings).map_err(|message| SolverError {
        solver: method.name(),
        kind: ErrorKind::InvalidInput,
        t: t0,
        state: y0.to_vec(),
        flag: 0,
        message,
    })?;
    let integrator: Box<dyn Integrator + 's> = match method {
        Method::CvodeBdf => Box::new(Solver::cvode(system, cvode(CvodeMethod::Bdf), t0, y0, options)?),
        Method::CvodeAdams => Box::new(Solver::cvode(system, cvode(CvodeMethod::Adams), t0, y0, options)?),
        Method::ArkodeDirk => Box::new(Solver::arkstep(system, ArkMethod::Dirk(tables.implicit.unwrap_or_default()), ark, t0, y0, options)?),
        Method::ArkodeErk => Box::new(Solver::arkstep(system, ArkMethod::Erk(tables.explicit.unwrap_or_default()), ark, t0, y0, options)?),
        Method::ArkodeImex => {
            let (default_i, default_e) = sundials::default_imex_tables();
            let implicit = tables.implicit.unwrap_or(default_i);
            let explicit = tables.explicit.unwrap_or(default_e);
            Box::new(Solver::arkstep_imex(system, implicit, explicit, ark, t0, y0, options)?)
        }
        Method::Radau5 => Box::new(Radau5::new(system, t0, y0, options)?),
        Method::Rodas5p if settings.autonomous => Box::new(Rodas5p::new(system, t0, y0, options)?.autonomous()),
        Method::Rodas5p => Box::new(Rodas5p::new(system, t0, y0, options)?),
        Method::Extrapolation => Box::new(Extrapolation::new(system, t0, y0, options)?),
    };
    let tables = match method {
        Method::ArkodeDirk => vec![tables.implicit.unwrap_or_default().name().into()],
        Method::ArkodeErk => vec![tables.explicit.unwrap_or_default().name().into()],
        Method::ArkodeImex => {
            let (default_i, default_e) = sundials::default_imex_tables();
            vec![tables.implicit.unwrap_or(default_i).name().into(), tables.explicit.unwrap_or(default_e).name().into()]
        }
        _ => vec![],
    };
    Ok(Built { integrator, tables })
}

/// The Butcher tables a method asked for by name (None: its default).
struct Tables {
    implicit: Option<DirkTable>,
    explicit: Option<ErkTable>,
}

/// Resolves the table names of `settings` for `method`; an unknown name, or a table for a
/// method that takes none, is an error naming the field (made an
/// [`ErrorKind::InvalidInput`] by [`build`]).
fn check_tables(method: Method, settings: &MethodSettings) -> Result<Tables, String> {
    let invalid = |message: String| message;
    let dirk = |field: &str, name: &str| {
        DirkTable::from_name(name).ok_or_else(|| invalid(format!("{field}: unknown implicit table \"{name}\"; available: {}", DirkTable::names().collect::<Vec<_>>().join(", "))))
    };
    let erk = |field: &str, name: &str| {
        ErkTable::from_name(name).ok_or_else(|| invalid(format!("{field}: unknown explicit table \"{name}\"; available: {}", ErkTable::names().collect::<Vec<_>>().join(", "))))
    };
    let (table, explicit_table) = (settings.table.as_deref(), settings.explicit_table.as_deref());
    if explicit_table.is_some() && method != Method::ArkodeImex {
        return Err(invalid(format!("explicit_table: {} takes no explicit table (only arkode-imex does)", method.name())));
    }
    match method {
        Method::ArkodeDirk => Ok(Tables { implicit: table.map(|n| dirk("table", n)).transpose()?, explicit: None }),
        Method::ArkodeErk => Ok(Tables { implicit: None, explicit: table.map(|n| erk("table", n)).transpose()? }),
        Method::ArkodeImex => {
            let implicit = table.map(|n| dirk("table", n)).transpose()?;
            let paired = table.and_then(|n| ErkTable::from_name(&n.replace("_DIRK_", "_ERK_")));
            let explicit = match explicit_table {
                Some(n) => Some(erk("explicit_table", n)?),
                None => paired,
            };
            Ok(Tables { implicit, explicit })
        }
        _ if table.is_some() => Err(invalid(format!("table: {} takes no Butcher table (only the arkode methods do)", method.name()))),
        _ => Ok(Tables { implicit: None, explicit: None }),
    }
}
