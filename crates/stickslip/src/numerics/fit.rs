//! Linear least squares for the small fits of the asymptotic analysis (a few basis functions,
//! a dozen points), solved by SVD.

use nalgebra::{DMatrix, DVector};

/// A fitted linear model `y ≈ Σ coefficients[k]·basis_k(x)`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Fit {
    /// The model, in words, e.g. "a + b ln γ + c ln ln γ".
    pub model: String,
    /// Fitted coefficients, in the order of the model's terms.
    pub coefficients: Vec<f64>,
    /// Root-mean-square residual of the fit.
    pub residual_rms: f64,
    /// Largest absolute residual.
    pub residual_max: f64,
    /// Number of points fitted.
    pub points: usize,
}

/// Fits `y ≈ Σ c_k basis[k](x)` over the points; None if there are fewer points than terms, the
/// basis is rank deficient on them, or a value is not finite.
pub fn least_squares(
    model: &str,
    x: &[f64],
    y: &[f64],
    basis: &[&dyn Fn(f64) -> f64],
) -> Option<Fit> {
    let (n, m) = (x.len(), basis.len());
    if n < m || m == 0 || n != y.len() {
        return None;
    }
    let a = DMatrix::from_fn(n, m, |i, k| basis[k](x[i]));
    let b = DVector::from_column_slice(y);
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return None;
    }
    let svd = a.clone().svd(true, true);
    let (s_max, s_min) = (svd.singular_values.max(), svd.singular_values.min());
    if s_min.is_nan() || s_min <= 1e-12 * s_max {
        return None;
    }
    let c = svd.solve(&b, 0.0).ok()?;
    let r = &a * &c - &b;
    let coefficients: Vec<f64> = c.iter().copied().collect();
    Some(Fit {
        model: model.into(),
        coefficients,
        residual_rms: (r.norm_squared() / n as f64).sqrt(),
        residual_max: r.amax(),
        points: n,
    })
}

/// A fit y ≈ a + b·x^(−p) with a free exponent p > 0: the limit a of y as x → ∞.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PowerLimit {
    /// The model, in words.
    pub model: String,
    /// The limit a.
    pub limit: f64,
    /// The amplitude b.
    pub amplitude: f64,
    /// The exponent p.
    pub exponent: f64,
    /// Root-mean-square residual.
    pub residual_rms: f64,
    /// Points fitted.
    pub points: usize,
}

/// Fits y ≈ a + b·x^(−p) (x > 0): for each p the best (a, b) by least squares, p minimising
/// the residual over (0.05, 10] (grid, then golden section). None with fewer than 4 points
/// or if the best p lies on the boundary of the search (no power-law approach).
pub fn power_limit(model: &str, x: &[f64], y: &[f64]) -> Option<PowerLimit> {
    if x.len() < 4 || x.iter().any(|&v| v.is_nan() || v <= 0.0) {
        return None;
    }
    let at = |p: f64| least_squares(model, x, y, &[&|_| 1.0, &|v: f64| v.powf(-p)]);
    let rms = |p: f64| at(p).map_or(f64::INFINITY, |f| f.residual_rms);
    let grid: Vec<f64> = (1..=200).map(|k| 0.05 * k as f64).collect();
    let best = (0..grid.len()).min_by(|&i, &j| rms(grid[i]).total_cmp(&rms(grid[j])))?;
    if best == 0 || best == grid.len() - 1 {
        return None;
    }
    let (mut lo, mut hi) = (grid[best - 1], grid[best + 1]);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if rms(a) < rms(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    let p = 0.5 * (lo + hi);
    let f = at(p)?;
    Some(PowerLimit {
        model: model.into(),
        limit: f.coefficients[0],
        amplitude: f.coefficients[1],
        exponent: p,
        residual_rms: f.residual_rms,
        points: f.points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_an_exact_model_and_refuses_too_few_points() {
        let x: Vec<f64> = (1..8).map(|k| (10f64).powi(k).ln()).collect();
        let y: Vec<f64> = x.iter().map(|l| 2.0 + 0.5 * l - 1.5 * l.ln()).collect();
        let f = least_squares("a + b L + c ln L", &x, &y, &[&|_| 1.0, &|l| l, &|l: f64| l.ln()])
            .unwrap();
        for (got, want) in f.coefficients.iter().zip([2.0, 0.5, -1.5]) {
            assert!((got - want).abs() < 1e-9, "{:?}", f.coefficients);
        }
        assert!(f.residual_max < 1e-9);
        assert!(least_squares("a + b L", &x[..1], &y[..1], &[&|_| 1.0, &|l| l]).is_none());
        assert!(least_squares("a + b", &x, &y, &[&|_| 1.0, &|_| 2.0]).is_none(), "rank deficient");
    }

    #[test]
    fn power_limit_recovers_limit_and_exponent() {
        let x: Vec<f64> = (4..=12).map(|k| 10f64.powi(k).ln()).collect();
        let y: Vec<f64> = x.iter().map(|l| 2.0944 + 100.0 * l.powf(-2.7)).collect();
        let f = power_limit("a + b x^-p", &x, &y).unwrap();
        assert!((f.limit - 2.0944).abs() < 1e-6 && (f.exponent - 2.7).abs() < 1e-3, "{f:?}");
        // A straight line has no finite limit: the exponent runs to the boundary.
        let line: Vec<f64> = x.iter().map(|l| 1.0 + 0.5 * l).collect();
        assert!(power_limit("a + b x^-p", &x, &line).is_none());
    }
}
