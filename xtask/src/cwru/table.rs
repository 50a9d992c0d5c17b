//! What each run named, judged against the record's label, and the table with its counts.
//!
//! The rule: a record is **right** when the first bearing defect the loop adds is the label's
//! family (BPFI, BSF or BPFO) at the drive-end bearing (`bearing 1`), **wrong** when the first
//! is another family or the fan-end bearing, **missed** when it names no bearing defect.
//! Smith & Randall's grade stands beside it: where the benchmark cannot diagnose a record,
//! nothing named (or the label's family) is what issue #35 asks for.

use super::catalogue::{Fault, Record};
use serde_json::Value;
use std::fmt::Write as _;

/// The drive-end bearing's location as the rotor's loop writes it (its node in
/// `rotor_cwru.toml`).
pub const DRIVE_END: &str = "bearing 1";

/// What one run's `report.json` says about the bearings.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Outcome {
    /// Each `bearing_defect` added, in order: (family, location).
    pub defects: Vec<(String, String)>,
    /// The other effects added (their kinds).
    pub others: Vec<String>,
    /// Bearing defects the data could not tell apart (`not_identifiable`), as location and
    /// rivals.
    pub undecided: Vec<String>,
    /// The running speed the loop used (`running_speed.hz`), rpm.
    pub rpm: Option<f64>,
}

impl Outcome {
    /// Reads the parts of a rotor loop's `report.json` the table needs; an error names what is
    /// missing (a report of another schema should not be scored as "nothing named").
    pub fn from_report(json: &Value) -> Result<Self, String> {
        let added = json.get("effects_added").and_then(Value::as_array).ok_or("report.json has no effects_added")?;
        let mut out = Outcome::default();
        for e in added {
            let kind = e.get("kind").and_then(Value::as_str).ok_or("an added effect has no kind")?;
            let location = e.get("location").and_then(Value::as_str).unwrap_or("?").to_string();
            if kind == "bearing_defect" {
                let line = e.get("line").and_then(Value::as_str).unwrap_or("?").to_string();
                out.defects.push((line, location));
            } else {
                out.others.push(format!("{kind} at {location}"));
            }
        }
        out.rpm = json.pointer("/running_speed/hz").and_then(Value::as_f64).map(|hz| hz * 60.0);
        for n in json.get("not_identifiable").and_then(Value::as_array).into_iter().flatten() {
            if n.get("kind").and_then(Value::as_str) == Some("bearing_defect") {
                let at = n.get("location").and_then(Value::as_str).unwrap_or("?");
                let rivals: Vec<&str> =
                    n.get("rivals").and_then(Value::as_array).into_iter().flatten().filter_map(Value::as_str).collect();
                let with = if rivals.is_empty() { String::new() } else { format!(" (rivals {})", rivals.join(", ")) };
                out.undecided.push(format!("{at}{with}"));
            }
        }
        Ok(out)
    }

    /// What the loop named, for the table.
    pub fn named(&self) -> String {
        let mut parts: Vec<String> = self.defects.iter().map(|(line, at)| format!("{line} at {at}")).collect();
        if parts.is_empty() {
            parts.push("nothing".into());
        }
        let mut text = parts.join(", then ");
        if !self.undecided.is_empty() {
            let _ = write!(text, "; not identifiable: {}", self.undecided.join(", "));
        }
        if !self.others.is_empty() {
            let _ = write!(text, "; also {}", collapse(&self.others).join(", "));
        }
        text
    }
}

/// `items` with repeats said once, with their count (`extra_mode at all channels ×4`), in the
/// order of first appearance.
fn collapse(items: &[String]) -> Vec<String> {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for item in items {
        match seen.iter_mut().find(|(s, _)| *s == item.as_str()) {
            Some((_, n)) => *n += 1,
            None => seen.push((item.as_str(), 1)),
        }
    }
    seen.into_iter().map(|(s, n)| if n == 1 { s.to_string() } else { format!("{s} ×{n}") }).collect()
}

