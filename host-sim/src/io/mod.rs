//! Files that `edgekf` reads and writes.

pub mod data;
