//! The sky (`sky_color`, `sky_gradient`, `sky_texture`, `sky_scale`; docs/scene-format.md):
//! radiance from every direction a ray leaves the scene in, which lights the scene. +y is up.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::color::Color;
use crate::geometry::{vec3, Vec3};
use crate::image_io::{self, Image};

/// A sky: its radiance by direction.
#[derive(Clone, Debug, PartialEq)]
pub enum Sky {
    /// The same radiance from every direction (`sky_color r g b`).
    Uniform(Color),
    /// Linear in the direction's height from the horizon's radiance to the zenith's above it
    /// and to the nadir's below (`sky_gradient zenith horizon nadir`).
    Gradient {
        zenith: Color,
        horizon: Color,
        nadir: Color,
    },
    /// A latitude–longitude image (`sky_texture file`).
    Map(Arc<SkyMap>),
}

impl Sky {
    /// The radiance arriving from the unit direction `towards` (a ray going that way sees it).
    pub fn radiance(&self, towards: Vec3) -> Color {
        match self {
            Sky::Uniform(c) => *c,
            Sky::Gradient {
                zenith,
                horizon,
                nadir,
            } => {
                let y = towards.y.clamp(-1.0, 1.0);
                if y >= 0.0 {
                    *horizon + (*zenith - *horizon) * y
                } else {
                    *horizon + (*nadir - *horizon) * -y
                }
            }
            Sky::Map(map) => map.radiance(towards),
        }
    }

    /// Its radiance integrated over the sphere of directions, ∫ L dω: for a uniform sky 4π·L,
    /// for a gradient π·(zenith + 2·horizon + nadir) (each hemisphere's radiance is linear in
    /// the height y, and dω = dy dφ), for a map the sum over its texels of radiance × solid
    /// angle.
    pub fn integral(&self) -> Color {
        match self {
            Sky::Uniform(c) => *c * (4.0 * std::f32::consts::PI),
            Sky::Gradient {
                zenith,
                horizon,
                nadir,
            } => (*zenith + *horizon * 2.0 + *nadir) * std::f32::consts::PI,
            Sky::Map(map) => map.integral(),
        }
    }

    /// The sky with every radiance multiplied by `scale` (`sky_scale`).
    pub fn scaled(self, scale: f32) -> Sky {
        match self {
            Sky::Uniform(c) => Sky::Uniform(c * scale),
            Sky::Gradient {
                zenith,
                horizon,
                nadir,
            } => Sky::Gradient {
                zenith: zenith * scale,
                horizon: horizon * scale,
                nadir: nadir * scale,
            },
            Sky::Map(map) => {
                let mut map = Arc::unwrap_or_clone(map);
                map.scale *= scale;
                Sky::Map(Arc::new(map))
            }
        }
    }

    /// The map, for a sky that is one: lights sample it by its importance, where the smooth
    /// skies are sampled by the cosine about the lit surface's normal.
    pub fn map(&self) -> Option<&SkyMap> {
        match self {
            Sky::Map(map) => Some(map),
            _ => None,
        }
    }
}

/// A latitude–longitude sky image and the distribution lights sample it by. Row 0 is the
/// zenith (+y), the last row the nadir; column 0 looks along +x, and the columns turn
/// towards −z (φ = atan2(−z, x) from 0 to 2π): seen from inside, the image reads left to
/// right as one turns to the right. Each texel is constant over its patch of the sphere.
#[derive(Clone, PartialEq)]
pub struct SkyMap {
    /// The image file, as the scene names it, and the line that names it.
    pub file: PathBuf,
    pub line: u32,
    /// Multiplies every texel (`sky_scale`).
    pub scale: f32,
    pub width: u32,
    pub height: u32,
    /// Linear radiance, row 0 at the top (the zenith). Empty until decoded.
    texels: Vec<Color>,
    /// The cumulative share of each row in the texels' weights (luminance × sin θ), 0 first
    /// and 1 last (height + 1 entries).
    rows: Vec<f32>,
    /// For each row, the cumulative share of each of its texels (width + 1 entries a row).
    columns: Vec<f32>,
    /// The density in solid angle with which `sample` draws each texel's directions, row by
    /// row as `texels`: computed once, where every light sample and every escaping ray of a
    /// path asks for it.
    density: Vec<f32>,
    /// None: the layout above. Some(rotation from the scene's frame to the map's): Mitsuba's
    /// `envmap` layout, the mirror image of ours: column 0 looks along −z and the columns
    /// turn towards +x (u = atan2(x, −z) / 2π), row 0 is +y.
    pub mitsuba_frame: Option<glam::Mat3>,
}

