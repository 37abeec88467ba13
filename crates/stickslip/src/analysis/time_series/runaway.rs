//! The report's `runaway` section: where a time series with a runaway threshold
//! (`time_series.runaway_velocity`) stopped, the time the slip rate reached it located by root
//! finding on ln v in the integrator's dense output. The result of a run under the no-healing
//! law, which has no cycle: the block runs away (docs/state-laws.md).

use crate::model::drr::{Drr, THETA, U, W};
use crate::model::scales::{dimensionless_friction, PhysicalScales};
use crate::model::Friction;
use serde::Serialize;

/// The "runaway" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Runaway {
    /// The threshold slip rate v (dimensionless, units of v0).
    pub v_threshold: f64,
    /// Whether v reached the threshold before t_max.
    pub reached: bool,
    /// Where it was reached (absent when it was not).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub at: Option<RunawayPoint>,
    /// The threshold and, when reached, the point in the input's units (dimensional input).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub physical: Option<RunawayPhysical>,
}

/// The state where v reached the threshold (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunawayPoint {
    /// The time v reached the threshold (units of D_c/v0, from the start t = 0).
    pub t: f64,
    /// v there (the threshold, to the root finder's accuracy on ln v).
    pub v_reached: f64,
    /// u there.
    pub u: f64,
    /// θ there.
    pub theta: f64,
    /// Slip since the start, u − u(0) + t (units of D_c).
    pub slip: f64,
    /// The dimensionless friction φ = θ + f(v) there (units of a; see
    /// [`dimensionless_friction`]).
    pub stress: f64,
}

/// The runaway in the input's units (SI: s, m/s, m, Pa).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunawayPhysical {
    /// The threshold slip rate (velocity units).
    pub velocity_threshold: f64,
    /// The time it was reached (time units).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
    /// The slip since the start (length units).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip: Option<f64>,
    /// The state Θ there (time units; logarithmic and QDYN friction laws only, where it is a
    /// finite double).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub state: Option<f64>,
    /// The shear stress relative to steady sliding at v0, aσ·φ (stress units).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shear_stress_change: Option<f64>,
}

impl Runaway {
    /// The section for a run with threshold `v_threshold` that reached it at absolute time `t`
    /// in state `y` (None: not reached by t_max), from the start u(0) = `u0`.
    pub fn new(
        drr: &Drr,
        scales: Option<&PhysicalScales>,
        v_threshold: f64,
        reached: Option<(f64, [f64; 3])>,
        u0: f64,
    ) -> Self {
        let at = reached.map(|(t, y)| RunawayPoint {
            t,
            v_reached: y[W].exp(),
            u: y[U],
            theta: y[THETA],
            slip: y[U] - u0 + t,
            stress: dimensionless_friction(drr.params(), y[THETA], y[W]),
        });
        // Θ means θ = (b/a) ln(v0Θ/D_c) only under these laws (as for `initial.state`).
        let has_state = matches!(
            drr.params().friction,
            Friction::Log | Friction::CutOff { .. } | Friction::Regularised { .. }
        );
        let physical = scales.map(|s| RunawayPhysical {
            velocity_threshold: s.velocity(v_threshold),
            t: at.map(|a| s.time(a.t)),
            slip: at.map(|a| s.slip(a.slip)),
            // Absent where Θ = (D_c/v0)·e^{θa/b} is not a double (θ far above 0).
            state: at
                .filter(|_| has_state)
                .map(|a| s.state_from_theta(a.theta))
                .filter(|x| x.is_finite()),
            shear_stress_change: at.map(|a| s.shear_stress_change(a.stress)),
        });
        Self { v_threshold, reached: at.is_some(), at, physical }
    }
}
