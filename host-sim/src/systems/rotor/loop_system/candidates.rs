//! The rotor's candidates for the loop's next effect: what a signature names directly (a bias,
//! a line at an order, a line at neither an order nor a natural frequency), then the
//! structural effects, then the catch-all; a force or a mass that may act at any node is tried
//! at the few nodes whose inputs explain most of the innovations at its lines
//! ([`locate`](crate::diagnostics::locate)).

use super::effects::{force_columns, AugmentedModel, Effect, Parameter};
use super::RotorSystem;
use crate::diagnostics::locate::{self, open_loop, C64};
use crate::residual_loop::filter::Run;
use crate::residual_loop::RunSummary;
use nalgebra::DMatrix;
use std::f64::consts::TAU;

/// How many nodes a force at an order or a point mass is fitted at: the ones whose inputs
/// explain most of the innovations at its lines.
pub const PLACES: usize = 3;

/// At most this many nodes for a force when more explain as much as the best.
const MAX_PLACES: usize = 8;

/// Shares of the innovations that close to the best's are ties.
const TIED_SHARE: f64 = 1e-3;

/// The input a node is ranked for.
#[derive(Debug, Clone, Copy)]
enum Input {
    /// A force rotating forward (one direction per node).
    Rotating,
    /// A mass's inertial force, `x` and `y` independent.
    Inertial,
}