impl SkyMap {
    /// A map of `file` (relative to the scene file) not yet decoded.
    pub fn named(file: PathBuf, line: u32) -> SkyMap {
        SkyMap {
            file,
            line,
            scale: 1.0,
            width: 0,
            height: 0,
            texels: Vec::new(),
            rows: Vec::new(),
            columns: Vec::new(),
            density: Vec::new(),
            mitsuba_frame: None,
        }
    }

    /// Reads the image (relative to directory `dir`): .exr and .pfm as linear radiance, .png
    /// and .ppm (any other format `image_io::read_8bit` knows) decoded from sRGB.
    pub fn decode(&mut self, dir: &Path) -> Result<(), String> {
        let path = dir.join(&self.file);
        let Image {
            width,
            height,
            pixels: texels,
        } = image_io::read_radiance(&path)?;
        if width == 0 || height == 0 {
            return Err(format!("{}: an empty image", path.display()));
        }
        if let Some(bad) = texels
            .iter()
            .find(|c| !c.is_finite() || c.min_element() < 0.0)
        {
            return Err(format!(
                "{}: radiance must be finite and ≥ 0, found {bad}",
                path.display()
            ));
        }
        *self = SkyMap {
            scale: self.scale,
            line: self.line,
            mitsuba_frame: self.mitsuba_frame,
            ..SkyMap::from_texels(width, height, texels)
        };
        self.file = path
            .strip_prefix(dir)
            .map_or(path.clone(), Path::to_path_buf);
        Ok(())
    }

    /// A map of `width`×`height` linear texels (row 0 the zenith), with its distribution.
    pub fn from_texels(width: u32, height: u32, texels: Vec<Color>) -> SkyMap {
        let (w, h) = (width as usize, height as usize);
        let mut columns = Vec::with_capacity(h * (w + 1));
        let mut row_weights = Vec::with_capacity(h);
        for row in 0..h {
            let sin = ((row as f32 + 0.5) / h as f32 * std::f32::consts::PI).sin();
            let mut sum = 0.0f64;
            columns.push(0.0);
            for c in &texels[row * w..(row + 1) * w] {
                sum += (luminance(*c) * sin) as f64;
                columns.push(sum as f32);
            }
            normalize_cdf(&mut columns[row * (w + 1)..(row + 1) * (w + 1)], sum);
            row_weights.push(sum);
        }
        let total: f64 = row_weights.iter().sum();
        let mut rows = Vec::with_capacity(h + 1);
        rows.push(0.0);
        let mut sum = 0.0f64;
        for r in &row_weights {
            sum += r;
            rows.push(sum as f32);
        }
        normalize_cdf(&mut rows, total);
        // Each texel's share over its solid angle, (2π/w)·(cos θ0 − cos θ1).
        let band = |k: usize| (k as f32 / h as f32 * std::f32::consts::PI).cos();
        let mut density = Vec::with_capacity(w * h);
        for r in 0..h {
            let row_share = rows[r + 1] - rows[r];
            let cdf = &columns[r * (w + 1)..(r + 1) * (w + 1)];
            let solid_angle = (band(r) - band(r + 1)) * std::f32::consts::TAU / w as f32;
            density.extend(cdf.windows(2).map(|c| {
                if solid_angle <= 0.0 {
                    0.0
                } else {
                    row_share * (c[1] - c[0]) / solid_angle
                }
            }));
        }
        SkyMap {
            file: PathBuf::new(),
            line: 0,
            scale: 1.0,
            width,
            height,
            texels,
            rows,
            columns,
            density,
            mitsuba_frame: None,
        }
    }

    /// The texel a unit direction falls in: (column, row).
    fn texel_of(&self, d: Vec3) -> (usize, usize) {
        let (d, phi) = match self.mitsuba_frame {
            None => (d, (-d.z).atan2(d.x)),
            Some(r) => {
                let d = r * d;
                (d, d.x.atan2(-d.z))
            }
        };
        let theta = d.y.clamp(-1.0, 1.0).acos();
        let phi = phi.rem_euclid(std::f32::consts::TAU);
        let column = (phi / std::f32::consts::TAU * self.width as f32) as usize;
        let row = (theta / std::f32::consts::PI * self.height as f32) as usize;
        (
            column.min(self.width as usize - 1),
            row.min(self.height as usize - 1),
        )
    }

