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

    /// The point `p` relative to `origin` in the sheared frame: (x, y) across the ray, and
    /// z along it scaled by `sz`.
    #[inline(always)]
    pub fn project(&self, origin: Vec3, p: Vec3) -> [f32; 3] {
        let a = (p - origin).to_array();
        [
            a[self.kx] - self.sx * a[self.kz],
            a[self.ky] - self.sy * a[self.kz],
            self.sz * a[self.kz],
        ]
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
    let [a, b, c] = [v0, v1, v2].map(|p| shear.project(ray.origin, p));
    sheared_triangle_hit(ray, t_max, [a, b, c], c[0] * b[1] - c[1] * b[0])
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
///
/// The answer, bit for bit, of `intersect_triangle_sheared` on `(v0, v1, v3)` and then, if
/// that misses, on `(v2, v3, v1)` with its parameters turned to the quad's. The second half
/// shares two vertices and the diagonal with the first: their sheared coordinates are taken
/// over, and its diagonal's edge function is the first's negated, which is exact (the two are
/// the same two products subtracted the other way round; where either is zero the f64 test
/// recomputes all three anyway).
#[inline(always)]
pub fn intersect_quad_sheared(
    ray: &Ray,
    shear: &RayShear,
    t_max: f32,
    v: &[Vec3; 4],
) -> Option<(f32, f32, f32)> {
    let project = |p: Vec3| shear.project(ray.origin, p);
    let (p0, p1, p3) = (project(v[0]), project(v[1]), project(v[3]));
    let diagonal = p3[0] * p1[1] - p3[1] * p1[0];
    if let Some(first) = sheared_triangle_hit(ray, t_max, [p0, p1, p3], diagonal) {
        return Some(first);
    }
    sheared_triangle_hit(ray, t_max, [project(v[2]), p3, p1], -diagonal)
        .map(|(t, a, b)| (t, 1.0 - a, 1.0 - b))
}

/// The watertight test of the triangle `[a, b, c]` of sheared vertices (`RayShear::project`),
/// given its edge function `u` of the edge b–c (which a quad's second half takes over from
/// its first).
#[inline(always)]
fn sheared_triangle_hit(
    ray: &Ray,
    t_max: f32,
    [a, b, c]: [[f32; 3]; 3],
    mut u: f32,
) -> Option<(f32, f32, f32)> {
    let (mut v, mut w) = sheared_edge_functions([a, b, c]);
    if edge_function_zero(u, v, w) {
        let (ax, ay, bx, by, cx, cy) = (
            a[0] as f64,
            a[1] as f64,
            b[0] as f64,
            b[1] as f64,
            c[0] as f64,
            c[1] as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if edge_functions_disagree(u, v, w) {
        return None;
    }
    let (t, b1, b2, solvable) = sheared_triangle_solve([a, b, c], (u, v, w));
    (solvable && t > ray.t_min && t < t_max).then_some((t, b1, b2))
}

// The pieces of the watertight test below join their conditions with `&` and `|`: the BVH's
// lanes (`accel::lanes`) run them for sixteen rays at once, where branches would keep the
// compiler from vectorising the loop.

/// The edge functions of the edges c–a and a–b of the triangle `[a, b, c]` of sheared
/// vertices (`RayShear::project`), in f32.
#[inline(always)]
pub(crate) fn sheared_edge_functions([a, b, c]: [[f32; 3]; 3]) -> (f32, f32) {
    (a[0] * c[1] - a[1] * c[0], b[0] * a[1] - b[1] * a[0])
}

/// Whether an edge function is exactly zero: the case the watertight test decides again in
/// f64.
#[inline(always)]
pub(crate) fn edge_function_zero(u: f32, v: f32, w: f32) -> bool {
    (u == 0.0) | (v == 0.0) | (w == 0.0)
}

/// Whether the edge functions take both signs: the ray passes outside the triangle.
#[inline(always)]
pub(crate) fn edge_functions_disagree(u: f32, v: f32, w: f32) -> bool {
    ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0))
}

/// The hit's t and barycentrics `(b1, b2)` from the edge functions `(u, v, w)` of the
/// triangle `[a, b, c]` of sheared vertices, and whether their sum (the determinant) is
/// finite and not zero, without which there is no hit.
#[inline(always)]
pub(crate) fn sheared_triangle_solve(
    [a, b, c]: [[f32; 3]; 3],
    (u, v, w): (f32, f32, f32),
) -> (f32, f32, f32, bool) {
    let det = u + v + w;
    let t_scaled = u * a[2] + v * b[2] + w * c[2];
    let inv = 1.0 / det;
    (
        t_scaled * inv,
        v * inv,
        w * inv,
        (det != 0.0) & det.is_finite(),
    )
}

/// The front normal of a planar quad (unnormalised): cross product of its diagonals.
#[inline]
pub fn quad_normal(v: &[Vec3; 4]) -> Vec3 {
    (v[2] - v[0]).cross(v[3] - v[1])
}

/// The front normal of triangle `v` (unnormalised): the side its vertices run
/// counter-clockwise round.
#[inline]
pub fn triangle_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0])
}

