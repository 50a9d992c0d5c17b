//! The rotor as a [`LoopSystem`]: the reduced virtual-sensing filter of
//! [`rotor_akf`](crate::systems::rotor::estimate) with the effect library of [`effects`], on a data file
//! with the configured sensors' channels.

//!
//! * [`effects`]: the rotor's effect library (`sensor_bias`, `sensor_scale`, `sensor_delay`,
//!   `harmonic_force`, `unknown_input`, `parameter`, `point_mass`, `extra_mode`, `bearing_defect`) composed
//!   onto the reduced rotor's public matrices;
//! * [`speed`]: the running speed read from the data;
//! * [`healthy`]: what a healthy machine shows that the model lacks, as parts of the model;
//!   [`baseline`]: those parts learned from a healthy recording, and what changed since;
//! * [`inject`]: undeclared effects added to simulated data; [`cases`]: the ones the tests and
//!   the README use; [`twin`]: a synthetic twin of the CWRU bearing rig.

pub mod baseline;
pub mod cases;
pub mod effects;
pub mod healthy;
pub mod inject;
pub mod speed;
pub mod twin;

use self::baseline::RotorBaseline;
use self::effects::{
    apply_parameters, augment, force_columns, AugmentedModel, Effect, EffectTuning, Flexibility, Parameter,
};
use self::healthy::Healthy;
use self::speed::{estimate_speed, RunningSpeed};
use crate::diagnostics::bearings::envelope::LineSearch;
use crate::diagnostics::bearings::impacts::{self, ImpactLine};
use crate::diagnostics::locate::{self, open_loop, C64};
use crate::io::data::DataFile;
use crate::residual_loop::filter::{run_state_space, Run, StateSpace};
use crate::residual_loop::onset::settled_mean;
use crate::residual_loop::signature::{summarise, Channel, NamedLine, ReferenceLines, SummaryContext};
use crate::residual_loop::{
    search, Applied, EffectDetail, EffectKind, EffectLabel, Fitting, LoopOptions, LoopReport, LoopSystem, PreStage,
    RunSummary, SystemSection, Traces,
};
use crate::systems::rotor::bearing_geometry::BearingLine;
use crate::systems::rotor::estimate::Tuning;
use crate::systems::rotor::estimate::{reduce, ReducedRotor};
use crate::systems::rotor::{RotorConfig, RotorModel};
use anyhow::{anyhow, Result};
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

/// The rotor's own settings of the loop: its filter's tuning, its effects' noise and priors,
/// and whether the running speed is read from the data.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RotorLoopOptions {
    /// The base filter's tuning (the configuration's `[filter]` section is put in place).
    pub tuning: Tuning,
    /// The effects' noise and priors.
    pub effects: EffectTuning,
    /// Estimate the running speed from the data within this fraction of the configured
    /// (nominal) speed, instead of taking the configured speed as exact.
    pub speed_band: Option<f64>,
    /// How the bearings' defect lines are looked for in the innovations' envelope (the first
    /// stage, [`impacts`]).
    pub envelope: LineSearch,
}

/// A rotor, its data and the loop's options: what [`close_loop`] searches.
pub struct RotorSystem<'a> {
    cfg: &'a RotorConfig,
    model: &'a RotorModel,
    /// The reduced rotor as declared.
    bare: ReducedRotor,
    /// The reduced rotor with the healthy parts in place.
    red: ReducedRotor,
    /// What a healthy machine shows beside the declared model (none without a baseline).
    healthy: Healthy,
    /// The baseline the record is compared with (`baseline_comparison`), if any.
    baseline: Option<RotorBaseline>,
    flex: Flexibility,
    /// Sensor channels with their offsets removed.
    columns: Vec<Vec<f64>>,
    data: &'a DataFile,
    /// Displacement rows estimated (both directions at every force site).
    rows: Vec<usize>,
    row_names: Vec<String>,
    /// Nodes where forces are tried (disks and unbalances).
    force_sites: Vec<usize>,
    /// Bearing lines as orders: (bearing index, line, order), in the order of
    /// `reference.named`.
    lines: Vec<(usize, BearingLine, f64)>,
    /// Where the innovations' lines are placed.
    reference: ReferenceLines,
    /// The sensor channels with their units.
    channel_info: Vec<Channel>,
    /// The virtual-sensing rows (displacements, m).
    row_info: Vec<Channel>,
    /// The running speed used and where it came from.
    speed: RunningSpeed,
    options: LoopOptions,
    rotor: RotorLoopOptions,
}

