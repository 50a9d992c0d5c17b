//! Every system's TOML configuration reader on arbitrary text: an error, never a panic.
#![no_main]

use edgekf_sim::systems::crank::estimate::model::FastModel;
use edgekf_sim::systems::crank::CrankConfig;
use edgekf_sim::systems::oscillator::scenario::Scenario;
use edgekf_sim::systems::rotor::RotorConfig;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    // The readers take text; the CLI reads files with `read_to_string`, which refuses
    // non-UTF-8 before any parser sees it.
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    let _ = RotorConfig::from_toml_str(text).map_err(|e| e.to_string());
    let _ = Scenario::from_toml_str(text).map_err(|e| e.to_string());
    let _ = CrankConfig::from_toml_str(text).map_err(|e| e.to_string());
    let _ = FastModel::from_toml_str(text).map_err(|e| e.to_string());
});
