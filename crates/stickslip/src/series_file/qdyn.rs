//! QDYN's output files for a spring-block (`stickslip run … --qdyn-output DIR`): `output_ot_0`
//! (the time series at the block), `output_vmax` (the same at the fastest point: the block)
//! and `output_ox` (snapshots), thinned as QDYN thins them when the run comes from a qdyn.in
//! (every `NTOUT_OT`-th step and every `NTOUT`-th, each with the first and the last; without
//! one, every row and the first and last snapshots), with QDYN's headers, columns and
//! Fortran formats (`E24.14` for time, `E15.7` for the rest, `I15` for `ivmax`) and its SI
//! units, so that pyqdyn's `read_output` reads them unchanged. The layout is copied from files
//! QDYN wrote (data/reference/qdyn_output/, its README says how they were made).
//!
//! Columns (QDYN's names): t (s), potency and potency rate (slip·L and V·L, L the
//! spring-block's length, m²·… as QDYN computes them), V (m/s), Θ (s), τ = σμ (Pa), dtau_dt,
//! slip (m, from t = 0) and σ (Pa). QDYN's own spring-block files hold 0 in dtau_dt (it never
//! updates it when MESHDIM = 0); stickslip writes the spring's stressing rate k(V_pl − V).

use crate::analysis::time_series::SeriesSink;
use crate::model::scales::PhysicalScales;
use crate::model::Friction;
use crate::scene::qdyn_input::QdynOutputIntervals;
use crate::scene::Scene;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// The header of `output_ot_0`.
pub const OT_HEADER: &str = "# macroscopic values:\n# 1=t, 2=pot, 3=pot_rate\n# values at selected point:\n# 4=V, 5=theta, 6=tau, 7=dtau_dt, 8=slip, 9=sigma\n";

/// The header of `output_vmax`.
pub const VMAX_HEADER: &str =
    "# values at max(V) location:\n# 1=t, 2=ivmax, 3=v, 4=theta, 5=tau, 6=dtau_dt, 7=slip, 8=sigma\n";

/// The header of each snapshot in `output_ox`.
pub const OX_HEADER: &str = "# t x y z v theta tau tau_dot slip sigma\n";

/// What turns a scene's time-series rows into QDYN's columns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QdynColumns {
    scales: PhysicalScales,
    /// The spring-block's length L (potency = slip·L).
    length: f64,
    /// σ.
    sigma: f64,
    /// The friction law (μ's absolute level).
    friction: Friction,
}

impl QdynColumns {
    /// The columns for `scene`; the error names the scene field that is missing (QDYN's files
    /// are physical: σ, the length L and the absolute friction level are needed).
    pub fn for_scene(scene: &Scene) -> Result<Self, String> {
        let (Some(scales), Some(d)) = (scene.scales, scene.dimensional) else {
            return Err("QDYN's output is in physical units: the scene needs model.dimensional (SI: Pa, m, m/s, s)".into());
        };
        let sigma = scales.sigma.ok_or("QDYN's σ column and τ = σμ need model.dimensional.sigma (with a and b as friction coefficients)")?;
        let length = match (d.length, d.shear_modulus) {
            (Some(l), _) => l,
            (None, Some(g)) => g / scales.k,
            (None, None) => return Err("QDYN's potency columns (slip·L) need the spring-block's length: model.dimensional.length with shear_modulus (k = G/L), or shear_modulus beside k (L = G/k)".into()),
        };
        let friction = scene.params.friction;
        scales.friction_level(&friction).ok_or_else(|| match friction {
            Friction::Log => "QDYN's τ = σμ is absolute: the scene needs model.dimensional.mu0 and v_ref (QDYN's MU_SS, V_SS)".to_string(),
            Friction::CutOff { .. } => "QDYN's τ = σμ is absolute: the cut-off law needs model.friction.cut_off.mu_star (QDYN's MU_SS)".to_string(),
            other => format!("QDYN's τ = σμ is absolute, which the {} friction law does not fix; use the log, cut-off or regularised law", other.label()),
        })?;
        Ok(Self { scales, length, sigma, friction })
    }

    /// QDYN's nine ot values (t, pot, pot_rate, V, Θ, τ, dtau_dt, slip, σ) from the
    /// dimensionless t, θ, v, φ and slip of one row (None if μ's level is not fixed, which
    /// [`QdynColumns::for_scene`] rules out).
    fn values(&self, t: f64, theta: f64, v: f64, phi: f64, slip: f64) -> Option<[f64; 9]> {
        let s = &self.scales;
        let (big_v, slip) = (s.velocity(v), s.slip(slip));
        Some([
            s.time(t),
            slip * self.length,
            big_v * self.length,
            big_v,
            s.state_from_theta(theta),
            s.shear_stress(&self.friction, phi)?,
            s.k * (s.v0 - big_v),
            slip,
            self.sigma,
        ])
    }
}

