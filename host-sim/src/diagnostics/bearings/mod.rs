//! Rolling-element bearing diagnosis from a filter's innovations:
//!
//! * [`envelope`]: envelope analysis (kurtogram, squared envelope, lines in its spectrum);
//! * [`cyclic`]: a resonance rung by periodic impacts, fitted to the innovations by likelihood;
//! * [`impacts`]: the first stage of a machine's loop: periodic impacts named by their
//!   envelope lines, fitted, and taken out of the data before the search.

pub mod cyclic;
pub mod envelope;
pub mod impacts;
