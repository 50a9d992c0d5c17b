//! What a system gives the engine: the [`LoopSystem`] trait, how each of its effects is fitted
//! ([`Fitting`]), and what a system's own first stage found before the search ([`PreStage`]).
//!
//! The trait is small on purpose: the runs, the summaries, the effects (declared, proposed,
//! labelled, valued, written into the configuration) and the report's traces are the system's; acceptance, identifiability and
//! the report are the engine's, so they read the same for every system.

use super::correction::Correction;
use super::filter::Run;
use super::optimize::ScalarRange;
use super::report::{AddedEffect, NotIdentifiable, Refused, SystemSection, Traces, Trial};
use super::signature::RunSummary;
use super::vocabulary::{Applied, EffectKind, EffectLabel};
use anyhow::Result;
use std::fmt::Debug;

/// How the engine fits one effect: what it costs, the scalar it searches, what the model
/// allows, and whether it may begin mid-run.
///
/// ```
/// use edgekf_sim::residual_loop::{Fitting, ScalarRange};
/// let bias = Fitting::states(2);
/// assert_eq!((bias.parameters, bias.scalar.is_none(), bias.limit), (2, true, None));
/// let factor = ScalarRange::factor(0.5, 2.0, 1e-4);
/// let stiffness = Fitting { may_start_mid_run: true, ..Fitting::scalar(1, factor, 5) };
/// assert_eq!(stiffness.scalar.map(|(_, grid)| grid), Some(5));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fitting {
    /// Free parameters it costs in the BIC (an onset, when fitted, costs one more).
    pub parameters: usize,
    /// The range of its scalar θ and the grid points to search it with, if it has one (else
    /// only its states are estimated, by the filter).
    pub scalar: Option<(ScalarRange, usize)>,
    /// The largest size the model allows its [`value`](LoopSystem::value) to reach, if it has
    /// one beside its scalar's range (a force's bound): a fit beyond it is refused as
    /// [`OUTSIDE`](super::OUTSIDE) what the model allows.
    pub limit: Option<f64>,
    /// Whether it may begin mid-run (a fault, a knock on the sensor, a part working loose):
    /// the engine then also fits it with an onset and tests the halves of the stretch after
    /// the onset. Only systems whose [`run`](LoopSystem::run) honours [`Applied::onset_s`]
    /// may say yes.
    pub may_start_mid_run: bool,
}

impl Fitting {
    /// An effect whose `parameters` states the filter estimates (no scalar, no bound, present
    /// from the start).
    pub fn states(parameters: usize) -> Self {
        Self { parameters, scalar: None, limit: None, may_start_mid_run: false }
    }

    /// An effect with a scalar in `range`, searched from `grid` points.
    pub fn scalar(parameters: usize, range: ScalarRange, grid: usize) -> Self {
        Self { scalar: Some((range, grid)), ..Self::states(parameters) }
    }
}

/// What a system's own first stage found before the search (the rotor's: periodic impacts
/// named by their envelope lines), in the report's terms: the stage is the system's, handed
/// to [`search_staged`](super::search::search_staged), so that a system without one (most)
/// has nothing to implement for it.
#[derive(Debug, Clone)]
pub struct PreStage<E> {
    /// Effects the stage kept, each with the system's effect it stands for.
    pub added: Vec<(E, AddedEffect)>,
    /// Every fit it tried (iteration 0).
    pub trials: Vec<Trial>,
    /// What it saw but did not keep.
    pub refused: Vec<Refused>,
    /// Kinds the search must not fit after what the stage kept, each with the reason the
    /// report gives (a broadband stand-in after impacts would be their ringing).
    pub excludes: Vec<(EffectKind, String)>,
    /// Whether the stage changed the system's data (took the vibration it explained out), so
    /// that the base model must be run again.
    pub data_changed: bool,
    /// What the stage found the data cannot tell apart (two defects whose lines fit equally).
    pub not_identifiable: Vec<NotIdentifiable>,
}

impl<E> Default for PreStage<E> {
    fn default() -> Self {
        Self {
            added: Vec::new(),
            trials: Vec::new(),
            refused: Vec::new(),
            excludes: Vec::new(),
            data_changed: false,
            not_identifiable: Vec::new(),
        }
    }
}

