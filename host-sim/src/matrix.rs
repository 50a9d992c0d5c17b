//! Effect matrices: a system's loop run on recordings of its own reference simulator, each
//! with one effect its configuration does not declare (or none), its `truth_` columns taken
//! out before the loop runs (a real recording has none) and used only to score. One rule
//! scores every case of every system ([`score`]); a system supplies its cases and runs them.
//!
//! The rule: the right kind at the right place (or a tie the report lists that includes it),
//! its change from the declared value within a fifth of the true change, nothing else added,
//! and the error after the loop at most 1.5 times the clean run's; where the effect is below
//! what the data can tell, `not_identifiable` naming it; on a clean run, nothing.

use crate::io::data::DataFile;
use crate::residual_loop::limits::detection_limit;
use crate::residual_loop::Described;
use crate::residual_loop::{EffectKind, LoopOptions, LoopReport, LoopSystem};

/// `data` without its `truth_` columns: what a real recording has, and what the loop is given.
///
/// ```
/// use edgekf_sim::io::data::DataFile;
/// use edgekf_sim::matrix::without_truth;
/// let d = DataFile { names: vec!["x".into(), "truth_x".into()], t: vec![0.0], columns: vec![vec![1.0], vec![2.0]], sha256: None };
/// assert_eq!(without_truth(&d).names, ["x"]);
/// ```
pub fn without_truth(data: &DataFile) -> DataFile {
    let keep: Vec<usize> = (0..data.names.len()).filter(|&i| !data.names[i].starts_with("truth_")).collect();
    DataFile {
        names: keep.iter().map(|&i| data.names[i].clone()).collect(),
        t: data.t.clone(),
        columns: keep.iter().map(|&i| data.columns[i].clone()).collect(),
        sha256: None,
    }
}

/// What a case expects of the loop.
#[derive(Debug, Clone, PartialEq)]
pub enum Expect {
    /// A clean run: nothing is added.
    Nothing,
    /// This effect is added.
    Effect(Expected),
    /// Below what the data can tell: nothing is added and `not_identifiable` names it.
    CannotTell(Expected),
}

/// An effect a case carries, as the report would name it.
#[derive(Debug, Clone, PartialEq)]
pub struct Expected {
    /// Its kind.
    pub kind: EffectKind,
    /// Its place (`section 3`, `incl_angle`).
    pub location: String,
    /// The parameter, for a `parameter`.
    pub parameter: Option<String>,
    /// The value the report should give.
    pub value: f64,
    /// The value the declared model has (1 for a factor): the change is measured from it.
    pub declared: f64,
    /// Whether the value is a factor (its change is then a ratio, compared in `ln`).
    pub factor: bool,
}

impl Expected {
    /// The change from the declared value: `ln` of the ratio for a factor, else the difference.
    fn change(&self, value: f64) -> f64 {
        if self.factor {
            (value / self.declared).ln()
        } else {
            value - self.declared
        }
    }

    /// Whether a report's entry names this effect at `location`.
    fn names(&self, kind: EffectKind, location: &str, parameter: Option<&str>) -> bool {
        kind == self.kind && location == self.location && parameter == self.parameter.as_deref()
    }
}

/// How a case came out.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// The effect named rightly (or nothing, on a clean run).
    Right,
    /// Said, rightly, that the data cannot tell it.
    CannotTell,
    /// Anything else, with why.
    Wrong(String),
}

/// Scores `report` against `expect`; `errors` are the error after the loop and the clean
/// run's (the system's own error measure, against the truth columns), where it has one.
pub fn score(expect: &Expect, report: &LoopReport, errors: Option<(f64, f64)>) -> Verdict {
    let added = |e: &crate::residual_loop::AddedEffect| format!("{} at {} = {:.4}", e.kind, e.location, e.value);
    let unseen =
        |x: &Expected| report.not_identifiable.iter().any(|n| x.names(n.kind, &n.location, n.parameter.as_deref()));
    match expect {
        Expect::Nothing => match report.effects_added.first() {
            None => Verdict::Right,
            Some(e) => Verdict::Wrong(format!("added {} to a clean run", added(e))),
        },
        Expect::CannotTell(x) => match report.effects_added.first() {
            Some(e) if !x.names(e.kind, &e.location, e.detail.parameter.as_deref()) => {
                Verdict::Wrong(format!("added {} for an effect below the limit", added(e)))
            }
            Some(_) => Verdict::Right,
            None if unseen(x) => Verdict::CannotTell,
            None => Verdict::Wrong("nothing added, and not_identifiable does not name it".into()),
        },
        Expect::Effect(x) => {
            let tie = |e: &crate::residual_loop::AddedEffect| {
                report.not_identifiable.iter().any(|n| {
                    n.statistic == "delta_log_likelihood_gap" && x.names(n.kind, &n.location, n.parameter.as_deref())
                }) && e.kind == x.kind
            };
            let hit =
                report.effects_added.iter().position(|e| x.names(e.kind, &e.location, e.detail.parameter.as_deref()));
            let hit = hit.or_else(|| report.effects_added.iter().position(tie));
            let Some(i) = hit else {
                return match report.effects_added.first() {
                    Some(e) => Verdict::Wrong(format!("added {} instead", added(e))),
                    None if unseen(x) => Verdict::CannotTell,
                    None => Verdict::Wrong(format!("nothing added ({})", report.stopped)),
                };
            };
            if let Some(e) = report.effects_added.iter().enumerate().find(|(j, _)| *j != i).map(|(_, e)| e) {
                return Verdict::Wrong(format!("also added {}", added(e)));
            }
            let e = &report.effects_added[i];
            let (fitted, truth) = (x.change(e.value), x.change(x.value));
            if e.location == x.location && (fitted - truth).abs() > 0.2 * truth.abs() {
                return Verdict::Wrong(format!("{} off: {:.4} for {:.4}", added(e), e.value, x.value));
            }
            match errors {
                Some((after, clean)) if after > 1.5 * clean => Verdict::Wrong(format!(
                    "{}, but the error after is {after:.3}, the clean run's {clean:.3}",
                    added(e)
                )),
                _ => Verdict::Right,
            }
        }
    }
}