    fn radiance(&self, towards: Vec3) -> Color {
        if self.texels.is_empty() {
            return Vec3::ZERO;
        }
        let (c, r) = self.texel_of(towards);
        self.texels[r * self.width as usize + c] * self.scale
    }

    fn integral(&self) -> Color {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut sum = Vec3::ZERO;
        for row in 0..h {
            let band = |r: usize| (r as f32 / h as f32 * std::f32::consts::PI).cos();
            let solid_angle = (band(row) - band(row + 1)) * std::f32::consts::TAU / w as f32;
            let row_sum = self.texels[row * w..(row + 1) * w]
                .iter()
                .fold(Vec3::ZERO, |a, c| a + *c);
            sum += row_sum * solid_angle;
        }
        sum * self.scale
    }

    /// A direction drawn in proportion to the texels' luminance (× sin θ, so the density is
    /// proportional to luminance per solid angle), from (u, v) in [0,1)², and its density in
    /// solid angle; None for a black map.
    pub fn sample(&self, u: f32, v: f32) -> Option<(Vec3, f32)> {
        if self.rows.last().is_none_or(|&t| t <= 0.0) {
            return None;
        }
        let (w, h) = (self.width as usize, self.height as usize);
        let (row, fv) = pick(&self.rows, v)?;
        let (column, fu) = pick(&self.columns[row * (w + 1)..(row + 1) * (w + 1)], u)?;
        let theta = (row as f32 + fv) / h as f32 * std::f32::consts::PI;
        let phi = (column as f32 + fu) / w as f32 * std::f32::consts::TAU;
        let sin = theta.sin();
        let d = match self.mitsuba_frame {
            None => vec3(sin * phi.cos(), theta.cos(), -sin * phi.sin()),
            Some(r) => r.transpose() * vec3(sin * phi.sin(), theta.cos(), -sin * phi.cos()),
        };
        let pdf = self.density[row * w + column];
        (pdf > 0.0).then_some((d, pdf))
    }

    /// A direction drawn by `sample` for lighting a surface of unit normal `n`, with what its
    /// radiance is weighed by in the surface's irradiance over π, (cos/π)/density; None for a
    /// direction below the surface (it brings nothing) or a black map.
    pub fn sample_above(&self, n: Vec3, u: f32, v: f32) -> Option<(Vec3, f32)> {
        let (d, density) = self.sample(u, v)?;
        let cos = n.dot(d);
        (cos > 0.0).then(|| (d, cos / (std::f32::consts::PI * density)))
    }

    /// The density in solid angle with which `sample` draws the unit direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        if self.density.is_empty() {
            return 0.0;
        }
        let (c, r) = self.texel_of(d);
        self.density[r * self.width as usize + c]
    }
}

/// The file, size and scale, and a hash of the texels (not the texels themselves: a map has
/// millions, and `Scene::content_hash` hashes what this prints).
impl std::fmt::Debug for SkyMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let hash = self.texels.iter().fold(0u64, |h, c| {
            c.to_array()
                .iter()
                .fold(h, |h, x| crate::sampling::mix64(h ^ x.to_bits() as u64))
        });
        write!(
            f,
            "SkyMap({}, {}x{}, scale {}, texels {hash:016x})",
            self.file.display(),
            self.width,
            self.height,
            self.scale
        )?;
        match self.mitsuba_frame {
            Some(r) => write!(f, ", Mitsuba's layout, rotated {r:?}"),
            None => Ok(()),
        }
    }
}

/// The photometric luminance of a linear colour.
fn luminance(c: Color) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Divides a running sum by its total (so it ends at 1); all zero for a total of 0.
fn normalize_cdf(cdf: &mut [f32], total: f64) {
    for x in cdf.iter_mut() {
        *x = if total > 0.0 {
            (*x as f64 / total) as f32
        } else {
            0.0
        };
    }
    if total > 0.0 {
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
    }
}

