//! The exact ray–triangle and ray–quad tests. The built-in BVH and the final surface
//! computation of every hit call these (Embree runs its own watertight test on the same
//! vertices), so a hit's surface is computed by the same arithmetic whichever backend found it.

use super::ray::Ray;
use super::Vec3;

/// The per-ray constants of the watertight ray–triangle test of Woop, Benthin and Wald
/// (JCGT 2013): the ray's dominant axis and the shear that maps its direction to +z.
#[derive(Clone, Copy, Debug, Default)]
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

    /// The permuted axes `[kx, ky, kz]`: z the direction's dominant axis.
    #[inline]
    pub fn axes(&self) -> [usize; 3] {
        [self.kx, self.ky, self.kz]
    }

    /// The shear factors `(sx, sy, sz)`.
    #[inline]
    pub fn factors(&self) -> (f32, f32, f32) {
        (self.sx, self.sy, self.sz)
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
