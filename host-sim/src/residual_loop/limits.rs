//! The smallest change of an effect the data could tell: how far its scalar must move from
//! its neutral value before the log-likelihood changes by what an effect must gain to be
//! added (its BIC cost and the model's floor: the acceptance rule's own threshold). An
//! effect's size in a test case is stated as a multiple of this limit, so that a case says
//! how hard it is, not only how large.

use super::fit::Engine;
use super::system::Described;
use super::vocabulary::Applied;
use super::{LoopOptions, LoopSystem};
use anyhow::Result;

/// The detection limit of `effect` on `sys`'s data with its declared model: the signed change
/// of its scalar (in the fitting variable: `ln f` for a factor) on the side with the more
/// room, to the scalar's tolerance. `None` for an effect without a scalar, or when even the
/// end of the range it may take changes the log-likelihood by less (these sensors cannot see
/// it).
pub fn detection_limit<S: LoopSystem>(sys: &S, effect: S::Effect, options: &LoopOptions) -> Result<Option<f64>> {
    let Some((range, _)) = sys.fitting(&effect).scalar else { return Ok(None) };
    let (_, run) = sys.run(&[])?;
    let nis_scale = sys.summarise(&run).nis_scale();
    let engine = Engine { sys, options, t: Vec::new(), n_meas: run.measurements().max(2) as f64, nis_scale };
    let threshold = engine.penalty(&effect, false);
    let base = run.log_likelihood();
    // A trial the filter cannot run counts as seen: the data reject it.
    let change = |theta: f64| {
        sys.run(&[Applied::new(effect, theta)]).map_or(f64::INFINITY, |(_, r)| (r.log_likelihood() - base).abs())
    };
    let up = range.high - range.neutral >= range.neutral - range.low;
    let (sign, room) = if up { (1.0, range.high - range.neutral) } else { (-1.0, range.neutral - range.low) };
    if room.is_nan() || room <= 0.0 || change(range.neutral + sign * room) < threshold {
        return Ok(None);
    }
    // Near the neutral value the change grows with the square of the distance: bisect.
    let (mut lo, mut hi) = (0.0, room);
    while hi - lo > range.tolerance.max(1e-12 * room) {
        let mid = 0.5 * (lo + hi);
        if change(range.neutral + sign * mid) < threshold {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Some(sign * hi))
}