/// One case's outcome, for the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The case, in words (`section 3 EI ×0.93 (10× the limit), seed 2`).
    pub case: String,
    /// How it came out.
    pub verdict: Verdict,
    /// What the loop added, in words.
    pub added: String,
    /// Seconds the loop took.
    pub seconds: f64,
}

/// The README's table for `system`: the counts, the loop's time per run, and every case
/// with what was added and, for a wrong one, why.
pub fn table(system: &str, outcomes: &[Outcome]) -> String {
    let count = |f: fn(&Verdict) -> bool| outcomes.iter().filter(|o| f(&o.verdict)).count();
    let right = count(|v| *v == Verdict::Right);
    let cannot = count(|v| *v == Verdict::CannotTell);
    let wrong = count(|v| matches!(v, Verdict::Wrong(_)));
    let n = outcomes.len().max(1) as f64;
    let mean = outcomes.iter().map(|o| o.seconds).sum::<f64>() / n;
    let mut out = format!(
        "{system}: {} cases, **{right} right, {cannot} rightly 'cannot tell', {wrong} wrong** ({:.0} % right or rightly cannot tell); the loop takes {mean:.1} s a run on average.\n\n",
        outcomes.len(),
        100.0 * (right + cannot) as f64 / n
    );
    out += "| case | the loop added | verdict |\n|---|---|---|\n";
    for o in outcomes {
        let verdict = match &o.verdict {
            Verdict::Right => "right".to_string(),
            Verdict::CannotTell => "cannot tell (right)".to_string(),
            Verdict::Wrong(why) => format!("**wrong**: {why}"),
        };
        out += &format!("| {} | {} | {verdict} |\n", o.case, if o.added.is_empty() { "nothing" } else { &o.added });
    }
    out
}

/// The rows `(case, added, verdict)` of `system`'s table in `readme`, between its
/// `<!-- loop-matrix SYSTEM -->` markers (`None` without them): what a CI slice checks its
/// cases against.
///
/// ```
/// use edgekf_sim::matrix::readme_rows;
/// let md = "<!-- loop-matrix uuv -->\n| case | the loop added | verdict |\n|---|---|---|\n| clean, seed 1 | nothing | right |\n<!-- /loop-matrix uuv -->";
/// let rows = readme_rows(md, "uuv").unwrap();
/// assert_eq!(rows, [["clean, seed 1".to_string(), "nothing".into(), "right".into()]]);
/// assert!(readme_rows(md, "boom").is_none());
/// ```
pub fn readme_rows(readme: &str, system: &str) -> Option<Vec<[String; 3]>> {
    let start = readme.find(&format!("<!-- loop-matrix {system} -->"))?;
    let end = readme.find(&format!("<!-- /loop-matrix {system} -->"))?;
    Some(
        readme
            .get(start..end)?
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| case "))
            .map(cells)
            .collect(),
    )
}

/// The three cells of a table row `| a | b | c |`.
fn cells(line: &str) -> [String; 3] {
    let mut c = line.trim().trim_matches('|').split(" | ").map(|s| s.trim().to_string());
    [(); 3].map(|_| c.next().unwrap_or_default())
}

/// `outcome` as its table row's cells.
///
/// ```
/// use edgekf_sim::matrix::{row, Outcome, Verdict};
/// let o = Outcome { case: "clean, seed 1".into(), verdict: Verdict::Right, added: String::new(), seconds: 1.0 };
/// assert_eq!(row(&o), ["clean, seed 1".to_string(), "nothing".into(), "right".into()]);
/// ```
pub fn row(outcome: &Outcome) -> [String; 3] {
    cells(table("", std::slice::from_ref(outcome)).lines().last().unwrap_or_default())
}

/// One size of a declared setting, for a case: the effect with its scalar, what the report
/// should then say, and the case's words.
#[derive(Debug, Clone)]
pub struct SettingCase<E> {
    /// The setting.
    pub effect: E,
    /// Its scalar in the simulated machine.
    pub theta: f64,
    /// Its value as the report gives it (`exp θ` for a factor, else `θ`).
    pub value: f64,
    /// Whether it is a factor.
    pub factor: bool,
    /// What the loop should say.
    pub expect: Expect,
    /// `parameter at place` (the parameter's name, or the kind's).
    pub what: String,
    /// `3× the limit`, or `below the limit`.
    pub size: String,
}

