use crate::Real;

/// Running mean and variance (Welford's algorithm: one pass, no catastrophic cancellation).
///
/// ```
/// use edgekf::residual::RunningStats;
/// let mut s = RunningStats::<f64>::new();
/// for v in [1.0, 2.0, 3.0, 4.0] { s.push(v); }
/// assert_eq!(s.mean(), 2.5);
/// assert!((s.variance() - 5.0 / 3.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunningStats<T: Real> {
    n: u32,
    mean: T,
    m2: T,
}

impl<T: Real> Default for RunningStats<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> RunningStats<T> {
    /// Empty statistics.
    pub fn new() -> Self {
        Self { n: 0, mean: T::zero(), m2: T::zero() }
    }

    /// Adds one value (non-finite values are ignored: they are counted elsewhere).
    ///
    /// The count saturates at `u32::MAX` instead of overflowing (at 1 kHz that is 50 days); from
    /// there on the statistics become an exponentially weighted average with that time
    /// constant. In `f32`, the mean effectively stops moving after about 2²⁴ values (4.7 hours
    /// at 1 kHz): for long runs on the chip, [`RunningStats::reset`] it per reporting period.
    pub fn push(&mut self, v: T) {
        if !v.is_finite() {
            return;
        }
        self.n = self.n.saturating_add(1);
        let d = v - self.mean;
        self.mean += d / T::of_f64(self.n as f64);
        self.m2 += d * (v - self.mean);
    }

    /// Starts over.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Number of values.
    pub fn count(&self) -> u32 {
        self.n
    }

    /// Mean (0 when empty).
    pub fn mean(&self) -> T {
        self.mean
    }

    /// Unbiased sample variance (0 with fewer than two values).
    pub fn variance(&self) -> T {
        if self.n < 2 {
            T::zero()
        } else {
            self.m2 / T::of_f64((self.n - 1) as f64)
        }
    }

    /// Standard error of the mean, `sqrt(var / n)`; a mean several times this is a bias.
    pub fn standard_error(&self) -> T {
        if self.n < 2 {
            T::zero()
        } else {
            (self.variance() / T::of_f64(self.n as f64)).sqrt()
        }
    }

    /// Root mean square, `sqrt(mean² + var·(n−1)/n)`.
    pub fn rms(&self) -> T {
        if self.n == 0 {
            return T::zero();
        }
        (self.mean * self.mean + self.m2 / T::of_f64(self.n as f64)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_offset_does_not_cancel() {
        let mut s = RunningStats::<f64>::new();
        for k in 0..1000 {
            s.push(1e9 + (k % 2) as f64);
        }
        assert!((s.variance() - 0.25025025025).abs() < 1e-9);
        assert!((s.rms() - (1e9 + 0.5)).abs() < 1e-3);
        s.push(f64::NAN);
        assert_eq!(s.count(), 1000);
    }
}