impl<'a> RotorSystem<'a> {
    /// The rotor `model` (its configured sensors, unbalance nodes, bearings and operating
    /// speed) on `data`, which must have every sensor's channel.
    pub fn new(
        model: &'a RotorModel,
        data: &'a DataFile,
        options: &LoopOptions,
        rotor: &RotorLoopOptions,
    ) -> Result<Self> {
        let hz = model.config().operation.speed / TAU;
        Self::at_speed(
            model,
            data,
            options,
            rotor,
            RunningSpeed { hz, declared_hz: hz, source: "config", spectral_hz: None },
        )
    }

    /// As [`RotorSystem::new`], running at `speed` instead of the configured speed.
    ///
    /// The base filter's noise levels are those of `rotor.tuning` with the configuration's
    /// `[filter]` section put in place.
    pub fn at_speed(
        model: &'a RotorModel,
        data: &'a DataFile,
        options: &LoopOptions,
        rotor: &RotorLoopOptions,
        running: RunningSpeed,
    ) -> Result<Self> {
        Self::healthy(model, data, options, rotor, running, Healthy::default())
    }

    /// As [`RotorSystem::at_speed`], with the `healthy` parts in the base model (a baseline's).
    pub fn healthy(
        model: &'a RotorModel,
        data: &'a DataFile,
        options: &LoopOptions,
        rotor: &RotorLoopOptions,
        running: RunningSpeed,
        healthy: Healthy,
    ) -> Result<Self> {
        Self::build(model, data, options, rotor, running, |_| Ok(healthy))
    }

