//! The numerical soak's checks ([`edgekf_firmware::soak`]), shared by the host soak and the
//! QEMU soak: one verdict for the figures wherever they were computed.

use edgekf_firmware::soak::{SoakFrame, SoakRow};

/// What is wrong with a soak's figures, or `None`: every step finite, the covariance positive
/// definite at every check and never worse than `1e-5` asymmetric, at most one covariance reset
/// per 10⁶ steps, no refused update, no estimate out of bounds, and the worst block's NIS mean
/// (per measurement) and error within the row's limits; for the crank, the recording's
/// features within `1e-3` of their `f64` accumulation.
pub fn problems(row: &SoakRow, f: &SoakFrame) -> Option<String> {
    let mut p = Vec::new();
    if f.non_finite != 0 {
        p.push(format!("{} non-finite steps", f.non_finite));
    }
    if f.not_positive_definite != 0 {
        p.push(format!("{} of {} covariance checks not positive definite", f.not_positive_definite, f.checks));
    }
    if f.worst_asymmetry.is_nan() || f.worst_asymmetry > 1e-5 {
        p.push(format!("covariance asymmetry {:e}", f.worst_asymmetry));
    }
    if f.covariance_resets > f.steps / 1_000_000 {
        p.push(format!("{} covariance resets in {} steps", f.covariance_resets, f.steps));
    }
    if f.refused_updates != 0 {
        p.push(format!("{} refused updates", f.refused_updates));
    }
    if f.out_of_bounds != 0 {
        p.push(format!("{} estimates out of bounds", f.out_of_bounds));
    }
    if let Some(limit) = row.nis_limit {
        if f.worst_nis.is_nan() || f.worst_nis >= limit {
            p.push(format!("worst block NIS mean {} ≥ {limit}", f.worst_nis));
        }
    }
    if f.worst_error.is_nan() || f.worst_error >= row.error_limit {
        p.push(format!("worst block error {} ≥ {}", f.worst_error, row.error_limit));
    }
    if f.worst_drift.is_nan() || f.worst_drift >= 1e-3 {
        p.push(format!("features {} from their f64 accumulation", f.worst_drift));
    }
    (!p.is_empty()).then(|| format!("soak {}: {}; {f:?}", row.name, p.join(", ")))
}

/// One line of figures.
pub fn line(row: &SoakRow, f: &SoakFrame) -> String {
    format!(
        "soak {:<20} {:>9} steps, {:>4} blocks: worst block NIS mean {:.3}, worst error {:.3e} ({}), \
         asymmetry {:.1e}, drift {:.1e}, {} checks, {} resets, {} refused, {} out of bounds",
        row.name,
        f.steps,
        f.blocks,
        f.worst_nis,
        f.worst_error,
        row.error_of,
        f.worst_asymmetry,
        f.worst_drift,
        f.checks,
        f.covariance_resets,
        f.refused_updates,
        f.out_of_bounds
    )
}
