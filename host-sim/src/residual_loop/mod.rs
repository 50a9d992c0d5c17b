//! The residual-loop engine: closing the loop with measured data for any system. Run the
//! system's filter, read the innovations' signatures (bias, NIS, whiteness, spectral lines
//! placed at the system's reference lines, steps in power), ask the system for candidate
//! effects, and keep an effect only if it raises the innovations' log-likelihood by more than
//! its BIC cost in both halves of the run; repeat until the innovations are consistent or
//! nothing helps, then report what is left and what the data cannot tell.
//!
//! The engine knows no system and no domain: a system implements [`LoopSystem`] in its own
//! folder, and reaches the toolkits of [`crate::diagnostics`] (envelope analysis, locating an
//! input) itself, and hands the engine what they found through [`search_staged`]. A test
//! (`host-sim/tests/engine_words.rs`) keeps the engine's code free of system and domain words.
//!
//! * [`system`]: the [`LoopSystem`] trait, how an effect is fitted ([`Fitting`]) and what a
//!   system's first stage found ([`PreStage`]);
//! * [`search`](mod@search): the loop; [`options`]: its settings;
//! * [`fit`]: one candidate fitted (its scalar, its onset, its gains and costs);
//! * [`identifiability`]: rivals a winner cannot be told from, parameters the data cannot see;
//! * [`vocabulary`]: the effect kinds, their extra fields and [`Applied`] effects;
//! * [`report`]: what a run reports (`report.json`'s layout);
//! * [`onset`]: effects that start mid-run (the onset's placement, the halves after it);
//! * [`order_lines`]: the innovations' lines tested at the running speed's orders, where a
//!   force would leave one;
//! * [`signature`]: the innovations' statistics and what is left unexplained; [`recording`]:
//!   a system's data as the summaries and the report's traces read them;
//! * [`baseline`]: a healthy baseline's source and the comparison of a record with it;
//!   [`levels`]: the baseline any system can have (its gain floor, its innovation levels);
//! * [`limits`]: the smallest change of an effect the data could tell (a test case's unit);
//! * [`filter`]: a dynamic-size Kalman filter for the host search (time-varying gain until the
//!   covariance converges, then frozen);
//! * [`modal_form`]: the transition in real modal form, so that a covariance step is `O(n²)`;
//! * [`tuning`]: the process noise set from the data before the search;
//! * [`optimize`]: the one-dimensional maximum-likelihood fit of an effect's scalar.

pub mod baseline;
pub mod correction;
pub mod filter;
pub mod fit;
pub mod identifiability;
pub mod levels;
pub mod limits;
pub mod modal_form;
pub mod onset;
pub mod optimize;
pub mod options;
pub mod order_lines;
pub mod recording;
pub mod report;
pub mod score;
pub mod search;
pub mod signature;
pub mod system;
pub mod tuning;
pub mod vocabulary;

pub use correction::{Correction, EffectCorrection};
pub use fit::OUTSIDE;
pub use optimize::ScalarRange;
pub use options::LoopOptions;
pub use recording::Recording;
pub use report::{
    AddedEffect, LoopReport, NotIdentifiable, Refused, Source, SystemFigure, SystemSection, Traces, Trial,
    SCHEMA_VERSION,
};
pub use search::{search, search_staged};
pub use signature::{Channel, ChannelSignature, PeakSignature, RunSummary, Signature, SignatureOptions};
pub use system::{Described, Fitting, LoopSystem, PreStage, Rivals};
pub use vocabulary::{Applied, EffectDetail, EffectKind, EffectLabel};
