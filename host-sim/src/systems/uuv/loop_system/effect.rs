//! What the vehicle's model may lack, as effects of the residual loop, and the filter states
//! each occupies.
//!
//! The loop's filter has one fixed set of states ([`STATES`]): the ten vehicle states, then a
//! slot for every state an effect can bring. A slot no effect uses is held inert (its
//! neutral value, a negligible variance, no process noise and no part in the model), so every
//! model the loop tries is the same filter with other slots switched on.

use super::super::simulate::MEASURED;
use edgekf::systems::uuv::{Layout, VEHICLE_STATES};
use std::ops::Range;

/// States of the loop's filter: 10 vehicle states, `k_t`, `k_v`, accelerometer biases (3),
/// gyro biases (3), the current (north, east), DVL biases (3).
pub const STATES: usize = 23;

/// First slot of each kind.
const K_T: usize = VEHICLE_STATES;
const K_V: usize = VEHICLE_STATES + 1;
const ACC_BIAS: usize = VEHICLE_STATES + 2;
const GYRO_BIAS: usize = VEHICLE_STATES + 5;
const CURRENT: usize = VEHICLE_STATES + 8;
const DVL_BIAS: usize = VEHICLE_STATES + 10;

/// The measured channels the filter reads, in its innovation order (the data file's names).
pub const CHANNELS: [&str; 11] = [
    MEASURED[0],
    MEASURED[1],
    MEASURED[2],
    MEASURED[3],
    MEASURED[4],
    MEASURED[5],
    MEASURED[6],
    MEASURED[7],
    MEASURED[8],
    MEASURED[9],
    MEASURED[10],
];

/// A thruster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Thruster {
    /// The main (surge) thruster, `k_t`.
    Main,
    /// The vertical tunnel thruster, `k_v`.
    Vertical,
}

impl Thruster {
    /// Index of its detector (0 main, 1 vertical).
    pub fn index(self) -> usize {
        match self {
            Thruster::Main => 0,
            Thruster::Vertical => 1,
        }
    }

    /// `main` or `vertical`, as in the configuration's `[estimator] health`.
    pub fn name(self) -> &'static str {
        match self {
            Thruster::Main => "main",
            Thruster::Vertical => "vertical",
        }
    }
}

/// A sensor axis that may carry an offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensor {
    /// Accelerometer axis 0–2 (body x, y, z).
    Acc(usize),
    /// Gyro axis 0–2.
    Gyro(usize),
    /// DVL axis 0–2.
    Dvl(usize),
}

impl Sensor {
    /// Its channel in [`CHANNELS`].
    pub fn channel(self) -> usize {
        match self {
            Sensor::Acc(a) => a,
            Sensor::Gyro(a) => 3 + a,
            Sensor::Dvl(a) => 8 + a,
        }
    }

    /// The sensor reading `channel` of [`CHANNELS`], if it is one that may carry a bias.
    pub fn of_channel(channel: usize) -> Option<Sensor> {
        match channel {
            0..=2 => Some(Sensor::Acc(channel)),
            3..=5 => Some(Sensor::Gyro(channel - 3)),
            8..=10 => Some(Sensor::Dvl(channel - 8)),
            _ => None,
        }
    }

    /// Its unit.
    pub fn unit(self) -> &'static str {
        match self {
            Sensor::Acc(_) => "m/s^2",
            Sensor::Gyro(_) => "rad/s",
            Sensor::Dvl(_) => "m/s",
        }
    }
}

/// A vehicle constant the loop may find wrong, fitted as a factor on the declared value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// The mass (the weight; the buoyancy is the hull's and stays).
    Mass,
    /// The surge drag `X_u|u|`.
    SurgeDrag,
}

impl Parameter {
    /// The name in reports (the configuration's key).
    pub fn name(self) -> &'static str {
        match self {
            Parameter::Mass => "mass",
            Parameter::SurgeDrag => "x_uu",
        }
    }
}

/// One augmentation of the vehicle's model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// A thruster's health factor (with its detector, as the node's estimator carries it).
    Health(Thruster),
    /// A constant offset on a sensor axis (a slow random walk).
    Bias(Sensor),
    /// An undeclared horizontal current (north and east, random walks): the vehicle's velocity
    /// through the water is not its velocity over ground.
    Current,
    /// A factor on a vehicle constant.
    Parameter(Parameter),
    /// A fixed offset on a DVL axis 0–2, m/s: the scalar the engine's screen moves to ask
    /// whether the data can see a DVL offset at all (the node's estimator carries none).
    DvlOffset(usize),
}

