//! `cargo xtask bench`: per-step instruction counts of the filters on the Cortex-M4F under
//! QEMU, checked against the budgets of the image table ([`crate::images`]). (Host timings:
//! `cargo bench -p edgekf`.)

use crate::{firmware, images};
use anyhow::{bail, Context, Result};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Compiles the instruction-counting TCG plugin with the host C compiler.
pub fn plugin(root: &Path) -> Result<PathBuf> {
    let src = root.join("xtask/qemu-plugin/insn_section.c");
    let out_dir = root.join("target/qemu-plugin");
    std::fs::create_dir_all(&out_dir)?;
    let lib = out_dir.join("libinsn_section.so");
    let st = Command::new("gcc")
        .args(["-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-o"])
        .arg(&lib)
        .arg(&src)
        .status()
        .context("running gcc for the QEMU plugin (install gcc)")?;
    if !st.success() {
        bail!("compiling {} failed", src.display());
    }
    Ok(lib)
}

fn symbol(elf: &Path, name: &str) -> Result<String> {
    let out = Command::new("arm-none-eabi-nm").arg(elf).output().context("arm-none-eabi-nm")?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() == 3 && f[2] == name).then(|| format!("0x{}", f[0]))
        })
        .with_context(|| format!("symbol {name} not found in {}", elf.display()))
}

/// Builds and runs the benchmark image; prints and returns `(label, n, m, instructions)`. With
/// `host`, then also edgekf's host speed against the peers ([`crate::peers`]). Writes
/// `target/bench/results.json` either way.
pub fn run(root: &Path, host: bool) -> Result<Vec<(String, usize, usize, u64)>> {
    let lib = plugin(root)?;
    let elf = firmware::build(images::bench_image())?;
    let (start, end) = (symbol(&elf, "bench_start")?, symbol(&elf, "bench_end")?);
    let arg = format!("{},start={start},end={end}", lib.display());
    let run = edgekf_tests::qemu::run_with(&elf, b"", Duration::from_secs(300), &["-plugin", &arg, "-d", "plugin"])?;
    if let Some(msg) = run.failure() {
        bail!(msg);
    }
    let counts: Vec<u64> = run
        .stderr
        .lines()
        .filter_map(|l| l.strip_prefix("insn_section: ")?.strip_suffix(" instructions")?.parse().ok())
        .collect();
    let labels: Vec<(String, usize, usize)> = run
        .lines
        .iter()
        .filter_map(|l| {
            let mut it = l.strip_prefix("bench ")?.split_whitespace();
            let label = it.next()?.to_string();
            let n = it.next()?.strip_prefix("n=")?.parse().ok()?;
            let m = it.next()?.strip_prefix("m=")?.parse().ok()?;
            Some((label, n, m))
        })
        .collect();
    if labels.len() != counts.len() {
        bail!("{} benchmark labels but {} counts:\n{}", labels.len(), counts.len(), run.stderr);
    }
    println!("{:<20} {:>3} {:>3} {:>13}  target", "kernel (f32, one step)", "n", "m", "instructions");
    let mut rows = Vec::new();
    let mut missed = Vec::new();
    for ((label, n, m), count) in labels.into_iter().zip(counts) {
        let target = images::budgets().find(|t| t.0 == label && t.1 == n && t.2 == m).map(|t| t.3);
        let verdict = match target {
            Some(t) if count <= t => format!("≤ {t}: met"),
            Some(t) => {
                missed.push(format!("{label} n={n} m={m}: {count} > {t}"));
                format!("≤ {t}: MISSED")
            }
            None => String::new(),
        };
        println!("{label:<20} {n:>3} {m:>3} {count:>13}  {verdict}");
        rows.push((label, n, m, count));
    }
    for (label, n, m, _) in images::budgets() {
        if !rows.iter().any(|r| (r.0.as_str(), r.1, r.2) == (*label, *n, *m)) {
            missed.push(format!("{label} n={n} m={m}: not measured by the bench image"));
        }
    }
    let (table, late) = real_time(&rows);
    missed.extend(late);
    // The chip's verdict first: the host half takes minutes and needs PyPI.
    let host = if host && missed.is_empty() { Some(crate::peers::run_all(root)?) } else { None };
    write_results(root, &rows, &table, host.as_ref())?;
    if !missed.is_empty() {
        bail!("instruction budgets missed: {}", missed.join("; "));
    }
    Ok(rows)
}

