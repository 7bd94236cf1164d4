//! Random numbers that depend only on (seed, stream, index): an image never depends on thread
//! scheduling or on how work is split; strata of them, and the maps from them to points on a
//! disk and directions in a cone.

use crate::geometry::Vec3;

mod sobol;
pub use sobol::{PathSampler, PathSamples, SampleId, SobolLanes, SOBOL_LANES};

/// SplitMix64's finaliser: a strong 64-bit mix.
#[inline(always)]
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

/// What each draw adds to an `Rng`'s state (the golden ratio's 64-bit fraction, SplitMix64's).
const RNG_STEP: u64 = 0x9e37_79b9_7f4a_7c15;

impl Rng {
    pub fn new(seed: u64, a: u64, b: u64) -> Rng {
        Rng {
            state: hash3(seed, a, b),
        }
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(RNG_STEP);
        mix64(self.state)
    }

    /// Steps past `n` numbers without making them: the state `n` draws leave.
    #[inline]
    pub fn skip(&mut self, n: u64) {
        self.state = self.state.wrapping_add(n.wrapping_mul(RNG_STEP));
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * UNIT_24
    }
}

/// 2^-24: a 24-bit integer times this is a float in [0, 1) with every bit exact.
const UNIT_24: f32 = 1.0 / (1u64 << 24) as f32;

/// How points on a light (or in a pixel) are placed (`--light-sampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Pattern {
    /// Independent uniform points.
    Random,
    /// The centres of a grid of strata (no randomness).
    Stratified,
    /// One uniform point in each stratum of the grid.
    #[default]
    Jittered,
    /// Correlated multi-jittered points (Kensler, "Correlated Multi-Jittered Sampling",
    /// 2013): one in each cell of an m × n grid (m = ⌊√N⌋, n = ⌈N/m⌉) and, projected on
    /// either axis, one in each of the N intervals of width 1/N. The light samplers that
    /// integrate one axis exactly (`render::solid_angle`) are left with a 1-D integral over
    /// the other, which N strata resolve far better than √N.
    MultiJittered,
}

/// How the ray tracer places its shadow rays on a light (`--light-sampling`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LightSampling {
    /// Rectangular lights by solid angle across the longer edge and by the receiver's
    /// cosine along it, multi-jittered in that parametrisation; spheres uniform in the cone
    /// they subtend; other lights, and lights too small or far to matter, by area (the
    /// points multi-jittered too).
    SolidAngle,
    /// As `solid-angle`, with independent uniform points in its parametrisation: what one
    /// shadow ray is worth alone, its error falling as 1/N (the default's strata make it fall
    /// faster).
    SolidAngleRandom,
    /// Independent uniform points by area (the course's comparison; the path tracer's light
    /// samples by area, as Mitsuba's and pbrt's).
    Random,
    /// The centres of a grid of strata by area (no randomness).
    Stratified,
    /// One uniform point by area in each stratum of the grid.
    Jittered,
    /// Rectangular lights: shadow rays to the corners, the light split in four where they
    /// disagree, `--adaptive-depth` levels deep, each part's light exact (Photonix's
    /// adaptive area lights; `render::adaptive`). Other lights as `solid-angle`.
    Adaptive,
}

impl LightSampling {
    /// Whether rectangles and spheres are sampled by the solid angle they subtend.
    pub fn by_solid_angle(self) -> bool {
        matches!(
            self,
            LightSampling::SolidAngle | LightSampling::SolidAngleRandom
        )
    }

    /// The pattern of the (u, v) points, in whichever parametrisation.
    pub fn pattern(self) -> Pattern {
        match self {
            LightSampling::SolidAngle | LightSampling::Adaptive => Pattern::MultiJittered,
            LightSampling::Jittered => Pattern::Jittered,
            LightSampling::Random | LightSampling::SolidAngleRandom => Pattern::Random,
            LightSampling::Stratified => Pattern::Stratified,
        }
    }
}

