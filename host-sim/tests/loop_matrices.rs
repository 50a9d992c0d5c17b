//! Fixed slices of the systems' effect matrices (`edgekf_sim::matrix`), run as CI runs them:
//! every sixth of the boom's cases (clean runs, a stiffness, a section, a lag, the sideways
//! mode), every third of the vehicle's (clean flights, the mass, a DVL offset), every other
//! of the oscillator's and every eighth of the rotor's (a clean run, a disk's mass, a bearing
//! below its limit, a gain) come out as the README's tables (written by `cargo xtask
//! loop-matrix`) say they do: the same effects added, the same verdict. A change of the
//! loop's behaviour on these cases fails here until the tables are written again.

use edgekf_sim::matrix::{readme_rows, row, Case, Outcome};
use edgekf_sim::systems::{boom, oscillator, rotor, uuv};

/// Checks every `step`-th of `system`'s `cases` against the README's rows.
fn check_slice<T>(system: &str, cases: &[Case<T>], step: usize, outcome: impl Fn(&Case<T>) -> Outcome) {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let rows = readme_rows(&readme, system).unwrap_or_else(|| panic!("the README's {system} matrix"));
    let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
    let listed: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(names, listed, "the README's table lists other cases: run `cargo xtask loop-matrix {system}`");
    for (case, listed) in cases.iter().zip(&rows).step_by(step) {
        let o = outcome(case);
        let ours = row(&o);
        eprintln!("{system}: {ours:?}  ({:.1} s)", o.seconds);
        assert_eq!(ours[1..], listed[1..], "{}", case.name);
    }
}

#[test]
fn a_slice_of_the_boom_matrix_comes_out_as_the_readme_says() {
    let declared = boom::BoomConfig::default();
    let cases = boom::matrix::cases(&declared).unwrap();
    check_slice("boom", &cases, 6, |c| {
        let clean = boom::matrix::clean_error(&declared, c.seed).unwrap();
        boom::matrix::run_case(c, &declared, clean).unwrap()
    });
}

#[test]
fn a_slice_of_the_vehicle_matrix_comes_out_as_the_readme_says() {
    let declared = uuv::UuvConfig::default();
    let cases = uuv::matrix::cases(&declared).unwrap();
    check_slice("uuv", &cases, 3, |c| {
        let clean = uuv::matrix::clean_error(&declared, c.seed).unwrap();
        uuv::matrix::run_case(c, &declared, clean).unwrap()
    });
}

#[test]
fn a_slice_of_the_oscillator_matrix_comes_out_as_the_readme_says() {
    let declared = oscillator::scenario::Scenario { duration_s: 4.0, ..Default::default() };
    let cases = oscillator::matrix::cases(&declared).unwrap();
    check_slice("oscillator", &cases, 2, |c| {
        let clean = oscillator::matrix::clean_error(&declared, c.seed).unwrap();
        oscillator::matrix::run_case(c, &declared, clean).unwrap()
    });
}

#[test]
fn a_slice_of_the_rotor_matrix_comes_out_as_the_readme_says() {
    let declared = rotor::matrix::declared().unwrap();
    let cases = rotor::matrix::cases(&declared).unwrap();
    check_slice("rotor", &cases, 8, |c| {
        let clean = rotor::matrix::clean_error(&declared, c.seed).unwrap();
        rotor::matrix::run_case(c, &declared, clean).unwrap()
    });
}
