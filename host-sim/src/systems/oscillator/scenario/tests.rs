use super::*;
use crate::systems::oscillator::sensor::G;

const DEMO_TOML: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/oscillator_demo.toml"));

#[test]
fn shipped_demo_config_is_the_default_scenario() {
    assert_eq!(Scenario::from_toml_str(DEMO_TOML).unwrap(), Scenario::default());
}

#[test]
fn default_recording_has_the_demo_physics_and_sensor_noise() {
    let s = Scenario::default();
    let r = s.simulate();
    assert_eq!(r.len(), 12_000);
    assert_eq!(r.t[11_999], 11.999);
    // Amplitude schedule: 5 N, then 3 N from 6.2 s.
    assert_eq!((r.truth_force_amplitude[5_999], r.truth_force_amplitude[6_200]), (5.0, 3.0));
    // x reads the mode's acceleration plus 4.86 mm/s² of noise; y and z noise alone.
    let sigma = s.sensor.noise_std();
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (mut n, mut sum) = (0.0, 0.0);
        for x in v {
            n += 1.0;
            sum += x * x;
        }
        (sum / n).sqrt()
    };
    let ex = rms(&mut r.ax.iter().zip(&r.truth_accel).map(|(a, t)| a - t));
    assert!((ex / sigma - 1.0).abs() < 0.03, "x noise {ex}");
    assert!((rms(&mut r.ay.iter().copied()) / sigma - 1.0).abs() < 0.03);
    assert!((rms(&mut r.az.iter().copied()) / sigma - 1.0).abs() < 0.03);
    // Steady acceleration amplitude before the step: Ω²|X| = 7737 × 0.62 mm = 4.80 m/s².
    let peak = r.truth_accel[4_000..6_000].iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!((peak - 4.796).abs() < 0.01, "{peak}");
    assert!(r.fault_nack.iter().chain(&r.fault_timeout).chain(&r.fault_garbage).all(|&n| n == 0));
    assert!(r.fault_stuck.iter().chain(&r.fault_drop).chain(&r.fault_reset).all(|&s| !s));
}

#[test]
fn the_seed_fixes_the_noise() {
    let s = Scenario { duration_s: 0.5, ..Default::default() };
    assert_eq!(s.simulate(), s.simulate());
    let other = Scenario { seed: 2, ..s.clone() }.simulate();
    let base = s.simulate();
    assert_ne!(base.ax, other.ax);
    assert_eq!(base.truth_x, other.truth_x);
}

#[test]
fn faults_land_on_the_right_samples() {
    let s = Scenario { faults: Fault::demo_set(12.0), ..Default::default() };
    let r = s.simulate();
    let counts = |v: &[u8]| v.iter().copied().enumerate().filter(|(_, n)| *n > 0).collect::<Vec<(usize, u8)>>();
    let flags = |v: &[bool]| (0..r.len()).filter(|&k| v[k]).collect::<Vec<usize>>();
    assert_eq!(counts(&r.fault_nack), [(3_000, 3)]);
    assert_eq!(counts(&r.fault_timeout), [(3_600, 2)]);
    assert_eq!(counts(&r.fault_garbage), [(4_200, 3)]);
    let stuck = flags(&r.fault_stuck);
    assert_eq!(stuck.len(), 50);
    assert_eq!((stuck[0], stuck[49]), (4_800, 4_849));
    assert_eq!(flags(&r.fault_drop), (6_000..6_020).collect::<Vec<_>>());
    assert_eq!(flags(&r.fault_reset), [7_200]);
    // Saturation: 3 g on the x axis reads as the 2 g full scale for 20 samples; truth unchanged.
    let clipped: Vec<usize> = (0..r.len()).filter(|&k| r.ax[k] == 2.0 * G).collect();
    assert_eq!(clipped, (9_000..9_020).collect::<Vec<_>>());
    assert!(r.truth_accel[9_010].abs() < 5.0);
    // The virtual-device faults leave ax alone: same noise as the clean run there.
    let clean = Scenario::default().simulate();
    assert_eq!(r.ax[4_800..4_850], clean.ax[4_800..4_850]);
    assert_eq!(r.ax[6_000..6_020], clean.ax[6_000..6_020]);
    assert_eq!([r.ax[3_000], r.ax[3_600], r.ax[4_200], r.ax[7_200]], [3_000, 3_600, 4_200, 7_200].map(|k| clean.ax[k]));
}

