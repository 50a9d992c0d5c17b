//! The runner without the data: the folder's checks, the flags, and a whole run through a
//! stand-in `edgekf` (a shell script that writes what the real one writes, and fails where
//! told), so CI checks the error paths and the table's plumbing in milliseconds.

use super::table::Verdict;
use super::*;

fn folder(files: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in files {
        std::fs::write(dir.path().join(f), "t,n1_ay\n0,0\n").unwrap();
    }
    dir
}

fn plan_error(files: &[&str], loads: &[u8]) -> String {
    let dir = folder(files);
    format!("{:#}", plan(dir.path(), loads).unwrap_err())
}

#[test]
fn a_missing_or_empty_folder_is_refused_with_what_to_do() {
    let e = format!("{:#}", plan(Path::new("/no/such/cwru"), &[0]).unwrap_err());
    assert_eq!(e, "--dir /no/such/cwru: no such folder");
    let e = plan_error(&["097a.csv", "notes.txt"], &[0, 1, 2, 3]);
    assert!(e.contains("holds none of the 60") && e.contains("tools/cwru_convert_all.sh"), "{e}");
}

#[test]
fn the_folder_needs_records_at_the_loads_asked_and_the_healthy_half() {
    let e = plan_error(&["107.csv", "097a.csv"], &[0, 1]);
    assert!(e.ends_with("1 record(s), none at the loads asked for ([0, 1] hp)"), "{e}");
    let e = plan_error(&["105.csv"], &[0]);
    assert!(e.contains("097a.csv: missing") && e.contains("--decimate 4"), "{e}");
    let e = plan_error(&["105.csv", "12k_Drive_End_IR007_0_105.csv", "097a.csv"], &[0]);
    assert!(e.contains("record 105 is in") && e.contains("twice"), "{e}");
    let e = plan_error(&["12k_Drive_End_IR007_1_105.csv", "097a.csv"], &[0]);
    assert!(e.contains("record 105 is IR007 at 0 hp"), "{e}");
}

#[test]
fn the_plan_takes_both_names_the_loads_asked_in_catalogue_order() {
    let dir = folder(&["3001.csv", "12k_Drive_End_OR007@3_1_145.csv", "105.csv", "107.csv", "097a.csv", "097.csv"]);
    let p = plan(dir.path(), &[0, 1]).unwrap();
    let numbers: Vec<u32> = p.records.iter().map(|(r, _)| r.number).collect();
    assert_eq!(numbers, [105, 3001, 145]);
    assert!(p.records[2].1.ends_with("12k_Drive_End_OR007@3_1_145.csv"));
    assert_eq!(p.healthy, dir.path().join("097a.csv"));
}

#[test]
fn the_flags_parse_and_refuse_what_cannot_be() {
    let a = Args::try_parse_from(["cwru", "--dir", "d", "--loads", "0,1", "--jobs", "1"]).unwrap();
    assert_eq!((a.loads, a.jobs), (vec![0, 1], Some(1)));
    assert_eq!(Args::try_parse_from(["cwru", "--dir", "d"]).unwrap().loads, [0, 1, 2, 3]);
    assert!(Args::try_parse_from(["cwru", "--dir", "d", "--loads", "4"]).is_err());
    assert!(Args::try_parse_from(["cwru", "--dir", "d", "--jobs", "0"]).is_err());
    assert!(Args::try_parse_from(["cwru"]).is_err());
}

#[test]
fn outputs_are_checked_before_any_run_and_never_replaced_unasked() {
    let dir = folder(&["105.csv", "097a.csv", "old.md"]);
    let d = dir.path();
    let args = |extra: &[&str]| {
        let mut argv = vec!["cwru".to_string(), "--dir".into(), d.display().to_string()];
        argv.extend(extra.iter().map(|s| s.to_string()));
        Args::try_parse_from(argv).unwrap()
    };
    let data = d.join("105.csv");
    let inputs = [Some(data.as_path())];
    let old = d.join("old.md").display().to_string();
    let e = check_outputs(&args(&["--out", &old]), &inputs).unwrap_err().to_string();
    assert!(e.ends_with("old.md: exists; choose another name or add --force to replace it"), "{e}");
    assert!(check_outputs(&args(&["--out", &old, "--force"]), &inputs).is_ok());
    let e = check_outputs(&args(&["--out", &data.display().to_string(), "--force"]), &inputs).unwrap_err();
    assert!(e.to_string().contains("this is the input"), "{e}");
    let e = check_outputs(&args(&["--out", "/no/such/dir/t.md"]), &inputs).unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    // --keep: a new folder or an empty one; one with files only with --force.
    let used = d.display().to_string();
    assert!(check_outputs(&args(&["--keep", &used]), &inputs).unwrap_err().to_string().contains("holds files already"));
    assert!(check_outputs(&args(&["--keep", &used, "--force"]), &inputs).is_ok());
    assert!(check_outputs(&args(&["--keep", &d.join("new").display().to_string()]), &inputs).is_ok());

    // Writing: a file that appeared meanwhile is kept unless forced, and no temporary is left.
    let out = d.join("old.md");
    assert!(write_table(&out, "new\n", false).is_err());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "t,n1_ay\n0,0\n");
    write_table(&out, "new\n", true).unwrap();
    write_table(&d.join("fresh.md"), "fresh\n", false).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new\n");
    assert_eq!(std::fs::read_to_string(d.join("fresh.md")).unwrap(), "fresh\n");
    let partial = std::fs::read_dir(d)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().ends_with(".partial"));
    assert_eq!(partial.count(), 0);
}

