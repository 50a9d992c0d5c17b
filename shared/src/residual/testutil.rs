//! Deterministic noise for the residual tests: xorshift64* and Box–Muller, so every run (and
//! every machine) sees the same numbers.

/// A small deterministic random number generator.
pub(crate) struct Rng {
    state: u64,
    spare: Option<f64>,
}

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        // Any non-zero state works; mix the seed so that seeds 1, 2, 3 … are unrelated streams.
        let mut rng = Self { state: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1, spare: None };
        for _ in 0..8 {
            rng.next_u64();
        }
        rng
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        let mut x = self.state;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.state = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in (0, 1).
    pub(crate) fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal.
    pub(crate) fn gauss(&mut self) -> f64 {
        if let Some(v) = self.spare.take() {
            return v;
        }
        let r = libm::sqrt(-2.0 * libm::log(self.uniform()));
        let t = core::f64::consts::TAU * self.uniform();
        self.spare = Some(r * libm::sin(t));
        r * libm::cos(t)
    }
}
