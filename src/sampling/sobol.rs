//! The path tracer's numbers: the first two dimensions of the Sobol sequence, shuffled afresh
//! for every dimension a path draws (the index Owen-scrambled, as in Burley's "Practical
//! Hash-based Owen Scrambling", JCGT 2020; pbrt-v4's padded Sobol sampler permutes it too)
//! and each coordinate randomised by a digital shift. The samples of one pixel then cover each
//! 2-D draw — a point on the light, a bounce direction — as a (0, m, 2)-net: one point in each
//! of the 2^m elementary intervals of every shape, where independent numbers leave clumps and
//! holes. Every point is still uniform in the square, so the estimate stays unbiased. On the
//! Cornell box at 64 samples a pixel the relMSE falls to 0.64× at 1.04–1.06× the time
//! (`scripts/path-time-vs-mitsuba.sh`).
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
    /// Independent uniform numbers for every path (Mitsuba 3's `independent` sampler:
    /// the one to compare with it).
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

impl Ahead {
    /// Puts `point` after the points held (of which there are fewer than `AHEAD`).
    #[inline(always)]
    fn push(&mut self, point: (f32, f32)) {
        self.points[(self.first + self.len) % AHEAD] = point;
        self.len += 1;
    }
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
            let point = self.make();
            self.ahead.push(point);
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

/// Paths `SobolLanes` prepares at once.
pub const SOBOL_LANES: usize = 16;

/// `PathSamples::prepare` for up to `SOBOL_LANES` paths at once: each path's state taken into
/// a lane (`load`), the points of all of them made together in SIMD lanes (`make`, compiled
/// for the processor's widest instructions by `pulp`'s run-time dispatch), and handed back
/// (`store`). Each path gets the points `prepare` would make it, bit for bit. The path
/// tracer's wavefront prepares its paths so.
#[derive(Default)]
pub struct SobolLanes {
    pixel: [u64; SOBOL_LANES],
    dimension: [u64; SOBOL_LANES],
    reversed_index: [u32; SOBOL_LANES],
    keep: [u32; SOBOL_LANES],
    /// Points each lane's path still needs (0: none, or not a Sobol path).
    need: [usize; SOBOL_LANES],
    x: [[f32; SOBOL_LANES]; AHEAD],
    y: [[f32; SOBOL_LANES]; AHEAD],
}

impl SobolLanes {
    /// Takes the state of `samples` into lane `k`.
    pub fn load(&mut self, k: usize, samples: &PathSamples) {
        self.need[k] = 0;
        if let Source::Sobol(p) = &samples.source {
            self.pixel[k] = p.pixel;
            self.dimension[k] = p.dimension;
            self.reversed_index[k] = p.reversed_index;
            self.keep[k] = p.keep;
            self.need[k] = AHEAD - p.ahead.len;
        }
    }

    /// Makes the points every lane needs.
    pub fn make(&mut self, arch: pulp::Arch) {
        arch.dispatch(MakePoints(self))
    }

    /// Hands lane `k`'s points to `samples` (the path loaded into it).
    pub fn store(&self, k: usize, samples: &mut PathSamples) {
        if let Source::Sobol(p) = &mut samples.source {
            for d in 0..self.need[k] {
                p.ahead.push((self.x[d][k], self.y[d][k]));
                p.dimension += 1;
            }
        }
    }
}

/// `SobolLanes::make` for `pulp::Arch::dispatch`. The loop over the lanes is the inner one:
/// so LLVM vectorises it (with the dimensions inside, it did not).
struct MakePoints<'a>(&'a mut SobolLanes);

impl pulp::WithSimd for MakePoints<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let l = self.0;
        let depth = l.need.iter().copied().max().unwrap_or(0);
        for d in 0..depth {
            for k in 0..SOBOL_LANES {
                let dimension = l.dimension[k] + 1 + d as u64;
                let (x, y) = sobol_point(l.pixel[k], dimension, l.reversed_index[k], l.keep[k]);
                l.x[d][k] = x;
                l.y[d][k] = y;
            }
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

/// The second coordinate, as a 32-bit fraction, of the Sobol point whose index reversed is
/// `reversed`, by shifts and masks alone (no table, so that it runs in SIMD lanes too).
///
/// The second dimension's direction numbers (primitive polynomial x + 1) are v₀ = 2³¹,
/// vⱼ = vⱼ₋₁ ⊕ (vⱼ₋₁ >> 1): bit 31 − k of vⱼ is C(j, k) mod 2, which by Lucas' theorem is 1
/// exactly when k's bits are a subset of j's. Bit 31 − j of `reversed` is bit j of the index,
/// and complementing 5-bit positions (p = 31 − k) turns "k ⊆ j" into "31 − j ⊆ 31 − k": bit p
/// of the coordinate is the XOR of the bits of `reversed` at the positions that are subsets of
/// p. That sum over subsets takes five steps, one per bit of the position, each adding the
/// position's neighbour with that bit cleared to the positions that have it set.
#[inline(always)]
fn sobol_second_of_reversed(reversed: u32) -> u32 {
    let mut w = reversed;
    w ^= (w << 1) & 0xaaaa_aaaa;
    w ^= (w << 2) & 0xcccc_cccc;
    w ^= (w << 4) & 0xf0f0_f0f0;
    w ^= (w << 8) & 0xff00_ff00;
    w ^= (w << 16) & 0xffff_0000;
    w
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

    /// `SobolLanes` gives each path the points `prepare` gives it: paths of different pixels,
    /// indices and counts, some with points already made ahead and some with draws taken,
    /// and an independent path (which it leaves alone), in a block not full.
    #[test]
    fn lanes_prepare_the_points_prepare_makes() {
        let make = |k: u32| {
            let id = SampleId {
                seed: 5,
                pixel: 1000 + k as u64 / 3,
                index: k * 7,
                count: [Some(64), None, Some(1)][k as usize % 3],
            };
            let mut s = match k {
                11 => PathSamples::independent(Rng::new(1, 2, 3)),
                _ => PathSamples::sobol(id),
            };
            for _ in 0..k % 4 {
                s.next_2d();
            }
            if k.is_multiple_of(5) {
                s.prepare();
                s.next_1d();
            }
            s
        };
        let lanes_used = SOBOL_LANES as u32 - 3;
        let mut alone: Vec<PathSamples> = (0..lanes_used).map(make).collect();
        let mut together: Vec<PathSamples> = (0..lanes_used).map(make).collect();
        let mut lanes = SobolLanes::default();
        for (k, s) in together.iter().enumerate() {
            lanes.load(k, s);
        }
        lanes.make(pulp::Arch::new());
        for (k, s) in together.iter_mut().enumerate() {
            lanes.store(k, s);
        }
        for s in &mut alone {
            s.prepare();
        }
        for (k, (a, b)) in alone.iter_mut().zip(&mut together).enumerate() {
            for draw in 0..5 {
                let (p, q) = (a.next_2d(), b.next_2d());
                let bits = |(x, y): (f32, f32)| (x.to_bits(), y.to_bits());
                assert_eq!(bits(p), bits(q), "path {k}, draw {draw}");
            }
        }
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
    /// bit: the first eight points are 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8, and the shifts
    /// and masks agree with the bit loop on indices of every size and on each single bit.
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
        let random = (0..10_000).map(|_| (rng.next_u64() >> (rng.next_u64() % 33)) as u32);
        for index in random.chain((0..32).map(|j| 1 << j)) {
            assert_eq!(
                sobol_second_of_reversed(index.reverse_bits()),
                bit_by_bit(index),
                "{index:#x}"
            );
        }
    }
}
