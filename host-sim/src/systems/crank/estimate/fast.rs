//! A fast clearance estimator: features of the crank angular acceleration averaged over the
//! recording, mapped to the clearance by a map learned on the host from the reference
//! simulator. No simulation at run time.
//!
//! The single-feature, joint-A-only predecessor of [`super::model`] (which `edgekf crank
//! estimate --method fast` now uses); kept for old `--model` files with `impact_rate` and
//! `clearance`. Its windows' statistics (the median `|Δα|`, the impact crossings) need every
//! sample, so a recording with a missing one in a window it uses is refused, naming its time.

use super::{EstimateRow, Recording};

/// Recording-level features of the crank angular acceleration (means over windows).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Features {
    /// RMS of the first difference `αₖ − αₖ₋₁`, rad/s² (high-band energy).
    pub diff_rms: f64,
    /// Kurtosis of the first difference (impulsiveness).
    pub diff_kurtosis: f64,
    /// Impacts per second: upward crossings of `|Δα|` over 6 × its median absolute value.
    pub impact_rate: f64,
    /// RMS of α itself.
    pub rms: f64,
    /// Mean absolute value of the first difference.
    pub diff_mean_abs: f64,
    /// Windows averaged.
    pub windows: usize,
    /// Arithmetic operations spent (approximate count: a few per sample).
    pub operations: u64,
}

/// Samples per window of `window_s` at `rate` Hz (at least 8).
fn window_len(rate: f64, window_s: f64) -> usize {
    ((window_s * rate).round() as usize).max(8)
}

