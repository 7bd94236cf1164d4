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
///
/// Mitsuba's `envmap` (`mitsuba_frame`) lays its texels out otherwise, and interpolates them.
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
    /// The cells `sample` draws from, each of constant density: (columns, rows). In our
    /// layout the texels; in Mitsuba's the squares between four texel centres, over which its
    /// radiance is bilinear: `width` × (`height` − 1), the first column's left edge at the
    /// first texel's centre.
    cells: (usize, usize),
    /// The cumulative share of each row of cells in their weights (luminance × sin θ; in
    /// Mitsuba's layout the mean of the cell's four corners), 0 first and 1 last.
    rows: Vec<f32>,
    /// For each row, the cumulative share of each of its cells (columns + 1 entries a row).
    columns: Vec<f32>,
    /// The guide tables of `rows` (one entry a row) and of each row's `columns` (one entry a
    /// cell), where `pick` starts its search.
    row_guide: Vec<u32>,
    column_guide: Vec<u32>,
    /// The density in solid angle with which `sample` draws each cell's directions, row by
    /// row: computed once, where every light sample and every escaping ray of a path asks
    /// for it.
    density: Vec<f32>,
    /// None: the layout above. Some(rotation from the scene's frame to the map's): Mitsuba's
    /// `envmap` layout, the mirror image of ours: the texel centres of a row at
    /// u = (column + 0.5) / width, u = atan2(x, −z) / 2π (column 0 looks along −z, the columns
    /// turn towards +x), those of a column at θ = π · row / (height − 1) (row 0 at +y, the
    /// last at −y), radiance bilinear between them, periodic in u.
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
            cells: (0, 0),
            rows: Vec::new(),
            columns: Vec::new(),
            row_guide: Vec::new(),
            column_guide: Vec::new(),
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
            ..SkyMap::from_texels(width, height, texels, self.mitsuba_frame)
        };
        self.file = path
            .strip_prefix(dir)
            .map_or(path.clone(), Path::to_path_buf);
        Ok(())
    }

    /// A map of `width`×`height` linear texels (row 0 the zenith), in our layout or (with
    /// `mitsuba_frame`) in Mitsuba's, with its distribution.
    pub fn from_texels(
        width: u32,
        height: u32,
        texels: Vec<Color>,
        mitsuba_frame: Option<glam::Mat3>,
    ) -> SkyMap {
        let (w, h) = (width as usize, height as usize);
        let cells = match mitsuba_frame {
            None => (w, h),
            Some(_) => (w, h.saturating_sub(1).max(1)),
        };
        let mut map = SkyMap {
            file: PathBuf::new(),
            line: 0,
            scale: 1.0,
            width,
            height,
            texels,
            cells,
            rows: Vec::new(),
            columns: Vec::new(),
            row_guide: Vec::new(),
            column_guide: Vec::new(),
            density: Vec::new(),
            mitsuba_frame,
        };
        let (cw, ch) = cells;
        let mut columns = Vec::with_capacity(ch * (cw + 1));
        let mut row_weights = Vec::with_capacity(ch);
        for row in 0..ch {
            let sin = ((row as f32 + 0.5) / ch as f32 * std::f32::consts::PI).sin();
            let mut sum = 0.0f64;
            columns.push(0.0);
            for column in 0..cw {
                sum += (luminance(map.cell_mean(column, row)) * sin) as f64;
                columns.push(sum as f32);
            }
            normalize_cdf(&mut columns[row * (cw + 1)..(row + 1) * (cw + 1)], sum);
            row_weights.push(sum);
        }
        let total: f64 = row_weights.iter().sum();
        let mut rows = Vec::with_capacity(ch + 1);
        rows.push(0.0);
        let mut sum = 0.0f64;
        for r in &row_weights {
            sum += r;
            rows.push(sum as f32);
        }
        normalize_cdf(&mut rows, total);
        let mut density = Vec::with_capacity(cw * ch);
        for r in 0..ch {
            let row_share = rows[r + 1] - rows[r];
            let cdf = &columns[r * (cw + 1)..(r + 1) * (cw + 1)];
            let solid_angle = map.cell_solid_angle(r);
            density.extend(cdf.windows(2).map(|c| {
                if solid_angle <= 0.0 {
                    0.0
                } else {
                    row_share * (c[1] - c[0]) / solid_angle
                }
            }));
        }
        map.row_guide = guide(&rows).collect();
        map.column_guide = columns.chunks(cw + 1).flat_map(guide).collect();
        map.rows = rows;
        map.columns = columns;
        map.density = density;
        map
    }

    /// The texel at (column, row), the column periodic and the row clamped.
    fn texel(&self, column: usize, row: usize) -> Color {
        let (w, h) = (self.width as usize, self.height as usize);
        // Columns come in [0, w] (a bilinear lookup's right neighbour): the division of `%`
        // only for the one past the end.
        let column = if column < w { column } else { column % w };
        self.texels[row.min(h - 1) * w + column]
    }

    /// A cell's mean radiance (unscaled): its texel in our layout; in Mitsuba's the mean of
    /// its four corners, which is the mean of the bilinear radiance over the cell.
    fn cell_mean(&self, column: usize, row: usize) -> Color {
        match self.mitsuba_frame {
            None => self.texel(column, row),
            Some(_) => {
                (self.texel(column, row)
                    + self.texel(column + 1, row)
                    + self.texel(column, row + 1)
                    + self.texel(column + 1, row + 1))
                    * 0.25
            }
        }
    }

    /// The solid angle of a cell of row `row`: (2π/columns)·(cos θ0 − cos θ1).
    fn cell_solid_angle(&self, row: usize) -> f32 {
        let (cw, ch) = self.cells;
        let band = |k: usize| (k as f32 / ch as f32 * std::f32::consts::PI).cos();
        (band(row) - band(row + 1)) * std::f32::consts::TAU / cw as f32
    }

    /// Where a unit direction points in the map: (u, v) in [0, 1)×[0, 1], u = φ/2π in the
    /// map's layout, v = θ/π from the zenith.
    fn uv_of(&self, d: Vec3) -> (f32, f32) {
        let (d, phi) = match self.mitsuba_frame {
            None => (d, (-d.z).atan2(d.x)),
            Some(r) => {
                let d = r * d;
                (d, d.x.atan2(-d.z))
            }
        };
        let theta = d.y.clamp(-1.0, 1.0).acos();
        (
            phi.rem_euclid(std::f32::consts::TAU) / std::f32::consts::TAU,
            theta / std::f32::consts::PI,
        )
    }

    /// The cell a unit direction falls in: (column, row).
    fn cell_of(&self, d: Vec3) -> (usize, usize) {
        let (u, v) = self.uv_of(d);
        let (cw, ch) = self.cells;
        // Mitsuba's cells start at the first texel's centre, half a cell on.
        let shift = if self.mitsuba_frame.is_some() {
            0.5
        } else {
            0.0
        };
        let column = (u * cw as f32 - shift).rem_euclid(cw as f32) as usize;
        let row = (v * ch as f32) as usize;
        (column.min(cw - 1), row.min(ch - 1))
    }

    fn radiance(&self, towards: Vec3) -> Color {
        if self.texels.is_empty() {
            return Vec3::ZERO;
        }
        if self.mitsuba_frame.is_none() {
            let (c, r) = self.cell_of(towards);
            return self.texel(c, r) * self.scale;
        }
        // Bilinear between the four texel centres around the direction.
        let (u, v) = self.uv_of(towards);
        let (w, h) = (self.width as f32, self.height as f32);
        let x = (u * w - 0.5).rem_euclid(w);
        let y = (v * (h - 1.0)).clamp(0.0, (h - 1.0).max(0.0));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (c, r) = (x0 as usize, y0 as usize);
        let top = self.texel(c, r) * (1.0 - fx) + self.texel(c + 1, r) * fx;
        let bottom = self.texel(c, r + 1) * (1.0 - fx) + self.texel(c + 1, r + 1) * fx;
        (top * (1.0 - fy) + bottom * fy) * self.scale
    }

    /// ∫ L dω: the sum over the cells of their mean radiance × solid angle (exact in our
    /// layout; in Mitsuba's to second order in the cell's size).
    fn integral(&self) -> Color {
        let (cw, ch) = self.cells;
        let mut sum = Vec3::ZERO;
        for row in 0..ch {
            let row_sum = (0..cw).fold(Vec3::ZERO, |a, c| a + self.cell_mean(c, row));
            sum += row_sum * self.cell_solid_angle(row);
        }
        sum * self.scale
    }

    /// A direction drawn in proportion to the cells' luminance (× sin θ, so the density is
    /// proportional to luminance per solid angle), from (u, v) in [0,1)², and its density in
    /// solid angle; None for a black map.
    pub fn sample(&self, u: f32, v: f32) -> Option<(Vec3, f32)> {
        if self.rows.last().is_none_or(|&t| t <= 0.0) {
            return None;
        }
        let (cw, ch) = self.cells;
        let (row, fv) = pick(&self.rows, &self.row_guide, v)?;
        let (column, fu) = pick(
            &self.columns[row * (cw + 1)..(row + 1) * (cw + 1)],
            &self.column_guide[row * cw..(row + 1) * cw],
            u,
        )?;
        let theta = (row as f32 + fv) / ch as f32 * std::f32::consts::PI;
        let sin = theta.sin();
        let d = match self.mitsuba_frame {
            None => {
                let phi = (column as f32 + fu) / cw as f32 * std::f32::consts::TAU;
                vec3(sin * phi.cos(), theta.cos(), -sin * phi.sin())
            }
            Some(r) => {
                let phi = (column as f32 + 0.5 + fu) / cw as f32 * std::f32::consts::TAU;
                r.transpose() * vec3(sin * phi.sin(), theta.cos(), -sin * phi.cos())
            }
        };
        let pdf = self.density[row * cw + column];
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
        let (c, r) = self.cell_of(d);
        self.density[r * self.cells.0 + c]
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

/// A cumulative distribution's guide table (Chen & Asau's cutpoints), n entries for its n
/// intervals: entry j is the first interval that ends above j/n.
fn guide(cdf: &[f32]) -> impl Iterator<Item = u32> + '_ {
    let n = cdf.len() - 1;
    let mut k = 0;
    (0..n).map(move |j| {
        let threshold = j as f32 / n as f32;
        while k < n - 1 && cdf[k + 1] <= threshold {
            k += 1;
        }
        k as u32
    })
}

