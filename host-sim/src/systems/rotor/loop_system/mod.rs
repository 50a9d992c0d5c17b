//! The rotor as a [`LoopSystem`]: the reduced virtual-sensing filter of
//! [`rotor_akf`](crate::systems::rotor::estimate) with the effect library of [`effects`], on a data file
//! with the configured sensors' channels.
//!
//! * [`system`]: the [`LoopSystem`] implementation; [`candidates`]: what the loop tries next;
//!   [`bearings`]: the defect lines looked for before the search;
//! * [`effects`]: the rotor's effect library (`sensor_bias`, `sensor_scale`, `sensor_delay`,
//!   `harmonic_force`, `unknown_input`, `parameter`, `point_mass`, `extra_mode`, `bearing_defect`) composed
//!   onto the reduced rotor's public matrices;
//! * [`speed`]: the running speed read from the data;
//! * [`healthy`]: what a healthy machine shows that the model lacks, as parts of the model;
//!   [`baseline`]: those parts learned from a healthy recording, and what changed since;
//! * [`inject`]: undeclared effects added to simulated data; [`cases`]: the ones the tests and
//!   the README use; [`twin`]: a synthetic twin of the CWRU bearing rig.

pub mod baseline;
pub mod bearings;
pub mod candidates;
pub mod cases;
pub mod effects;
mod family_figure;
pub mod healthy;
pub mod inject;
pub mod speed;
pub mod system;
pub mod twin;

use self::baseline::RotorBaseline;
use self::effects::{apply_parameters, augment, AugmentedModel, Effect, EffectTuning, Flexibility};
use self::healthy::Healthy;
use self::speed::{estimate_speed, RunningSpeed};
use crate::diagnostics::bearings::envelope::LineSearch;
use crate::diagnostics::bearings::family::Diagnosis;
use crate::io::data::DataFile;
use crate::residual_loop::filter::{run_state_space, Run, StateSpace};
use crate::residual_loop::onset::settled_mean;
use crate::residual_loop::signature::{Channel, NamedLine, ReferenceLines};
use crate::residual_loop::{Applied, LoopOptions, LoopReport, LoopSystem, Recording};
use crate::systems::rotor::bearing_geometry::BearingLine;
use crate::systems::rotor::estimate::Tuning;
use crate::systems::rotor::estimate::{reduce, ReducedRotor};
use crate::systems::rotor::{RotorConfig, RotorModel};
use anyhow::{anyhow, Result};
use nalgebra::DMatrix;
use std::f64::consts::TAU;
use std::sync::Mutex;

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
    /// The bearings' fault family the raw vibration carries (set by the first stage).
    families: Option<Diagnosis>,
    /// The sensor channels with their units.
    channel_info: Vec<Channel>,
    /// The virtual-sensing rows (displacements, m).
    row_info: Vec<Channel>,
    /// The running speed used and where it came from.
    speed: RunningSpeed,
    options: LoopOptions,
    rotor: RotorLoopOptions,
    /// The nodes of the last proposal whose force at an order explains the innovations' lines
    /// as well as the best node's (per order): their responses at the sensors are the same.
    steady_ties: Mutex<Vec<(u32, Vec<usize>)>>,
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
            families: None,
            channel_info,
            row_info,
            speed: running,
            options: *options,
            rotor: *rotor,
            steady_ties: Mutex::new(Vec::new()),
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

    /// The shaft's nodes, how many.
    pub fn nodes(&self) -> usize {
        self.red.displacement.nrows() / 2
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

    /// The data as the engine reads them: each displacement row's truth where simulated.
    fn recording(&self) -> Recording<'_> {
        let truth = self.row_names.iter().map(|n| self.data.column(&format!("truth_{n}"))).collect();
        let (channels, rows) = (&self.channel_info[..], &self.row_info[..]);
        Recording { t: &self.data.t, channels, rows, truth, sample_rate: self.red.sample_rate }
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
    system_for(model, data, options, rotor)?.search(options)
}

/// The system [`close_loop`] searches: `model` on `data` at its running speed (what an effect
/// matrix asks its detection limits of).
pub fn system_for<'a>(
    model: &'a RotorModel,
    data: &'a DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
) -> Result<RotorSystem<'a>> {
    let speed = running_speed(model, data, options, rotor)?;
    RotorSystem::at_speed(model, data, options, rotor, speed)
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
    let options = &LoopOptions { gain_floor: baseline::FLOOR_MARGIN * baseline.gain_floor, ..*options };
    system_from(model, data, options, rotor, baseline)?.search(options)
}

/// The record's levels beside `baseline`'s (`baseline_comparison`, with their intervals) from
/// the base model alone, without the search: what [`close_loop_from`] reports of a record where
/// it adds nothing, at the cost of one filter run.
pub fn compare_with(
    model: &RotorModel,
    data: &DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
    baseline: &RotorBaseline,
) -> Result<Vec<crate::residual_loop::baseline::Comparison>> {
    let sys = system_from(model, data, options, rotor, baseline)?;
    let (base, run) = sys.run(&[])?;
    Ok(baseline.compare(&sys, &base, &run))
}

/// `model` on `data` with `baseline`'s parts, at the running speed read from `data` (within
/// `rotor.speed_band`, default ±10 %).
fn system_from<'a>(
    model: &'a RotorModel,
    data: &'a DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
    baseline: &RotorBaseline,
) -> Result<RotorSystem<'a>> {
    let rotor = &RotorLoopOptions { speed_band: rotor.speed_band.or(Some(0.1)), ..*rotor };
    let speed = running_speed(model, data, options, rotor)?;
    RotorSystem::from_baseline(model, data, options, rotor, speed, baseline)
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
