//! The oscillator image's kernels in the bench image (`edgekf-bench`): the harmonic-force step
//! and the ADXL355 source's polls. Their budgets are in [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    harmonic::<M>();
    monitored::<M>();
    captured::<M>();
    adxl_poll::<M>();
}

/// The step as the image runs it, with the model monitor (`crate::monitor`): an ordinary
/// sample (`harmonic_monitored`: the step, `√NIS` and the monitor's CUSUM and window sums) and
/// the sample that closes a monitor window (`harmonic_monitored_window`: plus the bias and
/// whiteness tests). Its settling time is left out so that the monitor runs from the first
/// sample.
fn monitored<M: Markers>() {
    use super::{compiled_estimator, monitor_settings, NodeConfig};
    use crate::monitor::Monitored;
    use crate::node::NodeEstimator;
    let config = NodeConfig::default().estimator;
    let Ok(est) = compiled_estimator(&config) else {
        defmt::error!("bench harmonic_monitored: no estimator");
        exit(1)
    };
    let settings = edgekf::residual::MonitorSettings { settle_s: 0.0, ..monitor_settings(config.sample_rate_hz) };
    let window = settings.window;
    let mut node = Monitored::new(super::Watched::compiled(est), &settings);
    let input = |k: u32| Some(0.01 * (k % 7) as f32 - 0.03);
    for k in 1..window {
        if k == 10 {
            M::start();
            core::hint::black_box(node.step(core::hint::black_box(input(k))));
            M::end();
            defmt::info!("bench harmonic_monitored n={=usize} m={=usize} resets={=u32}", 4usize, 1usize, 0u32);
        } else {
            node.step(input(k));
        }
    }
    M::start();
    core::hint::black_box(node.step(core::hint::black_box(input(window))));
    M::end();
    defmt::info!("bench harmonic_monitored_window n={=usize} m={=usize} resets={=u32}", 4usize, 1usize, 0u32);
}

/// The step as the image runs it since the window hand-over (`crate::capture`): the monitored
/// step and the ring's store (`harmonic_captured`), and one poll's share of a hand-over
/// (`window_chunk`: `CHUNK` = 64 `window` frames through defmt). The ring here is 64 samples:
/// neither cost depends on its length.
fn captured<M: Markers>() {
    use super::{compiled_estimator, monitor_settings, NodeConfig};
    use crate::capture::{Captured, CHUNK, GUARD};
    use crate::frame::Defmt;
    use crate::monitor::{MismatchFrame, Monitored};
    use crate::node::NodeEstimator;
    let config = NodeConfig::default().estimator;
    let Ok(est) = compiled_estimator(&config) else {
        defmt::error!("bench harmonic_captured: no estimator");
        exit(1)
    };
    let settings = edgekf::residual::MonitorSettings { settle_s: 0.0, ..monitor_settings(config.sample_rate_hz) };
    let mut ring = [0.0f32; CHUNK];
    let mut node = Captured::new(Monitored::new(super::Watched::compiled(est), &settings), &mut ring, 1000);
    let input = |k: u32| Some(0.01 * (k % 7) as f32 - 0.03);
    for k in 1..10 {
        node.step(input(k));
    }
    M::start();
    core::hint::black_box(node.step(core::hint::black_box(input(10))));
    M::end();
    defmt::info!("bench harmonic_captured n={=usize} m={=usize} resets={=u32}", 4usize, 1usize, 0u32);
    // Past the guard: the next call sends the header, the one after it the chunk.
    node.request(MismatchFrame { channel: 0, statistic: 1, since: 1 });
    for k in 11..GUARD + 2 * CHUNK as u32 {
        node.step(input(k));
    }
    node.hand_over(&mut Defmt);
    M::start();
    node.hand_over(&mut Defmt);
    M::end();
    if !node.handed_over() {
        defmt::error!("bench window_chunk: the window did not go out");
        exit(1)
    }
    defmt::info!("bench window_chunk n={=usize} m={=usize} resets={=u32}", 4usize, 1usize, 0u32);
}

/// The ADXL355 source's poll on the virtual ADXL355, without the estimator: `adxl_poll`, an
/// ordinary poll (the status read with the IDs, the 16-sample FIFO burst, screening and
/// conversion); `adxl_poll_stall`, one that finds the FIFO empty although samples are due (a
/// dropped period: plus the configuration read-back); `adxl_poll_reset`, the poll after a
/// reset (plus the re-initialisation and 16 bridged samples). The virtual device's register
/// emulation is in the counts, as the I²C driver's would be on the board.
fn adxl_poll<M: Markers>() {
    use crate::adxl355::{Adxl355, I2cInterface};
    use crate::node::{Health, Recorded, SampleSource};
    use crate::source::{Adxl355Settings, Adxl355Source};
    use crate::virtual_adxl355::{FeedSample, SliceFeed, VirtualAdxl355};
    let mut feed = [FeedSample::new([0.0, 0.0, 9.8]); 96];
    for (k, s) in feed.iter_mut().enumerate() {
        let x = k as f32;
        s.accel = [0.5 * x - 20.0, 3.0 - 0.25 * x, 9.8 + 0.01 * x];
    }
    // Periods 0–2 ordinary, 3 dropped, 4 reset at its first sample, 5 ordinary.
    for s in feed.get_mut(48..64).into_iter().flatten() {
        s.dropped = true;
    }
    if let Some(s) = feed.get_mut(64) {
        s.reset = true;
    }
    let sensor = Adxl355::new_i2c(VirtualAdxl355::new(SliceFeed::new(&feed)), 0x1D);
    let mut health = Health::default();
    let Ok(mut source) = Adxl355Source::start(sensor, Adxl355Settings::default(), &mut health) else {
        defmt::error!("bench adxl_poll: the virtual part did not start");
        exit(1)
    };
    type Source<'a> = Adxl355Source<I2cInterface<VirtualAdxl355<SliceFeed<'a>>>>;
    // One period passes and the source reads it, counted if `label` says what it is.
    fn poll<M: Markers>(source: &mut Source<'_>, health: &mut Health, label: Option<&str>) {
        source.advance();
        if label.is_some() {
            M::start();
        }
        let read = source.read(health, |s| {
            core::hint::black_box(s);
        });
        if let Some(label) = label {
            M::end();
            defmt::info!("bench {=str} n={=usize} m={=usize} read={=u16}", label, 16usize, 1usize, read);
        }
    }
    poll::<M>(&mut source, &mut health, None);
    poll::<M>(&mut source, &mut health, None);
    poll::<M>(&mut source, &mut health, Some("adxl_poll"));
    poll::<M>(&mut source, &mut health, Some("adxl_poll_stall"));
    poll::<M>(&mut source, &mut health, Some("adxl_poll_reset"));
    if (health.config_checks, health.resets, health.bridged) != (2, 1, 32) {
        defmt::error!("bench adxl_poll: not the polls meant: {}", health);
        exit(1)
    }
}

/// The harmonic-force estimator's step (`harmonic_step`).
fn harmonic<M: Markers>() {
    use edgekf::systems::oscillator::{HarmonicForceEstimator, HarmonicForceParams};
    let Ok(mut est) = HarmonicForceEstimator::<f32>::new(&HarmonicForceParams::default()) else {
        defmt::error!("bench harmonic: no estimator");
        exit(1)
    };
    let resets = |e: &HarmonicForceEstimator<f32>| e.counters().filter.covariance_resets;
    crate::bench::one_step::<M, _, _>("harmonic_step", (4, 1), &mut est, |e, y| e.step(y), resets);
}
