/// Quantile of the standard normal distribution (Acklam's rational approximation refined by one
/// Halley step; absolute error below 1e-12 for `p` in [1e-12, 1 − 1e-12]). Returns NaN outside
/// (0, 1).
///
/// ```
/// use edgekf::residual::normal_quantile;
/// assert!((normal_quantile(0.975) - 1.959963984540054).abs() < 1e-9);
/// ```
pub fn normal_quantile(p: f64) -> f64 {
    if !(p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.38357751867269e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] =
        [-5.447609879822406e1, 1.615858368580409e2, -1.556989798598866e2, 6.680131188771972e1, -1.328068155288572e1];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    let p_low = 0.02425;
    let x = if p < p_low {
        let q = libm::sqrt(-2.0 * libm::log(p));
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - p_low {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = libm::sqrt(-2.0 * libm::log(1.0 - p));
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // One Halley step on Φ(x) − p.
    let e = 0.5 * libm::erfc(-x / core::f64::consts::SQRT_2) - p;
    let u = e * libm::sqrt(2.0 * core::f64::consts::PI) * libm::exp(x * x / 2.0);
    x - u / (1.0 + x * u / 2.0)
}

/// Quantile of the χ² distribution with `dof` degrees of freedom (Wilson–Hilferty cube
/// approximation: relative error under 1 % for `dof ≥ 3` in the tails used for consistency tests,
/// and better as `dof` grows, which is the case for windowed NIS sums).
///
/// ```
/// use edgekf::residual::chi2_quantile;
/// // Tables: χ²₀.₉₅(10) = 18.307, χ²₀.₀₅(100) = 77.929
/// assert!((chi2_quantile(0.95, 10.0) / 18.307 - 1.0).abs() < 2e-3);
/// assert!((chi2_quantile(0.05, 100.0) / 77.929 - 1.0).abs() < 1e-3);
/// ```
pub fn chi2_quantile(p: f64, dof: f64) -> f64 {
    let z = normal_quantile(p);
    let a = 2.0 / (9.0 * dof);
    let c = 1.0 - a + z * libm::sqrt(a);
    dof * c * c * c
}

/// Two-sided acceptance interval for the mean NIS of `n` independent innovations of dimension
/// `m`: `n·mean(NIS) ~ χ²(n m)` when the filter is consistent.
///
/// ```
/// use edgekf::residual::NisBounds;
/// let b = NisBounds::new(1, 1000, 0.01);
/// assert!(b.contains(1.0) && !b.contains(1.2) && !b.contains(0.85));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NisBounds {
    /// Lower bound on the mean NIS.
    pub lower: f64,
    /// Upper bound on the mean NIS.
    pub upper: f64,
}

impl NisBounds {
    /// Bounds at false-alarm probability `alpha` (split equally between the two tails).
    pub fn new(m: usize, n: usize, alpha: f64) -> Self {
        let dof = (m * n) as f64;
        Self {
            lower: chi2_quantile(alpha / 2.0, dof) / n as f64,
            upper: chi2_quantile(1.0 - alpha / 2.0, dof) / n as f64,
        }
    }

    /// Whether `mean_nis` lies inside the interval.
    pub fn contains(&self, mean_nis: f64) -> bool {
        mean_nis >= self.lower && mean_nis <= self.upper
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantile_reference_values() {
        // scipy.stats.norm.ppf
        for (p, z) in [(0.5, 0.0), (0.995, 2.5758293035489004), (1e-6, -4.753424308822899), (0.01, -2.3263478740408408)]
        {
            assert!((normal_quantile(p) - z).abs() < 1e-9, "{p}");
        }
        assert!(normal_quantile(0.0).is_nan() && normal_quantile(1.5).is_nan());
    }
}