    /// The system with the healthy parts `parts` gives for the reduced rotor's channels (in the
    /// filter's order): the rotor is reduced once, whatever the parts.
    fn build(
        model: &'a RotorModel,
        data: &'a DataFile,
        options: &LoopOptions,
        rotor: &RotorLoopOptions,
        running: RunningSpeed,
        parts: impl FnOnce(&[String]) -> Result<Healthy>,
    ) -> Result<Self> {
        let cfg = model.config();
        let speed = running.hz * TAU;
        let rotor = &RotorLoopOptions { tuning: rotor.tuning.with_filter(&cfg.filter), ..*rotor };
        let bare = reduce(model, speed, &rotor.tuning)?;
        let healthy = parts(&bare.channels)?;
        let columns: Vec<Vec<f64>> = bare
            .channels
            .iter()
            .zip(&bare.offsets)
            .enumerate()
            .map(|(ch, (name, off))| {
                let off = off + healthy.offset(ch);
                data.column(name)
                    .map(|c| c.iter().map(|v| v - off).collect())
                    .ok_or_else(|| anyhow!("the data file has no channel {name}"))
            })
            .collect::<Result<_>>()?;
        let red = healthy.apply(&bare)?;
        let mut force_sites: Vec<usize> =
            cfg.disks.iter().map(|d| d.node).chain(red.force_nodes.iter().copied()).collect();
        force_sites.sort_unstable();
        force_sites.dedup();
        let rows = force_sites.iter().flat_map(|&n| [2 * n, 2 * n + 1]).collect();
        let row_names: Vec<String> = force_sites.iter().flat_map(|&n| [format!("n{n}_x"), format!("n{n}_y")]).collect();
        let lines: Vec<(usize, BearingLine, f64)> = cfg
            .bearings
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.geometry.map(|g| (i, g)))
            .flat_map(|(i, g)| BearingLine::ALL.map(|l| (i, l, g.order(l))))
            .collect();
        let reference = ReferenceLines {
            speed,
            naturals: red.frequencies_hz.clone(),
            named: lines
                .iter()
                .map(|&(b, l, order)| NamedLine {
                    name: l.name().to_string(),
                    location: format!("bearing {}", cfg.bearings[b].node),
                    hz: order * speed / TAU,
                })
                .collect(),
        };
        let channel_info = red.channels.iter().map(|n| channel(n)).collect();
        let row_info = row_names.iter().map(|n| Channel::new(n.clone(), "m").shown_in(1e6, "µm")).collect();
        Ok(Self {
            cfg,
            model,
            flex: Flexibility::new(model, speed),
            bare,
            red,
            healthy,
            baseline: None,
            columns,
            data,
            rows,
            row_names,
            force_sites,
            lines,
            reference,
            channel_info,
            row_info,
            speed: running,
            options: *options,
            rotor: *rotor,
        })
    }

    fn channels(&self) -> usize {
        self.red.channels.len()
    }

    /// The sensor channels as the filter reads them (offsets removed), `[channel][k]`.
    pub fn columns(&self) -> &[Vec<f64>] {
        &self.columns
    }

    /// The base model's log-likelihood on the data (no effects).
    pub fn base_log_likelihood(&self) -> Result<f64> {
        Ok(self.run(&[])?.1.log_likelihood())
    }

    /// The healthy parts in the base model.
    pub fn healthy_parts(&self) -> &Healthy {
        &self.healthy
    }

    /// The system with `baseline`'s parts in its base model, comparing the record with it in
    /// the report (`baseline_comparison`).
    pub fn from_baseline(
        model: &'a RotorModel,
        data: &'a DataFile,
        options: &LoopOptions,
        rotor: &RotorLoopOptions,
        running: RunningSpeed,
        baseline: &RotorBaseline,
    ) -> Result<Self> {
        let mut sys = Self::build(model, data, options, rotor, running, |channels| baseline.healthy(channels))?;
        sys.baseline = Some(baseline.clone());
        Ok(sys)
    }

    /// The sensor channels' names, in the filter's order.
    pub fn channel_names(&self) -> &[String] {
        &self.red.channels
    }

    /// The unit of channel `name` (`m/s^2`, `m`, `V`).
    pub fn channel_unit(&self, name: &str) -> String {
        channel(name).unit
    }

    /// The data's sample times, s.
    pub fn times(&self) -> &[f64] {
        &self.data.t
    }

    /// Samples per second.
    pub fn sample_rate(&self) -> f64 {
        self.red.sample_rate
    }

    /// Each channel's declared measurement-noise standard deviation per sample.
    pub fn declared_noise(&self) -> Vec<f64> {
        (0..self.channels()).map(|ch| self.bare.r[(ch, ch)].sqrt()).collect()
    }

    /// The disks' nodes.
    pub fn disk_nodes(&self) -> Vec<usize> {
        self.cfg.disks.iter().map(|d| d.node).collect()
    }

    /// The nodes whose unbalance the filter estimates.
    pub fn unbalance_nodes(&self) -> &[usize] {
        &self.red.force_nodes
    }

    /// Runs the filter with `effects` as [`LoopSystem::run`] does, with other healthy parts
    /// in the base model (their offsets are not used: the data's were taken out when the
    /// system was built). How a baseline is fitted.
    pub fn run_healthy(&self, healthy: &Healthy, effects: &[Applied<Effect>]) -> Result<(AugmentedModel, Run)> {
        self.run_on(&healthy.apply(&self.bare)?, healthy, effects)
    }

    /// The filter over the data with `applied` on `red` (the reduced rotor with `healthy`'s
    /// parts in place), re-reducing the rotor when a component parameter is changed.
    fn run_on(
        &self,
        red: &ReducedRotor,
        healthy: &Healthy,
        applied: &[Applied<Effect>],
    ) -> Result<(AugmentedModel, Run)> {
        if applied.iter().any(|e| e.onset_s.is_some()) {
            return Err(anyhow!("the rotor's effects act from the start of the run (no onset)"));
        }
        let effects: Vec<(Effect, f64)> =
            healthy.forces.iter().map(|e| (*e, 0.0)).chain(applied.iter().map(|e| (e.effect, e.theta))).collect();
        let effects = effects.as_slice();
        let cols: Vec<&[f64]> = self.columns.iter().map(Vec::as_slice).collect();
        let dt = 1.0 / red.sample_rate;
        let tuning = &self.rotor.effects;
        let m = if effects.iter().any(|(e, _)| e.changes_structure()) {
            let cfg = apply_parameters(self.cfg, effects)?;
            let model = RotorModel::from_config(&cfg)?;
            let red = healthy.apply(&reduce(&model, red.speed, &self.rotor.tuning)?)?;
            let flex = Flexibility::new(&model, red.speed);
            augment(&red, &model, &flex, effects, tuning)?
        } else {
            augment(red, self.model, &self.flex, effects, tuning)?
        };
        let run = run_filter(&m, dt, &cols, &self.rows)?;
        Ok((m, run))
    }

    /// The [`PLACES`] nodes of the shaft where an `input` at `order`'s columns explains most of
    /// the innovations of `run` (made with `model`) at the lines `hz`, and for a force any
    /// further ones that explain as much (up to eight); all the force sites if nothing can be
    /// ranked.
    fn places(&self, run: &Run, model: &AugmentedModel, hz: &[f64], order: u32, input: Input) -> Vec<usize> {
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
            return self.force_sites.clone();
        }
        // A force's nodes the innovations cannot tell apart (a lever's worth of nodes on an
        // overhang) are all fitted, so that the fits list them as rivals; a mass's fits cost
        // dozens of runs each, so it keeps to the best few.
        let best = ranked[0].explained;
        let tied = |i: usize, p: &locate::Placement<usize>| {
            i < PLACES || (matches!(input, Input::Rotating) && i < MAX_PLACES && p.explained >= best - TIED_SHARE)
        };
        ranked.iter().enumerate().take_while(|(i, p)| tied(*i, p)).map(|(_, p)| columns[p.location].0).collect()
    }

    /// The running speed, Hz, and where it came from.
    pub fn speed(&self) -> RunningSpeed {
        self.speed
    }

    /// The unbalance at each unbalance node in the model of `run`, kg·m: the settled size of
    /// its force phasor over Ω².
    pub fn unbalance(&self, model: &AugmentedModel, run: &Run) -> Vec<(usize, f64)> {
        let first = model.effects.iter().map(|(e, _, _)| e.states(self.channels())).sum::<usize>();
        let s = &run.effect_states;
        let w2 = self.red.speed.powi(2);
        self.red
            .force_nodes
            .iter()
            .enumerate()
            .map(|(j, &node)| {
                let (x, y) = (&s[first + 2 * j], &s[first + 2 * j + 1]);
                let size: Vec<f64> = x.iter().zip(y).map(|(a, b)| a.hypot(*b)).collect();
                (node, settled_mean(&size, 0) / w2)
            })
            .collect()
    }

    /// Every defect line of every bearing with a geometry, at the running speed: an inner-race
    /// defect turns with the shaft through the load zone (modulated at the shaft's rate), a
    /// rolling element with the cage (at the cage's, FTF). A line found on an integer order of
    /// the shaft speed is refused by the stage (a synchronous modulation looks the same).
    fn impact_lines(&self) -> Vec<ImpactLine<Effect>> {
        let shaft_hz = self.red.speed / TAU;
        self.lines
            .iter()
            .map(|&(bearing, line, order)| {
                let cage = self.lines.iter().find(|(b, l, _)| *b == bearing && *l == BearingLine::Ftf).map(|x| x.2);
                let modulation_hz = match line {
                    BearingLine::Bpfi => Some(shaft_hz),
                    BearingLine::Bsf => cage.map(|c| c * shaft_hz),
                    BearingLine::Bpfo | BearingLine::Ftf => None,
                };
                let order_milli = (order * 1e3).round() as u32;
                ImpactLine {
                    effect: Effect::BearingDefect { bearing, line, order_milli },
                    hz: order * shaft_hz,
                    modulation_hz,
                    synchronous_hz: Some(shaft_hz),
                }
            })
            .collect()
    }

    /// Takes `signal` (in the channel's unit) out of channel `channel` of the data: the
    /// vibration of the impacts the first stage found, so that later runs do not see it.
    fn subtract(&mut self, channel: usize, signal: &[f64]) -> Result<()> {
        let col = self.columns.get_mut(channel).ok_or_else(|| anyhow!("no channel #{channel}"))?;
        if col.len() != signal.len() {
            return Err(anyhow!("a signal of {} samples for a channel of {}", signal.len(), col.len()));
        }
        col.iter_mut().zip(signal).for_each(|(v, s)| *v -= s);
        Ok(())
    }
}

