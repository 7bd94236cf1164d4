//! Random numbers that depend only on (seed, stream, index): an image never depends on thread
//! scheduling or on how work is split; strata of them, and the maps from them to points on a
//! disk and directions in a cone.

use crate::geometry::Vec3;

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
}

/// How the ray tracer places its shadow rays on a light (`--light-sampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LightSampling {
    /// Uniform in the solid angle a rectangular light subtends, one jittered point per
    /// stratum of that parametrisation (other lights, and rectangles too small or far to
    /// matter, by area with jittered points).
    #[default]
    SolidAngle,
    /// Independent uniform points by area (the course's comparison).
    Random,
    /// The centres of a grid of strata by area (no randomness).
    Stratified,
    /// One uniform point by area in each stratum of the grid.
    Jittered,
}

impl LightSampling {
    /// The pattern of the (u, v) points, in whichever parametrisation.
    pub fn pattern(self) -> Pattern {
        match self {
            LightSampling::SolidAngle | LightSampling::Jittered => Pattern::Jittered,
            LightSampling::Random => Pattern::Random,
            LightSampling::Stratified => Pattern::Stratified,
        }
    }
}

/// `n` samples in [0,1)² placed by a pattern over a grid of strata: √n × √n when n is a
/// square, else n × 1 (n strata along the first axis, which callers align with the longer
/// edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strata {
    pattern: Pattern,
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
        let (nx, ny) = if r * r == n { (r, r) } else { (n, 1) };
        Strata {
            pattern,
            nx,
            ny,
            dx: 1.0 / nx as f32,
            dy: 1.0 / ny as f32,
        }
    }

    /// Sample `k` (of the n the grid was made for).
    #[inline]
    pub fn sample(&self, k: u32, rng: &mut Rng) -> (f32, f32) {
        self.in_cell(k % self.nx, k / self.nx, rng)
    }

    /// All n samples in order (sample k is the k-th), without the division that finds
    /// sample k's stratum.
    pub fn samples<'a>(&'a self, rng: &'a mut Rng) -> impl Iterator<Item = (f32, f32)> + 'a {
        let mut cell = (0, 0);
        std::iter::from_fn(move || {
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
            Pattern::Jittered => (
                (ix as f32 + rng.next_f32()) * self.dx,
                (iy as f32 + rng.next_f32()) * self.dy,
            ),
        }
    }
}

/// A uniform point on the unit disk (concentric mapping of Shirley and Chiu).
pub fn sample_disk(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * phi.cos(), r * phi.sin())
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
