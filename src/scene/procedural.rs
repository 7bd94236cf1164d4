//! Solid procedural textures and bump maps (`texture_procedural`, `bump_procedural`,
//! `bump_file`; docs/scene-format.md).
//!
//! A pattern is a function of the point in pattern space: the scene-space point relative to
//! the pattern's origin, divided by its size (`texture_scale`, `bump_scale`). trilux's
//! objects carry no transform, so object space is scene space; the origin moves with the
//! scene when it is moved or scaled (`Scene::transformed`), so the pattern stays on the
//! objects.
//!
//! Every pattern is evaluated over a footprint, the half-width of what one pixel sees at the
//! point (`Footprint`), and detail finer than the footprint is replaced by its mean, so a
//! pattern does not alias at one sample per pixel: the checker is box-filtered in closed form,
//! noise octaves fade out as their wavelength nears the footprint, and the rings, veins and
//! cracks fade to their mean.

use std::f32::consts::TAU;

use crate::color::Color;
use crate::geometry::{vec3, Vec3};

/// A procedural pattern: a value in [0, 1] at each point of space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// Concentric rings about the pattern space's y axis, one per unit, warped by noise.
    Wood,
    /// Veins across the x axis, one per unit, warped by noise.
    Marble,
    /// Fractal gradient noise (Perlin's improved noise, summed over octaves).
    Noise,
    /// Cells of unit size with dark cracks along their borders (Worley's cellular basis).
    Crackle,
    /// A 3-D checkerboard of unit cells.
    Checker,
}

impl Pattern {
    /// The names of the patterns, as the scene file spells them.
    pub const NAMES: [(&'static str, Pattern); 5] = [
        ("wood", Pattern::Wood),
        ("marble", Pattern::Marble),
        ("noise", Pattern::Noise),
        ("crackle", Pattern::Crackle),
        ("checker", Pattern::Checker),
    ];

    pub fn from_name(name: &str) -> Option<Pattern> {
        Self::NAMES
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(_, p)| p)
    }

    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(_, p)| *p == self)
            .map_or("?", |(n, _)| n)
    }

    /// The pattern's value at `q` (pattern space), averaged over a footprint of half-width
    /// `w[axis]` along each axis (pattern units). The checker is filtered along each axis;
    /// the other patterns by one width, the geometric mean of the two largest (a footprint
    /// lies in a surface's plane, and an oblique view stretches it along one direction only).
    pub fn value(self, q: Vec3, w: Vec3) -> f32 {
        let w = w.max(Vec3::splat(MIN_HALF_WIDTH));
        let iso = (w.max_element() * (w.x + w.y + w.z - w.max_element() - w.min_element())).sqrt();
        match self {
            Pattern::Noise => (0.5 + NOISE_CONTRAST * fractal_noise(q, iso)).clamp(0.0, 1.0),
            Pattern::Marble => {
                let phase = |q: Vec3| q.x + 1.5 * fractal_noise(q, iso);
                0.5 + 0.5 * periodic_weight(&phase, q, iso) * (TAU * phase(q)).sin()
            }
            Pattern::Wood => {
                let radius = |q: Vec3| {
                    let grain = fractal_noise(vec3(q.x, 0.1 * q.y, q.z), iso);
                    (q.x * q.x + q.z * q.z).sqrt() + 0.4 * grain
                };
                0.5 + 0.5 * periodic_weight(&radius, q, iso) * (TAU * radius(q)).cos()
            }
            Pattern::Crackle => {
                let keep = detail_weight(1.0, iso);
                if keep <= 0.0 {
                    return CRACKLE_MEAN;
                }
                // The crack is a band |gap| < CRACK_WIDTH about the border; the footprint is
                // taken to cover gaps within iso of the point's (the gap grows between 0 and
                // 2 times as fast as the distance to the border; 1 came closest to the true
                // pixel averages in tests/procedural.rs), and the value is the share not
                // cracked.
                let (gap, reach) = (cell_border_gap(q), iso);
                let overlap =
                    ((gap + reach).min(CRACK_WIDTH) - (gap - reach).max(-CRACK_WIDTH)).max(0.0);
                let uncracked = 1.0 - overlap / (2.0 * reach);
                keep * uncracked + (1.0 - keep) * CRACKLE_MEAN
            }
            Pattern::Checker => {
                let q = q + Vec3::splat(CHECKER_PHASE);
                let s = filtered_square(q.x, w.x)
                    * filtered_square(q.y, w.y)
                    * filtered_square(q.z, w.z);
                0.5 + 0.5 * s
            }
        }
    }
}

