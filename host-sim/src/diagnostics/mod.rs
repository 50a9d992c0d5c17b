//! Toolkits a system may use to find and name what its model lacks, outside the loop engine
//! (which reaches them only through the system that uses them):
//!
//! * [`bearings`]: rolling-element bearing diagnosis: envelope analysis (kurtogram, squared
//!   envelope, lines in its spectrum), impacts ringing a resonance fitted by likelihood, and the
//!   stage that names a defect from its lines before the loop's search;
//! * [`locate`]: where an input the model lacks acts, ranked from the innovations' directions;
//! * [`severity`]: a machine's broadband vibration velocity and its ISO 20816-3 zone.

pub mod bearings;
pub mod locate;
pub mod severity;