impl RotorSystem<'_> {
    /// Candidates named directly by a signature (a bias, a line at an order, a bearing line or
    /// elsewhere), then the structural ones (scales, delays, parameters, point masses) when the
    /// innovations carry lines or colour; the catch-all (`unknown_input` at each force site) in
    /// a tier of its own. A force at an order and a point mass may act at any node: they are
    /// tried at the [`PLACES`] nodes whose inputs explain most of the innovations at their
    /// lines ([`locate`]).
    pub(super) fn propose(&self, s: &RunSummary, run: &Run, model: &AugmentedModel) -> Vec<Vec<Effect>> {
        let mut named = Vec::new();
        let mut biased: Vec<(f64, usize)> = s
            .channels
            .iter()
            .enumerate()
            .filter(|(_, c)| c.z.abs() >= self.options.signatures.bias_z)
            .map(|(i, c)| (c.z.abs(), i))
            .collect();
        biased.sort_by(|a, b| b.0.total_cmp(&a.0));
        named.extend(biased.into_iter().map(|(_, channel)| Effect::SensorBias { channel }));
        let mut structural = false;
        let mut modes: Vec<u32> = Vec::new();
        let mut orders: Vec<(f64, u32)> = Vec::new();
        for c in &s.channels {
            if c.whiteness_p < self.options.signatures.alpha || !c.peaks.is_empty() {
                structural = true;
            }
            for p in &c.peaks {
                if p.line.is_some() {
                    // A bearing line in the spectrum itself: the envelope stage looks for defects.
                    continue;
                } else if let Some(k) = p.order {
                    match orders.iter_mut().find(|(_, o)| *o == k) {
                        Some(e) => e.0 = e.0.max(p.prominence_db),
                        None => orders.push((p.prominence_db, k)),
                    }
                } else if p.class == "unexplained" {
                    let mhz = (p.frequency_hz * 1e3).round() as u32;
                    let near = |m: &u32| (*m as f64 - mhz as f64).abs() * 1e-3 < 2.0 * s.bin_width_hz;
                    if !modes.iter().any(near) {
                        modes.push(mhz);
                    }
                }
            }
        }
        orders.sort_by(|a, b| b.0.total_cmp(&a.0));
        let shaft_hz = self.red.speed / TAU;
        let mut ties = Vec::new();
        for (_, order) in orders {
            let (places, tied) = self.places(run, model, &[order as f64 * shaft_hz], order, Input::Rotating);
            ties.push((order, tied));
            for node in places {
                if order == 1 && self.red.force_nodes.contains(&node) {
                    continue;
                }
                named.push(Effect::HarmonicForce { node, order });
            }
        }
        named.extend(modes.into_iter().map(|seed_mhz| Effect::ExtraMode { seed_mhz }));
        if structural || !s.nis_consistent {
            // With a baseline the sensors are as it found them: a sensor's scale, delay and
            // lag do not change between a healthy and a faulty record of the same rig.
            for channel in (0..self.channels()).filter(|_| self.baseline.is_none()) {
                named.push(Effect::SensorScale { channel });
                named.push(Effect::SensorDelay { channel });
                named.push(Effect::SensorLag { channel });
            }
            named.extend(Parameter::all(self.cfg).into_iter().map(Effect::Parameter));
            // A mass changes the 1× response and the natural frequencies: its inertial force at
            // the node, in x and y alike. One at a disk is that disk's mass (a parameter).
            let mut lines = vec![shaft_hz];
            lines.extend(
                s.channels
                    .iter()
                    .flat_map(|c| &c.peaks)
                    .filter(|p| p.class.starts_with("natural"))
                    .map(|p| p.frequency_hz),
            );
            let disks = self.disk_nodes();
            let nodes =
                self.places(run, model, &lines, 1, Input::Inertial).0.into_iter().filter(|n| !disks.contains(n));
            named.extend(nodes.map(|node| Effect::PointMass { node }));
        }
        let catch_all = self.force_sites.iter().map(|&node| Effect::UnknownInput { node }).collect();
        if let Ok(mut stored) = self.steady_ties.lock() {
            *stored = ties;
        }
        vec![named, catch_all]
    }

    /// The other nodes whose force at `order` was proposed as tied with `node`'s in the last
    /// proposal (see [`places`](Self::places)).
    pub(super) fn steady_rivals(&self, node: usize, order: u32) -> Vec<usize> {
        let Ok(stored) = self.steady_ties.lock() else { return Vec::new() };
        let tied = stored.iter().find(|(o, _)| *o == order).map_or(&[][..], |(_, t)| t.as_slice());
        if !tied.contains(&node) {
            return Vec::new();
        }
        tied.iter().copied().filter(|&n| n != node).collect()
    }

    /// The [`PLACES`] nodes of the shaft where an `input` at `order`'s columns explains most of
    /// the innovations of `run` (made with `model`) at the lines `hz`, for a force any further
    /// ones that explain as much (up to eight); all the force sites if nothing can be ranked
    /// (the engine then fits a winner's neighbours: [`Rivals::neighbours`](crate::residual_loop::Rivals)). Second, of those, the nodes whose force explains as much as the best's (within
    /// [`TIED_SHARE`]): the sensors see the same response from each, up to the force's own
    /// amplitude and phase (at one housing, a 1× force at any node).
    fn places(
        &self,
        run: &Run,
        model: &AugmentedModel,
        hz: &[f64],
        order: u32,
        input: Input,
    ) -> (Vec<usize>, Vec<usize>) {
        let nodes = self.red.displacement.nrows() / 2;
        let n = model.a.nrows();
        let columns: Vec<(usize, DMatrix<f64>, DMatrix<f64>)> = (0..nodes)
            .filter_map(|node| {
                let (b, d) = force_columns(&self.red, self.model, &self.flex, node, order).ok()?;
                let mut padded = DMatrix::<f64>::zeros(n, 2);
                let rows = b.nrows().min(n);
                padded.view_mut((0, 0), (rows, 2)).copy_from(&b.rows(0, rows));
                Some((node, padded, d))
            })
            .collect();
        let response = |i: &usize, f: f64| {
            let (_, b, d) = &columns[*i];
            let y = open_loop(&model.a, b, &model.c, d, f)?;
            Some(match input {
                // Forward: F_y lags F_x by a quarter turn, F = (1, −i) c.
                Input::Rotating => {
                    let forward = y.column(0) - y.column(1) * C64::new(0.0, 1.0);
                    DMatrix::from_column_slice(forward.nrows(), 1, forward.as_slice())
                }
                Input::Inertial => y,
            })
        };
        let ranked = locate::rank(run, hz, self.red.sample_rate, (0..columns.len()).collect(), response);
        if ranked.is_empty() {
            return (self.force_sites.clone(), Vec::new());
        }
        // A force's nodes the innovations cannot tell apart (a lever's worth of nodes on an
        // overhang) are all fitted, so that the fits list them as rivals; a mass's fits cost
        // dozens of runs each, so it keeps to the best few.
        let best = ranked[0].explained;
        let tied = |i: usize, p: &locate::Placement<usize>| {
            i < PLACES || (matches!(input, Input::Rotating) && i < MAX_PLACES && p.explained >= best - TIED_SHARE)
        };
        let places: Vec<usize> =
            ranked.iter().enumerate().take_while(|(i, p)| tied(*i, p)).map(|(_, p)| columns[p.location].0).collect();
        let same = ranked
            .iter()
            .take(places.len())
            .filter(|p| matches!(input, Input::Rotating) && p.explained >= best - TIED_SHARE)
            .map(|p| columns[p.location].0)
            .collect();
        (places, same)
    }
}
