//! The health-factor timelines of the scenarios (depth 10 m, heading 45°, main thruster at
//! 1500 rpm, 300 s by default).

use clap::ValueEnum;

/// A scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Scenario {
    /// The paper's field trial: `k_t = 0.1` from 220 s, back to 1 during [228, 230),
    /// [233, 236), [238.5, 240) and [242, 244), 0.1 from 244 s on.
    Paper,
    /// The vertical thruster at 40 % from 150 s.
    Vertical,
    /// Both thrusters healthy throughout.
    Healthy,
}

/// The paper scenario's recoveries of the main thruster, s.
pub const PAPER_RECOVERIES: [(f64, f64); 4] = [(228.0, 230.0), (233.0, 236.0), (238.5, 240.0), (242.0, 244.0)];
/// When the paper scenario's fault starts, s.
pub const PAPER_FAULT: f64 = 220.0;
/// When the vertical scenario's fault starts, s.
pub const VERTICAL_FAULT: f64 = 150.0;

impl Scenario {
    /// `(k_t, k_v)` at `t` seconds of the recording.
    ///
    /// ```
    /// use edgekf_sim::systems::uuv::Scenario;
    /// assert_eq!(Scenario::Paper.health(219.99), (1.0, 1.0));
    /// assert_eq!(Scenario::Paper.health(225.0), (0.1, 1.0));
    /// assert_eq!(Scenario::Paper.health(229.0), (1.0, 1.0));
    /// assert_eq!(Scenario::Paper.health(250.0), (0.1, 1.0));
    /// assert_eq!(Scenario::Vertical.health(151.0), (1.0, 0.4));
    /// ```
    pub fn health(self, t: f64) -> (f64, f64) {
        match self {
            Scenario::Paper => {
                let recovered = PAPER_RECOVERIES.iter().any(|&(a, b)| t >= a && t < b);
                (if t < PAPER_FAULT || recovered { 1.0 } else { 0.1 }, 1.0)
            }
            Scenario::Vertical => (1.0, if t < VERTICAL_FAULT { 1.0 } else { 0.4 }),
            Scenario::Healthy => (1.0, 1.0),
        }
    }

    /// The instants the main (`0`) or vertical (`1`) thruster's health changes, s.
    pub fn transitions(self, thruster: usize) -> Vec<f64> {
        match (self, thruster) {
            (Scenario::Paper, 0) => {
                let mut t = vec![PAPER_FAULT];
                for (a, b) in PAPER_RECOVERIES {
                    t.extend([a, b]);
                }
                t
            }
            (Scenario::Vertical, 1) => vec![VERTICAL_FAULT],
            _ => Vec::new(),
        }
    }

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Paper => "paper",
            Scenario::Vertical => "vertical",
            Scenario::Healthy => "healthy",
        }
    }
}
