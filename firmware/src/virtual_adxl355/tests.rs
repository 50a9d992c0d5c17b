//! The real driver against the virtual device, and the CSV feed.
#![allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::vec::Vec;

use embedded_hal::i2c::{Error as _, ErrorKind, I2c as _, NoAcknowledgeSource};

use super::*;
use crate::adxl355::{is_nack, Adxl355, Config, Error, I2cInterface, OutputDataRate, RawSample, RAW_MAX, RAW_MIN};
use edgekf::csv_header::{ColumnName, HeaderError};

type Driver<'a> = Adxl355<I2cInterface<VirtualAdxl355<SliceFeed<'a>>>>;

fn driver(samples: &[FeedSample], config: Config) -> Driver<'_> {
    let mut adxl = Adxl355::new_i2c(VirtualAdxl355::new(SliceFeed::new(samples)), 0x1D);
    adxl.init(config).unwrap();
    adxl
}

/// One watermark period passes.
fn tick<F: SampleFeed>(adxl: &mut Adxl355<I2cInterface<VirtualAdxl355<F>>>) -> usize {
    adxl.interface_mut().bus_mut().advance_period()
}

fn device<'d, 'a>(adxl: &'d Driver<'a>) -> &'d VirtualAdxl355<SliceFeed<'a>> {
    adxl.interface().bus()
}

/// A deterministic, varied signal within ±2 g.
fn signal(n: usize) -> Vec<FeedSample> {
    (0..n)
        .map(|i| {
            let t = i as f32 * 0.001;
            FeedSample::new([
                3.0 * libm::sinf(2.0 * core::f32::consts::PI * 30.0 * t),
                -1.234_567 + 0.5 * libm::cosf(7.0 * t),
                9.80665 + 0.01 * i as f32,
            ])
        })
        .collect()
}

/// Advances one period, polls STATUS and drains the FIFO until the device is exhausted.
fn run(adxl: &mut Driver<'_>) -> Vec<RawSample> {
    let mut all = Vec::new();
    let mut block = [RawSample::default(); 32];
    for _ in 0..10_000 {
        if device(adxl).is_exhausted() {
            break;
        }
        tick(adxl);
        adxl.status().unwrap();
        let read = adxl.read_fifo(&mut block).unwrap();
        assert_eq!(read.skipped_entries, 0);
        all.extend_from_slice(&block[..read.samples]);
    }
    assert!(device(adxl).is_exhausted());
    all
}

#[test]
fn driver_round_trips_within_one_lsb() {
    for config in [
        Config::default(),
        Config { range: crate::adxl355::Range::G8, odr: OutputDataRate::Hz4000, fifo_watermark: 96 },
        Config { fifo_watermark: 3, ..Config::default() },
    ] {
        let input = signal(100);
        let mut adxl = driver(&input, config);
        let output = run(&mut adxl);
        assert_eq!(output.len(), input.len());
        let lsb = 9.80665 / config.range.lsb_per_g();
        for (raw, sample) in output.iter().zip(&input) {
            let got = adxl.to_mps2(*raw);
            for axis in 0..3 {
                assert!((got[axis] - sample.accel[axis]).abs() <= lsb, "{got:?} vs {:?}", sample.accel);
            }
        }
        // The data registers hold the last sample.
        assert_eq!(adxl.read_xyz().unwrap(), *output.last().unwrap());
        assert_eq!(device(&adxl).counters(), VirtualCounters { samples_loaded: 100, ..Default::default() });
    }
}

