//! Time integration of the slider-crank, with output at a fixed sample rate.
//!
//! Two integrators:
//!
//! * [`Integrator::SymplecticEuler`]: the paper's scheme, `ż ← ż + h z̈(z, ż)`, `z ← z + h ż`,
//!   at a fixed step (1e-5 s). Contacts start and end at the step where the geometry says so
//!   ([`Mechanism::sync_contacts`] before each step), so an impact's onset is known only to
//!   within one step and its ~0.1 ms duration is resolved by ~10 steps: first-order accurate.
//!   It is the reference of the paper and is kept as such.
//! * [`Integrator::Adaptive`]: Dormand–Prince 5(4) with PI step control (Hairer's DOPRI5
//!   constants), 4th-order dense output, and located contact events. Within a step the contact
//!   set is frozen; each step's dense output is searched for a journal touching or leaving its
//!   bearing, the step is cut at the located instant (bisection on the interpolant to ~1e-15 of
//!   the step), and the contact set is switched there. So every step integrates a smooth right-
//!   hand side, the impact velocity that sets the Lankarani–Nikravesh damping is taken at the
//!   true onset, and the step shrinks only while contact forces act. Output samples come from
//!   the dense output (one extra evaluation per sample for the acceleration).
//!
//! Both call a sink at every sample instant `t₀ + k / rate`, `k = 0 … n−1`, and leave the state
//! at `t₀ + n / rate`, so consecutive runs concatenate into exactly one long run's samples.
//! The adaptive scheme is the more accurate per unit of work; see `host-sim/tests/crank.rs`
//! (`integrator_comparison`) for the measurement.

use super::config::{IntegratorConfig, Method};
use super::error::CrankError;
use super::mechanism::{Dynamics, Mechanism};
use super::state::{State, DOF};
use super::Joint;

/// How to integrate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Integrator {
    /// Symplectic Euler at a fixed `step` (s), reduced if needed to divide the sample period.
    SymplecticEuler {
        /// Step, s.
        step: f64,
    },
    /// Dormand–Prince 5(4), adaptive, with contact events.
    Adaptive {
        /// Relative error tolerance per step (absolute parts scale with 1 rad, 10 rad/s, the
        /// clearance and the clearance per millisecond).
        tolerance: f64,
        /// Largest step, s.
        max_step: f64,
    },
}

impl Integrator {
    /// The integrator a configuration asks for.
    pub fn from_config(c: &IntegratorConfig) -> Self {
        match c.method {
            Method::Symplectic => Integrator::SymplecticEuler { step: c.step },
            Method::Adaptive => Integrator::Adaptive { tolerance: c.tolerance, max_step: c.max_step },
        }
    }

    /// Checks the numbers.
    pub fn validate(&self) -> Result<(), CrankError> {
        let ok = match *self {
            Integrator::SymplecticEuler { step } => step.is_finite() && step > 0.0,
            Integrator::Adaptive { tolerance, max_step } => {
                tolerance > 0.0 && tolerance <= 1e-2 && max_step.is_finite() && max_step > 0.0
            }
        };
        if ok {
            Ok(())
        } else {
            Err(CrankError::Options(format!("{self:?}: step must be positive, tolerance in (0, 0.01]")))
        }
    }

    /// A short name: `symplectic` or `adaptive`.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::SymplecticEuler { .. } => "symplectic",
            Integrator::Adaptive { .. } => "adaptive",
        }
    }
}

/// Work done by a run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IntegrationStats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (adaptive only).
    pub rejected: u64,
    /// Evaluations of the equations of motion (the cost measure).
    pub evaluations: u64,
    /// Contacts started at each joint A, B, C.
    pub impacts: [u64; 3],
    /// Smallest and largest accepted step, s.
    pub step_range: (f64, f64),
}

impl IntegrationStats {
    fn note_step(&mut self, h: f64) {
        self.steps += 1;
        if self.steps == 1 {
            self.step_range = (h, h);
        } else {
            self.step_range = (self.step_range.0.min(h), self.step_range.1.max(h));
        }
    }

    /// Adds another run's work.
    pub fn add(&mut self, o: &IntegrationStats) {
        if o.steps > 0 {
            self.step_range = if self.steps == 0 {
                o.step_range
            } else {
                (self.step_range.0.min(o.step_range.0), self.step_range.1.max(o.step_range.1))
            };
        }
        self.steps += o.steps;
        self.rejected += o.rejected;
        self.evaluations += o.evaluations;
        for j in 0..3 {
            self.impacts[j] += o.impacts[j];
        }
    }
}

