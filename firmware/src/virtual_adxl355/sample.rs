//! One sample period of the virtual device's input: the true acceleration and the faults it
//! injects with it (what a CSV line and every feed yield).

/// One sample period of input to the [`VirtualAdxl355`](super::VirtualAdxl355).
///
/// Besides the acceleration, each sample may carry fault instructions for the virtual device.
/// The bus faults (`nack`, `timeout`, `garbage`) are queued when the sample's period passes and
/// hit the transactions that follow; the others act on the sample itself.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeedSample {
    /// True acceleration on X, Y, Z in m/s² (before quantisation and saturation).
    pub accel: [f32; 3],
    /// Number of bus transactions to NACK once this sample is due: a bus glitch the firmware's
    /// retry layer must ride through.
    pub nack: u8,
    /// Number of bus transactions to fail with a timeout once this sample is due: a bus held
    /// low for a while, which the node does not retry within the poll.
    pub timeout: u8,
    /// Number of bus transactions whose read data is garbage (every byte `0xFF`, writes lost)
    /// once this sample is due: the ID registers read back wrong, and the node must not take
    /// the FIFO data of such a transaction for samples.
    pub garbage: u8,
    /// Output frozen: the device repeats its previous output codes instead of this sample,
    /// the signature of a stuck sensor that the diagnostics must catch.
    pub stuck: bool,
    /// The device produces no sample for this period (nothing enters the FIFO): the node must
    /// bridge it by prediction so that the estimator's clock does not slip.
    pub dropped: bool,
    /// The device resets as this sample is due: registers back to their defaults (standby),
    /// FIFO cleared; this sample and every one until the node reconfigures the part are lost.
    pub reset: bool,
}

impl FeedSample {
    /// A fault-free sample.
    pub const fn new(accel: [f32; 3]) -> Self {
        FeedSample { accel, nack: 0, timeout: 0, garbage: 0, stuck: false, dropped: false, reset: false }
    }
}
