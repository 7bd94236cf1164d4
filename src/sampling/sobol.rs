//! The path tracer's numbers: the first two dimensions of the Sobol sequence, shuffled afresh
//! for every dimension a path draws (the index Owen-scrambled, as in Burley's "Practical
//! Hash-based Owen Scrambling", JCGT 2020; pbrt-v4's padded Sobol sampler permutes it too)
//! and each coordinate randomised by a digital shift. The samples of one pixel then cover each
//! 2-D draw — a point on the light, a bounce direction — as a (0, m, 2)-net: one point in each
//! of the 2^m elementary intervals of every shape, where independent numbers leave clumps and
//! holes. Every point is still uniform in the square, so the estimate stays unbiased. On the
//! Cornell box at 64 samples a pixel the relMSE falls to 0.64× at 1.04–1.06× the time
//! (BENCHMARKS.md, session 33).
//!
//! Everything is a hash of (seed, pixel, dimension) and the sample's index, as `Rng` is: an
//! image does not depend on threads or on how a render is split into parts.

use super::{mix64, Rng, UNIT_24};

/// Where the path tracer's numbers come from (`--sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PathSampler {
    /// A pixel's paths stratified together: each draw from a dimension of its own of the
    /// pixel's scrambled Sobol points (pbrt-v4's default sampler is of this kind).
    #[default]
    Sobol,
    /// Independent uniform numbers for every path (Mitsuba 3's `independent` sampler, and
    /// this renderer's until session 33).
    Independent,
}

/// Which camera sample a path belongs to: what its numbers are drawn from.
#[derive(Clone, Copy, Debug)]
pub struct SampleId {
    /// `--seed`.
    pub seed: u64,
    /// The pixel's number (row-major from the bottom row).
    pub pixel: u64,
    /// The sample's number within its pixel.
    pub index: u32,
    /// Samples a pixel takes in all, None when open-ended (`--time-limit`).
    pub count: Option<u32>,
}

/// Where a path's random numbers come from, one draw at a time.
pub struct PathSamples {
    source: Source,
}

enum Source {
    /// Independent uniform numbers.
    Independent(Rng),
    /// The scrambled Sobol points of one pixel.
    Sobol(SobolPoints),
}

/// One camera sample's points of its pixel's scrambled Sobol sequence, a dimension a draw.
struct SobolPoints {
    /// Hash of (seed, pixel): the scrambles of every dimension derive from it.
    pixel: u64,
    /// The sample's index, its bits reversed (what the index shuffle starts from).
    reversed_index: u32,
    /// The shuffled index keeps its low bits, as many as the pixel's sample count needs, so
    /// that its samples fill one aligned block of the sequence (all 32 when open-ended): the
    /// mask of those bits reversed.
    keep: u32,
    /// Dimensions made so far: each draw takes the point of a dimension of its own.
    dimension: u64,
    /// Points made ahead of their draws (`prepare`), the next first.
    ahead: Ahead,
}

/// The most points `prepare` makes ahead: about a vertex's draws.
const AHEAD: usize = 3;

/// Points of the next dimensions, made before they are drawn, in a ring.
#[derive(Clone, Copy, Default)]
struct Ahead {
    points: [(f32, f32); AHEAD],
    first: usize,
    len: usize,
}

impl SobolPoints {
    /// The point of the dimension after the last one made.
    #[inline(always)]
    fn make(&mut self) -> (f32, f32) {
        self.dimension += 1;
        sobol_point(self.pixel, self.dimension, self.reversed_index, self.keep)
    }

    /// See `PathSamples::prepare`.
    #[inline]
    fn prepare(&mut self) {
        while self.ahead.len < AHEAD {
            let slot = (self.ahead.first + self.ahead.len) % AHEAD;
            self.ahead.points[slot] = self.make();
            self.ahead.len += 1;
        }
    }