/// The interval of a cumulative distribution (n + 1 entries from 0 to 1) that `u` falls in,
/// and where in it, in [0, 1); intervals of zero width are never picked. The search starts
/// where `guide` (the distribution's `guide` table) says and steps on: a step or two, where a
/// binary search waited on a cache miss at each of its log₂ n steps (the column search of a
/// 512-wide map was a tenth of a path-traced envmap scene's time).
fn pick(cdf: &[f32], guide: &[u32], u: f32) -> Option<(usize, f32)> {
    let n = cdf.len().checked_sub(1)?;
    // One bucket back: u·n rounded up onto an integer must not start past the answer.
    let bucket = ((u * n as f32) as usize).min(n - 1).saturating_sub(1);
    // The first k with cdf[k + 1] > u (the last interval if none).
    let mut k = guide[bucket] as usize;
    while k < n - 1 && cdf[k + 1] <= u {
        k += 1;
    }
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

    /// `pick` finds the interval a binary search finds (the first whose end is above u), on
    /// distributions flat, peaked and with empty stretches, for u across [0, 1).
    #[test]
    fn the_guided_search_finds_the_interval_a_binary_search_finds() {
        let weights: [Vec<f32>; 4] = [
            vec![1.0; 37],
            (0..200).map(|k| if k == 77 { 1e4 } else { 0.01 }).collect(),
            (0..64)
                .map(|k| if k % 9 < 4 { 0.0 } else { k as f32 })
                .collect(),
            vec![0.0, 0.0, 5.0],
        ];
        let mut rng = crate::sampling::Rng::new(4, 5, 6);
        for w in &weights {
            let mut cdf = vec![0.0f32];
            let mut sum = 0.0f64;
            for x in w {
                sum += *x as f64;
                cdf.push(sum as f32);
            }
            normalize_cdf(&mut cdf, sum);
            let table: Vec<u32> = guide(&cdf).collect();
            let n = cdf.len() - 1;
            for k in 0..20_000 {
                let u = if k < 1000 {
                    k as f32 / 1000.0
                } else {
                    rng.next_f32()
                };
                let binary = cdf[1..].partition_point(|&c| c <= u).min(n - 1);
                let found = pick(&cdf, &table, u).map(|(k, _)| k);
                let expected = (cdf[binary + 1] > cdf[binary]).then_some(binary);
                assert_eq!(found, expected, "u {u} in {cdf:?}");
            }
        }
    }

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

    /// A map with a bright patch, in our layout and in Mitsuba's (rotated): `sample`'s
    /// directions fall in each cell as often as its share says, `pdf` is what `sample`
    /// returns, and the map's integral is the sum ∫ L dω that uniform directions estimate.
    #[test]
    fn map_sampling_follows_the_texels_and_integrates() {
        for frame in [None, Some(glam::Mat3::from_rotation_y(0.3))] {
            sampling_follows_the_cells(frame);
        }
    }

    fn sampling_follows_the_cells(frame: Option<glam::Mat3>) {
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
        let map = SkyMap::from_texels(w, h, texels, frame);
        let mut rng = crate::sampling::Rng::new(1, 2, 3);
        let n = 400_000;
        let (mut bright, mut estimate) = (0usize, Vec3::ZERO);
        for _ in 0..n {
            let (d, pdf) = map.sample(rng.next_f32(), rng.next_f32()).expect("samples");
            assert!((map.pdf(d) / pdf - 1.0).abs() < 1e-3, "{d}: {pdf}");
            if map.cell_of(d) == (3, 2) {
                bright += 1;
            }
            estimate += map.radiance(d) / pdf;
        }
        let estimate = estimate / n as f32;
        let exact = map.integral();
        for c in 0..3 {
            assert!(
                (estimate[c] / exact[c] - 1.0).abs() < 0.01,
                "{frame:?}: {estimate} against {exact}"
            );
        }
        let expected = map.rows[3] - map.rows[2];
        let expected = expected * (map.columns[2 * 17 + 4] - map.columns[2 * 17 + 3]);
        assert!(expected > 0.05, "the bright cell's share {expected}");
        let share = bright as f32 / n as f32;
        assert!(
            (share / expected - 1.0).abs() < 0.02,
            "{frame:?}: {share} against {expected}"
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
            "{frame:?}: {uniform} against {exact}"
        );
    }
}
