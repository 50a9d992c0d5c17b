//! Driver tests against mock buses. Register addresses and values are written as literals from
//! the datasheet, not taken from `registers`, so the tests are an independent oracle.
#![allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::vec;
use std::vec::Vec;

use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cTransaction};
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as SpiTransaction};

use super::*;

const ADDR: u8 = 0x1D;

/// The exact I2C traffic of `init` with the given FILTER, RANGE and FIFO_SAMPLES values.
fn init_traffic(addr: u8, filter: u8, range: u8, watermark: u8) -> Vec<I2cTransaction> {
    vec![
        I2cTransaction::write_read(addr, vec![0x00], vec![0xAD, 0x1D, 0xED]),
        I2cTransaction::write(addr, vec![0x2F, 0x52]),
        I2cTransaction::write(addr, vec![0x28, filter]),
        I2cTransaction::write(addr, vec![0x2C, range]),
        I2cTransaction::write(addr, vec![0x29, watermark]),
        I2cTransaction::write(addr, vec![0x2D, 0x00]),
    ]
}

fn finish(adxl: Adxl355<I2cInterface<I2cMock>>) {
    adxl.release().release().done();
}

/// Encodes a code into the datasheet byte layout, independently of the crate's encoder.
fn bytes_of(code: i32, flags: u8) -> [u8; 3] {
    let v = (code as u32) & 0xFFFFF;
    [(v >> 12) as u8, (v >> 4) as u8, ((v & 0xF) << 4) as u8 | flags]
}

fn fifo_bytes(entries: &[(i32, u8)]) -> Vec<u8> {
    entries.iter().flat_map(|&(c, f)| bytes_of(c, f)).collect()
}

#[test]
fn init_default_traffic() {
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&init_traffic(ADDR, 0x02, 0x81, 48)), ADDR);
    adxl.init(Config::default()).unwrap();
    assert_eq!(adxl.config(), Config::default());
    finish(adxl);
}

#[test]
fn init_other_config_traffic() {
    let config = Config { range: Range::G8, odr: OutputDataRate::Hz3_906, fifo_watermark: 96 };
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&init_traffic(0x53, 0x0A, 0x83, 96)), ADDRESS_ASEL_HIGH);
    adxl.init(config).unwrap();
    assert_eq!(adxl.config(), config);
    finish(adxl);

    let config = Config { range: Range::G4, odr: OutputDataRate::Hz4000, fifo_watermark: 3 };
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&init_traffic(ADDR, 0x00, 0x82, 3)), ADDR);
    adxl.init(config).unwrap();
    finish(adxl);
}

#[test]
fn wrong_device_id_stops_init() {
    let expectations = [I2cTransaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xEE])];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    assert_eq!(adxl.init(Config::default()), Err(Error::WrongDevice { ad: 0xAD, mst: 0x1D, part: 0xEE }));
    assert_eq!(adxl.config(), Config::default());
    finish(adxl);
}

#[test]
fn invalid_watermark_sends_nothing() {
    for watermark in [0u8, 1, 2, 4, 47, 97, 99, 255] {
        let mut adxl = Adxl355::new_i2c(I2cMock::new(&[]), ADDR);
        let config = Config { fifo_watermark: watermark, ..Config::default() };
        assert!(!config.is_valid());
        assert_eq!(adxl.init(config), Err(Error::InvalidConfig));
        finish(adxl);
    }
}

#[test]
fn status_and_fifo_entries() {
    let expectations = [
        I2cTransaction::write_read(ADDR, vec![0x04], vec![0b0000_0111]),
        I2cTransaction::write_read(ADDR, vec![0x04], vec![0b0001_1000]),
        I2cTransaction::write_read(ADDR, vec![0x05], vec![0x80 | 42]),
    ];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    assert_eq!(adxl.status().unwrap(), Status { data_ready: true, fifo_full: true, fifo_overrun: true });
    assert_eq!(adxl.status().unwrap(), Status::default());
    assert_eq!(adxl.fifo_entries().unwrap(), 42);
    finish(adxl);
}

#[test]
fn poll_status_reads_ids_status_and_entries_in_one_burst() {
    let expectations = [
        // IDs, REVID, STATUS (overrun, full, ready), FIFO_ENTRIES (bit 7 is not part of it).
        I2cTransaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED, 0x01, 0b0000_0111, 0x80 | 48]),
        I2cTransaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED, 0x01, 0, 0]),
        // A bus returning all ones, then all zeros: wrong IDs, whatever STATUS says.
        I2cTransaction::write_read(ADDR, vec![0x00], vec![0xFF; 6]),
        I2cTransaction::write_read(ADDR, vec![0x00], vec![0x00; 6]),
    ];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let all = Status { data_ready: true, fifo_full: true, fifo_overrun: true };
    assert_eq!(adxl.poll_status().unwrap(), PollStatus { status: all, fifo_entries: 48 });
    assert_eq!(adxl.poll_status().unwrap(), PollStatus::default());
    assert_eq!(adxl.poll_status(), Err(Error::WrongDevice { ad: 0xFF, mst: 0xFF, part: 0xFF }));
    assert_eq!(adxl.poll_status(), Err(Error::WrongDevice { ad: 0, mst: 0, part: 0 }));
    finish(adxl);
}

