//! Regularized incomplete gamma functions: the χ² distribution function behind every p-value in
//! this module.
//!
//! `P(a, x) = γ(a, x) / Γ(a)` by its power series where that converges fast (`x < a + 1`) and
//! `Q(a, x) = 1 − P(a, x)` by its continued fraction (modified Lentz) elsewhere, as in Numerical
//! Recipes' `gammp`/`gammq`. In both far tails the small side is the one computed directly, so
//! an upper-tail probability of 1e-30 keeps its relative accuracy instead of cancelling to zero
//! in `1 − P`; near the split (`x ≈ a + 1`) the computed side stays below about 0.92 for
//! `a ≥ ½` (every χ²), so taking `1 −` it costs at most one digit. Everything is `f64`: a p-value
//! is computed once per window, not per sample, so the cost of software `f64` on the chip does
//! not matter.

/// Relative accuracy at which the series and the continued fraction stop.
const EPS: f64 = 1e-15;

/// Above this shape parameter the Wilson–Hilferty normal approximation replaces the iterations,
/// whose length grows like `√a` (absolute error below 1e-9 at `a = 2·10⁶`, tested). No test in
/// this crate comes near: Ljung–Box with `L` lags uses `a = L/2`.
const LARGE_A: f64 = 1e6;

/// Hard bound on the iterations: with `a ≤ 1e6` both expansions converge in under ~9000 terms.
const MAX_ITER: u32 = 20_000;

/// Regularized lower incomplete gamma function `P(a, x) = γ(a, x) / Γ(a)`, the distribution
/// function of a Gamma(a, 1) variable (so `P(k/2, x/2)` is the χ²(k) CDF).
///
/// Accuracy, against 50-digit references over `a ∈ [0.5, 9·10⁵]`, `x = a + z√a`, `z ∈ [−3, 10]`:
/// relative error below 2e-13 on the smaller of `P`, `Q` (the one computed directly; the other is
/// `1 −` it). Beyond `a = 10⁶` a normal approximation takes over (absolute error below 1e-9).
/// Defined for every input: `x ≤ 0` gives 0, `x = +∞` gives 1, and NaN, `a ≤ 0` or `a = ∞` give
/// NaN.
///
/// ```
/// use edgekf::residual::gamma_p;
/// // P(1, x) = 1 − e^{−x}
/// assert!((gamma_p(1.0, 2.0) - (1.0 - (-2.0f64).exp())).abs() < 1e-15);
/// ```
pub fn gamma_p(a: f64, x: f64) -> f64 {
    match Tail::of(a, x) {
        Tail::Value(v) => v,
        Tail::Lower(p) => p,
        Tail::Upper(q) => 1.0 - q,
    }
}

/// Regularized upper incomplete gamma function `Q(a, x) = 1 − P(a, x)`: the survival function,
/// so `Q(k/2, x/2)` is the upper-tail p-value of a χ²(k) statistic `x`.
///
/// Small values keep their relative accuracy (no `1 − P` cancellation where `Q` is small).
/// `x ≤ 0` gives 1, `x = +∞` gives 0, NaN or `a ≤ 0` gives NaN.
///
/// ```
/// use edgekf::residual::gamma_q;
/// // Q(1, x) = e^{−x}, far into the tail
/// assert!((gamma_q(1.0, 50.0) / (-50.0f64).exp() - 1.0).abs() < 1e-12);
/// ```
pub fn gamma_q(a: f64, x: f64) -> f64 {
    match Tail::of(a, x) {
        Tail::Value(v) => 1.0 - v,
        Tail::Lower(p) => 1.0 - p,
        Tail::Upper(q) => q,
    }
}

/// Which tail was computed directly.
enum Tail {
    /// An edge case whose `P` is exact (0, 1 or NaN).
    Value(f64),
    /// `P(a, x)`, computed by the series.
    Lower(f64),
    /// `Q(a, x)`, computed by the continued fraction.
    Upper(f64),
}

impl Tail {
    fn of(a: f64, x: f64) -> Self {
        if a.is_nan() || x.is_nan() || a <= 0.0 || a == f64::INFINITY {
            return Tail::Value(f64::NAN);
        }
        if x <= 0.0 {
            return Tail::Value(0.0);
        }
        if x == f64::INFINITY {
            return Tail::Value(1.0);
        }
        if a > LARGE_A {
            return wilson_hilferty(a, x);
        }
        if x < a + 1.0 {
            Tail::Lower(series(a, x))
        } else {
            Tail::Upper(continued_fraction(a, x))
        }
    }
}

