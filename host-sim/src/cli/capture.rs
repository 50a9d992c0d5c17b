//! `edgekf capture --log node.log --out window.csv`: the window a node handed over after a
//! model mismatch (its `window_start`, `window` and `window_end` frames, see the firmware's
//! `capture` module) turned into a recording in the data contract, which `edgekf loop <system>
//! --data window.csv` reads: a header, `t` in seconds from the node's first sample, then the
//! channel in its SI unit (a missing sample as an empty cell).
//!
//! The log is the node's decoded defmt output, one frame a line (what `cargo xtask run` prints,
//! or `defmt-print`'s on the board: a prefix such as a level or a timestamp before the frame's
//! tag is skipped). A log without a window, with more than one, or with a window cut short is
//! refused with the reason: a loop on half a window would name the wrong effect.

use crate::io::output::check;
use anyhow::{anyhow, bail, Context, Result};
use clap::{ArgMatches, Args, FromArgMatches};
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// `edgekf capture`'s flags.
#[derive(Debug, Clone, Args)]
pub struct CaptureArgs {
    /// The node's decoded log (one frame a line).
    #[arg(long, value_name = "LOG")]
    pub log: PathBuf,
    /// The recording to write (refused if it exists, unless --force).
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// The channel's name in the recording: the one the system's loop reads (the oscillator's
    /// accelerometer axis, `ax`, in m/s²).
    #[arg(long, value_name = "NAME", default_value = "ax")]
    pub channel: String,
    /// Replace `--out` if it exists.
    #[arg(long)]
    pub force: bool,
}

/// The `capture` command.
pub fn command() -> clap::Command {
    CaptureArgs::augment_args(clap::Command::new("capture")).about(
        "Turn a node's log into the loop's input: the window of raw samples the node handed over after a \
         model mismatch, as a CSV recording",
    )
}

/// A window as the node's frames gave it.
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// The mismatch's channel and statistic (0 CUSUM, 1 bias, 2 whiteness) and its `since`.
    pub mismatch: (u8, u8, u32),
    /// The first sample's number (from 1 at the node's start).
    pub first: u32,
    /// Samples a second.
    pub rate: u32,
    /// The estimator's state frame as it came (its values, without the tag).
    pub state: Option<String>,
    /// The raw samples, oldest first (NaN: missing).
    pub samples: Vec<f32>,
}

impl Window {
    /// The sample `j`'s time, s from the node's first sample.
    pub fn t(&self, j: usize) -> f64 {
        (f64::from(self.first) - 1.0 + j as f64) / f64::from(self.rate)
    }

    /// The recording: `t,<channel>` then one row a sample.
    pub fn to_csv(&self, channel: &str) -> String {
        let mut out = format!("t,{channel}\n");
        for (j, a) in self.samples.iter().enumerate() {
            let cell = if a.is_finite() { a.to_string() } else { String::new() };
            out.push_str(&format!("{},{cell}\n", self.t(j)));
        }
        out
    }
}

/// The `label=value` tokens after a frame's tag, as `(label, value)`; an unlabelled token is an
/// error (every window frame labels its values).
fn fields<'a>(tokens: &[&'a str], line: usize) -> Result<Vec<(&'a str, &'a str)>> {
    tokens.iter().map(|t| t.split_once('=').ok_or_else(|| anyhow!("line {line}: `{t}` is not label=value"))).collect()
}

/// The value labelled `name`, parsed.
fn field<T: std::str::FromStr>(fields: &[(&str, &str)], name: &str, line: usize) -> Result<T> {
    let (_, v) = fields.iter().find(|(l, _)| *l == name).ok_or_else(|| anyhow!("line {line}: no `{name}=`"))?;
    v.parse().map_err(|_| anyhow!("line {line}: `{name}={v}` is not a valid value"))
}

