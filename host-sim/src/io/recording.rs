//! A recording read for a system: the data file (its notices to standard error), its rate
//! checked against the configuration's, and its samples put on one timeline where lost
//! samples become missing ones. Every system's commands read their data through here.

use anyhow::Result;
use std::path::Path;

/// Reads `path` as a data file whose channels are `known` (notices to standard error), checks
/// that it is sampled at `rate` Hz (within 1 %) and puts it on one timeline
/// ([`super::timeline`]): lost samples become missing ones. The loop needs one stretch, so a
/// gap too long to bridge is an error.
pub fn read_data(
    path: &Path,
    known: &[&str],
    rate: f64,
    timeline: &super::timeline::TimelineOptions,
) -> Result<super::data::DataFile> {
    let (file, notes) = super::data::read(path, known)?;
    let (file, restarts) = on_one_timeline(path, file, &notes, rate, timeline)?;
    if let Some(r) = restarts.first() {
        anyhow::bail!(
            "{}: a {:.3} s gap before t = {:.6} s is too long to bridge (timeline.max_gap_s); close the loop on each stretch",
            path.display(),
            r.gap_s,
            r.t
        );
    }
    Ok(file)
}

/// Reads `path` as a data file with its `required` channels among the `known` ones, checks its
/// rate and puts it on one timeline as [`read_data`] does; an estimator starts afresh at the
/// rows returned, where a gap too long to bridge restarts the timeline.
pub fn read_estimator_data(
    path: &Path,
    required: &[&str],
    known: &[&str],
    rate: f64,
) -> Result<(super::data::DataFile, Vec<usize>)> {
    let (file, notes) = super::data::read_required(path, required, known)?;
    let (file, restarts) = on_one_timeline(path, file, &notes, rate, &Default::default())?;
    Ok((file, restarts.iter().map(|r| r.row).collect()))
}

/// The notices, the rate check (within 1 % of `rate` Hz) and the bridging both readers share.
fn on_one_timeline(
    path: &Path,
    file: super::data::DataFile,
    notes: &super::data::DataReport,
    rate: f64,
    timeline: &super::timeline::TimelineOptions,
) -> Result<(super::data::DataFile, Vec<super::timeline::Restart>)> {
    let rows = file.len();
    let (file, bridged) = super::timeline::bridge(&file, &notes.timing, timeline);
    // A slow channel's empty cells between its updates are its rate, said once below.
    let mut shown = notes.clone();
    shown.nan_cells.retain(|(name, count)| !bridged.only_between_updates(name, *count, rows));
    eprintln!("{}: {shown}", path.display());
    if (notes.timing.sample_rate - rate).abs() > 0.01 * rate {
        anyhow::bail!(
            "{}: sampled at {:.3} Hz, the configuration says {rate} Hz",
            path.display(),
            notes.timing.sample_rate
        );
    }
    for n in bridged.notices() {
        eprintln!("notice: {n}");
    }
    Ok((file, bridged.restarts))
}
