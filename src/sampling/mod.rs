//! Random numbers that depend only on (seed, stream, index): an image never depends on thread
//! scheduling or on how work is split.

/// SplitMix64's finaliser: a strong 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hash of a seed and two counters (e.g. pixel and sample).
#[inline]
pub fn hash3(seed: u64, a: u64, b: u64) -> u64 {
    mix64(
        seed ^ mix64(
            a.wrapping_add(0x9e37_79b9_7f4a_7c15) ^ mix64(b.wrapping_mul(0xd1b5_4a32_d192_ed03)),
        ),
    )
}

/// A small generator seeded from `hash3(seed, a, b)`.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    pub fn new(seed: u64, a: u64, b: u64) -> Rng {
        Rng {
            state: hash3(seed, a, b),
        }
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.state)
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}