impl LoopSystem for RotorSystem<'_> {
    type Effect = Effect;
    type Model = AugmentedModel;

    fn name(&self) -> &str {
        "rotor"
    }

    /// Composes the augmented model (the healthy parts, then the effects; re-reducing the
    /// rotor when a component parameter is changed) and runs the filter over the data.
    fn run(&self, applied: &[Applied<Effect>]) -> Result<(AugmentedModel, Run)> {
        self.run_on(&self.red, &self.healthy, applied)
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let truth: Vec<Option<&[f64]>> =
            self.row_names.iter().map(|n| self.data.column(&format!("truth_{n}"))).collect();
        let ctx = SummaryContext {
            t: &self.data.t,
            channels: &self.channel_info,
            rows: &self.row_info,
            truth: &truth,
            lines: &self.reference,
            sample_rate: self.red.sample_rate,
        };
        summarise(run, &ctx, &self.options.signatures)
    }

    /// Candidates named directly by a signature (a bias, a line at an order, a bearing line or
    /// elsewhere), then the structural ones (scales, delays, parameters, point masses) when the
    /// innovations carry lines or colour; the catch-all (`unknown_input` at each force site) in
    /// a tier of its own. A force at an order and a point mass may act at any node: they are
    /// tried at the [`PLACES`] nodes whose inputs explain most of the innovations at their
    /// lines ([`locate`]).
    fn candidates(
        &self,
        s: &RunSummary,
        run: &Run,
        model: &AugmentedModel,
        _effects: &[Applied<Effect>],
    ) -> Vec<Vec<Effect>> {
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
        for (_, order) in orders {
            for node in self.places(run, model, &[order as f64 * shaft_hz], order, Input::Rotating) {
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
            let nodes = self.places(run, model, &lines, 1, Input::Inertial).into_iter().filter(|n| !disks.contains(n));
            named.extend(nodes.map(|node| Effect::PointMass { node }));
        }
        let catch_all = self.force_sites.iter().map(|&node| Effect::UnknownInput { node }).collect();
        vec![named, catch_all]
    }

    fn label(&self, e: &Effect) -> EffectLabel {
        let detail = EffectDetail {
            order: e.order(),
            parameter: match e {
                Effect::Parameter(p) => Some(p.name().to_string()),
                _ => None,
            },
            line: match e {
                Effect::BearingDefect { line, .. } => Some(line.name().to_string()),
                _ => None,
            },
            ..EffectDetail::default()
        };
        EffectLabel {
            kind: e.kind(),
            location: e.location(&self.red.channels, self.cfg),
            detail,
            unit: match e {
                // A bias is in its channel's unit.
                Effect::SensorBias { channel } => {
                    self.channel_info.get(*channel).map_or_else(|| e.unit().to_string(), |c| c.unit.clone())
                }
                _ => e.unit().to_string(),
            },
        }
    }

    /// Parameters and point masses get a finer grid: a stiffness factor's log-likelihood has
    /// side lobes where a natural frequency crosses a line. A force (harmonic or unknown) may
    /// not exceed `[bounds] force`, by default the rotor's weight: a larger one is the force
    /// standing in for something else.
    fn fitting(&self, e: &Effect) -> Fitting {
        let grid = if e.changes_structure() { 7 } else { 4 };
        Fitting {
            parameters: e.parameters(self.channels()),
            scalar: e.scalar(self.red.sample_rate, &self.cfg.bounds, self.cfg.mass()).map(|r| (r, grid)),
            limit: matches!(e, Effect::HarmonicForce { .. } | Effect::UnknownInput { .. })
                .then(|| self.cfg.bounds.force_n(self.cfg.weight())),
            may_start_mid_run: false,
        }
    }

    /// The fitted scalar (a factor as `exp θ`), or the effect states' size once settled.
    fn value(&self, model: &AugmentedModel, run: &Run, applied: &Applied<Effect>) -> f64 {
        let effect = &applied.effect;
        let Some(pos) = model.effects.iter().position(|(e, _, _)| e == effect) else { return f64::NAN };
        let m = self.channels();
        let offset: usize = model.effects[..pos].iter().map(|(e, _, _)| e.states(m)).sum();
        let from = applied.first_sample(&self.data.t);
        let s = &run.effect_states;
        let settled = |f: &dyn Fn(usize) -> f64| settled_mean(&(0..s[offset].len()).map(f).collect::<Vec<_>>(), from);
        match effect {
            Effect::SensorBias { .. } => settled(&|k| s[offset][k]),
            Effect::HarmonicForce { .. } => settled(&|k| s[offset][k].hypot(s[offset + 1][k])),
            Effect::UnknownInput { .. } => settled(&|k| s[offset][k].powi(2) + s[offset + 1][k].powi(2)).sqrt(),
            Effect::SensorScale { .. } | Effect::SensorLag { .. } | Effect::Parameter(_) | Effect::PointMass { .. } => {
                applied.theta.exp()
            }
            Effect::SensorDelay { .. } | Effect::ExtraMode { .. } => applied.theta,
            // Valued by the envelope stage, which fits it.
            Effect::BearingDefect { .. } => f64::NAN,
        }
    }

    /// Every component parameter (the engine screens them for what the data cannot see).
    fn declared(&self) -> Vec<Effect> {
        Parameter::all(self.cfg).into_iter().map(Effect::Parameter).collect()
    }

    /// The bearings' defects named by their envelope lines ([`impacts`]) and their vibration
    /// taken out of the data; after a defect is named, a broadband stand-in (a mode the model
    /// lacks, a catch-all input) is not fitted: the impacts ring every lightly damped mode.
    fn prestage(&mut self, run: &Run, options: &LoopOptions) -> Result<PreStage<Effect>> {
        let lines = self.impact_lines();
        let traces = self.traces();
        let found = impacts::stage(&lines, |e| self.label(e), run, &traces, &self.rotor.envelope, options.half_gain);
        for (channel, signal) in &found.signals {
            self.subtract(*channel, signal)?;
        }
        if options.progress {
            for (_, a) in &found.added {
                eprintln!(
                    "loop: impacts {} at {}: Δ log-likelihood {:.1}, BIC cost {:.1}",
                    a.kind, a.location, a.delta_log_likelihood, a.bic_penalty
                );
            }
        }
        let excludes = match found.added.first() {
            Some((_, defect)) => [EffectKind::ExtraMode, EffectKind::UnknownInput]
                .map(|kind| {
                    let why = format!(
                        "not fitted: the impacts of the {} at {} ring every lightly damped mode, and a broadband \
                         stand-in fitted after them is their ringing",
                        defect.kind, defect.location
                    );
                    (kind, why)
                })
                .to_vec(),
            None => Vec::new(),
        };
        Ok(PreStage {
            data_changed: !found.signals.is_empty(),
            added: found.added,
            trials: found.trials,
            refused: found.refused,
            excludes,
        })
    }

    fn traces(&self) -> Traces {
        Traces {
            t: self.data.t.clone(),
            channels: self.channel_info.clone(),
            rows: self.row_info.clone(),
            truth: self
                .row_names
                .iter()
                .map(|n| self.data.column(&format!("truth_{n}")).map(<[f64]>::to_vec))
                .collect(),
            ..Traces::default()
        }
    }

    /// `running_speed`: the speed the loop used and where it came from; with a baseline, the
    /// baseline it started from (`baseline`) and the record's levels beside its
    /// (`baseline_comparison`).
    fn section(&self, model: &AugmentedModel, run: &Run) -> SystemSection {
        let mut section = SystemSection::default();
        if let Ok(v) = serde_json::to_value(self.speed) {
            section.fields.insert("running_speed".into(), v);
        }
        section.lines.push(("running speed".into(), self.speed.describe()));
        if let Some(b) = &self.baseline {
            let about = serde_json::json!({
                "condition": b.condition,
                "data": b.source.data,
                "data_sha256": b.source.data_sha256,
                "speed_hz": b.speed_hz,
                "resonances": b.resonances.len(),
                "synchronous_forces": b.forces.len(),
            });
            section.fields.insert("baseline".into(), about);
            let what = b.condition.as_deref().map(|c| format!(" ({c})")).unwrap_or_default();
            section.lines.push(("baseline".into(), format!("learned on {}{what}", b.source.data)));
            let rows = b.compare(self, model, run);
            for c in &rows {
                section.lines.push(("compared".into(), c.describe()));
            }
            if let Ok(v) = serde_json::to_value(&rows) {
                section.fields.insert("baseline_comparison".into(), v);
            }
        }
        section
    }
}