/// Fortran's `Ew.d` edit descriptor: a mantissa 0.d…d with `d` digits, `E±ee` (or `±eee`
/// without the E beyond ±99), right-aligned in `w` characters; `Infinity`, `-Infinity` and
/// `NaN` as gfortran writes them.
pub fn fortran_e(x: f64, w: usize, d: usize) -> String {
    let body = if x.is_nan() {
        "NaN".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "Infinity" } else { "-Infinity" }.to_string()
    } else if x == 0.0 {
        format!("0.{}E+00", "0".repeat(d))
    } else {
        // Rust's d.ddde±x (mantissa in [1, 10)) is Fortran's 0.dddd (in [0.1, 1)) times 10^(x+1).
        let s = format!("{:.*e}", d.max(1) - 1, x.abs());
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
        let e = exponent.parse::<i32>().unwrap_or(0) + 1;
        let sign = if e < 0 { '-' } else { '+' };
        let exponent = if e.abs() <= 99 {
            format!("E{sign}{:02}", e.abs())
        } else {
            format!("{sign}{:03}", e.abs())
        };
        format!("{}0.{digits}{exponent}", if x < 0.0 { "-" } else { "" })
    };
    format!("{body:>w$}")
}

/// Where each needed column sits in the rows.
#[derive(Debug, Clone, Copy)]
struct Indices {
    t: usize,
    theta: usize,
    v: usize,
    stress: usize,
    slip: usize,
}

/// The size of the files above which [`QdynOutputSink`] announces its estimate: 100 MB.
pub const LARGE_OUTPUT_BYTES: u64 = 100_000_000;

/// The written size at which the estimate is first made (then at each doubling): 4 MB.
const FIRST_ESTIMATE_BYTES: u64 = 4_000_000;

/// Where the rows go and what is announced about their size.
pub struct QdynOutputSink {
    columns: QdynColumns,
    ot: BufWriter<File>,
    vmax: BufWriter<File>,
    ox: BufWriter<File>,
    indices: Option<Indices>,
    /// QDYN's intervals, in rows (every row a step); None: every row, first and last
    /// snapshots.
    intervals: Option<QdynOutputIntervals>,
    /// The last row received, and whether it went to the time series and to a snapshot.
    last: Option<([f64; 9], bool, bool)>,
    rows: u64,
    /// The end of the run (the time column's unit), for the size estimate.
    t_max: f64,
    bytes: u64,
    next_estimate: u64,
    /// Receives the size estimate, once, when it exceeds [`LARGE_OUTPUT_BYTES`].
    announce: Box<dyn FnMut(&str)>,
    announced: bool,
}

impl QdynOutputSink {
    /// Creates `dir` (if needed) and its files `output_ot_0`, `output_vmax`, `output_ox`.
    /// `intervals`: QDYN's `NTOUT_OT` and `NTOUT` of the run's qdyn.in (every row is then one
    /// integrator step), or None. `t_max` is the run's end in the time column's unit; once
    /// the files written so far, extrapolated to it, exceed [`LARGE_OUTPUT_BYTES`], `announce`
    /// receives the estimate (once).
    pub fn create(
        dir: &Path,
        columns: QdynColumns,
        intervals: Option<QdynOutputIntervals>,
        t_max: f64,
        announce: Box<dyn FnMut(&str)>,
    ) -> io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let file = |name: &str| File::create(dir.join(name)).map(BufWriter::new);
        Ok(Self {
            columns,
            ot: file("output_ot_0")?,
            vmax: file("output_vmax")?,
            ox: file("output_ox")?,
            indices: None,
            intervals,
            last: None,
            rows: 0,
            t_max,
            bytes: 0,
            next_estimate: FIRST_ESTIMATE_BYTES,
            announce,
            announced: false,
        })
    }

    fn snapshot(&mut self, q: &[f64; 9]) -> io::Result<()> {
        let mut line = fortran_e(q[0], 24, 14) + &fortran_e(0.0, 24, 14);
        for x in [0.0, 0.0, q[3], q[4], q[5], q[6], q[7], q[8]] {
            line += &fortran_e(x, 15, 7);
        }
        self.ox.write_all(OX_HEADER.as_bytes())?;
        writeln!(self.ox, "{line}")?;
        self.bytes += (OX_HEADER.len() + line.len() + 1) as u64;
        Ok(())
    }

    /// One row of `output_ot_0` and of `output_vmax`.
    fn time_series(&mut self, q: &[f64; 9]) -> io::Result<()> {
        let mut ot = fortran_e(q[0], 24, 14);
        let mut vmax = ot.clone() + &format!("{:>15}", 1);
        for (k, x) in q.iter().enumerate().skip(1) {
            let field = fortran_e(*x, 15, 7);
            if k >= 3 {
                vmax += &field;
            }
            ot += &field;
        }
        writeln!(self.ot, "{ot}")?;
        writeln!(self.vmax, "{vmax}")?;
        self.bytes += (ot.len() + vmax.len() + 2) as u64;
        Ok(())
    }

    /// Announces the files' size extrapolated to t_max from what was written by time `t`,
    /// when it is large (checked at 4 MB written and at each doubling).
    fn estimate(&mut self, t: f64) {
        if self.announced || self.bytes < self.next_estimate || t <= 0.0 {
            return;
        }
        self.next_estimate *= 2;
        let expected = self.bytes as f64 * (self.t_max / t).max(1.0);
        if expected > LARGE_OUTPUT_BYTES as f64 {
            self.announced = true;
            // The interval that would bring the files near the announced size.
            let n = (expected / LARGE_OUTPUT_BYTES as f64).ceil();
            let thin = match self.intervals {
                Some(i) => format!(
                    "the qdyn.in's NTOUT_OT (line 8, now {}) writes every NTOUT_OT-th step: \
                     NTOUT_OT = {} gives about {} MB",
                    i.time_series,
                    n * i.time_series as f64,
                    LARGE_OUTPUT_BYTES / 1_000_000
                ),
                None => format!(
                    "the time_series option \"every\": N writes every N-th step: N = {n} times \
                     the scene's gives about {} MB",
                    LARGE_OUTPUT_BYTES / 1_000_000
                ),
            };
            (self.announce)(&format!(
                "--qdyn-output: the files will hold about {:.3} GB by t = {:e} s at the rate so \
                 far ({:.1} MB by t = {t:.4e} s); {thin}",
                expected / 1e9,
                self.t_max,
                self.bytes as f64 / 1e6
            ));
        }
    }
}

