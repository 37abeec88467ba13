//! The CLI summary of a report: one function per section, in the order they are printed.

use super::{CyclePhysical, CycleSection, ModelReport, ModelSection, Physical, Report};
use crate::analysis::continuation::ContinuationReport;
use crate::analysis::cycle::{CycleStatus, CycleValues};
use crate::analysis::hopf::HopfReport;
use crate::analysis::noise::NoiseReport;
use crate::analysis::shooting::{PeriodDoubling, PeriodicOrbit, ShootingReport};
use crate::analysis::time_series::{Event, Runaway, TimeSeriesReport};
use crate::paper::claims::Claim;
use crate::paper::{asymptotics, lyapunov};
use crate::scene::{OtherModel, CHOSEN_BY_SCENE};

impl Report {
    /// A readable summary for the terminal: each section the scene asked for, in a fixed
    /// order.
    pub fn summary(&self) -> String {
        let si = self.scene["model"]["dimensional"]["unit_system"] == "SI";
        let sections = [
            Some(self.model_and_solver()),
            self.hopf.as_ref().map(|h| hopf(h, self.model.epsilon)),
            self.cycle.as_ref().map(|c| cycle(c, &self.model)),
            self.physical.as_ref().map(physical),
            self.time_series.as_ref().map(|t| time_series(t, self.events.as_deref(), si)),
            self.runaway.as_ref().map(|r| runaway(r, self.time_series.as_ref(), si)),
            self.forcing.as_ref().map(|f| {
                format!(
                    "forcing: amplitude {:e} A, period {:e} (units of D_c/v0); {}\n",
                    f.amplitude, f.period, f.statement
                )
            }),
            self.cycle.as_ref().and_then(|c| c.physical.as_ref()).map(|p| cycle_physical(p, si)),
            Some(self.warnings.iter().map(|w| format!("warning: {w}\n")).collect()),
            self.asymptotics.as_ref().map(asymptotics::summary),
            self.lyapunov.as_ref().map(lyapunov::summary),
            self.shooting.as_ref().map(shooting),
            self.continuation.as_ref().map(continuation),
            self.noise.as_ref().map(NoiseReport::summary),
            self.paper.as_deref().map(paper),
        ];
        sections.into_iter().flatten().collect()
    }

    /// The scene's model, then the solver (with why it runs, where the scene did not choose it
    /// all) and its statistics.
    fn model_and_solver(&self) -> String {
        let (solver, stats) = (&self.solver, &self.solver.stats);
        let why = match solver.chosen_by.as_str() {
            CHOSEN_BY_SCENE => String::new(),
            why => format!(" ({why})"),
        };
        format!(
            "{}solver {} ({}), rtol {:e}{why}, SUNDIALS {}; {} steps, {} RHS, {} Jacobians, {:.3} s\n",
            model(&self.name, &self.model),
            solver.method.name(),
            solver.integrator,
            solver.rtol,
            self.sundials_version,
            stats.steps,
            stats.rhs_evals + stats.rhs_evals_explicit,
            stats.jac_evals,
            self.wall_time_s
        )
    }
}

impl ModelReport {
    /// A readable summary for the terminal.
    pub fn summary(&self) -> String {
        let model = match &self.model {
            OtherModel::SaddleNode { params, x0 } => {
                format!("saddle-node, μ0 = {}, r = {}, x(0) = {x0}", params.mu0, params.r)
            }
            OtherModel::VanDerPol { params, initial } => {
                format!("van der Pol, β = {}, a = {}, start {initial:?}", params.beta, params.a)
            }
        };
        format!("scene {}: {model}; {:.3} s\n{}", self.name, self.wall_time_s, self.noise.summary())
    }
}

