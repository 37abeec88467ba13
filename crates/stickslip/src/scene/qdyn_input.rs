//! QDYN's input file (`qdyn.in`) for its spring-block (`MESHDIM = 0`), read line by line in the
//! layout of QDYN's reader (its src/input.f90) as QDYN's Python wrapper (pyqdyn's
//! `write_input`) writes it, and mapped to a scene in the `dimensional` form
//! (docs/from-qdyn.md has the table). The scene is returned as JSON text, so that
//! `stickslip run qdyn.in --print-scene` shows exactly what runs and a kept copy runs the same.
//!
//! Each line holds its values separated by blanks or commas (Fortran's list-directed read);
//! whatever follows them is a comment (pyqdyn writes the field names there), a Fortran `d`
//! exponent (`1d-9`) is accepted, and blank lines are skipped (a list-directed read goes on
//! to the next line that holds values). Whatever stickslip does not run is refused naming the
//! line, the field and what is supported; so is a start exactly on the fixed point, where
//! nothing happens.

use serde_json::{json, Value};
use std::path::Path;

/// A QDYN input file stickslip cannot read or run: the line, the field and why. CLI exit 2.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("QDYN input {source_name} line {line}: {field}: {message}")]
pub struct QdynInputError {
    /// The file.
    pub source_name: String,
    /// Line number (from 1).
    pub line: usize,
    /// QDYN's name of the field, e.g. `APER`.
    pub field: String,
    /// What is wrong and what is supported.
    pub message: String,
}

/// Whether a scene file is a QDYN input file: its name ends in `.in`, or its first line is an
/// integer followed by the word `meshdim` (as pyqdyn writes it). A JSON scene starts with `{`.
pub fn is_qdyn_input(path: &Path, text: &str) -> bool {
    if path.extension().is_some_and(|e| e == "in") {
        return true;
    }
    let mut first = text.lines().next().unwrap_or("").split_whitespace();
    first.next().is_some_and(|t| t.parse::<i64>().is_ok())
        && first.next().is_some_and(|t| t.eq_ignore_ascii_case("meshdim"))
}

/// QDYN's output intervals (line 8): its time series (`output_ot_0`, `output_vmax`) are
/// written at every `NTOUT_OT`-th step, its snapshots (`output_ox`) at every `NTOUT`-th, each
/// also at the first step (step 0) and the last (QDYN's output.f90, `write_output`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QdynOutputIntervals {
    /// `NTOUT_OT`: steps between time-series rows.
    pub time_series: u64,
    /// `NTOUT`: steps between snapshots.
    pub snapshots: u64,
}

/// A QDYN input file read: the scene it maps to and what QDYN's output would hold.
#[derive(Debug, Clone, PartialEq)]
pub struct QdynInput {
    /// The scene (pretty JSON text), as [`to_scene`] gives it.
    pub scene: String,
    /// The intervals of QDYN's output files (for `--qdyn-output`).
    pub output: QdynOutputIntervals,
}

/// The scene (pretty JSON text) equivalent to a QDYN spring-block input file: quasi-dynamic,
/// SI units, radau5 at rtol = `ACC`, the "cycle" analysis (not under periodic loading,
/// `APER` ≠ 0, which forces the system) and a "time_series" run to `TMAX` (without healing,
/// `THETA_LAW = 0`: the run to `TMAX` or to the runaway at [`NO_HEALING_RUNAWAY_VELOCITY`],
/// and no cycle).
/// `name` names the scene (e.g. the file's stem).
pub fn to_scene(text: &str, source_name: &str, name: &str) -> Result<String, QdynInputError> {
    read(text, source_name, name).map(|input| input.scene)
}

/// The file read: its scene ([`to_scene`]) and its output intervals. A start exactly on the
/// fixed point (V = V_PL, Θ at its steady state, no periodic loading), where the state never
/// changes, is refused naming `V_0` and `TH_0`.
pub fn read(text: &str, source_name: &str, name: &str) -> Result<QdynInput, QdynInputError> {
    let mut mapped = map(&mut Lines::new(text, source_name))?;
    mapped.scene["name"] = json!(name);
    let scene = serde_json::to_string_pretty(&mapped.scene).expect("a JSON value serialises");
    // A scene the mapping cannot build is refused where it is run, in the scene's terms.
    if let Ok(parsed) = super::parse(&scene, source_name) {
        let drr = crate::model::Drr::new(parsed.params);
        if parsed.loading.is_none() && drr.at_rest(&parsed.initial) {
            return Err(mapped.start.on_fixed_point(source_name));
        }
    }
    Ok(QdynInput { scene, output: mapped.output })
}