/// `xᵃ e^{−x} / Γ(a)`, the factor shared by both expansions.
///
/// Written as `√(a/2π) · exp(−bd0(a, x) − stirlerr(a))` (Loader's saddle-point form, as in R's
/// `dpois_raw`) rather than `exp(a ln x − x − ln Γ(a))`: near `x ≈ a`, where the p-values of
/// interest live, the naive exponent cancels terms of size `a ln a` and loses about `log₁₀ a`
/// digits, while `bd0` is computed directly as the small quantity it is.
fn prefactor(a: f64, x: f64) -> f64 {
    libm::sqrt(a / (2.0 * core::f64::consts::PI)) * libm::exp(-bd0(a, x) - stirlerr(a))
}

/// `a ln(a/x) + x − a ≥ 0`, by a series in `v = (a − x)/(a + x)` when `a` and `x` are close.
fn bd0(a: f64, x: f64) -> f64 {
    if (a - x).abs() < 0.1 * (a + x) {
        let v = (a - x) / (a + x);
        let v2 = v * v;
        let mut sum = (a - x) * v;
        let mut term = 2.0 * a * v;
        for j in 1..100 {
            term *= v2;
            let next = sum + term / (2 * j + 1) as f64;
            if next == sum {
                break;
            }
            sum = next;
        }
        sum
    } else {
        a * libm::log(a / x) + x - a
    }
}

/// Stirling's error `ln Γ(a) − (a − ½) ln a + a − ½ ln 2π`: its asymptotic series for `a > 15`
/// (five terms: error below 1e-17), the definition through `lgamma` below, where nothing
/// cancels badly.
fn stirlerr(a: f64) -> f64 {
    const S0: f64 = 1.0 / 12.0;
    const S1: f64 = 1.0 / 360.0;
    const S2: f64 = 1.0 / 1260.0;
    const S3: f64 = 1.0 / 1680.0;
    const S4: f64 = 1.0 / 1188.0;
    if a > 15.0 {
        let aa = a * a;
        (S0 - (S1 - (S2 - (S3 - S4 / aa) / aa) / aa) / aa) / a
    } else {
        libm::lgamma(a) - (a - 0.5) * libm::log(a) + a - 0.5 * libm::log(2.0 * core::f64::consts::PI)
    }
}

/// `P(a, x) = e^{−x} x^a / Γ(a) · Σₙ xⁿ / (a (a+1) ⋯ (a+n))`, for `x < a + 1`.
fn series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut term = 1.0 / a;
    let mut sum = term;
    for _ in 0..MAX_ITER {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if term.abs() < sum.abs() * EPS {
            break;
        }
    }
    (sum * prefactor(a, x)).min(1.0)
}

/// `Q(a, x)` by the continued fraction `e^{−x} x^a / Γ(a) · 1/(x+1−a− 1·(1−a)/(x+3−a− …))`,
/// evaluated with the modified Lentz method, for `x ≥ a + 1`.
fn continued_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..=MAX_ITER {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    (h * prefactor(a, x)).clamp(0.0, 1.0)
}