#[test]
fn config_read_back_tells_a_reset_part() {
    let mut traffic = init_traffic(ADDR, 0x03, 0x82, 30);
    traffic.extend([
        // FILTER, FIFO_SAMPLES, INT_MAP, SYNC, RANGE, POWER_CTL as programmed.
        I2cTransaction::write_read(ADDR, vec![0x28], vec![0x03, 30, 0, 0, 0x82, 0x00]),
        // The reset defaults: ODR 4 kHz, 96 entries, ±2 g, standby.
        I2cTransaction::write_read(ADDR, vec![0x28], vec![0x00, 0x60, 0, 0, 0x81, 0x01]),
        // Programmed, but in standby.
        I2cTransaction::write_read(ADDR, vec![0x28], vec![0x03, 30, 0, 0, 0x82, 0x01]),
    ]);
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&traffic), ADDR);
    adxl.init(Config { range: Range::G4, odr: OutputDataRate::Hz500, fifo_watermark: 30 }).unwrap();
    assert_eq!(adxl.config_matches(), Ok(true));
    assert_eq!(adxl.config_matches(), Ok(false));
    assert_eq!(adxl.config_matches(), Ok(false));
    finish(adxl);
}

#[test]
fn read_fifo_entries_takes_the_count_it_is_given() {
    let data = fifo_bytes(&[(1, 1), (2, 0), (3, 0), (4, 1), (5, 0), (6, 0)]);
    // 8 entries known from the status read: one 6-entry burst, no FIFO_ENTRIES read.
    let expectations = [I2cTransaction::write_read(ADDR, vec![0x11], data)];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let mut out = [RawSample::default(); 4];
    assert_eq!(adxl.read_fifo_entries(8, &mut out).unwrap(), FifoRead { samples: 2, skipped_entries: 0 });
    assert_eq!(out[1], RawSample { x: 4, y: 5, z: 6 });
    // Fewer than 3 entries, or no room: no traffic.
    assert_eq!(adxl.read_fifo_entries(2, &mut out).unwrap(), FifoRead::default());
    assert_eq!(adxl.read_fifo_entries(96, &mut []).unwrap(), FifoRead::default());
    finish(adxl);
}

#[test]
fn timeouts_are_told_from_nacks() {
    let expectations = [I2cTransaction::write_read(ADDR, vec![0x00], vec![0; 6]).with_error(ErrorKind::Other)];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let err = adxl.poll_status().unwrap_err();
    assert!(is_timeout(&err) && !is_nack(&err));
    assert!(!is_timeout(&Error::Comm(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data))));
    assert!(!is_timeout::<ErrorKind>(&Error::WrongDevice { ad: 0, mst: 0, part: 0 }));
    finish(adxl);
}

#[test]
fn read_xyz_decodes_extremes() {
    let expectations = [
        I2cTransaction::write_read(ADDR, vec![0x08], vec![0x7F, 0xFF, 0xF0, 0x80, 0x00, 0x00, 0xFF, 0xFF, 0xF0]),
        // DATA1 bits 3:0 are not data and must be ignored.
        I2cTransaction::write_read(ADDR, vec![0x08], vec![0x00, 0x00, 0x1F, 0x12, 0x34, 0x5A, 0xED, 0xCB, 0xA3]),
    ];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let s = adxl.read_xyz().unwrap();
    assert_eq!(s, RawSample { x: 524_287, y: -524_288, z: -1 });
    assert!(s.is_saturated());
    let s = adxl.read_xyz().unwrap();
    assert_eq!(s, RawSample { x: 1, y: 0x12345, z: 0xEDCBA - 0x100000 });
    assert!(!s.is_saturated());
    finish(adxl);
}

#[test]
fn axis_codec_round_trips() {
    for code in [0, 1, -1, 256_000, -256_000, 524_287, -524_288, 0x12345, -0x54321] {
        assert_eq!(encode_axis(code, 0x3), bytes_of(code, 0x3));
        assert_eq!(decode_axis(encode_axis(code, 0x3)), code);
    }
    assert_eq!(encode_axis(600_000, 0), bytes_of(524_287, 0));
    assert_eq!(encode_axis(-600_000, 0), bytes_of(-524_288, 0));
}

