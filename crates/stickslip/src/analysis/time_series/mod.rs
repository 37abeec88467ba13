//! A run of fixed length from t = 0 (the transient included), in absolute time, streamed row
//! by row to a [`SeriesSink`], with a catalogue of its events (slip episodes).
//!
//! The integration runs on a [`Clock`]: its local time is re-based whenever the steps fall
//! below what the local clock resolves (and after each event's peak for integrators whose
//! re-base is an exact time shift, as the cycle analysis does), and the absolute time is the
//! clock's epoch plus the local time, kept as an unevaluated sum of two doubles ([`Time`]).
//! Every absolute time written or reported is that sum rounded once, so it carries no error
//! from the length of the run: at γ = 1e8 the arrest's steps of 1e-17 add up exactly however
//! many cycles pass. Durations (an event's duration, its recurrence) are differences of such
//! sums, exact to ~1e-30 relative before their own rounding.
//!
//! A row's time is a double, and near t = 1000 doubles are 1.1e-13 apart while the arrest
//! after a slip at γ = 1e8 (or the quasi-dynamic model at crustal damping) takes steps far
//! below that. A step whose end rounds to the previous row's time is therefore not written
//! (counted in `merged_rows`), so that the rows' times increase strictly, as readers of a
//! trajectory (e.g. `compare --against`) require.
//!
//! Events are located on the state as in the cycle analysis: an episode starts where v rises
//! through 1 (the loading velocity) and ends where it falls back through it (crossings of
//! w = 0, refined on the integrator's dense output); its peak is the largest maximum of w
//! inside it (where the dense output's dw/dt changes sign). An episode is an event when its
//! peak exceeds `event_threshold` (e.g. 100·V_pl, or QDYN's V_TH): creep around steady sliding
//! and slow transients are not events, and every event's slip exceeds the loading's over it
//! (v > 1 throughout), so its stress drop is positive. A run that starts with v above 1 is
//! inside an episode from t = 0: if its peak exceeds the threshold it is catalogued, flagged
//! `started_before_run` (its start, slip, duration and stress drop count from t = 0). An event
//! still open at t_max is not catalogued (`in_event_at_end`).
//!
//! With a runaway threshold (`runaway_v`) the run ends where ln v rises through it,
//! located like the events' crossings (root finding on w in the dense output), and the
//! outcome's [`Runaway`] gives the time: the result under the no-healing law, whose slip rate
//! runs away.

pub mod options;
pub mod runaway;
pub mod sink;

pub use options::{Sampling, TimeSeriesOptions};
pub use runaway::Runaway;
pub use sink::{DiscardSink, SeriesCollector, SeriesSink, TeeSink};

use super::AnalysisError;
use crate::integrate::{Clock, Integrator, OdeSystem, Time};
use crate::model::drr::{Drr, THETA, U, W};
use crate::model::scales::{dimensionless_friction, PhysicalScales};
use crate::numerics::events;
use serde::Serialize;

/// How the analysis runs (dimensionless).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSeriesSettings {
    /// End of the run (units of D_c/v0); the run starts at t = 0.
    pub t_max: f64,
    /// Which rows to write.
    pub sampling: Sampling,
    /// The peak slip rate v an episode of v above 1 must exceed to be an event.
    pub event_threshold: f64,
    /// Fail after this many integrator steps.
    pub max_steps: u64,
    /// The integrator's (rtol, atol) on w = ln v, to judge where a re-base is safe.
    pub w_tolerance: (f64, f64),
    /// The slip rate v (units of v0) at which the run stops before t_max (the runaway
    /// threshold), if any.
    pub runaway_v: Option<f64>,
}

/// The dimensionless columns, in order: the first four are what `compare --against` reads.
pub const COLUMNS: [&str; 7] = ["t", "u", "v", "theta", "ln_v", "slip", "stress"];

/// The physical columns that follow [`COLUMNS`] with dimensional input: t, v, slip and the
/// shear stress relative to steady sliding at v0 ([`PhysicalScales::shear_stress_change`]).
pub const PHYSICAL_COLUMNS: [&str; 4] = ["t_phys", "v_phys", "slip_phys", "stress_phys"];

/// The columns that follow [`PHYSICAL_COLUMNS`] when the scene gives the absolute friction
/// level (σ with μ0 at V_ref, the cut-off law's μ*, or the regularised law): the shear stress τ = σμ and the friction coefficient μ.
pub const ABSOLUTE_COLUMNS: [&str; 2] = ["tau_phys", "mu"];