    /// The point of the next draw: made ahead, or now.
    #[inline(always)]
    fn next(&mut self) -> (f32, f32) {
        if self.ahead.len == 0 {
            return self.make();
        }
        let point = self.ahead.points[self.ahead.first];
        self.ahead.first = (self.ahead.first + 1) % AHEAD;
        self.ahead.len -= 1;
        point
    }
}

impl PathSamples {
    /// The numbers of camera sample `id`.
    pub fn sobol(id: SampleId) -> PathSamples {
        let bits = id.count.map_or(32, |n| {
            u32::BITS - n.max(1).saturating_sub(1).leading_zeros()
        });
        PathSamples {
            source: Source::Sobol(SobolPoints {
                pixel: mix64(id.seed ^ mix64(id.pixel.wrapping_add(0x5bd1_e995))),
                reversed_index: id.index.reverse_bits(),
                keep: if bits >= 32 {
                    u32::MAX
                } else {
                    ((1u32 << bits) - 1).reverse_bits()
                },
                dimension: 0,
                ahead: Ahead::default(),
            }),
        }
    }

    /// The numbers of camera sample `id` by `sampler`; `rng` is the sample's own generator
    /// (what `Independent` draws from).
    pub fn new(sampler: PathSampler, id: SampleId, rng: Rng) -> PathSamples {
        match sampler {
            PathSampler::Sobol => PathSamples::sobol(id),
            PathSampler::Independent => PathSamples::independent(rng),
        }
    }

    /// Independent numbers from `rng` (where there is no pixel to stratify over).
    pub fn independent(rng: Rng) -> PathSamples {
        PathSamples {
            source: Source::Independent(rng),
        }
    }

    /// One number in [0, 1): a dimension of its own (the first coordinate of its point).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        match &mut self.source {
            Source::Independent(rng) => rng.next_f32(),
            Source::Sobol(points) => points.next().0,
        }
    }

    /// Two numbers in [0, 1)², stratified together across the pixel's samples.
    #[inline]
    pub fn next_2d(&mut self) -> (f32, f32) {
        match &mut self.source {
            Source::Independent(rng) => (rng.next_f32(), rng.next_f32()),
            Source::Sobol(points) => points.next(),
        }
    }

    /// Makes the points of the next draws now (as many as a vertex takes), where their
    /// latency can hide under work that does not need them: the path tracer calls it before
    /// tracing the ray to the next vertex, whose traversal runs beside these multiplies (the
    /// Cornell box at 64 paths a pixel: 0.95× the time). The numbers drawn are the same
    /// either way.
    #[inline]
    pub fn prepare(&mut self) {
        if let Source::Sobol(points) = &mut self.source {
            points.prepare();
        }
    }
}

/// Point `reversed_index` (bits reversed) of dimension `dimension` of the pixel hashed to
/// `pixel`, its shuffled index kept to `keep` (a mask of the top bits, the index reversed).
#[inline(always)]
fn sobol_point(pixel: u64, dimension: u64, reversed_index: u32, keep: u32) -> (f32, f32) {
    let seeds = mix64(pixel ^ dimension.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    // Owen-scrambling the index shuffles it so that the first 2^q samples of the pixel stay
    // one aligned block of 2^q Sobol points (a net), in another order in every dimension:
    // the dimensions' points are not paired alike. The scramble runs on the reversed index,
    // and the point's first coordinate is that reversed index itself: no reversal at all.
    let reversed = laine_karras(reversed_index, (seeds >> 32) as u32) & keep;
    // A random digital shift of each coordinate (an XOR; it keeps the net, and makes each
    // point uniform in the square).
    let shift_x = seeds as u32;
    let shift_y = (seeds.wrapping_mul(0xd1b5_4a32_d192_ed03) >> 32) as u32;
    (
        to_unit(reversed ^ shift_x),
        to_unit(sobol_second_of_reversed(reversed) ^ shift_y),
    )
}

/// A 32-bit fraction's top 24 bits as a float in [0, 1).
#[inline(always)]
fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * UNIT_24
}

