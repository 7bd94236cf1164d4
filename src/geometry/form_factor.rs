//! The point-to-polygon form factor, exact: Lambert's contour integral over the polygon
//! clipped to the hemisphere above the point. Radiosity averages it over points of a
//! receiving patch (each tested for visibility with one ray); the ray tracer's adaptive
//! light sampling weighs the cells of a light with it.

use crate::geometry::Vec3;

/// Form factor from a differential area at `x` with unit normal `n` to the polygon `polygon`
/// (planar, convex, any orientation): the fraction of the light leaving `x` diffusely that
/// reaches the polygon, ignoring occlusion. The part of the polygon below `x`'s tangent plane
/// is clipped away first; a polygon seen from behind counts like one seen from the front
/// (callers decide which side emits).
pub fn point_to_polygon(x: Vec3, n: Vec3, polygon: &[Vec3]) -> f32 {
    let mut clipped = [Vec3::ZERO; 8];
    // Most polygons lie wholly above the plane, and clipping would copy them as they are.
    let vertices = if polygon.iter().all(|&p| (p - x).dot(n) > 0.0) {
        polygon
    } else {
        let count = clip_above(x, n, polygon, &mut clipped);
        &clipped[..count]
    };
    if vertices.len() < 3 {
        return 0.0;
    }
    // The edges' terms are independent: taken four at a time in lanes (the compiler makes
    // vector instructions of the lane loops), each lane with the scalar operations in the
    // scalar order, so the result is the same to the bit; summed in edge order.
    let count = vertices.len();
    let mut sum = 0.0f64;
    for first in (0..count).step_by(LANES) {
        let mut a = [[0.0f32; LANES]; 3];
        let mut b = [[0.0f32; LANES]; 3];
        for l in 0..LANES.min(count - first) {
            let (p, q) = (
                vertices[first + l] - x,
                vertices[(first + l + 1) % count] - x,
            );
            for axis in 0..3 {
                a[axis][l] = p[axis];
                b[axis][l] = q[axis];
            }
        }
        // A lane past the last edge has a = b = 0: no length, no term.
        for term in edge_terms(a, b, n) {
            sum += term as f64;
        }
    }
    (sum.abs() / std::f64::consts::TAU) as f32
}

/// Edges a polygon's contour sum takes at once.
const LANES: usize = 4;

/// Each lane's term of Lambert's contour sum for the edge from a to b (vertices seen from
/// the point, given by axis then lane): n·(a×b)/|a×b| times the angle between a and b, 0
/// where a×b has no (finite) length.
#[inline]
fn edge_terms(a: [[f32; LANES]; 3], b: [[f32; LANES]; 3], n: Vec3) -> [f32; LANES] {
    let mut terms = [0.0f32; LANES];
    for l in 0..LANES {
        let (ax, ay, az) = (a[0][l], a[1][l], a[2][l]);
        let (bx, by, bz) = (b[0][l], b[1][l], b[2][l]);
        // a × b, |a × b| and a·b as glam's Vec3 computes them.
        let (cx, cy, cz) = (ay * bz - by * az, az * bx - bz * ax, ax * by - bx * ay);
        let len = ((cx * cx) + (cy * cy) + (cz * cz)).sqrt();
        let dot = (ax * bx) + (ay * by) + (az * bz);
        let normal = (n.x * cx) + (n.y * cy) + (n.z * cz);
        let term = normal / len * angle_atan2(len, dot);
        terms[l] = if len > 0.0 && len.is_finite() {
            term
        } else {
            0.0
        };
    }
    terms
}

/// atan2(y, x) for y ≥ 0, in [0, π]: the polynomial of Abramowitz & Stegun 4.4.49 (error
/// below 2e-8 on [0, 1], under f32's own rounding) after reducing to that interval. libm's
/// atan2f was a fifth of the time of a radiosity solve; this is a few multiply-adds.
#[inline]
fn angle_atan2(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let ax = x.abs();
    let (num, den) = if ax >= y { (y, ax) } else { (ax, y) };
    // 0/0 where x = y = 0: then 0, as atan2 gives.
    let t = if den == 0.0 { 0.0 } else { num / den };
    let t2 = t * t;
    let poly = [
        -0.016_165_737,
        0.042_909_614,
        -0.075_289_64,
        0.106_562_64,
        -0.142_089,
        0.199_935_51,
        -0.333_331_45,
        1.0,
    ]
    .into_iter()
    .fold(0.002_866_225_7f32, |acc, c| fused_multiply_add(acc, t2, c));
    let a = t * poly;
    let a = if ax >= y { a } else { FRAC_PI_2 - a };
    if x < 0.0 {
        PI - a
    } else {
        a
    }
}

/// a·b + c rounded once to f32, as `f32::mul_add`, which on the baseline x86-64 target
/// (no FMA instruction) is a software routine that took a quarter of the hierarchical
/// solver's time. The product of two f32 is exact in f64 and the sum is rounded to f64 and
/// then to f32: the same as one rounding but where the f64 sum lands exactly halfway
/// between two f32 (about one operation in 2^29).
#[inline]
fn fused_multiply_add(a: f32, b: f32, c: f32) -> f32 {
    (a as f64 * b as f64 + c as f64) as f32
}

