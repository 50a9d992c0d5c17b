//! `cargo xtask bench`: per-step instruction counts of the filters on the Cortex-M4F under
//! QEMU, checked against the budgets of the image table ([`crate::images`]). (Host timings:
//! `cargo bench -p edgekf`.)

use crate::{firmware, images};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Compiles the instruction-counting TCG plugin with the host C compiler.
fn plugin(root: &Path) -> Result<PathBuf> {
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

/// Builds and runs the benchmark image; prints and returns `(label, n, m, instructions)`.
pub fn run(root: &Path) -> Result<Vec<(String, usize, usize, u64)>> {
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
    if !missed.is_empty() {
        bail!("instruction budgets missed: {}", missed.join("; "));
    }
    Ok(rows)
}
