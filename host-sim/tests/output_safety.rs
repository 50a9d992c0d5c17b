//! No command loses a user's file: an output that is one of the command's inputs (by another
//! spelling, through `..` or a symlink) is refused before any work, with exit code 1 and the
//! input byte for byte as it was; an output into a missing folder is refused before the work
//! starts; a closed pipe ends the command quietly with exit 0; errors are one line.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const CONFIGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs");

fn edgekf() -> Command {
    Command::new(env!("CARGO_BIN_EXE_edgekf"))
}

/// A fresh folder with copies of the shipped configurations and a stand-in recording.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("edgekf-safety-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    for f in ["oscillator_demo.toml", "rotor_paper.toml", "crank_paper.toml"] {
        std::fs::copy(Path::new(CONFIGS).join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("rec.csv"), "t,ax,n12_x\n0,0.1,1e-6\n0.001,0.2,2e-6\n").unwrap();
    dir
}

/// Runs `args` in `dir`; asserts exit 1, a one-line error containing `says`, and that `kept`
/// is unchanged.
fn refused(dir: &Path, args: &[&str], kept: &str, says: &str) {
    let before = std::fs::read(dir.join(kept)).unwrap();
    let o = edgekf().current_dir(dir).args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    let last = err.lines().last().unwrap_or("");
    assert!(last.starts_with("error: ") && last.contains(says), "{args:?}: {err}");
    assert_eq!(std::fs::read(dir.join(kept)).unwrap(), before, "{args:?} changed {kept}");
}

const SAME: &str = "(the same file)";
const NO_FOLDER: &str = "does not exist";

#[test]
fn no_command_overwrites_its_input() {
    let dir = scratch("same");
    #[cfg(unix)]
    std::os::unix::fs::symlink(dir.join("rec.csv"), dir.join("link.csv")).unwrap();
    #[cfg(not(unix))]
    std::fs::copy(dir.join("rec.csv"), dir.join("link.csv")).unwrap();
    let rec = "sub/../rec.csv";
    let cases: &[(&[&str], &str)] = &[
        (
            &["oscillator", "simulate", "--config", "oscillator_demo.toml", "--out", "./oscillator_demo.toml"],
            "oscillator_demo.toml",
        ),
        (&["oscillator", "estimate", "--data", "rec.csv", "--out", rec], "rec.csv"),
        (
            &["oscillator", "export", "--config", "oscillator_demo.toml", "--out", "sub/../oscillator_demo.toml"],
            "oscillator_demo.toml",
        ),
        (
            &["rotor", "simulate", "--config", "rotor_paper.toml", "--duration", "0.1", "--out", "./rotor_paper.toml"],
            "rotor_paper.toml",
        ),
        (&["rotor", "estimate", "--config", "rotor_paper.toml", "--data", "rec.csv", "--out", rec], "rec.csv"),
        (&["rotor", "export", "--config", "rotor_paper.toml", "--out", "./rotor_paper.toml"], "rotor_paper.toml"),
        (
            &["crank", "simulate", "--config", "crank_paper.toml", "--duration", "0.1", "--out", "./crank_paper.toml"],
            "crank_paper.toml",
        ),
        (&["crank", "estimate", "--data", "rec.csv", "--method", "fast", "--out", rec], "rec.csv"),
        (&["crank", "export", "--model", "crank_paper.toml", "--out", "./crank_paper.toml"], "crank_paper.toml"),
        (&["crank", "train", "--out", "m.toml", "--load-features", "rec.csv", "--save-features", rec], "rec.csv"),
        (
            &["loop", "oscillator", "--config", "oscillator_demo.toml", "--data", "sub/report.json", "--report", "sub"],
            "sub/report.json",
        ),
    ];
    std::fs::write(dir.join("sub/report.json"), "{\"a recording\": true}").unwrap();
    for (args, kept) in cases {
        refused(&dir, args, kept, SAME);
    }
    // Through a symlink to the recording.
    if cfg!(unix) {
        refused(&dir, &["oscillator", "estimate", "--data", "rec.csv", "--out", "link.csv"], "rec.csv", SAME);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_output_into_a_missing_folder_is_refused_before_the_work() {
    let dir = scratch("folder");
    let cases: &[&[&str]] = &[
        &["oscillator", "simulate", "--out", "no/data.csv"],
        &["oscillator", "estimate", "--data", "rec.csv", "--out", "no/est.csv"],
        &["rotor", "simulate", "--config", "rotor_paper.toml", "--duration", "30", "--out", "no/data.csv"],
        &["rotor", "estimate", "--config", "rotor_paper.toml", "--data", "rec.csv", "--out", "no/est.csv"],
        &["crank", "simulate", "--duration", "30", "--out", "no/data.csv"],
        &["crank", "train", "--out", "no/model.toml"],
        &["loop", "oscillator", "--config", "oscillator_demo.toml", "--data", "rec.csv", "--report", "no/such/dir"],
        &["demo", "--out", "no/such/dir"],
    ];
    for args in cases {
        refused(&dir, args, "rec.csv", NO_FOLDER);
        assert!(!dir.join("no").exists(), "{args:?} made a folder");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_closed_pipe_ends_quietly() {
    let mut child = edgekf()
        .args(["rotor", "campbell", "--config", &format!("{CONFIGS}/rotor_paper.toml"), "--steps", "200"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = child.stdout.take().unwrap();
    let mut first = [0u8; 16];
    std::io::Read::read_exact(&mut out, &mut first).unwrap();
    drop(out);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_toml_error_is_one_line_with_its_line_and_column() {
    let dir = scratch("toml");
    std::fs::write(dir.join("bad.toml"), "# scenario\nduration_s = \"long\"\n").unwrap();
    let o = edgekf()
        .current_dir(&dir)
        .args(["oscillator", "simulate", "--config", "bad.toml", "--out", "x.csv"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("bad.toml") && err.contains("line 2, column 14"), "{err}");
    assert!(!dir.join("x.csv").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// A missing input is named once with what the system said (the reason is not repeated by the
/// error's chain), for a recording and for a configuration.
#[test]
fn a_missing_input_is_named_once_with_its_reason() {
    let dir = scratch("missing");
    let cases: [&[&str]; 2] = [
        &["loop", "oscillator", "--config", "oscillator_demo.toml", "--data", "absent.csv", "--report", "out"],
        &["uuv", "simulate", "--scenario", "healthy", "--config", "absent.toml", "--out", "sim.csv"],
    ];
    for args in cases {
        let o = edgekf().current_dir(&dir).args(args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("absent.") && err.contains("cannot read"), "{args:?}: {err}");
        assert_eq!(err.matches("No such file or directory").count(), 1, "{args:?}: {err}");
    }
}