/// A stand-in for `edgekf`: `baseline` writes its `--out`; `loop` needs that baseline, fails on
/// 106 as the real binary fails (an `error:` line), refuses a one-channel record under the
/// two-channel configuration, and otherwise writes a report naming BPFI at the drive end.
#[cfg(unix)]
const FAKE_EDGEKF: &str = r#"#!/bin/sh
cmd=$1
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$2; shift;;
    --data) data=$2; shift;;
    --report) report=$2; shift;;
    --config) config=$2; shift;;
    --baseline) baseline=$2; shift;;
  esac
  shift
done
if [ "$cmd" = baseline ]; then
  case "$config" in *broken*) echo "error: $config: cannot load the rotor" >&2; exit 1;; esac
  echo healthy > "$out"; exit 0
fi
[ -f "$baseline" ] || { echo "error: no baseline $baseline" >&2; exit 1; }
case "$data" in
  *106.csv) echo "progress" >&2; echo "error: $data: a 0.500 s gap is too long to bridge" >&2; exit 1;;
  *3001.csv) case "$config" in *_de.toml) ;; *) echo "error: no column n11_ay" >&2; exit 1;; esac;;
esac
mkdir -p "$report"
echo '{"effects_added":[{"kind":"bearing_defect","location":"bearing 1","line":"BPFI"}],"not_identifiable":[]}' > "$report/report.json"
"#;

/// One test for every run through the stand-in (a script being written while another test
/// starts one could make it "text file busy").
#[cfg(unix)]
#[test]
fn a_run_goes_on_past_a_failed_record_and_a_failed_baseline_stops_it() {
    use std::os::unix::fs::PermissionsExt;
    let data = folder(&["105.csv", "106.csv", "3001.csv", "097a.csv"]);
    let tools = tempfile::tempdir().unwrap();
    let edgekf = tools.path().join("edgekf");
    std::fs::write(&edgekf, FAKE_EDGEKF).unwrap();
    std::fs::set_permissions(&edgekf, std::fs::Permissions::from_mode(0o755)).unwrap();
    let configs =
        Configs { both: tools.path().join("rotor_cwru.toml"), drive_end: tools.path().join("rotor_cwru_de.toml") };
    let work = tools.path().join("work");
    let runner = Runner { edgekf: edgekf.clone(), configs, work: work.clone(), jobs: 2 };
    let p = plan(data.path(), &[0, 1]).unwrap();
    let rows = runner.run(&p).unwrap();
    let verdicts: Vec<(u32, Verdict)> = rows.iter().map(|r| (r.record.number, r.verdict())).collect();
    assert_eq!(verdicts, [(105, Verdict::Right), (106, Verdict::Failed), (3001, Verdict::Right)]);
    assert!(progress_line(&rows[0]).starts_with("105 (IR007, 0 hp): BPFI at bearing 1 — right, "));
    assert!(progress_line(&rows[1]).starts_with("106 (IR007, 1 hp): failed: "));
    let RunResult::Failed(why) = &rows[1].result else { unreachable!() };
    assert!(why.ends_with("106.csv: a 0.500 s gap is too long to bridge"), "{why}");
    assert!(
        work.join("baseline-097a-rotor_cwru.toml").is_file() && work.join("baseline-097a-rotor_cwru_de.toml").is_file()
    );
    assert!(std::fs::read_to_string(work.join("106.log")).unwrap().contains("gap is too long"));
    let md = table::markdown(&rows, "#");
    assert!(md.contains("| 106 | inner race 0.007 in, 1 hp (BPFI) | failed: "), "{md}");

    // A report that is not JSON is the row's failure, with the file named.
    std::fs::write(work.join("105/report.json"), "{").unwrap();
    let e = read_outcome(&work.join("105/report.json")).unwrap_err();
    assert!(e.contains("105/report.json"), "{e}");

    let broken = Configs { both: tools.path().join("broken.toml"), drive_end: tools.path().join("rotor_cwru_de.toml") };
    let runner = Runner { configs: broken, work: tools.path().join("work2"), ..runner };
    let e = format!("{:#}", runner.run(&p).unwrap_err());
    assert!(e.contains("learning the baseline with") && e.contains("cannot load the rotor"), "{e}");
    let missing = Runner { edgekf: tools.path().join("no-edgekf"), ..runner };
    let e = format!("{:#}", missing.run(&p).unwrap_err());
    assert!(e.contains("cannot start"), "{e}");
}
