//! Data series for figures, reduced to a moderate size by keeping a subset of the computed
//! samples (never interpolated ones): equal steps of arc length in normalised coordinates, so
//! that a slip lasting 1e-8 of the cycle keeps as many points as its share of the curve, plus
//! the first, the last and the extrema of every spacing column.

/// Indices (increasing) of at most `max_points` (≥ 2) samples of the curve
/// (x, `columns[0]`, `columns[1]`, …), chosen at equal steps of arc length in coordinates
/// normalised by their ranges. All indices if there are at most `max_points` samples.
pub fn decimate(x: &[f64], columns: &[&[f64]], max_points: usize) -> Vec<usize> {
    let n = x.len();
    let max_points = max_points.max(2);
    if n <= max_points {
        return (0..n).collect();
    }
    let range = |c: &[f64]| {
        let (lo, hi) = c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        if hi > lo {
            hi - lo
        } else {
            1.0
        }
    };
    let mut coords: Vec<(&[f64], f64)> = vec![(x, range(x))];
    coords.extend(columns.iter().map(|c| (*c, range(c))));
    let mut arc = vec![0.0; n];
    for i in 1..n {
        let step: f64 =
            coords.iter().map(|(c, r)| ((c[i] - c[i - 1]) / r).powi(2)).sum::<f64>().sqrt();
        arc[i] = arc[i - 1] + step;
    }
    // Extrema of each spacing column and the two ends are always kept.
    let mut keep: Vec<usize> = vec![0, n - 1];
    for c in columns {
        let arg = |better: fn(f64, f64) -> bool| {
            (0..n).fold(0, |b, i| if better(c[i], c[b]) { i } else { b })
        };
        keep.push(arg(|a, b| a > b));
        keep.push(arg(|a, b| a < b));
    }
    keep.sort_unstable();
    keep.dedup();
    let slots = max_points.saturating_sub(keep.len()).max(1);
    let total = arc[n - 1];
    if total > 0.0 {
        let mut next = 1;
        for (i, &s) in arc.iter().enumerate() {
            if next < slots && s >= total * next as f64 / slots as f64 {
                keep.push(i);
                next += 1;
            }
        }
    }
    keep.sort_unstable();
    keep.dedup();
    keep
}

/// The values at the given indices.
pub fn pick(values: &[f64], indices: &[usize]) -> Vec<f64> {
    indices.iter().map(|&i| values[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_ends_extrema_and_the_size_limit() {
        // A long flat stretch and a narrow spike: the spike keeps points.
        let x: Vec<f64> = (0..100_000).map(|i| i as f64 * 1e-3).collect();
        let y: Vec<f64> = x.iter().map(|&t| (-((t - 70.0) / 0.05).powi(2)).exp()).collect();
        let idx = decimate(&x, &[&y], 500);
        assert!(idx.len() <= 500 && idx.len() > 400, "{}", idx.len());
        assert_eq!((idx[0], *idx.last().unwrap()), (0, 99_999));
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
        assert!(idx.contains(&70_000), "the peak is kept");
        let near_spike = idx.iter().filter(|&&i| (69_900..70_100).contains(&i)).count();
        assert!(near_spike >= 10, "the spike is resolved: {near_spike}");
        assert_eq!(decimate(&x[..10], &[&y[..10]], 500), (0..10).collect::<Vec<_>>());
    }
}