#[test]
fn new_fault_kinds_read_from_toml_and_are_checked() {
    let text = "[[faults]]\nkind = \"timeout\"\nt = 1.0\ntransactions = 2\n\
                [[faults]]\nkind = \"garbage\"\nt = 1.5\ntransactions = 4\n\
                [[faults]]\nkind = \"dropout\"\nt_start = 2.0\nt_end = 2.01\n\
                [[faults]]\nkind = \"reset\"\nt = 3.0\n";
    let s = Scenario::from_toml_str(text).unwrap();
    let want = [
        Fault::Timeout { t: 1.0, transactions: 2 },
        Fault::Garbage { t: 1.5, transactions: 4 },
        Fault::Dropout { t_start: 2.0, t_end: 2.01 },
        Fault::Reset { t: 3.0 },
    ];
    assert_eq!(s.faults, want);
    assert_eq!(s.faults.iter().map(Fault::kind).collect::<Vec<_>>(), ["timeout", "garbage", "dropout", "reset"]);
    let e = |t: &str| format!("{:#}", Scenario::from_toml_str(t).unwrap_err());
    assert!(e("[[faults]]\nkind = \"dropout\"\nt_start = 2.0\nt_end = 1.0\n").contains("faults[0]"));
    assert!(e("[[faults]]\nkind = \"reset\"\nt = nan\n").contains("reset: t must be finite"));
    assert!(e("[[faults]]\nkind = \"timeout\"\nt = 1.0\ntransactions = 300\n").contains("integer `300`, expected u8"));
}

#[test]
fn csv_has_exactly_the_contract_columns() {
    let r = Scenario {
        duration_s: 0.01,
        faults: vec![Fault::Stuck { t_start: 0.002, t_end: 0.004 }],
        ..Default::default()
    }
    .simulate();
    let text = r.to_csv_string();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,ax,ay,az,fault_nack,fault_timeout,fault_garbage,fault_stuck,fault_drop,fault_reset,truth_x,truth_v,\
         truth_force,truth_force_amplitude,truth_accel"
    );
    let row2: Vec<&str> = lines.nth(2).unwrap().split(',').collect();
    assert_eq!((row2[0], row2[4], row2[7], row2[8], row2[13]), ("0.002", "0", "1", "0", "5"));
    assert_eq!(text.lines().count(), 11);
}

#[test]
fn estimator_params_come_from_the_scenario() {
    let s = Scenario::from_toml_str(
        "[mode]\nnatural_freq_hz = 35.0\n[sensor]\nodr_hz = 2000.0\n[filter]\nforce_psd = 1e-3\n[force]\ndrive_rad_s = 100.0\n",
    )
    .unwrap();
    let p = s.estimator_params();
    assert_eq!((p.natural_freq_hz, p.damping_ratio, p.drive_rad_s, p.sample_rate_hz), (35.0, 0.02, 100.0, 2000.0));
    assert!((p.accel_noise_std - 25e-6 * G * (1.57f64 * 500.0).sqrt()).abs() < 1e-15);
    assert_eq!(p.force_psd, 1e-3);
    assert_eq!(p.gate_nis, HarmonicForceParams::default().gate_nis);
    // A [force] table without `changes` means a constant force.
    assert!(s.force.changes.is_empty());
}

#[test]
fn bad_scenarios_are_refused_with_the_field_named() {
    let e = |t: &str| format!("{:#}", Scenario::from_toml_str(t).unwrap_err());
    assert!(e("[mode]\nnatural_freq = 20.0\n").contains("unknown field `natural_freq`"));
    assert!(e("[mode]\ndamping_ratio = 1.5\n").contains("mode.damping_ratio = 1.5"));
    assert!(e("duration_s = -1.0\n").contains("duration_s = -1"));
    assert!(e("[sensor]\nodr_hz = 1200.0\n").contains("odr_hz = 1200"));
    assert!(e("[[faults]]\nkind = \"stuck\"\nt_start = 2.0\nt_end = 1.0\n").contains("faults[0]"));
    assert!(e("[[faults]]\nkind = \"melt\"\n").contains("melt"));
    assert!(e("[filter]\nforce_psd = -1.0\n").contains("force_psd"));
    assert!(e("[filter]\ngain = \"fast\"\n").contains("unknown variant `fast`"));
    assert!(e("duration_s = \"long\"\n").contains("duration_s"));
}

#[test]
fn an_offset_fault_shifts_the_x_axis_from_its_time_on() {
    let base = Scenario::from_toml_str("duration_s = 1.0\n").unwrap();
    let shifted =
        Scenario::from_toml_str("duration_s = 1.0\n[[faults]]\nkind = \"offset\"\nt = 0.5\naccel = 0.05\n").unwrap();
    let (a, b) = (base.simulate(), shifted.simulate());
    for k in 0..a.len() {
        let expected = if a.t[k] >= 0.5 - TIME_TOLERANCE { 0.05 } else { 0.0 };
        assert!((b.ax[k] - a.ax[k] - expected).abs() < 1e-12, "sample {k}");
        assert_eq!((a.ay[k], a.truth_x[k]), (b.ay[k], b.truth_x[k]));
    }
    assert!(Scenario::from_toml_str("[[faults]]\nkind = \"offset\"\nt = 0.5\naccel = nan\n").is_err());
    assert!(Scenario::from_toml_str("[filter]\naccel_offset_m_s2 = 100.0\n").is_err());
}
