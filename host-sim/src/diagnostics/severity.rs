//! Vibration severity as the standard grades a machine in service: the broadband r.m.s.
//! velocity measured on its bearing housings, put into the evaluation zones of ISO 20816-3
//! (which took over ISO 10816-3's velocity criteria for industrial machines above 15 kW):
//!
//! * A: newly commissioned machines;
//! * B: acceptable for unrestricted long-term operation;
//! * C: unsatisfactory for long-term operation, run only until a suitable opportunity for
//!   remedial action;
//! * D: severe enough to cause damage.
//!
//! The zone boundaries depend on the machine's group (group 1: 300 kW–50 MW; group 2:
//! 15–300 kW) and its support (rigid or flexible), so the class is a configuration key
//! (`[severity] machine_class`); the velocity is reported whatever the class. The band is
//! 10–1000 Hz for machines running at 600 rpm or more, 2–1000 Hz below, as the standard asks.
//!
//! The velocity comes from an accelerometer by integrating in the frequency domain (each
//! line divided by 2πf), which is what a vibration meter's integrator does within its band.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use serde::{Deserialize, Serialize};

/// A machine's class for the zone boundaries (`[severity] machine_class`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MachineClass {
    /// A small machine, up to 15 kW (ISO 10816-1 Annex B, class I: ISO 20816-3 starts at
    /// 15 kW, and this is still the usual grading below it).
    Class1Small,
    /// Group 1 (300 kW–50 MW) on rigid supports.
    Group1Rigid,
    /// Group 1 (300 kW–50 MW) on flexible supports.
    Group1Flexible,
    /// Group 2 (15–300 kW) on rigid supports.
    Group2Rigid,
    /// Group 2 (15–300 kW) on flexible supports.
    Group2Flexible,
}

impl MachineClass {
    /// The A/B, B/C and C/D zone boundaries, mm/s r.m.s. (ISO 20816-3, velocity criteria).
    pub fn boundaries_mm_s(self) -> [f64; 3] {
        match self {
            MachineClass::Class1Small => [0.71, 1.8, 4.5],
            MachineClass::Group1Rigid => [2.3, 4.5, 7.1],
            MachineClass::Group1Flexible => [3.5, 7.1, 11.0],
            MachineClass::Group2Rigid => [1.4, 2.8, 4.5],
            MachineClass::Group2Flexible => [2.3, 4.5, 7.1],
        }
    }

    /// How a report names it.
    pub fn describe(self) -> &'static str {
        match self {
            MachineClass::Class1Small => "class I (up to 15 kW, ISO 10816-1)",
            MachineClass::Group1Rigid => "group 1 (300 kW–50 MW), rigid supports",
            MachineClass::Group1Flexible => "group 1 (300 kW–50 MW), flexible supports",
            MachineClass::Group2Rigid => "group 2 (15–300 kW), rigid supports",
            MachineClass::Group2Flexible => "group 2 (15–300 kW), flexible supports",
        }
    }

    /// The zone of a velocity `mm_s` (r.m.s.): `'A'` to `'D'`; a value on a boundary belongs
    /// to the worse zone.
    ///
    /// ```
    /// use edgekf_sim::diagnostics::severity::MachineClass;
    /// assert_eq!(MachineClass::Group2Rigid.zone(1.0), 'A');
    /// assert_eq!(MachineClass::Group2Rigid.zone(2.8), 'C');
    /// assert_eq!(MachineClass::Group1Flexible.zone(12.0), 'D');
    /// ```
    pub fn zone(self, mm_s: f64) -> char {
        let above = self.boundaries_mm_s().iter().filter(|&&b| mm_s >= b).count();
        ['A', 'B', 'C', 'D'][above]
    }
}

/// What the zone means for the machine, in the standard's words.
pub fn zone_meaning(zone: char) -> &'static str {
    match zone {
        'A' => "as newly commissioned",
        'B' => "acceptable for unrestricted long-term operation",
        'C' => "unsatisfactory for long-term operation: plan remedial action",
        _ => "severe enough to cause damage",
    }
}

/// The severity of one accelerometer channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Severity {
    /// The channel's name.
    pub channel: String,
    /// Broadband r.m.s. velocity in the band, mm/s.
    pub velocity_rms_mm_s: f64,
    /// The band, Hz.
    pub band_hz: [f64; 2],
    /// The class the zone is graded for, if configured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_class: Option<MachineClass>,
    /// The zone (`A`–`D`), if a class is configured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zone: Option<char>,
}

impl Severity {
    /// Grades `accel` (m/s², sampled at `fs` Hz) of a machine running at `speed_hz`.
    ///
    /// ```
    /// use edgekf_sim::diagnostics::severity::{MachineClass, Severity};
    /// // 50 Hz vibration of 3 mm/s r.m.s. velocity: acceleration amplitude 2πf·v·√2.
    /// let (fs, f, v) = (2000.0, 50.0, 3e-3);
    /// let a: Vec<f64> = (0..4000)
    ///     .map(|k| std::f64::consts::TAU * f * v * 2f64.sqrt() * (std::f64::consts::TAU * f * k as f64 / fs).cos())
    ///     .collect();
    /// let s = Severity::of("ax", &a, fs, 25.0, Some(MachineClass::Group2Rigid)).unwrap();
    /// assert!((s.velocity_rms_mm_s - 3.0).abs() < 0.03);
    /// assert_eq!(s.zone, Some('C'));
    /// ```
    pub fn of(channel: &str, accel: &[f64], fs: f64, speed_hz: f64, class: Option<MachineClass>) -> Option<Self> {
        let low = if speed_hz >= 10.0 { 10.0 } else { 2.0 };
        let band = [low, 1000.0_f64.min(0.5 * fs)];
        let v = velocity_rms(accel, fs, band)? * 1e3;
        Some(Severity {
            channel: channel.to_string(),
            velocity_rms_mm_s: v,
            band_hz: band,
            machine_class: class,
            zone: class.map(|c| c.zone(v)),
        })
    }