/// What [`map`] reads: the scene's JSON value (without its name), the output intervals and
/// the start (for the fixed-point message).
struct Mapped {
    scene: Value,
    output: QdynOutputIntervals,
    start: Start,
}

/// The start as the file gives it (line `line`), in SI units.
struct Start {
    line: usize,
    v_0: f64,
    th_0: f64,
    v_pl: f64,
    d_c: f64,
}

impl Start {
    /// The error of a start on the fixed point, in the file's terms and units.
    fn on_fixed_point(&self, source_name: &str) -> QdynInputError {
        QdynInputError {
            source_name: source_name.into(),
            line: self.line,
            field: "V_0, TH_0".into(),
            message: format!(
                "the run starts on the fixed point, steady sliding at the loading rate: V_0 = \
                 {:e} m/s is V_PL and TH_0 = {:e} s is the steady state DC/V_PL = {:e} s, where \
                 V and Θ never change, so nothing happens (no event, no cycle, to TMAX). Perturb \
                 the start, e.g. V_0 = {:e} m/s (0.5·V_PL) or TH_0 = {:e} s (2·DC/V_PL)",
                self.v_0,
                self.th_0,
                self.d_c / self.v_pl,
                0.5 * self.v_pl,
                2.0 * self.d_c / self.v_pl
            ),
        }
    }
}

/// The file's lines with their numbers, consumed in QDYN's reading order.
struct Lines<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    source_name: &'a str,
    last: usize,
}

/// One line's values, with its number for messages.
struct Line<'a> {
    number: usize,
    tokens: Vec<&'a str>,
    source_name: &'a str,
    names: &'static [&'static str],
}

impl<'a> Lines<'a> {
    fn new(text: &'a str, source_name: &'a str) -> Self {
        Self { lines: text.lines().enumerate(), source_name, last: 0 }
    }

    /// The next line that holds values (blank lines skipped, as QDYN's list-directed reads
    /// skip them), which must hold the values `names` (QDYN's names, in order).
    fn next(&mut self, names: &'static [&'static str]) -> Result<Line<'a>, QdynInputError> {
        let mut lines = self.lines.by_ref().filter(|(_, text)| !is_blank(text));
        let Some((i, text)) = lines.next() else {
            return Err(QdynInputError {
                source_name: self.source_name.into(),
                line: self.last + 1,
                field: names.join(", "),
                message: "missing: the file ends here; QDYN's spring-block input has this line \
                          next (pyqdyn's write_input writes it)"
                    .into(),
            });
        };
        self.last = i + 1;
        let tokens: Vec<&str> = text.split(is_separator).filter(|t| !t.is_empty()).collect();
        let line = Line { number: i + 1, tokens, source_name: self.source_name, names };
        if line.tokens.len() < names.len() {
            return Err(line.error(
                line.tokens.len().min(names.len() - 1),
                format!(
                    "this line needs {} values ({}); it has {}",
                    names.len(),
                    names.join(", "),
                    line.tokens.len()
                ),
            ));
        }
        Ok(line)
    }
}

/// Whether `c` separates values (Fortran's list-directed read: blanks and commas).
fn is_separator(c: char) -> bool {
    c.is_whitespace() || c == ','
}

/// Whether a line holds nothing but blanks (a list-directed read skips it; a comma is not
/// blank: it separates null values).
fn is_blank(text: &str) -> bool {
    text.chars().all(char::is_whitespace)
}

