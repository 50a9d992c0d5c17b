//! One-dimensional maximisation for the effects' scalars (a factor, a delay, a frequency): a
//! coarse grid to find the right basin (a log-likelihood in a stiffness factor can have side
//! lobes where a natural frequency crosses a line), then Brent's method inside the bracket.

/// The range a scalar effect parameter is fitted over, and how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarRange {
    /// Lower end (in the fitting variable).
    pub low: f64,
    /// Upper end.
    pub high: f64,
    /// Where the model is unchanged (1 for a factor, 0 for a delay).
    pub neutral: f64,
    /// Fitted in `ln` (factors), so the report shows `exp(θ)`.
    pub log: bool,
    /// Tolerance of the fit.
    pub tolerance: f64,
}

impl ScalarRange {
    /// A factor on a declared value, fitted in `ln` between `low` and `high` (neutral at 1) to
    /// `tolerance` in `ln`.
    ///
    /// ```
    /// use edgekf_sim::residual_loop::ScalarRange;
    /// let r = ScalarRange::factor(0.5, 2.0, 1e-4);
    /// assert_eq!((r.low, r.high, r.neutral, r.log), (0.5f64.ln(), 2f64.ln(), 0.0, true));
    /// ```
    pub fn factor(low: f64, high: f64, tolerance: f64) -> Self {
        Self { low: low.ln(), high: high.ln(), neutral: 0.0, log: true, tolerance }
    }
}

/// The best point found and how many evaluations it took.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Maximum {
    /// Argument.
    pub x: f64,
    /// Value there.
    pub value: f64,
    /// Evaluations used.
    pub evaluations: usize,
}

/// Maximises `f` over `[low, high]`: `grid` equally spaced interior points, then Brent's
/// parabolic/golden-section search between the best grid point's neighbours to `tolerance`.
/// Evaluations that fail (return `None`) count as −∞. Returns `None` if every evaluation failed.
///
/// ```
/// use edgekf_sim::residual_loop::optimize::maximise;
/// // A log-likelihood-like bowl with its top at 0.3.
/// let m = maximise(|x| Some(-(x - 0.3f64).powi(2)), -1.0, 1.0, 8, 1e-8).unwrap();
/// assert!((m.x - 0.3).abs() < 1e-6);
/// ```
pub fn maximise(
    mut f: impl FnMut(f64) -> Option<f64>,
    low: f64,
    high: f64,
    grid: usize,
    tolerance: f64,
) -> Option<Maximum> {
    let mut evaluations = 0;
    let mut eval = |x: f64| {
        evaluations += 1;
        f(x).filter(|v| v.is_finite()).unwrap_or(f64::NEG_INFINITY)
    };
    let n = grid.max(1);
    let xs: Vec<f64> = (0..n + 2).map(|i| low + (high - low) * i as f64 / (n + 1) as f64).collect();
    let mut values = vec![f64::NEG_INFINITY; xs.len()];
    for i in 1..=n {
        values[i] = eval(xs[i]);
    }
    let best = (1..=n).max_by(|&a, &b| values[a].total_cmp(&values[b]))?;
    if values[best] == f64::NEG_INFINITY {
        return None;
    }
    let (a, b) = (xs[best - 1], xs[best + 1]);
    let (x, value) = brent(|x| -eval(x), a, b, xs[best], -values[best], tolerance);
    let (x, value) = if -value >= values[best] { (x, -value) } else { (xs[best], values[best]) };
    Some(Maximum { x, value, evaluations })
}

/// Brent's minimiser on `[a, b]` started at `x` (with `fx = f(x)`), to absolute `tol`.
fn brent(mut f: impl FnMut(f64) -> f64, mut a: f64, mut b: f64, x0: f64, fx0: f64, tol: f64) -> (f64, f64) {
    const GOLD: f64 = 0.381_966_011_250_105_1;
    let (mut x, mut w, mut v) = (x0, x0, x0);
    let (mut fx, mut fw, mut fv) = (fx0, fx0, fx0);
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        let tol1 = tol + 1e-12 * x.abs();
        let tol2 = 2.0 * tol1;
        if (x - m).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 {
            // Parabola through x, w, v.
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < m { tol1 } else { -tol1 };
                }
                golden = false;
            }
        }
        if golden {
            e = if x < m { b - x } else { a - x };
            d = GOLD * e;
        }
        let u = if d.abs() >= tol1 { x + d } else { x + tol1.copysign(d) };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    (x, fx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_smooth_maximum_in_few_evaluations() {
        let m = maximise(|x| Some(-(x - 1.234_567f64).powi(2)), 0.0, 3.0, 5, 1e-9).unwrap();
        assert!((m.x - 1.234_567).abs() < 1e-6, "{m:?}");
        assert!(m.evaluations < 5 + 20, "{m:?}");
    }

    #[test]
    fn the_grid_picks_the_main_lobe_over_a_side_lobe() {
        // A side maximum at 0.2 (value 0.5), the main one at 0.8 (value 1).
        let f = |x: f64| Some((-(x - 0.8f64).powi(2) * 400.0).exp() + 0.5 * (-(x - 0.2f64).powi(2) * 400.0).exp());
        let m = maximise(f, 0.0, 1.0, 9, 1e-9).unwrap();
        assert!((m.x - 0.8).abs() < 1e-4, "{m:?}");
    }

    #[test]
    fn failed_evaluations_are_minus_infinity() {
        let m = maximise(|x| (x > 0.5).then(|| -(x - 0.7f64).powi(2)), 0.0, 1.0, 4, 1e-9).unwrap();
        assert!((m.x - 0.7).abs() < 1e-5);
        assert!(maximise(|_| None, 0.0, 1.0, 4, 1e-9).is_none());
    }
}