/// The scene `name`'s model: γ (or none), ξ, ε, the laws and the radiation damping.
fn model(name: &str, m: &ModelSection) -> String {
    format!(
        "scene {}: {}, ξ = {}, ε = {}, friction {}, {} law{}\n",
        name,
        if m.inertia { format!("γ = {:e}", m.gamma) } else { "quasi-dynamic (no inertia)".into() },
        m.xi,
        m.epsilon,
        m.friction,
        m.state_law.name(),
        if m.radiation_damping > 0.0 {
            format!(", radiation damping η = {:e}", m.radiation_damping)
        } else {
            String::new()
        }
    )
}

/// The threshold and the verdict on the fixed point; with ε < 0 (b < a) the fault is named
/// velocity-strengthening, the reason it is stable.
fn hopf(h: &HopfReport, epsilon: f64) -> String {
    format!(
        "hopf: ε_c = {:.12}, ω_c = {:.9}, period_c = {:.9} (2π/√ξ = {:.9}); {}\n",
        h.epsilon_c,
        h.omega_c,
        h.period_c,
        h.period_c_large_gamma,
        if h.above_threshold {
            "above threshold: fixed point unstable"
        } else if epsilon < 0.0 {
            "velocity-strengthening (ε = b/a − 1 < 0, b < a): fixed point stable, no stick-slip"
        } else {
            "below threshold: fixed point stable"
        }
    )
}

/// The cycle by its status: the periodic cycle's values, a period-n orbit's cycles, the
/// fixed point, or how far an unconverged run got.
fn cycle(c: &CycleSection, m: &ModelSection) -> String {
    match (c.status, &c.values) {
        (CycleStatus::Periodic, Some(v)) => periodic(c, v, m),
        (CycleStatus::PeriodN, _) => period_n(c),
        (CycleStatus::FixedPoint, _) => {
            "cycle: none; the oscillation dies out and the fixed point is stable\n".into()
        }
        _ => format!(
            "cycle: NOT converged after {} cycles / t = {:.6e}{} (see cycle.last_cycles)\n",
            c.cycles_computed,
            c.time_integrated,
            c.stopped_by.map_or(String::new(), |l| format!(", stopped by the limit {l}"))
        ),
    }
}

/// The periodic cycle's values `v`, each with its estimated error.
fn periodic(c: &CycleSection, v: &CycleValues, m: &ModelSection) -> String {
    let mut s = format!(
        "cycle: periodic after {} cycles (mean of the last {}; ± estimated error: transient \
         left plus cycle-to-cycle noise)\n",
        c.cycles_computed, c.cycles_used,
    );
    let e = c.error_estimate;
    let pm = |x: Option<f64>| x.map_or(String::new(), |x| format!(" ± {x:.1e}"));
    s += &format!(
        "  period          {:.10}{}\n  t0              {:.10}{}\n",
        v.main.period,
        pm(e.map(|e| e.period)),
        v.main.t0,
        pm(e.map(|e| e.t0))
    );
    let hw = pm(e.and_then(|e| e.slip_half_width));
    match v.main.slip_half_width {
        Some(w) if m.inertia => {
            s += &format!("  slip half-width {:.6e}{hw} (× γ = {:.6})\n", w, w * m.gamma)
        }
        Some(w) => s += &format!("  slip half-width {:.6e}{hw}\n", w),
        None => {}
    }
    s += &format!(
        "  v_max           {:.10e}{} (ln {:.9})\n  v_min           {:.6e}{}\n  u, θ at v_max   \
         {:.9}, {:.9}\n  slip            {:.9}{}\n",
        v.main.v_max,
        pm(e.map(|e| e.v_max)),
        v.main.ln_v_max,
        v.main.v_min,
        pm(e.map(|e| e.v_min)),
        v.extremes.u_at_v_max,
        v.extremes.theta_at_v_max,
        v.main.slip,
        pm(e.map(|e| e.slip))
    );
    s
}