/// The smallest half-width a pattern is averaged over, in pattern units: it keeps even the
/// checker continuous, so points that differ only by rounding (a scene moved or scaled) get
/// the same colour to within rounding.
const MIN_HALF_WIDTH: f32 = 1.0 / 128.0;

/// The checker's cells start this far (in cells) below the lattice of integers: planes at
/// round coordinates (a floor at y = 0) then lie inside a cell, not on a border where the
/// rounding of each hit would pick the colour.
const CHECKER_PHASE: f32 = 1.0 / 32.0;

/// How far the noise pattern's fractal sum is stretched about its mean 0.5.
const NOISE_CONTRAST: f32 = 0.6;

/// The noise octaves summed, the first of unit wavelength.
const OCTAVES: u32 = 8;

/// Width of the cracks of `crackle`, in the units of `cell_border_gap`.
const CRACK_WIDTH: f32 = 0.03;

/// The mean of the crackle pattern over space (what it fades to where its cells are finer
/// than a pixel); measured over 10⁶ points by the test `means_are_what_detail_fades_to`.
const CRACKLE_MEAN: f32 = 0.886;

/// How much of a detail of `wavelength` a footprint of half-width `w` keeps: all of it up to
/// w = wavelength/4, none from w = wavelength/2 (where sampling would alias it).
fn detail_weight(wavelength: f32, w: f32) -> f32 {
    ((0.5 * wavelength - w) / (0.25 * wavelength)).clamp(0.0, 1.0)
}

/// How much of a wave of unit period in `phase` a footprint of half-width `w` about `q`
/// keeps: the phase's change across the footprint (warped by noise, the veins and rings are
/// denser in places than one a unit) taken as the footprint's width in periods. The change
/// is summed over both halves, so a phase that turns back (a ring's radius across its centre)
/// is not taken for a still one.
fn periodic_weight(phase: &dyn Fn(Vec3) -> f32, q: Vec3, w: f32) -> f32 {
    let centre = phase(q);
    let change =
        |axis: Vec3| (phase(q + axis * w) - centre).abs() + (centre - phase(q - axis * w)).abs();
    let spread = change(Vec3::X).max(change(Vec3::Y)).max(change(Vec3::Z));
    detail_weight(1.0, 0.5 * spread)
}

/// The square wave of period 2, +1 on [0, 1) and −1 on [1, 2), averaged over [x − w, x + w]:
/// the difference of its integral (a triangle wave) across the interval.
fn filtered_square(x: f32, w: f32) -> f32 {
    let integral = |x: f32| {
        let d = x.rem_euclid(2.0);
        if d <= 1.0 {
            d
        } else {
            2.0 - d
        }
    };
    ((integral(x + w) - integral(x - w)) / (2.0 * w)).clamp(-1.0, 1.0)
}

/// Octaves of gradient noise, each of half the wavelength and half the amplitude of the one
/// before, fading out as their wavelength nears the footprint `w`. Zero mean.
fn fractal_noise(q: Vec3, w: f32) -> f32 {
    let mut sum = 0.0;
    let (mut frequency, mut amplitude) = (1.0f32, 1.0f32);
    for octave in 0..OCTAVES {
        let keep = detail_weight(frequency.recip(), w);
        if keep <= 0.0 {
            break;
        }
        // Each octave is shifted, or the lattice points (where noise is 0) of all octaves
        // would coincide at the origin.
        let shift = vec3(17.13, -3.71, 9.29) * octave as f32;
        sum += keep * amplitude * gradient_noise(q * frequency + shift);
        frequency *= 2.0;
        amplitude *= 0.5;
    }
    sum
}