/// The interval of a cumulative distribution (n + 1 entries from 0 to 1) that `u` falls in,
/// and where in it, in [0, 1); intervals of zero width are never picked.
fn pick(cdf: &[f32], u: f32) -> Option<(usize, f32)> {
    let n = cdf.len().checked_sub(1)?;
    // The first k with cdf[k + 1] > u.
    let k = cdf[1..].partition_point(|&c| c <= u).min(n - 1);
    let width = cdf[k + 1] - cdf[k];
    if width <= 0.0 {
        return None;
    }
    Some((k, ((u - cdf[k]) / width).clamp(0.0, 1.0 - f32::EPSILON)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    /// `integral` against a midpoint sum over the sphere in (y, φ) (dω = dy dφ).
    #[test]
    fn integral_matches_a_sum_over_the_sphere() {
        let sky = Sky::Gradient {
            zenith: vec3(3.0, 2.0, 1.0),
            horizon: vec3(1.0, 1.0, 1.0),
            nadir: vec3(0.5, 0.0, 0.25),
        };
        let n = 400;
        let mut sum = Color::ZERO;
        for i in 0..n {
            let y = -1.0 + (i as f32 + 0.5) * 2.0 / n as f32;
            let r = (1.0 - y * y).sqrt();
            for j in 0..n {
                let phi = (j as f32 + 0.5) * std::f32::consts::TAU / n as f32;
                sum += sky.radiance(vec3(r * phi.cos(), y, r * phi.sin()));
            }
        }
        let sum = sum * (2.0 / n as f32) * (std::f32::consts::TAU / n as f32);
        let exact = sky.integral();
        for c in 0..3 {
            assert!(
                (sum[c] / exact[c] - 1.0).abs() < 1e-3,
                "{sum} against {exact}"
            );
        }
        let uniform = Sky::Uniform(vec3(1.0, 2.0, 3.0)).integral();
        assert!((uniform - vec3(4.0, 8.0, 12.0) * std::f32::consts::PI).length() < 1e-5);
    }

    /// A map with a bright patch: `sample`'s directions fall in each texel as often as its
    /// share says, `pdf` is what `sample` returns, and the map's integral is the sum
    /// ∫ L dω that uniform directions estimate.
    #[test]
    fn map_sampling_follows_the_texels_and_integrates() {
        let (w, h) = (16u32, 8u32);
        let texels: Vec<Color> = (0..w * h)
            .map(|k| {
                let (c, r) = (k % w, k / w);
                if (c, r) == (3, 2) {
                    vec3(50.0, 40.0, 30.0)
                } else {
                    vec3(0.2, 0.3, 1.0) * (1.0 + r as f32 * 0.1)
                }
            })
            .collect();
        let map = SkyMap::from_texels(w, h, texels);
        let mut rng = crate::sampling::Rng::new(1, 2, 3);
        let n = 400_000;
        let (mut bright, mut estimate) = (0usize, Vec3::ZERO);
        for _ in 0..n {
            let (d, pdf) = map.sample(rng.next_f32(), rng.next_f32()).expect("samples");
            assert!((map.pdf(d) / pdf - 1.0).abs() < 1e-3, "{d}: {pdf}");
            if map.texel_of(d) == (3, 2) {
                bright += 1;
            }
            estimate += map.radiance(d) / pdf;
        }
        let estimate = estimate / n as f32;
        let exact = map.integral();
        for c in 0..3 {
            assert!(
                (estimate[c] / exact[c] - 1.0).abs() < 0.01,
                "{estimate} against {exact}"
            );
        }
        let expected = map.rows[3] - map.rows[2];
        let expected = expected * (map.columns[2 * 17 + 4] - map.columns[2 * 17 + 3]);
        let share = bright as f32 / n as f32;
        assert!(
            (share / expected - 1.0).abs() < 0.02,
            "{share} against {expected}"
        );
        // Uniform directions estimate the same integral.
        let mut uniform = Vec3::ZERO;
        for _ in 0..n {
            let d = crate::sampling::sample_cone(Vec3::Y, -1.0, rng.next_f32(), rng.next_f32());
            uniform += map.radiance(d);
        }
        let uniform = uniform * (4.0 * std::f32::consts::PI / n as f32);
        assert!(
            (uniform.z / exact.z - 1.0).abs() < 0.02,
            "{uniform} against {exact}"
        );
    }
}
