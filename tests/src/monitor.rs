//! Recordings for the model monitor's tests (`tests/monitor_node.rs` on the host, `tests/hil.rs`
//! under QEMU): healthy runs, and the same with a sensor offset from half-way on.

use edgekf_sim::systems::oscillator::scenario::Scenario;

/// Adds `offset` to column `column` of every data row at or after `from_s` (by its `t`).
pub fn offset_from(csv: &str, column: &str, from_s: f64, offset: f64) -> String {
    let mut rows = csv.lines();
    let header = rows.next().expect("a header");
    let names: Vec<&str> = header.split(',').collect();
    let (t, c) = (names.iter().position(|n| *n == "t").unwrap(), names.iter().position(|n| *n == column).unwrap());
    let mut out = vec![header.to_owned()];
    for row in rows {
        let mut cells: Vec<String> = row.split(',').map(str::to_owned).collect();
        if cells[t].parse::<f64>().unwrap() >= from_s {
            cells[c] = format!("{}", cells[c].parse::<f64>().unwrap() + offset);
        }
        out.push(cells.join(","));
    }
    out.join("\n") + "\n"
}

/// The oscillator's healthy recording (seed `seed`: the demo's force held at 5 N, which the
/// model explains, where the demo steps it to 3 N in 0.2 s, which it does not: the monitor flags
/// that step) and the same with an X-axis offset of five noise standard deviations (0.024 m/s²,
/// 2.5 mg) from half-way on; the sample it starts at. The filter takes up about 85 % of an
/// offset into its motion states: one standard deviation leaves an innovation bias of 0.15 σ,
/// which 6 s do not show; three are found on seed 1 (a bias in the window from 6.12 s), five
/// on every seed tried (1–3).
pub fn oscillator_recordings(seed: u64) -> (String, String, u32) {
    let mut scenario = Scenario { seed, ..Scenario::default() };
    scenario.force.changes.clear();
    let csv = scenario.simulate().to_csv_string();
    let from_s = scenario.duration_s / 2.0;
    let biased = offset_from(&csv, "ax", from_s, 5.0 * scenario.sensor.noise_std());
    (csv, biased, (from_s * scenario.sensor.odr_hz) as u32 + 1)
}
