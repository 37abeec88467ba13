//! The record's load-point displacement against the scene's loading: a record in other units
//! (metres against a scene in µm) or a velocity typed wrong in the scene is refused before a
//! fit starts, naming the units or the segment.

use crate::model::Loading;

/// Largest ratio, either way, between the record's load-point velocity (the slope of its x_lp
/// over a segment) and the scene's, before the two are called inconsistent.
pub const VELOCITY_RATIO_LIMIT: f64 = 2.0;

/// Checks the record's x_lp (`x` at times `t`, inside the loading) against `loading`,
/// segment by segment: the least-squares slope of x over each sliding segment's samples
/// against the segment's velocity. Segments with fewer than 3 samples, holds, and slopes
/// whose standard error exceeds a tenth of the scene's velocity are not judged. Err: the
/// message names the units (a power of ten on every judged segment) or the segment and both
/// velocities.
pub fn check_displacement(t: &[f64], x: &[f64], loading: &Loading) -> Result<(), String> {
    let n = loading.segments.len();
    let mut judged = vec![]; // (segment, scene velocity, record's slope)
    for (j, seg) in loading.segments.iter().enumerate() {
        let (t0, t1) = (seg.t_start, loading.segment_end(j));
        let inside: Vec<(f64, f64)> = t
            .iter()
            .zip(x)
            .filter(|(ti, _)| **ti >= t0 && **ti < t1)
            .map(|(ti, xi)| (*ti, *xi))
            .collect();
        if seg.velocity <= 0.0 || inside.len() < 3 {
            continue;
        }
        let (slope, se) = slope(&inside);
        if se.is_nan() || se > 0.1 * seg.velocity {
            continue;
        }
        judged.push((j, seg.velocity, slope));
    }
    let bad: Vec<&(usize, f64, f64)> = judged
        .iter()
        .filter(|(_, v, s)| {
            !(*s / *v <= VELOCITY_RATIO_LIMIT && *s / *v >= 1.0 / VELOCITY_RATIO_LIMIT)
        })
        .collect();
    let Some(first) = bad.first() else {
        return Ok(());
    };
    // A power of ten shared by every judged segment: the units differ.
    let power = |(_, v, s): &(usize, f64, f64)| {
        let e = (s / v).log10();
        (e.is_finite() && (e - e.round()).abs() < 0.15 && e.round() != 0.0)
            .then(|| e.round() as i32)
    };
    let powers: Vec<Option<i32>> = judged.iter().map(power).collect();
    if bad.len() == judged.len() && powers.iter().all(|p| p.is_some() && *p == powers[0]) {
        let k = powers[0].expect("checked");
        return Err(format!(
            "the record's x_lp moves 1e{k} times as fast as the scene's loading (the record's {:.4e} per s against the scene's {} µm/s in segment {} of {n}): {}; lab scenes are in µm and s (docs/lab.md), so convert the record's x_lp column (multiply it by 1e{}) or the scene",
            first.2,
            first.1,
            first.0 + 1,
            units(k),
            -k
        ));
    }
    let (j, v, s) = **first;
    Err(format!(
        "segment {} of {n} (from t = {} s): the scene's load-point velocity {v} µm/s is {:.3}× the record's, whose x_lp moves at {s:.5} µm/s there (its least-squares slope): a typo in the scene's loading? Give the velocity the record shows (data/scenes/lab-basalt-b819.json takes them from a line fitted to each part of the record), or drop the record's x_lp column from --columns if it is not the load point's displacement",
        j + 1,
        loading.segments[j].t_start,
        v / s
    ))
}

/// The least-squares slope of y against t and its standard error.
fn slope(points: &[(f64, f64)]) -> (f64, f64) {
    let m = points.len() as f64;
    let (tm, ym) = points.iter().fold((0.0, 0.0), |(a, b), (t, y)| (a + t / m, b + y / m));
    let (sxx, sxy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (t, y)| (a + (t - tm) * (t - tm), b + (t - tm) * (y - ym)));
    let s = sxy / sxx;
    let rss: f64 = points.iter().map(|(t, y)| (y - ym - s * (t - tm)).powi(2)).sum();
    let se = if points.len() > 2 { (rss / (m - 2.0) / sxx).sqrt() } else { f64::INFINITY };
    (s, se)
}

/// What a factor 10^k between the record's x_lp and a scene in µm says about the units.
fn units(k: i32) -> String {
    match k {
        -6 => "the record's x_lp looks to be in metres against the scene's µm".into(),
        -3 => "the record's x_lp looks to be in mm against the scene's µm".into(),
        -4 => "the record's x_lp looks to be in cm against the scene's µm".into(),
        3 => "the record's x_lp looks to be in nm against the scene's µm, or the scene's velocities in mm/s".into(),
        6 => "the scene's velocities look to be in m/s against the record's x_lp in µm".into(),
        _ => format!("the record's x_lp and the scene's loading differ in units by a factor 1e{k}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Segment;

    fn loading() -> Loading {
        let seg = |t_start, velocity| Segment { t_start, velocity };
        Loading::new(vec![seg(0.0, 3.0), seg(10.0, 10.0)], 20.0).unwrap()
    }

    /// A record consistent with the loading passes; in metres it is refused naming the units;
    /// a velocity typed 10× too large is refused naming the segment.
    #[test]
    fn the_records_displacement_is_checked_against_the_loading() {
        let l = loading();
        let t: Vec<f64> = (0..200).map(|i| 0.1 * f64::from(i)).collect();
        let x = l.displacements_at(&t);
        assert!(check_displacement(&t, &x, &l).is_ok());
        let metres: Vec<f64> = x.iter().map(|v| 1e-6 * v + 0.0085).collect();
        let e = check_displacement(&t, &metres, &l).unwrap_err();
        assert!(e.contains("metres") && e.contains("µm"), "{e}");
        let seg = |t_start, velocity| Segment { t_start, velocity };
        let typo = Loading::new(vec![seg(0.0, 3.0), seg(10.0, 100.0)], 20.0).unwrap();
        let e = check_displacement(&t, &x, &typo).unwrap_err();
        assert!(e.contains("segment 2 of 2") && e.contains("typo"), "{e}");
    }
}