/// One event's quantities (dimensionless, or in physical units in [`Event::physical`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EventValues {
    /// Absolute time of the upward crossing of v = 1 (0 for an event under way at the
    /// start, [`Event::started_before_run`]).
    pub t_start: f64,
    /// Absolute time of the slip-rate maximum.
    pub t_peak: f64,
    /// Absolute time of the downward crossing of v = 1.
    pub t_end: f64,
    /// The largest slip rate.
    pub v_max: f64,
    /// Slip from t_start to t_end: ∫v dt = Δu + duration.
    pub slip: f64,
    /// t_end − t_start.
    pub duration: f64,
    /// Drop of the spring stress from t_start to t_end, ξ·(u(t_end) − u(t_start)) in units
    /// of A = aσ (k·D_c·Δu physical, [`PhysicalScales::stress_drop`]); under periodic loading
    /// the spring's alone, without the change of the periodic load.
    pub stress_drop: f64,
    /// Time since the previous event's peak (null for the first event).
    pub recurrence: Option<f64>,
}

/// One entry of the event catalogue.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Event {
    /// Dimensionless quantities (times in D_c/v0, slip in D_c, stress in A, v in v0).
    #[serde(flatten)]
    pub values: EventValues,
    /// The same keys in the input's units, with dimensional input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub physical: Option<EventValues>,
    /// Whether the event was under way at t = 0 (the run started with v above 1): its start
    /// is the run's, and its slip, duration and stress drop count from t = 0 only.
    pub started_before_run: bool,
}

/// The "time_series" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimeSeriesReport {
    /// End of the run (dimensionless).
    pub t_max: f64,
    /// End of the run in the input's time unit, with dimensional input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t_max_physical: Option<f64>,
    /// Which rows were written.
    pub sampling: Sampling,
    /// The column names, in order.
    pub columns: Vec<&'static str>,
    /// Rows written (to the series file with `--series`).
    pub rows: u64,
    /// Steps whose end rounded to the previous row's time and were not written.
    pub merged_rows: u64,
    /// Integrator steps.
    pub steps: u64,
    /// Re-bases of the local clock.
    pub rebases: u64,
    /// The event threshold: the peak v (dimensionless) an episode above v = 1 must exceed.
    pub event_threshold: f64,
    /// The event threshold in the input's velocity unit, with dimensional input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub event_threshold_physical: Option<f64>,
    /// Events catalogued (the report's `events`).
    pub event_count: usize,
    /// Whether an event (an episode whose peak so far exceeds the threshold) was still under
    /// way at t_max (not catalogued).
    pub in_event_at_end: bool,
    /// The state (u, v, θ) at t_max.
    pub final_state: [f64; 3],
}

/// The analysis's result: its section and its event catalogue.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSeriesOutcome {
    /// The "time_series" section.
    pub report: TimeSeriesReport,
    /// The event catalogue.
    pub events: Vec<Event>,
    /// Where v reached the runaway threshold (with `runaway_v`).
    pub runaway: Option<Runaway>,
}

/// Where a run ended: at t_max, or earlier where v reached the runaway threshold.
struct End {
    t: Time,
    y: [f64; 3],
    runaway: bool,
}

/// One step end: local time, state and the interpolant's derivative.
#[derive(Debug, Clone, Copy)]
struct Sample {
    t: f64,
    y: [f64; 3],
    d: [f64; 3],
}

/// An episode of v above 1 under way.
#[derive(Debug, Clone, Copy)]
struct OpenEvent {
    start: Time,
    y_start: [f64; 3],
    peak: Time,
    w_peak: f64,
    rise_rate: f64,
    /// Whether it was under way at t = 0.
    started_before_run: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Crossing {
    Up,
    Down,
    Max,
}

/// Writes rows: the columns of one state at one absolute time.
struct Rows<'s> {
    sink: &'s mut dyn SeriesSink,
    drr: &'s Drr,
    scales: Option<PhysicalScales>,
    /// Whether the absolute shear stress and friction are known ([`PhysicalScales::friction_level`]).
    absolute: bool,
    u0: f64,
    last_t: f64,
    written: u64,
    merged: u64,
    buffer: Vec<f64>,
}