/// Integrates `state` over `samples` sample periods of length `period` (s), calling
/// `sink(state, dynamics)` at each sample instant, and leaves `state` at the end.
pub fn run(
    mech: &Mechanism,
    state: &mut State,
    period: f64,
    samples: usize,
    integrator: &Integrator,
    sink: &mut dyn FnMut(&State, &Dynamics),
) -> Result<IntegrationStats, CrankError> {
    integrator.validate()?;
    if !(period.is_finite() && period > 0.0) {
        return Err(CrankError::Options(format!("sample period {period} s must be positive")));
    }
    if !state.is_finite() {
        return Err(CrankError::Options("the initial state has non-finite numbers".into()));
    }
    for joint in Joint::ALL {
        if mech.clearance(joint).is_none() && state.eccentricity(joint) != [0.0; 2] {
            return Err(CrankError::Options(format!(
                "the initial state has an eccentricity at the ideal joint {joint} (use Mechanism::transfer_state)"
            )));
        }
    }
    let residual = mech.constraint_residual(state);
    if !(residual.is_finite() && residual < 1e-6) {
        return Err(CrankError::Options("the initial state cannot be assembled (rod angle out of range)".into()));
    }
    let mut stats = IntegrationStats::default();
    match *integrator {
        Integrator::SymplecticEuler { step } => symplectic(mech, state, period, samples, step, sink, &mut stats)?,
        Integrator::Adaptive { tolerance, max_step } => {
            adaptive(mech, state, period, samples, tolerance, max_step, sink, &mut stats)?
        }
    }
    Ok(stats)
}

/// Sub-steps per sample period: the fewest steps no longer than `step`.
pub fn substeps(period: f64, step: f64) -> u64 {
    let ratio = period / step;
    let n = if (ratio - ratio.round()).abs() <= 1e-9 * ratio { ratio.round() } else { ratio.ceil() };
    n.clamp(1.0, 1e12) as u64
}

fn diverged(t: f64, what: &str) -> CrankError {
    CrankError::Diverged { t, reason: format!("{what}; try a smaller step or tolerance") }
}

fn symplectic(
    mech: &Mechanism,
    s: &mut State,
    period: f64,
    samples: usize,
    step: f64,
    sink: &mut dyn FnMut(&State, &Dynamics),
    stats: &mut IntegrationStats,
) -> Result<(), CrankError> {
    let nsub = substeps(period, step);
    let h = period / nsub as f64;
    let t0 = s.t;
    let active: Vec<usize> = mech.active().to_vec();
    for k in 0..samples {
        s.t = t0 + k as f64 * period;
        for i in 0..nsub {
            mech.sync_contacts(s, &mut stats.impacts);
            let d = mech.dynamics(s);
            stats.evaluations += 1;
            if !d.zdd.iter().all(|v| v.is_finite()) {
                return Err(diverged(s.t, "non-finite acceleration"));
            }
            if i == 0 {
                sink(s, &d);
            }
            for &a in &active {
                s.zd[a] += h * d.zdd[a];
                s.z[a] += h * s.zd[a];
            }
            s.dissipated += h * d.dissipation;
            s.t = t0 + (k as f64 + (i + 1) as f64 / nsub as f64) * period;
            stats.note_step(h);
        }
    }
    s.t = t0 + samples as f64 * period;
    Ok(())
}

const NY: usize = 2 * DOF + 1;
type Y = [f64; NY];

fn pack(s: &State) -> Y {
    let mut y = [0.0; NY];
    y[..DOF].copy_from_slice(&s.z);
    y[DOF..2 * DOF].copy_from_slice(&s.zd);
    y[2 * DOF] = s.dissipated;
    y
}

fn unpack(y: &Y, t: f64, memory: [Option<f64>; 3]) -> State {
    let mut s = State { t, z: [0.0; DOF], zd: [0.0; DOF], impact_velocity: memory, dissipated: y[2 * DOF] };
    s.z.copy_from_slice(&y[..DOF]);
    s.zd.copy_from_slice(&y[DOF..2 * DOF]);
    s
}