impl Line<'_> {
    fn error(&self, index: usize, message: String) -> QdynInputError {
        QdynInputError {
            source_name: self.source_name.into(),
            line: self.number,
            field: self.names[index].into(),
            message,
        }
    }

    /// The value `index` as a number (a Fortran `d` exponent accepted).
    fn number(&self, index: usize) -> Result<f64, QdynInputError> {
        let token = self.tokens[index];
        token
            .replace(['d', 'D'], "e")
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.error(index, format!("\"{token}\" is not a finite number")))
    }

    /// The value `index` as an integer flag.
    fn integer(&self, index: usize) -> Result<i64, QdynInputError> {
        let token = self.tokens[index];
        token
            .parse::<i64>()
            .map_err(|_| self.error(index, format!("\"{token}\" is not an integer")))
    }

    /// The value `index`, which must be > 0.
    fn positive(&self, index: usize, what: &str) -> Result<f64, QdynInputError> {
        let v = self.number(index)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.error(index, format!("{v} must be > 0 ({what})")))
        }
    }

    /// The value `index` as a step interval ≥ 1.
    fn interval(&self, index: usize, what: &str) -> Result<u64, QdynInputError> {
        match self.integer(index)? {
            n if n >= 1 => Ok(n as u64),
            n => Err(self.error(index, format!("{n} must be ≥ 1 ({what})"))),
        }
    }

    /// The flag `index`, which stickslip supports only at `supported` (QDYN's off value).
    fn only(&self, index: usize, supported: i64, what: &str) -> Result<(), QdynInputError> {
        let v = self.integer(index)?;
        if v == supported {
            Ok(())
        } else {
            Err(self.error(index, format!("{v} is not supported: {what}")))
        }
    }
}