/// `n` samples in [0,1)² placed by a pattern over a grid of strata: √n × √n when n is a
/// square, else n × 1 (n strata along the first axis, which callers align with the longer
/// edge); multi-jittered points take an m × n grid (`Pattern::MultiJittered`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strata {
    pattern: Pattern,
    /// The number of samples.
    count: u32,
    nx: u32,
    ny: u32,
    /// 1/nx and 1/ny: a stratum's size, multiplied rather than divided by (a divide per
    /// sample was a good part of the shadow-ray loop's time).
    dx: f32,
    dy: f32,
}

impl Strata {
    pub fn new(pattern: Pattern, n: u32) -> Strata {
        let n = n.max(1);
        let r = (n as f64).sqrt().round() as u32;
        let (nx, ny) = if pattern == Pattern::MultiJittered {
            // m × n cells holding at least N points (the extra cells of the last row stay
            // empty; `samples` stops after N).
            let m = ((n as f64).sqrt().floor() as u32).max(1);
            (m, n.div_ceil(m))
        } else if r * r == n {
            (r, r)
        } else {
            (n, 1)
        };
        Strata {
            pattern,
            count: n,
            nx,
            ny,
            dx: 1.0 / nx as f32,
            dy: 1.0 / ny as f32,
        }
    }

    /// Sample `k` (of the n the grid was made for). The multi-jittered pattern draws the
    /// key of a whole pattern from `rng` for it, so only there does this differ from the
    /// k-th of `samples`.
    #[inline]
    pub fn sample(&self, k: u32, rng: &mut Rng) -> (f32, f32) {
        if self.pattern == Pattern::MultiJittered {
            return self.multi_jittered(k, rng.next_u64());
        }
        self.in_cell(k % self.nx, k / self.nx, rng)
    }

    /// All n samples in order (sample k is the k-th), without the division that finds
    /// sample k's stratum.
    pub fn samples<'a>(&'a self, rng: &'a mut Rng) -> impl Iterator<Item = (f32, f32)> + 'a {
        let mut cell = (0, 0);
        // One key for the whole multi-jittered pattern (its permutations and jitter).
        let key = if self.pattern == Pattern::MultiJittered {
            rng.next_u64()
        } else {
            0
        };
        let mut k = 0;
        std::iter::from_fn(move || {
            if self.pattern == Pattern::MultiJittered {
                k += 1;
                return (k <= self.count).then(|| self.multi_jittered(k - 1, key));
            }
            let (ix, iy) = cell;
            if iy == self.ny {
                return None;
            }
            cell = if ix + 1 == self.nx {
                (0, iy + 1)
            } else {
                (ix + 1, iy)
            };
            Some(self.in_cell(ix, iy, rng))
        })
    }

    #[inline(always)]
    fn in_cell(&self, ix: u32, iy: u32, rng: &mut Rng) -> (f32, f32) {
        match self.pattern {
            Pattern::Random => (rng.next_f32(), rng.next_f32()),
            Pattern::Stratified => ((ix as f32 + 0.5) * self.dx, (iy as f32 + 0.5) * self.dy),
            Pattern::Jittered | Pattern::MultiJittered => (
                (ix as f32 + rng.next_f32()) * self.dx,
                (iy as f32 + rng.next_f32()) * self.dy,
            ),
        }
    }

    /// Point `k` of the multi-jittered pattern of key `key` (Kensler 2013, section 3): the
    /// points are shuffled over the cells, the cell's column picks the x sub-interval within
    /// the row's stratum by one permutation, the row the y sub-interval by another.
    fn multi_jittered(&self, k: u32, key: u64) -> (f32, f32) {
        let (m, n) = (self.nx, self.ny);
        let key32 = |salt: u64| (mix64(key ^ salt) >> 32) as u32;
        let s = permute(k, m * n, key32(0x51633e2d));
        let (column, row) = (s % m, s / m);
        let sx = permute(column, m, key32(0x68bc21eb));
        let sy = permute(row, n, key32(0x02e5be93));
        let jitter = hash3(key, k as u64, 0x967a889b);
        let jx = (jitter >> 40) as f32 * UNIT_24;
        let jy = ((jitter >> 8) & 0xff_ffff) as f32 * UNIT_24;
        let x = (column as f32 + (sy as f32 + jx) / n as f32) / m as f32;
        let y = (row as f32 + (sx as f32 + jy) / m as f32) / n as f32;
        // Rounding may carry a point to 1.0; the samplers expect [0, 1).
        (x.min(ONE_BELOW), y.min(ONE_BELOW))
    }
}