/// For very large `a`: `(x/a)^{1/3}` is nearly normal with mean `1 − 1/(9a)` and variance
/// `1/(9a)`. The tail on the far side of the mean is returned, so it keeps relative accuracy.
fn wilson_hilferty(a: f64, x: f64) -> Tail {
    let v = 1.0 / (9.0 * a);
    let z = (libm::cbrt(x / a) - (1.0 - v)) / libm::sqrt(v);
    if z < 0.0 {
        Tail::Lower(0.5 * libm::erfc(-z / core::f64::consts::SQRT_2))
    } else {
        Tail::Upper(0.5 * libm::erfc(z / core::f64::consts::SQRT_2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn reference_values() {
        // mpmath.gammainc(a, 0, x, regularized=True) and gammainc(a, x, inf, ...), 30 digits.
        let cases = [
            // (a, x, P, Q)
            (0.5, 0.25, 0.5204998778130465, 0.4795001221869535),
            (5.0, 9.1535, 0.9499994109086018, 0.05000058909139812),
            (50.0, 50.0, 0.5188083154720433, 0.48119168452795674),
            (500.0, 500.0, 0.5059471461707603, 0.49405285382923964),
            (10.0, 100.0, 1.0, 1.1253473960842733e-31),
            (20.0, 10.0, 0.0034543419758568078, 0.9965456580241432),
            (1e4, 10150.0, 0.9326593784960509, 0.06734062150394914),
        ];
        for (a, x, p, q) in cases {
            assert!(rel(gamma_p(a, x), p) < 1e-12, "P({a}, {x}) = {} vs {p}", gamma_p(a, x));
            assert!(rel(gamma_q(a, x), q) < 1e-12, "Q({a}, {x}) = {} vs {q}", gamma_q(a, x));
        }
    }

    /// (a, x, P, Q) at `x = a + z√a`, z ∈ {−3, −1, 0, 1, 3, 6, 10}: mpmath `gammainc` at 50
    /// digits, rounded to 17. Data, not code: a CSV of 92 rows beside this file.
    const GRID: &str = include_str!("gamma_grid.csv");

    #[test]
    fn grid_against_mpmath() {
        let mut rows = 0;
        for line in GRID.lines().skip(1) {
            let mut values = line.split(',').map(|v| v.parse::<f64>().unwrap());
            let mut next = || values.next().unwrap();
            let (a, x, p, q) = (next(), next(), next(), next());
            rows += 1;
            let (gp, gq) = (gamma_p(a, x), gamma_q(a, x));
            // The smaller tail is the one computed directly (relative accuracy matters there);
            // the larger is 1 − the smaller.
            let (small, small_ref, large, large_ref) = if p < q { (gp, p, gq, q) } else { (gq, q, gp, p) };
            assert!(rel(small, small_ref) < 2e-13, "a {a} x {x}: {small:e} vs {small_ref:e}");
            assert!(rel(large, large_ref) < 2e-13, "a {a} x {x}: {large:e} vs {large_ref:e}");
        }
        assert_eq!(rows, 92);
    }

    #[test]
    fn closed_forms() {
        // P(1, x) = 1 − e^{−x};  P(1/2, x) = erf(√x).
        for x in [1e-8, 0.01, 0.3, 1.0, 2.5, 7.0, 30.0] {
            assert!((gamma_p(1.0, x) - -libm::expm1(-x)).abs() < 1e-15 * (1.0 + x), "{x}");
            assert!(rel(gamma_q(1.0, x), libm::exp(-x)) < 1e-13, "{x}");
            assert!(rel(gamma_p(0.5, x), libm::erf(libm::sqrt(x))) < 1e-13, "{x}");
            assert!(rel(gamma_q(0.5, x), libm::erfc(libm::sqrt(x))) < 1e-12, "{x}");
        }
    }

    #[test]
    fn edges_are_defined() {
        assert_eq!(gamma_p(2.0, 0.0), 0.0);
        assert_eq!(gamma_p(2.0, -3.0), 0.0);
        assert_eq!(gamma_q(2.0, -3.0), 1.0);
        assert_eq!(gamma_p(2.0, f64::INFINITY), 1.0);
        assert_eq!(gamma_q(2.0, f64::INFINITY), 0.0);
        for (a, x) in [(0.0, 1.0), (-1.0, 1.0), (f64::NAN, 1.0), (1.0, f64::NAN), (f64::INFINITY, 1.0)] {
            assert!(gamma_p(a, x).is_nan() && gamma_q(a, x).is_nan(), "{a} {x}");
        }
        // Extreme but finite arguments stay in [0, 1].
        for (a, x) in [(1e-300, 1e-300), (1e-10, 1e300), (1e300, 1.0), (1e5, 1e5), (2e6, 2e6), (3.0, 1e-300)] {
            let (p, q) = (gamma_p(a, x), gamma_q(a, x));
            assert!((0.0..=1.0).contains(&p) && (0.0..=1.0).contains(&q), "{a} {x}: {p} {q}");
        }
    }

    #[test]
    fn wilson_hilferty_beyond_a_million() {
        // mpmath at 50 digits, a = 2·10⁶, x = a + z√a for z = −3, 0, 3, 6.
        let cases = [
            (1995757.3593128808, 0.998658446546177),
            (2000000.0, 0.49990596840248086),
            (2004242.6406871192, 0.0013582669845885267),
            (2008485.2813742387, 1.0378386171870452e-09),
        ];
        for (x, q) in cases {
            let got = gamma_q(2e6, x);
            assert!((got - q).abs() < 1e-9 && rel(got, q) < 1e-4, "{x}: {got:e} vs {q:e}");
        }
    }

    #[test]
    fn large_shape_switches_smoothly() {
        // Either side of the Wilson–Hilferty switch agree to the approximation's accuracy.
        let a = LARGE_A;
        for z in [-3.0, 0.0, 2.0] {
            let x = a + z * libm::sqrt(a);
            let below = gamma_p(a * (1.0 - 1e-12), x);
            let above = gamma_p(a * (1.0 + 1e-12), x);
            assert!((below - above).abs() < 1e-6, "{z}: {below} {above}");
        }
    }
}