/// Sutherland–Hodgman: the part of `polygon` strictly above the plane through `x` with
/// normal `n`, written into `out`; returns its vertex count.
fn clip_above(x: Vec3, n: Vec3, polygon: &[Vec3], out: &mut [Vec3; 8]) -> usize {
    let mut count = 0;
    let m = polygon.len();
    for k in 0..m {
        let (p, q) = (polygon[k], polygon[(k + 1) % m]);
        let (dp, dq) = ((p - x).dot(n), (q - x).dot(n));
        if dp > 0.0 && count < out.len() {
            out[count] = p;
            count += 1;
        }
        if (dp > 0.0) != (dq > 0.0) && dp != dq && count < out.len() {
            let t = dp / (dp - dq);
            // The crossing lies on the plane up to rounding; it must be kept whichever side
            // rounding puts it (testing it against the plane dropped about half of them,
            // cutting a corner off every straddling polygon).
            out[count] = p + (q - p) * t;
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    #[test]
    fn point_under_the_centre_of_a_large_square_sees_nearly_all() {
        let s = 1e3;
        let square = [
            vec3(-s, -s, 1.0),
            vec3(s, -s, 1.0),
            vec3(s, s, 1.0),
            vec3(-s, s, 1.0),
        ];
        let f = point_to_polygon(Vec3::ZERO, vec3(0.0, 0.0, 1.0), &square) as f64;
        // Four corners of the closed form below: 1 − 8.2e-7 at half-side 1000. Measured
        // 1e-7 from it (f32 spacing near 1); the bound is five spacings.
        let x = s as f64 / (1.0 + (s as f64).powi(2)).sqrt();
        let expected = 4.0 * (x * x.atan()) / std::f64::consts::PI;
        assert!((f - expected).abs() < 6e-7, "{f} vs {expected}");
    }

    #[test]
    fn fast_angle_matches_atan2() {
        let mut worst = 0.0f32;
        for i in 0..=2000 {
            let phi = std::f32::consts::PI * i as f32 / 2000.0;
            for r in [1e-6f32, 1.0, 1e6] {
                let (y, x) = (r * phi.sin(), r * phi.cos());
                worst = worst.max((angle_atan2(y.abs(), x) - y.abs().atan2(x)).abs());
            }
        }
        // Measured 2.4e-7 (two f32 spacings near π/2); the bound is four times that.
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn polygon_behind_the_point_contributes_nothing() {
        let square = [
            vec3(0.0, 0.0, -1.0),
            vec3(1.0, 0.0, -1.0),
            vec3(1.0, 1.0, -1.0),
            vec3(0.0, 1.0, -1.0),
        ];
        assert_eq!(
            point_to_polygon(Vec3::ZERO, vec3(0.0, 0.0, 1.0), &square),
            0.0
        );
    }

    /// Point to a coaxial disc-like square: the closed form for a point below the corner of
    /// an a×b rectangle at height c, (1/2π)(X/√(1+X²)·atan(Y/√(1+X²)) + Y/√(1+Y²)·atan(X/√(1+Y²)))
    /// with X = a/c, Y = b/c.
    #[test]
    fn point_below_a_rectangle_corner_matches_the_closed_form() {
        let (a, b, c) = (2.0f64, 0.5f64, 1.0f64);
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        let expected =
            (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / std::f64::consts::TAU;
        let rect = [
            vec3(0.0, 0.0, 1.0),
            vec3(a as f32, 0.0, 1.0),
            vec3(a as f32, b as f32, 1.0),
            vec3(0.0, b as f32, 1.0),
        ];
        let f = point_to_polygon(Vec3::ZERO, vec3(0.0, 0.0, 1.0), &rect) as f64;
        // Measured 9.6e-9; the bound is ten times that.
        assert!((f - expected).abs() < 1e-7, "{f} vs {expected}");
    }

    #[test]
    fn half_of_a_straddling_polygon_is_clipped() {
        // A vertical square centred on the point's tangent plane: only its upper half counts.
        let full = [
            vec3(-1.0, 1.0, -1.0),
            vec3(1.0, 1.0, -1.0),
            vec3(1.0, 1.0, 1.0),
            vec3(-1.0, 1.0, 1.0),
        ];
        let upper = [
            vec3(-1.0, 1.0, 0.0),
            vec3(1.0, 1.0, 0.0),
            vec3(1.0, 1.0, 1.0),
            vec3(-1.0, 1.0, 1.0),
        ];
        let n = vec3(0.0, 0.0, 1.0);
        let (f, g) = (
            point_to_polygon(Vec3::ZERO, n, &full),
            point_to_polygon(Vec3::ZERO, n, &upper),
        );
        // Measured exactly equal; the bound is one f32 spacing near 0.4.
        assert!(f > 0.0 && (f - g).abs() < 3e-8, "{f} vs {g}");
    }

    /// The straddling square above, turned and moved about: the form factor cannot change,
    /// though the clip's crossings now land on the plane only up to rounding. (Tested
    /// against the plane, about half of them were dropped, and a corner of the clipped
    /// polygon with them: the Cornell MGF's block faces summed their form factors 10% short.)
    #[test]
    fn a_straddling_polygon_turned_and_moved_keeps_its_form_factor() {
        let square = [
            vec3(-1.0, 1.0, -1.0),
            vec3(1.0, 1.0, -1.0),
            vec3(1.0, 1.0, 1.0),
            vec3(-1.0, 1.0, 1.0),
        ];
        let n = vec3(0.0, 0.0, 1.0);
        let upright = point_to_polygon(Vec3::ZERO, n, &square) as f64;
        let mut rng = crate::sampling::Rng::new(11, 0, 0);
        let mut worst = 0.0f64;
        for _ in 0..1000 {
            let axis = vec3(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            let turn = glam::Quat::from_axis_angle(axis.normalize(), 6.0 * rng.next_f32());
            let offset = (vec3(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * 20.0;
            let moved = square.map(|p| turn * p + offset);
            let f = point_to_polygon(offset, turn * n, &moved) as f64;
            worst = worst.max((f / upright - 1.0).abs());
        }
        // Measured 1.3e-6 (the moved corners' rounding at 10); the bound is 7.9 times it.
        assert!(worst < 1e-5, "worst relative change {worst}");
    }
}