impl Rows<'_> {
    fn write(&mut self, t: Time, y: &[f64; 3]) -> std::io::Result<()> {
        let t = t.to_f64();
        if self.written > 0 && t <= self.last_t {
            self.merged += 1;
            return Ok(());
        }
        let v = y[W].exp();
        let slip = y[U] - self.u0 + t;
        let stress = dimensionless_friction(self.drr.params(), y[THETA], y[W]);
        self.buffer.clear();
        self.buffer.extend([t, y[U], v, y[THETA], y[W], slip, stress]);
        if let Some(s) = &self.scales {
            self.buffer.extend([
                s.time(t),
                s.velocity(v),
                s.slip(slip),
                s.shear_stress_change(stress),
            ]);
            if let (true, Some(tau), Some(mu)) = (
                self.absolute,
                s.shear_stress(&self.drr.params().friction, stress),
                s.friction_coefficient(&self.drr.params().friction, stress),
            ) {
                self.buffer.extend([tau, mu]);
            }
        }
        self.sink.row(&self.buffer)?;
        self.last_t = t;
        self.written += 1;
        Ok(())
    }
}

/// Runs the integrator (at local time 0 with the scene's initial state, absolute time 0) to
/// `settings.t_max`, writing rows to `sink` and cataloguing events. `system` is the system
/// integrated: `drr` itself, or `drr` under periodic loading ([`crate::model::ForcedDrr`]).
/// `scales` adds the physical columns and event quantities.
pub fn run(
    integ: &mut dyn Integrator,
    drr: &Drr,
    system: &dyn OdeSystem,
    settings: &TimeSeriesSettings,
    scales: Option<PhysicalScales>,
    sink: &mut dyn SeriesSink,
) -> Result<TimeSeriesOutcome, AnalysisError> {
    let y0 = integ.state();
    let y0 = [y0[0], y0[1], y0[2]];
    let mut d0 = [0.0; 3];
    system.rhs(integ.t(), &y0, &mut d0);
    let prev = Sample { t: integ.t(), y: y0, d: d0 };
    let mut columns: Vec<&'static str> = COLUMNS.to_vec();
    let absolute = scales.is_some_and(|s| s.shear_stress(&drr.params().friction, 0.0).is_some());
    if scales.is_some() {
        columns.extend(PHYSICAL_COLUMNS);
    }
    if absolute {
        columns.extend(ABSOLUTE_COLUMNS);
    }
    let io = |e: std::io::Error, t: f64, y: &[f64]| AnalysisError::Failed {
        analysis: "time_series",
        t,
        state: y.to_vec(),
        message: format!("writing the series failed: {e}"),
    };
    sink.begin(&columns).map_err(|e| io(e, 0.0, &y0))?;
    let mut run = Run {
        clock: Clock::new(integ, Time::new(0.0)),
        drr,
        settings,
        peak_level: settings.event_threshold.ln(),
        prev,
        // A start at v ≥ 1 is inside an episode from t = 0 (before the run if v > 1).
        open: (y0[W] >= 0.0).then_some(OpenEvent {
            start: Time::new(0.0),
            y_start: y0,
            peak: Time::new(0.0),
            w_peak: y0[W],
            rise_rate: 0.0,
            started_before_run: y0[W] > 0.0,
        }),
        events: Vec::new(),
        scales,
        last_peak: None,
        steps: 0,
        next_point: 0,
        rows: Rows {
            sink,
            drr,
            scales,
            absolute,
            u0: y0[U],
            last_t: 0.0,
            written: 0,
            merged: 0,
            buffer: Vec::with_capacity(columns.len()),
        },
    };
    let end = match run.integrate() {
        Ok(end) => end,
        Err(e) => return Err(e.at_global(&run.clock)),
    };
    let final_state = end.y;
    let Run { rows, events, open, steps, clock, .. } = run;
    let rebases = clock.rebases();
    rows.sink.finish().map_err(|e| io(e, settings.t_max, &final_state))?;
    let report = TimeSeriesReport {
        t_max: settings.t_max,
        t_max_physical: scales.map(|s| s.time(settings.t_max)),
        sampling: settings.sampling,
        columns,
        rows: rows.written,
        merged_rows: rows.merged,
        steps,
        rebases,
        event_threshold: settings.event_threshold,
        event_threshold_physical: scales.map(|s| s.velocity(settings.event_threshold)),
        event_count: events.len(),
        in_event_at_end: open.is_some_and(|e| e.w_peak > settings.event_threshold.ln()),
        final_state: [final_state[U], final_state[W].exp(), final_state[THETA]],
    };
    let runaway = settings.runaway_v.map(|v| {
        let reached = end.runaway.then_some((end.t.to_f64(), end.y));
        Runaway::new(drr, scales.as_ref(), v, reached, y0[U])
    });
    Ok(TimeSeriesOutcome { report, events, runaway })
}

