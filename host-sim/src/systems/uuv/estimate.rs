//! The shared estimator (`edgekf::systems::uuv::UuvEstimator`) over a data file, in `f64`:
//! the same code the node runs in `f32`.

use super::config::UuvConfig;
use super::error::UuvError;
use crate::io::data::{format_value, DataFile};
use edgekf::systems::uuv::{Command, Estimate, Sample, Status, UuvEstimator};

/// The input channels the estimator needs.
pub const REQUIRED: [&str; 15] = super::simulate::MEASURED;

/// Numeric output columns after `t` and before the status columns (which are words).
pub const NUMERIC: [&str; 4] = ["k_t", "k_v", "k_t_std", "k_v_std"];

/// State columns after the status columns.
pub const STATE: [&str; 12] = ["x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r"];

/// Nuisance columns last (empty where the filter does not carry them).
pub const NUISANCE: [&str; 9] = [
    "current_n",
    "current_e",
    "acc_bias_x",
    "acc_bias_y",
    "acc_bias_z",
    "gyro_bias_x",
    "gyro_bias_y",
    "gyro_bias_z",
    "imu_nis",
];

/// One estimate per row of the data.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimateTable {
    /// Row times, s.
    pub t: Vec<f64>,
    /// [`NUMERIC`], then [`STATE`], then [`NUISANCE`] columns (NaN: none).
    pub columns: Vec<Vec<f64>>,
    /// Main and vertical thrusters' status per row (`None`: no health state).
    pub status: [Vec<Option<Status>>; 2],
    /// CUSUM alarms of the main and vertical thrusters over the run.
    pub alarms: [u32; 2],
    /// Covariance resets and refused updates of the filter over the run.
    pub repairs: (u32, u32),
}

impl EstimateTable {
    /// The numeric column called `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        NUMERIC.iter().chain(&STATE).chain(&NUISANCE).position(|n| *n == name).map(|i| self.columns[i].as_slice())
    }

    /// The estimate CSV: `t, k_t, k_v, k_t_std, k_v_std, status_t, status_v`, the state, the
    /// nuisance states; missing values empty.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("t,k_t,k_v,k_t_std,k_v_std,status_t,status_v");
        for n in STATE.iter().chain(&NUISANCE) {
            out.push(',');
            out.push_str(n);
        }
        out.push('\n');
        let cell = |out: &mut String, v: f64| {
            out.push(',');
            if v.is_finite() {
                out.push_str(&format_value(v));
            }
        };
        for (row, t) in self.t.iter().enumerate() {
            out.push_str(&format_value(*t));
            for col in &self.columns[..NUMERIC.len()] {
                cell(&mut out, col[row]);
            }
            for s in &self.status {
                out.push(',');
                out.push_str(s[row].map_or("", Status::name));
            }
            for col in &self.columns[NUMERIC.len()..] {
                cell(&mut out, col[row]);
            }
            out.push('\n');
        }
        out
    }
}

/// Runs the estimator of `config` over `data` (on one timeline), starting again at each row of
/// `restarts`.
pub fn estimate(config: &UuvConfig, data: &DataFile, restarts: &[usize]) -> Result<EstimateTable, UuvError> {
    let layout = config.estimator.layout();
    match layout.len() {
        10 => run::<10>(config, data, restarts),
        11 => run::<11>(config, data, restarts),
        12 => run::<12>(config, data, restarts),
        13 => run::<13>(config, data, restarts),
        14 => run::<14>(config, data, restarts),
        16 => run::<16>(config, data, restarts),
        17 => run::<17>(config, data, restarts),
        18 => run::<18>(config, data, restarts),
        19 => run::<19>(config, data, restarts),
        20 => run::<20>(config, data, restarts),
        n => Err(UuvError::Config(format!("[estimator]: no filter of {n} states"))),
    }
}

/// The data's columns as the estimator's samples.
pub fn samples(data: &DataFile) -> Result<Vec<Sample<f64>>, UuvError> {
    let mut cols = Vec::new();
    for name in REQUIRED {
        cols.push(data.column(name).ok_or_else(|| UuvError::Options(format!("the data has no `{name}` column")))?);
    }
    Ok((0..data.len())
        .map(|k| {
            let v = |i: usize| cols[i][k];
            let dvl = [v(8), v(9), v(10)];
            Sample {
                acc: [v(0), v(1), v(2)],
                gyro: [v(3), v(4), v(5)],
                depth: v(6),
                heading: v(7),
                dvl: dvl.iter().all(|d| d.is_finite()).then_some(dvl),
                command: Command { n_t: v(11), n_v: v(12), rudder: v(13), elevator: v(14) },
            }
        })
        .collect())
}

fn run<const N: usize>(config: &UuvConfig, data: &DataFile, restarts: &[usize]) -> Result<EstimateTable, UuvError> {
    let settings = config.estimator.settings(config.sensors.rate);
    let new = || {
        UuvEstimator::<f64, N>::new(&config.vehicle, &settings)
            .map_err(|e| UuvError::Config(format!("[estimator]: the filter cannot be built: {e:?}")))
    };
    let mut est = new()?;
    let rows = samples(data)?;
    let width = NUMERIC.len() + STATE.len() + NUISANCE.len();
    let mut table = EstimateTable {
        t: data.t.clone(),
        columns: vec![Vec::with_capacity(rows.len()); width],
        status: [Vec::with_capacity(rows.len()), Vec::with_capacity(rows.len())],
        alarms: [0; 2],
        repairs: (0, 0),
    };
    let add_repairs = |est: &UuvEstimator<f64, N>, table: &mut EstimateTable| {
        let h = est.health();
        table.repairs.0 += h.covariance_resets;
        table.repairs.1 += h.refused_updates;
    };
    for (k, s) in rows.iter().enumerate() {
        if restarts.contains(&k) {
            add_repairs(&est, &mut table);
            est = new()?;
        }
        let e = est.step(s);
        push_row(&mut table, &e);
    }
    add_repairs(&est, &mut table);
    Ok(table)
}

fn push_row(table: &mut EstimateTable, e: &Estimate<f64>) {
    let nan = f64::NAN;
    let (kt, kv) = (e.main, e.vertical);
    let mut row = vec![
        kt.map_or(nan, |h| h.k),
        kv.map_or(nan, |h| h.k),
        kt.map_or(nan, |h| h.sd),
        kv.map_or(nan, |h| h.sd),
        e.position[0],
        e.position[1],
        e.z,
    ];
    row.extend(e.attitude);
    row.extend(e.nu);
    row.extend(e.current.unwrap_or([nan; 2]));
    row.extend(e.acc_bias.unwrap_or([nan; 3]));
    row.extend(e.gyro_bias.unwrap_or([nan; 3]));
    row.push(e.imu_nis.unwrap_or(nan));
    for (col, v) in table.columns.iter_mut().zip(row) {
        col.push(v);
    }
    table.status[0].push(kt.map(|h| h.status));
    table.status[1].push(kv.map(|h| h.status));
    for (a, h) in table.alarms.iter_mut().zip([kt, kv]) {
        if let Some(h) = h {
            *a = h.alarms;
        }
    }
}