/// A sensor channel of the rotor with its unit: displacement probes in m (shown in µm),
/// accelerometers in m/s², raw accelerometer outputs in V.
fn channel(name: &str) -> Channel {
    if name.ends_with("_volts") {
        Channel::new(name, "V")
    } else if name.ends_with("_ax") || name.ends_with("_ay") {
        Channel::new(name, "m/s^2").shown_in(1.0, "m/s²")
    } else {
        Channel::new(name, "m").shown_in(1e6, "µm")
    }
}

/// Closes the loop on `data` with the rotor `model` (its configured sensors, unbalance nodes,
/// bearings and operating speed): runs the base filter, then adds effects while the
/// innovations are not consistent and an effect pays for its parameters (BIC) in both halves of
/// the run.
///
/// With [`RotorLoopOptions::speed_band`] the running speed is first estimated from the data
/// ([`estimate_speed`]); the report says which speed was used and where it came from.
pub fn close_loop(
    model: &RotorModel,
    data: &DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
) -> Result<LoopReport> {
    let speed = running_speed(model, data, options, rotor)?;
    search(&mut RotorSystem::at_speed(model, data, options, rotor, speed)?, options)
}

/// As [`close_loop`], asking what changed since `baseline`: its parts (offsets, noise levels,
/// resonances, synchronous forces) are in the base model, only the running speed is read from
/// `data` (within `rotor.speed_band`, default ±10 %), an effect must gain more than
/// [`baseline::FLOOR_MARGIN`] times what the baseline's own record leaves unexplained, and the
/// report compares the record's unbalance and order levels with the baseline's
/// (`baseline_comparison`).
pub fn close_loop_from(
    model: &RotorModel,
    data: &DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
    baseline: &RotorBaseline,
) -> Result<LoopReport> {
    let rotor = &RotorLoopOptions { speed_band: rotor.speed_band.or(Some(0.1)), ..*rotor };
    let options = &LoopOptions { gain_floor: baseline::FLOOR_MARGIN * baseline.gain_floor, ..*options };
    let speed = running_speed(model, data, options, rotor)?;
    search(&mut RotorSystem::from_baseline(model, data, options, rotor, speed, baseline)?, options)
}

