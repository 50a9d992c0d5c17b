//! The third part of `edgekf demo`: a loose joint in the slider-crank, named and measured by
//! the fast estimator the node runs, on a recording it was not trained on.

use super::estimate::model::{FastModel, ModelEstimate};
use super::estimate::Recording;
use super::{CrankConfig, CrankRecording, Joint, Mechanism, SimOptions};

/// The demo's loose joint, its clearance (m), release angle (degrees), journal radius factor
/// and noise seed: a draw inside the model's training ranges but not one of its runs.
const CASE: (Joint, f64, f64, f64, u64) = (Joint::B, 0.3e-3, 34.0, 1.1, 4242);

/// The run: the recording and what the fast estimator made of it.
#[derive(Debug, Clone)]
pub struct CrankDemo {
    /// 10 s of the paper's mechanism (symplectic Euler at 1e-5 s, as in the paper).
    pub recording: CrankRecording,
    /// The fast estimator's answer (built-in model).
    pub estimate: ModelEstimate,
    /// Its rows for the estimate file (one per window, then the whole recording).
    pub rows: Vec<super::estimate::EstimateRow>,
}

impl CrankDemo {
    /// One line on what the demo does.
    pub fn describe() -> String {
        let (joint, c, angle, radius, _) = CASE;
        format!(
            "slider-crank: {:.2} mm of clearance at joint {joint}, released at {angle}° with journals ×{radius} the configured radius; the node's fast estimator names the joint and sizes it from 10 s of crank acceleration",
            c * 1e3
        )
    }

    /// Simulates and estimates.
    pub fn run() -> anyhow::Result<Self> {
        let (joint, c, angle, radius, seed) = CASE;
        let mut cfg = CrankConfig::default();
        cfg.release.crank_angle_deg = angle;
        cfg.contact.journal_radius *= radius;
        let mut clearances = [None; 3];
        clearances[joint.index()] = Some(c);
        let recording =
            Mechanism::new(&cfg, clearances)?.simulate(&SimOptions { seed, ..SimOptions::from_config(&cfg, 10.0) })?;
        let rec = Recording::from_simulation(&recording, cfg.sensor.sample_rate);
        let model = FastModel::builtin();
        let estimate = model.estimate(&rec)?;
        Ok(Self { rows: model.rows(&rec, &estimate)?, estimate, recording })
    }

    /// The truth and the estimate, one line each.
    pub fn summary(&self) -> String {
        let (joint, c, ..) = CASE;
        let e = &self.estimate;
        let named = e.clearance[e.joint.index()];
        let law = match (e.release, e.features.release) {
            (Some(h), Some(r)) => format!(
                "the first contact after release, seen at {:.1} ms (contact {} after release)",
                r.contact * 1e3,
                h + 1
            ),
            _ => "the window features (no release law fits)".to_string(),
        };
        format!(
            "  truth: joint {joint}, {:.4} mm\n  estimate: joint {}, {:.4} mm ({:+.1} %), from {law}; the window features alone {:.4} mm ({:+.1} %)\n  cost: {} arithmetic operations for the 10 s\n",
            c * 1e3,
            e.joint,
            named * 1e3,
            (named / c - 1.0) * 100.0,
            e.per_joint[joint.index()] * 1e3,
            (e.per_joint[joint.index()] / c - 1.0) * 100.0,
            e.operations
        )
    }
}
