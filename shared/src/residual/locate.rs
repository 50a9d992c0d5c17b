//! Where a spectral peak of the innovations sits relative to the machine: an order of the
//! running speed, a natural frequency of the model, both, or neither (see [`locate_peak`]).

use crate::Real;

/// How close a peak must be to a reference frequency `f_ref` to be attributed to it:
/// `|f − f_ref| ≤ abs_hz + rel · f_ref`.
///
/// The absolute part is the frequency resolution of the peak (about one bin width `fs/N` of the
/// spectrum); the relative parts are what is uncertain about the reference: the running speed
/// (an error of ε in Ω moves the `k×` line by `k·ε·Ω`, hence relative) and the model's natural
/// frequencies (typically a few percent).
///
/// ```
/// use edgekf::residual::PeakTolerance;
/// let tol = PeakTolerance::new(1.0f64); // 1 Hz resolution, default relative parts
/// assert_eq!(tol.max_denominator, 1);
/// assert!(tol.order_rel < tol.natural_rel);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakTolerance<T: Real> {
    /// Frequency resolution, Hz.
    pub abs_hz: T,
    /// Relative uncertainty of the running speed.
    pub order_rel: T,
    /// Relative uncertainty of the model's natural frequencies.
    pub natural_rel: T,
    /// Largest denominator `q` of an order `p/q`: 1 for integer orders only, 2 to also
    /// recognise ½×, 3⁄2×, …, 3 for ⅓×, ⅔×, ….
    pub max_denominator: u32,
}

impl<T: Real> PeakTolerance<T> {
    /// `abs_hz` (the resolution, e.g. the bin width) with a running speed known to 0.5 %,
    /// natural frequencies to 5 %, and integer orders only.
    pub fn new(abs_hz: T) -> Self {
        Self { abs_hz, order_rel: T::of_f64(0.005), natural_rel: T::of_f64(0.05), max_denominator: 1 }
    }
}

/// An order `numerator / denominator` of the running speed, in lowest terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Order {
    /// `p` in `p/q`.
    pub numerator: u32,
    /// `q` in `p/q` (1 for an integer order).
    pub denominator: u32,
}

impl Order {
    /// Whether this is an integer order `k×`.
    pub fn is_integer(&self) -> bool {
        self.denominator == 1
    }

    /// `p/q` as a number.
    pub fn value<T: Real>(&self) -> T {
        T::of_f64(self.numerator as f64 / self.denominator as f64)
    }
}

/// The running-speed order a peak was compared with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderMatch<T: Real> {
    /// The peak's exact order, `f_peak / f_run` with `f_run = Ω / 2π`.
    pub ratio: T,
    /// The order it is attributed to: the one with the smallest denominator (then the nearest)
    /// among those within tolerance; if none is, the nearest integer order (at least 1).
    pub order: Order,
    /// `f_peak − order · f_run`, Hz.
    pub distance_hz: T,
    /// Whether `|distance_hz|` is within the order tolerance.
    pub within_tolerance: bool,
}

/// The natural frequency nearest to a peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NaturalMatch<T: Real> {
    /// Index in the list given to [`locate_peak`].
    pub index: usize,
    /// That natural frequency, Hz.
    pub frequency_hz: T,
    /// `f_peak − frequency_hz`, Hz.
    pub distance_hz: T,
    /// Whether `|distance_hz|` is within the natural-frequency tolerance.
    pub within_tolerance: bool,
}

/// What a peak is attributed to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PeakClass {
    /// An order of the running speed (integer or fractional), away from every natural
    /// frequency: a periodic force the model lacks.
    Order(Order),
    /// A natural frequency (by index), not an order: a mode that is missing or mistuned.
    Natural(usize),
    /// An order that coincides with a natural frequency: a resonance. Both explanations fit;
    /// the order is the excitation, the mode the amplifier.
    OrderAtNatural {
        /// The order.
        order: Order,
        /// Index of the natural frequency.
        natural: usize,
    },
    /// Neither (or an invalid peak frequency).
    Unexplained,
}

/// Where a peak sits; see [`locate_peak`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakLocation<T: Real> {
    /// Comparison with the running-speed orders; `None` if the running speed or the peak
    /// frequency is not finite and positive.
    pub order: Option<OrderMatch<T>>,
    /// The nearest natural frequency; `None` if the list holds no finite positive frequency
    /// (or the peak frequency is not finite and positive).
    pub natural: Option<NaturalMatch<T>>,
    /// The verdict.
    pub class: PeakClass,
}