/// The configured running speed, or the one read from the data with `rotor.speed_band`.
fn running_speed(
    model: &RotorModel,
    data: &DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
) -> Result<RunningSpeed> {
    let declared_hz = model.config().operation.speed / TAU;
    let Some(band) = rotor.speed_band else {
        return Ok(RunningSpeed { hz: declared_hz, declared_hz, source: "config", spectral_hz: None });
    };
    if options.progress {
        eprintln!("loop: estimating the running speed within ±{:.0} % of {declared_hz:.3} Hz", band * 100.0);
    }
    let s = estimate_speed(model, data, options, rotor, band)?;
    if options.progress {
        eprintln!(
            "loop: running speed {:.4} Hz ({:+.2} % from the configured speed; spectral line at {:.4} Hz)",
            s.hz,
            (s.hz / declared_hz - 1.0) * 100.0,
            s.spectral_hz.unwrap_or(f64::NAN)
        );
    }
    Ok(s)
}

/// Runs the filter of `model` over `columns` (`[channel][k]`, offsets removed) at `dt`, and
/// reports the displacement rows `rows` of the model.
fn run_filter(model: &AugmentedModel, dt: f64, columns: &[&[f64]], rows: &[usize]) -> Result<Run> {
    let n = model.a.nrows();
    let m = model.c.nrows();
    let out_rows = DMatrix::from_fn(rows.len(), n, |i, j| model.displacement[(rows[i], j)]);
    // The effects' states, then the unbalance forces' (read by `RotorSystem::unbalance`).
    let effect_idx: Vec<usize> =
        model.effects.iter().flat_map(|(e, _, s)| *s..*s + e.states(m)).chain(model.unbalance.clone()).collect();
    let ss = StateSpace { a: &model.a, qc: &model.qc, c: &model.c, r: &model.r, p0: &model.p0 };
    run_state_space(&ss, dt, columns, &out_rows, &effect_idx)
}
