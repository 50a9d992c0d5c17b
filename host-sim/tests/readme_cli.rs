//! The README's command-line section and `edgekf --help` checked against each other: every
//! command and every long flag of the clap tree is in the README's list, and every `--flag`
//! the section names exists in the tree. The tree is the one `edgekf` runs
//! (`cli::command(systems::REGISTRY)`), so a flag added to the code and not to the README, or
//! a README flag the code dropped, fails here.

use edgekf_sim::{cli, systems};
use std::collections::{BTreeMap, BTreeSet};

/// The section's text, from its heading to the next `## ` heading.
fn cli_section() -> String {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let start = readme.find("## The `edgekf` command line").expect("the README has its CLI section");
    let rest = &readme[start..];
    let end = rest[3..].find("\n## ").map_or(rest.len(), |i| i + 3);
    rest[..end].to_string()
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
