//! Undeclared effects added to a data file (simulated data with something the model lacks).

use crate::io::data::{DataFile, TRUTH_PREFIX};
use crate::linalg::expm;
use crate::systems::rotor::{dof, RotorModel, SensorKind};
use anyhow::{anyhow, bail, Result};
use faer::linalg::solvers::Solve;
use faer::{c64, Mat};

fn column_mut<'a>(data: &'a mut DataFile, name: &str) -> Option<&'a mut Vec<f64>> {
    let i = data.names.iter().position(|n| n == name)?;
    data.columns.get_mut(i)
}

/// Adds `value` to every sample of channel `channel` (a sensor offset; the truth is unchanged).
pub fn inject_bias(data: &mut DataFile, channel: &str, value: f64) -> Result<()> {
    let col = column_mut(data, channel).ok_or_else(|| anyhow!("the data file has no channel {channel}"))?;
    col.iter_mut().for_each(|v| *v += value);
    Ok(())
}

/// A force rotating forward at `order × speed` at `node`: `F_x = A cos(ωt + φ)`, `F_y = A
/// sin(ωt + φ)`, `ω = order·speed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicForce {
    /// The node it acts at.
    pub node: usize,
    /// Its frequency in orders of the running speed.
    pub order: f64,
    /// Its amplitude `A`, N.
    pub amplitude: f64,
    /// Its phase `φ` at `t = 0`, rad.
    pub phase_rad: f64,
}

/// Steady complex response of every DOF to `force`, from `(K − ω² M + iω (C + Ω G)) Q̂ = F̂`
/// (the gyroscopic matrix scales with the spin speed Ω).
pub fn harmonic_response(model: &RotorModel, speed: f64, force: &HarmonicForce) -> Result<Vec<c64>> {
    let HarmonicForce { node, order, amplitude, phase_rad } = *force;
    if node >= model.n_nodes() {
        bail!("no node {node}");
    }
    let s = model.matrices();
    let n = s.n();
    let w = order * speed;
    let z = Mat::<c64>::from_fn(n, n, |i, j| {
        c64::new(s.k[(i, j)] - w * w * s.m[(i, j)], w * (s.c[(i, j)] + speed * s.g[(i, j)]))
    });
    let f = c64::from_polar(amplitude, phase_rad);
    let rhs = Mat::<c64>::from_fn(n, 1, |i, _| {
        if i == dof(node, 0) {
            f
        } else if i == dof(node, 1) {
            f * c64::new(0.0, -1.0)
        } else {
            c64::new(0.0, 0.0)
        }
    });
    let q = z.partial_piv_lu().solve(&rhs);
    let q: Vec<c64> = (0..n).map(|i| q[(i, 0)]).collect();
    if q.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
        bail!("harmonic response at {w} rad/s: singular dynamic stiffness");
    }
    Ok(q)
}

/// Superposes the response to a harmonic force switched on at the first sample with the rotor
/// at rest (as the reference simulator starts its unbalance) on the `truth_n*_x/y` columns and
/// the displacement-probe channels of `data` (accelerometer channels are not supported).
///
/// By linearity that is the steady response (see [`harmonic_response`]) minus the free
/// response of the FE model from the steady response's initial state, `e^{A t} x_ss(0)`
/// (exact, through the matrix exponential of the first-order state matrix).
pub fn inject_harmonic_force(data: &mut DataFile, model: &RotorModel, speed: f64, force: &HarmonicForce) -> Result<()> {
    let q = harmonic_response(model, speed, force)?;
    let w = force.order * speed;
    let t = data.t.clone();
    let t0 = t.first().copied().unwrap_or(0.0);
    let n = q.len();
    // Free response from x_ss(t0): q = Re(q̂ e^{iωt0}), q̇ = Re(iω q̂ e^{iωt0}).
    let e0 = c64::from_polar(1.0, w * t0);
    let mut x =
        Mat::<f64>::from_fn(
            2 * n,
            1,
            |i, _| if i < n { (q[i] * e0).re } else { (q[i - n] * e0 * c64::new(0.0, w)).re },
        );
    let a = model.state_matrix(speed).map_err(|e| anyhow!("{e}"))?;
    let dt = if t.len() > 1 { (t[t.len() - 1] - t0) / (t.len() - 1) as f64 } else { 0.0 };
    let step = expm((&a * dt).as_ref()).map_err(|e| anyhow!("{e}"))?;
    let mut delta = vec![vec![0.0; t.len()]; n];
    for (k, tk) in t.iter().enumerate() {
        let e = c64::from_polar(1.0, w * tk);
        for (i, d) in delta.iter_mut().enumerate() {
            d[k] = (q[i] * e).re - x[(i, 0)];
        }
        x = &step * &x;
    }
    let add = |col: &mut Vec<f64>, d: &[f64]| col.iter_mut().zip(d).for_each(|(v, d)| *v += d);
    for k in 0..model.n_nodes() {
        for (d, dir) in ["x", "y"].iter().enumerate() {
            if let Some(col) = column_mut(data, &format!("{TRUTH_PREFIX}n{k}_{dir}")) {
                add(col, &delta[dof(k, d)]);
            }
        }
    }
    for s in &model.config().sensors {
        if !matches!(s.kind, SensorKind::Displacement { .. }) {
            bail!("inject_harmonic_force supports displacement probes only ({} is not one)", s.channel_name());
        }
        if let Some(col) = column_mut(data, &s.channel_name()) {
            add(col, &delta[dof(s.node, s.direction.dof())]);
        }
    }
    Ok(())
}