/// The Sobol sequence's second dimension by bytes of the bit-reversed index: `SECOND_BY_BYTE
/// [i][b]` is the coordinate of the index whose byte `i` (from the low end) is `b` reversed and
/// which is zero elsewhere. The sequence is linear over bits (XOR), so a point is the XOR of
/// its four bytes' entries: four loads where a loop over the index's bits took a dozen steps.
/// The direction numbers (primitive polynomial x + 1) are v₀ = 2³¹, vⱼ = vⱼ₋₁ ⊕ (vⱼ₋₁ >> 1);
/// the first dimension's are the powers of two, which make it the bit-reversed index.
static SECOND_BY_BYTE: [[u32; 256]; 4] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut j = 1;
    while j < 32 {
        v[j] = v[j - 1] ^ (v[j - 1] >> 1);
        j += 1;
    }
    let mut table = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut b = 0;
        while b < 256 {
            // Bit k of the reversed byte b is bit 7 − k of b: index bit 8·byte + 7 − k.
            let mut x = 0;
            let mut k = 0;
            while k < 8 {
                if b >> k & 1 != 0 {
                    x ^= v[8 * byte + 7 - k];
                }
                k += 1;
            }
            table[byte][b] = x;
            b += 1;
        }
        byte += 1;
    }
    table
};

/// The second coordinate, as a 32-bit fraction, of the Sobol point whose index reversed is
/// `reversed` (byte 0 of the index is the top byte of `reversed`).
#[inline(always)]
fn sobol_second_of_reversed(reversed: u32) -> u32 {
    let byte = |i: u32| (reversed >> (24 - 8 * i) & 0xff) as usize;
    SECOND_BY_BYTE[0][byte(0)]
        ^ SECOND_BY_BYTE[1][byte(1)]
        ^ SECOND_BY_BYTE[2][byte(2)]
        ^ SECOND_BY_BYTE[3][byte(3)]
}