    /// One line for people: the velocity, its band and, with a class, the zone and its meaning.
    pub fn describe(&self) -> String {
        let v = self.velocity_rms_mm_s;
        let v = if v >= 0.1 { format!("{v:.2}") } else { format!("{v:.2e}") };
        let head = format!("{}: {v} mm/s r.m.s. ({:.0}–{:.0} Hz)", self.channel, self.band_hz[0], self.band_hz[1]);
        match (self.machine_class, self.zone) {
            (Some(c), Some(z)) => format!("{head}: zone {z} for {}, {}", c.describe(), zone_meaning(z)),
            _ => format!("{head}; set `[severity] machine_class` to grade it (ISO 20816-3 zones)"),
        }
    }
}

/// The r.m.s. of the velocity whose derivative is `accel` (m/s², at `fs` Hz) within `band`
/// (Hz), m/s; `None` for fewer than 16 finite samples or a band with no line in it. Non-finite
/// samples are replaced by the mean (they carry no information about the level).
pub fn velocity_rms(accel: &[f64], fs: f64, band: [f64; 2]) -> Option<f64> {
    let finite: Vec<f64> = accel.iter().copied().filter(|x| x.is_finite()).collect();
    if finite.len() < 16 || fs.is_nan() || fs <= 0.0 {
        return None;
    }
    let mean = finite.iter().sum::<f64>() / finite.len() as f64;
    let n = accel.len();
    let mut x: Vec<Complex<f64>> =
        accel.iter().map(|&a| Complex::new(if a.is_finite() { a - mean } else { 0.0 }, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut x);
    let df = fs / n as f64;
    let mut sum = 0.0;
    let mut lines = 0;
    for (k, c) in x.iter().enumerate().take(n.div_ceil(2)).skip(1) {
        let f = k as f64 * df;
        if f >= band[0] && f <= band[1] {
            sum += 2.0 * c.norm_sqr() / (std::f64::consts::TAU * f).powi(2);
            lines += 1;
        }
    }
    (lines > 0).then(|| (sum / (n as f64 * n as f64)).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn tone(fs: f64, f: f64, v_rms: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| TAU * f * v_rms * 2f64.sqrt() * (TAU * f * k as f64 / fs).sin()).collect()
    }

    #[test]
    fn two_tones_add_in_power_and_a_tone_outside_the_band_counts_nothing() {
        let fs = 4096.0;
        let a: Vec<f64> =
            tone(fs, 30.0, 2e-3, 8192).iter().zip(tone(fs, 400.0, 1.5e-3, 8192)).map(|(x, y)| x + y).collect();
        let v = velocity_rms(&a, fs, [10.0, 1000.0]).unwrap();
        assert!((v - 2.5e-3).abs() < 2.5e-5, "{v}");
        let low = tone(fs, 5.0, 4e-3, 8192);
        assert!(velocity_rms(&low, fs, [10.0, 1000.0]).unwrap() < 1e-4);
        assert!((velocity_rms(&low, fs, [2.0, 1000.0]).unwrap() - 4e-3).abs() < 4e-5);
    }

    #[test]
    fn zones_follow_the_classes_boundaries_and_slow_machines_get_the_wider_band() {
        assert_eq!(MachineClass::Group2Rigid.zone(1.39), 'A');
        assert_eq!(MachineClass::Group2Rigid.zone(4.5), 'D');
        assert_eq!(MachineClass::Group1Rigid.zone(4.4), 'B');
        assert_eq!(MachineClass::Group2Flexible.zone(5.0), 'C');
        assert_eq!(MachineClass::Class1Small.zone(1.0), 'B');
        let s = Severity::of("ax", &tone(2000.0, 40.0, 1e-3, 4000), 2000.0, 5.0, None).unwrap();
        assert_eq!(s.band_hz, [2.0, 1000.0]);
        assert_eq!(s.zone, None);
        assert!(s.describe().contains("machine_class"), "{}", s.describe());
        let c: MachineClass =
            toml::from_str::<toml::Table>("c = \"group1_flexible\"").unwrap()["c"].clone().try_into().unwrap();
        assert_eq!(c, MachineClass::Group1Flexible);
    }

    #[test]
    fn too_little_data_or_nan_gives_no_grade_rather_than_a_wrong_one() {
        assert!(velocity_rms(&[1.0; 8], 1000.0, [10.0, 500.0]).is_none());
        let mut a = tone(2000.0, 50.0, 1e-3, 4000);
        a[100] = f64::NAN;
        assert!((velocity_rms(&a, 2000.0, [10.0, 1000.0]).unwrap() - 1e-3).abs() < 2e-5);
    }
}