/// Multiplies channel `channel` by `factor` from time `from` on (s, in the file's clock; `None`:
/// the whole run): a sensor scale error, or a gain that switches during the run.
pub fn inject_scale(data: &mut DataFile, channel: &str, factor: f64, from: Option<f64>) -> Result<()> {
    let t = data.t.clone();
    let col = column_mut(data, channel).ok_or_else(|| anyhow!("the data file has no channel {channel}"))?;
    for (v, tk) in col.iter_mut().zip(&t) {
        if from.is_none_or(|f| *tk >= f) {
            *v *= factor;
        }
    }
    Ok(())
}

/// A localised rolling-element bearing defect as a housing accelerometer sees it, the standard
/// model (McFadden & Smith 1984; Randall & Antoni 2011): an impact each time a rolling element
/// passes the defect, at the defect line's frequency, with a small random slip of each interval
/// (the rolling elements slide a little), each impact ringing a housing resonance
/// `h(t) = e^{−ζ ω_r t} (cos ω_d t − (ζ ω_r/ω_d) sin ω_d t)` (the derivative of a decaying sine:
/// zero mean, since a housing's vibration carries no steady acceleration). A defect on a rotating part (the inner race, a ball) is
/// carried through the load zone once per revolution of that part, which modulates the impacts
/// by `q(θ) = (1 − (1 − cos θ)/(2ε))^{3/2}` (zero outside the zone).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DefectSignal {
    /// Impact rate: the defect line's frequency, Hz.
    pub frequency_hz: f64,
    /// Peak acceleration of one impact's ringing (full load), m/s².
    pub peak: f64,
    /// Housing resonance the impacts ring, Hz.
    pub resonance_hz: f64,
    /// Its damping ratio.
    pub damping: f64,
    /// Standard deviation of each impact interval, as a fraction of the mean interval (0.01–0.02).
    pub slip: f64,
    /// Frequency at which the defect passes through the load zone, Hz (the shaft speed for an
    /// inner-race defect, the cage speed for a ball); `None` for a defect on the fixed outer
    /// race in the load zone (every impact at full load).
    pub modulation_hz: Option<f64>,
    /// Load-distribution factor `ε` (0.5: half the bearing loaded).
    pub load_zone: f64,
}

