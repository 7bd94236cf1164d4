//! Mitsuba's binary volume grids (`.vol`, the format of its `gridvolume`) and their lookup as
//! Mitsuba makes it: trilinear between the cell centres, clamped to the outer cells.
//!
//! The file, little-endian: the bytes `VOL`, the version byte 3, an `i32` encoding (1:
//! float32, the only one), the `i32` cell counts along x, y and z, the `i32` channel count,
//! the bounding box as six `f32` (min x, y, z, max x, y, z), then the values, channels
//! interleaved, x fastest, then y, then z.

use std::path::Path;

use glam::{Affine3A, DMat4};

use crate::color::Color;
use crate::geometry::{Bounds3, Vec3};

/// Bytes before the values.
const HEADER_BYTES: usize = 48;

/// A grid of values read from a `.vol` file.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeGrid {
    /// Cells along x, y and z (each ≥ 1).
    pub size: [usize; 3],
    /// Values a cell: 1 (a density) or 3 (a colour).
    pub channels: usize,
    /// The box the file places the grid in (min, max): where Mitsuba's `use_grid_bbox` puts it.
    pub bbox: (Vec3, Vec3),
    /// The values, channels interleaved, x fastest, then y, then z.
    pub data: Vec<f32>,
}

impl VolumeGrid {
    /// Reads a `.vol` file; the error names the file and what it expected there.
    pub fn load(path: &Path) -> Result<VolumeGrid, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        VolumeGrid::parse(&bytes).map_err(|why| format!("{}: {why}", path.display()))
    }

    /// Decodes the bytes of a `.vol` file: its header checked, and its length against the
    /// header's counts before anything is allocated.
    pub fn parse(bytes: &[u8]) -> Result<VolumeGrid, String> {
        if bytes.len() < HEADER_BYTES {
            return Err(format!(
                "{} bytes: expected a Mitsuba volume grid's {HEADER_BYTES}-byte header",
                bytes.len()
            ));
        }
        if &bytes[0..3] != b"VOL" {
            return Err("expected a Mitsuba volume grid (starting with \"VOL\")".into());
        }
        if bytes[3] != 3 {
            return Err(format!("version {}: expected version 3", bytes[3]));
        }
        let int = |k: usize| i32::from_le_bytes(bytes[4 + 4 * k..8 + 4 * k].try_into().unwrap());
        let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let encoding = int(0);
        if encoding != 1 {
            return Err(format!("encoding {encoding}: expected 1 (float32)"));
        }
        let count = |k: usize, what: &str| {
            usize::try_from(int(k))
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| format!("{} cells along {what}: expected at least 1", int(k)))
        };
        let size = [count(1, "x")?, count(2, "y")?, count(3, "z")?];
        let channels = int(4);
        if channels != 1 && channels != 3 {
            return Err(format!("{channels} channels: expected 1 or 3"));
        }
        let channels = channels as usize;
        let values = size
            .iter()
            .try_fold(channels, |n, &s| n.checked_mul(s))
            .filter(|n| n.checked_mul(4).is_some())
            .ok_or_else(|| format!("{size:?} cells of {channels} channels: too many"))?;
        let expected = HEADER_BYTES as u64 + 4 * values as u64;
        if bytes.len() as u64 != expected {
            return Err(format!(
                "{} bytes: expected {expected} for {}×{}×{} cells of {channels} channel(s)",
                bytes.len(),
                size[0],
                size[1],
                size[2]
            ));
        }
        let bbox = (
            Vec3::new(float(24), float(28), float(32)),
            Vec3::new(float(36), float(40), float(44)),
        );
        let data: Vec<f32> = bytes[HEADER_BYTES..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        if let Some(k) = data.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "value {k} is {}: expected a finite number",
                data[k]
            ));
        }
        Ok(VolumeGrid {
            size,
            channels,
            bbox,
            data,
        })
    }

    /// The largest value of any cell and channel (0 for none above it).
    pub fn max(&self) -> f32 {
        self.data.iter().fold(0.0, |m, &v| m.max(v))
    }

    /// The value at `p` in the grid's unit cube [0, 1]³, as Mitsuba's trilinear filter with
    /// its default `clamp` wrap gives it: interpolated between the centres of the eight
    /// nearest cells, the outer cells' values held beyond their centres. A single channel is
    /// grey.
    pub fn trilinear(&self, p: Vec3) -> Color {
        // Cell k's centre is at (k + ½)/n.
        let mut index = [[0usize; 2]; 3];
        let mut weight = [0f32; 3];
        for axis in 0..3 {
            let n = self.size[axis];
            let x = p[axis] * n as f32 - 0.5;
            let floor = x.floor();
            weight[axis] = x - floor;
            let clamp = |i: f32| i.clamp(0.0, (n - 1) as f32) as usize;
            index[axis] = [clamp(floor), clamp(floor + 1.0)];
        }
        let [nx, ny, _] = self.size;
        let value = |x: usize, y: usize, z: usize| {
            let at = ((z * ny + y) * nx + x) * self.channels;
            if self.channels == 1 {
                Color::splat(self.data[at])
            } else {
                Color::new(self.data[at], self.data[at + 1], self.data[at + 2])
            }
        };
        let lerp = |a: Color, b: Color, w: f32| a * (1.0 - w) + b * w;
        let [[x0, x1], [y0, y1], [z0, z1]] = index;
        let along_x = |y, z| lerp(value(x0, y, z), value(x1, y, z), weight[0]);
        let along_y = |z| lerp(along_x(y0, z), along_x(y1, z), weight[1]);
        lerp(along_y(z0), along_y(z1), weight[2])
    }
}

