//! Bus interfaces: the register-level protocol over I2C or SPI.
//!
//! The driver only needs "write one register" and "read a run of registers in one
//! transaction"; keeping that behind a trait lets the same driver run on I2C, SPI, a mock bus
//! in tests and the [`VirtualAdxl355`](crate::virtual_adxl355::VirtualAdxl355).

use embedded_hal::i2c::I2c;
use embedded_hal::spi::{Operation, SpiDevice};

/// Register access to the part.
pub trait Interface {
    /// The bus error.
    type Error;

    /// Writes `value` to register `reg`.
    fn write_register(&mut self, reg: u8, value: u8) -> Result<(), Self::Error>;

    /// Reads `buf.len()` bytes starting at register `start`, in one bus transaction.
    ///
    /// The part auto-increments the address after each byte, except at `FIFO_DATA` (0x11),
    /// where every byte comes from the FIFO: that is what makes a one-transaction FIFO burst
    /// possible.
    fn read_registers(&mut self, start: u8, buf: &mut [u8]) -> Result<(), Self::Error>;

    /// Whether `error` is a "no acknowledge", the transient failure a retry layer counts as
    /// such (only I2C has them; the default says no).
    fn is_nack(error: &Self::Error) -> bool {
        let _ = error;
        false
    }

    /// Whether `error` is a timeout, which a retry layer does not retry at once (the default
    /// says no).
    fn is_timeout(error: &Self::Error) -> bool {
        let _ = error;
        false
    }
}

/// The part on an I2C bus: a register write is `[reg, value]`; a read is a write of `[reg]`
/// followed by a repeated-start read.
#[derive(Debug)]
pub struct I2cInterface<I2C> {
    i2c: I2C,
    address: u8,
}

impl<I2C> I2cInterface<I2C> {
    /// Wraps `i2c`; the part answers at `address` (7-bit:
    /// [`ADDRESS_ASEL_LOW`](super::ADDRESS_ASEL_LOW) or
    /// [`ADDRESS_ASEL_HIGH`](super::ADDRESS_ASEL_HIGH)).
    pub fn new(i2c: I2C, address: u8) -> Self {
        I2cInterface { i2c, address }
    }

    /// The 7-bit device address in use.
    pub fn address(&self) -> u8 {
        self.address
    }

    /// The bus, e.g. to inspect a test double.
    pub fn bus(&self) -> &I2C {
        &self.i2c
    }

    /// The bus, mutably, e.g. to talk to another device on it or to finish a mock.
    pub fn bus_mut(&mut self) -> &mut I2C {
        &mut self.i2c
    }

    /// Gives the bus back.
    pub fn release(self) -> I2C {
        self.i2c
    }
}

impl<I2C: I2c> Interface for I2cInterface<I2C> {
    type Error = I2C::Error;

    fn write_register(&mut self, reg: u8, value: u8) -> Result<(), Self::Error> {
        self.i2c.write(self.address, &[reg, value])
    }

    fn read_registers(&mut self, start: u8, buf: &mut [u8]) -> Result<(), Self::Error> {
        self.i2c.write_read(self.address, &[start], buf)
    }

    fn is_nack(error: &Self::Error) -> bool {
        super::error::is_i2c_nack(error)
    }

    fn is_timeout(error: &Self::Error) -> bool {
        super::error::is_i2c_timeout(error)
    }
}

/// The part on an SPI bus. The first byte of a transaction is the command
/// `(register << 1) | R/W̄`: bit 0 set for a read, clear for a write.
#[derive(Debug)]
pub struct SpiInterface<SPI> {
    spi: SPI,
}

impl<SPI> SpiInterface<SPI> {
    /// Wraps `spi` (a device: the chip select is managed by the `SpiDevice`).
    pub fn new(spi: SPI) -> Self {
        SpiInterface { spi }
    }

    /// The bus device.
    pub fn bus(&self) -> &SPI {
        &self.spi
    }

    /// The bus device, mutably.
    pub fn bus_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// Gives the bus device back.
    pub fn release(self) -> SPI {
        self.spi
    }
}

/// SPI command byte: the 7-bit register address in bits 7:1, the read flag in bit 0.
const fn spi_command(reg: u8, read: bool) -> u8 {
    ((reg & 0x7F) << 1) | read as u8
}

impl<SPI: SpiDevice> Interface for SpiInterface<SPI> {
    type Error = SPI::Error;

    fn write_register(&mut self, reg: u8, value: u8) -> Result<(), Self::Error> {
        self.spi.write(&[spi_command(reg, false), value])
    }

    fn read_registers(&mut self, start: u8, buf: &mut [u8]) -> Result<(), Self::Error> {
        self.spi.transaction(&mut [Operation::Write(&[spi_command(start, true)]), Operation::Read(buf)])
    }
}
