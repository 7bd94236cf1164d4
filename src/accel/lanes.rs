//! Sixteen rays against one primitive at once, a ray a lane: the built-in BVH's closest hits
//! in a tree so small that every ray is best tested against all its primitives
//! (`Bvh::intersect_batch`). Each lane's arithmetic is the single ray's, written out without
//! branches so that the compiler runs the sixteen lanes in the processor's widest registers
//! (the batched queries' `pulp` dispatch): a quad is `intersect_quad_sheared`'s two watertight
//! triangle tests, a sphere `SphereShape::roots`, the stable quadratic of its single test, each giving the bits
//! the single ray gets. A lane whose quad test hangs on an edge function of exactly zero
//! (where the single test recomputes in f64) is flagged, for the caller to test alone.

use crate::geometry::{
    edge_function_zero, edge_functions_disagree, faces_ray, sheared_edge_functions,
    sheared_triangle_solve, Ray, SphereShape, Vec3,
};

/// Rays tested at once.
pub(super) const LANES: usize = 16;

type Lanes = [f32; LANES];

/// Up to `LANES` rays, lane by lane, with their shears (`RayShear`); lanes beyond the rays
/// repeat the last one.
pub(super) struct RayLanes {
    origin: [Lanes; 3],
    direction: [Lanes; 3],
    t_min: Lanes,
    /// The shear's axes (x, y, z of the sheared frame, as 0, 1, 2) and factors.
    axes: [[u32; LANES]; 3],
    factors: [Lanes; 3],
    /// The origin's coordinates along the shear's axes.
    origin_sheared: [Lanes; 3],
}

impl RayLanes {
    /// The rays' shears are `RayShear::new`'s, made in the lanes.
    #[inline(always)]
    pub fn new(rays: &[Ray]) -> RayLanes {
        let mut r = RayLanes {
            origin: [[0.0; LANES]; 3],
            direction: [[0.0; LANES]; 3],
            t_min: [0.0; LANES],
            axes: [[0; LANES]; 3],
            factors: [[0.0; LANES]; 3],
            origin_sheared: [[0.0; LANES]; 3],
        };
        for k in 0..LANES {
            let ray = &rays[k.min(rays.len() - 1)];
            let (o, d) = (ray.origin.to_array(), ray.direction.to_array());
            for a in 0..3 {
                r.origin[a][k] = o[a];
                r.direction[a][k] = d[a];
            }
            r.t_min[k] = ray.t_min;
        }
        for k in 0..LANES {
            let (o, d) = (r.origin(k), r.direction(k));
            // `Vec3::max_position` of the direction's magnitudes.
            let m = d.abs();
            let (largest, kz) = if m.y > m.x { (m.y, 1) } else { (m.x, 0) };
            let kz = if m.z > largest { 2 } else { kz };
            let (kx, ky) = (next_axis(kz), next_axis(next_axis(kz)));
            let dz = pick(d, kz);
            // Keep the winding: swap when the dominant component is negative.
            let (kx, ky) = if dz < 0.0 { (ky, kx) } else { (kx, ky) };
            for (a, axis) in [kx, ky, kz].into_iter().enumerate() {
                r.axes[a][k] = axis;
                r.origin_sheared[a][k] = pick(o, axis);
            }
            r.factors[0][k] = pick(d, kx) / dz;
            r.factors[1][k] = pick(d, ky) / dz;
            r.factors[2][k] = 1.0 / dz;
        }
        r
    }

    /// `p` relative to lane `k`'s origin in its sheared frame: `RayShear::project`'s numbers
    /// (a coordinate of `p − origin` is that coordinate of `p` less the origin's).
    #[inline(always)]
    fn project(&self, k: usize, p: Vec3) -> [f32; 3] {
        let along = |a: usize| pick(p, self.axes[a][k]) - self.origin_sheared[a][k];
        let (x, y, z) = (along(0), along(1), along(2));
        [
            x - self.factors[0][k] * z,
            y - self.factors[1][k] * z,
            self.factors[2][k] * z,
        ]
    }

    #[inline(always)]
    fn direction(&self, k: usize) -> Vec3 {
        Vec3::new(
            self.direction[0][k],
            self.direction[1][k],
            self.direction[2][k],
        )
    }

    #[inline(always)]
    fn origin(&self, k: usize) -> Vec3 {
        Vec3::new(self.origin[0][k], self.origin[1][k], self.origin[2][k])
    }
}

/// The axis after `axis` (0, 1, 2), round from z to x.
#[inline(always)]
fn next_axis(axis: u32) -> u32 {
    if axis == 2 {
        0
    } else {
        axis + 1
    }
}

/// Coordinate `axis` (0, 1, 2) of `p`, chosen without indexing (a select in each lane).
#[inline(always)]
fn pick(p: Vec3, axis: u32) -> f32 {
    if axis == 0 {
        p.x
    } else if axis == 1 {
        p.y
    } else {
        p.z
    }
}