/// A grid placed in the world (Mitsuba's `gridvolume`): its unit cube mapped by `to_world`
/// (or, with `use_grid_bbox`, the box the file gives mapped so).
#[derive(Clone, Debug, PartialEq)]
pub struct GridVolume {
    pub grid: VolumeGrid,
    /// From the world to the grid's unit cube.
    pub to_local: Affine3A,
}

impl GridVolume {
    /// The grid placed by `to_world`; with `use_grid_bbox`, the file's box is the grid's
    /// extent before `to_world` (Mitsuba's default is the unit cube). None where the map (or
    /// the file's box) is degenerate.
    pub fn new(grid: VolumeGrid, to_world: DMat4, use_grid_bbox: bool) -> Option<GridVolume> {
        let mut to_local = to_world.inverse();
        if use_grid_bbox {
            let (min, max) = (grid.bbox.0.as_dvec3(), grid.bbox.1.as_dvec3());
            to_local =
                DMat4::from_scale((max - min).recip()) * DMat4::from_translation(-min) * to_local;
        }
        let affine = Affine3A::from_mat4(to_local.as_mat4());
        let finite = to_local.is_finite() && to_local.determinant() != 0.0;
        finite.then_some(GridVolume {
            grid,
            to_local: affine,
        })
    }

    /// The value at the world point `p` (clamped to the outer cells beyond the grid).
    pub fn eval(&self, p: Vec3) -> Color {
        self.grid.trilinear(self.to_local.transform_point3(p))
    }

    /// The grid's box in the world: its unit cube's corners mapped there.
    pub fn bounds(&self) -> Bounds3 {
        let to_world = self.to_local.inverse();
        let corners: Vec<Vec3> = (0..8)
            .map(|k| {
                let corner = Vec3::new((k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2) as f32);
                to_world.transform_point3(corner)
            })
            .collect();
        Bounds3::from_points(&corners)
    }

    /// The same grid in a world scaled by `scale` about the origin and moved by `offset`.
    pub fn transformed(&self, scale: f32, offset: Vec3) -> GridVolume {
        let from_new =
            Affine3A::from_scale(Vec3::splat(scale.recip())) * Affine3A::from_translation(-offset);
        GridVolume {
            grid: self.grid.clone(),
            to_local: self.to_local * from_new,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bytes of a `.vol` file of `size` cells of `channels` channels and these values.
    fn file(size: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
        let mut bytes = b"VOL\x03".to_vec();
        for v in [1, size[0], size[1], size[2], channels] {
            bytes.extend(v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(values) {
            bytes.extend(v.to_le_bytes());
        }
        bytes
    }

    #[test]
    fn reads_a_grid_and_interpolates_between_cell_centres() {
        // 2×1×1, values 0 and 1: 0 up to x = ¼ (the first centre), linear to 1 at x = ¾,
        // 1 beyond (clamped); y and z change nothing.
        let grid = VolumeGrid::parse(&file([2, 1, 1], 1, &[0.0, 1.0])).expect("reads");
        assert_eq!(grid.size, [2, 1, 1]);
        assert_eq!(grid.max(), 1.0);
        for (x, expected) in [(0.0, 0.0), (0.25, 0.0), (0.5, 0.5), (0.6, 0.7), (0.9, 1.0)] {
            for (y, z) in [(0.5, 0.5), (0.0, 1.0), (0.9, 0.1)] {
                let v = grid.trilinear(Vec3::new(x, y, z));
                assert!(
                    (v - Color::splat(expected)).abs().max_element() < 1e-6,
                    "({x}, {y}, {z}): {v}"
                );
            }
        }
        // Three channels, x fastest: cell (x, y, z) = (1, 0, 1) of a 2×2×2 grid is the sixth.
        let values: Vec<f32> = (0..24).map(|v| v as f32).collect();
        let grid = VolumeGrid::parse(&file([2, 2, 2], 3, &values)).expect("reads");
        assert_eq!(
            grid.trilinear(Vec3::new(0.75, 0.25, 0.75)),
            Color::new(15.0, 16.0, 17.0)
        );
        // The middle of the grid is the mean of its cells.
        assert_eq!(
            grid.trilinear(Vec3::splat(0.5)),
            Color::new(10.5, 11.5, 12.5)
        );
    }

    #[test]
    fn refuses_bad_files_saying_what_it_expected() {
        let good = file([2, 2, 1], 1, &[0.0; 4]);
        let cases: [(Vec<u8>, &str); 7] = [
            (
                good[..40].to_vec(),
                "40 bytes: expected a Mitsuba volume grid's 48-byte header",
            ),
            (
                good[..60].to_vec(),
                "60 bytes: expected 64 for 2×2×1 cells of 1 channel(s)",
            ),
            ([&good[..], &[0; 4]].concat(), "68 bytes: expected 64"),
            (
                b"BOL".iter().chain(&good[3..]).copied().collect(),
                "\"VOL\"",
            ),
            (
                file([2, 0, 1], 1, &[]),
                "0 cells along y: expected at least 1",
            ),
            (file([1, 1, 1], 2, &[0.0; 2]), "2 channels: expected 1 or 3"),
            (file([1, 1, 1], 1, &[f32::NAN]), "value 0 is NaN"),
        ];
        for (bytes, expected) in cases {
            let why = VolumeGrid::parse(&bytes).expect_err(expected);
            assert!(why.contains(expected), "{why:?} does not say {expected:?}");
        }
        // Counts whose product overflows are refused before anything is allocated.
        let huge = file([i32::MAX, i32::MAX, i32::MAX], 3, &[]);
        assert!(VolumeGrid::parse(&huge).is_err());
        let missing = Path::new("/nonexistent/grid.vol");
        let why = VolumeGrid::load(missing).expect_err("no such file");
        assert!(why.starts_with("/nonexistent/grid.vol: "), "{why}");
    }
}
