//! The sigma points' simulations of one window: every member of every sigma point from its
//! carried state, on rayon, and the ensembles' means and pooled spread.

use super::UkfOptions;
use crate::systems::crank::feature::spectral_feature;
use crate::systems::crank::integrate::Integrator;
use crate::systems::crank::parallel::map_in_order;
use crate::systems::crank::{CrankConfig, CrankError, Mechanism, SimOptions, State};

/// One simulated member: its mechanism and where it stopped.
pub(super) type Carried = (Mechanism, State);

/// A member's result: sigma point, member, feature, where it stopped, integration steps.
type Member = (usize, usize, f64, Carried, u64);

/// What the ensembles of the three sigma points gave for one window.
pub(super) struct Ensembles {
    /// Mean feature per sigma point.
    pub(super) mean: [f64; 3],
    /// Pooled variance of a member's feature about its sigma point's mean.
    pub(super) var: f64,
    /// Final states, per sigma point, per member.
    pub(super) carried: Vec<Vec<Carried>>,
    pub(super) steps: u64,
}

pub(super) struct Simulator<'a> {
    pub(super) config: &'a CrankConfig,
    pub(super) opts: &'a UkfOptions,
    pub(super) sample_rate: f64,
    pub(super) window_s: f64,
    pub(super) integrator: Integrator,
}

impl Simulator<'_> {
    /// Simulates window `k` for sigma points `xs`, every member from its carried state (or
    /// from its release state if `from` is `None`).
    pub(super) fn window(
        &self,
        k: usize,
        xs: [f64; 3],
        from: Option<&Vec<Vec<Carried>>>,
    ) -> Result<Ensembles, CrankError> {
        let m = self.opts.members.max(1);
        let jobs: Vec<(usize, usize)> = (0..3).flat_map(|i| (0..m).map(move |j| (i, j))).collect();
        let results =
            map_in_order(self.opts.threads, &jobs, |_, &(i, j)| self.member(k, xs[i], i, j, from.map(|f| &f[i][j])));
        let mut feats = vec![vec![0.0; m]; 3];
        let mut carried: Vec<Vec<Option<Carried>>> = (0..3).map(|_| (0..m).map(|_| None).collect()).collect();
        let mut steps = 0;
        for r in results {
            let (i, j, a, c, st) = r?;
            feats[i][j] = a;
            carried[i][j] = Some(c);
            steps += st;
        }
        let mean = [0, 1, 2].map(|i| feats[i].iter().sum::<f64>() / m as f64);
        let var = if m > 1 {
            (0..3).map(|i| feats[i].iter().map(|a| (a - mean[i]).powi(2)).sum::<f64>()).sum::<f64>()
                / (3 * (m - 1)) as f64
        } else {
            0.0
        };
        let carried =
            carried.into_iter().map(|v| v.into_iter().map(|c| c.expect("every member simulated")).collect()).collect();
        Ok(Ensembles { mean, var, carried, steps })
    }

    fn member(&self, k: usize, c: f64, i: usize, j: usize, from: Option<&Carried>) -> Result<Member, CrankError> {
        let mut cfg = *self.config;
        cfg.release.crank_angle_deg += j as f64 * self.opts.member_spacing_deg;
        let mech = Mechanism::new(&cfg, [Some(c), None, None])?;
        let start = match from {
            Some((m, st)) => mech.transfer_state(m, st),
            None => mech.release_state(),
        };
        let sim = SimOptions {
            duration: self.window_s,
            sample_rate: self.sample_rate,
            noise_std: cfg.sensor.noise_std,
            // Common random numbers: member j has the same noise in every sigma point.
            seed: 1 + k as u64 * 1000 + j as u64,
            integrator: self.integrator,
            initial: Some(start),
        };
        let out = mech.simulate(&sim)?;
        let a = spectral_feature(&out.crank_alpha, self.sample_rate)
            .map(|f| f.a)
            .ok_or_else(|| CrankError::Diverged { t: out.final_state.t, reason: "no spectral feature".into() })?;
        Ok((i, j, a, (mech, out.final_state), out.stats.steps))
    }
}
