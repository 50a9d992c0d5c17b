//! The loop's effect matrices (`edgekf_sim::matrix`): every case of a system run in parallel
//! over the cores, scored by the one rule, printed as the README's table; with
//! `--readme README.md` the table replaces the one between the README's markers
//! `<!-- loop-matrix SYSTEM -->` and `<!-- /loop-matrix SYSTEM -->`.
//!
//! `cargo run --release -p edgekf-sim --example loop_matrix -- [boom] [oscillator] [rotor] [uuv] [--readme README.md]`
//! (`cargo xtask loop-matrix` runs it). `--case TEXT` runs only the cases whose name holds
//! `TEXT` (to look at one row again; not with `--readme`, whose tables are whole).

use anyhow::{bail, Context, Result};
use edgekf_sim::matrix::{table, Case, Outcome};
use edgekf_sim::systems::boom::{matrix as boom, BoomConfig};
use edgekf_sim::systems::oscillator::{matrix as oscillator, scenario::Scenario};
use edgekf_sim::systems::rotor::matrix as rotor;
use edgekf_sim::systems::uuv::{matrix as uuv, UuvConfig};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The systems with a matrix.
const SYSTEMS: [&str; 4] = ["boom", "oscillator", "rotor", "uuv"];

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut systems, mut readme, mut only) = (Vec::new(), None, None);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--readme" => readme = Some(PathBuf::from(args.next().context("--readme takes a file")?)),
            "--case" => only = Some(args.next().context("--case takes the text of a case's name")?),
            s if SYSTEMS.contains(&s) => systems.push(s.to_string()),
            other => bail!("unknown argument `{other}` (systems with a matrix: {})", SYSTEMS.join(", ")),
        }
    }
    if readme.is_some() && only.is_some() {
        bail!("--case runs part of a matrix; the README's tables are written from whole ones");
    }
    if systems.is_empty() {
        systems = SYSTEMS.iter().map(|s| s.to_string()).collect();
    }
    let only = only.as_deref().unwrap_or("");
    for system in systems {
        let text = system_table(&system, only)?;
        print!("{text}");
        if let Some(path) = &readme {
            replace_between_markers(path, &system, &text)?;
        }
    }
    Ok(())
}

/// A system's matrix from its module's three functions: its cases, a clean run's error at a
/// seed, and one case run and scored.
struct Matrix<D, T> {
    cases: fn(&D) -> Result<Vec<Case<T>>>,
    clean_error: fn(&D, u64) -> Result<f64>,
    run_case: fn(&Case<T>, &D, f64) -> Result<Outcome>,
}

impl<D: Sync, T: Sync> Matrix<D, T> {
    /// The table of the cases whose name holds `only`, against the `declared` model.
    fn table(&self, system: &str, declared: &D, only: &str) -> Result<String> {
        let cases = matching((self.cases)(declared)?, only)?;
        parallel_table(
            system,
            &cases,
            |s| (self.clean_error)(declared, s),
            |c, clean| (self.run_case)(c, declared, clean),
        )
    }
}

/// Each system's table: the boom and the vehicle as their defaults declare them, the
/// oscillator on 4 s runs of the demo's mode and drive, the rotor on 3 s runs of the paper rotor.
fn system_table(system: &str, only: &str) -> Result<String> {
    macro_rules! table {
        ($m:ident, $declared:expr) => {
            Matrix { cases: $m::cases, clean_error: $m::clean_error, run_case: $m::run_case }
                .table(system, &$declared, only)
        };
    }
    match system {
        "boom" => table!(boom, BoomConfig::default()),
        "uuv" => table!(uuv, UuvConfig::default()),
        "oscillator" => table!(oscillator, Scenario { duration_s: 4.0, ..Scenario::default() }),
        "rotor" => table!(rotor, rotor::declared()?),
        _ => unreachable!("checked against SYSTEMS"),
    }
}

/// The cases whose name holds `only` (every case for an empty `only`); none is an error.
fn matching<T>(cases: Vec<Case<T>>, only: &str) -> Result<Vec<Case<T>>> {
    let names: Vec<String> = cases.iter().map(|c| c.name.clone()).collect();
    let kept: Vec<Case<T>> = cases.into_iter().filter(|c| c.name.contains(only)).collect();
    if kept.is_empty() {
        bail!("no case's name holds `{only}`; the cases are:\n  {}", names.join("\n  "));
    }
    Ok(kept)
}

/// A system's cases run in parallel, each against the clean run's error at its seed (each
/// seed's clean run once), as the README's table.
fn parallel_table<T: Sync>(
    system: &str,
    cases: &[Case<T>],
    clean: impl Fn(u64) -> Result<f64> + Sync,
    run: impl Fn(&Case<T>, f64) -> Result<Outcome> + Sync,
) -> Result<String> {
    eprintln!("{system}: {} cases", cases.len());
    let mut seeds: Vec<u64> = cases.iter().map(|c| c.seed).collect();
    seeds.sort_unstable();
    seeds.dedup();
    let clean: BTreeMap<u64, f64> = seeds.par_iter().map(|&s| Ok((s, clean(s)?))).collect::<Result<_>>()?;
    let outcomes: Vec<Outcome> = cases
        .par_iter()
        .map(|c| {
            let o = run(c, clean[&c.seed]);
            match &o {
                Ok(o) => eprintln!("  {}: {:?}", o.case, o.verdict),
                Err(e) => eprintln!("  {}: {e:#}", c.name),
            }
            o
        })
        .collect::<Result<_>>()?;
    Ok(table(system, &outcomes))
}

/// Puts `text` between the README's markers for `system`, the rest of the file as it was.
fn replace_between_markers(path: &PathBuf, system: &str, text: &str) -> Result<()> {
    let readme = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let (open, close) = (format!("<!-- loop-matrix {system} -->\n"), format!("<!-- /loop-matrix {system} -->"));
    let (Some(a), Some(b)) = (readme.find(&open), readme.find(&close)) else {
        bail!("{}: no `{}` … `{close}` markers", path.display(), open.trim_end());
    };
    if b < a {
        bail!("{}: the markers for {system} are out of order", path.display());
    }
    let updated = format!("{}{open}{text}{}", &readme[..a], &readme[b..]);
    edgekf_sim::io::output::write_atomic(path, updated).with_context(|| format!("{}: cannot write", path.display()))?;
    eprintln!("wrote the {system} table into {}", path.display());
    Ok(())
}