/// A system the loop can be closed on: a base model with a filter, a library of effects that
/// augment it, and the data. The engine ([`search`](super::search())) asks it for filter runs
/// with a list of effects, for summaries of those runs and for candidates; everything else
/// (acceptance, identifiability, the report) is the engine's.
///
/// An effect is an [`Applied`]: what and where (`Self::Effect`), the scalar θ the engine fits
/// by maximum likelihood when its [`Fitting`] gives it a range (0 otherwise), and, for effects
/// that may start mid-run, the onset the engine fits with it.
pub trait LoopSystem: Sync {
    /// One augmentation at one place.
    type Effect: Copy + PartialEq + Debug + Send + Sync;
    /// What a run was made with (the system reads effect values from it).
    type Model: Send;
    /// The system's name in the report.
    const NAME: &'static str;
    /// Runs the filter with `effects` over the whole recording; an effect with an
    /// [`onset_s`](Applied::onset_s) acts from that time on and is absent before it.
    fn run(&self, effects: &[Applied<Self::Effect>]) -> Result<(Self::Model, Run)>;
    /// The innovations' statistics and the virtual-sensing error of a run.
    fn summarise(&self, run: &Run) -> RunSummary;
    /// The effects whose place the configuration fixes (its component parameters, its
    /// sensors' settings), in a stable order: the engine checks those with a scalar for what
    /// the data cannot see on the final model (a component parameter, [`EffectKind::Parameter`]
    /// as a factor `θ = ln f`, halved and doubled; any other over the range it may take).
    fn declared(&self) -> Vec<Self::Effect>;
    /// Candidates for the next effect, given the current model's `effects`, its `run` (and
    /// what it was made with, `model`) and the run's summary, in tiers: a later tier is tried
    /// only when no candidate of an earlier one is kept (the catch-all goes last). The engine
    /// drops effects already in the model. A system with many places an effect could act
    /// ranks them from the run's innovations ([`locate`](crate::diagnostics::locate)) and
    /// proposes the few they point to. Within a tier the likelier in service comes first
    /// (a platform's load before a damaged section). Where the data cannot choose between two
    /// quantities, the engine adds neither and lists each as not identifiable, the others
    /// named as its rivals (a model corrected in the wrong quantity estimates worse).
    fn candidates(
        &self,
        summary: &RunSummary,
        run: &Run,
        model: &Self::Model,
        effects: &[Applied<Self::Effect>],
    ) -> Vec<Vec<Self::Effect>>;
    /// How `effect` reads in the report, and how the engine fits it (the engine reads the two
    /// halves through [`Described`]).
    fn describe(&self, effect: &Self::Effect) -> (EffectLabel, Fitting);
    /// The size the report gives `effect` in the model of `run` (a state's size over the
    /// settled part of the effect's stretch: [`settled_mean`](super::onset::settled_mean)).
    fn value(&self, model: &Self::Model, run: &Run, effect: &Applied<Self::Effect>) -> f64;
    /// How `effect`, of size `value` in the final model ([`value`](Self::value)), enters the
    /// configuration: the config's own keys for a model or calibration effect, a limit the
    /// node tracks for a fault, or why no key holds it ([`Correction`]).
    fn correction(&self, effect: &Applied<Self::Effect>, value: f64) -> Correction;
    /// Time, channels, virtual rows and truth for the report's plots (the engine fills in
    /// the runs before and after).
    fn traces(&self) -> Traces;
    /// The system's own part of the report, from the model and run the loop ended with (none
    /// by default).
    fn section(&self, _model: &Self::Model, _run: &Run) -> SystemSection {
        SystemSection::default()
    }
    /// Who else could explain what `effect` explains, as the system knows it (none by default;
    /// see [`Rivals`]), with `effects` in the model.
    fn rivals(&self, _effect: &Self::Effect, _effects: &[Applied<Self::Effect>]) -> Rivals<Self::Effect> {
        Rivals::default()
    }
    /// Scales the process noise the engine may set from the data before the search by `scale`
    /// (1: the configuration's) in every later run, and says what that noise covers; `None`,
    /// with nothing scaled, for a system without one (the default; see
    /// [`tuning`](super::tuning)).
    fn scale_noise(&mut self, _scale: f64) -> Option<TunableNoise> {
        None
    }
}

/// The noise a system lets the engine scale: what it covers and the configuration's keys.
#[derive(Debug, Clone, PartialEq)]
pub struct TunableNoise {
    /// What the noise stands for, in a few words ("the velocity and rate").
    pub what: String,
    /// The configuration keys the scale multiplies (each a process noise density), each with
    /// the value in effect (what the key is taken to hold where the configuration leaves it
    /// out).
    pub keys: Vec<(String, f64)>,
}

/// The rivals of an effect that the system knows of beyond what the fits show.
#[derive(Debug, Clone, PartialEq)]
pub struct Rivals<E> {
    /// What the model already carries that takes the effect up whole where the data cannot see
    /// it (a current for a speed sensor's offset at one heading): named as its rivals when the
    /// effect goes to `not_identifiable`.
    pub carried: Vec<E>,
    /// Candidates of the last proposal whose responses at the sensors the system's own
    /// signature analysis finds the same as the effect's up to its own states (a 1× force at
    /// any node of a shaft read at one housing): listed as rivals of the effect when it wins,
    /// whatever gap their fits show.
    pub tied: Vec<E>,
    /// The same effect at the places next to its own (a force at the shaft's neighbouring
    /// nodes): where the system's proposal places an effect only roughly, the engine fits
    /// these too once it wins, moves it to one that fits better, and lists the ones its fit
    /// cannot tell from it.
    pub neighbours: Vec<E>,
}

impl<E> Default for Rivals<E> {
    fn default() -> Self {
        Self { carried: Vec::new(), tied: Vec::new(), neighbours: Vec::new() }
    }
}

/// The halves of [`LoopSystem::describe`] by name, for the engine's code.
pub trait Described: LoopSystem {
    /// How `effect` reads in the report.
    fn label(&self, effect: &Self::Effect) -> EffectLabel {
        self.describe(effect).0
    }
    /// How the engine fits `effect`.
    fn fitting(&self, effect: &Self::Effect) -> Fitting {
        self.describe(effect).1
    }
}

impl<S: LoopSystem> Described for S {}
