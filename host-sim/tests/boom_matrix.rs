//! A fixed slice of the boom's effect matrix (`edgekf_sim::systems::boom::matrix`), run as CI
//! runs it: every fifth case (clean runs, a stiffness, a section, a lag and the sideways mode)
//! comes out as the README's table, written by `cargo xtask loop-matrix boom`, says it does:
//! the same effects added, the same verdict. A change of the loop's behaviour on these cases
//! fails here until the table is written again.

use edgekf_sim::matrix::{table, Outcome};
use edgekf_sim::systems::boom::{matrix, BoomConfig};

/// The README's rows of the boom's table: `(case, added, verdict)`.
fn readme_rows() -> Vec<(String, String, String)> {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let start = readme.find("<!-- loop-matrix boom -->").expect("the README's boom matrix");
    let end = readme.find("<!-- /loop-matrix boom -->").expect("its end marker");
    readme[start..end]
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| case "))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split(" | ").map(str::trim).collect();
            (cells[0].to_string(), cells[1].to_string(), cells[2].to_string())
        })
        .collect()
}

#[test]
fn a_slice_of_the_boom_matrix_comes_out_as_the_readme_says() {
    let declared = BoomConfig::default();
    let cases = matrix::cases(&declared).unwrap();
    let rows = readme_rows();
    let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
    let listed: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(names, listed, "the README's table lists other cases: run `cargo xtask loop-matrix boom`");
    for (case, row) in cases.iter().zip(&rows).step_by(6) {
        let clean = matrix::clean_error(&declared, case.seed).unwrap();
        let outcome: Outcome = matrix::run_case(case, &declared, clean).unwrap();
        let ours = table("boom", std::slice::from_ref(&outcome));
        let line = ours.lines().last().unwrap().to_string();
        eprintln!("{line}  ({:.1} s)", outcome.seconds);
        let cells: Vec<&str> = line.trim_matches('|').split(" | ").map(str::trim).collect();
        assert_eq!((cells[1], cells[2]), (row.1.as_str(), row.2.as_str()), "{}", case.name);
    }
}
