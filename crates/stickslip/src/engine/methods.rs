//! How the engine runs each method on the spring-slider: one row per [`Method`]
//! ([`EngineSettings::of`]), one `match` without a wildcard arm, so that a method added to
//! stickslip-ode does not compile here until its row is written. The ODE crate says what each
//! method accepts ([`Method::capabilities`]); this table says which of those options the
//! engine sets, and why (the measurements are in the field docs, the rows and the comments of
//! `integrator_with_max_step` in src/engine.rs, which reads the table).

use crate::solver::Method;

/// The engine's per-method settings on the spring-slider (src/engine.rs gives the reasons and
/// measurements).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineSettings {
    /// [`Options::jacobian_max_age`]: `Some(1)`, a fresh Jacobian at every step, for the
    /// stiff methods with a Newton iteration whose Jacobian would otherwise age.
    ///
    /// [`Options::jacobian_max_age`]: crate::integrate::Options::jacobian_max_age
    pub jacobian_max_age: Option<i64>,
    /// [`MethodSettings::deduce_implicit_rhs`] (ARKStep's implicit methods).
    ///
    /// [`MethodSettings::deduce_implicit_rhs`]: crate::solver::MethodSettings::deduce_implicit_rhs
    pub deduce_implicit_rhs: bool,
    /// ARKStep DIRK's tighter Newton iteration: `nonlin_conv_coef` = 1000 u / rtol within
    /// [1e-3, 0.1] and `max_nonlin_iters` = 5.
    pub dirk_newton: bool,
    /// ln v's error weighed absolutely at this fraction of rtol ([`Options::error_scales`]):
    /// a tenth of rtol for CVODE BDF, Radau5 and Rodas5P, rtol for Extrapolation and ARKStep
    /// DIRK; see `engine`.
    ///
    /// [`Options::error_scales`]: crate::integrate::Options::error_scales
    pub absolute_ln_v: Option<f64>,
    /// [`Options::max_conv_fails`] per step, where the method's default stops a run (CVODE
    /// and ARKStep DIRK with ln v weighed absolutely); see `engine`.
    ///
    /// [`Options::max_conv_fails`]: crate::integrate::Options::max_conv_fails
    pub max_conv_fails: Option<i32>,
    /// Stop a run with an error once 10 000 steps of one size in a row leave u unchanged while
    /// du/dt ≠ 0 (ARKStep IMEX deep on a stick, where the round-off of its explicit first stage
    /// holds its steps below u's spacing; see `engine`).
    pub stop_when_u_freezes: bool,
    /// Uses the Jacobian of the variational equations only in its Newton iteration, so the
    /// engine gives it the simplified one without the coupling block ∂(JΦ)/∂y (Radau5: its
    /// Newton iteration failed with that block, entries ~1e29, in the ageing and PRZ laws'
    /// sticks at γ = 1e8; Rodas5P and extrapolation need the exact one, and CVODE measured no
    /// difference; see `engine` and src/model/variational.rs).
    pub variational_newton_jacobian: bool,
    /// With radiation damping, the rtol below which its default table falls to order 2 on
    /// the quasi-static slip that damping creates (ARKStep's SDIRK-5-3-4 has stage order 1),
    /// so that a cycle costs ~rtol^(-1/2) steps: the stress grid's known limit
    /// (docs/robustness.md).
    pub damping_rtol_floor: Option<f64>,
}

impl EngineSettings {
    /// How the engine runs `method`: the one table of per-method engine settings.
    pub const fn of(method: Method) -> Self {
        let plain = EngineSettings {
            jacobian_max_age: None,
            deduce_implicit_rhs: false,
            dirk_newton: false,
            absolute_ln_v: None,
            max_conv_fails: None,
            stop_when_u_freezes: false,
            variational_newton_jacobian: false,
            damping_rtol_floor: None,
        };
        // A fresh Jacobian at every step, see `engine`.
        let fresh = EngineSettings { jacobian_max_age: Some(1), ..plain };
        match method {
            Method::CvodeBdf => {
                EngineSettings { absolute_ln_v: Some(0.1), max_conv_fails: Some(20), ..fresh }
            }
            Method::CvodeAdams => plain,
            // With `jacobian_max_age` = 1 stickslip-ode's arkode-dirk applies every step-size
            // change and rebuilds its Newton matrix at every stage (its `dirk_settings`), for
            // what was measured here. The window: in the arrest after a slip, where the error
            // estimate sits on a floor that does not fall with h, h stalled there: the DRR
            // work–precision cell γ = 1e8, rtol 1e-11 held h = 3.08e-13 for 192 523 accepted
            // steps of one cycle (270 214 steps in 3 cycles; 29 576 with these settings). The
            // stages: with the window alone two damped laws-grid cells ended in 20 error-test
            // failures at an estimate constant to 5 digits from h = 0.13 to 4.9e-11, 10/3 of
            // the offset measured at y_n (PRZ, γ = 1e6, ξ = 0.7, ε = 10, η = 0.1, rtol 1e-6:
            // w 5.4e-6, 0.56 of its weight, off the manifold after a step over which w fell by
            // 0.8, so that the stiff rate γ²e^(−w) at its last stage was 2.3× the one of the
            // Jacobian taken at the step's start); docs/robustness.md, "Why the damped cells
            // fail with every step change applied".
            Method::ArkodeDirk => EngineSettings {
                deduce_implicit_rhs: true,
                dirk_newton: true,
                absolute_ln_v: Some(1.0),
                max_conv_fails: Some(20),
                damping_rtol_floor: Some(1e-8),
                ..fresh
            },
            Method::ArkodeImex => {
                EngineSettings { deduce_implicit_rhs: true, stop_when_u_freezes: true, ..fresh }
            }
            Method::ArkodeErk => plain,
            Method::Radau5 => EngineSettings {
                absolute_ln_v: Some(0.1),
                variational_newton_jacobian: true,
                ..fresh
            },
            Method::Rodas5p => EngineSettings { absolute_ln_v: Some(0.1), ..plain },
            Method::Extrapolation => EngineSettings { absolute_ln_v: Some(1.0), ..plain },
        }
    }
}
