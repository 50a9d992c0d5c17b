//! The numerical soak in QEMU (`edgekf-soak`, run by `cargo xtask test`, which sets
//! `EDGEKF_SOAK_ELF`): every soak of `edgekf_firmware::soak` on the Cortex-M4F, each in its own
//! QEMU run, its figures bit-identical to the same soak's on the host for the same steps and
//! within the same limits. CI runs each row's `qemu_steps`; with `EDGEKF_LONG=1` (`cargo xtask
//! soak`) each runs its `qemu_long_steps`, about 10¹⁰ instructions' worth, and with
//! `EDGEKF_QEMU_PLUGIN` (the instruction-counting TCG plugin, which `cargo xtask soak` builds)
//! the instructions each run took are printed.

#![cfg(feature = "hil")]

use edgekf_firmware::frame::Frame;
use edgekf_firmware::soak::{run, SoakFrame, SOAKS};
use edgekf_tests::qemu;
use edgekf_tests::report::frames;
use edgekf_tests::soak::{line, problems};
use std::time::{Duration, Instant};

#[test]
fn every_soak_in_qemu_matches_the_host_and_stays_sound() {
    let elf = qemu::soak_elf().unwrap_or_else(|e| panic!("{e:#}"));
    let long = std::env::var_os("EDGEKF_LONG").is_some();
    let plugin = std::env::var("EDGEKF_QEMU_PLUGIN").ok();
    let extra: Vec<String> =
        plugin.iter().flat_map(|p| [String::from("-plugin"), p.clone(), "-d".into(), "plugin".into()]).collect();
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    let mut failures = Vec::new();
    // Each soak in its own QEMU run, followed by its host run, all at once (they share the cores).
    std::thread::scope(|scope| {
        let runs: Vec<_> = SOAKS
            .iter()
            .enumerate()
            .map(|(index, row)| {
                let steps = if long { row.qemu_long_steps } else { row.qemu_steps };
                let (elf, extra) = (&elf, &extra);
                scope.spawn(move || {
                    let start = Instant::now();
                    let plan = format!("{} {steps}\n", row.name);
                    let chip = qemu::run_with(elf, plan.as_bytes(), Duration::from_secs(3600), extra)
                        .unwrap_or_else(|e| panic!("{e:#}"));
                    let seconds = start.elapsed().as_secs_f64();
                    if let Some(msg) = chip.failure() {
                        return Err(format!("{}: {msg}", row.name));
                    }
                    let got: Vec<SoakFrame> = frames(&chip.lines).unwrap();
                    let host = run(index, steps).unwrap();
                    let instructions = chip.stderr.lines().find_map(|l| {
                        l.strip_prefix("insn_section: total ")?.strip_suffix(" instructions")?.parse::<u64>().ok()
                    });
                    let per_step = instructions.map_or(String::new(), |n| {
                        format!(
                            ", {n} instructions ({:.0} a step: {:.2e} steps in 1e10)",
                            n as f64 / f64::from(steps),
                            1e10 * f64::from(steps) / n as f64
                        )
                    });
                    eprintln!("QEMU {} in {seconds:.1} s{per_step}", line(row, &host));
                    let bits = |f: &SoakFrame| {
                        let mut s = String::new();
                        f.write_line(&mut s).unwrap();
                        (s, [f.worst_nis, f.worst_error, f.worst_asymmetry, f.worst_drift].map(f32::to_bits))
                    };
                    match got.as_slice() {
                        [f] if bits(f) == bits(&host) => problems(row, f).map_or(Ok(()), Err),
                        _ => Err(format!("{}: QEMU reported {got:?}, the host {host:?}", row.name)),
                    }
                })
            })
            .collect();
        for r in runs {
            if let Err(e) = r.join().unwrap() {
                failures.push(e);
            }
        }
    });
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