/// A hash in which each bit is flipped by a function of the bits below it only: on a
/// bit-reversed index, a nested uniform (Owen) scramble of the index (Laine and Karras 2011,
/// Burley's constants).
#[inline(always)]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixel_points(pixel: u64, count: u32, draws: usize) -> Vec<Vec<(f32, f32)>> {
        let mut per_draw = vec![Vec::new(); draws];
        for index in 0..count {
            let mut s = PathSamples::sobol(SampleId {
                seed: 7,
                pixel,
                index,
                count: Some(count),
            });
            for points in per_draw.iter_mut() {
                points.push(s.next_2d());
            }
        }
        per_draw
    }

    /// Every 2-D draw of a pixel's 2^m samples is a (0, m, 2)-net: for every split of m bits
    /// between the axes, each of the 2^m elementary boxes holds exactly one point.
    #[test]
    fn each_draw_of_a_pixels_samples_is_a_net() {
        for m in [0u32, 1, 4, 6, 8] {
            let n = 1u32 << m;
            for pixel in [0u64, 1, 12345] {
                for (draw, points) in pixel_points(pixel, n, 5).iter().enumerate() {
                    for bits_x in 0..=m {
                        let (nx, ny) = (1u32 << bits_x, 1u32 << (m - bits_x));
                        let mut seen = vec![false; n as usize];
                        for &(x, y) in points {
                            assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                            let cell = (x * nx as f32) as u32 * ny + (y * ny as f32) as u32;
                            assert!(
                                !std::mem::replace(&mut seen[cell as usize], true),
                                "m {m}, pixel {pixel}, draw {draw}: two points in box {cell} of {nx}×{ny}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// Open-ended: the first 2^q samples of a pixel are a net for every q, whatever comes
    /// after them.
    #[test]
    fn open_ended_samples_are_nets_at_every_power_of_two() {
        let mut points = Vec::new();
        for index in 0..256u32 {
            let mut s = PathSamples::sobol(SampleId {
                seed: 3,
                pixel: 99,
                index,
                count: None,
            });
            s.next_1d();
            points.push(s.next_2d());
        }
        for q in 0..=8u32 {
            let n = 1usize << q;
            for axis in 0..2 {
                let mut seen = vec![false; n];
                for &(x, y) in &points[..n] {
                    let cell = ([x, y][axis] * n as f32) as usize;
                    assert!(
                        !std::mem::replace(&mut seen[cell], true),
                        "q {q}: axis {axis}, cell {cell}"
                    );
                }
            }
        }
    }

    /// The draws are not the same points in the same order: the correlation of one draw's x
    /// with the next draw's x over a pixel's samples is near zero (it would be 1 unshuffled),
    /// and two pixels' points differ.
    #[test]
    fn draws_and_pixels_are_decorrelated() {
        let n = 256;
        let draws = pixel_points(5, n, 4);
        for pair in draws.windows(2) {
            let (a, b): (Vec<f32>, Vec<f32>) = pair[0]
                .iter()
                .zip(&pair[1])
                .map(|(p, q)| (p.0 - 0.5, q.0 - 0.5))
                .unzip();
            let dot: f32 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let norm = (a.iter().map(|x| x * x).sum::<f32>()
                * b.iter().map(|y| y * y).sum::<f32>())
            .sqrt();
            assert!((dot / norm).abs() < 0.2, "correlation {}", dot / norm);
        }
        assert_ne!(draws[0], pixel_points(6, n, 1)[0]);
    }

    /// Points made ahead (`prepare`) are the points drawn without it, in the same order,
    /// whatever mix of 1-D and 2-D draws comes between.
    #[test]
    fn points_made_ahead_are_the_same_points() {
        let id = SampleId {
            seed: 11,
            pixel: 4321,
            index: 17,
            count: Some(64),
        };
        let (mut plain, mut ahead) = (PathSamples::sobol(id), PathSamples::sobol(id));
        for step in 0..40 {
            if step % 3 == 0 {
                ahead.prepare();
            }
            if step % 4 == 1 {
                assert_eq!(plain.next_1d().to_bits(), ahead.next_1d().to_bits());
            } else {
                let (a, b) = (plain.next_2d(), ahead.next_2d());
                assert_eq!(
                    (a.0.to_bits(), a.1.to_bits()),
                    (b.0.to_bits(), b.1.to_bits())
                );
            }
        }
    }

    /// The index shuffle is a bijection of the reversed index that maps each aligned block of
    /// the first indices onto an aligned block (checked on the top 8 bits exhaustively).
    #[test]
    fn index_shuffle_keeps_blocks() {
        for seed in [0u32, 1, 0xdead_beef] {
            for bits in 1..=8u32 {
                let keep = ((1u32 << bits) - 1).reverse_bits();
                let mut seen = vec![false; 1 << bits];
                for i in 0..1u32 << bits {
                    let x = (laine_karras(i.reverse_bits(), seed) & keep) >> (32 - bits);
                    assert!(!std::mem::replace(&mut seen[x as usize], true));
                }
            }
        }
    }

    /// The second coordinate is the Sobol sequence's, from its direction numbers bit by
    /// bit: the first eight points are 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8, and the byte
    /// tables agree with the bit loop on indices of every size.
    #[test]
    fn second_dimension_is_sobols() {
        let bit_by_bit = |index: u32| {
            let mut v = 1u32 << 31;
            let mut x = 0;
            for j in 0..32 {
                if index >> j & 1 != 0 {
                    x ^= v;
                }
                v ^= v >> 1;
            }
            x
        };
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, w) in want.iter().enumerate() {
            let x = sobol_second_of_reversed((i as u32).reverse_bits());
            assert_eq!(x as f64 / 2f64.powi(32), *w, "point {i}");
        }
        let mut rng = Rng::new(1, 2, 3);
        for _ in 0..10_000 {
            let index = (rng.next_u64() >> (rng.next_u64() % 33)) as u32;
            assert_eq!(
                sobol_second_of_reversed(index.reverse_bits()),
                bit_by_bit(index),
                "{index:#x}"
            );
        }
    }
}
