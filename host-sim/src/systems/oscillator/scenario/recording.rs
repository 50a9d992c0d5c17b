//! What a simulated scenario produces: the sensor's three axes, the fault instructions for the
//! virtual device, and the truth.

use crate::io::data::{self, DataError, DataFile};
use std::path::Path;

/// One simulated run, column by column (every vector has one entry per sample).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Recording {
    /// Time, s.
    pub t: Vec<f64>,
    /// Accelerometer x axis (on the mode), m/s².
    pub ax: Vec<f64>,
    /// Accelerometer y axis (noise only), m/s².
    pub ay: Vec<f64>,
    /// Accelerometer z axis (noise only), m/s².
    pub az: Vec<f64>,
    /// NACK-burst instruction for the virtual device: transactions to refuse from this sample.
    pub fault_nack: Vec<u8>,
    /// Timeout instruction for the virtual device: transactions to time out from this sample.
    pub fault_timeout: Vec<u8>,
    /// Garbage instruction for the virtual device: transactions to answer with `0xFF` bytes
    /// from this sample.
    pub fault_garbage: Vec<u8>,
    /// Stuck-registers instruction for the virtual device.
    pub fault_stuck: Vec<bool>,
    /// Dropped-sample instruction for the virtual device: it produces nothing for this sample.
    pub fault_drop: Vec<bool>,
    /// Reset instruction for the virtual device: it resets to its defaults at this sample.
    pub fault_reset: Vec<bool>,
    /// True modal displacement, m.
    pub truth_x: Vec<f64>,
    /// True modal velocity, m/s.
    pub truth_v: Vec<f64>,
    /// True total force, N.
    pub truth_force: Vec<f64>,
    /// True amplitude of the harmonic force at the drive frequency, N: what the estimator
    /// reports as `force_amplitude`.
    pub truth_force_amplitude: Vec<f64>,
    /// True modal acceleration, m/s² (before noise, bias, clipping or saturation faults).
    pub truth_accel: Vec<f64>,
}

impl Recording {
    /// The CSV columns after `t`, in order.
    pub const CHANNELS: [&'static str; 14] = [
        "ax",
        "ay",
        "az",
        "fault_nack",
        "fault_timeout",
        "fault_garbage",
        "fault_stuck",
        "fault_drop",
        "fault_reset",
        "truth_x",
        "truth_v",
        "truth_force",
        "truth_force_amplitude",
        "truth_accel",
    ];

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The recording as a [`DataFile`] with the columns of [`Recording::CHANNELS`] (fault
    /// columns as 0/1 and counts).
    pub fn to_data_file(&self) -> DataFile {
        let count = |v: &[u8]| v.iter().map(|&n| f64::from(n)).collect::<Vec<f64>>();
        let flag = |v: &[bool]| v.iter().map(|&s| if s { 1.0 } else { 0.0 }).collect::<Vec<f64>>();
        let columns = vec![
            self.ax.clone(),
            self.ay.clone(),
            self.az.clone(),
            count(&self.fault_nack),
            count(&self.fault_timeout),
            count(&self.fault_garbage),
            flag(&self.fault_stuck),
            flag(&self.fault_drop),
            flag(&self.fault_reset),
            self.truth_x.clone(),
            self.truth_v.clone(),
            self.truth_force.clone(),
            self.truth_force_amplitude.clone(),
            self.truth_accel.clone(),
        ];
        DataFile {
            sha256: None,
            names: Self::CHANNELS.iter().map(|s| s.to_string()).collect(),
            t: self.t.clone(),
            columns,
        }
    }

    /// The CSV text: `t,ax,ay,az,fault_nack,fault_timeout,fault_garbage,fault_stuck,fault_drop,
    /// fault_reset,truth_x,truth_v,truth_force,truth_force_amplitude,truth_accel`, numbers in
    /// shortest round-trip form, fault columns as integers.
    pub fn to_csv_string(&self) -> String {
        self.csv(Path::new("<memory>")).unwrap_or_else(|e| format!("# inconsistent recording: {e}\n"))
    }

    fn csv(&self, path: &Path) -> Result<String, DataError> {
        let file = self.to_data_file();
        let cols: Vec<&[f64]> = file.columns.iter().map(Vec::as_slice).collect();
        data::to_csv_string(path, &Self::CHANNELS, &file.t, &cols)
    }

    /// Writes [`Recording::to_csv_string`] to `path`.
    pub fn write_csv(&self, path: &Path) -> Result<(), DataError> {
        let text = self.csv(path)?;
        crate::io::output::write_atomic(path, text).map_err(|reason| DataError::Write { path: path.to_owned(), reason })
    }
}