/// Attributes a peak at `peak_hz` to an order of the running speed `running_speed_rad_s`
/// (Ω, rad/s, as in the model parameters) and/or to one of `natural_freqs_hz`.
///
/// The first step from "the innovations are coloured" to "the model lacks X": an integer order
/// `k·Ω` points at a missing harmonic force (2× misalignment, blade pass, …), a fractional order
/// (½×, ⅓×) at a rub or looseness, a natural frequency at a mode whose damping or excitation is
/// wrong, an order on a natural frequency at a resonance, and neither at something outside the
/// model (another machine, a mode the model does not have).
///
/// Among orders `p/q` with `q ≤ max_denominator` within tolerance, the smallest denominator
/// wins (then the nearest): with a generous tolerance 1.1× is "1×", not "11/10×". Natural
/// frequencies that are not finite and positive are ignored. Never panics; an invalid peak
/// frequency is [`PeakClass::Unexplained`].
///
/// ```
/// use edgekf::residual::{locate_peak, Order, PeakClass, PeakTolerance};
/// let omega = 87.96f64; // rad/s: 14.0 Hz
/// let naturals = [20.0, 55.0];
/// let tol = PeakTolerance::new(1.0); // ~ one bin at N = 1024, fs = 1 kHz
/// let at_2x = locate_peak(28.02, omega, &naturals, &tol);
/// assert_eq!(at_2x.class, PeakClass::Order(Order { numerator: 2, denominator: 1 }));
/// assert!(at_2x.order.unwrap().distance_hz.abs() < 0.05);
/// assert_eq!(locate_peak(20.3, omega, &naturals, &tol).class, PeakClass::Natural(0));
/// assert_eq!(locate_peak(37.0, omega, &naturals, &tol).class, PeakClass::Unexplained);
/// ```
pub fn locate_peak<T: Real>(
    peak_hz: T,
    running_speed_rad_s: T,
    natural_freqs_hz: &[T],
    tolerance: &PeakTolerance<T>,
) -> PeakLocation<T> {
    let valid = |f: T| f.is_finite() && f > T::zero();
    if !valid(peak_hz) {
        return PeakLocation { order: None, natural: None, class: PeakClass::Unexplained };
    }
    let allowed = |reference: T, rel: T| tolerance.abs_hz + rel * reference;
    let order = valid(running_speed_rad_s)
        .then(|| match_order(peak_hz, running_speed_rad_s / T::two_pi(), tolerance, &allowed))
        .flatten();
    let natural = natural_freqs_hz
        .iter()
        .enumerate()
        .filter(|(_, f)| valid(**f))
        .fold(None::<(usize, T)>, |best, (i, &f)| match best {
            Some((_, b)) if (peak_hz - b).abs() <= (peak_hz - f).abs() => best,
            _ => Some((i, f)),
        })
        .map(|(index, frequency_hz)| {
            let distance_hz = peak_hz - frequency_hz;
            let within_tolerance = distance_hz.abs() <= allowed(frequency_hz, tolerance.natural_rel);
            NaturalMatch { index, frequency_hz, distance_hz, within_tolerance }
        });
    let on_order = order.filter(|o| o.within_tolerance).map(|o| o.order);
    let on_natural = natural.filter(|n| n.within_tolerance).map(|n| n.index);
    let class = match (on_order, on_natural) {
        (Some(order), Some(natural)) => PeakClass::OrderAtNatural { order, natural },
        (Some(order), None) => PeakClass::Order(order),
        (None, Some(index)) => PeakClass::Natural(index),
        (None, None) => PeakClass::Unexplained,
    };
    PeakLocation { order, natural, class }
}