/// Perlin's improved gradient noise (2002): 0 on the integer lattice, smooth (C²), in about
/// [−1, 1], mean 0.
fn gradient_noise(p: Vec3) -> f32 {
    let (fx, fy, fz) = (p.x.floor(), p.y.floor(), p.z.floor());
    let (x, y, z) = (p.x - fx, p.y - fy, p.z - fz);
    // Lattice coordinates modulo 256 (casts saturate, and NaN gives 0).
    let cell = |f: f32| (f as i64 & 255) as usize;
    let (xi, yi, zi) = (cell(fx), cell(fy), cell(fz));
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let p = &PERMUTATION;
    let a = p[xi] as usize + yi;
    let (aa, ab) = (p[a] as usize + zi, p[a + 1] as usize + zi);
    let b = p[xi + 1] as usize + yi;
    let (ba, bb) = (p[b] as usize + zi, p[b + 1] as usize + zi);
    let lerp = |t: f32, a: f32, b: f32| a + t * (b - a);
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(p[aa], x, y, z), grad(p[ba], x - 1.0, y, z)),
            lerp(
                u,
                grad(p[ab], x, y - 1.0, z),
                grad(p[bb], x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(p[aa + 1], x, y, z - 1.0),
                grad(p[ba + 1], x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(p[ab + 1], x, y - 1.0, z - 1.0),
                grad(p[bb + 1], x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// The dot product of (x, y, z) with one of the 12 edge directions of a cube, picked by hash.
fn grad(hash: u8, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// A fixed permutation of 0..256, repeated: noise is the same in every run and every build.
const PERMUTATION: [u8; 512] = permutation(0x7472_696c_7578);

/// A Fisher–Yates shuffle of 0..256 driven by SplitMix64 from `seed`, then repeated once.
const fn permutation(seed: u64) -> [u8; 512] {
    let mut p = [0u8; 512];
    let mut i = 0;
    while i < 256 {
        p[i] = i as u8;
        i += 1;
    }
    let mut state = seed;
    let mut i = 255;
    while i > 0 {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        let j = (z % (i as u64 + 1)) as usize;
        let t = p[i];
        p[i] = p[j];
        p[j] = t;
        i -= 1;
    }
    let mut k = 0;
    while k < 256 {
        p[256 + k] = p[k];
        k += 1;
    }
    p
}

/// Worley's cellular basis with one jittered feature point per unit cell: the difference
/// F2 − F1 of the distances to the nearest and second-nearest feature points, 0 on the
/// borders between cells.
fn cell_border_gap(q: Vec3) -> f32 {
    let base = q.floor();
    let (mut f1, mut f2) = (f32::INFINITY, f32::INFINITY);
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                let cell = base + vec3(dx as f32, dy as f32, dz as f32);
                let d = cell + feature_offset(cell) - q;
                let d = d.length();
                if d < f1 {
                    (f1, f2) = (d, f1);
                } else if d < f2 {
                    f2 = d;
                }
            }
        }
    }
    f2 - f1
}

/// Where in its unit cell the feature point of `cell` lies: a hash of the cell's coordinates.
fn feature_offset(cell: Vec3) -> Vec3 {
    let key = |c: f32| c as i64 as u64;
    let h = crate::sampling::hash3(
        0x0063_7261_636b_6c65,
        key(cell.x),
        key(cell.y) ^ (key(cell.z) << 32),
    );
    let unit = |bits: u64| (bits & 0xFFFF) as f32 / 65536.0;
    vec3(unit(h), unit(h >> 16), unit(h >> 32))
}

/// A procedural texture (`texture_procedural`, `texture_scale`, `texture_colors`): the
/// material's albedo mixed from two colours by a pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProceduralTexture {
    pub pattern: Pattern,
    /// The pattern's size in scene units (`texture_scale`, default 1).
    pub scale: f32,
    /// The albedo where the pattern is 1 and where it is 0 (`texture_colors`, default white
    /// and black).
    pub colors: [Color; 2],
    /// The scene-space point the pattern is laid out from (the origin, until the scene is
    /// moved).
    pub origin: Vec3,
}

impl ProceduralTexture {
    pub fn new(pattern: Pattern) -> ProceduralTexture {
        ProceduralTexture {
            pattern,
            scale: 1.0,
            colors: [Vec3::ONE, Vec3::ZERO],
            origin: Vec3::ZERO,
        }
    }

    /// The albedo at scene point `p` averaged over a footprint of half-widths `w` (scene
    /// units, per axis).
    pub fn albedo(&self, p: Vec3, w: Vec3) -> Color {
        let v = self
            .pattern
            .value((p - self.origin) / self.scale, w / self.scale);
        self.colors[1] + (self.colors[0] - self.colors[1]) * v
    }
}

/// Where a bump map's heights come from.
#[derive(Clone, Debug, PartialEq)]
pub enum BumpSource {
    /// A pattern (`bump_procedural noise|crackle|wood`) of size `scale` (`bump_scale`,
    /// default 1) laid out from `origin`.
    Procedural {
        pattern: Pattern,
        scale: f32,
        origin: Vec3,
    },
    /// A height image looked up by texture coordinates (`bump_file`): its file, and its index
    /// into `Scene::height_maps` once decoded.
    File {
        file: std::path::PathBuf,
        map: Option<usize>,
    },
}

/// A bump map: heights in [0, 1] times `amplitude` displace the surface along its normal,
/// which tilts the shading normal without moving the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Bump {
    pub source: BumpSource,
    /// The height of a value of 1, in scene units (`bump_amplitude`, default 0.01).
    pub amplitude: f32,
}

