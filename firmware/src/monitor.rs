//! The model monitor on the node: any estimator whose steps give each channel's normalised
//! innovation runs [`edgekf::residual::ModelMonitor`] beside it ([`Monitored`]), and the run
//! emits a [`MismatchFrame`] for each channel and statistic that stops fitting the model, once.
//!
//! Why on the node: the estimator's innovations are there at full rate, and a mismatch frame is
//! a few bytes where the innovations would be a stream; the host is told when to look.

pub use crate::mismatch::MismatchFrame;
use crate::node::{Innovation, NodeEstimator, Poll};
use core::ops::{Deref, DerefMut};
use edgekf::residual::{ModelMonitor, MonitorSettings};

/// An estimator whose steps give each of `C` channels' normalised innovation `ν / √S` (the
/// channel's own variance, so each is standard normal while the model holds).
pub trait Normalised<const C: usize>: NodeEstimator {
    /// One step as [`NodeEstimator::step`], also writing each channel's normalised innovation
    /// into `z` (left NaN where the channel had no update).
    fn step_normalised(&mut self, input: Option<Self::Input>, z: &mut [f32; C]) -> Innovation;
}

/// Estimator `E` with a model monitor on its `C` channels. Dereferences to `E`, so an image's
/// end-of-run frames read the estimator as before.
pub struct Monitored<E, const C: usize> {
    estimator: E,
    monitor: ModelMonitor<f32, C>,
}

impl<E: Normalised<C>, const C: usize> Monitored<E, C> {
    /// `estimator` watched with the thresholds `settings` give (the shipped false-alarm rate is
    /// [`MonitorSettings::new`]'s, one per 100 hours of the whole monitor), computed here, once,
    /// in `f64`.
    pub fn new(estimator: E, settings: &MonitorSettings) -> Self {
        Self { estimator, monitor: ModelMonitor::new(&settings.thresholds(C)) }
    }

    /// The monitor (its latches and alarm counts).
    pub fn monitor(&self) -> &ModelMonitor<f32, C> {
        &self.monitor
    }
}

impl<E, const C: usize> Deref for Monitored<E, C> {
    type Target = E;
    fn deref(&self) -> &E {
        &self.estimator
    }
}

impl<E, const C: usize> DerefMut for Monitored<E, C> {
    fn deref_mut(&mut self) -> &mut E {
        &mut self.estimator
    }
}

impl<E: Normalised<C>, const C: usize> NodeEstimator for Monitored<E, C> {
    type Input = E::Input;
    type Frame = E::Frame;

    fn step(&mut self, input: Option<E::Input>) -> Innovation {
        let mut z = [f32::NAN; C];
        let innovation = self.estimator.step_normalised(input, &mut z);
        self.monitor.push(&z);
        innovation
    }

    fn report(&mut self, poll: &Poll) -> Option<E::Frame> {
        self.estimator.report(poll)
    }

    fn take_mismatch(&mut self) -> Option<MismatchFrame> {
        self.monitor.take_event().map(MismatchFrame::from)
    }
}