fn deriv(mech: &Mechanism, y: &Y, memory: &[Option<f64>; 3]) -> (Y, Dynamics) {
    let mut z = [0.0; DOF];
    let mut zd = [0.0; DOF];
    z.copy_from_slice(&y[..DOF]);
    zd.copy_from_slice(&y[DOF..2 * DOF]);
    let d = mech.eval(&z, &zd, memory);
    let mut dy = [0.0; NY];
    dy[..DOF].copy_from_slice(&zd);
    dy[DOF..2 * DOF].copy_from_slice(&d.zdd);
    dy[2 * DOF] = d.dissipation;
    (dy, d)
}

// Dormand–Prince 5(4) (Hairer, Nørsett & Wanner, DOPRI5), as rows of the Butcher tableau.
/// Stage 2's weight of k1.
const A2: [f64; 1] = [1.0 / 5.0];
/// Stage 3's weights of k1, k2.
const A3: [f64; 2] = [3.0 / 40.0, 9.0 / 40.0];
/// Stage 4's weights of k1 … k3.
const A4: [f64; 3] = [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0];
/// Stage 5's weights of k1 … k4.
const A5: [f64; 4] = [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0];
/// Stage 6's weights of k1 … k5.
const A6: [f64; 5] = [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0];
/// The 5th-order solution's weights of k1, k3, k4, k5, k6 (k2's is zero).
const B: [f64; 5] = [35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0];
/// The error estimate's weights of k1, k3 … k7.
const E: [f64; 6] = [71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];
/// The dense output's weights of k1, k3 … k7.
const D: [f64; 6] = [
    -12715105075.0 / 11282082432.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// `y + h Σ cᵢ kᵢ`, the terms in the order given.
fn combine(y: &Y, h: f64, weights: &[f64], ks: &[&Y]) -> Y {
    let mut out = *y;
    for (c, k) in weights.iter().zip(ks) {
        let hc = h * c;
        for i in 0..NY {
            out[i] += hc * k[i];
        }
    }
    out
}

/// One DOPRI5 trial step of size `h` from `y` (slope `k1`), the contact set frozen.
struct Trial {
    /// The stages k1 … k7 (k7 is the slope at `y1`: the next step's k1).
    k: [Y; 7],
    /// The 5th-order solution.
    y1: Y,
    /// The error estimate.
    ev: Y,
}

impl Trial {
    fn new(mech: &Mechanism, y: &Y, k1: &Y, h: f64, memory: &[Option<f64>; 3]) -> Self {
        let stage = |a: &[f64], ks: &[&Y]| deriv(mech, &combine(y, h, a, ks), memory).0;
        let k2 = stage(&A2, &[k1]);
        let k3 = stage(&A3, &[k1, &k2]);
        let k4 = stage(&A4, &[k1, &k2, &k3]);
        let k5 = stage(&A5, &[k1, &k2, &k3, &k4]);
        let k6 = stage(&A6, &[k1, &k2, &k3, &k4, &k5]);
        let y1 = combine(y, h, &B, &[k1, &k3, &k4, &k5, &k6]);
        let (k7, _) = deriv(mech, &y1, memory);
        let ev = combine(&[0.0; NY], h, &E, &[k1, &k3, &k4, &k5, &k6, &k7]);
        Self { k: [*k1, k2, k3, k4, k5, k6, k7], y1, ev }
    }

    /// The step's continuous extension from `y`.
    fn dense(&self, y: &Y, h: f64) -> Dense {
        let [k1, _, k3, k4, k5, k6, k7] = &self.k;
        let ydiff: Y = std::array::from_fn(|i| self.y1[i] - y[i]);
        let bspl: Y = std::array::from_fn(|i| h * k1[i] - ydiff[i]);
        Dense {
            y0: *y,
            r1: ydiff,
            r2: bspl,
            r3: std::array::from_fn(|i| ydiff[i] - h * k7[i] - bspl[i]),
            r4: combine(&[0.0; NY], h, &D, &[k1, k3, k4, k5, k6, k7]),
        }
    }
}

/// Hairer's continuous extension of one DOPRI5 step.
struct Dense {
    y0: Y,
    r1: Y,
    r2: Y,
    r3: Y,
    r4: Y,
}

impl Dense {
    fn component(&self, i: usize, th: f64) -> f64 {
        let th1 = 1.0 - th;
        self.y0[i] + th * (self.r1[i] + th1 * (self.r2[i] + th * (self.r3[i] + th1 * self.r4[i])))
    }

    fn at(&self, th: f64) -> Y {
        std::array::from_fn(|i| self.component(i, th))
    }
}

/// Absolute error scales of the controlled components (0: not controlled).
fn error_scales(mech: &Mechanism) -> Y {
    let mut sc = [0.0; NY];
    sc[0] = 1.0;
    sc[DOF] = 10.0;
    for joint in Joint::ALL {
        if let Some(c) = mech.clearance(joint) {
            let i = super::state::eccentricity_index(joint);
            sc[i] = c;
            sc[i + 1] = c;
            sc[DOF + i] = 1e3 * c;
            sc[DOF + i + 1] = 1e3 * c;
        }
    }
    sc
}

/// Earliest θ ∈ (0, 1] of the step at which a contact starts or ends, and whether one does.
fn locate_event(mech: &Mechanism, dense: &Dense, memory: &[Option<f64>; 3]) -> Option<f64> {
    let mut earliest: Option<f64> = None;
    for joint in Joint::ALL {
        let Some(c) = mech.clearance(joint) else { continue };
        let i = super::state::eccentricity_index(joint);
        let in_contact = memory[joint.index()].is_some();
        // Positive when the contact set must change.
        let s = |th: f64| {
            let delta = dense.component(i, th).hypot(dense.component(i + 1, th)) - c;
            if in_contact {
                -delta
            } else {
                delta
            }
        };
        const PROBES: usize = 4;
        let mut lo = 0.0;
        for p in 1..=PROBES {
            let hi = p as f64 / PROBES as f64;
            if earliest.is_some_and(|e| lo >= e) {
                break;
            }
            if s(hi) > 0.0 {
                let (mut a, mut b) = (lo, hi);
                for _ in 0..52 {
                    let m = 0.5 * (a + b);
                    if s(m) > 0.0 {
                        b = m;
                    } else {
                        a = m;
                    }
                }
                earliest = Some(earliest.map_or(b, |e: f64| e.min(b)));
                break;
            }
            lo = hi;
        }
    }
    earliest
}

/// The error control of the adaptive steps: Hairer's PI controller on the RMS of the
/// controlled components' errors, each relative to `tol` times its scale plus its size.
struct StepControl {
    scales: Y,
    controlled: Vec<usize>,
    tol: f64,
    max_step: f64,
    fac_old: f64,
}

impl StepControl {
    fn new(mech: &Mechanism, tol: f64, max_step: f64) -> Self {
        let scales = error_scales(mech);
        let controlled: Vec<usize> = (0..NY).filter(|&i| scales[i] > 0.0).collect();
        Self { scales, controlled, tol, max_step, fac_old: 1e-4 }
    }

    /// The next step's size if the trial from `y` is accepted; `None` after shrinking `h` for a
    /// retry (an error above tolerance, or a non-finite one).
    fn accept(&mut self, y: &Y, trial: &Trial, h: &mut f64, stats: &mut IntegrationStats) -> Option<f64> {
        let y1 = &trial.y1;
        let mut sum = 0.0;
        for &i in &self.controlled {
            let sc = self.tol * (self.scales[i] + y[i].abs().max(y1[i].abs()));
            sum += (trial.ev[i] / sc).powi(2);
        }
        let err = (sum / self.controlled.len() as f64).sqrt();
        if !(err.is_finite() && y1.iter().all(|v| v.is_finite())) {
            *h *= 0.25;
            stats.rejected += 1;
            return None;
        }
        let fac11 = err.powf(0.17);
        if err > 1.0 {
            *h /= (fac11 / 0.9).min(5.0);
            stats.rejected += 1;
            return None;
        }
        let fac = (fac11 / self.fac_old.powf(0.04) / 0.9).clamp(0.1, 5.0);
        self.fac_old = err.max(1e-4);
        Some((*h / fac).min(self.max_step))
    }
}

/// The sample instants `t₀ + k / rate`, `k = next … count−1`, still to deliver to the sink.
struct Samples<'s> {
    t0: f64,
    period: f64,
    count: usize,
    next: usize,
    sink: &'s mut dyn FnMut(&State, &Dynamics),
}

