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

// Dormand–Prince 5(4) (Hairer, Nørsett & Wanner, DOPRI5).
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// `y + h Σ cᵢ kᵢ`.
fn combine(y: &Y, h: f64, terms: &[(f64, &Y)]) -> Y {
    let mut out = *y;
    for (c, k) in terms {
        let hc = h * c;
        for i in 0..NY {
            out[i] += hc * k[i];
        }
    }
    out
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
    let mut next = 0usize;
    if samples > 0 {
        sink(s, &d0);
        next = 1;
    }
    let scales = error_scales(mech);
    let controlled: Vec<usize> = (0..NY).filter(|&i| scales[i] > 0.0).collect();
    let mut h = 1e-5_f64.min(max_step).min(period);
    let mut fac_old: f64 = 1e-4;
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
        let (k2, _) = deriv(mech, &combine(&y, h, &[(A21, &k1)]), &memory);
        let (k3, _) = deriv(mech, &combine(&y, h, &[(A31, &k1), (A32, &k2)]), &memory);
        let (k4, _) = deriv(mech, &combine(&y, h, &[(A41, &k1), (A42, &k2), (A43, &k3)]), &memory);
        let (k5, _) = deriv(mech, &combine(&y, h, &[(A51, &k1), (A52, &k2), (A53, &k3), (A54, &k4)]), &memory);
        let (k6, _) =
            deriv(mech, &combine(&y, h, &[(A61, &k1), (A62, &k2), (A63, &k3), (A64, &k4), (A65, &k5)]), &memory);
        let y1 = combine(&y, h, &[(B1, &k1), (B3, &k3), (B4, &k4), (B5, &k5), (B6, &k6)]);
        let (k7, _) = deriv(mech, &y1, &memory);
        stats.evaluations += 6;
        let ev = combine(&[0.0; NY], h, &[(E1, &k1), (E3, &k3), (E4, &k4), (E5, &k5), (E6, &k6), (E7, &k7)]);
        let mut sum = 0.0;
        for &i in &controlled {
            let sc = tol * (scales[i] + y[i].abs().max(y1[i].abs()));
            sum += (ev[i] / sc).powi(2);
        }
        let err = (sum / controlled.len() as f64).sqrt();
        if !(err.is_finite() && y1.iter().all(|v| v.is_finite())) {
            h *= 0.25;
            stats.rejected += 1;
            continue;
        }
        let fac11 = err.powf(0.17);
        if err > 1.0 {
            h /= (fac11 / 0.9).min(5.0);
            stats.rejected += 1;
            continue;
        }
        let fac = (fac11 / fac_old.powf(0.04) / 0.9).clamp(0.1, 5.0);
        fac_old = err.max(1e-4);
        let h_new = (h / fac).min(max_step);

        let ydiff: Y = std::array::from_fn(|i| y1[i] - y[i]);
        let bspl: Y = std::array::from_fn(|i| h * k1[i] - ydiff[i]);
        let dense = Dense {
            y0: y,
            r1: ydiff,
            r2: bspl,
            r3: std::array::from_fn(|i| ydiff[i] - h * k7[i] - bspl[i]),
            r4: combine(&[0.0; NY], h, &[(D1, &k1), (D3, &k3), (D4, &k4), (D5, &k5), (D6, &k6), (D7, &k7)]),
        };
        let event = locate_event(mech, &dense, &memory);
        let th_end = event.unwrap_or(1.0);
        let seg_end = match event {
            Some(_) => t + th_end * h,
            None if reaching_end => t_end,
            None => t + h,
        };
        while next < samples {
            let ts = t0 + next as f64 * period;
            if ts > seg_end {
                break;
            }
            let th = ((ts - t) / h).clamp(0.0, th_end);
            let ys = dense.at(th);
            let (_, d) = deriv(mech, &ys, &memory);
            stats.evaluations += 1;
            sink(&unpack(&ys, ts, memory), &d);
            next += 1;
        }
        stats.note_step(th_end * h);
        if event.is_some() {
            stalled_events = if seg_end - t < 1e-15 { stalled_events + 1 } else { 0 };
            if stalled_events > 1000 {
                return Err(diverged(t, "contact switching without progress (grazing contact)"));
            }
            y = dense.at(th_end);
            t = seg_end;
            let mut st = unpack(&y, t, memory);
            mech.sync_contacts(&mut st, &mut stats.impacts);
            memory = st.impact_velocity;
            k1 = deriv(mech, &y, &memory).0;
            stats.evaluations += 1;
        } else {
            y = y1;
            t = seg_end;
            k1 = k7;
        }
        h = h_new;
    }
    while next < samples {
        // Only reachable through rounding of the last sample instant.
        let (_, d) = deriv(mech, &y, &memory);
        stats.evaluations += 1;
        sink(&unpack(&y, t0 + next as f64 * period, memory), &d);
        next += 1;
    }
    *s = unpack(&y, t_end, memory);
    if !s.is_finite() {
        return Err(diverged(t, "non-finite state"));
    }
    Ok(())
}