/// How a run went.
#[derive(Debug, Clone, PartialEq)]
pub enum RunResult {
    /// It ran and wrote its report.
    Done(Outcome),
    /// It did not: why.
    Failed(String),
}

/// The judgement of one row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The label's family at the drive end, first.
    Right,
    /// Another family or bearing first.
    Wrong,
    /// No bearing defect named.
    Missed,
    /// The run failed.
    Failed,
}

impl Verdict {
    /// In words: `right`, `wrong`, `missed`, `failed`.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Right => "right",
            Verdict::Wrong => "wrong",
            Verdict::Missed => "missed",
            Verdict::Failed => "failed",
        }
    }

    /// For the table: a wrong answer stands out.
    fn text(self) -> &'static str {
        match self {
            Verdict::Wrong => "**wrong**",
            v => v.word(),
        }
    }
}

/// One record's run.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The record.
    pub record: Record,
    /// The load of the healthy record its baseline was learnt from, hp.
    pub baseline_hp: u8,
    /// What happened.
    pub result: RunResult,
    /// Wall time of the run, s.
    pub seconds: f64,
}

impl Row {
    /// Right, wrong, missed or failed, by the module's rule.
    pub fn verdict(&self) -> Verdict {
        let RunResult::Done(o) = &self.result else { return Verdict::Failed };
        match o.defects.first() {
            None => Verdict::Missed,
            Some((line, at)) if line == self.record.fault.family() && at == DRIVE_END => Verdict::Right,
            Some(_) => Verdict::Wrong,
        }
    }

    /// Whether the row is what the issue asks on a record the benchmark does not diagnose:
    /// nothing named, or the label's family.
    fn acceptable_when_undiagnosable(&self) -> bool {
        matches!(self.verdict(), Verdict::Right | Verdict::Missed)
    }

    /// Whether it ran against a baseline of another load.
    pub fn other_load_baseline(&self) -> bool {
        self.baseline_hp != self.record.load_hp
    }
}

/// `k/n`, or `–` when there is nothing to count.
fn ratio(k: usize, n: usize) -> String {
    if n == 0 {
        "–".into()
    } else {
        format!("{k}/{n}")
    }
}

/// The record table (sorted by load, then fault, then record number).
pub fn record_table(rows: &[Row]) -> String {
    let mut rows: Vec<&Row> = rows.iter().collect();
    rows.sort_by_key(|r| (r.record.load_hp, r.record.fault, r.record.number));
    let mut out = String::from(
        "| record | expected | the loop names | verdict | Smith & Randall | speed, rpm (nominal) | baseline | time, s |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let (named, rpm) = match &r.result {
            RunResult::Done(o) => (o.named(), o.rpm.map_or("?".into(), |v| format!("{v:.1}"))),
            RunResult::Failed(why) => (format!("failed: {why}"), "–".into()),
        };
        let baseline = if r.other_load_baseline() {
            format!("{} hp ⚑ (not the record's load)", r.baseline_hp)
        } else {
            format!("{} hp", r.baseline_hp)
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {rpm} ({}) | {} | {:.0} |",
            r.record.number,
            r.record.expected(),
            named.replace('|', "/"),
            r.verdict().text(),
            r.record.grade.label(),
            r.record.nominal_rpm(),
            baseline,
            r.seconds
        );
    }
    out
}

/// Counts per fault type and in total over `rows` selected by `keep`.
fn count_line(label: &str, rows: &[Row], keep: impl Fn(&Row) -> bool, hit: impl Fn(&Row) -> bool) -> String {
    let mut cells = Vec::new();
    for f in Fault::ALL.iter().map(Some).chain([None]) {
        let of: Vec<&Row> = rows.iter().filter(|r| keep(r) && f.is_none_or(|f| r.record.fault == *f)).collect();
        cells.push(ratio(of.iter().filter(|r| hit(r)).count(), of.len()));
    }
    format!("| {label} | {} |\n", cells.join(" | "))
}