/// How far off its plane quad `v` (of unit normal `unit` and diagonal `size`) is, when it is
/// too far to count as planar: None when no vertex lies farther off the plane through its
/// centre than a thousandth of its size (the course dialect's tolerance) or than rounding its
/// coordinates to f32 can put it, whichever is larger. Without the second, a small quad far
/// from the origin is planar in its file's numbers but not in f32's: a hospital arrayed 300 m
/// along an axis (MGF's `xf -a 16 -t 20 0 0`) lost 70% of its quads in its last copies, each
/// split into two triangles.
pub fn quad_off_plane(v: &[Vec3; 4], unit: Vec3, size: f32) -> Option<f32> {
    let centre = (v[0] + v[1] + v[2] + v[3]) * 0.25;
    let reach = v
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0f32, f32::max);
    let tolerance = (1e-3 * size).max(4.0 * f32::EPSILON * reach);
    let off_plane = v
        .iter()
        .map(|&p| (p - centre).dot(unit).abs())
        .fold(0.0f32, f32::max);
    (off_plane > tolerance).then_some(off_plane)
}

/// Whether a one-sided surface with front normal `n` can be hit by a ray going along `dir`.
/// Embree's quad filter in `sys/shim.c` makes the same test with the same arithmetic.
#[inline]
pub fn faces_ray(n: Vec3, dir: Vec3) -> bool {
    n.x * dir.x + n.y * dir.y + n.z * dir.z < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The quad test as two calls of the triangle test: what `intersect_quad_sheared` must
    /// answer bit for bit.
    fn two_triangles(ray: &Ray, t_max: f32, v: &[Vec3; 4]) -> Option<(f32, f32, f32)> {
        let shear = RayShear::new(ray);
        intersect_triangle_sheared(ray, &shear, t_max, v[0], v[1], v[3]).or_else(|| {
            intersect_triangle_sheared(ray, &shear, t_max, v[2], v[3], v[1])
                .map(|(t, a, b)| (t, 1.0 - a, 1.0 - b))
        })
    }

    fn bits(hit: Option<(f32, f32, f32)>) -> Option<[u32; 3]> {
        hit.map(|(t, u, v)| [t.to_bits(), u.to_bits(), v.to_bits()])
    }

    /// Rays at random points of random planar quads, at points of their diagonal, edges and
    /// corners (where the edge functions are zero or nearly), and past them: two million
    /// rays, every answer the same bits as the two triangle tests'.
    #[test]
    fn quad_test_is_the_two_triangle_tests_bit_for_bit() {
        let mut rng = Rng::new(7, 0, 0);
        let mut r = || rng.next_f32() * 2.0 - 1.0;
        let mut hits = 0;
        for case in 0..2_000_000u32 {
            let origin = Vec3::new(r(), r(), r()) * 10.0;
            let corner = Vec3::new(r(), r(), r()) * 3.0;
            let (e1, e2) = (Vec3::new(r(), r(), r()), Vec3::new(r(), r(), r()));
            // A parallelogram or a trapezoid, planar either way.
            let stretch = 1.0 + 0.5 * r();
            let v = [corner, corner + e1, corner + e1 * stretch + e2, corner + e2];
            let target = match case % 5 {
                0 => v[1] + (v[3] - v[1]) * rng_unit(r()),
                1 => v[0] + (v[1] - v[0]) * rng_unit(r()),
                2 => v[(case as usize / 5) % 4],
                3 => v[0] + e1 * rng_unit(r()) + e2 * rng_unit(r()),
                _ => v[0] + e1 * (2.0 * r()) + e2 * (2.0 * r()),
            };
            let ray = Ray::new(origin, target - origin);
            let t_max = if case % 7 == 0 { 0.999 } else { f32::INFINITY };
            let want = two_triangles(&ray, t_max, &v);
            let got = intersect_quad_sheared(&ray, &RayShear::new(&ray), t_max, &v);
            assert_eq!(bits(got), bits(want), "case {case}: {ray:?} {v:?}");
            hits += want.is_some() as u32;
        }
        assert!(hits > 500_000, "{hits} hits");
    }

    fn rng_unit(x: f32) -> f32 {
        0.5 * (x + 1.0)
    }
}