/// Reads the file in QDYN's order (src/input.f90, mesh.f90's read_mesh_parameters) and builds
/// the scene's JSON value (without its name).
fn map(lines: &mut Lines) -> Result<Mapped, QdynInputError> {
    let l = lines.next(&["MESHDIM"])?;
    l.only(0, 0, "stickslip runs QDYN's spring-block, MESHDIM = 0 (a single degree of freedom); 1D and 2D faults (MESHDIM = 1, 2) are not supported")?;
    lines.next(&["NN"])?.integer(0)?; // QDYN sets NN = 1 for MESHDIM = 0.
    let l = lines.next(&["L", "W"])?;
    let length = l.positive(0, "the spring-block's length L, k = MU/L, e.g. 120 (m)")?;
    l.number(1)?; // W: unused by the spring-block.
    let l = lines.next(&["THETA_LAW"])?;
    let state_law = match l.integer(0)? {
        1 => "ageing",
        2 => "slip",
        0 => "no_healing",
        other => return Err(l.error(0, format!("{other} is not a QDYN state law; stickslip runs THETA_LAW = 0 (no healing), 1 (ageing) and 2 (slip)"))),
    };
    let l = lines.next(&["RNS_LAW"])?;
    let rns_law = l.integer(0)?;
    match rns_law {
        0..=2 => {}
        3 => return Err(l.error(0, "3 (the Chen–Niemeijer–Spiers model, FRICTION_MODEL = \"CNS\") is not supported; stickslip runs RNS_LAW = 0 (classic), 1 (cut-off velocities) and 2 (regularised)".into())),
        other => return Err(l.error(0, format!("{other} is not a QDYN friction law; stickslip runs RNS_LAW = 0 (classic), 1 (cut-off velocities) and 2 (regularised)"))),
    }
    lines.next(&["SIGMA_CPL"])?.only(
        0,
        0,
        "normal-stress coupling (i_sigma_law) is not modelled; stickslip's σ is constant (0)",
    )?;
    let l = lines.next(&["FEAT_STRESS_COUPL", "FEAT_TP", "FEAT_LOCALISATION"])?;
    l.only(0, 0, "normal-stress coupling is not modelled; stickslip's σ is constant (0)")?;
    l.only(1, 0, "thermal pressurisation is not modelled (0)")?;
    l.only(2, 0, "strain localisation (a CNS feature) is not modelled (0)")?;
    // Output intervals: those of QDYN's files (--qdyn-output); the other output settings
    // (selected element, spatial intervals, snapshot files) have no meaning for one block.
    let l = lines.next(&[
        "NTOUT_OT",
        "NTOUT",
        "IC",
        "NXOUT",
        "NWOUT",
        "NXOUT_DYN",
        "NWOUT_DYN",
        "OX_SEQ",
        "OX_DYN",
    ])?;
    let output = QdynOutputIntervals {
        time_series: l.interval(0, "QDYN writes its time series every NTOUT_OT-th step, e.g. 1")?,
        snapshots: l.interval(1, "QDYN writes a snapshot every NTOUT-th step, e.g. 1000")?,
    };
    let speeds = lines.next(&["VS", "MU", "LAM", "D", "HD", "V_TH"])?;
    let l = &speeds;
    let vs = l.number(0)?;
    if vs < 0.0 {
        return Err(l.error(
            0,
            format!("{vs} must be ≥ 0 (the shear-wave speed c_s; 0 = no radiation damping)"),
        ));
    }
    if vs == 0.0 {
        return Err(l.error(0, "0 means no radiation damping, which the quasi-dynamic spring-block cannot run (without it V blows up in finite time at the first event); give the shear-wave speed c_s, e.g. 3000 (m/s)".into()));
    }
    let mu = l.positive(1, "the shear modulus G, e.g. 3e10 (Pa)")?;
    for i in 2..5 {
        l.number(i)?; // LAM, D, HD: 2D/3D kernels and damage zones only.
    }
    let v_th = l.number(5)?;
    let l = lines.next(&["TPER", "APER"])?;
    let tper = l.number(0)?;
    let aper = l.number(1)?;
    if aper != 0.0 && tper <= 0.0 {
        return Err(l.error(
            0,
            format!("{tper} must be > 0 with APER ≠ 0 (the period of the periodic loading, in s)"),
        ));
    }
    let l = lines.next(&["DTTRY", "DTMAX", "TMAX", "ACC"])?;
    l.number(0)?; // DTTRY, DTMAX: stickslip's integrators choose their own steps.
    l.number(1)?;
    let t_max = l.positive(2, "the end of the run in s (NSTOP = 0)")?;
    let acc = l.positive(3, "the solver's relative accuracy, e.g. 1e-7")?;
    if acc >= 1.0 {
        return Err(l.error(3, format!("{acc} must be < 1 (a relative accuracy, e.g. 1e-7)")));
    }
    lines.next(&["NSTOP"])?.only(0, 0, "stickslip stops at TMAX (NSTOP = 0); the stops after the first peak (2) and at a slip-rate threshold (3) are not supported")?;
    let l = lines.next(&["DYN_FLAG", "DYN_SKIP"])?;
    l.only(0, 0, "coupling to a dynamic-rupture code is not supported (0)")?;
    lines.next(&["DYN_M", "DYN_TH_ON", "DYN_TH_OFF"])?;
    let l = lines.next(&["FAULT_TYPE", "SOLVER"])?;
    l.integer(0)?; // FAULT_TYPE: 3D faults only.
    l.integer(1)?; // SOLVER: QDYN's integrator; stickslip runs radau5 at rtol = ACC.
    let l = lines.next(&[
        "SIGMA", "V_0", "TH_0", "A", "B", "DC", "V1", "V2", "MU_SS", "V_SS", "IOT", "IASP", "CO",
        "V_PL",
    ])?;
    let sigma = l.positive(0, "the effective normal stress σ, e.g. 1e7 (Pa)")?;
    let v_0 = l.positive(1, "the initial slip rate, e.g. 5e-10 (m/s)")?;
    let th_0 = l.positive(2, "the initial state Θ, e.g. 1e5 (s)")?;
    let a = l.positive(3, "the direct-effect coefficient a, e.g. 0.01")?;
    let b = l.positive(4, "the state-effect coefficient b, e.g. 0.015")?;
    let d_c = l.positive(5, "the critical slip distance D_c, e.g. 1e-4 (m)")?;
    for i in 6..10 {
        l.number(i)?; // V1, V2, MU_SS, V_SS: read below by the law that uses them.
    }
    l.integer(10)?; // IOT: QDYN's output selection.
    let iasp = l.integer(11)?;
    let co = l.number(12)?;
    if co != 0.0 {
        return Err(l.error(12, format!("{co}: cohesion is not supported (τ = σμ; CO = 0)")));
    }
    let v_pl = l.positive(13, "the loading velocity V_pl, e.g. 1e-9 (m/s)")?;
    let start = Start { line: l.number, v_0, th_0, v_pl, d_c };
    // QDYN lists the peaks of V above V_TH (output_iasp) where IASP = 1, and uses V_TH for
    // nothing else: there it is the file's event threshold; elsewhere the default holds.
    let event_threshold = if iasp == 1 {
        if v_th <= v_pl {
            return Err(speeds.error(5, format!("{v_th} must be above V_PL = {v_pl:e} m/s with IASP = 1 (QDYN lists the peaks of V above V_TH; an event is an episode of V above V_PL peaking above V_TH), e.g. 1e-2 (m/s, pyqdyn's default)")));
        }
        Some(v_th / v_pl)
    } else {
        None
    };
    let friction = match rns_law {
        0 => json!("log"),
        1 => {
            let mu_ss = l.number(8)?;
            let v1 = l.positive(6, "the cut-off velocity V1 of the direct effect (m/s)")?;
            let v2 = l.positive(7, "the cut-off velocity V2 of the state effect (m/s)")?;
            json!({"cut_off": {"velocity_1": v1, "velocity_2": v2, "mu_star": mu_ss}})
        }
        _ => {
            let mu_ss = l.number(8)?;
            let v_ss = l.positive(9, "the reference velocity V* (m/s)")?;
            json!({"regularised": {"mu_star": mu_ss, "velocity_star": v_ss}})
        }
    };
    let mut dimensional = json!({
        "unit_system": "SI",
        "sigma": sigma, "a": a, "b": b, "d_c": d_c, "v0": v_pl,
        "shear_modulus": mu, "length": length, "shear_wave_speed": vs,
    });
    if aper != 0.0 {
        dimensional["periodic_loading"] = json!({"amplitude": aper, "period": tper});
    }
    if rns_law == 0 {
        let mu_ss = l.positive(8, "the reference friction coefficient μ*, e.g. 0.6")?;
        let v_ss = l.positive(9, "the reference velocity V*, e.g. 1e-6 (m/s)")?;
        dimensional["mu0"] = json!(mu_ss);
        dimensional["v_ref"] = json!(v_ss);
    }
    let scene = json!({
        "name": "",
        "description": "QDYN spring-block input (MESHDIM = 0) mapped by stickslip (docs/from-qdyn.md)",
        "model": {
            "inertia": false,
            "state_law": state_law,
            "friction": friction,
            "dimensional": dimensional,
        },
        "initial": {"velocity": v_0, "state": th_0},
        "solver": {"method": "radau5", "rtol": acc},
        "analyses": analyses(state_law, aper != 0.0, t_max, event_threshold),
    });
    Ok(Mapped { scene, output, start })
}