/// Features of `x` sampled at `rate` Hz, averaged over windows of `window_s`.
pub fn features(x: &[f64], rate: f64, window_s: f64) -> Features {
    let n = window_len(rate, window_s);
    let mut f = Features::default();
    let mut ops = 0u64;
    for w in x.chunks_exact(n) {
        let d: Vec<f64> = w.windows(2).map(|p| p[1] - p[0]).collect();
        let m = d.len() as f64;
        let s2 = d.iter().map(|v| v * v).sum::<f64>() / m;
        let s4 = d.iter().map(|v| v.powi(4)).sum::<f64>() / m;
        let mabs = d.iter().map(|v| v.abs()).sum::<f64>() / m;
        let mut sorted: Vec<f64> = d.iter().map(|v| v.abs()).collect();
        sorted.sort_by(f64::total_cmp);
        let med = sorted[sorted.len() / 2];
        let thr = 6.0 * med;
        let mut count = 0usize;
        let mut above = false;
        for v in &d {
            let a = v.abs() > thr;
            if a && !above {
                count += 1;
            }
            above = a;
        }
        f.diff_rms += s2.sqrt();
        f.diff_kurtosis += s4 / (s2 * s2).max(1e-300);
        f.impact_rate += count as f64 * rate / n as f64;
        f.rms += (w.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        f.diff_mean_abs += mabs;
        f.windows += 1;
        ops += (12 + (n as f64).log2().ceil() as u64) * n as u64;
    }
    let k = f.windows.max(1) as f64;
    f.diff_rms /= k;
    f.diff_kurtosis /= k;
    f.impact_rate /= k;
    f.rms /= k;
    f.diff_mean_abs /= k;
    f.operations = ops;
    f
}

/// The built-in map: mean impact rate (1/s) of 10 s recordings against the clearance at A (m),
/// each the mean over five runs (release 22°, 30°, 38° with the configured journal radius, and
/// 30° with the journal radius × 0.8 and × 1.2; noise seeds 1–5), paper's mechanism, symplectic
/// Euler at 1e-5 s, 5 rad/s² noise. Scatter of the five runs: ±3 % of the rate at 0.05–0.1 mm,
/// ±5–10 % at 0.2–0.5 mm.
pub const BUILTIN_TABLE: [(f64, f64); 7] = [
    (701.1, 0.05e-3),
    (522.8, 0.10e-3),
    (397.2, 0.20e-3),
    (364.9, 0.25e-3),
    (357.5, 0.30e-3),
    (326.8, 0.40e-3),
    (296.3, 0.50e-3),
];

/// A monotone table from the recording's impact rate to the clearance at A, interpolated
/// linearly in `ln rate` → `ln c` (extrapolated with the end slopes, clamped to 0.01–1 mm).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
pub struct FeatureMap {
    /// Impact rates, 1/s, strictly decreasing.
    pub impact_rate: Vec<f64>,
    /// Clearances at A, m, strictly increasing.
    pub clearance: Vec<f64>,
}

/// Result of the fast estimator.
#[derive(Debug, Clone, PartialEq)]
pub struct FastEstimate {
    /// Clearances A, B, C, m (B and C taken as tight).
    pub clearance: [f64; 3],
    /// The features it was computed from.
    pub features: Features,
    /// Windows used.
    pub windows: usize,
    /// Arithmetic operations spent on the features (about `n (12 + log₂ w)` for `n` samples
    /// and windows of `w`: the median is taken by sorting).
    pub operations: u64,
}

impl FastEstimate {
    /// Rows of the estimate file: one, the whole recording.
    pub fn rows(&self, rec: &Recording) -> Vec<EstimateRow> {
        vec![EstimateRow { t: rec.t.last().copied().unwrap_or(0.0), clearance: self.clearance }]
    }
}

impl FeatureMap {
    /// The built-in map ([`BUILTIN_TABLE`]).
    pub fn builtin() -> Self {
        Self {
            impact_rate: BUILTIN_TABLE.iter().map(|p| p.0).collect(),
            clearance: BUILTIN_TABLE.iter().map(|p| p.1).collect(),
        }
    }

    /// Reads a map from TOML (`impact_rate = [...]`, `clearance = [...]`).
    pub fn load(path: &std::path::Path) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))?;
        let map: Self = crate::io::config::parse_toml(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        map.validate().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        Ok(map)
    }

    fn validate(&self) -> Result<(), String> {
        let (r, c) = (&self.impact_rate, &self.clearance);
        if r.len() != c.len() || r.len() < 2 {
            return Err("impact_rate and clearance must have the same length, at least 2".into());
        }
        let ok = r.iter().chain(c).all(|v| v.is_finite() && *v > 0.0)
            && r.windows(2).all(|w| w[1] < w[0])
            && c.windows(2).all(|w| w[1] > w[0]);
        if !ok {
            return Err("impact_rate must fall and clearance rise strictly, all positive".into());
        }
        Ok(())
    }

    /// The clearance for an impact rate.
    pub fn clearance_for(&self, rate: f64) -> f64 {
        let (r, c) = (&self.impact_rate, &self.clearance);
        let n = r.len();
        let x = rate.max(1e-9).ln();
        // Segment: the first whose lower rate is below x (rates fall), else the last.
        let i = (0..n - 1).find(|&i| x >= r[i + 1].ln()).unwrap_or(n - 2);
        let (x0, x1) = (r[i].ln(), r[i + 1].ln());
        let (y0, y1) = (c[i].ln(), c[i + 1].ln());
        let y = y0 + (x - x0) * (y1 - y0) / (x1 - x0);
        y.exp().clamp(1e-5, 1e-3)
    }

    /// Estimates the clearance at A from a recording (0.25 s windows); refuses one with a
    /// missing sample in those windows.
    pub fn estimate(&self, rec: &Recording) -> anyhow::Result<FastEstimate> {
        self.validate().map_err(|e| anyhow::anyhow!("feature map: {e}"))?;
        let n = window_len(rec.sample_rate, 0.25);
        let why = "the legacy impact-rate map takes statistics of whole windows and needs every sample; \
                   the built-in model (`--method fast` without `--model`) or one from `edgekf crank train` \
                   steps through missing ones";
        rec.require_every_sample(rec.crank_alpha.len() / n * n, why).map_err(anyhow::Error::msg)?;
        let f = features(&rec.crank_alpha, rec.sample_rate, 0.25);
        if f.windows == 0 {
            anyhow::bail!("the recording is shorter than one 0.25 s window");
        }
        Ok(FastEstimate {
            clearance: [self.clearance_for(f.impact_rate), 0.0, 0.0],
            features: f,
            windows: f.windows,
            operations: f.operations,
        })
    }
}
