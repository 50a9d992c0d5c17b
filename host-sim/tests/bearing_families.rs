//! Bearing diagnosis by fault family ([`family`](edgekf_sim::diagnostics::bearings::family)) on
//! synthetic rigs made by the project's simulator (`loop_system::inject`): impacts ringing a
//! housing's resonance with 1.5 % random slip between impacts, the mean rate 0.5 % off the
//! kinematic one, the load zone's modulation (inner race: the shaft rate; ball: the cage
//! rate), over a second housing resonance, shaft harmonics, mains tones and sensor noise, with
//! the broadband ringing itself modulated at the shaft rate (so the envelope carries integer
//! orders that no family may claim). Nothing here uses the detector's own signature model.
//!
//! The bearings have lines 0.3–2 % from an integer order: the CWRU fan end's 6203 (BPFO 3.053,
//! BPFI 4.947, 2×BSF 3.988, FTF 0.382) and an 8-ball bearing with d/D = 0.245 (BPFO 3.020,
//! BPFI 4.980, 2×BSF 3.836, FTF 0.378); the other bearing on the shaft is the 6205. Two speeds,
//! records of 2 s and 10 s, inner, outer and ball faults: each is named, with its bearing; two
//! identical bearings cannot be told apart; healthy rigs get nothing.

use edgekf_sim::diagnostics::bearings::family::{diagnose, BearingSpec, Family, Verdict, CARRY};
use edgekf_sim::io::data::DataFile;
use edgekf_sim::systems::rotor::bearing_geometry::{BearingGeometry, BearingLine};
use edgekf_sim::systems::rotor::loop_system::inject::{
    inject_bearing_defect, inject_resonance, inject_tones, DefectSignal,
};
use rand::{Rng, SeedableRng};
use std::f64::consts::TAU;

const FS: f64 = 12_000.0;

/// The CWRU fan end's 6203.
const G6203: BearingGeometry =
    BearingGeometry { balls: 8, ball_diameter: 6.746e-3, pitch_diameter: 28.50e-3, contact_angle_deg: 0.0 };
/// An 8-ball bearing with BPFI 0.4 % and BPFO 0.7 % from an order.
const G_NEAR: BearingGeometry =
    BearingGeometry { balls: 8, ball_diameter: 0.245 * 30e-3, pitch_diameter: 30e-3, contact_angle_deg: 0.0 };
/// The CWRU drive end's 6205.
const G6205: BearingGeometry =
    BearingGeometry { balls: 9, ball_diameter: 7.94e-3, pitch_diameter: 39.04e-3, contact_angle_deg: 0.0 };

/// A record of `seconds` at shaft rate `shaft_hz`: channel `a` on the faulty bearing's
/// housing (3.05 kHz), `b` on the other's (3.42 kHz); the shaft's harmonics (an unbalance's
/// 1× of 0.2 m/s², as the CWRU records show, so that the speed can be read); a defect of `family` on the bearing of
/// geometry `g` if given.
fn record(g: &BearingGeometry, family: Option<Family>, shaft_hz: f64, seconds: f64, seed: u64) -> DataFile {
    let n = (seconds * FS) as usize;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / FS).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let noise = |rng: &mut rand_chacha::ChaCha8Rng| (0..n).map(|_| 0.05 * (rng.gen::<f64>() - 0.5)).collect();
    let columns = vec![noise(&mut rng), noise(&mut rng)];
    let mut d = DataFile { names: vec!["a".into(), "b".into()], t: t.clone(), columns, sha256: None };
    // The housings' broadband ringing, modulated 30 % at the shaft rate.
    let mut ring =
        DataFile { names: vec!["a".into(), "b".into()], t: t.clone(), columns: vec![vec![0.0; n]; 2], sha256: None };
    inject_resonance(&mut ring, "a", 3050.0, 0.04, 0.25, seed * 10 + 1).unwrap();
    inject_resonance(&mut ring, "b", 3420.0, 0.04, 0.25, seed * 10 + 2).unwrap();
    for (col, r) in d.columns.iter_mut().zip(&ring.columns) {
        for ((v, x), tk) in col.iter_mut().zip(r).zip(&t) {
            *v += x * (1.0 + 0.3 * (TAU * shaft_hz * tk).cos());
        }
    }
    let tones: Vec<(f64, f64, f64)> = (1..=6)
        .map(|h| (h as f64 * shaft_hz, 0.2 / h as f64, 0.7 * h as f64))
        .chain([(60.0, 0.03, 0.3), (120.0, 0.08, 1.1), (180.0, 0.02, 2.0)])
        .collect();
    for ch in ["a", "b"] {
        inject_tones(&mut d, ch, &tones).unwrap();
    }
    if let Some(family) = family {
        let order = |l| g.order(l) * shaft_hz;
        let (rate, modulation_hz) = match family {
            Family::OuterRace => (order(BearingLine::Bpfo), None),
            Family::InnerRace => (order(BearingLine::Bpfi), Some(shaft_hz)),
            Family::Ball => (2.0 * order(BearingLine::Bsf), Some(order(BearingLine::Ftf))),
        };
        let signal = DefectSignal {
            frequency_hz: 0.995 * rate,
            peak: 1.5,
            resonance_hz: 3050.0,
            damping: 0.04,
            slip: 0.015,
            modulation_hz: modulation_hz.map(|m| 0.995 * m),
            load_zone: 0.5,
        };
        inject_bearing_defect(&mut d, "a", &signal, seed + 100).unwrap();
    }
    d
}

