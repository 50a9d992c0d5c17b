//! Rolling-element bearing diagnosis from a filter's innovations:
//!
//! * [`prewhiten`]: cepstral prewhitening (the discrete part of a vibration taken out);
//! * [`shaft`]: the running speed refined from the shaft harmonics;
//! * [`family`]: the diagnosis by fault family (outer race, inner race, ball), each scored as
//!   a whole in the squared envelope spectrum of the prewhitened signal;
//! * [`envelope`]: envelope analysis (kurtogram, squared envelope, lines in its spectrum);
//! * [`cyclic`]: a resonance rung by periodic impacts, fitted to the innovations by likelihood;
//! * [`impacts`]: the first stage of a machine's loop: periodic impacts named by their
//!   envelope lines, fitted, and taken out of the data before the search.

pub mod cyclic;
pub mod envelope;
pub mod family;
pub mod impacts;
pub mod prewhiten;
pub mod shaft;