/// The counts: right per fault type with 0–1 hp and 2–3 hp apart, then against the
/// benchmark's grades, then the failures.
pub fn counts(rows: &[Row]) -> String {
    let right = |r: &Row| r.verdict() == Verdict::Right;
    let low = |r: &Row| r.record.load_hp <= 1;
    let mut out = String::from("| | inner race | ball | outer race | all |\n|---|---|---|---|---|\n");
    out += &count_line("right, 0–1 hp", rows, low, right);
    out += &count_line("right, 2–3 hp", rows, |r| !low(r), right);
    out += &count_line("right, all loads run", rows, |_| true, right);
    out += &count_line(
        "Smith & Randall diagnose (Y1/Y2), of the records run",
        rows,
        |_| true,
        |r| r.record.grade.diagnosable(),
    );
    out += &count_line("right where they diagnose, 0–1 hp", rows, |r| low(r) && r.record.grade.diagnosable(), right);
    out += &count_line("right where they diagnose, 2–3 hp", rows, |r| !low(r) && r.record.grade.diagnosable(), right);
    out += &count_line(
        "nothing or the label's family where they do not (P/N), all loads run",
        rows,
        |r| !r.record.grade.diagnosable(),
        Row::acceptable_when_undiagnosable,
    );
    out += &count_line("wrong family or bearing named first", rows, |_| true, |r| r.verdict() == Verdict::Wrong);
    out += &count_line("failed runs", rows, |_| true, |r| r.verdict() == Verdict::Failed);
    out
}

