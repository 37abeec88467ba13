//! The lab model's friction at the record's times and its exact derivatives with respect to
//! the varied parameters: CVODES' forward sensitivities, segment by segment.

use crate::analysis::lab::LabSolver;
use crate::integrate::{Options, SolverError, Task, Tolerance};
use crate::model::lab::LN_V;
use crate::model::{LabParameter, LabParametric, LabParams, Loading};
use crate::sundials::{SensitivitySettings, SensitivitySolver};

/// μ at each time and ∂μ/∂p_j (row-major: `dmu[i * m + j]`, m = `varied.len()`).
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionSensitivities {
    /// μ(t_i).
    pub mu: Vec<f64>,
    /// ∂μ(t_i)/∂p_j, row-major.
    pub dmu: Vec<f64>,
}

/// Integrates the lab model (quasi-static or with inertia) from steady sliding at the first segment's velocity through
/// `loading` with the sensitivities to `varied` (any of a, b_i, ln D_c,i, k, μ0), and returns
/// μ and ∂μ/∂p at `times` (non-decreasing, inside the loading). At least one varied parameter
/// other than μ0 is required (μ0 alone has no sensitivity equation). Every segment is integrated
/// on its own in local time, with the state and sensitivities carried across the jump.
pub fn friction_sensitivities(
    params: &LabParams,
    loading: &Loading,
    times: &[f64],
    varied: &[LabParameter],
    solver: &LabSolver,
) -> Result<FrictionSensitivities, (usize, SolverError)> {
    let n = params.dim();
    let m = varied.len();
    // Quasi-static, μ0 has no sensitivity equation: ∂μ/∂μ0 = 1 is added where μ is formed.
    // With inertia the measured friction is the state τ and μ0 moves the slider.
    let inertial = params.mass.is_some();
    let dynamic: Vec<LabParameter> =
        varied.iter().copied().filter(|p| inertial || *p != LabParameter::Mu0).collect();
    let md = dynamic.len();
    let v_first = loading.segments[0].velocity;
    let mut y = params.steady_state(v_first);
    let mut s = vec![0.0; n * md];
    for (j, p) in dynamic.iter().enumerate() {
        params.steady_state_parameter_derivative(v_first, *p, &mut s[j * n..(j + 1) * n]);
    }
    let mut out = FrictionSensitivities {
        mu: Vec::with_capacity(times.len()),
        dmu: Vec::with_capacity(times.len() * m),
    };
    let record = |y: &[f64], s: &[f64], out: &mut FrictionSensitivities| {
        out.mu.push(params.measured_friction(y));
        if let Some(it) = params.tau_index() {
            out.dmu.extend((0..md).map(|j| s[j * n + it]));
            return;
        }
        let mut jd = 0;
        for p in varied {
            let mut d = params.friction_parameter_derivative(y, *p);
            if *p != LabParameter::Mu0 {
                let column = &s[jd * n..(jd + 1) * n];
                d += params.a * column[LN_V];
                for (i, state) in params.states.iter().enumerate() {
                    d += state.b * column[1 + i];
                }
                jd += 1;
            }
            out.dmu.push(d);
        }
    };
    let options = Options::new(solver.rtol, Tolerance::Scalar(solver.atol));
    let system = LabParametric {
        params: params.clone(),
        v_lp: loading.segments[0].velocity,
        varied: dynamic.clone(),
    };
    let mut cvodes =
        SensitivitySolver::new(system, &SensitivitySettings::default(), 0.0, &y, &s, &options)
            .map_err(|e| (0, e))?;
    let mut next = 0;
    for (j, seg) in loading.segments.iter().enumerate() {
        let fail = |e| (j, e);
        if j > 0 {
            // A jump of V_lp: CVODE and the sensitivities restart from the carried state.
            cvodes.reinit_with(0.0, &y, &s, |system| system.v_lp = seg.velocity).map_err(fail)?;
        }
        let t0 = seg.t_start;
        let t1 = loading.segment_end(j);
        let last = j + 1 == loading.segments.len();
        let in_segment = |t: f64| t >= t0 && (t < t1 || (last && t <= t1));
        cvodes.set_stop_time(t1 - t0).map_err(fail)?;
        while next < times.len() && in_segment(times[next]) {
            let local = times[next] - t0;
            if local > 0.0 {
                cvodes.advance(local, Task::Normal).map_err(fail)?;
                record(cvodes.state(), cvodes.sensitivities(), &mut out);
            } else {
                record(&y, &s, &mut out);
            }
            next += 1;
        }
        if cvodes.t() < t1 - t0 {
            cvodes.advance(t1 - t0, Task::Normal).map_err(fail)?;
        }
        y.copy_from_slice(cvodes.state());
        s.copy_from_slice(cvodes.sensitivities());
    }
    Ok(out)
}