#[test]
fn registers_after_init_and_reset() {
    let mut dev = VirtualAdxl355::new(SliceFeed::new(&[]));
    let mut ids = [0u8; 4];
    dev.write_read(0x1D, &[0x00], &mut ids).unwrap();
    assert_eq!(ids, [0xAD, 0x1D, 0xED, 0x01]);
    let mut ctl = [0u8; 4];
    dev.write_read(0x1D, &[0x2C], &mut ctl).unwrap();
    assert_eq!(ctl, [0x81, 0x01, 0x00, 0x00]);
    dev.write_read(0x1D, &[0x28], &mut ctl[..2]).unwrap();
    assert_eq!(ctl[..2], [0x00, 0x60]);

    let samples = [FeedSample::new([1.0, 2.0, 3.0])];
    let adxl = driver(&samples, Config { fifo_watermark: 33, ..Config::default() });
    let dev = device(&adxl);
    assert_eq!(dev.peek_register(0x28), 0x02);
    assert_eq!(dev.peek_register(0x29), 33);
    assert_eq!(dev.peek_register(0x2C), 0x81);
    assert_eq!(dev.peek_register(0x2D), 0x00);

    // Writing the reset code restores defaults and clears the FIFO; other values do nothing.
    let mut dev = adxl.release().release();
    dev.advance_period();
    assert_eq!(dev.fifo_len(), 3);
    dev.write(0x1D, &[0x2F, 0x51]).unwrap();
    assert_eq!(dev.fifo_len(), 3);
    dev.write(0x1D, &[0x2F, 0x52]).unwrap();
    assert_eq!(dev.fifo_len(), 0);
    assert_eq!([0x28, 0x29, 0x2C, 0x2D].map(|r| dev.peek_register(r)), [0x00, 0x60, 0x81, 0x01]);
    // Read-only registers ignore writes; a multi-byte write auto-increments.
    dev.write(0x1D, &[0x00, 0x12]).unwrap();
    dev.write(0x1D, &[0x28, 0x03, 0x30]).unwrap();
    assert_eq!([0x00, 0x28, 0x29].map(|r| dev.peek_register(r)), [0xAD, 0x03, 0x30]);
}

#[test]
fn standby_does_not_advance_time() {
    let input = signal(10);
    let mut dev = VirtualAdxl355::new(SliceFeed::new(&input));
    let mut status = [0u8; 1];
    assert_eq!(dev.advance_period(), 0);
    dev.write_read(0x1D, &[0x04], &mut status).unwrap();
    assert_eq!(status, [0]);
    assert_eq!(dev.counters().samples_loaded, 0);
    dev.write(0x1D, &[0x2D, 0x00]).unwrap();
    assert_eq!(dev.advance_period(), 10);
    dev.write_read(0x1D, &[0x04], &mut status).unwrap();
    // 0x60 = 96 entries: 32 samples wanted, only 10 there: DATA_RDY, not FIFO_FULL.
    assert_eq!(status, [0b001]);
    assert_eq!(dev.counters().samples_loaded, 10);
    // Bus reads never advance time, whichever register they start at.
    let mut regs = [0u8; 6];
    dev.write_read(0x1D, &[0x00], &mut regs).unwrap();
    assert_eq!(regs[5], 30); // FIFO_ENTRIES
    assert!(!dev.is_exhausted());
}

#[test]
fn fifo_data_pops_entries_and_reports_empty() {
    let input = [FeedSample::new([0.0, 0.0, 9.80665])];
    let mut dev = VirtualAdxl355::new(SliceFeed::new(&input));
    dev.write(0x1D, &[0x2D, 0x00]).unwrap();
    dev.advance_period();
    let mut burst = [0u8; 12];
    dev.write_read(0x1D, &[0x11], &mut burst).unwrap();
    // X (marker), Y, Z = 256000 = 0x3E800, then the empty indicator.
    assert_eq!(burst, [0, 0, 0x01, 0, 0, 0, 0x3E, 0x80, 0x00, 0, 0, 0x02]);
    assert!(dev.is_exhausted());
}

#[test]
fn saturates_at_the_rails() {
    let input = [FeedSample::new([30.0, -30.0, 1e30]), FeedSample::new([f32::NAN, f32::INFINITY, -f32::INFINITY])];
    let mut adxl = driver(&input, Config { fifo_watermark: 6, ..Config::default() });
    tick(&mut adxl);
    let mut out = [RawSample::default(); 2];
    assert_eq!(adxl.read_fifo(&mut out).unwrap().samples, 2);
    assert_eq!(out[0], RawSample { x: RAW_MAX, y: RAW_MIN, z: RAW_MAX });
    assert!(out[0].is_saturated());
    assert_eq!(out[1], RawSample { x: 0, y: RAW_MAX, z: RAW_MIN });
    // 30 m/s² fits at ±4 g.
    let mut adxl = driver(&input[..1], Config { range: crate::adxl355::Range::G4, ..Config::default() });
    tick(&mut adxl);
    adxl.read_fifo(&mut out).unwrap();
    assert_eq!((out[0].x, out[0].y, out[0].z), (391_571, -391_571, RAW_MAX)); // 30 / 9.80665 * 128000 = 391571.1
}

