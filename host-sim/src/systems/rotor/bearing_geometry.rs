//! Rolling-element bearing geometry and its defect frequencies.
//!
//! A damaged rolling-element bearing knocks at frequencies fixed by its geometry and the shaft
//! speed (outer race fixed, inner race turning with the shaft), the textbook kinematic formulas:
//!
//! * BPFO, ball pass frequency of the outer race: `n/2 · (1 − d/D cos θ) · f_r`;
//! * BPFI, ball pass frequency of the inner race: `n/2 · (1 + d/D cos θ) · f_r`;
//! * BSF, ball spin frequency: `D/(2d) · (1 − (d/D cos θ)²) · f_r`;
//! * FTF, fundamental train (cage) frequency: `1/2 · (1 − d/D cos θ) · f_r`;
//!
//! with `n` rolling elements of diameter `d` on pitch diameter `D` at contact angle `θ`. The
//! residual loop reads them as orders of the running speed (`f / f_r`), so a spectral line at a
//! non-integer order can be named.
//!
//! ```
//! use edgekf_sim::systems::rotor::bearing_geometry::{BearingGeometry, BearingLine};
//! // The SKF 6205 drive-end bearing of the Case Western Reserve data set.
//! let g = BearingGeometry { balls: 9, ball_diameter: 7.94e-3, pitch_diameter: 39.04e-3, contact_angle_deg: 0.0 };
//! assert!((g.order(BearingLine::Bpfo) - 3.5848).abs() < 1e-3);
//! ```

use serde::Deserialize;

/// Geometry of a rolling-element bearing (`geometry = { … }` in a `[[bearing]]`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BearingGeometry {
    /// Number of rolling elements.
    pub balls: u32,
    /// Rolling-element diameter, m.
    pub ball_diameter: f64,
    /// Pitch diameter, m.
    pub pitch_diameter: f64,
    /// Contact angle, degrees; default 0.
    #[serde(default)]
    pub contact_angle_deg: f64,
}

/// A bearing defect line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BearingLine {
    /// Ball pass frequency, outer race.
    Bpfo,
    /// Ball pass frequency, inner race.
    Bpfi,
    /// Ball spin frequency.
    Bsf,
    /// Fundamental train (cage) frequency.
    Ftf,
}

impl BearingLine {
    /// All four lines.
    pub const ALL: [BearingLine; 4] = [BearingLine::Bpfo, BearingLine::Bpfi, BearingLine::Bsf, BearingLine::Ftf];

    /// The name used in reports (`BPFO`, …).
    pub fn name(self) -> &'static str {
        match self {
            BearingLine::Bpfo => "BPFO",
            BearingLine::Bpfi => "BPFI",
            BearingLine::Bsf => "BSF",
            BearingLine::Ftf => "FTF",
        }
    }
}

impl BearingGeometry {
    /// Checks the geometry makes sense (at least one ball, `0 < d < D`, `|θ| < 90°`).
    pub fn validate(&self) -> Result<(), String> {
        let ok = self.balls > 0
            && self.ball_diameter > 0.0
            && self.pitch_diameter > self.ball_diameter
            && self.contact_angle_deg.abs() < 90.0;
        if ok {
            Ok(())
        } else {
            Err(format!(
                "bearing geometry needs balls ≥ 1, 0 < ball_diameter < pitch_diameter and |contact_angle_deg| < 90 \
                 (got {} balls, d = {} m, D = {} m, θ = {}°)",
                self.balls, self.ball_diameter, self.pitch_diameter, self.contact_angle_deg
            ))
        }
    }

    /// The line's frequency as a multiple of the shaft rotation frequency.
    pub fn order(&self, line: BearingLine) -> f64 {
        let ratio = self.ball_diameter / self.pitch_diameter * self.contact_angle_deg.to_radians().cos();
        let n = self.balls as f64;
        match line {
            BearingLine::Bpfo => 0.5 * n * (1.0 - ratio),
            BearingLine::Bpfi => 0.5 * n * (1.0 + ratio),
            BearingLine::Bsf => 0.5 * self.pitch_diameter / self.ball_diameter * (1.0 - ratio * ratio),
            BearingLine::Ftf => 0.5 * (1.0 - ratio),
        }
    }

    /// The four lines as the family diagnosis reads them
    /// ([`family`](crate::diagnostics::bearings::family)).
    pub fn kinematics(&self) -> crate::diagnostics::bearings::family::Kinematics {
        crate::diagnostics::bearings::family::Kinematics {
            bpfo: self.order(BearingLine::Bpfo),
            bpfi: self.order(BearingLine::Bpfi),
            bsf: self.order(BearingLine::Bsf),
            ftf: self.order(BearingLine::Ftf),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published defect frequencies of the SKF 6205-2RS JEM (the CWRU drive-end bearing), as
    /// multiples of the running speed: BPFO 3.5848, BPFI 5.4152, BSF 2.3568 (the CWRU page
    /// lists 4.7135 = 2·BSF), FTF 0.39828.
    #[test]
    fn skf_6205_lines() {
        let g = BearingGeometry {
            balls: 9,
            ball_diameter: 0.3126 * 25.4e-3,
            pitch_diameter: 1.537 * 25.4e-3,
            contact_angle_deg: 0.0,
        };
        let expect = [
            (BearingLine::Bpfo, 3.5848),
            (BearingLine::Bpfi, 5.4152),
            (BearingLine::Bsf, 2.3568),
            (BearingLine::Ftf, 0.39828),
        ];
        for (line, order) in expect {
            assert!((g.order(line) - order).abs() < 2e-4, "{}: {} vs {order}", line.name(), g.order(line));
        }
        // BPFO + BPFI = n.
        assert!((g.order(BearingLine::Bpfo) + g.order(BearingLine::Bpfi) - 9.0).abs() < 1e-12);
    }

    #[test]
    fn nonsense_geometry_is_refused() {
        let g = BearingGeometry { balls: 9, ball_diameter: 0.05, pitch_diameter: 0.04, contact_angle_deg: 0.0 };
        assert!(g.validate().unwrap_err().contains("ball_diameter < pitch_diameter"));
    }
}