/// The state of a run.
struct Run<'a, 's> {
    clock: Clock<'a>,
    drr: &'a Drr,
    settings: &'a TimeSeriesSettings,
    /// ln of the event threshold (an episode's peak w must exceed it).
    peak_level: f64,
    prev: Sample,
    open: Option<OpenEvent>,
    events: Vec<Event>,
    scales: Option<PhysicalScales>,
    last_peak: Option<Time>,
    steps: u64,
    /// Index of the next uniform row (`Sampling::Points`).
    next_point: u64,
    rows: Rows<'s>,
}

impl Run<'_, '_> {
    fn failed(&self, message: String) -> AnalysisError {
        AnalysisError::Failed {
            analysis: "time_series",
            t: self.clock.now().to_f64(),
            state: self.clock.state().to_vec(),
            message,
        }
    }

    fn write(&mut self, t: Time, y: &[f64; 3]) -> Result<(), AnalysisError> {
        self.rows.write(t, y).map_err(|e| self.failed(format!("writing the series failed: {e}")))
    }

    fn state_at(&mut self, t: f64) -> Result<[f64; 3], AnalysisError> {
        let y = self.clock.integrator().dense(t, 0)?;
        Ok([y[0], y[1], y[2]])
    }

    /// The time of the uniform row `i`.
    fn point_time(&self, i: u64) -> Option<Time> {
        match self.settings.sampling {
            // The last row exactly at t_max (t_max·i/(n − 1) may round above it).
            Sampling::Points(n) if i + 1 == n => Some(Time::new(self.settings.t_max)),
            Sampling::Points(n) if i < n => {
                Some(Time::new(self.settings.t_max * i as f64 / (n - 1) as f64))
            }
            _ => None,
        }
    }

    /// Integrates to t_max, or to where v reaches the runaway threshold; returns where it
    /// ended.
    fn integrate(&mut self) -> Result<End, AnalysisError> {
        let t_max = Time::new(self.settings.t_max);
        let y0 = self.prev.y;
        self.write(Time::new(0.0), &y0)?;
        self.next_point = 1;
        loop {
            if self.drr.deep_stick(&self.prev.y).is_some() {
                return Err(self.failed(format!(
                    "ln v = {:.1} is below −500, where v is zero in double precision: the \
                     time series does not cross such deep sticks (the \"cycle\" analysis does, \
                     in closed form)",
                    self.prev.y[W]
                )));
            }
            if self.steps >= self.settings.max_steps {
                return Err(AnalysisError::Budget {
                    analysis: "time_series",
                    t: self.clock.now().to_f64(),
                    state: self.clock.state().to_vec(),
                    message: format!(
                        "{} {} steps before t_max = {} (time_series.max_steps; raise it)",
                        self.steps,
                        self.clock.name(),
                        self.settings.t_max
                    ),
                });
            }
            let step = self.clock.step()?;
            if step.start != self.prev.t {
                // The clock re-based before this step.
                self.prev.t = step.start;
            }
            self.steps += 1;
            let (y, d) = events::step_end(&mut self.clock, step.t)?;
            let next = Sample { t: step.t, y, d };
            if y.iter().chain(&next.d).any(|v| !v.is_finite()) {
                return Err(self.failed(format!(
                    "{} accepted a step to a non-finite state or derivative (dy/dt = {:?})",
                    self.clock.name(),
                    next.d
                )));
            }
            // The end of this step, or t_max or the runaway inside it (local time).
            let end = self.clock.global(next.t);
            let mut last = (end.since(t_max) >= 0.0).then_some(t_max);
            let mut until =
                if last.is_some() { t_max.since(self.clock.global(0.0)) } else { next.t };
            let runaway = match self.settings.runaway_v.map(f64::ln) {
                Some(level) if self.prev.y[W] < level && next.y[W] >= level => {
                    let span = (self.prev.t, next.t);
                    let t = events::refine(self.clock.integrator(), span, 0, W, level)?;
                    (t <= until).then_some(t)
                }
                _ => None,
            };
            if let Some(t) = runaway {
                (until, last) = (t, Some(self.clock.global(t)));
            }
            let peaked = self.events(&next, until)?;
            self.sample_rows(&next, until)?;
            if let Some(t) = last {
                let y = self.state_at(until)?;
                if runaway.is_some() || !matches!(self.settings.sampling, Sampling::Points(_)) {
                    self.write(t, &y)?;
                }
                return Ok(End { t, y, runaway: runaway.is_some() });
            }
            if matches!(self.settings.sampling, Sampling::Steps)
                || matches!(self.settings.sampling, Sampling::Every(n) if self.steps.is_multiple_of(n))
            {
                self.write(end, &y)?;
            }
            self.prev = next;
            // After a peak, move the clock's origin there so that the arrest runs at small
            // local times (only where a re-base is an exact time shift and the model's dw/dt
            // is resolved; see the cycle analysis).
            if let Some(rate) = peaked {
                if !self.clock.rebase_restarts()
                    && super::cycle::restart_safe(self.drr, self.settings.w_tolerance, &y, rate)
                {
                    let shift = self.clock.rebase()?;
                    self.prev.t -= shift;
                }
            }
        }
    }