#[test]
fn read_fifo_reads_one_burst() {
    // 7 entries available: round down to 6 (two samples).
    let data = fifo_bytes(&[(100, 1), (-200, 0), (256_000, 0), (524_287, 1), (-524_288, 0), (-1, 0)]);
    let expectations =
        [I2cTransaction::write_read(ADDR, vec![0x05], vec![7]), I2cTransaction::write_read(ADDR, vec![0x11], data)];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let mut out = [RawSample::default(); 4];
    let read = adxl.read_fifo(&mut out).unwrap();
    assert_eq!(read, FifoRead { samples: 2, skipped_entries: 0 });
    assert_eq!(out[0], RawSample { x: 100, y: -200, z: 256_000 });
    assert_eq!(out[1], RawSample { x: 524_287, y: -524_288, z: -1 });
    finish(adxl);
}

#[test]
fn read_fifo_caps_burst_at_output_length() {
    let data = fifo_bytes(&[(1, 1), (2, 0), (3, 0)]);
    let expectations =
        [I2cTransaction::write_read(ADDR, vec![0x05], vec![96]), I2cTransaction::write_read(ADDR, vec![0x11], data)];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let mut out = [RawSample::default(); 1];
    assert_eq!(adxl.read_fifo(&mut out).unwrap(), FifoRead { samples: 1, skipped_entries: 0 });
    assert_eq!(out[0], RawSample { x: 1, y: 2, z: 3 });
    finish(adxl);
}

#[test]
fn read_fifo_without_whole_sample_sends_no_burst() {
    let expectations = [I2cTransaction::write_read(ADDR, vec![0x05], vec![2])];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let mut out = [RawSample::default(); 4];
    assert_eq!(adxl.read_fifo(&mut out).unwrap(), FifoRead::default());
    // An empty output slice needs no traffic at all.
    assert_eq!(adxl.read_fifo(&mut []).unwrap(), FifoRead::default());
    finish(adxl);
}

#[test]
fn read_fifo_realigns_on_x_marker() {
    // Starts at Y: skip Y, Z; then one good set; then X, Y cut off by the end of the burst.
    let data = fifo_bytes(&[(20, 0), (30, 0), (11, 1), (21, 0), (31, 0), (12, 1), (22, 0), (32, 0), (13, 1)]);
    let expectations =
        [I2cTransaction::write_read(ADDR, vec![0x05], vec![9]), I2cTransaction::write_read(ADDR, vec![0x11], data)];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let mut out = [RawSample::default(); 3];
    let read = adxl.read_fifo(&mut out).unwrap();
    assert_eq!(read, FifoRead { samples: 2, skipped_entries: 3 });
    assert_eq!(out[0], RawSample { x: 11, y: 21, z: 31 });
    assert_eq!(out[1], RawSample { x: 12, y: 22, z: 32 });
    finish(adxl);
}

#[test]
fn fifo_decoder_skips_empty_and_broken_sets() {
    let data = fifo_bytes(&[
        (1, 1),
        (2, 0),
        (0, 1), // X marker before the set was complete: drop (1, 2)
        (5, 0),
        (6, 0),
        (0, 2), // empty indicator
        (7, 1),
        (0, 2), // empty in the middle of a set: drop it
        (8, 0), // unaligned
    ]);
    let mut out = [RawSample::default(); 3];
    let read = decode_fifo(&data, &mut out);
    assert_eq!(read, FifoRead { samples: 1, skipped_entries: 6 });
    assert_eq!(out[0], RawSample { x: 0, y: 5, z: 6 });
}

#[test]
fn to_mps2_uses_standard_gravity() {
    let mut traffic = init_traffic(ADDR, 0x02, 0x81, 48);
    traffic.extend(init_traffic(ADDR, 0x02, 0x83, 48));
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&traffic), ADDR);
    adxl.init(Config::default()).unwrap();
    let [x, y, z] = adxl.to_mps2(RawSample { x: 256_000, y: -128_000, z: 0 });
    assert!((x - 9.80665).abs() < 2e-6, "{x}");
    assert!((y + 4.903325).abs() < 1e-6, "{y}");
    assert_eq!(z, 0.0);
    // Bit-exact: the scale is precomputed in f32 as 9.80665 / 256000.
    assert_eq!(x, 256_000.0f32 * (9.80665f32 / 256_000.0f32));

    adxl.init(Config { range: Range::G8, ..Config::default() }).unwrap();
    let [x, _, _] = adxl.to_mps2(RawSample { x: 64_000, y: 0, z: 0 });
    assert!((x - 9.80665).abs() < 2e-6, "{x}");
    finish(adxl);
}