/// One image's real-time figures: name, rate, period, worst ordinary sample, worst spike (all
/// in instructions), highest sustainable rate, and whether it is real time.
type RealTimeRow = (&'static str, u32, f64, f64, f64, f64, bool);

/// Writes `target/bench/results.json` (through a temporary file, renamed when complete): the
/// instruction counts with their budgets, and the real-time table.
fn write_results(
    root: &Path,
    rows: &[(String, usize, usize, u64)],
    table: &[RealTimeRow],
    host: Option<&serde_json::Value>,
) -> Result<()> {
    let dir = root.join("target/bench");
    std::fs::create_dir_all(&dir)?;
    let unix = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let kernels: Vec<serde_json::Value> = rows
        .iter()
        .map(|(label, n, m, count)| {
            let budget = images::budgets().find(|t| (t.0, t.1, t.2) == (label.as_str(), *n, *m)).map(|t| t.3);
            json!({ "label": label, "n": n, "m": m, "instructions": count, "budget": budget })
        })
        .collect();
    let real_time: Vec<serde_json::Value> = table
        .iter()
        .map(|(bin, rate, period, worst, spike, max_rate, ok)| {
            json!({ "image": bin, "rate_hz": rate, "period_cycles": period.round(), "worst_ordinary": worst.round(),
                    "worst_spike": spike.round(), "max_rate_hz": max_rate.round(), "real_time": ok })
        })
        .collect();
    let mut results = json!({
        "unix_time": unix,
        "machine": crate::peers::machine(),
        "clock_hz": images::CLOCK_HZ,
        "fifo_samples": images::FIFO_SAMPLES,
        "kernels": kernels,
        "real_time": real_time,
    });
    if let (Some(h), Some(r)) = (host, results.as_object_mut()) {
        r.insert("host".into(), h.clone());
    }
    let json = serde_json::to_string_pretty(&results)? + "\n";
    let (tmp, out) = (dir.join("results.json.tmp"), dir.join("results.json"));
    std::fs::write(&tmp, json)?;
    std::fs::rename(&tmp, &out)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// Prints every image's real-time table from the measured `rows` ([`images::RealTime`]);
/// returns it and what it misses.
fn real_time(rows: &[(String, usize, usize, u64)]) -> (Vec<RealTimeRow>, Vec<String>) {
    let count = |label: &str, n: usize, m: usize| {
        rows.iter().find(|r| (r.0.as_str(), r.1, r.2) == (label, n, m)).map(|r| r.3 as f64)
    };
    let (mut missed, mut table) = (Vec::new(), Vec::new());
    println!(
        "\nreal time per FIFO block at {:.0} MHz, one instruction a cycle (a lower bound on the time), FIFO {} samples:",
        images::CLOCK_HZ / 1e6,
        images::FIFO_SAMPLES
    );
    println!(
        "{:<20} {:>8} {:>10} {:>12} {:>7} {:>12} {:>12}  verdict",
        "image", "rate Hz", "period", "worst ord.", "load", "worst spike", "max rate Hz"
    );
    for (image, rt) in images::real_time() {
        let period = images::CLOCK_HZ / f64::from(rt.rate_hz);
        let mut worst = 0.0f64;
        let mut problems = Vec::new();
        for phase in rt.phases {
            let mut cost = 0.0;
            for (label, n, m, samples) in phase.iter() {
                match count(label, *n, *m) {
                    Some(c) => cost += c / f64::from(*samples),
                    None => problems.push(format!("{label} n={n} m={m} not measured")),
                }
            }
            worst = worst.max(cost);
        }
        let mut spike = 0.0f64;
        for (label, n, m) in rt.spikes {
            match count(label, *n, *m) {
                Some(c) => spike = spike.max(c),
                None => problems.push(format!("{label} n={n} m={m} not measured")),
            }
        }
        let fifo = images::FIFO_SAMPLES;
        if worst > period {
            problems.push(format!("an ordinary sample takes {worst:.0} of {period:.0} cycles"));
        }
        if spike + (fifo - 1.0) * worst > fifo * period {
            problems.push(format!(
                "a FIFO block with its costliest sample takes {:.0} of {:.0} cycles",
                spike + (fifo - 1.0) * worst,
                fifo * period
            ));
        }
        // The highest rate at which both conditions hold.
        let max_rate = (images::CLOCK_HZ / worst).min(images::CLOCK_HZ * fifo / (spike + (fifo - 1.0) * worst));
        let verdict = if problems.is_empty() {
            "real time".to_string()
        } else {
            format!("NOT REAL TIME: {}", problems.join(", "))
        };
        println!(
            "{:<20} {:>8} {:>10.0} {:>12.0} {:>6.1}% {:>12.0} {:>12.0}  {verdict}",
            image.bin.trim_start_matches("edgekf-"),
            rt.rate_hz,
            period,
            worst,
            100.0 * worst / period,
            spike,
            max_rate
        );
        table.push((image.bin, rt.rate_hz, period, worst, spike, max_rate, problems.is_empty()));
        missed.extend(problems.into_iter().map(|p| format!("{}: {p}", image.bin)));
    }
    (table, missed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every label the real-time table needs, at a cost of `each`, except `over` at `cost`.
    fn rows(each: u64, over: &str, cost: u64) -> Vec<(String, usize, usize, u64)> {
        let mut rows: Vec<(String, usize, usize, u64)> = Vec::new();
        for (_, rt) in images::real_time() {
            let labels =
                rt.phases.iter().flat_map(|p| p.iter().map(|s| (s.0, s.1, s.2))).chain(rt.spikes.iter().copied());
            for (label, n, m) in labels {
                rows.push((label.to_string(), n, m, if label == over { cost } else { each }));
            }
        }
        rows
    }

    /// The 1 kHz rotor misses real time with a start-up step of 90 000 instructions (the dense
    /// filter's 94 000 did), and a 100 Hz boom with a re-reduction of 30 M (backlog 36 samples);
    /// 20 000 and 16 M pass.
    #[test]
    fn the_real_time_check_fails_a_sample_over_its_period_or_a_block_over_the_fifo() {
        assert!(real_time(&rows(100, "rotor_node_step", 20_000)).1.is_empty());
        let (_, missed) = real_time(&rows(100, "rotor_node_step", 90_000));
        assert!(!missed.is_empty() && missed.iter().all(|m| m.contains("edgekf-rotor-qemu")), "{missed:?}");
        assert!(missed[0].contains("an ordinary sample takes 90000 of 84000 cycles"), "{missed:?}");
        assert!(real_time(&rows(100, "boom_rereduce", 16_000_000)).1.is_empty());
        let (_, missed) = real_time(&rows(100, "boom_rereduce", 30_000_000));
        assert!(missed.len() == 1 && missed[0].contains("FIFO block"), "{missed:?}");
        let (_, missed) = real_time(&rows(100, "none", 0)[1..]);
        assert!(missed.iter().any(|m| m.contains("not measured")), "{missed:?}");
    }
}