/// Each declared setting with a scalar of `sys` at `multiples` of its detection limit on
/// `sys`'s data (those within its range), or, where the data cannot see it at all, a fifth of
/// the way to the end of its range, expected as "cannot tell" (see
/// [`detection_limit`](crate::residual_loop::limits::detection_limit)).
pub fn setting_cases<S: LoopSystem>(
    sys: &S,
    options: &LoopOptions,
    multiples: &[f64],
) -> anyhow::Result<Vec<SettingCase<S::Effect>>> {
    let mut out = Vec::new();
    for effect in sys.declared() {
        let Some((range, _)) = sys.fitting(&effect).scalar else { continue };
        let label = sys.label(&effect);
        let what = format!(
            "{} at {}",
            label.detail.parameter.clone().unwrap_or_else(|| label.kind.to_string()),
            label.location
        );
        let limit = detection_limit(sys, effect, options)?;
        let sizes: Vec<(f64, String)> = match limit {
            Some(d) => multiples
                .iter()
                .filter(|k| (range.low..=range.high).contains(&(range.neutral + *k * d)))
                .map(|k| (range.neutral + k * d, format!("{k}× the limit")))
                .collect(),
            None => vec![(range.neutral + 0.2 * (range.high - range.neutral), "below the limit".into())],
        };
        for (theta, size) in sizes {
            let value = if range.log { theta.exp() } else { theta };
            let expected = Expected {
                kind: label.kind,
                location: label.location.clone(),
                parameter: label.detail.parameter.clone(),
                value,
                declared: if range.log { 1.0 } else { range.neutral },
                factor: range.log,
            };
            let expect = if limit.is_some() { Expect::Effect(expected) } else { Expect::CannotTell(expected) };
            out.push(SettingCase { effect, theta, value, factor: range.log, expect, what: what.clone(), size });
        }
    }
    Ok(out)
}

/// One case of a system's matrix: the simulated machine (`T`, its configuration), the seed of
/// its run and what the loop should say.
#[derive(Debug, Clone)]
pub struct Case<T> {
    /// In words, for the table.
    pub name: String,
    /// The simulated machine.
    pub truth: T,
    /// The seed of its run.
    pub seed: u64,
    /// What the loop should say.
    pub expect: Expect,
}

/// The clean runs of `declared` at `seeds`: nothing should be added.
///
/// ```
/// use edgekf_sim::matrix::{clean_cases, Expect};
/// let cases = clean_cases(&"model", &[1, 2]);
/// assert_eq!((cases[1].name.as_str(), cases[1].seed), ("clean, seed 2", 2));
/// assert_eq!(cases[0].expect, Expect::Nothing);
/// ```
pub fn clean_cases<T: Clone>(declared: &T, seeds: &[u64]) -> Vec<Case<T>> {
    seeds
        .iter()
        .map(|&seed| Case {
            name: format!("clean, seed {seed}"),
            truth: declared.clone(),
            seed,
            expect: Expect::Nothing,
        })
        .collect()
}

/// How `case` came out in `report`, which took `seconds`, scored with `errors` (see [`score`]).
pub fn outcome<T>(case: &Case<T>, report: &LoopReport, errors: Option<(f64, f64)>, seconds: f64) -> Outcome {
    let added = report
        .effects_added
        .iter()
        .map(|e| format!("{} at {} = {:.4}", e.kind, e.location, e.value))
        .collect::<Vec<_>>()
        .join("; ");
    Outcome { case: case.name.clone(), verdict: score(&case.expect, report, errors), added, seconds }
}

/// RMS of `estimate` against `full`'s column `truth` from `from_s` on (the filter's start left
/// out), over the samples where both are finite.
///
/// ```
/// use edgekf_sim::io::data::DataFile;
/// use edgekf_sim::matrix::rms_error;
/// let d = DataFile { names: vec!["truth_x".into()], t: vec![0.0, 1.0, 2.0], columns: vec![vec![0.0; 3]], sha256: None };
/// assert_eq!(rms_error(&d, "truth_x", &[9.0, 3.0, 4.0], 1.0).unwrap(), 12.5f64.sqrt());
/// ```
pub fn rms_error(full: &DataFile, truth: &str, estimate: &[f64], from_s: f64) -> anyhow::Result<f64> {
    let column = full.column(truth).ok_or_else(|| anyhow::anyhow!("the run has no `{truth}`"))?;
    let squares: Vec<f64> = full
        .t
        .iter()
        .zip(column.iter().zip(estimate))
        .filter(|(t, (a, b))| **t >= from_s && a.is_finite() && b.is_finite())
        .map(|(_, (a, b))| (a - b).powi(2))
        .collect();
    if squares.is_empty() {
        anyhow::bail!("no estimate of `{truth}` after {from_s} s");
    }
    Ok((squares.iter().sum::<f64>() / squares.len() as f64).sqrt())
}
