//! Adaptive area-light sampling (`--light-sampling adaptive`, Photonix's and POV-Ray's): a
//! shadow ray to each corner of a parallelogram light; where the corners agree the light is
//! taken as wholly visible or wholly hidden, where they disagree it is split in four and each
//! quarter tested the same way, down to `--adaptive-depth` levels (2×2, 3×3, 5×5, … points,
//! corners shared between cells traced once). A cell's unoccluded light is exact (its form
//! factor by Lambert's contour formula), scaled by the fraction of its corners that see the
//! point. Soft shadows cost four rays where a light is fully lit or fully hidden and more only
//! in the penumbra; the estimate is deterministic, so it has no noise but is biased where a
//! shadow's edge crosses a cell of the finest level, or where an occluder slips between
//! corners that agree.

use crate::geometry::form_factor::point_to_polygon;
use crate::geometry::Vec3;

use super::lights::Parallelogram;

/// The deepest `--adaptive-depth` accepted: 65×65 corner points.
pub const MAX_DEPTH: u32 = 6;

/// Where a corner's shadow ray goes, in from the light's rim by this fraction of an edge: a
/// ray to the rim itself grazes the surfaces the light is set in (the ceiling around a
/// ceiling light, the walls it touches).
const RIM_INSET: f32 = 1e-3;

/// A corner's state in `scratch`.
const UNTRACED: u8 = 0;
const SEES: u8 = 1;
const HIDDEN: u8 = 2;

/// The form factor from the point `x` (unit normal `n`) to the parts of the light `quad` that
/// it sees (none from behind a one-sided light), refined `depth` levels where corners disagree. `sees(p)` traces the
/// shadow ray to the light point `p`; `scratch` holds the corners' states between calls (its
/// allocation is reused). Multiplied by the light's radiance, this is the reflected radiance
/// over the albedo.
pub fn visible_form_factor(
    x: Vec3,
    n: Vec3,
    quad: &Parallelogram,
    depth: u32,
    scratch: &mut Vec<u8>,
    mut sees: impl FnMut(Vec3) -> bool,
) -> f32 {
    // Behind a one-sided light, nothing to see and no ray to trace.
    if quad.normal_towards(x).is_none() {
        return 0.0;
    }
    let cells = 1usize << depth.min(MAX_DEPTH);
    let side = cells + 1;
    scratch.clear();
    scratch.resize(side * side, UNTRACED);
    let step = 1.0 / cells as f32;
    let mut corner_sees = |i: usize, j: usize| {
        let state = &mut scratch[j * side + i];
        if *state == UNTRACED {
            let inset = |k: usize| RIM_INSET + (1.0 - 2.0 * RIM_INSET) * (k as f32 * step);
            *state = if sees(quad.sample(inset(i), inset(j)).point) {
                SEES
            } else {
                HIDDEN
            };
        }
        *state == SEES
    };
    // Cells still to test: corner (i, j) and size in grid steps. Depth-first, so at most
    // three siblings wait per level: a fixed stack, no allocation per shading point.
    let mut pending = [(0usize, 0usize, 0usize); 3 * MAX_DEPTH as usize + 1];
    pending[0] = (0, 0, cells);
    let mut waiting = 1;
    let mut total = 0.0;
    while waiting > 0 {
        waiting -= 1;
        let (i, j, size) = pending[waiting];
        let seen = [(i, j), (i + size, j), (i + size, j + size), (i, j + size)]
            .into_iter()
            .filter(|&(a, b)| corner_sees(a, b))
            .count();
        if seen == 0 || seen == 4 || size == 1 {
            if seen > 0 {
                let at = |a: usize, b: usize| quad.sample(a as f32 * step, b as f32 * step).point;
                let cell = [
                    at(i, j),
                    at(i + size, j),
                    at(i + size, j + size),
                    at(i, j + size),
                ];
                total += seen as f32 / 4.0 * point_to_polygon(x, n, &cell);
            }
        } else {
            let half = size / 2;
            for (a, b) in [(0, 0), (half, 0), (half, half), (0, half)] {
                pending[waiting] = (i + a, j + b, half);
                waiting += 1;
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    /// A unit square light at height 1 facing down, over the origin.
    fn ceiling_light() -> Parallelogram {
        Parallelogram::new(
            vec3(-0.5, 1.0, -0.5),
            vec3(1.0, 0.0, 0.0),
            vec3(0.0, 0.0, 1.0),
            vec3(0.0, -1.0, 0.0),
            false,
        )
    }

    #[test]
    fn an_unoccluded_light_takes_four_rays_and_lamberts_value() {
        let light = ceiling_light();
        let whole = [
            vec3(-0.5, 1.0, -0.5),
            vec3(0.5, 1.0, -0.5),
            vec3(0.5, 1.0, 0.5),
            vec3(-0.5, 1.0, 0.5),
        ];
        let (x, n) = (vec3(0.2, 0.0, -0.1), vec3(0.0, 1.0, 0.0));
        let mut rays = 0;
        let f = visible_form_factor(x, n, &light, 3, &mut Vec::new(), |_| {
            rays += 1;
            true
        });
        assert_eq!(rays, 4);
        assert_eq!(f, point_to_polygon(x, n, &whole));
        // Behind the light (it faces down): nothing, and no ray.
        let f = visible_form_factor(vec3(0.0, 2.0, 0.0), -n, &light, 3, &mut Vec::new(), |_| {
            unreachable!("no ray from behind a one-sided light")
        });
        assert_eq!(f, 0.0);
    }

    /// An occluder hides the light's part x > 0.13 from the origin. Cells wholly on either
    /// side are exact; each cell the edge crosses is counted half seen, so the error is at
    /// most half the form factor of the column of finest cells the edge crosses, which
    /// halves with each level; rays are spent only along the edge.
    #[test]
    fn a_shadow_edge_is_refined_where_the_corners_disagree() {
        let light = ceiling_light();
        let (x, n) = (Vec3::ZERO, vec3(0.0, 1.0, 0.0));
        let edge = 0.13;
        let strip = |from: f32, to: f32| {
            point_to_polygon(
                x,
                n,
                &[
                    vec3(from, 1.0, -0.5),
                    vec3(to, 1.0, -0.5),
                    vec3(to, 1.0, 0.5),
                    vec3(from, 1.0, 0.5),
                ],
            )
        };
        let exact = strip(-0.5, edge);
        for depth in 1..=MAX_DEPTH {
            let mut rays = 0;
            let f = visible_form_factor(x, n, &light, depth, &mut Vec::new(), |p| {
                rays += 1;
                p.x < edge
            });
            let width = 1.0 / (1u32 << depth) as f32;
            let column = ((edge + 0.5) / width).floor() * width - 0.5;
            let bound = 0.5 * strip(column, column + width);
            println!(
                "depth {depth}: {rays} rays, error {:.2e}, bound {bound:.2e}",
                (f - exact).abs()
            );
            assert!(
                (f - exact).abs() <= bound * 1.0001,
                "depth {depth}: {f} against {exact}"
            );
            // The corners of the edge's column at each level: about 4·2^depth, where the
            // whole grid has (2^depth + 1)².
            let side = (1u32 << depth) + 1;
            assert!(rays <= 4 * side + 2 * depth, "depth {depth}: {rays} rays");
        }
    }
}