/// The largest f32 below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// `i` in [0, len) moved by a permutation of [0, len) chosen by `key`: a keyed bijection of
/// the enclosing power-of-two range (xors, odd multiplications and right xorshifts, each
/// invertible on k-bit words), applied again until the value falls inside ("cycle walking",
/// which keeps it a bijection of [0, len)).
fn permute(mut i: u32, len: u32, key: u32) -> u32 {
    if len <= 1 {
        return 0;
    }
    let mask = u32::MAX >> (len - 1).leading_zeros();
    let bits = 32 - mask.leading_zeros();
    let half = bits.div_ceil(2);
    loop {
        i ^= key & mask;
        i = i.wrapping_mul(0x9e37_79b1 | 1) & mask;
        i ^= i >> half;
        i = i.wrapping_add(key >> 16) & mask;
        i = i.wrapping_mul((key | 1).wrapping_mul(0x2c1b_3c6d) | 1) & mask;
        i ^= i >> 1.max(half / 2);
        if i < len {
            return i;
        }
    }
}

/// A uniform point on the unit disk (concentric mapping of Shirley and Chiu).
#[inline(always)]
pub fn sample_disk(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    // The square's point at radius r and angle φ = π/4 · (b/a) from the x axis, or
    // π/2 − π/4 · (a/b) nearer the y axis, where cos φ and sin φ are the sine and the cosine
    // of π/4 · (a/b): both from one angle in [−π/4, π/4] (`sin_cos_quarter`). Without
    // branches (the centre, a = b = 0, takes ratio 0 and radius 0), so that the path tracer's
    // vertex kernel runs this lane by lane in SIMD.
    let near_x = a.abs() > b.abs();
    let (r, across, along) = if near_x { (a, b, a) } else { (b, a, b) };
    let ratio = if along == 0.0 { 0.0 } else { across / along };
    let (sin, cos) = sin_cos_quarter(std::f32::consts::FRAC_PI_4 * ratio);
    if near_x {
        (r * cos, r * sin)
    } else {
        (r * sin, r * cos)
    }
}

/// The sine and the cosine of `x` in [−π/4, π/4], by the minimax polynomials of Cephes'
/// `sinf` and `cosf` on that range (within 2 ulps of the exact values there). The disk's
/// angles never leave it, and libm's `sincosf` (range reduction, a call) was 3% of the path
/// tracer's time on the Cornell box.
#[inline(always)]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let z = x * x;
    let sin = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let cos = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (sin, cos)
}