impl Effect {
    /// The filter states it occupies (none for a parameter or a fixed offset).
    pub fn states(self) -> Range<usize> {
        let one = |i: usize| i..i + 1;
        match self {
            Effect::Health(Thruster::Main) => one(K_T),
            Effect::Health(Thruster::Vertical) => one(K_V),
            Effect::Bias(Sensor::Acc(a)) => one(ACC_BIAS + a),
            Effect::Bias(Sensor::Gyro(a)) => one(GYRO_BIAS + a),
            Effect::Bias(Sensor::Dvl(a)) => one(DVL_BIAS + a),
            Effect::Current => CURRENT..CURRENT + 2,
            Effect::Parameter(_) | Effect::DvlOffset(_) => 0..0,
        }
    }

    /// What a configuration's `[estimator]` declares (the base model the loop starts from).
    pub fn declared(layout: &Layout) -> Vec<Effect> {
        let mut out = Vec::new();
        if layout.main {
            out.push(Effect::Health(Thruster::Main));
        }
        if layout.vertical {
            out.push(Effect::Health(Thruster::Vertical));
        }
        if layout.biases {
            out.extend((0..3).map(|a| Effect::Bias(Sensor::Acc(a))));
            out.extend((0..3).map(|a| Effect::Bias(Sensor::Gyro(a))));
        }
        if layout.current {
            out.push(Effect::Current);
        }
        out
    }
}

/// Where the slots of the filter read from: the health factors, the biases added to the
/// channels, the current.
pub mod slot {
    use super::*;

    /// `k_t` and `k_v`.
    pub const HEALTH: [usize; 2] = [K_T, K_V];
    /// The bias slot of each channel of [`CHANNELS`] (depth and heading have none).
    pub const BIAS: [Option<usize>; 11] = [
        Some(ACC_BIAS),
        Some(ACC_BIAS + 1),
        Some(ACC_BIAS + 2),
        Some(GYRO_BIAS),
        Some(GYRO_BIAS + 1),
        Some(GYRO_BIAS + 2),
        None,
        None,
        Some(DVL_BIAS),
        Some(DVL_BIAS + 1),
        Some(DVL_BIAS + 2),
    ];
    /// The current's north component (east follows).
    pub const CURRENT_N: usize = CURRENT;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_slot_is_one_effects_and_the_layout_matches_the_estimators() {
        let all = [
            Effect::Health(Thruster::Main),
            Effect::Health(Thruster::Vertical),
            Effect::Bias(Sensor::Acc(0)),
            Effect::Bias(Sensor::Acc(1)),
            Effect::Bias(Sensor::Acc(2)),
            Effect::Bias(Sensor::Gyro(0)),
            Effect::Bias(Sensor::Gyro(1)),
            Effect::Bias(Sensor::Gyro(2)),
            Effect::Current,
            Effect::Bias(Sensor::Dvl(0)),
            Effect::Bias(Sensor::Dvl(1)),
            Effect::Bias(Sensor::Dvl(2)),
        ];
        let slots: Vec<usize> = all.iter().flat_map(|e| e.states()).collect();
        assert_eq!(slots, (VEHICLE_STATES..STATES).collect::<Vec<_>>());
        // The declared slots sit where the node's estimator puts them with every state on.
        let layout = Layout { main: true, vertical: true, biases: true, current: true };
        assert_eq!(Effect::Health(Thruster::Vertical).states().start, layout.k_v().unwrap());
        assert_eq!(Effect::Bias(Sensor::Acc(0)).states().start, layout.acc_bias().unwrap());
        assert_eq!(Effect::Bias(Sensor::Gyro(0)).states().start, layout.gyro_bias().unwrap());
        assert_eq!(Effect::Current.states().start, layout.current().unwrap());
        assert_eq!(Effect::declared(&layout).len(), 9);
        for c in 0..11 {
            assert_eq!(Sensor::of_channel(c).map(Sensor::channel), slot::BIAS[c].map(|_| c));
        }
        assert_eq!(CHANNELS[8], "dvl_u");
    }
}