/// The order match for a peak at `peak_hz` with running frequency `f_run` Hz (both positive).
fn match_order<T: Real>(
    peak_hz: T,
    f_run: T,
    tolerance: &PeakTolerance<T>,
    allowed: &impl Fn(T, T) -> T,
) -> Option<OrderMatch<T>> {
    let ratio = peak_hz / f_run;
    if !ratio.is_finite() {
        return None;
    }
    let candidate = |q: u32| {
        // `as` saturates (and maps NaN to 0): an absurd ratio just gives a distant candidate.
        let p = (libm::round(ratio.as_f64() * q as f64) as u32).max(1);
        let reference = T::of_f64(p as f64 / q as f64) * f_run;
        let distance_hz = peak_hz - reference;
        // An order is resolvable only while the speed's uncertainty there is under a quarter
        // of the spacing of the orders around it (and the resolution under half of it): at
        // 138× every line is within 0.5 % of some order.
        let spacing = f_run / T::of_f64((q * q) as f64);
        let resolvable =
            tolerance.order_rel * reference < spacing / T::of_f64(4.0) && tolerance.abs_hz < spacing / T::of_f64(2.0);
        let within_tolerance = resolvable && distance_hz.abs() <= allowed(reference, tolerance.order_rel);
        let g = gcd(p, q);
        OrderMatch { ratio, order: Order { numerator: p / g, denominator: q / g }, distance_hz, within_tolerance }
    };
    let integer = candidate(1);
    let best = (1..=tolerance.max_denominator.max(1)).map(candidate).filter(|c| c.within_tolerance).fold(
        None::<OrderMatch<T>>,
        |best, c| match best {
            Some(b) if b.order.denominator < c.order.denominator => best,
            Some(b) if b.order.denominator == c.order.denominator && b.distance_hz.abs() <= c.distance_hz.abs() => best,
            _ => Some(c),
        },
    );
    Some(best.unwrap_or(integer))
}

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    const OMEGA: f64 = 87.96; // rad/s
    const F_RUN: f64 = 87.96 / core::f64::consts::TAU; // 13.9994 Hz

    fn order(p: u32, q: u32) -> Order {
        Order { numerator: p, denominator: q }
    }

    #[test]
    fn integer_orders() {
        let tol = PeakTolerance::new(0.5);
        for k in 1..=8u32 {
            let f = k as f64 * F_RUN + 0.2;
            let loc = locate_peak(f, OMEGA, &[], &tol);
            assert_eq!(loc.class, PeakClass::Order(order(k, 1)), "{k}");
            let o = loc.order.unwrap();
            assert!((o.distance_hz - 0.2).abs() < 1e-9 && (o.ratio - f / F_RUN).abs() < 1e-12);
            assert!(loc.natural.is_none());
        }
        // The relative part grows with the order: 0.5 % of 20× = 1.4 Hz on top of 0.5 Hz.
        let loc = locate_peak(20.0 * F_RUN + 1.8, OMEGA, &[], &tol);
        assert_eq!(loc.class, PeakClass::Order(order(20, 1)));
        let loc = locate_peak(2.0 * F_RUN + 0.8, OMEGA, &[], &tol);
        assert_eq!(loc.class, PeakClass::Unexplained);
        let o = loc.order.unwrap();
        assert_eq!((o.order, o.within_tolerance), (order(2, 1), false));
        assert!((o.distance_hz - 0.8).abs() < 1e-9);
    }

    #[test]
    fn high_orders_that_cannot_be_resolved_are_not_orders() {
        // 30 Hz running speed known to 0.5 %: at 138× = 4140 Hz that is ±20.7 Hz, more than the
        // 30 Hz between orders could tell apart.
        let omega = 30.0 * core::f64::consts::TAU;
        let tol = PeakTolerance::new(12.0);
        assert_eq!(locate_peak(4144.3, omega, &[], &tol).class, PeakClass::Unexplained);
        // Low orders still are: 2× within 12 + 0.3 Hz, spacing 30 Hz.
        assert_eq!(locate_peak(61.0, omega, &[], &tol).class, PeakClass::Order(order(2, 1)));
        // With a finer bin the high order resolves again (1 + 2.07 Hz < 7.5 Hz).
        let fine = PeakTolerance { order_rel: 0.0005, ..PeakTolerance::new(1.0) };
        assert_eq!(locate_peak(4140.5, omega, &[], &fine).class, PeakClass::Order(order(138, 1)));
    }

    #[test]
    fn fractional_orders_only_when_asked() {
        let mut tol = PeakTolerance::new(0.3);
        let half = locate_peak(0.5 * F_RUN, OMEGA, &[], &tol);
        assert_eq!(half.class, PeakClass::Unexplained);
        assert_eq!(half.order.unwrap().order, order(1, 1));
        tol.max_denominator = 3;
        assert_eq!(locate_peak(0.5 * F_RUN, OMEGA, &[], &tol).class, PeakClass::Order(order(1, 2)));
        assert_eq!(locate_peak(1.5 * F_RUN + 0.1, OMEGA, &[], &tol).class, PeakClass::Order(order(3, 2)));
        assert_eq!(locate_peak(F_RUN / 3.0, OMEGA, &[], &tol).class, PeakClass::Order(order(1, 3)));
        // 4/2 is reported as 2/1, and the integer wins over an equally close fraction.
        assert_eq!(locate_peak(2.0 * F_RUN, OMEGA, &[], &tol).class, PeakClass::Order(order(2, 1)));
        // Simplest explanation first: 1.1× with a 2 Hz tolerance is 1×, though 11/10 is exact.
        tol.abs_hz = 2.0;
        tol.max_denominator = 10;
        assert_eq!(locate_peak(1.1 * F_RUN, OMEGA, &[], &tol).class, PeakClass::Order(order(1, 1)));
    }

    #[test]
    fn natural_frequencies_and_resonance() {
        let tol = PeakTolerance::new(0.5);
        let naturals = [55.0, 20.0, f64::NAN, -3.0];
        let loc = locate_peak(20.7, OMEGA, &naturals, &tol);
        assert_eq!(loc.class, PeakClass::Natural(1));
        let n = loc.natural.unwrap();
        assert_eq!((n.index, n.frequency_hz), (1, 20.0));
        assert!((n.distance_hz - 0.7).abs() < 1e-12 && n.within_tolerance);
        // 0.5 Hz + 5 % of 20 Hz = 1.5 Hz.
        assert_eq!(locate_peak(21.6, OMEGA, &naturals, &tol).class, PeakClass::Unexplained);
        // 4× = 56 Hz on the 55 Hz mode (5 % = 2.75 Hz): a resonance.
        let loc = locate_peak(4.0 * F_RUN, OMEGA, &naturals, &tol);
        assert_eq!(loc.class, PeakClass::OrderAtNatural { order: order(4, 1), natural: 0 });
        // Nothing near: the nearest of each is still reported.
        let loc = locate_peak(37.0, OMEGA, &naturals, &tol);
        assert_eq!(loc.class, PeakClass::Unexplained);
        assert_eq!(loc.natural.unwrap().index, 1);
        assert_eq!(loc.order.unwrap().order, order(3, 1));
    }

    #[test]
    fn invalid_inputs_are_defined() {
        let tol = PeakTolerance::new(0.5f32);
        for f in [f32::NAN, f32::INFINITY, 0.0, -14.0] {
            let loc = locate_peak(f, 87.96, &[20.0], &tol);
            assert_eq!((loc.order, loc.natural, loc.class), (None, None, PeakClass::Unexplained));
        }
        for omega in [0.0, -87.96, f32::NAN, f32::INFINITY] {
            let loc = locate_peak(20.2f32, omega, &[20.0], &tol);
            assert!(loc.order.is_none());
            assert_eq!(loc.class, PeakClass::Natural(0));
        }
        // A running speed so low that the ratio saturates: a distant candidate, no panic.
        let loc = locate_peak(400.0f32, 1e-30, &[], &tol);
        assert!(!loc.order.unwrap().within_tolerance);
        let loc = locate_peak(f32::MAX, f32::MIN_POSITIVE, &[], &tol);
        assert_eq!(loc.class, PeakClass::Unexplained);
        // Zero denominators are treated as 1.
        let zero = PeakTolerance { max_denominator: 0, ..tol };
        assert_eq!(locate_peak(28.0f32, 87.96, &[], &zero).class, PeakClass::Order(order(2, 1)));
    }

    #[test]
    fn f32_agrees_with_f64() {
        let tol64 = PeakTolerance { max_denominator: 2, ..PeakTolerance::new(0.5) };
        let tol32 = PeakTolerance { abs_hz: 0.5f32, order_rel: 0.005, natural_rel: 0.05, max_denominator: 2 };
        for i in 0..400 {
            let f = 0.25 * i as f64 + 0.1;
            let a = locate_peak(f, OMEGA, &[20.0, 55.0], &tol64);
            let b = locate_peak(f as f32, OMEGA as f32, &[20.0, 55.0], &tol32);
            assert_eq!(a.class, b.class, "{f}");
        }
    }
}
