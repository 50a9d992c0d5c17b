//! Writing outputs without ever losing a recording.
//!
//! A user's recording is the one file they cannot make again, so before any work starts each
//! command checks its outputs ([`check`]): the folder exists, and no output is one of its
//! inputs, compared as files (the same device and inode), not as strings, so another spelling,
//! a `..` or a symlink does not slip through. Every file is then written to a temporary file
//! in the same folder and renamed over its name only when complete ([`write_atomic`]): an error
//! or an interrupt leaves the old file or none, never a half-written one that looks finished.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Why an output path was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum OutputError {
    /// The output is one of the inputs.
    #[error("{}: this is the input {} (the same file); choose another output so the input is kept", output.display(), input.display())]
    IsAnInput {
        /// The output as given.
        output: PathBuf,
        /// The input it names.
        input: PathBuf,
    },
    /// The folder the output goes into does not exist.
    #[error("{}: the folder {} does not exist", output.display(), folder.display())]
    NoFolder {
        /// The output as given.
        output: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// A file output names a folder.
    #[error("{}: is a folder, expected a file name", output.display())]
    IsAFolder {
        /// The output as given.
        output: PathBuf,
    },
    /// A folder output names a file.
    #[error("{}: is a file, expected a folder", output.display())]
    IsAFile {
        /// The output as given.
        output: PathBuf,
    },
}

/// The folder `path` is written into (`.` for a bare file name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Refuses `output` if it is the same file as one of `inputs` (inputs not given or that do not
/// exist are skipped: nothing can be lost there).
fn not_an_input(output: &Path, inputs: &[Option<&Path>]) -> Result<(), OutputError> {
    for input in inputs.iter().flatten() {
        if same_file::is_same_file(output, input).unwrap_or(false) {
            return Err(OutputError::IsAnInput { output: output.to_path_buf(), input: input.to_path_buf() });
        }
    }
    Ok(())
}

/// Checks, before any work, that each of `outputs` (files, those given) can be written without
/// touching `inputs` (those given): its folder exists, it is not a folder, and it is not an
/// input.
///
/// ```
/// use edgekf_sim::io::output::{check, OutputError};
/// let dir = std::env::temp_dir().join("edgekf-doc-output-check");
/// std::fs::create_dir_all(&dir).unwrap();
/// let data = dir.join("data.csv");
/// std::fs::write(&data, "t,ax\n0,1\n").unwrap();
/// // The same file through `..`: refused.
/// let other = dir.join("..").join("edgekf-doc-output-check").join("data.csv");
/// assert!(matches!(check(&[Some(&other)], &[Some(&data)]), Err(OutputError::IsAnInput { .. })));
/// assert!(check(&[Some(&dir.join("est.csv"))], &[Some(&data), None]).is_ok());
/// assert!(matches!(check(&[Some(&dir.join("no/such/est.csv"))], &[]), Err(OutputError::NoFolder { .. })));
/// ```
pub fn check(outputs: &[Option<&Path>], inputs: &[Option<&Path>]) -> Result<(), OutputError> {
    for output in outputs.iter().flatten() {
        let folder = folder_of(output);
        if !folder.is_dir() {
            return Err(OutputError::NoFolder { output: output.to_path_buf(), folder });
        }
        if output.is_dir() {
            return Err(OutputError::IsAFolder { output: output.to_path_buf() });
        }
        not_an_input(output, inputs)?;
    }
    Ok(())
}

/// Checks, before any work, that the folder `dir` can take the files `names` without touching
/// `inputs`: `dir` is a folder or can be made in an existing folder, and none of its files is
/// an input.
pub fn check_folder(dir: &Path, names: &[&str], inputs: &[Option<&Path>]) -> Result<(), OutputError> {
    if dir.exists() {
        if !dir.is_dir() {
            return Err(OutputError::IsAFile { output: dir.to_path_buf() });
        }
    } else {
        let parent = folder_of(dir);
        if !parent.is_dir() {
            return Err(OutputError::NoFolder { output: dir.to_path_buf(), folder: parent });
        }
    }
    for name in names {
        not_an_input(&dir.join(name), inputs)?;
    }
    Ok(())
}

/// Writes `contents` to `path` through a temporary file in the same folder, renamed over
/// `path` only when all of it is written (a rename within a folder is atomic).
///
/// ```
/// let path = std::env::temp_dir().join("edgekf-doc-write-atomic.txt");
/// edgekf_sim::io::output::write_atomic(&path, "complete\n").unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "complete\n");
/// ```
pub fn write_atomic(path: &Path, contents: impl AsRef<[u8]>) -> std::io::Result<()> {
    let prefix = format!(".{}.", path.file_name().and_then(|n| n.to_str()).unwrap_or("edgekf"));
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".partial");
    // A temporary file is private (0600); the output is an ordinary file, readable as the
    // umask allows, like one `std::fs::write` makes.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(folder_of(path))?;
    tmp.write_all(contents.as_ref())?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("edgekf-output-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[cfg(unix)]
    #[test]
    fn an_output_is_as_readable_as_an_ordinary_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("mode");
        let (ours, plain) = (dir.join("report.json"), dir.join("plain.json"));
        write_atomic(&ours, b"{}").unwrap();
        std::fs::write(&plain, b"{}").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&ours), mode(&plain));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_to_the_input_is_the_input() {
        let dir = scratch("symlink");
        let data = dir.join("s.csv");
        std::fs::write(&data, "t\n0\n").unwrap();
        let link = dir.join("link.csv");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&data, &link).unwrap();
        assert!(matches!(check(&[Some(&link)], &[Some(&data)]), Err(OutputError::IsAnInput { .. })));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_folder_output_checks_its_files_and_its_parent() {
        let dir = scratch("folder");
        let data = dir.join("report.json");
        std::fs::write(&data, "{}").unwrap();
        assert!(matches!(check_folder(&dir, &["report.json"], &[Some(&data)]), Err(OutputError::IsAnInput { .. })));
        assert!(check_folder(&dir.join("new"), &["report.json"], &[Some(&data)]).is_ok());
        assert!(matches!(check_folder(&dir.join("a/b"), &[], &[]), Err(OutputError::NoFolder { .. })));
        assert!(matches!(check_folder(&data, &[], &[]), Err(OutputError::IsAFile { .. })));
        assert!(matches!(check(&[Some(&dir)], &[]), Err(OutputError::IsAFolder { .. })));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_write_leaves_no_temporary_file_behind() {
        let dir = scratch("atomic");
        let path = dir.join("out.csv");
        std::fs::write(&path, "old").unwrap();
        write_atomic(&path, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, [std::ffi::OsString::from("out.csv")]);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_write_into_a_missing_folder_fails_and_creates_nothing() {
        let dir = scratch("missing");
        assert!(write_atomic(&dir.join("no/out.csv"), "x").is_err());
        assert!(!dir.join("no").exists());
        std::fs::remove_dir_all(&dir).ok();
    }
}
