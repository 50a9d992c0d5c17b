//! Axes: a linear or logarithmic range, the constructors that fit one to data (exact span,
//! padded, with headroom, log around a reference value, log frequency), the mapping between
//! values and fractions along the axis that clipping and markers use, and the tick labels.

/// An axis: its scale and range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Axis {
    /// Linear from the first to the second value.
    Linear(f64, f64),
    /// Logarithmic from the first to the second value (both positive).
    Log(f64, f64),
}

impl Axis {
    /// The smallest and largest finite values of `v` (None when there are none).
    pub fn extent(v: &[f64]) -> Option<(f64, f64)> {
        let (lo, hi) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        (lo <= hi).then_some((lo, hi))
    }

    /// A linear axis exactly over the finite values of `v` (time axes).
    pub fn span(v: &[f64]) -> Self {
        match Self::extent(v) {
            Some((lo, hi)) if hi > lo => Axis::Linear(lo, hi),
            Some((lo, _)) => Axis::Linear(lo - 0.5, lo + 0.5),
            None => Axis::Linear(0.0, 1.0),
        }
    }

    /// A linear axis over the finite values of `v`, padded by 5 % (`0..1` when there are none).
    pub fn linear(v: &[f64]) -> Self {
        match Self::extent(v) {
            Some((lo, hi)) if hi > lo => Axis::Linear(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)),
            Some((lo, _)) => Axis::Linear(lo - lo.abs().max(1.0) * 0.5, lo + lo.abs().max(1.0) * 0.5),
            None => Axis::Linear(0.0, 1.0),
        }
    }

    /// The axis with its end raised by `fraction` of its length (room for labels over the
    /// highest points).
    pub fn headroom(self, fraction: f64) -> Self {
        match self {
            Axis::Linear(a, b) => Axis::Linear(a, b + fraction * (b - a)),
            Axis::Log(a, b) => Axis::Log(a, b * (b / a).powf(fraction)),
        }
    }

    /// A log axis over the positive finite values, always including `keep` (with a margin).
    pub fn log_around(v: impl IntoIterator<Item = f64>, keep: f64) -> Self {
        let (lo, hi) = v
            .into_iter()
            .filter(|x| x.is_finite() && *x > 0.0)
            .fold((keep, keep), |(lo, hi), x| (lo.min(x), hi.max(x)));
        Axis::Log(lo / 1.5, hi * 1.5)
    }

    /// A log frequency axis from the lowest to the highest frequency of `spectrum`.
    pub fn log_frequency(spectrum: &[(f64, f64)]) -> Self {
        let f: Vec<f64> = spectrum.iter().map(|p| p.0).filter(|f| *f > 0.0).collect();
        match Self::extent(&f) {
            Some((lo, hi)) if hi > lo => Axis::Log(lo, hi),
            _ => Axis::Log(1.0, 1000.0),
        }
    }

    /// The range's ends.
    pub fn ends(self) -> (f64, f64) {
        match self {
            Axis::Linear(a, b) | Axis::Log(a, b) => (a, b),
        }
    }

    /// Where `v` sits along the axis (0 at the start, 1 at the end; outside for values out of
    /// range); None when the axis cannot place it (not finite, or not positive on a log axis).
    pub fn fraction(self, v: f64) -> Option<f64> {
        let f = match self {
            Axis::Linear(a, b) => (v - a) / (b - a),
            Axis::Log(a, b) if v > 0.0 => (v / a).ln() / (b / a).ln(),
            Axis::Log(..) => return None,
        };
        f.is_finite().then_some(f)
    }

    /// The value at fraction `f` along the axis (the inverse of [`Axis::fraction`]).
    pub fn value(self, f: f64) -> f64 {
        match self {
            Axis::Linear(a, b) => a + f * (b - a),
            Axis::Log(a, b) => a * (b / a).powf(f),
        }
    }
}

/// An axis tick label: short, without trailing zeros (`0.25`, `10`, `-3`; `1e-5` and `2e5`
/// outside `0.001..100000`).
pub fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.0e}");
    }
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(-3.0), "-3");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(2e-5), "2e-5");
        assert_eq!(tick(3e5), "3e5");
    }

    #[test]
    fn fractions_and_values_are_inverse() {
        let lin = Axis::Linear(-2.0, 6.0);
        assert_eq!(lin.fraction(2.0), Some(0.5));
        assert_eq!(lin.fraction(10.0), Some(1.5));
        assert_eq!(lin.value(0.25), 0.0);
        let log = Axis::Log(1.0, 1000.0);
        assert!((log.fraction(10.0).unwrap() - 1.0 / 3.0).abs() < 1e-12);
        assert!((log.value(2.0 / 3.0) - 100.0).abs() < 1e-9);
        assert_eq!(log.fraction(0.0), None);
        assert_eq!(lin.fraction(f64::NAN), None);
    }

    #[test]
    fn axes_fit_their_data() {
        assert_eq!(Axis::span(&[3.0, f64::NAN, 1.0, 2.0]), Axis::Linear(1.0, 3.0));
        assert_eq!(Axis::linear(&[0.0, 10.0]), Axis::Linear(-0.5, 10.5));
        assert_eq!(Axis::linear(&[f64::NAN]), Axis::Linear(0.0, 1.0));
        assert_eq!(Axis::Linear(0.0, 10.0).headroom(0.2), Axis::Linear(0.0, 12.0));
        assert_eq!(Axis::log_around([0.5, 3.0, -1.0, f64::INFINITY], 1.0), Axis::Log(0.5 / 1.5, 4.5));
        assert_eq!(Axis::log_frequency(&[(0.0, 1.0), (2.0, 1.0), (500.0, 1.0)]), Axis::Log(2.0, 500.0));
    }
}