    /// Uniform rows inside the step prev → next, up to local time `until`.
    fn sample_rows(&mut self, next: &Sample, until: f64) -> Result<(), AnalysisError> {
        while let Some(at) = self.point_time(self.next_point) {
            let local = at.since(self.clock.global(0.0));
            if local > until {
                break;
            }
            let y = if local >= next.t { next.y } else { self.state_at(local.max(self.prev.t))? };
            self.write(at, &y)?;
            self.next_point += 1;
        }
        Ok(())
    }

    /// Crossings of v = 1 and maxima of w inside the step prev → next, up to local time
    /// `until`; updates the catalogue. Returns the episode's rise rate when its peak moved in
    /// this step.
    fn events(&mut self, next: &Sample, until: f64) -> Result<Option<f64>, AnalysisError> {
        let (p, span, level) = (self.prev, (self.prev.t, next.t), 0.0);
        let mut found = Vec::new();
        if p.y[W] < level && next.y[W] >= level {
            found.push((events::refine(self.clock.integrator(), span, 0, W, level)?, Crossing::Up));
        }
        if p.y[W] >= level && next.y[W] < level {
            found.push((
                events::refine(self.clock.integrator(), span, 0, W, level)?,
                Crossing::Down,
            ));
        }
        if p.d[W] > 0.0 && next.d[W] <= 0.0 {
            found.push((events::refine(self.clock.integrator(), span, 1, W, 0.0)?, Crossing::Max));
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut peaked = None;
        for (t, crossing) in found.into_iter().filter(|(t, _)| *t <= until) {
            let y = self.state_at(t)?;
            let at = self.clock.global(t);
            match crossing {
                Crossing::Up => {
                    self.open = Some(OpenEvent {
                        start: at,
                        y_start: y,
                        peak: at,
                        w_peak: y[W],
                        rise_rate: 0.0,
                        started_before_run: false,
                    });
                }
                Crossing::Max => {
                    if let Some(e) = &mut self.open {
                        if y[W] > e.w_peak {
                            (e.peak, e.w_peak) = (at, y[W]);
                            peaked = Some(());
                        }
                    }
                }
                Crossing::Down => {
                    if let Some(e) = self.open.take() {
                        self.close(e, at, y);
                    }
                }
            }
        }
        // A peak at the step end (no sign change of dw/dt located inside the step).
        if let Some(e) = &mut self.open {
            e.rise_rate = e.rise_rate.max(next.d[W].abs());
            if next.t <= until && next.y[W] > e.w_peak {
                (e.peak, e.w_peak) = (self.clock.global(next.t), next.y[W]);
            }
        }
        Ok(peaked.and(self.open.map(|e| e.rise_rate)))
    }

    /// Ends the episode `e` at `end` (state `y`): catalogued if its peak exceeds the
    /// threshold.
    fn close(&mut self, e: OpenEvent, end: Time, y: [f64; 3]) {
        if e.w_peak <= self.peak_level {
            return;
        }
        let duration = end.since(e.start);
        let recurrence = self.last_peak.map(|p| e.peak.since(p));
        let values = EventValues {
            t_start: e.start.to_f64(),
            t_peak: e.peak.to_f64(),
            t_end: end.to_f64(),
            v_max: e.w_peak.exp(),
            slip: y[U] - e.y_start[U] + duration,
            duration,
            stress_drop: self.drr.params().xi * (y[U] - e.y_start[U]),
            recurrence,
        };
        let physical = self.scales.map(|s| EventValues {
            t_start: s.time(values.t_start),
            t_peak: s.time(values.t_peak),
            t_end: s.time(values.t_end),
            v_max: s.velocity(values.v_max),
            slip: s.slip(values.slip),
            duration: s.time(duration),
            stress_drop: s.stress_drop(e.y_start[U], y[U]),
            recurrence: recurrence.map(|r| s.time(r)),
        });
        self.events.push(Event { values, physical, started_before_run: e.started_before_run });
        self.last_peak = Some(e.peak);
    }
}
