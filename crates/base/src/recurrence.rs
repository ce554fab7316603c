//! Which of a run of matching events a fault fires on, and the
//! deterministic PRNG behind fault probabilities: shared by the CAN bus's
//! rules (`drivebus_can::FaultRule`) and the EtherCAT line's faults.

/// xorshift64* PRNG.
///
/// Hand-written rather than a `rand` dependency: the crate is `no_std`, needs
/// no cryptographic quality, and a simulation must replay bit-for-bit from its
/// seed whatever version of an external crate is resolved.
#[derive(Clone, Debug)]
pub struct XorShift64 {
    state: u64,
}

impl XorShift64 {
    /// A generator from `seed`; seed 0 (a fixed point of xorshift) is remapped.
    pub const fn new(seed: u64) -> Self {
        XorShift64 { state: if seed == 0 { 0x9E37_79B9_7F4A_7C15 } else { seed } }
    }
    /// Next 64 pseudo-random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.state;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.state = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `0..n` (`0` when `n == 0`); the tiny modulo bias is irrelevant here.
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 { 0 } else { self.next_u64() % n }
    }
}

/// Which of the matching events a rule fires on: it skips the first
/// `skip`, takes only every `every`-th after them, fires at most `times`
/// times, each time with a probability drawn from a seeded
/// [`XorShift64`]. The counting half of [`FaultRule`], also used by the
/// EtherCAT line's faults (`drivebus_esc::segment::LineFault`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Recurrence {
    skip: u32,
    every: u32,
    /// Matches seen after the skipped ones (for `every`).
    seen: u32,
    remaining: Option<u32>,
    /// Fires when a draw is below this; `None` means always.
    threshold: Option<u64>,
    fired: u32,
}

impl Default for Recurrence {
    fn default() -> Self {
        Recurrence::always()
    }
}

impl Recurrence {
    /// Every match, forever.
    pub const fn always() -> Self {
        Recurrence { skip: 0, every: 1, seen: 0, remaining: None, threshold: None, fired: 0 }
    }
    /// Let the first `n` matches through.
    pub fn skip(mut self, n: u32) -> Self {
        self.skip = n;
        self
    }
    /// After the skipped matches, only every `n`-th (`n` ≥ 1: the 1st, the
    /// `n+1`-th, …).
    pub fn every(mut self, n: u32) -> Self {
        self.every = n.max(1);
        self
    }
    /// At most `n` times.
    pub fn times(mut self, n: u32) -> Self {
        self.remaining = Some(n);
        self
    }
    /// With probability `p` (clamped to 0..=1) on each match.
    pub fn probability(mut self, p: f64) -> Self {
        self.threshold = if p >= 1.0 {
            None
        } else if p > 0.0 {
            // 2^64 · p; `as` saturates, NaN maps to 0 (never fires).
            Some((p * 18_446_744_073_709_551_616.0) as u64)
        } else {
            Some(0)
        };
        self
    }
    /// How many times it has fired.
    pub fn fired(&self) -> u32 {
        self.fired
    }
    /// Whether it will never fire again (`times` used up).
    pub fn is_spent(&self) -> bool {
        self.remaining == Some(0)
    }
    /// One more match: whether it fires, updating the counters; `rng`
    /// draws the probability.
    pub fn fire(&mut self, rng: &mut XorShift64) -> bool {
        if self.remaining == Some(0) {
            return false;
        }
        if self.skip > 0 {
            self.skip -= 1;
            return false;
        }
        self.seen = self.seen.wrapping_add(1);
        if !(self.seen - 1).is_multiple_of(self.every) {
            return false;
        }
        if let Some(t) = self.threshold
            && rng.next_u64() >= t
        {
            return false;
        }
        if let Some(r) = &mut self.remaining {
            *r -= 1;
        }
        self.fired = self.fired.saturating_add(1);
        true
    }
}