/// The whole Markdown: a heading line, the record table, the counts, the flag's meaning.
pub fn markdown(rows: &[Row], heading: &str) -> String {
    let mut out = format!("{heading}\n\n{}\n{}", record_table(rows), counts(rows));
    if rows.iter().any(Row::other_load_baseline) {
        out += "\n⚑ run against the 0 hp baseline (097a): the mirror holds no healthy record at the record's load \
                (098–100 are listed but empty).\n";
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::catalogue::find;
    use super::*;
    use serde_json::json;

    fn row(number: u32, result: RunResult) -> Row {
        Row { record: find(number).unwrap(), baseline_hp: 0, result, seconds: 61.4 }
    }

    fn done(defects: &[(&str, &str)]) -> RunResult {
        RunResult::Done(Outcome {
            defects: defects.iter().map(|(l, a)| (l.to_string(), a.to_string())).collect(),
            ..Outcome::default()
        })
    }

    #[test]
    fn a_report_gives_its_defects_in_order_and_the_rest_apart() {
        let report = json!({
            "effects_added": [
                {"kind": "bearing_defect", "location": "bearing 11", "line": "FTF", "value": 0.9},
                {"kind": "extra_mode", "location": "n1_ay"},
                {"kind": "bearing_defect", "location": "bearing 1", "line": "BPFO"},
                {"kind": "unknown_input", "location": "node 6"},
                {"kind": "extra_mode", "location": "n1_ay"}
            ],
            "running_speed": {"hz": 29.95, "declared_hz": 29.95, "source": "estimated"},
            "not_identifiable": [
                {"kind": "bearing_defect", "location": "bearing 1", "rivals": ["bearing 11"]},
                {"kind": "sensor_bias", "location": "n1_ay"}
            ]
        });
        let o = Outcome::from_report(&report).unwrap();
        assert_eq!(o.defects, [("FTF".into(), "bearing 11".into()), ("BPFO".into(), "bearing 1".into())]);
        assert_eq!(o.others, ["extra_mode at n1_ay", "unknown_input at node 6", "extra_mode at n1_ay"]);
        assert!((o.rpm.unwrap() - 1797.0).abs() < 1e-9);
        assert_eq!(
            o.named(),
            "FTF at bearing 11, then BPFO at bearing 1; not identifiable: bearing 1 (rivals bearing 11); also extra_mode at n1_ay ×2, unknown_input at node 6"
        );
        assert!(Outcome::from_report(&json!({"system": "rotor"})).is_err());
        assert_eq!(Outcome::from_report(&json!({"effects_added": []})).unwrap().named(), "nothing");
    }

    #[test]
    fn the_verdict_wants_the_labels_family_first_at_the_drive_end() {
        assert_eq!(row(105, done(&[("BPFI", "bearing 1")])).verdict(), Verdict::Right);
        assert_eq!(row(105, done(&[("BPFI", "bearing 11")])).verdict(), Verdict::Wrong);
        assert_eq!(row(130, done(&[("FTF", "bearing 1"), ("BPFO", "bearing 1")])).verdict(), Verdict::Wrong);
        assert_eq!(row(3005, done(&[("BSF", "bearing 1")])).verdict(), Verdict::Right);
        assert_eq!(row(118, done(&[])).verdict(), Verdict::Missed);
        assert_eq!(row(118, RunResult::Failed("exit 1".into())).verdict(), Verdict::Failed);
    }

    #[test]
    fn counts_split_faults_loads_and_grades() {
        let rows = vec![
            row(105, done(&[("BPFI", "bearing 1")])), // IR, 0 hp, Y2: right
            row(106, done(&[("BPFO", "bearing 1")])), // IR, 1 hp, Y2: wrong
            row(118, done(&[])),                      // ball, 0 hp, N1: missed, acceptable
            row(119, done(&[("BPFO", "bearing 1")])), // ball, 1 hp, N1: wrong, not acceptable
            row(130, done(&[("BPFO", "bearing 1")])), // OR, 0 hp, Y1: right
            row(132, RunResult::Failed("no".into())), // OR, 2 hp, Y1: failed
        ];
        let c = counts(&rows);
        assert!(c.contains("| right, 0–1 hp | 1/2 | 0/2 | 1/1 | 2/5 |"), "{c}");
        assert!(c.contains("| right, 2–3 hp | – | – | 0/1 | 0/1 |"), "{c}");
        assert!(c.contains("| Smith & Randall diagnose (Y1/Y2), of the records run | 2/2 | 0/2 | 2/2 | 4/6 |"), "{c}");
        assert!(c.contains("| right where they diagnose, 0–1 hp | 1/2 | – | 1/1 | 2/3 |"), "{c}");
        assert!(c.contains("(P/N), all loads run | – | 1/2 | – | 1/2 |"), "{c}");
        assert!(c.contains("| wrong family or bearing named first | 1/2 | 1/2 | 0/2 | 2/6 |"), "{c}");
        assert!(c.contains("| failed runs | 0/2 | 0/2 | 1/2 | 1/6 |"), "{c}");
    }

    #[test]
    fn the_table_flags_another_loads_baseline_and_says_why_a_run_failed() {
        let rows = vec![
            row(106, RunResult::Done(Outcome { rpm: Some(1771.84), ..Outcome::default() })),
            row(105, RunResult::Failed("105.csv: no column `n1_ay`".into())),
        ];
        let md = markdown(&rows, "## CWRU");
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines[0], "## CWRU");
        // 0 hp first, then 1 hp.
        assert_eq!(lines[4], "| 105 | inner race 0.007 in, 0 hp (BPFI) | failed: 105.csv: no column `n1_ay` | failed | Y2 | – (1797) | 0 hp | 61 |");
        assert_eq!(lines[5], "| 106 | inner race 0.007 in, 1 hp (BPFI) | nothing | missed | Y2 | 1771.8 (1772) | 0 hp ⚑ (not the record's load) | 61 |");
        assert!(md.contains("⚑ run against the 0 hp baseline"));
        assert!(!markdown(&rows[1..], "x").contains("⚑"));
    }
}
