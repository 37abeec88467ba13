//! Ensemble statistics on a grid of times relative to the event: means, covariances between
//! grid times, correlation times and growth factors. The same functions read the linear
//! response's covariances, so both are measured identically.

/// The grid of times s = t − t_c (ascending, ≤ 0, ending at 0): `uniform` equally spaced
/// values from −far to 0, `log` values of |s| log-spaced from `far` down to `near` (dense near
/// the event), 0, and the `extra` values in [−far, 0].
pub fn grid(far: f64, near: f64, uniform: usize, log: usize, extra: &[f64]) -> Vec<f64> {
    let fraction =
        |i: usize, count: usize| if count > 1 { i as f64 / (count - 1) as f64 } else { 0.0 };
    let mut s: Vec<f64> =
        (0..log).map(|i| -(far.ln() + fraction(i, log) * (near.ln() - far.ln())).exp()).collect();
    s.extend((0..uniform).map(|i| -far * (1.0 - fraction(i, uniform))));
    s.push(0.0);
    s.extend(extra.iter().copied().filter(|v| *v >= -far && *v <= 0.0));
    s.sort_by(|a, b| a.total_cmp(b));
    s.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (1.0 + b.abs()));
    s
}

/// The index of the grid value closest to `value`.
pub fn nearest(grid: &[f64], value: f64) -> usize {
    let mut best = 0;
    for (i, g) in grid.iter().enumerate() {
        if (g - value).abs() < (grid[best] - value).abs() {
            best = i;
        }
    }
    best
}

/// Mean, variance and selected rows of the covariance between grid times of one observable.
#[derive(Debug, Clone, PartialEq)]
pub struct Moments {
    /// Mean at each grid time.
    pub mean: Vec<f64>,
    /// Variance Γ(t_k, t_k) at each grid time.
    pub var: Vec<f64>,
    /// Rows (j, [Γ(t_j, t_k) for k = 0..=j]) at the requested grid times t_j.
    pub rows: Vec<(usize, Vec<f64>)>,
}

impl Moments {
    /// From samples stored realisation-major (`samples[r * stride + offset + k]` is realisation
    /// r at grid time k), summed in realisation order (so the result does not depend on how
    /// the realisations were scheduled), with covariance rows at `rows`. Covariances use the
    /// unbiased 1/(R − 1).
    pub fn from_samples(
        samples: &[f64],
        realisations: usize,
        stride: usize,
        offset: usize,
        points: usize,
        rows: &[usize],
    ) -> Self {
        let r_n = realisations as f64;
        let value = |r: usize, k: usize| samples[r * stride + offset + k];
        let mean: Vec<f64> = (0..points)
            .map(|k| (0..realisations).map(|r| value(r, k)).sum::<f64>() / r_n)
            .collect();
        let mut var = vec![0.0; points];
        let mut cov: Vec<(usize, Vec<f64>)> = rows.iter().map(|&j| (j, vec![0.0; j + 1])).collect();
        let mut dev = vec![0.0; points];
        for r in 0..realisations {
            for k in 0..points {
                dev[k] = value(r, k) - mean[k];
                var[k] += dev[k] * dev[k];
            }
            for (j, row) in cov.iter_mut() {
                let dj = dev[*j];
                for (c, dk) in row.iter_mut().zip(&dev[..=*j]) {
                    *c += dj * dk;
                }
            }
        }
        let norm = 1.0 / (r_n - 1.0).max(1.0);
        var.iter_mut().for_each(|c| *c *= norm);
        cov.iter_mut().flat_map(|(_, row)| row.iter_mut()).for_each(|c| *c *= norm);
        Self { mean, var, rows: cov }
    }

    /// Standard deviations σ(t_k) = √Γ(t_k, t_k).
    pub fn sigma(&self) -> Vec<f64> {
        self.var.iter().map(|v| v.max(0.0).sqrt()).collect()
    }
}

/// How the correlation time is read from Γ(t, t − t').
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Width {
    /// The paper's: the half-height width of Γ(t, t − t') in t' relative to its value at
    /// t' = 0, Γ(t, t) = σ²(t).
    HalfHeight,
    /// Half-height width of the correlation coefficient Γ(t, t − t')/(σ(t) σ(t − t')): blind
    /// to the growth of σ, it measures the memory alone.
    Coefficient,
}