/// A direction uniformly distributed over the cone of half-angle acos(`cos_max`) around the
/// unit vector `axis` (solid angle 2π(1 − cos_max)), from (u, v) in [0,1)².
pub fn sample_cone(axis: Vec3, cos_max: f32, u: f32, v: f32) -> Vec3 {
    let cos_t = 1.0 - u * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    let (t, b) = orthonormal_basis(axis);
    (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize_or_zero()
}

/// Two unit vectors that complete `n` to an orthonormal basis (Duff et al. 2017).
#[inline(always)]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3 {
            x: 1.0 + sign * n.x * n.x * a,
            y: sign * b,
            z: -sign * n.x,
        },
        Vec3 {
            x: b,
            y: sign + n.y * n.y * a,
            z: -n.y,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Skipping n numbers leaves the generator where drawing them does.
    #[test]
    fn skipping_numbers_is_drawing_them() {
        for n in [0u64, 1, 2, 7] {
            let (mut drawn, mut skipped) = (Rng::new(3, 4, 5), Rng::new(3, 4, 5));
            for _ in 0..n {
                drawn.next_u64();
            }
            skipped.skip(n);
            assert_eq!(drawn.next_u64(), skipped.next_u64(), "{n} skipped");
        }
    }

    #[test]
    fn quarter_sines_and_cosines_are_within_two_ulps() {
        // The gap from |value| (as an f32) to the next f32 up: one ulp there.
        let ulp = |value: f64| {
            let f = (value as f32).abs();
            (f.next_up() - f) as f64
        };
        for i in 0..=100_000 {
            let x = ((i as f64 / 100_000.0 * 2.0 - 1.0) * std::f64::consts::FRAC_PI_4) as f32;
            let (sin, cos) = sin_cos_quarter(x);
            for (got, exact) in [(sin, (x as f64).sin()), (cos, (x as f64).cos())] {
                let error = (got as f64 - exact).abs();
                assert!(error <= 2.0 * ulp(exact), "x {x}: {got} against {exact}");
            }
        }
    }

    #[test]
    fn disk_points_lie_on_the_disk_at_the_concentric_angle() {
        let mut rng = Rng::new(7, 0, 0);
        for _ in 0..100_000 {
            let (u, v) = (rng.next_f32(), rng.next_f32());
            let (x, y) = sample_disk(u, v);
            let (a, b) = (2.0 * u as f64 - 1.0, 2.0 * v as f64 - 1.0);
            let (r, phi) = if a.abs() > b.abs() {
                (a, std::f64::consts::FRAC_PI_4 * (b / a))
            } else {
                (
                    b,
                    std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b),
                )
            };
            assert!((x as f64 - r * phi.cos()).abs() < 1e-6, "({u}, {v})");
            assert!((y as f64 - r * phi.sin()).abs() < 1e-6, "({u}, {v})");
        }
    }

    #[test]
    fn permute_is_a_bijection() {
        for len in 1..200u32 {
            for key in [0u32, 1, 0xdead_beef, 0x8000_0001] {
                let mut seen: Vec<u32> = (0..len).map(|i| permute(i, len, key)).collect();
                seen.sort_unstable();
                assert!(seen.iter().copied().eq(0..len), "len {len}, key {key:#x}");
            }
        }
    }

    /// Multi-jittered points: one in each cell of the m × n grid and one in each of the
    /// m·n intervals of either axis, every coordinate in [0, 1).
    #[test]
    fn multi_jittered_points_are_stratified_in_two_and_one_dimensions() {
        for count in [1u32, 2, 3, 4, 7, 9, 10, 16, 50, 64, 256] {
            let strata = Strata::new(Pattern::MultiJittered, count);
            let (m, n) = (strata.nx, strata.ny);
            assert!(m * n >= count && m * (n - 1) < count, "{count}: {m} × {n}");
            for seed in 0..4 {
                let points: Vec<(f32, f32)> = strata
                    .samples(&mut Rng::new(seed, count as u64, 0))
                    .collect();
                assert_eq!(points.len(), count as usize);
                let distinct = |key: &dyn Fn(&(f32, f32)) -> u32| {
                    let mut k: Vec<u32> = points.iter().map(key).collect();
                    k.sort_unstable();
                    k.dedup();
                    k.len()
                };
                assert!(points
                    .iter()
                    .all(|&(x, y)| (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y)));
                let cells = distinct(&|&(x, y)| (x * m as f32) as u32 * n + (y * n as f32) as u32);
                let columns = distinct(&|&(x, _)| (x * (m * n) as f32) as u32);
                let rows = distinct(&|&(_, y)| (y * (m * n) as f32) as u32);
                assert_eq!(
                    [cells, columns, rows],
                    [count as usize; 3],
                    "{count} points"
                );
            }
        }
    }

    /// `samples` gives exactly what `sample(k)` gives for k = 0, 1, ..., with one point in
    /// each stratum for the jittered pattern.
    #[test]
    fn strata_iterator_matches_indexed_samples() {
        for n in [1, 4, 9, 10, 16] {
            let strata = Strata::new(Pattern::Jittered, n);
            let (mut a, mut b) = (Rng::new(3, n as u64, 0), Rng::new(3, n as u64, 0));
            let all: Vec<(f32, f32)> = strata.samples(&mut a).collect();
            assert_eq!(all.len(), n as usize);
            let mut cells: Vec<(u32, u32)> = Vec::new();
            for (k, &(u, v)) in all.iter().enumerate() {
                assert_eq!((u, v), strata.sample(k as u32, &mut b));
                cells.push(((u * strata.nx as f32) as u32, (v * strata.ny as f32) as u32));
            }
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(
                cells.len(),
                n as usize,
                "one sample per stratum for n = {n}"
            );
        }
    }
}
