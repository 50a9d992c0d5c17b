//! One folder per system: its reference simulator, estimators, residual-loop system, command
//! line, demo part and configuration types. [`REGISTRY`] is the one table that connects them to
//! the `edgekf` command line; adding a system is its folder plus one row there.
//!
//! * [`oscillator`]: a single mode driven by a harmonic force (the demo's first part);
//! * [`rotor`]: a flexible rotor on bearings (FE reference, phasor AKF virtual sensing, the
//!   residual loop);
//! * [`crank`]: a slider-crank with revolute clearance joints (multibody reference, the paper's
//!   UKF and the fast estimator the node runs);
//! * [`uuv`]: an underwater vehicle's thruster health (6-DOF reference, joint UKF of state and
//!   health factors with a change detector);
//! * [`boom`]: a long telescoping boom's tip vibration (FE reference with sliding sections);
//! * `sdof` (feature `sdof`, a test system): a base-excited mount's relative motion.

pub mod boom;
pub mod common;
pub mod crank;
pub mod oscillator;
pub mod rotor;
#[cfg(feature = "sdof")]
pub mod sdof;
pub mod uuv;

use crate::cli::registry::{dispatch, subcommands, BaselineEntry, DemoPart, LoopEntry, SystemEntry};

/// Every system of `edgekf`, in the order of `edgekf --help` and of the demo's parts.
pub const REGISTRY: &[SystemEntry] = &[
    SystemEntry {
        name: "oscillator",
        about: "Single mode driven by a harmonic force: simulate data, estimate the force",
        command: subcommands::<oscillator::cli::OscillatorCommand>,
        run: |m| dispatch(m, oscillator::cli::run),
        close_loop: Some(LoopEntry {
            about: "Oscillator: run the harmonic-force filter on `ax`, add what the innovations ask for (a bias or \
                    scale error of the sensor, a force at 2× or 3× the drive, a wrong natural frequency or damping) \
                    and report before/after (report.json, report.html)",
            args: |c| c,
            run: oscillator::cli::close_loop,
            baseline: Some(BaselineEntry { args: |c| c, learn: oscillator::cli::baseline }),
        }),
        demo: Some(DemoPart { closes_loop: false, run: oscillator::cli::demo }),
    },
    SystemEntry {
        name: "rotor",
        about: "Flexible rotor (FE model): natural frequencies and whirl, time response, virtual sensing",
        command: subcommands::<rotor::cli::RotorCommand>,
        run: |m| dispatch(m, rotor::cli::run),
        close_loop: Some(LoopEntry {
            about: "Rotor: run the virtual-sensing filter on a data file, read its innovations, add the effects \
                    the data asks for (sensor bias, scale or delay; a force at k× the running speed; a wrong disk, \
                    shaft or bearing parameter; an extra mode; a bearing defect line; an unknown input) and that \
                    pay for their parameters (BIC) in both halves of the run, and report before/after \
                    (report.json, report.html)",
            args: <rotor::cli::RotorLoopArgs as clap::Args>::augment_args,
            run: rotor::cli::close_loop,
            baseline: Some(BaselineEntry {
                args: <rotor::cli::RotorBaselineArgs as clap::Args>::augment_args,
                learn: rotor::cli::baseline,
            }),
        }),
        demo: Some(DemoPart { closes_loop: true, run: rotor::cli::demo }),
    },
    SystemEntry {
        name: "crank",
        about: "Planar slider-crank with revolute clearance joints: simulate, estimate the clearance",
        command: subcommands::<crank::cli::CrankCommand>,
        run: |m| dispatch(m, crank::cli::run),
        close_loop: None,
        demo: Some(DemoPart { closes_loop: false, run: crank::cli::demo }),
    },
    SystemEntry {
        name: "boom",
        about: "Long telescoping boom (fire-ladder truck): simulate its tip vibration (FE model), estimate it from a tip gyro and a root inclinometer",
        command: subcommands::<boom::cli::BoomCommand>,
        run: |m| dispatch(m, boom::cli::run),
        close_loop: Some(LoopEntry {
            about: "Boom: run the model-based tip-vibration filter the configuration declares on a data file, read \
                    the gyro's and the inclinometer's innovations, add what the data asks for (the inclinometer's \
                    lag or offset, the gyro's scale, a wrong stiffness or platform) and that pays for its \
                    parameter (BIC) in both halves, and report before/after with the peak error (report.json, \
                    report.html); needs --static",
            args: <boom::cli::BoomLoopArgs as clap::Args>::augment_args,
            run: boom::cli::close_loop,
            baseline: Some(BaselineEntry {
                args: <boom::cli::BoomLoopArgs as clap::Args>::augment_args,
                learn: boom::cli::baseline,
            }),
        }),
        demo: Some(DemoPart { closes_loop: true, run: boom::demo::demo }),
    },
    SystemEntry {
        name: "uuv",
        about: "Underwater vehicle (REMUS 100, 6-DOF): simulate a thruster fault, estimate the thrusters' health",
        command: subcommands::<uuv::cli::UuvCommand>,
        run: |m| dispatch(m, uuv::cli::run),
        close_loop: Some(LoopEntry {
            about: "Underwater vehicle: run the thruster-health filter the configuration declares on a data file, \
                    read its innovations, add the effects the data asks for (a thruster's health from an onset, a \
                    sensor bias on an IMU or DVL axis, an undeclared current, a wrong mass or surge drag) and that \
                    pay for their parameters (BIC) in both halves, and report before/after (report.json, \
                    report.html)",
            args: |c| c,
            run: uuv::cli::close_loop,
            baseline: Some(BaselineEntry { args: |c| c, learn: uuv::cli::baseline }),
        }),
        demo: Some(DemoPart { closes_loop: true, run: uuv::demo::demo }),
    },
    #[cfg(feature = "sdof")]
    SystemEntry {
        name: "sdof",
        about: "Base-excited mount (test system): simulate, estimate its relative displacement from the mass's acceleration",
        command: subcommands::<sdof::cli::SdofCommand>,
        run: |m| dispatch(m, sdof::cli::run),
        close_loop: None,
        demo: None,
    },
];
