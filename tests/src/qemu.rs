//! Runs the firmware image under QEMU on a data file and decodes what it says.

use anyhow::{bail, Context, Result};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Machine flags: an STM32F405 board model (Cortex-M4F, same memory map as the F411 target).
pub const QEMU_ARGS: [&str; 7] =
    ["-machine", "netduinoplus2", "-cpu", "cortex-m4", "-nographic", "-semihosting-config", "enable=on,target=native"];

/// What a firmware run left behind.
#[derive(Debug, Clone)]
pub struct FirmwareRun {
    /// QEMU's exit code (`None` if killed after the timeout).
    pub exit_code: Option<i32>,
    /// Decoded defmt messages, one per frame.
    pub lines: Vec<String>,
    /// Semihosting stderr (panic messages, plain-text errors).
    pub stderr: String,
}

impl FirmwareRun {
    /// A failure message with everything a reader needs, or `None` if the run ended with 0.
    pub fn failure(&self) -> Option<String> {
        if self.exit_code == Some(0) {
            return None;
        }
        let tail: Vec<&str> = self.lines.iter().rev().take(5).map(String::as_str).collect();
        Some(format!(
            "firmware run failed: exit code {:?}\n  stderr: {}\n  last defmt lines (newest first): {:?}",
            self.exit_code,
            self.stderr.trim(),
            tail
        ))
    }
}

/// The numerical soak image: `$EDGEKF_SOAK_ELF` (set by `cargo xtask test` and `soak`).
pub fn soak_elf() -> Result<PathBuf> {
    elf_from("EDGEKF_SOAK_ELF")
}

/// The ELF of a system's HIL image `bin` (its `HilImage::NAME`): the path in the environment
/// variable its row in the firmware's manifest names (`edgekf_firmware::systems::IMAGES`, which
/// `cargo xtask test` sets from the same row), so a new system's HIL test needs no function
/// here.
pub fn image_elf(bin: &str) -> Result<PathBuf> {
    let image = edgekf_firmware::systems::IMAGES
        .iter()
        .find(|i| i.bin == bin)
        .with_context(|| format!("{bin} is no system's image in edgekf_firmware::systems::IMAGES"))?;
    match image.role {
        edgekf_firmware::manifest::Role::Hil { env, .. } => elf_from(env),
        _ => bail!("{bin} is not a HIL image"),
    }
}

fn elf_from(var: &str) -> Result<PathBuf> {
    let path = std::env::var_os(var).with_context(|| {
        format!("{var} is not set: run the HIL tests through `cargo xtask test` (it builds the image)")
    })?;
    let path = PathBuf::from(path);
    if !path.is_file() {
        bail!("{var} points to {}, which is not a file", path.display());
    }
    Ok(path)
}

/// Runs `elf` under QEMU with `input` served as `hil_input.csv`; kills it after `timeout`.
pub fn run(elf: &Path, input: &[u8], timeout: Duration) -> Result<FirmwareRun> {
    run_with(elf, input, timeout, &[])
}

/// [`run`] with extra QEMU arguments (e.g. a TCG plugin).
pub fn run_with(elf: &Path, input: &[u8], timeout: Duration, extra: &[&str]) -> Result<FirmwareRun> {
    let dir = tempfile::tempdir().context("temporary directory for the QEMU run")?;
    std::fs::write(dir.path().join("hil_input.csv"), input).context("writing hil_input.csv")?;
    let mut child = Command::new("qemu-system-arm")
        .args(QEMU_ARGS)
        .args(extra)
        .arg("-kernel")
        .arg(elf)
        .current_dir(dir.path())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .context("starting qemu-system-arm (install Debian's qemu-system-arm, or run `cargo xtask test`)")?;
    let mut stdout = child.stdout.take().context("qemu stdout")?;
    let mut stderr = child.stderr.take().context("qemu stderr")?;
    let out = std::thread::spawn(move || {
        let mut v = Vec::new();
        stdout.read_to_end(&mut v).map(|_| v)
    });
    let err = std::thread::spawn(move || {
        let mut s = String::new();
        stderr.read_to_string(&mut s).map(|_| s)
    });
    let start = Instant::now();
    let exit_code = loop {
        if let Some(status) = child.try_wait()? {
            break status.code();
        }
        if start.elapsed() > timeout {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let bytes = out.join().map_err(|_| anyhow::anyhow!("stdout reader panicked"))??;
    let stderr = err.join().map_err(|_| anyhow::anyhow!("stderr reader panicked"))??;
    let lines = decode(elf, &bytes)?;
    Ok(FirmwareRun { exit_code, lines, stderr })
}

/// Decodes a raw defmt stream with the format table of `elf`.
pub fn decode(elf: &Path, bytes: &[u8]) -> Result<Vec<String>> {
    let image = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let table = defmt_decoder::Table::parse(&image)?.context("the ELF has no defmt table")?;
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = Vec::new();
    loop {
        match decoder.decode() {
            Ok(frame) => lines.push(frame.display_message().to_string()),
            Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
            Err(defmt_decoder::DecodeError::Malformed) => bail!("malformed defmt frame after {} lines", lines.len()),
        }
    }
    Ok(lines)
}
