//! The boom's estimators over a data file, in `f64`: the code the node runs in `f32`
//! (`edgekf::systems::boom`). The gyro's AR(2) model and bias come from the configuration where
//! it declares them, else from the static record; the inclinometer's noise from `[inclinometer]
//! noise`, else the static record's `incl_angle` if it has one, else 5e-4 rad.

use super::config::BoomConfig;
use super::simulate::MEASURED;
use crate::io::data::DataFile;
use anyhow::{anyhow, Context, Result};
use clap::ValueEnum;
use edgekf::systems::boom::{Ar2, ModelEstimator, ModelSettings, PaperEstimator, PaperSettings};

/// An estimator of the tip's vibration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// One Kalman filter on the reduced boom with the luffing command as input, the gyro's bias
    /// and AR noise and the inclinometer's lag in its state.
    Model,
    /// The paper's: AR(2) Kalman filter on the gyro, Simpson integration, fusion with the
    /// inclinometer (its declared lag taken out) at the equilibrium instants, `y = α l θ`,
    /// moving average.
    Paper,
}

impl Method {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Model => "model",
            Method::Paper => "paper",
        }
    }
}

/// The output columns after `t`.
pub const COLUMNS: [&str; 3] = ["tip_angle", "tip_vibration", "tip_deflection"];

/// One estimate per row of the data.
#[derive(Debug, Clone, PartialEq)]
pub struct BoomEstimate {
    /// Row times, s.
    pub t: Vec<f64>,
    /// [`COLUMNS`] (NaN where the method gives none: the paper's has no sag model).
    pub columns: [Vec<f64>; 3],
    /// Equilibrium instants fused (the paper's method).
    pub fusions: usize,
}

impl BoomEstimate {
    /// The column `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        COLUMNS.iter().position(|c| *c == name).map(|i| self.columns[i].as_slice())
    }

    /// The estimate CSV (missing values empty).
    pub fn to_csv(&self, path: &std::path::Path) -> Result<String> {
        let cols: Vec<&[f64]> = self.columns.iter().map(Vec::as_slice).collect();
        Ok(crate::io::data::to_csv_string_sparse(path, &COLUMNS, &self.t, &cols)?)
    }
}

/// The gyro's AR(2) model: the configuration's `[gyro] ar`, `noise`, `bias` where given, the
/// rest identified from `static_gyro` (the gyro at rest).
pub fn gyro_model(config: &BoomConfig, static_gyro: &[f64]) -> Result<Ar2> {
    let g = &config.gyro;
    let identified = Ar2::identify(static_gyro).map_err(|e| anyhow!("the static record gives no AR(2) model: {e:?}"));
    let fallback = || identified.as_ref().map_err(|e| anyhow!("{e}"));
    Ok(Ar2 {
        a: match g.ar {
            Some(a) => a,
            None => fallback()?.a,
        },
        sigma: match g.noise {
            Some(s) => s,
            None => fallback()?.sigma,
        },
        mean: match g.bias {
            Some(b) => b,
            None => fallback()?.mean,
        },
    })
}

/// The inclinometer's noise used when neither the configuration nor a static record gives it,
/// rad.
pub const INCLINOMETER_NOISE: f64 = 5e-4;

/// The model-based filter's settings for `config` with the gyro model `ar` and the
/// inclinometer's noise `incl_noise` (rad).
pub fn model_settings(config: &BoomConfig, ar: Ar2, incl_noise: f64) -> Result<ModelSettings> {
    let i = &config.inclinometer;
    let s = ModelSettings::new(
        1.0 / config.gyro.sample_rate,
        config.constants()?,
        config.damping.zeta,
        (config.drive.lag, config.drive.max_accel),
        config.gyro.scale,
        ar,
        (i.lag, i.offset, i.noise.unwrap_or(incl_noise)),
    );
    Ok(s)
}

/// Runs `method` of `config` over `data` with the gyro model `ar`.
pub fn estimate(config: &BoomConfig, data: &DataFile, ar: Ar2, method: Method) -> Result<BoomEstimate> {
    estimate_with(config, data, ar, INCLINOMETER_NOISE, method, &[])
}

/// [`estimate`] with the inclinometer's noise (rad) where the configuration gives none, and
/// the rows where the timeline restarts (a gap too long to bridge): the estimator starts
/// afresh there, as the node does after a reset.
pub fn estimate_with(
    config: &BoomConfig,
    data: &DataFile,
    ar: Ar2,
    incl_noise: f64,
    method: Method,
    restarts: &[usize],
) -> Result<BoomEstimate> {
    let col = |n: &str| data.column(n).ok_or_else(|| anyhow!("the data has no `{n}` column"));
    let (gyro, incl, length) = (col(MEASURED[0])?, col(MEASURED[1])?, col(MEASURED[2])?);
    let dt = 1.0 / config.gyro.sample_rate;
    let n = data.len();
    let mut columns = [vec![f64::NAN; n], vec![f64::NAN; n], vec![f64::NAN; n]];
    let mut fusions = 0;
    // The length to start from at row k: the first finite one from there.
    let length_from = |k: usize| length[k..].iter().copied().find(|l| l.is_finite() && *l > 0.0);
    let mut last_length = length_from(0).context("no finite, positive boom_length")?;
    match method {
        Method::Model => {
            let command = col(MEASURED[3])?;
            let settings = model_settings(config, ar, incl_noise)?;
            let start = |l: f64| {
                ModelEstimator::<f64>::new(&settings, l)
                    .map_err(|e| anyhow!("the model-based filter cannot start: {e:?}"))
            };
            let mut est = start(last_length)?;
            for k in 0..n {
                if restarts.contains(&k) {
                    est = start(length_from(k).unwrap_or(last_length))?;
                }
                let e = est.step(gyro[k], incl[k], length[k], command[k]);
                columns[0][k] = e.tip_angle;
                columns[1][k] = e.vibration;
                columns[2][k] = e.deflection;
            }
        }
        Method::Paper => {
            let settings = PaperSettings::new(dt, ar, config.gyro.scale, config.inclinometer.lag);
            let mut est = PaperEstimator::<f64>::new(&settings);
            for k in 0..n {
                if restarts.contains(&k) {
                    est = PaperEstimator::<f64>::new(&settings);
                }
                if length[k].is_finite() {
                    last_length = length[k];
                }
                let e = est.step(gyro[k], incl[k], last_length);
                columns[0][k] = e.tip_angle;
                columns[1][k] = e.vibration;
                fusions += usize::from(e.fused);
            }
        }
    }
    Ok(BoomEstimate { t: data.t.clone(), columns, fusions })
}
