use super::*;

/// A node's log with a window of `n` samples from sample 1001 at 1 kHz, `a = k / 1000`
/// (sample 1003 missing), amid other frames, each line with a defmt-print style prefix.
fn log(n: u32) -> String {
    let mut s = String::from("INFO start odr=1000 watermark=48\nINFO mismatch channel=0 statistic=1 since=700\n");
    s.push_str(&format!("INFO window_start channel=0 statistic=1 since=700 first=1001 samples={n} rate=1000\n"));
    s.push_str("INFO window_state displacement=1e-5 velocity=0 force_cos=4.3 force_sin=2.5 offset=0\n");
    for k in 1001..1001 + n {
        let a = if k == 1003 { "NaN".to_string() } else { format!("{}", k as f32 / 1000.0) };
        s.push_str(&format!("INFO window k={k} a={a}\nINFO blk 3 16 0 0 0 0 0 0 0 0\n"));
    }
    s.push_str(&format!("INFO window_end samples={n}\nINFO done\n"));
    s
}

#[test]
fn a_complete_window_becomes_the_recording() {
    let w = parse_log(&log(5)).unwrap();
    assert_eq!(w.mismatch, (0, 1, 700));
    assert_eq!(w.samples.len(), 5);
    assert_eq!(w.state.as_deref(), Some("displacement=1e-5 velocity=0 force_cos=4.3 force_sin=2.5 offset=0"));
    let csv = w.to_csv("ax");
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows, ["t,ax", "1,1.001", "1.001,1.002", "1.002,", "1.003,1.004", "1.004,1.005"]);
}

#[test]
fn a_log_without_a_window_is_refused() {
    let e = parse_log("start odr=1000 watermark=48\nblk 0 16 0 0 0 0 0 0 0 0\ndone\n").unwrap_err();
    assert!(e.to_string().contains("no window"), "{e}");
    assert!(parse_log("").is_err());
}

#[test]
fn a_truncated_window_is_refused() {
    let full = log(5);
    let cut: String = full.lines().take(8).map(|l| format!("{l}\n")).collect();
    let e = parse_log(&cut).unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
    // The end frame promises more samples than came.
    let short = full.replace("window_end samples=5", "window_end samples=6");
    assert!(parse_log(&short).unwrap_err().to_string().contains("ends after 5"));
}

#[test]
fn malformed_frames_holes_and_second_windows_are_refused() {
    let full = log(4);
    for (bad, says) in [
        (full.replace("window k=1002 a=1.002", "window k=1002 a=x"), "line"),
        (full.replace("window k=1002 a=1.002", "window k=1002"), "no `a=`"),
        (full.replace("window k=1002 a=1.002\n", ""), "hole"),
        (full.replace("rate=1000", "rate=0"), "0 Hz"),
        (full.replace("first=1001", "first=x"), "first"),
        (format!("{full}{full}"), "second window"),
        ("window k=1 a=0\n".to_string(), "before any"),
    ] {
        let e = parse_log(&bad).expect_err(says);
        assert!(format!("{e:#}").contains(says), "{says}: {e:#}");
    }
}

#[test]
fn an_existing_output_is_kept_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("window.csv");
    std::fs::write(&out, "keep me").unwrap();
    let e = write_new(&out, "new", false).unwrap_err();
    assert!(e.to_string().contains("--force"), "{e}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "keep me");
    write_new(&out, "new", true).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    let fresh = dir.path().join("fresh.csv");
    write_new(&fresh, "t,ax\n", false).unwrap();
    assert_eq!(std::fs::read_to_string(&fresh).unwrap(), "t,ax\n");
    // Only the outputs are left: no temporary file.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}
