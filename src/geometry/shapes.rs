//! The exact ray–primitive intersection routines. The built-in BVH, Embree's user geometry
//! (spheres and rings) and the final surface computation of every hit all call these, so both
//! backends run the same arithmetic on the same primitive.

use super::bounds::Bounds3;
use super::ray::Ray;
use super::{vec3, Vec3};

/// The per-ray constants of the watertight ray–triangle test of Woop, Benthin and Wald
/// (JCGT 2013): the ray's dominant axis and the shear that maps its direction to +z.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RayShear {
    #[inline]
    pub fn new(ray: &Ray) -> RayShear {
        let d = ray.direction.to_array();
        let kz = ray.direction.abs().max_position();
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keep the winding: swap when the dominant component is negative.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        RayShear {
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
        }
    }
}

/// Ray–triangle test. Returns `(t, b1, b2)` with the hit at
/// `v0 + b1·(v1 − v0) + b2·(v2 − v0)`, for `t` in `(ray.t_min, t_max)`; both sides hit.
#[inline]
pub fn intersect_triangle(
    ray: &Ray,
    t_max: f32,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
) -> Option<(f32, f32, f32)> {
    intersect_triangle_sheared(ray, &RayShear::new(ray), t_max, v0, v1, v2)
}

/// The watertight test with the ray's shear computed once (the BVH computes it per ray).
/// Edges are closed and an edge shared by two triangles is decided by the same arithmetic in
/// both, with the sign flipped exactly, so no ray passes between two triangles that share
/// an edge; the edge functions fall back to f64 where f32 gives exactly zero.
#[inline(always)]
pub fn intersect_triangle_sheared(
    ray: &Ray,
    shear: &RayShear,
    t_max: f32,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
) -> Option<(f32, f32, f32)> {
    let (kx, ky, kz) = (shear.kx, shear.ky, shear.kz);
    let a = (v0 - ray.origin).to_array();
    let b = (v1 - ray.origin).to_array();
    let c = (v2 - ray.origin).to_array();
    let ax = a[kx] - shear.sx * a[kz];
    let ay = a[ky] - shear.sy * a[kz];
    let bx = b[kx] - shear.sx * b[kz];
    let by = b[ky] - shear.sy * b[kz];
    let cx = c[kx] - shear.sx * c[kz];
    let cy = c[ky] - shear.sy * c[kz];
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t_scaled = u * (shear.sz * a[kz]) + v * (shear.sz * b[kz]) + w * (shear.sz * c[kz]);
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    (t > ray.t_min && t < t_max).then_some((t, v * inv, w * inv))
}

/// A planar quad `v0 v1 v2 v3` (counter-clockwise around its front normal), tested as the two
/// triangles `(v0, v1, v3)` and `(v2, v3, v1)` — the split Embree uses. Returns `(t, u, v)`
/// with `(u, v)` the quad's own parameters: `(0,0)` at v0, `(1,0)` at v1, `(1,1)` at v2,
/// `(0,1)` at v3. One-sidedness is the caller's test (see `faces_ray`). The triangle test is
/// watertight, so no ray slips through the diagonal between the halves.
#[inline]
pub fn intersect_quad(ray: &Ray, t_max: f32, v: &[Vec3; 4]) -> Option<(f32, f32, f32)> {
    intersect_quad_sheared(ray, &RayShear::new(ray), t_max, v)
}

/// `intersect_quad` with the ray's shear computed once.
#[inline(always)]
pub fn intersect_quad_sheared(
    ray: &Ray,
    shear: &RayShear,
    t_max: f32,
    v: &[Vec3; 4],
) -> Option<(f32, f32, f32)> {
    if let Some(first) = intersect_triangle_sheared(ray, shear, t_max, v[0], v[1], v[3]) {
        return Some(first);
    }
    intersect_triangle_sheared(ray, shear, t_max, v[2], v[3], v[1])
        .map(|(t, a, b)| (t, 1.0 - a, 1.0 - b))
}

/// The front normal of a planar quad (unnormalised): cross product of its diagonals.
#[inline]
pub fn quad_normal(v: &[Vec3; 4]) -> Vec3 {
    (v[2] - v[0]).cross(v[3] - v[1])
}

/// Whether a one-sided surface with front normal `n` can be hit by a ray going along `dir`.
/// Embree's quad filter in `sys/shim.c` makes the same test with the same arithmetic.
#[inline]
pub fn faces_ray(n: Vec3, dir: Vec3) -> bool {
    n.x * dir.x + n.y * dir.y + n.z * dir.z < 0.0
}

/// An analytic sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereShape {
    pub centre: Vec3,
    pub radius: f32,
}

impl SphereShape {
    pub fn bounds(&self) -> Bounds3 {
        let r = Vec3::splat(self.radius);
        Bounds3 {
            min: self.centre - r,
            max: self.centre + r,
        }
    }

    /// The nearest root in `(ray.t_min, t_max)`, computed in the numerically stable form of
    /// Haines et al. (Ray Tracing Gems, ch. 7): the discriminant from the distance of the
    /// centre to the ray line, and the smaller root as `c / q`, so a small sphere far from the
    /// ray origin loses no digits to cancellation.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let d = ray.direction;
        let a = d.dot(d);
        if a == 0.0 || !a.is_finite() {
            return None;
        }
        let f = ray.origin - self.centre;
        let b = -f.dot(d);
        // The centre's offset from the ray's line, without squaring a long distance.
        let l = f + d * (b / a);
        let r2 = self.radius * self.radius;
        let disc = r2 - l.dot(l);
        if disc < 0.0 {
            return None;
        }
        let c = f.dot(f) - r2;
        let q = b + b.signum() * (a * disc).sqrt();
        let (mut t0, mut t1) = (c / q, q / a);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        nearest_in_range(&[t0, t1], ray.t_min, t_max)
    }

    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        (p - self.centre).normalize_or_zero()
    }

    /// Spherical parameters in [0,1]²: longitude around +y, latitude from the bottom.
    pub fn uv_at(&self, p: Vec3) -> (f32, f32) {
        let n = self.normal_at(p);
        let u = (n.z.atan2(n.x) / std::f32::consts::TAU).rem_euclid(1.0);
        let v = n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        (u, 1.0 - v)
    }
}

