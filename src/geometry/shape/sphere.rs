//! The analytic sphere: one part, parameterized by longitude u around +y (from +x towards
//! +z) and latitude v from the bottom pole.

use super::{Shape, Tessellation};
use crate::geometry::{vec3, Bounds3, Ray, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereShape {
    pub centre: Vec3,
    pub radius: f32,
}

impl SphereShape {
    /// Where the line `origin + t·direction` meets the sphere, the smaller t first, and
    /// whether it does (a direction of non-zero finite length, a discriminant not negative).
    /// Computed in the numerically stable form of Haines et al. (Ray Tracing Gems, ch. 7):
    /// the discriminant from the distance of the centre to the line, and the smaller root as
    /// `c / q`, so a small sphere far from the origin loses no digits to cancellation. Without
    /// branches, so that the BVH's lanes (`accel::lanes`) run it for sixteen rays at once.
    #[inline(always)]
    pub fn roots(&self, origin: Vec3, d: Vec3) -> (f32, f32, bool) {
        let a = d.dot(d);
        let f = origin - self.centre;
        let b = -f.dot(d);
        // The centre's offset from the ray's line, without squaring a long distance.
        let l = f + d * (b / a);
        let r2 = self.radius * self.radius;
        let disc = r2 - l.dot(l);
        let c = f.dot(f) - r2;
        let q = b + b.signum() * (a * disc).sqrt();
        let (t0, t1) = (c / q, q / a);
        let (t0, t1) = if t0 > t1 { (t1, t0) } else { (t0, t1) };
        (t0, t1, (a != 0.0) & a.is_finite() & (disc >= 0.0))
    }
}

impl Shape for SphereShape {
    fn name(&self) -> &'static str {
        "sphere"
    }

    fn part_count(&self) -> u32 {
        1
    }

    fn bounds(&self) -> Bounds3 {
        let r = Vec3::splat(self.radius);
        Bounds3 {
            min: self.centre - r,
            max: self.centre + r,
        }
    }

    /// The nearer root within the ray's range, of `roots`.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        let (t0, t1, real) = self.roots(ray.origin, ray.direction);
        if !real {
            return None;
        }
        [t0, t1]
            .into_iter()
            .find(|&t| t > ray.t_min && t < t_max)
            .map(|t| (t, 0))
    }

    fn nearest_part(&self, _p: Vec3) -> u32 {
        0
    }

    fn project(&self, p: Vec3, part: u32) -> (Vec3, Vec3) {
        let n = self.normal_at(p, part);
        (self.centre + n * self.radius, n)
    }

    fn normal_at(&self, p: Vec3, _part: u32) -> Vec3 {
        (p - self.centre).normalize_or_zero()
    }

    fn uv_at(&self, p: Vec3, part: u32) -> (f32, f32) {
        let n = self.normal_at(p, part);
        let u = (n.z.atan2(n.x) / std::f32::consts::TAU).rem_euclid(1.0);
        let v = n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        (u, 1.0 - v)
    }

    fn point_at(&self, _part: u32, u: f32, v: f32) -> Vec3 {
        let (phi, theta) = (std::f32::consts::TAU * u, std::f32::consts::PI * (1.0 - v));
        // The poles exactly, so the faces around them share one vertex.
        let (sin_t, cos_t) = if v <= 0.0 {
            (0.0, -1.0)
        } else if v >= 1.0 {
            (0.0, 1.0)
        } else {
            theta.sin_cos()
        };
        let dir = vec3(sin_t * phi.cos(), cos_t, sin_t * phi.sin());
        self.centre + dir * self.radius
    }

    fn magnitude(&self) -> f32 {
        self.centre.abs().max_element() + self.radius
    }

    fn area(&self) -> f32 {
        4.0 * std::f32::consts::PI * self.radius * self.radius
    }

    fn sample(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        let z = 1.0 - 2.0 * u;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * v;
        let n = vec3(r * phi.cos(), z, r * phi.sin());
        (self.centre + n * self.radius, n)
    }

    /// The point of the sphere nearest to `towards`.
    fn point_towards(&self, towards: Vec3) -> (Vec3, Vec3) {
        let n = (towards - self.centre).normalize_or_zero();
        (self.centre + n * self.radius, n)
    }

    fn grid(&self, tessellation: &Tessellation) -> (u32, u32) {
        let (h, v) = tessellation.sphere;
        (h.max(3), v.max(2))
    }

    fn scaled(&self, scale: f32, offset: Vec3) -> Self {
        SphereShape {
            centre: self.centre * scale + offset,
            radius: self.radius * scale,
        }
    }
}
