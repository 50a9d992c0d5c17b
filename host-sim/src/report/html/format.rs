//! How the page writes numbers: about four significant digits, fixed decimals, p-values,
//! orders of the running speed, an effect's value in its unit (µm, ms, a factor in %), and
//! `–` for whatever is not finite.

/// A number with about four significant digits; `–` when not finite.
pub(super) fn num(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.3e}");
    }
    let decimals = if a == 0.0 { 0 } else { (3 - a.log10().floor() as i32).clamp(0, 6) as usize };
    format!("{v:.decimals$}")
}

/// `v` with `decimals` decimals; `–` when not finite.
pub(super) fn fixed(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "–".into()
    }
}

/// A p-value: three decimals, or scientific below 0.001.
pub(super) fn p_value(p: f64) -> String {
    if p == 0.0 {
        "0".into()
    } else if p.is_finite() && p < 1e-3 {
        format!("{p:.1e}")
    } else {
        fixed(p, 3)
    }
}

/// An order of the running speed: `2x`, `3.572x`.
pub(super) fn order(o: f64) -> String {
    if (o - o.round()).abs() < 1e-9 {
        format!("{o:.0}x")
    } else {
        format!("{o:.3}x")
    }
}

/// An effect's value in its unit: a factor as `1.050 (+5.0 %)`, metres in µm, seconds in ms
/// or µs.
pub(super) fn value_with_unit(v: f64, unit: &str) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    match unit {
        "1" => format!("{v:.3} ({:+.1} %)", (v - 1.0) * 100.0),
        "m" => format!("{} µm", num(v * 1e6)),
        "s" if v.abs() < 1e-3 => format!("{} µs", num(v * 1e6)),
        "s" => format!("{} ms", num(v * 1e3)),
        _ => format!("{} {unit}", num(v)),
    }
}

/// `running speed` → `Running speed`.
pub(super) fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or_else(String::new, |f| f.to_uppercase().chain(c).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_in_their_units() {
        assert_eq!(value_with_unit(1.05, "1"), "1.050 (+5.0 %)");
        assert_eq!(value_with_unit(0.98, "1"), "0.980 (-2.0 %)");
        assert_eq!(value_with_unit(20e-6, "m"), "20.00 µm");
        assert_eq!(value_with_unit(2.5e-4, "s"), "250.0 µs");
        assert_eq!(value_with_unit(f64::NAN, "N"), "–");
        assert_eq!(order(2.0), "2x");
        assert_eq!(order(3.5721), "3.572x");
        assert_eq!(p_value(0.0), "0");
        assert_eq!(p_value(2.5e-7), "2.5e-7");
        assert_eq!(p_value(0.25), "0.250");
    }

    #[test]
    fn numbers_have_four_significant_digits() {
        assert_eq!(num(1234.5678), "1235");
        assert_eq!(num(0.012346), "0.01235");
        assert_eq!(num(2.5e-6), "2.500e-6");
        assert_eq!(num(0.0), "0");
        assert_eq!(num(f64::INFINITY), "–");
        assert_eq!(fixed(f64::NAN, 2), "–");
        assert_eq!(capitalised("running speed"), "Running speed");
    }
}