/// The correlation time at grid time j from its covariance row (Γ(t_j, t_k), k = 0..=j) and
/// the variances: the smallest lag t' = s_j − s_k at which the normalised Γ falls to 1/2
/// (linear interpolation between grid times); None if it stays above 1/2 back to the start of
/// the grid, or σ(t_j) = 0.
pub fn correlation_time(
    row: &[f64],
    var: &[f64],
    s: &[f64],
    j: usize,
    width: Width,
) -> Option<f64> {
    let g0 = row[j];
    if g0.is_nan() || g0 <= 0.0 {
        return None;
    }
    let normalised = |k: usize| match width {
        Width::HalfHeight => row[k] / g0,
        Width::Coefficient => row[k] / (g0 * var[k]).sqrt(),
    };
    let (mut prev, mut prev_lag) = (1.0, 0.0);
    for k in (0..j).rev() {
        let (value, lag) = (normalised(k), s[j] - s[k]);
        if !value.is_finite() {
            return None;
        }
        if value <= 0.5 {
            return Some(prev_lag + (prev - 0.5) / (prev - value) * (lag - prev_lag));
        }
        (prev, prev_lag) = (value, lag);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_is_sorted_bounded_and_keeps_extra_points() {
        let g = grid(5.0, 0.01, 11, 50, &[-0.1, -1.0, -7.0]);
        assert!(g.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(*g.last().unwrap(), 0.0);
        assert!((g[0] + 5.0).abs() < 1e-12);
        assert!(g.contains(&-0.1) && g.contains(&-1.0) && g.contains(&-2.5) && !g.contains(&-7.0));
        assert_eq!(g[nearest(&g, -0.1)], -0.1);
    }

    #[test]
    fn correlation_time_of_an_exponential_covariance() {
        // Stationary Γ(t, t − t') = e^{−t'/T}: half height at T ln 2; fine uniform grid.
        let s: Vec<f64> = (0..2001).map(|i| -2.0 + 1e-3 * i as f64).collect();
        let t_c = 0.3;
        let j = 2000;
        let row: Vec<f64> = (0..=j).map(|k| (-(s[j] - s[k]) / t_c).exp()).collect();
        let var = vec![1.0; s.len()];
        let tau = correlation_time(&row, &var, &s, j, Width::HalfHeight).unwrap();
        assert!((tau - t_c * 2f64.ln()).abs() < 1e-6, "{tau}");
        let tau = correlation_time(&row, &var, &s, j, Width::Coefficient).unwrap();
        assert!((tau - t_c * 2f64.ln()).abs() < 1e-6, "{tau}");
        // A growing variance σ²(t) = e^{2t}: the half-height width shrinks, the coefficient's not.
        let grow: Vec<f64> =
            (0..=j).map(|k| (s[j] + s[k]).exp() * (-(s[j] - s[k]) / t_c).exp()).collect();
        let var: Vec<f64> = s.iter().map(|v| (2.0 * v).exp()).collect();
        let half = correlation_time(&grow, &var, &s, j, Width::HalfHeight).unwrap();
        let expected = 2f64.ln() / (1.0 + 1.0 / t_c);
        assert!((half - expected).abs() < 1e-6, "{half} vs {expected}");
        assert!(
            (correlation_time(&grow, &var, &s, j, Width::Coefficient).unwrap() - t_c * 2f64.ln())
                .abs()
                < 1e-6
        );
        // No half-height crossing within the grid.
        let short: Vec<f64> = (0..=50).map(|k| (-(s[50] - s[k]) / t_c).exp()).collect();
        assert_eq!(correlation_time(&short, &var, &s, 50, Width::HalfHeight), None);
    }

    #[test]
    fn moments_of_known_samples() {
        // Two realisations, two grid times: (1, 2) and (3, 6).
        let samples = [1.0, 2.0, 3.0, 6.0];
        let m = Moments::from_samples(&samples, 2, 2, 0, 2, &[1]);
        assert_eq!(m.mean, vec![2.0, 4.0]);
        assert_eq!(m.var, vec![2.0, 8.0]);
        assert_eq!(m.rows, vec![(1, vec![4.0, 8.0])]);
        assert_eq!(m.sigma(), vec![2f64.sqrt(), 8f64.sqrt()]);
    }
}
