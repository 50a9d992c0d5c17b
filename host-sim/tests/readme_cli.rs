//! The README's command-line section and `edgekf --help` checked against each other: every
//! command and every long flag of the clap tree is in the README's list, and every `--flag`
//! the section names exists in the tree. The tree is the one `edgekf` runs
//! (`cli::command(systems::REGISTRY)`), so a flag added to the code and not to the README, or
//! a README flag the code dropped, fails here.

use edgekf_sim::{cli, systems};
use std::collections::{BTreeMap, BTreeSet};

/// The section's text, from its heading to the next `## ` heading, without the `cargo …`
/// code spans (their flags are cargo's).
fn cli_section() -> String {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let start = readme.find("## The `edgekf` command line").expect("the README has its CLI section");
    let rest = &readme[start..];
    let end = rest[3..].find("\n## ").map_or(rest.len(), |i| i + 3);
    let parts: Vec<&str> = rest[..end].split('`').collect();
    let kept = parts.iter().enumerate().filter(|(i, p)| i % 2 == 0 || !p.starts_with("cargo "));
    kept.map(|(_, p)| *p).collect::<Vec<_>>().join("`")
}

/// `--flag` words in `text` (letters, digits and dashes after the two dashes).
fn flags(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices("--") {
        let name: String = text[i + 2..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
        let before = text[..i].chars().next_back();
        if !name.is_empty() && before.is_none_or(|c| !c.is_ascii_alphanumeric() && c != '-') {
            out.insert(name);
        }
    }
    out
}

/// The section's `edgekf …` usage lines, keyed by command path (`rotor campbell`; `a|b`
/// words expanded), with the flags each names.
fn readme_commands(section: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in section.lines().filter(|l| l.starts_with("edgekf ")) {
        let words: Vec<&str> = line.split_whitespace().skip(1).take_while(|w| !w.starts_with(['-', '['])).collect();
        let mut paths = vec![String::new()];
        for w in words {
            paths = paths
                .iter()
                .flat_map(|p| w.split('|').map(move |alt| format!("{p} {alt}").trim().to_string()))
                .collect();
        }
        for p in paths {
            out.entry(p).or_default().extend(flags(line));
        }
    }
    out
}

/// Every leaf command of the tree (`rotor campbell`, `loop boom`, `demo`) with its long flags,
/// `--help` and `--version` aside. The `sdof` test system is left out: users' builds lack it.
fn tree_commands() -> BTreeMap<String, BTreeSet<String>> {
    fn walk(cmd: &clap::Command, path: &str, out: &mut BTreeMap<String, BTreeSet<String>>) {
        if cmd.get_subcommands().next().is_none() {
            let longs = cmd
                .get_arguments()
                .filter(|a| !a.is_hide_set())
                .filter_map(|a| a.get_long())
                .filter(|l| !["help", "version"].contains(l))
                .map(str::to_string)
                .collect();
            out.insert(path.trim().to_string(), longs);
        }
        for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help" && !s.is_hide_set()) {
            if cfg!(feature = "sdof") && sub.get_name() == "sdof" {
                continue;
            }
            walk(sub, &format!("{path} {}", sub.get_name()), out);
        }
    }
    let mut out = BTreeMap::new();
    walk(&cli::command(systems::REGISTRY), "", &mut out);
    out
}

#[test]
fn every_command_and_flag_of_the_help_is_in_the_readme_and_back() {
    let section = cli_section();
    let readme = readme_commands(&section);
    let tree = tree_commands();
    assert!(tree.len() >= 25, "the walk found {} commands", tree.len());
    let mut wrong = Vec::new();
    for (path, longs) in &tree {
        match readme.get(path) {
            None => wrong.push(format!("`edgekf {path}` is not in the README's list")),
            Some(listed) => {
                for l in longs.difference(listed) {
                    wrong.push(format!("`edgekf {path} --{l}` is not in the README's list"));
                }
                for l in listed.difference(longs) {
                    wrong.push(format!("the README lists `edgekf {path} --{l}`, which the command lacks"));
                }
            }
        }
    }
    for path in readme.keys().filter(|p| !tree.contains_key(*p)) {
        wrong.push(format!("the README lists `edgekf {path}`, which is no command"));
    }
    let every: BTreeSet<&String> = tree.values().flatten().collect();
    for f in flags(&section).iter().filter(|f| !every.contains(f) && !["help", "version"].contains(&f.as_str())) {
        wrong.push(format!("the README's CLI section names `--{f}`, which no command has"));
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The checker itself: a flag missing from a README line, and a README flag the command lacks,
/// are both caught (the README text is made up here).
#[test]
fn the_checker_sees_a_missing_and_an_extra_flag() {
    let readme = readme_commands("edgekf baseline oscillator|uuv --config C [--quiet] [--bogus]\n");
    assert_eq!(readme.len(), 2);
    let uuv = &readme["baseline uuv"];
    let tree = tree_commands();
    let real = &tree["baseline uuv"];
    assert!(real.contains("data") && !uuv.contains("data"), "--data is missing from the made-up line");
    assert!(uuv.contains("bogus") && !real.contains("bogus"));
    assert_eq!(flags("a --x-y, not a-b--c, (`--json`)"), BTreeSet::from(["x-y".to_string(), "json".to_string()]));
}

/// No command's text is a flag struct's doc that `augment_args` left behind (`edgekf loop
/// --help` once described its subcommands as "the flags of every `edgekf loop <system>`" and
/// "`edgekf loop boom`'s own flag").
#[test]
fn no_command_describes_itself_as_its_flags() {
    fn walk(cmd: &clap::Command, path: &str, wrong: &mut Vec<String>) {
        for text in [cmd.get_about(), cmd.get_long_about()].into_iter().flatten() {
            let text = text.to_string();
            if text.contains("own flag") || text.starts_with("The flags of") {
                wrong.push(format!("`edgekf{path}`: {text}"));
            }
        }
        for sub in cmd.get_subcommands() {
            walk(sub, &format!("{path} {}", sub.get_name()), wrong);
        }
    }
    let mut wrong = Vec::new();
    walk(&cli::command(systems::REGISTRY), "", &mut wrong);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// A flag value outside the range its flag allows is a usage error, as a malformed one is:
/// clap's message naming the flag and exit code 2, before any file is read or written.
#[test]
fn flag_values_out_of_range_are_usage_errors() {
    let out_csv = std::env::temp_dir().join(format!("edgekf-usage-{}.csv", std::process::id()));
    let out = out_csv.to_str().unwrap();
    let rotor = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml");
    let cases: [&[&str]; 8] = [
        &["loop", "rotor", "--config", rotor, "--data", "absent.csv", "--report", "r", "--estimate-speed", "10"],
        &["rotor", "simulate", "--config", rotor, "--duration", "-1", "--out", out],
        &["rotor", "campbell", "--config", rotor, "--steps", "1"],
        &["rotor", "tune", "--config", rotor, "--budget", "4"],
        &["boom", "simulate", "--scenario", "luffing", "--duration", "0", "--out", out],
        &["boom", "simulate", "--scenario", "luffing", "--duration", "7200", "--out", out],
        &["uuv", "simulate", "--scenario", "healthy", "--duration", "0", "--out", out],
        &["crank", "simulate", "--clearance", "A=1e-4", "--duration", "-1", "--out", out],
    ];
    for args in cases {
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        let flag = args.iter().rev().find(|a| a.starts_with("--") && **a != "--out").unwrap();
        assert!(stderr.contains("invalid value") && stderr.contains(flag), "{args:?}: {stderr}");
        assert!(!out_csv.exists(), "{args:?} wrote its output");
    }
}
