//! Driver errors.

use core::fmt;

/// Everything the driver can report. `CommE` is the bus error of the interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<CommE> {
    /// The bus transaction failed (NACK, arbitration loss, ...). Often transient: see
    /// [`is_nack`] for the case a retry layer can usually recover.
    Comm(CommE),
    /// The identification registers do not read as an ADXL355: wrong part, wrong address, or
    /// a bus that returns garbage. The three bytes read are kept for the log.
    WrongDevice {
        /// `DEVID_AD` as read (0xAD expected).
        ad: u8,
        /// `DEVID_MST` as read (0x1D expected).
        mst: u8,
        /// `PARTID` as read (0xED expected).
        part: u8,
    },
    /// The [`Config`](super::Config) is out of range; nothing was sent to the part.
    InvalidConfig,
}

impl<CommE> From<CommE> for Error<CommE> {
    fn from(e: CommE) -> Self {
        Error::Comm(e)
    }
}

impl<CommE: fmt::Debug> fmt::Display for Error<CommE> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Comm(e) => write!(f, "ADXL355 bus error: {e:?}"),
            Error::WrongDevice { ad, mst, part } => {
                write!(f, "not an ADXL355: ids {ad:#04x} {mst:#04x} {part:#04x} (expected 0xad 0x1d 0xed)")
            }
            Error::InvalidConfig => {
                f.write_str("invalid ADXL355 configuration (FIFO watermark must be 3..=96, a multiple of 3)")
            }
        }
    }
}

impl<CommE: fmt::Debug> core::error::Error for Error<CommE> {}

/// Whether `e` is an I2C "no acknowledge" (address or data), the transient failure a retry
/// layer should retry: the part NACKs while it is busy (e.g. just after a reset) and a marginal
/// bus NACKs now and then. Other errors (arbitration loss, wrong device) are not retried.
///
/// ```
/// use edgekf_firmware::adxl355::{is_nack, Error};
/// use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
/// let nack: Error<ErrorKind> = Error::Comm(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data));
/// assert!(is_nack(&nack));
/// assert!(!is_nack(&Error::Comm(ErrorKind::Bus)));
/// assert!(!is_nack::<ErrorKind>(&Error::InvalidConfig));
/// ```
pub fn is_nack<E: embedded_hal::i2c::Error>(e: &Error<E>) -> bool {
    matches!(e, Error::Comm(c) if is_i2c_nack(c))
}

/// Whether `e` is an I2C timeout: embedded-hal 1.0 has no timeout kind, and HALs report theirs
/// as `ErrorKind::Other` (stm32f4xx-hal's `Error::Timeout`, the virtual bus's
/// `VirtualBusError::Timeout`), so that kind counts as one. A timeout already cost the HAL's
/// wait; the node does not retry it within a poll (see [`crate::source`]).
///
/// ```
/// use edgekf_firmware::adxl355::{is_timeout, Error};
/// use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
/// assert!(is_timeout(&Error::Comm(ErrorKind::Other)));
/// assert!(!is_timeout(&Error::Comm(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address))));
/// ```
pub fn is_timeout<E: embedded_hal::i2c::Error>(e: &Error<E>) -> bool {
    matches!(e, Error::Comm(c) if is_i2c_timeout(c))
}

/// Whether an I2C bus error is a timeout (kind `Other`, see [`is_timeout`]).
pub(crate) fn is_i2c_timeout<E: embedded_hal::i2c::Error>(e: &E) -> bool {
    matches!(e.kind(), embedded_hal::i2c::ErrorKind::Other)
}

/// Whether an I2C bus error is a NACK (address or data).
pub(crate) fn is_i2c_nack<E: embedded_hal::i2c::Error>(e: &E) -> bool {
    matches!(e.kind(), embedded_hal::i2c::ErrorKind::NoAcknowledge(_))
}