/// Where a lane's hit counts: beyond `t_min` and before `t_max`, or at `t_max` itself where
/// `to_max` (a closest hit so far at `t_max`, which an equally near one may still beat by the
/// tie rule: what the single test decides with `t_max.next_up()` as its bound, for t below
/// `next_up` is t at most `t_max`).
#[derive(Clone, Copy)]
struct Range {
    t_min: f32,
    t_max: f32,
    to_max: bool,
}

impl Range {
    #[inline(always)]
    fn holds(self, t: f32) -> bool {
        (t > self.t_min) & ((t < self.t_max) | (self.to_max & (t == self.t_max)))
    }
}

/// How far each lane's hits count, for `quad` and `sphere`: up to `t_max`, and at it where
/// `to_max` (see `Range`).
pub(super) struct Limits<'a> {
    pub t_max: &'a Lanes,
    pub to_max: &'a [bool; LANES],
}

impl Limits<'_> {
    #[inline(always)]
    fn range(&self, rays: &RayLanes, k: usize) -> Range {
        Range {
            t_min: rays.t_min[k],
            t_max: self.t_max[k],
            to_max: self.to_max[k],
        }
    }
}

/// The answer of one primitive's test in every lane: where `hit` is set, the hit's t and
/// parameters; where `unsure` is set, the lane must be tested alone.
pub(super) struct LaneHits {
    pub t: Lanes,
    pub u: Lanes,
    pub v: Lanes,
    pub hit: [bool; LANES],
    pub unsure: [bool; LANES],
}

impl Default for LaneHits {
    fn default() -> LaneHits {
        LaneHits {
            t: [0.0; LANES],
            u: [0.0; LANES],
            v: [0.0; LANES],
            hit: [false; LANES],
            unsure: [false; LANES],
        }
    }
}

// The lanes' conditions join with `&` and `|`, not `&&` and `||`: the short-circuit forms are
// branches, which kept the compiler from vectorising the loops for AVX2 (the Cornell box's path
// tracer 2.5x slower there than in AVX-512, whose mask registers took them).

/// One lane's watertight triangle test in f32: `polygon::sheared_triangle_hit` before its
/// f64 fallback, from the same pieces. Returns (t, b1, b2, hit, zero): `zero` where an edge
/// function is exactly zero, the case the single test recomputes in f64.
#[inline(always)]
fn triangle_lane(range: Range, triangle: [[f32; 3]; 3], u: f32) -> (f32, f32, f32, bool, bool) {
    let (v, w) = sheared_edge_functions(triangle);
    let (t, b1, b2, solvable) = sheared_triangle_solve(triangle, (u, v, w));
    let hit = !edge_functions_disagree(u, v, w) & solvable & range.holds(t);
    (t, b1, b2, hit, edge_function_zero(u, v, w))
}

/// The quad `v` against every lane, each within its own `limits`: `intersect_quad_sheared`'s
/// answer, lane by lane, where the quad faces the ray or `cull` is off (`faces_ray` on
/// `normal`).
#[inline(always)]
pub(super) fn quad(
    rays: &RayLanes,
    (v, normal, cull): (&[Vec3; 4], Vec3, bool),
    limits: &Limits,
    out: &mut LaneHits,
) {
    for k in 0..LANES {
        let (p0, p1, p3) = (
            rays.project(k, v[0]),
            rays.project(k, v[1]),
            rays.project(k, v[3]),
        );
        let p2 = rays.project(k, v[2]);
        let diagonal = p3[0] * p1[1] - p3[1] * p1[0];
        let range = limits.range(rays, k);
        let first = triangle_lane(range, [p0, p1, p3], diagonal);
        let second = triangle_lane(range, [p2, p3, p1], -diagonal);
        let meets = !cull | faces_ray(normal, rays.direction(k));
        let (t, u, w) = if first.3 {
            (first.0, first.1, first.2)
        } else {
            (second.0, 1.0 - second.1, 1.0 - second.2)
        };
        out.t[k] = t;
        out.u[k] = u;
        out.v[k] = w;
        out.hit[k] = meets & (first.3 | second.3);
        out.unsure[k] = meets & (first.4 | (!first.3 & second.4));
    }
}

