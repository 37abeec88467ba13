//! The statistics of a least-squares fit at its solution: covariance σ̂²(JᵀJ)⁻¹, standard
//! errors, correlations and the residuals' lag-1 autocorrelation.

use nalgebra::{DMatrix, DVector};

/// Standard errors and correlations of the parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Uncertainty {
    /// √(σ̂² (JᵀJ)⁻¹)_jj per parameter.
    pub standard_errors: Vec<f64>,
    /// The correlation matrix (row by row).
    pub correlation: Vec<Vec<f64>>,
}

/// σ̂² = |r|²/(m − p) and the covariance σ̂²(JᵀJ)⁻¹ of the m × p Jacobian `jac` at the
/// solution, inverted with the columns scaled to unit norm (the parameters' magnitudes differ
/// by decades). Err: JᵀJ is singular to working precision (names the parameters whose
/// columns are dependent, by `names`).
pub fn uncertainty(
    jac: &DMatrix<f64>,
    residuals: &DVector<f64>,
    names: &[String],
) -> Result<Uncertainty, String> {
    let (m, p) = jac.shape();
    if m <= p {
        return Err(format!(
            "{m} samples for {p} parameters: a fit needs more samples than parameters"
        ));
    }
    let sigma2 = residuals.norm_squared() / (m - p) as f64;
    let norms: Vec<f64> = jac.column_iter().map(|c| c.norm()).collect();
    if let Some(j) = norms.iter().position(|n| n.is_nan() || *n <= 0.0 || n.is_infinite()) {
        return Err(format!("the friction does not depend on {} at these samples: it cannot be fitted (leave it out of --params)", names[j]));
    }
    let scaled = DMatrix::from_fn(m, p, |i, j| jac[(i, j)] / norms[j]);
    let normal = scaled.transpose() * &scaled;
    let svd = normal.clone().svd(true, true);
    let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
    if smallest.is_nan() || smallest <= 1e-14 * largest {
        let v = svd.v_t.as_ref().map(|vt| vt.row(p - 1).transpose());
        let involved = v
            .map(|v| {
                (0..p).filter(|j| v[*j].abs() > 0.1).map(|j| names[j].clone()).collect::<Vec<_>>()
            })
            .unwrap_or_default();
        return Err(format!(
            "the parameters {} are not separately identifiable from this record (JᵀJ has condition number {:.1e}): fix one of them in the scene and leave it out of --params",
            involved.join(", "),
            largest / smallest
        ));
    }
    let inverse = normal.try_inverse().ok_or("JᵀJ could not be inverted")?;
    let cov = DMatrix::from_fn(p, p, |i, j| sigma2 * inverse[(i, j)] / (norms[i] * norms[j]));
    let standard_errors: Vec<f64> = (0..p).map(|j| cov[(j, j)].sqrt()).collect();
    let correlation = (0..p)
        .map(|i| (0..p).map(|j| cov[(i, j)] / (standard_errors[i] * standard_errors[j])).collect())
        .collect();
    Ok(Uncertainty { standard_errors, correlation })
}

/// The residuals' lag-1 autocorrelation Σ r_i r_{i+1} / Σ r_i² (0 for white noise).
pub fn lag1_autocorrelation(residuals: &[f64]) -> f64 {
    let sum2: f64 = residuals.iter().map(|r| r * r).sum();
    if sum2 == 0.0 {
        return 0.0;
    }
    residuals.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / sum2
}

/// Lag-1 autocorrelation above which the report warns that the standard errors are too small.
pub const AUTOCORRELATION_WARNING: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight-line fit y = c0 + c1 x: the textbook standard errors.
    #[test]
    fn straight_line_standard_errors() {
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let r = DVector::from_vec(vec![0.1, -0.2, 0.05, 0.0, 0.1, -0.1, 0.2, -0.05, 0.0, -0.1]);
        let jac = DMatrix::from_fn(10, 2, |i, j| if j == 0 { 1.0 } else { x[i] });
        let names = vec!["c0".to_string(), "c1".to_string()];
        let u = uncertainty(&jac, &r, &names).unwrap();
        let s2 = r.norm_squared() / 8.0;
        let sxx: f64 = x.iter().map(|v| (v - 4.5).powi(2)).sum();
        assert!((u.standard_errors[1] - (s2 / sxx).sqrt()).abs() < 1e-14);
        let se0 = (s2 * (1.0 / 10.0 + 4.5 * 4.5 / sxx)).sqrt();
        assert!((u.standard_errors[0] - se0).abs() < 1e-14);
        let singular = DMatrix::from_fn(10, 2, |i, _| x[i]);
        assert!(uncertainty(&singular, &r, &names).unwrap_err().contains("c0, c1"));
    }
}