/// A period-n orbit: its total period, then each cycle.
fn period_n(c: &CycleSection) -> String {
    let mut s = format!(
        "cycle: period-{} orbit, total period {:.10}\n",
        c.orbit.len(),
        c.orbit_period.unwrap_or(0.0)
    );
    for (i, o) in c.orbit.iter().enumerate() {
        s += &format!(
            "  cycle {}: period {:.10}, ln v_max {:.9}\n",
            i + 1,
            o.main.period,
            o.main.ln_v_max
        );
    }
    s
}

/// The cycle's durations in the scene's `units`.
fn physical(p: &Physical) -> String {
    format!("  in {}: period {:.6}, t0 {:.6}\n", p.time_unit, p.period, p.t0)
}

/// Where the time series stopped at its runaway threshold, or that it did not reach it.
fn runaway(r: &Runaway, series: Option<&TimeSeriesReport>, si: bool) -> String {
    let physical = r.physical.as_ref();
    let threshold = format!(
        "v = {:e}{}",
        r.v_threshold,
        physical.map_or(String::new(), |p| format!(
            " (V = {:e}{})",
            p.velocity_threshold,
            unit(si, "m/s", "velocity")
        ))
    );
    match &r.at {
        Some(a) => format!(
            "runaway: {threshold} reached at t = {:.12e}{}, slip {:.6e}, θ {:.6e} (the run stops there)\n",
            a.t,
            physical.and_then(|p| p.t).map_or(String::new(), |t| format!(" ({t:.12e}{})", unit(si, "s", "time"))),
            a.slip,
            a.theta
        ),
        None => format!(
            "runaway: {threshold} not reached by t_max{}\n",
            series.map_or(String::new(), |s| format!(" (v = {:e} there)", s.final_state[1]))
        ),
    }
}

/// The time series's extent and event count, then its last event.
/// A dimensional value's unit: its SI name where the scene declares SI units, "in the
/// input's … unit" otherwise.
fn unit(si: bool, si_name: &str, quantity: &str) -> String {
    if si {
        format!(" {si_name}")
    } else {
        format!(" in the input's {quantity} unit")
    }
}

fn time_series(t: &TimeSeriesReport, events: Option<&[Event]>, si: bool) -> String {
    let mut s = format!(
        "time series: t = 0 … {:e}{}, {} rows ({} steps), {} events (episodes above v = 1 \
         peaking above v = {}{}){}{}\n",
        t.t_max,
        t.t_max_physical.map_or(String::new(), |p| format!(" ({p:e}{})", unit(si, "s", "time"))),
        t.rows,
        t.steps,
        t.event_count,
        t.event_threshold,
        t.event_threshold_physical
            .map_or(String::new(), |p| format!(", {p:e}{}", unit(si, "m/s", "velocity"))),
        if events.is_some_and(|e| e.first().is_some_and(|e| e.started_before_run)) {
            ", the first under way at t = 0"
        } else {
            ""
        },
        if t.in_event_at_end { " (one more under way at the end)" } else { "" }
    );
    if let Some(last) = events.and_then(|e| e.last()) {
        let e = &last.values;
        s += &format!(
            "  last event: peak at t = {:.10e}, v_max {:.6e}, slip {:.6e}, stress drop {:.6e}, \
             recurrence {}\n",
            e.t_peak,
            e.v_max,
            e.slip,
            e.stress_drop,
            e.recurrence.map_or("-".to_string(), |r| format!("{r:.10e}"))
        );
    }
    s
}

/// The converged cycle in the dimensional input's units, named when the scene declares them
/// SI.
fn cycle_physical(p: &CyclePhysical, si: bool) -> String {
    if si {
        return format!(
            "  in SI units (cycle.physical): v_max {:.6e} m/s, v_min {:.6e} m/s, slip {:.6e} m, \
             stress drop {:.6e} Pa\n",
            p.v_max, p.v_min, p.slip, p.stress_drop
        );
    }
    format!(
        "  in the input's units (cycle.physical): v_max {:.6e}, v_min {:.6e}, slip {:.6e}, \
         stress drop {:.6e}\n",
        p.v_max, p.v_min, p.slip, p.stress_drop
    )
}

