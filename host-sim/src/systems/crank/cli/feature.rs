//! `edgekf crank feature`: the paper's spectral feature of each window of a recording.

use super::super::feature::window_features;
use super::FeatureArgs;
use crate::io::data;
use anyhow::Context as _;

pub(super) fn feature(args: FeatureArgs) -> anyhow::Result<()> {
    let (file, report) = data::read(&args.data, &[args.column.as_str()])?;
    eprintln!("{}: {report}", args.data.display());
    // Lost rows are missing samples here too (not a shorter recording), and refused alike.
    let (file, bridged) = crate::io::timeline::bridge(&file, &report.timing, &Default::default());
    let x =
        file.column(&args.column).with_context(|| format!("{}: no column `{}`", args.data.display(), args.column))?;
    let first_missing = x.iter().position(|v| !v.is_finite()).map(|k| file.t[k]);
    // A gap too long to bridge: its samples are missing from one period after the row before.
    let unbridged = bridged.restarts.first().and_then(|r| file.t.get(r.row.checked_sub(1)?));
    let unbridged = unbridged.map(|t| t + report.timing.dt_median);
    if let Some(t) = first_missing.into_iter().chain(unbridged).reduce(f64::min) {
        anyhow::bail!(
            "{}: column `{}` has sample(s) missing from t = {t:.6} s (rows lost from the time column or empty cells); \
             the spectrum needs every sample",
            args.data.display(),
            args.column
        );
    }
    let rate = report.timing.sample_rate;
    let feats = window_features(x, rate, args.window);
    if feats.is_empty() {
        anyhow::bail!("{}: shorter than one {} s window", args.data.display(), args.window);
    }
    println!(
        "{}: spectral feature of `{}`, {} s windows at {rate:.1} Hz",
        args.data.display(),
        args.column,
        args.window
    );
    println!("{:>8} {:>10} {:>14} {:>14}", "window", "t0 [s]", "a", "b [1/Hz]");
    let mut a_values = Vec::new();
    for (i, f) in feats.iter().enumerate() {
        let t0 = file.t[0] + i as f64 * args.window;
        match f {
            Some(f) => {
                println!("{i:>8} {t0:>10.3} {:>14.6} {:>14.6e}", f.a, f.b);
                a_values.push(f.a);
            }
            None => println!("{i:>8} {t0:>10.3} {:>14} {:>14}", "—", "—"),
        }
    }
    let n = a_values.len() as f64;
    if n > 0.0 {
        let mean = a_values.iter().sum::<f64>() / n;
        let std = (a_values.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        println!("a: mean {mean:.6}, std {std:.6} over {} window(s)", a_values.len());
    }
    Ok(())
}
