//! Mitsuba's `gridvolume`: a volume grid (read from its `.vol` file by `image_io`) placed in
//! the world, and its lookup as Mitsuba makes it: trilinear between the cell centres, clamped
//! to the outer cells.

use glam::{Affine3A, DMat4};

use crate::color::Color;
use crate::geometry::{Bounds3, Vec3};
use crate::image_io::VolumeGrid;

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
        trilinear(&self.grid, self.to_local.transform_point3(p))
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

/// The value at `p` in the grid's unit cube [0, 1]³, as Mitsuba's trilinear filter with
/// its default `clamp` wrap gives it: interpolated between the centres of the eight
/// nearest cells, the outer cells' values held beyond their centres. A single channel is
/// grey.
fn trilinear(grid: &VolumeGrid, p: Vec3) -> Color {
    // Cell k's centre is at (k + ½)/n.
    let mut index = [[0usize; 2]; 3];
    let mut weight = [0f32; 3];
    for axis in 0..3 {
        let n = grid.size[axis];
        let x = p[axis] * n as f32 - 0.5;
        let floor = x.floor();
        weight[axis] = x - floor;
        let clamp = |i: f32| i.clamp(0.0, (n - 1) as f32) as usize;
        index[axis] = [clamp(floor), clamp(floor + 1.0)];
    }
    let [nx, ny, _] = grid.size;
    let value = |x: usize, y: usize, z: usize| {
        let at = ((z * ny + y) * nx + x) * grid.channels;
        if grid.channels == 1 {
            Color::splat(grid.data[at])
        } else {
            Color::new(grid.data[at], grid.data[at + 1], grid.data[at + 2])
        }
    };
    let lerp = |a: Color, b: Color, w: f32| a * (1.0 - w) + b * w;
    let [[x0, x1], [y0, y1], [z0, z1]] = index;
    let along_x = |y, z| lerp(value(x0, y, z), value(x1, y, z), weight[0]);
    let along_y = |z| lerp(along_x(y0, z), along_x(y1, z), weight[1]);
    lerp(along_y(z0), along_y(z1), weight[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid on the unit cube of `size` cells of `channels` channels and these values.
    fn grid(size: [usize; 3], channels: usize, values: &[f32]) -> VolumeGrid {
        VolumeGrid {
            size,
            channels,
            bbox: (Vec3::ZERO, Vec3::ONE),
            data: values.to_vec(),
        }
    }

    #[test]
    fn interpolates_between_cell_centres() {
        // 2×1×1, values 0 and 1: 0 up to x = ¼ (the first centre), linear to 1 at x = ¾,
        // 1 beyond (clamped); y and z change nothing.
        let two = grid([2, 1, 1], 1, &[0.0, 1.0]);
        for (x, expected) in [(0.0, 0.0), (0.25, 0.0), (0.5, 0.5), (0.6, 0.7), (0.9, 1.0)] {
            for (y, z) in [(0.5, 0.5), (0.0, 1.0), (0.9, 0.1)] {
                let v = trilinear(&two, Vec3::new(x, y, z));
                assert!(
                    (v - Color::splat(expected)).abs().max_element() < 1e-6,
                    "({x}, {y}, {z}): {v}"
                );
            }
        }
        // Three channels, x fastest: cell (x, y, z) = (1, 0, 1) of a 2×2×2 grid is the sixth.
        let values: Vec<f32> = (0..24).map(|v| v as f32).collect();
        let cube = grid([2, 2, 2], 3, &values);
        assert_eq!(
            trilinear(&cube, Vec3::new(0.75, 0.25, 0.75)),
            Color::new(15.0, 16.0, 17.0)
        );
        // The middle of the grid is the mean of its cells.
        assert_eq!(
            trilinear(&cube, Vec3::splat(0.5)),
            Color::new(10.5, 11.5, 12.5)
        );
    }
}