/// The slip rate (m/s) at which a no-healing run (`THETA_LAW = 0`) stops: 1 m/s, a seismic
/// slip rate. QDYN itself runs on until its solver fails (exit 0).
pub const NO_HEALING_RUNAWAY_VELOCITY: f64 = 1.0;

/// The analyses of a mapped file: the cycle and the events to `TMAX`; under periodic loading
/// (`forced`), which has no cycle of its own, the events alone (and their locking to the
/// forcing); without healing, which has no cycle, the run to `TMAX` that stops where V
/// reaches [`NO_HEALING_RUNAWAY_VELOCITY`] (the report's `runaway`). `event_threshold`
/// (V_TH/V_PL, with IASP = 1) sets the time series' event threshold.
fn analyses(state_law: &str, forced: bool, t_max: f64, event_threshold: Option<f64>) -> Value {
    let mut time_series = json!({"t_max": t_max});
    if let Some(v) = event_threshold {
        time_series["event_threshold"] = json!(v);
    }
    if state_law == "no_healing" {
        time_series["runaway_velocity"] = json!(NO_HEALING_RUNAWAY_VELOCITY);
        json!([{ "time_series": time_series }])
    } else if forced {
        json!([{ "time_series": time_series }])
    } else {
        json!(["cycle", { "time_series": time_series }])
    }
}