fn spec(name: &str, g: &BearingGeometry) -> BearingSpec {
    BearingSpec { name: name.into(), orders: g.kinematics() }
}

fn verdict(d: &DataFile, bearings: &[BearingSpec], shaft_hz: f64) -> Verdict {
    let channels: Vec<&[f64]> = d.columns.iter().map(Vec::as_slice).collect();
    // The nominal speed is 1 % off the true one: the detector reads it from the data.
    let diag = diagnose(&channels, FS, 1.01 * shaft_hz, bearings).expect("a running speed");
    assert!((diag.shaft.hz / shaft_hz - 1.0).abs() < 5e-4, "{:?} against {shaft_hz}", diag.shaft);
    for f in diag.families.iter().take(2) {
        let m: Vec<String> = f.members.iter().map(|m| format!("{} {:.1}", m.label, m.strength_db)).collect();
        eprintln!(
            "    {} at {} [{:.1}, s {:+.2} %]: {}",
            f.family.name(),
            f.bearing,
            f.score,
            100.0 * f.slip,
            m.join(", ")
        );
    }
    diag.verdict
}

/// Every family on bearing `g` (the other bearing a 6205), both speeds, both lengths.
fn each_family_is_named(g: &BearingGeometry) {
    let bearings = [spec("near", g), spec("6205", &G6205)];
    let mut failures = Vec::new();
    for (i, family) in Family::ALL.into_iter().enumerate() {
        for (j, shaft_hz) in [24.6, 29.7].into_iter().enumerate() {
            for (k, seconds) in [2.0, 10.0].into_iter().enumerate() {
                let seed = (100 * i + 10 * j + k) as u64;
                eprintln!("{} at {shaft_hz} Hz, {seconds} s:", family.name());
                let v = verdict(&record(g, Some(family), shaft_hz, seconds, seed), &bearings, shaft_hz);
                let ok = matches!(&v, Verdict::Named(f) if f.family == family && f.bearing == "near" && f.carried);
                if !ok {
                    failures.push(format!("{} at {shaft_hz} Hz, {seconds} s: {v:?}", family.name()));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn each_family_of_the_6203_is_named_though_its_lines_sit_near_shaft_orders() {
    each_family_is_named(&G6203);
}

#[test]
fn each_family_of_a_bearing_with_bpfi_0_4_per_cent_from_an_order_is_named() {
    each_family_is_named(&G_NEAR);
}

#[test]
fn a_healthy_rig_carries_no_family() {
    let bearings = [spec("6203", &G6203), spec("6205", &G6205)];
    for (seed, (shaft_hz, seconds)) in [(24.6, 2.0), (29.7, 2.0), (24.6, 10.0), (29.7, 10.0)].into_iter().enumerate() {
        let v = verdict(&record(&G6203, None, shaft_hz, seconds, 500 + seed as u64), &bearings, shaft_hz);
        assert_eq!(v, Verdict::Nothing, "{shaft_hz} Hz, {seconds} s");
    }
}

#[test]
fn two_identical_bearings_cannot_be_told_apart() {
    let bearings = [spec("drive end", &G6203), spec("fan end", &G6203)];
    for (i, family) in Family::ALL.into_iter().enumerate() {
        let v = verdict(&record(&G6203, Some(family), 29.7, 10.0, 700 + i as u64), &bearings, 29.7);
        match v {
            Verdict::CannotTell(a, b) => {
                assert_eq!((a.family, b.family), (family, family));
                assert_ne!(a.bearing, b.bearing);
                assert!(a.carried && b.carried);
            }
            other => panic!("{}: {other:?}", family.name()),
        }
    }
}

#[test]
fn the_rule_is_two_members_at_ten_db() {
    // The rule the README states.
    assert_eq!((CARRY.members, CARRY.min_db, CARRY.false_alarm), (2, 10.0, 1e-3));
}