/// The window in a node's log `text` (see the module docs for what is refused).
///
/// ```
/// use edgekf_sim::cli::capture::parse_log;
/// let log = "blk 0 16 0 0 0 0 0 0 0 0\n\
///            window_start channel=0 statistic=1 since=10 first=301 samples=2 rate=1000\n\
///            window k=301 a=0.5\nwindow k=302 a=NaN\nwindow_end samples=2\n";
/// let w = parse_log(log).unwrap();
/// assert_eq!((w.first, w.samples.len(), w.t(1)), (301, 2, 0.301));
/// assert_eq!(w.to_csv("ax"), "t,ax\n0.3,0.5\n0.301,\n");
/// ```
pub fn parse_log(text: &str) -> Result<Window> {
    let mut window: Option<(Window, u32)> = None;
    let mut complete = false;
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let tokens: Vec<&str> = raw.split_whitespace().collect();
        let Some(at) =
            tokens.iter().position(|t| matches!(*t, "window_start" | "window" | "window_end" | "window_state"))
        else {
            continue;
        };
        let (tag, rest) = (tokens[at], &tokens[at + 1..]);
        match (tag, &mut window) {
            ("window_start", Some(_)) => bail!("line {line}: a second window; give the log of one node run"),
            ("window_start", None) => {
                let f = fields(rest, line)?;
                let (samples, rate): (u32, u32) = (field(&f, "samples", line)?, field(&f, "rate", line)?);
                if rate == 0 || samples == 0 {
                    bail!("line {line}: a window of {samples} samples at {rate} Hz");
                }
                let mismatch = (field(&f, "channel", line)?, field(&f, "statistic", line)?, field(&f, "since", line)?);
                let w = Window { mismatch, first: field(&f, "first", line)?, rate, state: None, samples: Vec::new() };
                window = Some((w, samples));
            }
            (_, None) => bail!("line {line}: a `{tag}` frame before any `window_start`"),
            ("window_state", Some((w, _))) => w.state = Some(rest.join(" ")),
            ("window", Some((w, _))) if !complete => {
                let f = fields(rest, line)?;
                let (k, a): (u32, f32) = (field(&f, "k", line)?, field(&f, "a", line)?);
                let expected = w.first as u64 + w.samples.len() as u64;
                if u64::from(k) != expected {
                    bail!("line {line}: sample {k} where {expected} was due: the window has a hole or is out of order");
                }
                w.samples.push(a);
            }
            ("window", Some(_)) => bail!("line {line}: a sample after `window_end`"),
            (_, Some((w, samples))) => {
                let f = fields(rest, line)?;
                let end: u32 = field(&f, "samples", line)?;
                if end != *samples || w.samples.len() != *samples as usize {
                    bail!(
                        "line {line}: the window ends after {} of its {samples} samples (`window_end samples={end}`)",
                        w.samples.len()
                    );
                }
                complete = true;
            }
        }
    }
    match window {
        None => bail!(
            "no window in the log: the node sent no `window_start` (no mismatch, or the run ended before the \
             window was recorded)"
        ),
        Some((w, samples)) if !complete => {
            bail!("the window is truncated: {} of its {samples} samples, and no `window_end`", w.samples.len())
        }
        Some((w, _)) => Ok(w),
    }
}

/// Writes `text` to `out` through a temporary file in its folder, renamed onto it only when
/// complete; an existing `out` is kept (an error) unless `force`.
fn write_new(out: &Path, text: &str, force: bool) -> Result<()> {
    if force {
        return crate::io::output::write_atomic(out, text).with_context(|| format!("{}: cannot write", out.display()));
    }
    if out.exists() {
        bail!("{}: exists; choose another name or add --force to replace it", out.display());
    }
    let folder = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".edgekf-capture.").suffix(".partial");
    // An ordinary file, readable as the umask allows (a temporary file is private).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(&folder)?;
    tmp.write_all(text.as_bytes())?;
    tmp.as_file().sync_all()?;
    tmp.persist_noclobber(out).map_err(|e| anyhow!("{}: cannot write: {}", out.display(), e.error))?;
    Ok(())
}

/// Runs `edgekf capture` (`m`: its matches).
pub fn run(m: &ArgMatches) -> Result<()> {
    let args = CaptureArgs::from_arg_matches(m).map_err(|e| anyhow!("{e}"))?;
    check(&[Some(&args.out)], &[Some(&args.log)])?;
    let text = std::fs::read_to_string(&args.log).with_context(|| format!("{}: cannot read", args.log.display()))?;
    let w = parse_log(&text).with_context(|| format!("{}", args.log.display()))?;
    write_new(&args.out, &w.to_csv(&args.channel), args.force)?;
    let (channel, statistic, since) = w.mismatch;
    let name = ["cusum", "bias", "whiteness"].get(statistic as usize).copied().unwrap_or("unknown");
    println!(
        "wrote {}: {} samples of {} at {} Hz, t = {:.3} … {:.3} s; after a {name} mismatch on channel {channel} \
         since sample {since} (t = {:.3} s); the node's state then: {}",
        args.out.display(),
        w.samples.len(),
        args.channel,
        w.rate,
        w.t(0),
        w.t(w.samples.len().saturating_sub(1)),
        (f64::from(since) - 1.0) / f64::from(w.rate),
        w.state.as_deref().unwrap_or("not sent")
    );
    Ok(())
}

#[cfg(test)]
mod tests;