/// The shooting orbit (or why there is none), then the period doubling.
fn shooting(r: &ShootingReport) -> String {
    let mut s = match &r.orbit {
        Some(o) => shooting_orbit(o),
        None => format!(
            "shooting: NOT converged: {}\n",
            r.failure.as_ref().map_or("?".to_string(), ToString::to_string)
        ),
    };
    if let Some(pd) = &r.period_doubling {
        s += &period_doubling(pd);
    }
    s
}

/// The converged orbit: its values, section point and Floquet multipliers.
fn shooting_orbit(o: &PeriodicOrbit) -> String {
    let mut s = format!(
        "shooting: converged in {} iterations (residual {:.1e}); period {:.10}, t0 {:.10}, \
         ln v_max {:.9}\n",
        o.newton_iterations, o.residual, o.period, o.t0, o.ln_v_max
    );
    s += &format!(
        "  section point (u, v, θ) = ({:.10}, 1, {:.10})\n",
        o.section_point[0], o.section_point[2]
    );
    let mu: Vec<String> = o
        .nontrivial()
        .iter()
        .map(|m| {
            if m.im == 0.0 {
                format!("{:.6e}", m.re)
            } else {
                format!("{:.6e}{:+.6e}i", m.re, m.im)
            }
        })
        .collect();
    s += &format!(
        "  Floquet multipliers: trivial 1{:+.1e}, others {} ({})\n",
        o.multipliers[0].re - 1.0,
        mu.join(", "),
        match o.stable {
            Some(true) => "stable".to_string(),
            Some(false) => "unstable".to_string(),
            None => format!("stability unknown: {}", o.multipliers_note.as_deref().unwrap_or("")),
        }
    );
    s
}

fn period_doubling(pd: &PeriodDoubling) -> String {
    format!(
        "  period doubling: multiplier {:.6}; {}\n",
        pd.multiplier,
        match &pd.doubled {
            Some(d) => format!("doubled orbit of period {:.10} ({})", d.period, pd.note),
            None => format!("doubled orbit not found ({})", pd.note),
        }
    )
}

/// The continuation's range and its first and last periods, where it stopped, its period
/// doublings and the period per decade of γ.
fn continuation(c: &ContinuationReport) -> String {
    let mut s = format!(
        "continuation in {} from {} to {}: {} points{}\n",
        c.parameter.name(),
        c.from,
        c.to,
        c.points.len(),
        if c.completed { String::new() } else { String::from(" (stopped)") }
    );
    if let (Some(first), Some(last)) = (c.points.first(), c.points.last()) {
        s += &format!(
            "  period {:.8} at {} … {:.8} at {}\n",
            first.orbit.period, first.value, last.orbit.period, last.value
        );
    }
    if let Some(stop) = &c.stopped {
        s += &format!(
            "  stopped after {} (failed at {}): {}\n",
            stop.last_value, stop.failed_at, stop.reason
        );
    }
    for f in &c.flips {
        s += &format!("  period doubling between {} and {}\n", f.from, f.to);
    }
    if let Some(d) = c.period_per_decade.first() {
        s += &format!(
            "  period per decade of γ: {:.4} (fit over log10 γ = {} … {})\n",
            d.slope, d.log10_gamma_from, d.log10_gamma_to
        );
    }
    s
}

/// The paper's claims against ours, one line each.
fn paper(claims: &[Claim]) -> String {
    let mut s = String::from("paper's claims:\n");
    for c in claims {
        let relative =
            c.relative_difference.map_or(String::new(), |r| format!(" ({:+.1} %)", 100.0 * r));
        s += &format!(
            "  {:<9} {} — paper {}, ours {:.6}{relative}\n",
            c.verdict, c.claim, c.reference, c.ours
        );
    }
    s
}