#[test]
fn injected_nack_then_retry_succeeds() {
    let mut input = signal(6);
    input[1].nack = 2;
    let mut adxl = driver(&input, Config { fifo_watermark: 9, ..Config::default() });
    // This period loads samples 0..3; sample 1 queues two NACKs for what follows.
    assert_eq!(tick(&mut adxl), 3);
    let mut out = [RawSample::default(); 8];
    for _ in 0..2 {
        let err = adxl.read_fifo(&mut out).unwrap_err();
        assert!(is_nack(&err));
        assert_eq!(err, Error::Comm(VirtualBusError::InjectedNack));
    }
    // No side effects: nothing was lost, the retry reads the whole block.
    assert_eq!(adxl.read_fifo(&mut out).unwrap(), crate::adxl355::FifoRead { samples: 3, skipped_entries: 0 });
    assert_eq!(device(&adxl).counters().nacks_sent, 2);
    assert_eq!(device(&adxl).pending_nacks(), 0);
    assert!((adxl.to_mps2(out[2])[2] - input[2].accel[2]).abs() < 1e-4);
}

#[test]
fn wrong_address_is_nacked() {
    let mut dev = VirtualAdxl355::new(SliceFeed::new(&[]));
    let err = dev.write(0x53, &[0x2D, 0x00]).unwrap_err();
    assert_eq!(err, VirtualBusError::AddressNack);
    assert_eq!(err.kind(), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
    assert_eq!(dev.peek_register(0x2D), 0x01);
    assert_eq!(dev.counters().nacks_sent, 0);
    let mut adxl = Adxl355::new_i2c(dev, 0x53);
    assert!(is_nack(&adxl.init(Config::default()).unwrap_err()));
}

#[test]
fn stuck_repeats_previous_output() {
    let mut input = signal(6);
    input[3].stuck = true;
    input[4].stuck = true;
    let mut adxl = driver(&input, Config { fifo_watermark: 18, ..Config::default() });
    tick(&mut adxl);
    let mut out = [RawSample::default(); 6];
    assert_eq!(adxl.read_fifo(&mut out).unwrap().samples, 6);
    assert_eq!(out[3], out[2]);
    assert_eq!(out[4], out[2]);
    assert_ne!(out[5], out[2]);
    assert_ne!(out[1], out[2]);
}

#[test]
fn overrun_discards_oldest_and_sets_flag() {
    let input = signal(40);
    let mut adxl = driver(&input, Config { fifo_watermark: 60, ..Config::default() });
    tick(&mut adxl);
    assert!(!adxl.status().unwrap().fifo_overrun); // 20 samples, 60 entries
    tick(&mut adxl);
    let status = adxl.status().unwrap(); // 20 more: 120 entries, 24 lost
    assert!(status.fifo_overrun && status.fifo_full && status.data_ready);
    assert_eq!(device(&adxl).counters().overrun_entries, 24);
    assert_eq!(adxl.fifo_entries().unwrap(), 96);
    let mut out = [RawSample::default(); 32];
    let read = adxl.read_fifo(&mut out).unwrap();
    assert_eq!(read, crate::adxl355::FifoRead { samples: 32, skipped_entries: 0 });
    // The oldest 8 samples are gone: the block starts at sample 8.
    let lsb = 9.80665 / 256_000.0;
    assert!((adxl.to_mps2(out[0])[2] - input[8].accel[2]).abs() <= lsb);
    // STATUS read cleared the flag (the feed is dry, nothing new is loaded).
    assert_eq!(tick(&mut adxl), 0);
    assert!(!adxl.status().unwrap().fifo_overrun);
    assert!(device(&adxl).is_exhausted());
}

#[test]
fn timeouts_fail_with_kind_other_and_come_before_nacks() {
    let mut input = signal(6);
    input[0].timeout = 2;
    input[0].nack = 1;
    let mut adxl = driver(&input, Config { fifo_watermark: 9, ..Config::default() });
    assert_eq!(tick(&mut adxl), 3);
    let mut out = [RawSample::default(); 8];
    for _ in 0..2 {
        let err = adxl.read_fifo(&mut out).unwrap_err();
        assert_eq!(err, Error::Comm(VirtualBusError::Timeout));
        assert!(crate::adxl355::is_timeout(&err) && !is_nack(&err));
        assert_eq!(VirtualBusError::Timeout.kind(), ErrorKind::Other);
    }
    assert!(is_nack(&adxl.read_fifo(&mut out).unwrap_err()));
    // No side effects: the whole block is still there.
    assert_eq!(adxl.read_fifo(&mut out).unwrap().samples, 3);
    let c = device(&adxl).counters();
    assert_eq!((c.timeouts_sent, c.nacks_sent, device(&adxl).pending_bus_faults()), (2, 1, 0));
}

#[test]
fn garbage_reads_all_ones_without_touching_the_part() {
    let mut input = signal(6);
    input[2].garbage = 3;
    let mut adxl = driver(&input, Config { fifo_watermark: 9, ..Config::default() });
    tick(&mut adxl);
    // The poll's status read: the IDs read 0xFF, refused as a wrong device.
    assert_eq!(adxl.poll_status(), Err(Error::WrongDevice { ad: 0xFF, mst: 0xFF, part: 0xFF }));
    // A garbage FIFO burst pops nothing (the entries stay) and decodes to nothing (0xFF carries
    // the empty indicator).
    let mut out = [RawSample::default(); 8];
    assert_eq!(
        adxl.read_fifo_entries(9, &mut out).unwrap(),
        crate::adxl355::FifoRead { samples: 0, skipped_entries: 9 }
    );
    assert_eq!(device(&adxl).fifo_len(), 9);
    // A lost write: the range does not change.
    adxl.interface_mut().bus_mut().write(0x1D, &[0x2C, 0x83]).unwrap();
    assert_eq!(device(&adxl).peek_register(0x2C), 0x81);
    // The burst is over: the status read is good and sees all 3 samples.
    let poll = adxl.poll_status().unwrap();
    assert_eq!((poll.fifo_entries, poll.status.fifo_overrun), (9, false));
    assert_eq!(adxl.read_fifo_entries(poll.fifo_entries, &mut out).unwrap().samples, 3);
    assert_eq!(device(&adxl).counters().garbage_sent, 3);
}

#[test]
fn dropped_samples_never_enter_the_fifo() {
    let mut input = signal(12);
    for s in &mut input[4..9] {
        s.dropped = true;
    }
    let mut adxl = driver(&input, Config { fifo_watermark: 18, ..Config::default() });
    assert_eq!((tick(&mut adxl), tick(&mut adxl)), (4, 3));
    let mut out = [RawSample::default(); 12];
    assert_eq!(adxl.read_fifo(&mut out).unwrap().samples, 7);
    // Sample 9 follows sample 3.
    let lsb = 9.80665 / 256_000.0;
    assert!((adxl.to_mps2(out[4])[2] - input[9].accel[2]).abs() <= lsb);
    let c = device(&adxl).counters();
    assert_eq!((c.samples_loaded, c.samples_dropped, c.samples_discarded), (7, 5, 0));
    assert_eq!(device(&adxl).period_shortfall(), 0);
}

#[test]
fn a_reset_mid_run_clears_the_fifo_and_time_goes_on_in_standby() {
    let mut input = signal(40);
    input[13].reset = true;
    let config = Config { fifo_watermark: 15, ..Config::default() }; // 5 samples a period
    let mut adxl = driver(&input, config);
    assert_eq!((tick(&mut adxl), tick(&mut adxl)), (5, 5));
    // Samples 10..13 enter, 13 resets the part: the FIFO (13 samples, unread) is cleared, 13
    // and 14 are due in standby.
    assert_eq!(tick(&mut adxl), 3);
    let dev = device(&adxl);
    assert_eq!(dev.fifo_len(), 0);
    assert_eq!([0x28, 0x29, 0x2C, 0x2D].map(|r| dev.peek_register(r)), [0x00, 0x60, 0x81, 0x01]);
    assert_eq!((dev.counters().resets, dev.counters().samples_discarded), (1, 15));
    assert!(!adxl.config_matches().unwrap());
    // Standby: the harness's period stays 5 samples, and they are lost.
    assert_eq!(tick(&mut adxl), 0);
    assert_eq!(device(&adxl).counters().samples_discarded, 20);
    assert_eq!(device(&adxl).period_samples(), 5);
    // Reconfigured, the part measures from the next period on, at sample 20.
    adxl.init(config).unwrap();
    assert!(adxl.config_matches().unwrap());
    assert_eq!(tick(&mut adxl), 5);
    let mut out = [RawSample::default(); 8];
    assert_eq!(adxl.read_fifo(&mut out).unwrap().samples, 5);
    assert!((adxl.to_mps2(out[0])[2] - input[20].accel[2]).abs() <= 9.80665 / 256_000.0);
    let c = device(&adxl).counters();
    assert_eq!((c.samples_loaded, c.resets, c.samples_discarded), (18, 1, 20));
}

#[test]
fn a_recording_that_ends_mid_period_reports_its_shortfall() {
    let input = signal(7);
    let mut adxl = driver(&input, Config { fifo_watermark: 15, ..Config::default() });
    assert_eq!((tick(&mut adxl), device(&adxl).period_shortfall()), (5, 0));
    assert_eq!((tick(&mut adxl), device(&adxl).period_shortfall()), (2, 3));
    assert_eq!((tick(&mut adxl), device(&adxl).period_shortfall()), (0, 5));
}

fn header_error(e: HeaderError) -> Result<CsvColumns, CsvError> {
    Err(CsvError::Header(e))
}

#[test]
fn csv_header_columns() {
    let cols = CsvColumns::from_header("t,ax,ay,az").unwrap();
    assert_eq!((cols.column_count(), cols.ignored(), cols.has_faults()), (4, 0, false));
    // A BOM before `t` and spaces around names are dropped (the shared header rules).
    let cols =
        CsvColumns::from_header("\u{feff} t ,truth_force,az,ay,ax,truth_phase,fault_stuck,fault_nack\r\n").unwrap();
    assert_eq!((cols.column_count(), cols.ignored(), cols.has_faults()), (8, 2, true));
    let s = cols.parse_line("0.5, 1.0, 3, 2, 1, 9.9, 1, 4\r").unwrap();
    assert_eq!(s, FeedSample { accel: [1.0, 2.0, 3.0], nack: 4, stuck: true, ..Default::default() });
    assert_eq!(cols.parse_record("0.5,1.0,3,2,1,9.9,0,").unwrap(), (0.5, FeedSample::new([1.0, 2.0, 3.0])));

    let name = ColumnName::new;
    assert_eq!(
        CsvColumns::from_header("ax,ay,az"),
        header_error(HeaderError::FirstColumnNotTime { found: name("ax") })
    );
    // `t` anywhere but first is refused, as on the host.
    assert_eq!(
        CsvColumns::from_header("truth_x,t,ax,ay,az"),
        header_error(HeaderError::FirstColumnNotTime { found: name("truth_x") })
    );
    assert_eq!(CsvColumns::from_header("t,ay,az"), header_error(HeaderError::MissingChannel { name: name("ax") }));
    assert_eq!(CsvColumns::from_header(""), header_error(HeaderError::FirstColumnNotTime { found: name("") }));
    let wide: std::string::String = (0..70).map(|i| std::format!(",c{i}")).collect();
    assert_eq!(
        CsvColumns::from_header(&(std::string::String::from("t,ax,ay,az") + &wide)),
        header_error(HeaderError::TooManyColumns { max: MAX_CSV_COLUMNS })
    );
    // A repeated name is refused with both columns (it used to keep the first one).
    let dup = CsvColumns::from_header("t,ax,ay,az,ax").unwrap_err();
    assert_eq!(dup, CsvError::Header(HeaderError::Duplicate { name: name("ax"), first: 2, second: 5 }));
    assert_eq!(std::format!("{dup}"), "CSV header: duplicate column name `ax`: columns 2 and 5");
}

#[test]
fn csv_fault_columns_in_any_order() {
    let header = "t,fault_reset,ax,fault_garbage,ay,fault_drop,az,fault_timeout,fault_stuck,fault_nack,truth_x";
    let cols = CsvColumns::from_header(header).unwrap();
    assert_eq!((cols.column_count(), cols.ignored(), cols.has_faults()), (11, 1, true));
    let s = cols.parse_line("0.25,1,1.5,7,2.5,1,3.5,9,0,3,0.1").unwrap();
    let want = FeedSample {
        accel: [1.5, 2.5, 3.5],
        nack: 3,
        timeout: 9,
        garbage: 7,
        stuck: false,
        dropped: true,
        reset: true,
    };
    assert_eq!(s, want);
    // Empty fault cells mean no fault; flags are 0 or 1, counts 0..=255.
    assert_eq!(cols.parse_line("0.25,,1.5,,2.5,,3.5,,,,0.1").unwrap(), FeedSample::new([1.5, 2.5, 3.5]));
    let bad = |column| Err(CsvError::BadField { column });
    assert_eq!(cols.parse_line("0.25,2,1.5,7,2.5,1,3.5,9,0,3,0.1"), bad(1));
    assert_eq!(cols.parse_line("0.25,1,1.5,256,2.5,1,3.5,9,0,3,0.1"), bad(3));
    assert_eq!(cols.parse_line("0.25,1,1.5,7,2.5,0.5,3.5,9,0,3,0.1"), bad(5));
    assert_eq!(cols.parse_line("0.25,1,1.5,7,2.5,1,3.5,-1,0,3,0.1"), bad(7));
    // Every fault column is one of the published names.
    for name in FAULT_COLUMNS {
        let cols = CsvColumns::from_header(&std::format!("t,ax,ay,az,{name}")).unwrap();
        assert_eq!((cols.ignored(), cols.has_faults()), (0, true), "{name}");
    }
}

#[test]
fn csv_bad_fields() {
    let cols = CsvColumns::from_header("t,ax,ay,az,fault_nack,fault_stuck,truth_x").unwrap();
    let bad = |column| Err(CsvError::BadField { column });
    assert!(cols.parse_line("0,1,2,3,0,0,garbage").is_ok()); // ignored columns are not parsed
    assert_eq!(cols.parse_line("x,1,2,3,0,0,0"), bad(0));
    assert_eq!(cols.parse_line("0,1,nan,3,0,0,0"), bad(2));
    assert_eq!(cols.parse_line("0,1,2,inf,0,0,0"), bad(3));
    assert_eq!(cols.parse_line("0,1,2,,0,0,0"), bad(3));
    assert_eq!(cols.parse_line("0,1,2,3,-1,0,0"), bad(4));
    assert_eq!(cols.parse_line("0,1,2,3,256,0,0"), bad(4));
    assert_eq!(cols.parse_line("0,1,2,3,1.5,0,0"), bad(4));
    assert_eq!(cols.parse_line("0,1,2,3,2.0,0,0").unwrap().nack, 2);
    assert_eq!(cols.parse_line("0,1,2,3,0,2,0"), bad(5));
    assert_eq!(cols.parse_line("0,1,2,3,0,0"), bad(6)); // truncated line
    assert_eq!(cols.parse_line("0,1,2,3,0,0,0,0"), bad(7)); // extra field
    assert_eq!(cols.parse_line(""), bad(0));
}

#[test]
fn csv_text_feed_drives_the_device() {
    let text = "t,ax,ay,az,fault_nack,truth_f\r\n\
                0.000,0.0,0.0,9.80665,0,1\r\n\
                \r\n\
                0.001,1.0,0.0,9.80665,0,1\r\n\
                0.002,bad,0.0,9.80665,0,1\r\n\
                0.003,2.0,0.0,9.80665,1,1\r\n";
    let feed = CsvTextFeed::new(text).unwrap();
    assert_eq!(feed.columns().ignored(), 1);
    let mut adxl = Adxl355::new_i2c(VirtualAdxl355::new(feed), 0x1D);
    adxl.init(Config { fifo_watermark: 9, ..Config::default() }).unwrap();
    tick(&mut adxl);
    let mut out = [RawSample::default(); 4];
    assert!(is_nack(&adxl.read_fifo(&mut out).unwrap_err()));
    assert_eq!(adxl.read_fifo(&mut out).unwrap().samples, 3);
    assert_eq!(out[..3].iter().map(|s| s.x).collect::<Vec<_>>(), [0, 26_105, 52_209]); // 1 and 2 m/s²: 26104.6, 52209.1

    // The feed has not said "no more" yet; the next period finds it dry.
    assert!(!adxl.interface().bus().is_exhausted());
    assert_eq!(tick(&mut adxl), 0);
    assert_eq!(adxl.status().unwrap(), crate::adxl355::Status::default());
    let dev = adxl.interface().bus();
    assert!(dev.is_exhausted());
    assert_eq!(dev.feed().bad_lines(), 1);
    let missing = HeaderError::MissingChannel { name: ColumnName::new("az") };
    assert_eq!(CsvTextFeed::new("\n\nt,ax,ay\n").unwrap_err(), CsvError::Header(missing));
}