impl Samples<'_> {
    /// Delivers the samples up to `seg_end` from a step's dense output (step from `t`, size `h`,
    /// cut at `th_end`), each with one evaluation for its acceleration.
    fn deliver(
        &mut self,
        mech: &Mechanism,
        dense: &Dense,
        (t, h, th_end, seg_end): (f64, f64, f64, f64),
        memory: [Option<f64>; 3],
        stats: &mut IntegrationStats,
    ) {
        while self.next < self.count {
            let ts = self.t0 + self.next as f64 * self.period;
            if ts > seg_end {
                break;
            }
            let th = ((ts - t) / h).clamp(0.0, th_end);
            let ys = dense.at(th);
            let (_, d) = deriv(mech, &ys, &memory);
            stats.evaluations += 1;
            (self.sink)(&unpack(&ys, ts, memory), &d);
            self.next += 1;
        }
    }

    /// Delivers what rounding of the last sample instant left, at the final state `y`.
    fn deliver_rest(&mut self, mech: &Mechanism, y: &Y, memory: [Option<f64>; 3], stats: &mut IntegrationStats) {
        while self.next < self.count {
            let (_, d) = deriv(mech, y, &memory);
            stats.evaluations += 1;
            (self.sink)(&unpack(y, self.t0 + self.next as f64 * self.period, memory), &d);
            self.next += 1;
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn adaptive(
    mech: &Mechanism,
    s: &mut State,
    period: f64,
    samples: usize,
    tol: f64,
    max_step: f64,
    sink: &mut dyn FnMut(&State, &Dynamics),
    stats: &mut IntegrationStats,
) -> Result<(), CrankError> {
    let t0 = s.t;
    let t_end = t0 + samples as f64 * period;
    mech.sync_contacts(s, &mut stats.impacts);
    let mut memory = s.impact_velocity;
    let mut y = pack(s);
    let mut t = t0;
    let (mut k1, d0) = deriv(mech, &y, &memory);
    stats.evaluations += 1;
    if !k1.iter().all(|v| v.is_finite()) {
        return Err(diverged(t, "non-finite acceleration"));
    }
    let mut out = Samples { t0, period, count: samples, next: 0, sink };
    if samples > 0 {
        (out.sink)(s, &d0);
        out.next = 1;
    }
    let mut control = StepControl::new(mech, tol, max_step);
    let mut h = 1e-5_f64.min(max_step).min(period);
    // Events in a row that advanced time by less than a femtosecond: a journal grazing its
    // bearing so exactly that contact flips back and forth without progress.
    let mut stalled_events = 0u32;
    while t < t_end {
        let reaching_end = t + h >= t_end - 1e-9 * period;
        if reaching_end {
            h = t_end - t;
        }
        if h <= 1e-14 * t.abs().max(1.0) {
            if reaching_end {
                // An event landed within rounding of the end: the state is the end state.
                break;
            }
            return Err(diverged(t, "step size underflow"));
        }
        let trial = Trial::new(mech, &y, &k1, h, &memory);
        stats.evaluations += 6;
        let Some(h_new) = control.accept(&y, &trial, &mut h, stats) else { continue };
        let dense = trial.dense(&y, h);
        let event = locate_event(mech, &dense, &memory);
        let th_end = event.unwrap_or(1.0);
        let seg_end = match event {
            Some(_) => t + th_end * h,
            None if reaching_end => t_end,
            None => t + h,
        };
        out.deliver(mech, &dense, (t, h, th_end, seg_end), memory, stats);
        stats.note_step(th_end * h);
        if event.is_some() {
            stalled_events = if seg_end - t < 1e-15 { stalled_events + 1 } else { 0 };
            if stalled_events > 1000 {
                return Err(diverged(t, "contact switching without progress (grazing contact)"));
            }
            // The contact set switches at the event: the step restarts there.
            y = dense.at(th_end);
            t = seg_end;
            let mut st = unpack(&y, t, memory);
            mech.sync_contacts(&mut st, &mut stats.impacts);
            memory = st.impact_velocity;
            k1 = deriv(mech, &y, &memory).0;
            stats.evaluations += 1;
        } else {
            y = trial.y1;
            t = seg_end;
            k1 = trial.k[6];
        }
        h = h_new;
    }
    out.deliver_rest(mech, &y, memory, stats);
    *s = unpack(&y, t_end, memory);
    if !s.is_finite() {
        return Err(diverged(t, "non-finite state"));
    }
    Ok(())
}
