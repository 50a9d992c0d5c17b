//! Parsers for flag values whose range is known without reading a file: a value outside it is
//! a usage error (clap's message naming the flag, exit code 2), as a malformed value is, and
//! never a data or configuration error (exit code 1).

/// A length of time in seconds: finite and above 0.
///
/// ```
/// use edgekf_sim::cli::values::positive_seconds;
/// assert_eq!(positive_seconds("2.5"), Ok(2.5));
/// assert!(positive_seconds("0").is_err() && positive_seconds("-1").is_err() && positive_seconds("inf").is_err());
/// ```
pub fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(s) if s.is_finite() && s > 0.0 => Ok(s),
        Ok(_) => Err(format!("{text} s is not a positive length of time")),
        Err(e) => Err(format!("{text:?}: {e}")),
    }
}

/// At most an hour (`boom simulate`, whose reference steps a finite-element boom): a
/// [`positive_seconds`] up to 3600.
///
/// ```
/// use edgekf_sim::cli::values::up_to_an_hour;
/// assert_eq!(up_to_an_hour("3600"), Ok(3600.0));
/// assert!(up_to_an_hour("3601").is_err() && up_to_an_hour("0").is_err());
/// ```
pub fn up_to_an_hour(text: &str) -> Result<f64, String> {
    let s = positive_seconds(text)?;
    if s > 3600.0 {
        return Err(format!("{text} s is longer than the hour a run may last"));
    }
    Ok(s)
}

/// A count of at least `N` (`--steps 2`, `--budget 16`).
///
/// ```
/// use edgekf_sim::cli::values::at_least;
/// assert_eq!(at_least::<2>("2"), Ok(2));
/// assert!(at_least::<2>("1").is_err() && at_least::<2>("x").is_err());
/// ```
pub fn at_least<const N: usize>(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n >= N => Ok(n),
        Ok(n) => Err(format!("{n} is less than the {N} it must be at least")),
        Err(e) => Err(format!("{text:?}: {e}")),
    }
}
