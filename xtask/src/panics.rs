//! The no-panic proof's locator: where an image's surviving panic paths are.
//!
//! The proof build (feature `no-panic-proof`) fails to link when a panic path survives, but the
//! linker can only name the panic handler. The ordinary build keeps the paths, so this module
//! disassembles it with line information (`arm-none-eabi-objdump -d -l --inlines`) and lists
//! every branch into `core`'s panic functions with the innermost source location in the
//! project's code that it was inlined into (else a dependency's, else the standard library's).

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;

/// One panic call site.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Site {
    /// `path:line` outside the standard library (or the innermost location, if all is in it).
    pub location: String,
    /// The panic function branched to (`core::panicking::panic_bounds_check`, …).
    pub panic: String,
    /// The symbol the branch is in.
    pub function: String,
}

/// Whether a branch target is one of `core`'s panic entry points.
fn is_panic_target(sym: &str) -> bool {
    sym.starts_with("core::") && (sym.contains("panic") || sym.contains("_fail"))
}

/// `path:line` of an objdump location line (`/p/x.rs:12`, `/p/x.rs:12 (discriminator 3)`,
/// `inlined by /p/x.rs:12 (mangled)`).
fn location(line: &str) -> &str {
    let l = line.strip_prefix("inlined by ").unwrap_or(line);
    l.split_whitespace().next().unwrap_or(l)
}

/// The panic call sites in `objdump -d -l --inlines -C` output, deduplicated and sorted.
pub fn parse(disassembly: &str) -> Vec<Site> {
    let mut function = String::new();
    let mut chain: Vec<&str> = Vec::new();
    let mut sites = Vec::new();
    for line in disassembly.lines() {
        if line.starts_with('/') {
            chain.clear();
            chain.push(location(line));
        } else if line.starts_with("inlined by ") {
            chain.push(location(line));
        } else if let Some((addr, sym)) = line.strip_suffix(">:").and_then(|l| l.split_once(" <")) {
            if addr.chars().all(|c| c.is_ascii_hexdigit()) {
                function = sym.to_string();
            }
        } else if let Some((_, target)) = line.split_once('\t').map(|(a, i)| (a, i.trim())) {
            // An instruction: `b`, `bl`, `b.w`, `beq.w`, … to `ADDR <symbol>`.
            let Some(sym) = target.strip_suffix('>').and_then(|t| t.split_once(" <")).map(|(_, s)| s) else {
                continue;
            };
            if !target.starts_with('b') || !is_panic_target(sym) || is_panic_target(&function) {
                continue;
            }
            // The project's own line if the path went through it, else a dependency's, else core's.
            let ours = |l: &&&str| !l.contains("/rustlib/") && !l.contains("/.cargo/registry/");
            let theirs = |l: &&&str| !l.contains("/rustlib/");
            let at = chain.iter().find(ours).or(chain.iter().find(theirs)).or(chain.first()).copied().unwrap_or("?");
            sites.push(Site { location: at.to_string(), panic: sym.to_string(), function: function.clone() });
        }
    }
    sites.sort();
    sites.dedup();
    sites
}

/// The panic call sites of an ELF built without the proof.
pub fn sites(elf: &Path) -> Result<Vec<Site>> {
    let out = Command::new("arm-none-eabi-objdump")
        .args(["-d", "-l", "--inlines", "-C", "--no-show-raw-insn"])
        .arg(elf)
        .output()
        .context("running arm-none-eabi-objdump")?;
    if !out.status.success() {
        bail!("arm-none-eabi-objdump failed on {}", elf.display());
    }
    Ok(parse(&String::from_utf8_lossy(&out.stdout)))
}

/// Prints `sites`, one line each.
pub fn print(sites: &[Site]) {
    for s in sites {
        println!("  {}  {}  (in {})", s.location, s.panic, s.function);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_branch_is_placed_at_its_innermost_workspace_line() {
        let dis = "\
08002400 <edgekf_firmware::line_feed::next_line>:
/usr/lib/rustlib/src/rust/library/core/src/slice/index.rs:443
inlined by /usr/lib/rustlib/src/rust/library/core/src/array/mod.rs:390 (_RNv)
inlined by /work/x/firmware/src/line_feed.rs:101 (_RNv)
inlined by /work/x/firmware/src/node.rs:7 (_RNv)
 80024c4:\tbl\t8002e00 <core::slice::index::slice_index_fail>
 80024c8:\tbl\t8002e04 <edgekf_firmware::other>
/work/x/shared/src/a.rs:5 (discriminator 2)
 80024cc:\tbeq.w\t8003174 <core::panicking::panic_bounds_check>
08003174 <core::panicking::panic_bounds_check>:
/usr/lib/rustlib/src/rust/library/core/src/panicking.rs:270
 8003178:\tbl\t80029cc <core::panicking::panic_fmt>
";
        let s = parse(dis);
        assert_eq!(s.len(), 2, "{s:?}");
        assert_eq!(s[0].location, "/work/x/firmware/src/line_feed.rs:101");
        assert_eq!(s[0].panic, "core::slice::index::slice_index_fail");
        assert_eq!(s[0].function, "edgekf_firmware::line_feed::next_line");
        assert_eq!(s[1].location, "/work/x/shared/src/a.rs:5");
    }
}
