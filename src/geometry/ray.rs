//! Rays and the robust spawning of secondary rays from surfaces.

use super::Vec3;

/// A ray `origin + t·direction` for `t` in `(t_min, t_max)`. The layout is the shim's `TxRay`,
/// so batches of rays go to Embree without copying.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub t_min: f32,
    pub direction: Vec3,
    pub t_max: f32,
}

impl Ray {
    /// A ray over `(0, ∞)`.
    pub fn new(origin: Vec3, direction: Vec3) -> Ray {
        Ray {
            origin,
            t_min: 0.0,
            direction,
            t_max: f32::INFINITY,
        }
    }

    pub fn with_range(origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> Ray {
        Ray {
            origin,
            t_min,
            direction,
            t_max,
        }
    }

    /// Whether an Accel can follow the ray: origin and direction finite, and its range not
    /// NaN (t_max may be ∞). Scene values in range make every ray so; the Accels check it
    /// anyway (an assertion in debug builds, a miss in release), since a ray of inf or NaN
    /// made Embree abort the process and the BVH's walk take the empty child slots that such
    /// a ray's slab test does not cull, back to the root, without end.
    #[inline(always)]
    pub fn is_traceable(&self) -> bool {
        self.origin.is_finite()
            && self.direction.is_finite()
            && !self.t_min.is_nan()
            && !self.t_max.is_nan()
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.direction * t
    }
}

/// Moves a point off a surface so that a ray spawned from it does not hit that surface again.
/// First by the point's own error bound `error` (absolute, per coordinate: the computed point
/// lies within that distance of the true surface, as pbrt tracks it), pushed along the normal
/// as far as the error box reaches; then by the offset of Wächter and Binder (Ray Tracing
/// Gems, ch. 6): a fixed number of floating-point steps (ULPs) along the normal, scaled with
/// the coordinates — near the origin as a float step of the same relative size, not their
/// fixed absolute one, so that tiny scenes work too. `n` must be a unit normal pointing to the
/// side the new ray leaves into.
#[inline(always)]
pub fn offset_ray_origin(p: Vec3, n: Vec3, error: f32) -> Vec3 {
    let reach = error * (n.x.abs() + n.y.abs() + n.z.abs());
    ulp_offset(p + n * reach, n)
}

#[inline(always)]
fn ulp_offset(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOOR: f32 = 1e-30;
    // Wächter & Binder use 256 ULPs; here the error bound has already moved the point off
    // the surface, so a few ULPs for the rounding of that move suffice. 256 ULPs are 0.016
    // units at coordinates of 1000: near a contact point (a sphere resting on a floor) that
    // put shadow rays inside the sphere, and scenes moved by 1e3 lost relMSE 1.8e-3.
    const INT_SCALE: f32 = 4.0;
    // Both steps are computed and one is chosen, without a branch, so that the path tracer's
    // vertex kernel runs this lane by lane in SIMD.
    let step = |p: f32, n: f32| -> f32 {
        // Wächter & Binder add a fixed 1/65536 near the origin, which in a scene a
        // ten-thousandth of a unit across is most of the way through it (secondary rays
        // started beyond the walls). INT_SCALE ulps of |p| instead, as the integer step moves
        // points farther out, floored where |p| is zero.
        let near = p + n * (INT_SCALE * f32::EPSILON * p.abs().max(FLOOR));
        // trunc(INT_SCALE·n) as an integer (n is a unit normal), without a saturating
        // conversion, which does not vectorize: 1.5·2^23 added to an integer below 2^22 in
        // magnitude leaves it in the low bits of the sum. A NaN normal moves nothing, as the
        // conversion's 0 did.
        const MAGIC: f32 = 12_582_912.0;
        let of_i = ((INT_SCALE * n).trunc() + MAGIC).to_bits() as i32 - MAGIC.to_bits() as i32;
        let of_i = if n.is_nan() { 0 } else { of_i };
        let bits = p.to_bits() as i32;
        let moved = if p < 0.0 {
            bits.wrapping_sub(of_i)
        } else {
            bits.wrapping_add(of_i)
        };
        if p.abs() < ORIGIN {
            near
        } else {
            f32::from_bits(moved as u32)
        }
    };
    Vec3 {
        x: step(p.x, n.x),
        y: step(p.y, n.y),
        z: step(p.z, n.z),
    }
}

/// A ray leaving surface point `p` (unit geometric normal `ng`, point error `error`) in
/// direction `dir`.
#[inline(always)]
pub fn spawn_ray(p: Vec3, ng: Vec3, error: f32, dir: Vec3) -> Ray {
    let n = if ng.dot(dir) < 0.0 { -ng } else { ng };
    Ray::new(offset_ray_origin(p, n, error), dir)
}

/// The ray from `origin` (already off its surface) that stops just short of `target`: 1e-4
/// of the way short, and at least `point_error` of the target's coordinates short. A point
/// 1e-4 from a light (a wall's edge where it meets the Cornell box's light) sent rays that
/// stopped 1e-8 short of the light, below f32's rounding of the light's plane (6e-8 near 1),
/// and one Accel found the light itself in the way where the other did not (7 of 3·10⁶
/// path-tracing shadow rays; the path-traced images differed in 9 pixels of 65,536).
#[inline(always)]
pub fn shadow_ray(origin: Vec3, target: Vec3) -> Ray {
    let d = target - origin;
    let error = point_error(target.abs().max_element());
    let length2 = d.length_squared();
    // Only short rays need the square root: 1e-4 of the way covers the error otherwise.
    let gap = if error * error > 1e-8 * length2 {
        (error / length2.sqrt()).min(0.5)
    } else {
        1e-4
    };
    Ray::with_range(origin, d, 0.0, 1.0 - gap)
}

/// A bound on the rounding error of a point computed from coordinates of magnitude up to
/// `magnitude` in a handful of floating-point operations.
#[inline(always)]
pub fn point_error(magnitude: f32) -> f32 {
    8.0 * f32::EPSILON * magnitude
}
