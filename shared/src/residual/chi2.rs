use super::gamma::{gamma_p, gamma_q};

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

/// Quantile of the χ² distribution with `dof` degrees of freedom: the Wilson–Hilferty cube
/// approximation as a start, refined by Newton steps on the exact distribution function (on
/// the upper tail for `p > ½`, so tiny tail probabilities keep their accuracy). Relative error
/// below 1e-10 wherever the start converges, which the tests check over `dof` from 1 to 10⁵ and
/// `p` from 1e-6 to 1 − 1e-6. NaN for `p` outside (0, 1) or `dof ≤ 0`.
///
/// ```
/// use edgekf::residual::chi2_quantile;
/// // Tables: χ²₀.₉₅(10) = 18.307038, χ²₀.₀₅(100) = 77.929465, χ²₀.₀₂₅(3) = 0.215795
/// assert!((chi2_quantile(0.95, 10.0) / 18.307038053275146 - 1.0).abs() < 1e-10);
/// assert!((chi2_quantile(0.05, 100.0) / 77.92946516501153 - 1.0).abs() < 1e-10);
/// assert!((chi2_quantile(0.025, 3.0) / 0.2157952826238981 - 1.0).abs() < 1e-9);
/// ```
pub fn chi2_quantile(p: f64, dof: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && dof > 0.0) {
        return f64::NAN;
    }
    let z = normal_quantile(p);
    let a = 2.0 / (9.0 * dof);
    let c = 1.0 - a + z * libm::sqrt(a);
    // The cube can go negative (small dof, small p): start from a small positive value instead.
    let mut x = if c > 0.0 { dof * c * c * c } else { dof * 1e-3 };
    let half = 0.5 * dof;
    let log_norm = half * core::f64::consts::LN_2 + libm::lgamma(half);
    for _ in 0..60 {
        let density = libm::exp((half - 1.0) * libm::log(x) - 0.5 * x - log_norm);
        if !density.is_finite() || density <= 0.0 {
            break;
        }
        // Residual in the tail we are solving for, so that its relative accuracy is kept.
        let step = if p > 0.5 { (1.0 - p - chi2_sf(x, dof)) / -density } else { (p - chi2_cdf(x, dof)) / density };
        let mut next = x + step;
        if next <= 0.0 {
            next = 0.5 * x;
        }
        let done = (next - x).abs() <= 1e-14 * x;
        x = next;
        if done {
            break;
        }
    }
    x
}

/// Distribution function of the χ² distribution with `dof` degrees of freedom, `P(dof/2, x/2)`
/// (see [`gamma_p`](crate::residual::gamma_p) for the accuracy).
///
/// `x ≤ 0` gives 0; NaN, `dof ≤ 0` or `dof = ∞` give NaN.
///
/// ```
/// use edgekf::residual::chi2_cdf;
/// // scipy.stats.chi2.cdf(100, 100)
/// assert!((chi2_cdf(100.0, 100.0) - 0.5188083154720433).abs() < 1e-13);
/// ```
pub fn chi2_cdf(x: f64, dof: f64) -> f64 {
    gamma_p(0.5 * dof, 0.5 * x)
}

/// Upper tail `1 − CDF` of the χ² distribution with `dof` degrees of freedom: the p-value of a
/// statistic `x` that is χ²(dof) under the null hypothesis. Computed directly (not as `1 − CDF`),
/// so tiny p-values keep their relative accuracy.
///
/// `x ≤ 0` gives 1; NaN, `dof ≤ 0` or `dof = ∞` give NaN.
///
/// ```
/// use edgekf::residual::chi2_sf;
/// // scipy.stats.chi2.sf(18.307, 10) and chi2.sf(3.0, 1)
/// assert!((chi2_sf(18.307, 10.0) - 0.05).abs() < 1e-6);
/// assert!((chi2_sf(3.0, 1.0) - 0.08326451666355039).abs() < 1e-14);
/// ```
pub fn chi2_sf(x: f64, dof: f64) -> f64 {
    gamma_q(0.5 * dof, 0.5 * x)
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

    #[test]
    fn chi2_distribution_reference_values() {
        // scipy.stats.chi2 (and mpmath at 30 digits for the far tail).
        assert!((chi2_sf(18.307, 10.0) - 0.0500005890913981).abs() < 1e-15);
        assert!((chi2_sf(3.0, 1.0) - 0.08326451666355039).abs() < 1e-15);
        assert!((chi2_cdf(100.0, 100.0) - 0.5188083154720433).abs() < 1e-14);
        assert!((chi2_sf(200.0, 20.0) / 1.1253473960842734e-31 - 1.0).abs() < 1e-12);
        assert!((chi2_cdf(2.0, 2.0) - (1.0 - libm::exp(-1.0))).abs() < 1e-15);
        assert_eq!(chi2_cdf(-1.0, 3.0), 0.0);
        assert_eq!(chi2_sf(0.0, 3.0), 1.0);
        assert!(chi2_cdf(1.0, 0.0).is_nan() && chi2_sf(f64::NAN, 3.0).is_nan());
    }

    #[test]
    fn quantile_inverts_the_distribution_function() {
        for dof in [1.0, 2.0, 3.0, 5.0, 10.0, 30.0, 1000.0, 1e5] {
            for p in [1e-6, 1e-3, 0.005, 0.025, 0.05, 0.5, 0.95, 0.975, 0.995, 0.999, 1.0 - 1e-6] {
                let x = chi2_quantile(p, dof);
                let back = if p > 0.5 { 1.0 - chi2_sf(x, dof) } else { chi2_cdf(x, dof) };
                let tail = p.min(1.0 - p);
                assert!(((back - p) / tail).abs() < 1e-9, "dof {dof} p {p}: x {x}, back {back}");
            }
        }
        assert!(chi2_quantile(0.0, 3.0).is_nan() && chi2_quantile(0.5, 0.0).is_nan());
    }
}