/// The sphere `s` against every lane, each within its own `limits`: `SphereShape::intersect`'s
/// answer, lane by lane (its parameters are zero, as the single test reports them).
#[inline(always)]
pub(super) fn sphere(rays: &RayLanes, s: &SphereShape, limits: &Limits, out: &mut LaneHits) {
    for k in 0..LANES {
        let (t0, t1, real) = s.roots(rays.origin(k), rays.direction(k));
        let within = |t: f32| limits.range(rays, k).holds(t);
        out.t[k] = if within(t0) { t0 } else { t1 };
        out.u[k] = 0.0;
        out.v[k] = 0.0;
        out.hit[k] = real & (within(t0) | within(t1));
        out.unsure[k] = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{faces_ray, intersect_quad_sheared, RayShear, Shape};
    use crate::sampling::Rng;

    fn point(rng: &mut Rng) -> Vec3 {
        Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE
    }

    /// Sixteen rays from near one point (so that some share their axes and some not) at a
    /// target each: a vertex of the square `v` (on an axis-aligned square, an edge function
    /// of exactly zero), the midpoint of an edge, a point inside or around it, or a point of
    /// the sphere; and each lane's limits: unbounded, cutting hits off, or with the hit so
    /// far at a distance a hit may equal.
    fn rays_at(rng: &mut Rng, v: &[Vec3; 4], case: usize) -> (Vec<Ray>, Lanes, [bool; LANES]) {
        let eye = point(rng) * 3.0;
        let mut t_max = [0.0; LANES];
        let mut to_max = [false; LANES];
        let rays = (0..LANES)
            .map(|k| {
                let target = match (case + k) % 5 {
                    0 => v[(case + k) % 4],
                    1 => (v[k % 4] + v[(k + 1) % 4]) * 0.5,
                    2 => point(rng),
                    3 => (v[0] + v[2]) * 0.5 + point(rng) * 0.01,
                    _ => point(rng) * 0.3,
                };
                let origin = eye + point(rng) * 0.05;
                let ray = Ray::new(origin, target - origin);
                t_max[k] = [f32::INFINITY, 1.0, 0.999, 0.5][(case + k) % 4];
                to_max[k] = (case + k).is_multiple_of(3);
                ray
            })
            .collect();
        (rays, t_max, to_max)
    }

    /// The bound the single tests take for a lane's limits: `t_max`, or its next float where
    /// an equal hit still counts.
    fn single_bound(t_max: f32, to_max: bool) -> f32 {
        if to_max {
            t_max.next_up()
        } else {
            t_max
        }
    }

    /// Every lane not handed back as unsure gives `intersect_quad_sheared`'s answer bit for
    /// bit (culled from behind where asked, as `faces_ray` decides), and every sphere lane
    /// `SphereShape::intersect`'s. Rays through the square's vertices are handed back, and
    /// some of them need it: their lanes' f32 answer is not the single test's.
    #[test]
    fn lanes_answer_as_the_single_tests() {
        let mut rng = Rng::new(5, 0, 0);
        let (mut hits, mut quad_hits_seen, mut checked) = (0, 0, 0);
        // Lanes handed back, and those of them whose f32 answer the single test's f64 one
        // overrules.
        let (mut unsure, mut overruled) = (0, 0);
        for case in 0..2000 {
            let size = 0.25 + rng.next_f32();
            let square = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| Vec3::new(x * size, y * size, 0.0));
            let normal = Vec3::Z;
            let sphere = SphereShape {
                centre: point(&mut rng) * 0.5,
                radius: 0.05 + 0.5 * rng.next_f32(),
            };
            let (rays, t_max, to_max) = rays_at(&mut rng, &square, case);
            let lanes = RayLanes::new(&rays);
            let limits = Limits {
                t_max: &t_max,
                to_max: &to_max,
            };
            let cull = case % 2 == 0;
            let (mut quad_hits, mut sphere_hits) = (LaneHits::default(), LaneHits::default());
            quad(&lanes, (&square, normal, cull), &limits, &mut quad_hits);
            super::sphere(&lanes, &sphere, &limits, &mut sphere_hits);
            for (k, ray) in rays.iter().enumerate() {
                let bound = single_bound(t_max[k], to_max[k]);
                let bits =
                    |h: Option<(f32, f32, f32)>| h.map(|(t, u, v)| [t, u, v].map(f32::to_bits));
                let lane = |h: &LaneHits| h.hit[k].then(|| (h.t[k], h.u[k], h.v[k]));
                let meets = !cull || faces_ray(normal, ray.direction);
                let want = intersect_quad_sheared(ray, &RayShear::new(ray), bound, &square)
                    .filter(|_| meets);
                if quad_hits.unsure[k] {
                    unsure += 1;
                    overruled += (bits(lane(&quad_hits)) != bits(want)) as u32;
                } else {
                    assert_eq!(
                        bits(lane(&quad_hits)),
                        bits(want),
                        "quad: case {case}, lane {k}"
                    );
                    quad_hits_seen += want.is_some() as u32;
                }
                let want = Shape::intersect(&sphere, ray, bound).map(|(t, _)| (t, 0.0, 0.0));
                assert_eq!(
                    bits(lane(&sphere_hits)),
                    bits(want),
                    "sphere: case {case}, lane {k}"
                );
                assert!(!sphere_hits.unsure[k]);
                hits += want.is_some() as u32;
                checked += 1;
            }
        }
        println!(
            "{hits} sphere and {quad_hits_seen} quad hits of {checked}, {unsure} quad lanes \
             unsure, {overruled} of them overruled"
        );
        assert!(
            hits > 2000 && checked - hits > 2000,
            "{hits} hits of {checked}"
        );
        let quad_checked = checked - unsure;
        assert!(
            quad_hits_seen > 2000 && quad_checked - quad_hits_seen > 2000,
            "{quad_hits_seen} quad hits of {quad_checked}"
        );
        assert!(
            overruled > 20,
            "{overruled} of {unsure} unsure quad lanes overruled"
        );
    }
}