/// The patterns `bump_procedural` accepts: the smooth ones (the checker and marble are left
/// to textures).
pub const BUMP_PATTERNS: [Pattern; 3] = [Pattern::Noise, Pattern::Crackle, Pattern::Wood];

/// The shading normal of a surface of unit normal `n` displaced by `amplitude` × a height
/// field whose differences across the tangent directions `t1`, `t2` (each a step `step`
/// long) are `dh1`, `dh2`: n − amplitude·∇h, normalized. It never turns past the tangent
/// plane.
pub fn bumped_normal(
    n: Vec3,
    (t1, t2): (Vec3, Vec3),
    (dh1, dh2): (f32, f32),
    amplitude: f32,
    step: f32,
) -> Vec3 {
    let slope = (t1 * dh1 + t2 * dh2) * (amplitude / step);
    let bent = (n - slope).normalize_or_zero();
    if bent.length_squared() > 0.0 {
        bent
    } else {
        n
    }
}

/// How wide a pixel is at a point of the scene: what textures are averaged over there.
/// `Footprint::default()` is zero everywhere (no averaging beyond the patterns' own minimum).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    eye: Vec3,
    forward: Vec3,
    /// A pixel's width per unit of depth in front of a perspective camera.
    per_depth: f32,
    /// A pixel's width in front of an orthographic camera.
    constant: f32,
}

impl Footprint {
    /// The footprint of a pixel of a `width`×`height` image through `camera`.
    pub fn of_pixels(camera: &super::Camera, width: u32, height: u32) -> Footprint {
        let pixels = width.max(height).max(1) as f32;
        let forward = (camera.point_of_interest - camera.position).normalize_or_zero();
        let (per_depth, constant) = match camera.projection {
            super::Projection::Perspective { angle } => (2.0 * (angle * 0.5).tan() / pixels, 0.0),
            super::Projection::Orthographic { size } => (0.0, size / pixels),
        };
        Footprint {
            eye: camera.position,
            forward,
            per_depth,
            constant,
        }
    }

    /// The same footprint in a scene scaled by `scale` about the origin, then moved by
    /// `offset` (`Scene::transformed`).
    pub fn transformed(self, scale: f32, offset: Vec3) -> Footprint {
        Footprint {
            eye: self.eye * scale + offset,
            constant: self.constant * scale,
            ..self
        }
    }

    /// The half-widths, along each axis, of a pixel's footprint on the surface through `p` of
    /// unit normal `n`. The footprint is an ellipse in the surface's plane: a pixel's width
    /// at p's depth across the line of sight, stretched by 1/cos along it where the surface
    /// is seen obliquely; each axis gets the ellipse's extent along it (the axis along the
    /// normal gets none).
    pub fn half_widths(&self, p: Vec3, n: Vec3) -> Vec3 {
        let to_eye = self.eye - p;
        let depth = (-to_eye).dot(self.forward).max(0.0);
        let width = self.constant + self.per_depth * depth;
        if width <= 0.0 {
            return Vec3::ZERO;
        }
        let view = to_eye.normalize_or_zero();
        let cos = n.dot(view).abs().max(0.01);
        // The ellipse's long axis: the line of sight projected on the plane.
        let along = (view - n * n.dot(view)).normalize_or_zero();
        if along.length_squared() == 0.0 {
            return disc_half_widths(n, 0.5 * width);
        }
        let across = n.cross(along);
        let (long, short) = (along * (0.5 * width / cos), across * (0.5 * width));
        let extent = |a: f32, b: f32| (a * a + b * b).sqrt();
        vec3(
            extent(long.x, short.x),
            extent(long.y, short.y),
            extent(long.z, short.z),
        )
    }
}