impl SeriesSink for QdynOutputSink {
    fn begin(&mut self, columns: &[&'static str]) -> io::Result<()> {
        let find = |name: &str| {
            columns.iter().position(|c| *c == name).ok_or_else(|| {
                io::Error::new(io::ErrorKind::InvalidData, format!("no column {name}"))
            })
        };
        self.indices = Some(Indices {
            t: find("t")?,
            theta: find("theta")?,
            v: find("v")?,
            stress: find("stress")?,
            slip: find("slip")?,
        });
        self.ot.write_all(OT_HEADER.as_bytes())?;
        self.vmax.write_all(VMAX_HEADER.as_bytes())?;
        self.bytes += (OT_HEADER.len() + VMAX_HEADER.len()) as u64;
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> io::Result<()> {
        let invalid = |m: &str| io::Error::new(io::ErrorKind::InvalidData, m.to_string());
        let i = self.indices.ok_or_else(|| invalid("a row before the columns"))?;
        let q = self
            .columns
            .values(values[i.t], values[i.theta], values[i.v], values[i.stress], values[i.slip])
            .ok_or_else(|| invalid("QDYN's τ = σμ needs μ's absolute level"))?;
        // Row k is step k: QDYN writes step 0 and every n-th.
        let (series, snapshot) = match self.intervals {
            Some(i) => {
                (self.rows.is_multiple_of(i.time_series), self.rows.is_multiple_of(i.snapshots))
            }
            None => (true, self.rows == 0),
        };
        if series {
            self.time_series(&q)?;
        }
        if snapshot {
            self.snapshot(&q)?;
        }
        self.rows += 1;
        self.last = Some((q, series, snapshot));
        self.estimate(q[0]);
        Ok(())
    }

    /// Writes the last row where it was not written (QDYN writes its last step to each
    /// file), and flushes.
    fn finish(&mut self) -> io::Result<()> {
        if let Some((q, series, snapshot)) = self.last {
            if !series {
                self.time_series(&q)?;
            }
            if !snapshot {
                self.snapshot(&q)?;
            }
        }
        self.ot.flush()?;
        self.vmax.flush()?;
        self.ox.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sink on the SI field scene (t_max = 1e9 s) writing to a fresh directory, with the
    /// announcements collected in `said`.
    fn sink(
        name: &str,
        intervals: Option<QdynOutputIntervals>,
    ) -> (QdynOutputSink, std::path::PathBuf, std::rc::Rc<std::cell::RefCell<Vec<String>>>) {
        let scene = crate::scene::parse(
            r#"{"name": "si", "model": {"inertia": false, "state_law": "ageing",
                "dimensional": {"sigma": 1e7, "a": 0.01, "b": 0.015, "d_c": 1e-4, "v0": 1e-9,
                    "mu0": 0.6, "v_ref": 1e-6, "length": 120, "shear_modulus": 3e10,
                    "shear_wave_speed": 3e3}},
                "analyses": [{"time_series": {"t_max": 1e9}}]}"#,
            "test",
        )
        .unwrap();
        let dir =
            std::env::temp_dir().join(format!("stickslip-qdyn-{name}-{}", std::process::id()));
        let said = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
        let log = said.clone();
        let announce = Box::new(move |m: &str| log.borrow_mut().push(m.to_string()));
        let columns = QdynColumns::for_scene(&scene).unwrap();
        (QdynOutputSink::create(&dir, columns, intervals, 1e9, announce).unwrap(), dir, said)
    }

    /// Feeds `n` rows at t = 0, 1, … (units of D_c/v0 = 1e5 s) and finishes.
    fn feed(sink: &mut QdynOutputSink, n: u64) {
        let columns = ["t", "u", "v", "theta", "ln_v", "slip", "stress"];
        sink.begin(&columns).unwrap();
        for k in 0..n {
            sink.row(&[k as f64, 0.0, 1.0, 0.0, 0.0, k as f64, 0.0]).unwrap();
        }
        sink.finish().unwrap();
    }

    fn data_lines(path: &std::path::Path) -> Vec<String> {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(String::from)
            .collect()
    }

    #[test]
    fn ntout_thins_the_files_as_qdyn_does() {
        // NTOUT_OT = 10, NTOUT = 40 over steps 0 … 104: time series at 0, 10, …, 100 and the
        // last (104); snapshots at 0, 40, 80 and the last.
        let intervals = QdynOutputIntervals { time_series: 10, snapshots: 40 };
        let (mut s, dir, said) = sink("thin", Some(intervals));
        feed(&mut s, 105);
        let t = |line: &String| line[..24].trim().parse::<f64>().unwrap() / 1e5;
        let ot: Vec<f64> = data_lines(&dir.join("output_ot_0")).iter().map(t).collect();
        let expected: Vec<f64> = (0..=10).map(|k| 10.0 * k as f64).chain([104.0]).collect();
        assert_eq!(ot, expected);
        assert_eq!(data_lines(&dir.join("output_vmax")).len(), expected.len());
        let ox: Vec<f64> = data_lines(&dir.join("output_ox")).iter().map(t).collect();
        assert_eq!(ox, [0.0, 40.0, 80.0, 104.0]);
        assert!(said.borrow().is_empty(), "a small file is not announced: {:?}", said.borrow());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn without_intervals_every_row_and_the_first_and_last_snapshots() {
        let (mut s, dir, _) = sink("all", None);
        feed(&mut s, 7);
        assert_eq!(data_lines(&dir.join("output_ot_0")).len(), 7);
        assert_eq!(data_lines(&dir.join("output_ox")).len(), 2);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_large_expected_size_is_announced_once() {
        // 30 000 rows at t = k·1e5 s, ~275 bytes each (8 MB). With t_max = 1e9 s the rows are
        // past t_max when 4 MB are written, so the estimate is what was written: not
        // announced. With t_max = 1e13 s the rate extrapolates to ~1e4 GB: announced, once.
        let (mut s, dir, said) = sink("small", None);
        feed(&mut s, 30_000);
        assert!(said.borrow().is_empty(), "{:?}", said.borrow());
        std::fs::remove_dir_all(&dir).ok();
        let (mut s, dir, said) =
            sink("large", Some(QdynOutputIntervals { time_series: 1, snapshots: 1000 }));
        s.t_max = 1e13;
        feed(&mut s, 30_000);
        let said = said.borrow();
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(
            said[0].contains("GB by t = 1e13 s") && said[0].contains("NTOUT_OT"),
            "{}",
            said[0]
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn fortran_e_matches_qdyns_fields() {
        // Fields copied from QDYN's own output_ot_0.
        assert_eq!(fortran_e(0.0, 24, 14), "    0.00000000000000E+00");
        assert_eq!(fortran_e(0.076174138036644, 24, 14), "    0.76174138036644E-01");
        assert_eq!(fortran_e(5e-10, 15, 7), "  0.5000000E-09");
        assert_eq!(fortran_e(5932128.0, 15, 7), "  0.5932128E+07");
        assert_eq!(fortran_e(1e7, 15, 7), "  0.1000000E+08");
        assert_eq!(fortran_e(-1.5, 15, 7), " -0.1500000E+01");
        assert_eq!(fortran_e(0.99999999, 15, 7), "  0.1000000E+01");
        assert_eq!(fortran_e(1.5e-120, 15, 7), "  0.1500000-119");
        assert_eq!(fortran_e(f64::INFINITY, 15, 7), "       Infinity");
    }
}