/// Which surface of a ring a hit lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RingPart {
    Outer,
    Inner,
    Bottom,
    Top,
}

impl RingPart {
    pub const ALL: [RingPart; 4] = [
        RingPart::Outer,
        RingPart::Inner,
        RingPart::Bottom,
        RingPart::Top,
    ];
}

/// A cylindrical ring: the solid between two coaxial cylinders of radius `r_in` and `r_out`,
/// axis along +y through `base`, from `base.y` to `base.y + height`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RingShape {
    pub base: Vec3,
    pub height: f32,
    pub r_in: f32,
    pub r_out: f32,
}

impl RingShape {
    pub fn bounds(&self) -> Bounds3 {
        Bounds3 {
            min: vec3(
                self.base.x - self.r_out,
                self.base.y,
                self.base.z - self.r_out,
            ),
            max: vec3(
                self.base.x + self.r_out,
                self.base.y + self.height,
                self.base.z + self.r_out,
            ),
        }
    }

    /// The nearest hit in `(ray.t_min, t_max)` over the four surfaces: outer wall, inner wall,
    /// bottom and top annulus.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, RingPart)> {
        let mut best: Option<(f32, RingPart)> = None;
        let mut limit = t_max;
        for (radius, part) in [(self.r_out, RingPart::Outer), (self.r_in, RingPart::Inner)] {
            if let Some(t) = self.intersect_wall(ray, limit, radius) {
                best = Some((t, part));
                limit = t;
            }
        }
        for (y, part) in [
            (self.base.y, RingPart::Bottom),
            (self.base.y + self.height, RingPart::Top),
        ] {
            if let Some(t) = self.intersect_cap(ray, limit, y) {
                best = Some((t, part));
                limit = t;
            }
        }
        best
    }

    /// A cylinder wall of the given radius between the ring's two heights: the same stable
    /// quadratic as the sphere's, in the xz-plane.
    #[inline]
    fn intersect_wall(&self, ray: &Ray, t_max: f32, radius: f32) -> Option<f32> {
        let (dx, dz) = (ray.direction.x, ray.direction.z);
        let len = (dx * dx + dz * dz).sqrt();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let (ux, uz) = (dx / len, dz / len);
        let (fx, fz) = (ray.origin.x - self.base.x, ray.origin.z - self.base.z);
        let b = -(fx * ux + fz * uz);
        let (lx, lz) = (fx + ux * b, fz + uz * b);
        let r2 = radius * radius;
        let disc = r2 - (lx * lx + lz * lz);
        if disc < 0.0 {
            return None;
        }
        let c = fx * fx + fz * fz - r2;
        let q = b + b.signum() * disc.sqrt();
        let (mut t0, mut t1) = (c / q, q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let (y0, y1) = (self.base.y, self.base.y + self.height);
        let within = |t: f32| {
            let y = ray.origin.y + ray.direction.y * t;
            y >= y0 && y <= y1
        };
        [t0 / len, t1 / len]
            .into_iter()
            .find(|&t| t > ray.t_min && t < t_max && within(t))
    }

    #[inline]
    fn intersect_cap(&self, ray: &Ray, t_max: f32, y: f32) -> Option<f32> {
        if ray.direction.y == 0.0 {
            return None;
        }
        let t = (y - ray.origin.y) / ray.direction.y;
        if !(t > ray.t_min && t < t_max) {
            return None;
        }
        let px = ray.origin.x + ray.direction.x * t - self.base.x;
        let pz = ray.origin.z + ray.direction.z * t - self.base.z;
        let rho2 = px * px + pz * pz;
        (rho2 >= self.r_in * self.r_in && rho2 <= self.r_out * self.r_out).then_some(t)
    }

    /// Outward normal of the solid on the given part.
    pub fn normal_at(&self, p: Vec3, part: RingPart) -> Vec3 {
        let radial = vec3(p.x - self.base.x, 0.0, p.z - self.base.z).normalize_or_zero();
        match part {
            RingPart::Outer => radial,
            RingPart::Inner => -radial,
            RingPart::Bottom => vec3(0.0, -1.0, 0.0),
            RingPart::Top => vec3(0.0, 1.0, 0.0),
        }
    }

    /// Parameters in [0,1]²: angle around the axis, and height on the walls or radial
    /// position on the caps.
    pub fn uv_at(&self, p: Vec3, part: RingPart) -> (f32, f32) {
        let (x, z) = (p.x - self.base.x, p.z - self.base.z);
        let u = (z.atan2(x) / std::f32::consts::TAU).rem_euclid(1.0);
        let v = match part {
            RingPart::Outer | RingPart::Inner => (p.y - self.base.y) / self.height,
            RingPart::Bottom | RingPart::Top => {
                ((x * x + z * z).sqrt() - self.r_in) / (self.r_out - self.r_in)
            }
        };
        (u, v.clamp(0.0, 1.0))
    }
}

#[inline]
fn nearest_in_range(roots: &[f32; 2], t_min: f32, t_max: f32) -> Option<f32> {
    roots.iter().copied().find(|&t| t > t_min && t < t_max)
}