/// The half-widths along each axis of a disc of radius `radius` in the plane of unit normal
/// `n` (the axis along the normal gets none of it).
pub fn disc_half_widths(n: Vec3, radius: f32) -> Vec3 {
    let across = |c: f32| (1.0 - c * c).max(0.0).sqrt();
    vec3(across(n.x), across(n.y), across(n.z)) * radius
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn random_point(rng: &mut Rng, extent: f32) -> Vec3 {
        vec3(rng.next_f32(), rng.next_f32(), rng.next_f32()) * extent
    }

    /// The checker's closed-form filter against the mean of the unfiltered pattern over the
    /// same box (a 24³ grid of midpoints), at footprints from a tenth of a cell to three.
    #[test]
    fn checker_filter_is_the_box_average() {
        let mut rng = Rng::new(1, 2, 3);
        for half in [0.1f32, 0.35, 0.8, 3.0] {
            for _ in 0..20 {
                let q = random_point(&mut rng, 10.0);
                let w = vec3(half, 0.6 * half, 1.3 * half);
                let n = 24;
                let mut sum = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        for k in 0..n {
                            let t = |i: u32| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                            let at = q + vec3(t(i) * w.x, t(j) * w.y, t(k) * w.z);
                            sum += Pattern::Checker.value(at, Vec3::ZERO);
                        }
                    }
                }
                let mean = sum / (n * n * n) as f32;
                let filtered = Pattern::Checker.value(q, w);
                assert!(
                    (filtered - mean).abs() < 0.03,
                    "{q} {w}: {filtered} against {mean}"
                );
            }
        }
    }

    /// Each pattern's mean over space is what it fades to where its detail is finer than a
    /// pixel: filtering changes no colour on average, only removes the detail.
    #[test]
    fn means_are_what_detail_fades_to() {
        let mut rng = Rng::new(4, 5, 6);
        for (name, pattern) in Pattern::NAMES {
            let n = 1_000_000;
            let mean = (0..n)
                .map(|_| {
                    pattern.value(
                        random_point(&mut rng, 200.0) - Vec3::splat(100.0),
                        Vec3::ZERO,
                    ) as f64
                })
                .sum::<f64>()
                / n as f64;
            let faded = pattern.value(vec3(0.3, 0.7, 0.1), Vec3::splat(4.0)) as f64;
            println!("{name}: mean {mean:.4}, faded {faded:.4}");
            assert!(
                (mean - faded).abs() < 0.01,
                "{name}: mean {mean}, faded {faded}"
            );
            let coarse = pattern.value(vec3(0.3, 0.7, 0.1), Vec3::splat(0.01));
            assert!((0.0..=1.0).contains(&coarse), "{name}: {coarse}");
        }
    }

    /// Noise is 0 on the lattice, bounded, continuous, and the same every time.
    #[test]
    fn gradient_noise_is_bounded_and_zero_on_the_lattice() {
        assert_eq!(gradient_noise(vec3(3.0, -7.0, 12.0)), 0.0);
        let mut rng = Rng::new(7, 8, 9);
        for _ in 0..100_000 {
            let p = random_point(&mut rng, 50.0);
            let v = gradient_noise(p);
            assert!(v.abs() <= 1.1, "{p}: {v}");
            let near = gradient_noise(p + Vec3::splat(1e-4));
            assert!((v - near).abs() < 2e-3, "{p}: {v} against {near}");
        }
    }

    /// A bump of zero slope leaves the normal; a slope of 1 along t1 at amplitude 1 tilts it
    /// by 45°.
    #[test]
    fn bumped_normal_tilts_against_the_slope() {
        let n = vec3(0.0, 0.0, 1.0);
        let t = (vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0));
        assert_eq!(bumped_normal(n, t, (0.0, 0.0), 1.0, 0.1), n);
        let b = bumped_normal(n, t, (0.1, 0.0), 1.0, 0.1);
        assert!(
            (b - vec3(-1.0, 0.0, 1.0).normalize()).length() < 1e-6,
            "{b}"
        );
    }
}