#[test]
fn range_and_rate_tables() {
    assert_eq!([Range::G2, Range::G4, Range::G8].map(Range::lsb_per_g), [256_000.0, 128_000.0, 64_000.0]);
    assert_eq!([Range::G2, Range::G4, Range::G8].map(Range::full_scale_g), [2.048, 4.096, 8.192]);
    assert_eq!(Range::from_register_code(0x81), Some(Range::G2));
    assert_eq!(Range::from_register_code(0x80), None);
    let hz = OutputDataRate::ALL.map(OutputDataRate::hz);
    assert_eq!(hz, [4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625, 7.813, 3.906]);
    let lp = OutputDataRate::ALL.map(OutputDataRate::lowpass_hz);
    assert_eq!(lp, [1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625, 7.813, 3.906, 1.953, 0.977]);
    for (code, odr) in OutputDataRate::ALL.iter().enumerate() {
        assert_eq!(usize::from(odr.register_code()), code);
        assert_eq!(OutputDataRate::from_register_code(code as u8), Some(*odr));
        assert_eq!(odr.filter_delay_samples(), 2.5);
    }
    assert_eq!(OutputDataRate::from_register_code(11), None);
    assert!((OutputDataRate::Hz1000.filter_delay_s() - 0.0025).abs() < 1e-9);
}

#[test]
fn spi_command_bytes() {
    let expectations = [
        // ID burst: read command (0x00 << 1) | 1.
        SpiTransaction::transaction_start(),
        SpiTransaction::write(0x01),
        SpiTransaction::read_vec(vec![0xAD, 0x1D, 0xED]),
        SpiTransaction::transaction_end(),
        // Writes: (reg << 1), value.
        SpiTransaction::transaction_start(),
        SpiTransaction::write_vec(vec![0x5E, 0x52]),
        SpiTransaction::transaction_end(),
        SpiTransaction::transaction_start(),
        SpiTransaction::write_vec(vec![0x50, 0x02]),
        SpiTransaction::transaction_end(),
        SpiTransaction::transaction_start(),
        SpiTransaction::write_vec(vec![0x58, 0x81]),
        SpiTransaction::transaction_end(),
        SpiTransaction::transaction_start(),
        SpiTransaction::write_vec(vec![0x52, 48]),
        SpiTransaction::transaction_end(),
        SpiTransaction::transaction_start(),
        SpiTransaction::write_vec(vec![0x5A, 0x00]),
        SpiTransaction::transaction_end(),
        // read_xyz: (0x08 << 1) | 1 = 0x11.
        SpiTransaction::transaction_start(),
        SpiTransaction::write(0x11),
        SpiTransaction::read_vec(vec![0x00, 0x00, 0x10, 0, 0, 0, 0, 0, 0]),
        SpiTransaction::transaction_end(),
    ];
    let mut adxl = Adxl355::new_spi(SpiMock::new(&expectations));
    adxl.init(Config::default()).unwrap();
    assert_eq!(adxl.read_xyz().unwrap(), RawSample { x: 1, y: 0, z: 0 });
    adxl.release().release().done();
}

#[test]
fn nack_propagates_as_comm_error() {
    let nack = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address);
    let expectations = [
        I2cTransaction::write_read(ADDR, vec![0x08], vec![0; 9]).with_error(nack),
        I2cTransaction::write_read(ADDR, vec![0x05], vec![0]).with_error(ErrorKind::ArbitrationLoss),
        I2cTransaction::write_read(ADDR, vec![0x04], vec![0x01]),
    ];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let err = adxl.read_xyz().unwrap_err();
    assert_eq!(err, Error::Comm(nack));
    assert!(is_nack(&err));
    let err = adxl.read_fifo(&mut [RawSample::default(); 2]).unwrap_err();
    assert_eq!(err, Error::Comm(ErrorKind::ArbitrationLoss));
    assert!(!is_nack(&err));
    // The driver holds no half-done state: the next call just works.
    assert!(adxl.status().unwrap().data_ready);
    finish(adxl);
}

#[test]
fn nack_during_init_keeps_old_config() {
    let nack = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data);
    let expectations = [
        I2cTransaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED]),
        I2cTransaction::write(ADDR, vec![0x2F, 0x52]).with_error(nack),
    ];
    let mut adxl = Adxl355::new_i2c(I2cMock::new(&expectations), ADDR);
    let err = adxl.init(Config { range: Range::G4, ..Config::default() }).unwrap_err();
    assert!(is_nack(&err));
    assert_eq!(adxl.config().range, Range::G2);
    finish(adxl);
}

#[test]
fn error_display_is_readable() {
    use std::string::ToString;
    let e: Error<ErrorKind> = Error::WrongDevice { ad: 0xAD, mst: 0x1D, part: 0xEE };
    assert_eq!(e.to_string(), "not an ADXL355: ids 0xad 0x1d 0xee (expected 0xad 0x1d 0xed)");
    assert!(Error::<ErrorKind>::InvalidConfig.to_string().contains("watermark"));
}
