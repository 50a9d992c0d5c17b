//! Files that `edgekf` reads and writes.

pub mod config;
pub mod config_edit;
pub mod data;
pub mod output;
pub mod recording;
pub mod rust_consts;
pub mod timeline;
