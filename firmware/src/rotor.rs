//! Rotor virtual sensing on the node: the modally reduced rotor (8 modes, one rotating phasor
//! per unbalance) and its augmented Kalman filter, computed on the host in `f64` and compiled in
//! (`edgekf rotor export --config host-sim/configs/rotor_paper.toml --out
//! firmware/src/generated/rotor.rs`; a cross-crate test checks the file is current).
//!
//! Inputs: the four proximity probes of the paper rotor (`n5_x, n5_y, n32_x, n32_y`, m).
//! Outputs per sample: the x/y displacement of both disk nodes (12 and 23), which no sensor
//! measures, and the unbalance forces there.

use edgekf::export::{matrix, model};
use edgekf::filter::{FilterHealth, KalmanFilter};
use nalgebra::{SMatrix, SVector};

// The steady-state gain (ROTOR_GAIN, ROTOR_S) is exported too, for a cheaper filter once the
// start-up transient is over; the node runs the time-varying filter for now.
#[allow(missing_docs, dead_code, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    include!("generated/rotor.rs");
}

/// States of the reduced model.
pub const STATES: usize = 20;
/// Sensor channels, in the order the filter takes them.
pub const CHANNELS: [&str; 4] = ["n5_x", "n5_y", "n32_x", "n32_y"];
/// Disk nodes whose displacement the node reports.
pub const DISK_NODES: [usize; 2] = [12, 23];

/// One sample's estimates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorReport {
    /// `x, y` of disk node 12 then of disk node 23, m.
    pub disk: [f32; 4],
    /// `F_x, F_y` at node 12 then at node 23, N.
    pub force: [f32; 4],
    /// NIS of this sample's update (NaN if the sample was missing or refused).
    pub nis: f32,
}

/// The filter with its output rows.
pub struct RotorEstimator {
    kf: KalmanFilter<f32, STATES, 4>,
    disk: SMatrix<f32, 4, STATES>,
    force: SMatrix<f32, 4, STATES>,
}

impl Default for RotorEstimator {
    fn default() -> Self {
        Self::new()
    }
}

impl RotorEstimator {
    /// The compiled-in model, starting at rest with the exported prior.
    ///
    /// ```
    /// let mut est = edgekf_firmware::rotor::RotorEstimator::new();
    /// let r = est.step(Some([0.0; 4]));
    /// assert!(r.nis.is_finite());
    /// ```
    pub fn new() -> Self {
        use constants::*;
        let m = model(&ROTOR_A, &ROTOR_C, &ROTOR_Q, &ROTOR_R).cast::<f32>();
        let p0 = matrix(&ROTOR_P0).map(|v| v as f32);
        Self {
            kf: KalmanFilter::new(m, SVector::zeros(), p0),
            disk: matrix(&ROTOR_DISK).map(|v| v as f32),
            force: matrix(&ROTOR_FORCE).map(|v| v as f32),
        }
    }

    /// One sample: update with the probes' reading (`None` if missing), report, then predict
    /// to the next sample.
    pub fn step(&mut self, y: Option<[f32; 4]>) -> RotorReport {
        let nis = match y.map(|v| self.kf.update(&SVector::from(v))) {
            Some(Ok(inn)) => inn.nis,
            _ => f32::NAN,
        };
        let x = self.kf.state();
        let (d, f) = (self.disk * x, self.force * x);
        self.kf.predict();
        RotorReport { disk: [d[0], d[1], d[2], d[3]], force: [f[0], f[1], f[2], f[3]], nis }
    }

    /// Repairs the filter needed (zero in a healthy run).
    pub fn health(&self) -> FilterHealth {
        self.kf.health()
    }
}