/// Adds the defect's vibration (see [`DefectSignal`]) to channel `channel` and to its
/// `truth_` column if the file has one (the housing really moves); impact times are drawn with
/// seed `seed`.
pub fn inject_bearing_defect(data: &mut DataFile, channel: &str, d: &DefectSignal, seed: u64) -> Result<()> {
    use rand::{Rng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    let valid = d.frequency_hz > 0.0 && d.resonance_hz > 0.0 && (0.0..1.0).contains(&d.damping);
    if !(valid && d.peak.is_finite() && d.slip >= 0.0 && d.slip < 0.2 && d.load_zone > 0.0) {
        bail!("bearing defect: frequency, resonance > 0, damping in [0, 1), slip in [0, 0.2), load zone > 0: {d:?}");
    }
    let t = data.t.clone();
    let (Some(&t0), Some(&t_end)) = (t.first(), t.last()) else { return Ok(()) };
    let dt = if t.len() > 1 { (t_end - t0) / (t.len() - 1) as f64 } else { 1.0 };
    let wr = std::f64::consts::TAU * d.resonance_hz;
    let wd = wr * (1.0 - d.damping * d.damping).sqrt();
    let decay = d.damping * wr;
    // The ringing has died to e^-12 of its start after this long.
    let ring = 12.0 / decay.max(1e-9);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let slip = Normal::new(0.0, d.slip).map_err(|e| anyhow!("{e}"))?;
    let period = 1.0 / d.frequency_hz;
    let mut signal = vec![0.0; t.len()];
    let mut tk = t0 + rng.gen::<f64>() * period;
    while tk <= t_end {
        let load = match d.modulation_hz {
            None => 1.0,
            Some(f) => {
                let theta = std::f64::consts::TAU * f * (tk - t0);
                (1.0 - (1.0 - theta.cos()) / (2.0 * d.load_zone)).max(0.0).powf(1.5)
            }
        };
        let first = ((tk - t0) / dt).ceil().max(0.0) as usize;
        let last = (((tk + ring - t0) / dt).floor() as usize).min(t.len() - 1);
        for (k, s) in signal.iter_mut().enumerate().take(last + 1).skip(first) {
            let tau = t[k] - tk;
            *s += d.peak * load * (-decay * tau).exp() * ((wd * tau).cos() - decay / wd * (wd * tau).sin());
        }
        tk += period * (1.0 + slip.sample(&mut rng));
    }
    add_signal(data, channel, &signal)
}

/// Delays channel `channel` by `tau` seconds (linear interpolation between samples; the first
/// samples repeat the first value): a sensor whose signal chain lags the others.
pub fn inject_delay(data: &mut DataFile, channel: &str, tau: f64) -> Result<()> {
    if !(tau.is_finite() && tau >= 0.0) {
        bail!("a delay must be zero or positive, not {tau}");
    }
    let t = data.t.clone();
    let dt = if t.len() > 1 { (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64 } else { 1.0 };
    let col = column_mut(data, channel).ok_or_else(|| anyhow!("the data file has no channel {channel}"))?;
    let old = col.clone();
    let last = old.len().saturating_sub(1);
    for (k, v) in col.iter_mut().enumerate() {
        let p = k as f64 - tau / dt;
        *v = if p <= 0.0 {
            old[0]
        } else {
            let (i, f) = (p.floor() as usize, p.fract());
            (1.0 - f) * old[i.min(last)] + f * old[(i + 1).min(last)]
        };
    }
    Ok(())
}

/// Adds a lightly damped housing or foundation resonance rung by broadband forces to channel
/// `channel` (and its `truth_` column): the output of `ẍ + 2ζω ẋ + ω² x = w` (white `w`),
/// the velocity scaled to RMS `rms`, discretised exactly per sample; a healthy machine shows it
/// too. Seeded with `seed`.
pub fn inject_resonance(data: &mut DataFile, channel: &str, hz: f64, damping: f64, rms: f64, seed: u64) -> Result<()> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let t = data.t.clone();
    if !(hz > 0.0 && damping > 0.0 && damping < 1.0 && rms.is_finite() && rms >= 0.0) || t.len() < 2 {
        bail!("a resonance needs a frequency > 0, a damping in (0, 1) and an RMS ≥ 0 on two samples or more");
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    let w = std::f64::consts::TAU * hz;
    let a = faer::mat![[0.0, 1.0], [-w * w, -2.0 * damping * w]];
    let step = expm((&a * dt).as_ref()).map_err(|e| anyhow!("{e}"))?;
    // White acceleration of density q gives the velocity a variance q / (4 ζ ω); per sample
    // the kick's variance is q dt.
    let kick = (rms * rms * 4.0 * damping * w * dt).sqrt();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).map_err(|e| anyhow!("{e}"))?;
    let (mut x, mut v) = (0.0, 0.0);
    let signal: Vec<f64> = (0..t.len())
        .map(|_| {
            (x, v) = (
                step[(0, 0)] * x + step[(0, 1)] * v,
                step[(1, 0)] * x + step[(1, 1)] * v + kick * unit.sample(&mut rng),
            );
            v
        })
        .collect();
    add_signal(data, channel, &signal)
}

/// Adds sinusoids `(frequency Hz, amplitude, phase rad)` to channel `channel` (and its
/// `truth_` column): the motor's electromagnetic forces at harmonics of the line frequency.
pub fn inject_tones(data: &mut DataFile, channel: &str, tones: &[(f64, f64, f64)]) -> Result<()> {
    let signal: Vec<f64> = data
        .t
        .iter()
        .map(|t| tones.iter().map(|(f, a, p)| a * (std::f64::consts::TAU * f * t + p).cos()).sum())
        .collect();
    add_signal(data, channel, &signal)
}

fn add_signal(data: &mut DataFile, channel: &str, signal: &[f64]) -> Result<()> {
    let add = |col: &mut Vec<f64>| col.iter_mut().zip(signal).for_each(|(v, s)| *v += s);
    add(column_mut(data, channel).ok_or_else(|| anyhow!("the data file has no channel {channel}"))?);
    if let Some(col) = column_mut(data, &format!("{TRUTH_PREFIX}{channel}")) {
        add(col);
    }
    Ok(())
}
