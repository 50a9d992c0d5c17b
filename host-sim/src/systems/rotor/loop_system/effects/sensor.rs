//! The sensor family: a bias (a slow random-walk state on the channel's output row), and the
//! output-side effects over the complete dynamics: a scale, a delay (`C e^{−Aτ}`), a
//! first-order lag (a state the channel reads instead).

use super::Parts;
use super::{Effect, EffectTuning};
use anyhow::{anyhow, bail, Result};
use edgekf::linalg::expm;
use nalgebra::DMatrix;

/// An error unless the model has channel `ch`.
pub(super) fn channel_ok(p: &Parts, ch: usize) -> Result<()> {
    if ch < p.c.nrows() {
        Ok(())
    } else {
        Err(anyhow!("no channel #{ch}"))
    }
}

/// A bias on `channel` in state `s`.
pub(super) fn bias(p: &mut Parts, s: usize, channel: usize, tuning: &EffectTuning) -> Result<()> {
    channel_ok(p, channel)?;
    p.c[(channel, s)] = 1.0;
    p.qc[(s, s)] = tuning.bias_psd;
    p.p0[(s, s)] = tuning.bias_std.powi(2);
    Ok(())
}

/// The scales and delays of `effects`, on the rows of the complete dynamics.
pub(super) fn outputs(p: &mut Parts, effects: &[(Effect, f64)]) -> Result<()> {
    for &(e, theta) in effects {
        match e {
            Effect::SensorScale { channel } => {
                let f = theta.exp();
                p.c.row_mut(channel).iter_mut().for_each(|v| *v *= f);
            }
            Effect::SensorDelay { channel } if theta != 0.0 => {
                let back = delay_matrix(&p.a, theta)?;
                let row = p.c.row(channel) * back;
                p.c.row_mut(channel).copy_from(&row);
            }
            _ => {}
        }
    }
    Ok(())
}

/// A lag reads what the channel read so far through `ẏ = (C x − y) / τ`, starting from it.
pub(super) fn lags(p: &mut Parts, placed: &[(Effect, f64, usize)]) -> Result<()> {
    let ns = p.a.ncols();
    for &(e, theta, s) in placed {
        if let Effect::SensorLag { channel } = e {
            let tau = theta.exp();
            if !(tau.is_finite() && tau > 0.0) {
                bail!("a sensor lag needs a positive time constant, not {tau}");
            }
            let row = p.c.row(channel).clone_owned();
            for j in 0..ns {
                p.a[(s, j)] += row[j] / tau;
            }
            p.a[(s, s)] -= 1.0 / tau;
            p.p0[(s, s)] = (&row * &p.p0 * row.transpose())[(0, 0)];
            p.c.row_mut(channel).fill(0.0);
            p.c[(channel, s)] = 1.0;
        }
    }
    Ok(())
}

/// `e^{−Aτ}`: maps the state now to the state `τ` ago along the noise-free dynamics (of the
/// reduced model, so by the shared core's [`expm`]).
fn delay_matrix(a: &DMatrix<f64>, tau: f64) -> Result<DMatrix<f64>> {
    expm(&(a * -tau)).map_err(|e| anyhow!("cannot form the delay: {e}"))
}
