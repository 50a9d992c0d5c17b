//! Models of the sensors, as seen at their outputs: what a driver reads, before quantisation.

pub mod adxl355;
