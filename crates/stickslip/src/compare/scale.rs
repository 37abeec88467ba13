//! Whether a user's trajectory fits the scene at all, decided before or while the reference
//! runs, so that a file in other units or offset fails at once (exit 2) with its likely cause,
//! and the reference's memory stays bounded whatever the file.
//!
//! - Before the reference: a quasi-dynamic scene has no u but the force balance's,
//!   u = −(Φ(v, θ) + η v)/ξ; a first sample off it by more than the tolerance (relative to
//!   max(|u|, 1)) is an offset u or values in other units. An inertial scene's first sample
//!   may be off it, but not by more than double precision can follow
//!   ([`first_sample_fits`]).
//! - While the reference runs: it may have at most [`event_budget`] events (v ≥ 1) and
//!   [`MAX_REFERENCE_STEPS`] steps over the file's span. Ten times the file's own events means
//!   the time column is not in the scene's time unit (an SI file against a dimensionless
//!   scene spans thousands of the scene's cycles).

use super::input::Trajectory;
use super::quantity::within;
use crate::model::Drr;
use crate::scene::Scene;

/// The most steps a reference run may take over the file's span (its steps are kept to locate
/// its events: about 100 bytes each).
pub const MAX_REFERENCE_STEPS: usize = 4_000_000;

/// The most events (v ≥ 1) the reference may have over the file's span, given the file's own
/// `user_events`: 10·user_events + 10.
pub fn event_budget(user_events: usize) -> usize {
    10 * user_events + 10
}

/// Why a user's file does not fit the scene (exit 2); each message names the columns and the
/// likely cause.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneMismatch {
    /// A QDYN output (SI units) against a scene without physical scales.
    #[error("a QDYN output file is in SI units: compare it against the qdyn.in that made it, or a scene with model.dimensional (docs/from-qdyn.md)")]
    NotPhysical,
    /// A periodically loaded scene: the reference runs the unforced model.
    #[error("the scene is periodically loaded (model.periodic_loading): the reference trajectory runs the unforced model; compare its events with `stickslip run` (time_series) instead")]
    Forced,
    /// A QDYN output against an inertial scene.
    #[error("QDYN's spring-block is quasi-dynamic, so u is known only from its force balance: compare its output against a scene with \"inertia\": false (a qdyn.in maps to one)")]
    Inertial,
    /// A QDYN output against a scene that does not fix μ's absolute level.
    #[error("the file's tau column is the absolute σμ: the scene needs μ's level (model.dimensional.mu0 and v_ref, or the cut-off law's mu_star)")]
    NoFrictionLevel,
    /// A QDYN sample whose τ is not the scene's σμ at its V and Θ.
    #[error("{at}: tau = {file} Pa, but the scene's friction at this sample's V = {v} m/s and theta = {state} s gives σμ = {scene} Pa: the file was made with other friction parameters than the scene (a, b, μ*, V*, V1, V2, σ, the law) or in other units")]
    Stress {
        /// Where the sample is.
        at: String,
        /// V there (m/s).
        v: f64,
        /// Θ there (s).
        state: f64,
        /// The file's τ (Pa).
        file: f64,
        /// The scene's σμ (Pa).
        scene: f64,
    },
    /// A quasi-dynamic scene's first sample off the force balance.
    #[error("{at}: the first sample breaks the scene's force balance: column u = {u}, where the quasi-dynamic balance u = −(Φ(v, θ) + η v)/ξ gives {balanced} at its v = {v} and theta = {theta}; u is likely offset (u = δ/D_c − t from the scene's start, not the slip from 0) or the columns are in other units than the scene's (SI values against a dimensionless scene?)")]
    ForceBalance {
        /// Where the sample is.
        at: String,
        /// The file's u.
        u: f64,
        /// The balance's u.
        balanced: f64,
        /// The file's v.
        v: f64,
        /// The file's θ.
        theta: f64,
    },
    /// An inertial scene's first sample too far off the force balance.
    #[error("{at}: the first sample's force imbalance ξ|u + (Φ(v, θ) + η v)/ξ| = {off:.3e} (column u = {u}, balanced at {balanced} for its v = {v} and theta = {theta}) would drive ln v by as much, beyond double precision's range (|ln v| < {max}): the columns are likely in other units than the scene's (SI values against a dimensionless scene?) or u is offset", max = MAX_IMBALANCE)]
    Imbalance {
        /// Where the sample is.
        at: String,
        /// The file's u.
        u: f64,
        /// The balance's u.
        balanced: f64,
        /// The file's v.
        v: f64,
        /// The file's θ.
        theta: f64,
        /// ξ|G|.
        off: f64,
    },
    /// The reference has far more events than the file over the same span.
    #[error("over the file's span t = {start} … {end} (its {user_events} events), the scene's model has more than {events} events (v ≥ 1) by t = {at}: the t column is likely in other units than the scene's time (D_c/v0 for a dimensionless scene: SI seconds against a dimensionless scene?), or v and theta are (v = V/v0, theta = (b/a) ln(v0 Θ/D_c))")]
    TooManyEvents {
        /// The file's first time.
        start: f64,
        /// Its last.
        end: f64,
        /// The file's complete events.
        user_events: usize,
        /// The budget exceeded.
        events: usize,
        /// The reference's time when it was exceeded.
        at: f64,
    },
    /// The reference needs too many steps over the file's span.
    #[error("the scene's model needs more than {steps} steps by t = {at} of the file's span t = {start} … {end}: either the file spans far more of the scene's time than it seems (t in other units than the scene's?), or it is too long to compare at once (compare a shorter stretch)")]
    TooManySteps {
        /// The file's first time.
        start: f64,
        /// Its last.
        end: f64,
        /// The budget exceeded.
        steps: usize,
        /// The reference's time when it was exceeded.
        at: f64,
    },
}

/// The largest force imbalance ξ|G| = |ξu + Φ + ηv| a first sample may have: the inertial
/// arrest drives ln v by that much (towards −(ξu + θ) for the paper's law), and e^700 is near
/// the end of double precision's range (e^±708).
pub const MAX_IMBALANCE: f64 = 700.0;

/// Refuses a periodically loaded scene, then checks the first sample against the scene's force balance G = u + (Φ(v, θ) + η v)/ξ: a
/// quasi-dynamic scene must be on it (within the tolerance, relative to max(|u|, 1)); an
/// inertial scene's start may be off it, by at most [`MAX_IMBALANCE`] in ξG.
pub fn first_sample_fits(
    scene: &Scene,
    user: &Trajectory,
    tolerance: f64,
) -> Result<(), SceneMismatch> {
    if scene.loading.is_some() {
        return Err(SceneMismatch::Forced);
    }
    let params = scene.params;
    let [u, v, theta] = user.y[0];
    let balanced = -Drr::new(params).strength(&[0.0, v.ln(), theta]).value / params.xi;
    let off = (u - balanced).abs();
    let at = user.origin[0].clone();
    if params.inertia && !within(params.xi * off, MAX_IMBALANCE) {
        return Err(SceneMismatch::Imbalance { at, u, balanced, v, theta, off: params.xi * off });
    }
    if params.inertia || off <= tolerance * u.abs().max(1.0) {
        return Ok(());
    }
    Err(SceneMismatch::ForceBalance { at, u, balanced, v, theta })
}
