//! Four triangles tested against one ray at once: the BVH's leaves keep their triangles in
//! packs of four, coordinates side by side (one SIMD lane a triangle), and run the same
//! watertight test as `intersect_triangle_sheared` in all four lanes. Every lane performs that
//! function's operations in its order, so a lane's hit, t and barycentrics are bit for bit the
//! scalar test's; the rare lane with an edge function exactly zero (where the scalar test
//! recomputes in f64) is handed to the scalar test itself. The same lanes serve the other way
//! round too (`Rays4`): one triangle against four rays, for the BVH's packets of rays.

use glam::Vec4;

use super::PackedPrim;
use crate::geometry::{
    faces_ray, intersect_triangle_sheared, triangle_normal, Ray, RayShear, Vec3,
};

/// Four triangles: `v[k][a]` holds coordinate `a` (x, y, z) of vertex `k` of each. A pack of
/// fewer than four repeats its last triangle, which can only give the same hit again.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct Tri4 {
    v: [[Vec4; 3]; 3],
    prims: [PackedPrim; 4],
}

/// The ray in the form the pack test wants, made once per ray: its origin and shear in every
/// lane, axes already permuted so that z is the direction's dominant axis.
pub(super) struct Tri4Ray {
    org: [Vec4; 3],
    sx: Vec4,
    sy: Vec4,
    sz: Vec4,
    t_min: Vec4,
    axes: [usize; 3],
}

impl Tri4Ray {
    pub fn new(ray: &Ray, shear: &RayShear) -> Tri4Ray {
        let axes = shear.axes();
        let (sx, sy, sz) = shear.factors();
        let o = ray.origin.to_array();
        Tri4Ray {
            org: axes.map(|a| Vec4::splat(o[a])),
            sx: Vec4::splat(sx),
            sy: Vec4::splat(sy),
            sz: Vec4::splat(sz),
            t_min: Vec4::splat(ray.t_min),
            axes,
        }
    }
}

/// The lanes a pack test found hit, with each lane's t and barycentrics.
pub(super) struct Tri4Hits {
    /// Bit `i` set when lane `i` is hit.
    pub mask: u32,
    pub t: [f32; 4],
    pub u: [f32; 4],
    pub v: [f32; 4],
}

impl Tri4 {
    /// Packs up to four triangles (at least one).
    pub fn new(tris: &[([Vec3; 3], PackedPrim)]) -> Tri4 {
        debug_assert!((1..=4).contains(&tris.len()));
        let lane = |i: usize| &tris[i.min(tris.len() - 1)];
        let v = std::array::from_fn(|k| {
            std::array::from_fn(|a| Vec4::from_array(std::array::from_fn(|i| lane(i).0[k][a])))
        });
        Tri4 {
            v,
            prims: std::array::from_fn(|i| lane(i).1),
        }
    }

    /// The distinct triangles of the pack.
    pub fn triangles(&self) -> impl Iterator<Item = ([Vec3; 3], PackedPrim)> + '_ {
        (0..4)
            .filter(|&i| i == 0 || self.prims[i] != self.prims[i - 1])
            .map(|i| (self.triangle(i), self.prims[i]))
    }

    /// The vertices of the triangle in `lane`.
    fn triangle(&self, lane: usize) -> [Vec3; 3] {
        std::array::from_fn(|k| {
            Vec3::new(self.v[k][0][lane], self.v[k][1][lane], self.v[k][2][lane])
        })
    }

    /// The pack's 160 bytes put to another use: `floats` (at most 36) in its lanes and `prim`
    /// in every reference (see the BVH's `LeafItem`).
    pub fn holding(floats: &[f32], prim: PackedPrim) -> Tri4 {
        let mut lanes = [0f32; 36];
        lanes[..floats.len()].copy_from_slice(floats);
        Tri4 {
            v: bytemuck::cast(lanes),
            prims: [prim; 4],
        }
    }

    /// The lanes of `lanes` whose triangles face a ray along `dir` (`faces_ray` of
    /// `triangle_normal`: the one test every backend makes).
    #[inline(always)]
    pub fn facing(&self, lanes: u32, dir: Vec3) -> u32 {
        (0..4)
            .filter(|&i| lanes >> i & 1 != 0 && faces_ray(triangle_normal(&self.triangle(i)), dir))
            .fold(0, |m, i| m | 1 << i)
    }

    /// The lanes as 36 floats, as `holding` wrote them.
    #[inline(always)]
    pub fn floats(&self) -> &[f32; 36] {
        bytemuck::cast_ref(&self.v)
    }

    #[inline(always)]
    pub fn prim(&self, lane: usize) -> PackedPrim {
        self.prims[lane]
    }

    /// The lanes hit in `(ray.t_min, limit)`, as `intersect_triangle_sheared` decides each.
    #[inline(always)]
    pub fn intersect(&self, r: &Tri4Ray, ray: &Ray, shear: &RayShear, limit: f32) -> Tri4Hits {
        let [kx, ky, kz] = r.axes;
        // Vertex k relative to the origin, on the permuted axes.
        let rel = |k: usize| {
            let v = &self.v[k];
            [v[kx] - r.org[0], v[ky] - r.org[1], v[kz] - r.org[2]]
        };
        let lanes = sheared_lanes(
            [rel(0), rel(1), rel(2)],
            [r.sx, r.sy, r.sz],
            (r.t_min, Vec4::splat(limit)),
        );
        let mut hits = Tri4Hits {
            mask: lanes.hit,
            t: lanes.t.to_array(),
            u: lanes.u.to_array(),
            v: lanes.v.to_array(),
        };
        if lanes.on_edge != 0 {
            self.settle_on_edge(lanes.on_edge, ray, shear, limit, &mut hits);
        }
        hits
    }

    /// Lanes with an edge function exactly zero, decided by the scalar test (which redoes
    /// them in f64).
    #[cold]
    fn settle_on_edge(
        &self,
        lanes: u32,
        ray: &Ray,
        shear: &RayShear,
        limit: f32,
        hits: &mut Tri4Hits,
    ) {
        for i in (0..4).filter(|i| lanes >> i & 1 != 0) {
            let [a, b, c] = self.triangle(i);
            let hit = intersect_triangle_sheared(ray, shear, limit, a, b, c);
            if let Some((t, u, v)) = hit {
                hits.mask |= 1 << i;
                hits.t[i] = t;
                hits.u[i] = u;
                hits.v[i] = v;
            }
        }
    }
}

/// What the watertight test decides in four lanes.
struct Lanes {
    /// Lanes hit, of those without an edge function exactly zero.
    hit: u32,
    /// Lanes with an edge function exactly zero, which the scalar test redoes in f64.
    on_edge: u32,
    t: Vec4,
    u: Vec4,
    v: Vec4,
}

/// `intersect_triangle_sheared`'s operations, in its order, in four lanes, each lane a
/// triangle and a ray: `rel[k]` holds vertex k relative to the ray's origin on the ray's
/// permuted axes, `shear` the ray's shear factors, `range` its `(t_min, t_max)`.
#[inline(always)]
fn sheared_lanes(rel: [[Vec4; 3]; 3], shear: [Vec4; 3], range: (Vec4, Vec4)) -> Lanes {
    let [[a_x, a_y, a_z], [b_x, b_y, b_z], [c_x, c_y, c_z]] = rel;
    let [sx, sy, sz] = shear;
    let ax = a_x - sx * a_z;
    let ay = a_y - sy * a_z;
    let bx = b_x - sx * b_z;
    let by = b_y - sy * b_z;
    let cx = c_x - sx * c_z;
    let cy = c_y - sy * c_z;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = Vec4::ZERO;
    let on_edge = u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero);
    let outside = (u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero))
        & (u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero));
    let det = u + v + w;
    let t_scaled = u * (sz * a_z) + v * (sz * b_z) + w * (sz * c_z);
    let inv = Vec4::ONE / det;
    let t = t_scaled * inv;
    let hit = !outside
        & det.cmpne(zero)
        & det.abs().cmplt(Vec4::INFINITY)
        & t.cmpgt(range.0)
        & t.cmplt(range.1);
    Lanes {
        hit: (hit & !on_edge).bitmask(),
        on_edge: on_edge.bitmask(),
        t,
        u: v * inv,
        v: w * inv,
    }
}

/// Four rays whose directions share their dominant axis and its sign (so one permutation of
/// the axes serves them all), set up to be tested against one triangle at once: one lane a
/// ray. The batched occlusion query tests quads so, where a packet's rays run alike.
pub(super) struct Rays4 {
    /// Origins on the permuted axes.
    org: [Vec4; 3],
    /// Directions on the scene's axes (for `faces`).
    dir: [Vec4; 3],
    shear: [Vec4; 3],
    range: (Vec4, Vec4),
    axes: [usize; 3],
}

impl Rays4 {
    /// The four rays in lanes, or `None` when their permutations differ.
    #[inline(always)]
    pub fn new(rays: [(&Ray, &RayShear); 4]) -> Option<Rays4> {
        let axes = rays[0].1.axes();
        if rays.iter().any(|(_, s)| s.axes() != axes) {
            return None;
        }
        // Rows: origin (permuted), direction, shear, t_min, t_max.
        let mut rows = [[0f32; 4]; 11];
        for (i, (ray, shear)) in rays.iter().enumerate() {
            let (sx, sy, sz) = shear.factors();
            let lane = [
                ray.origin[axes[0]],
                ray.origin[axes[1]],
                ray.origin[axes[2]],
                ray.direction.x,
                ray.direction.y,
                ray.direction.z,
                sx,
                sy,
                sz,
                ray.t_min,
                ray.t_max,
            ];
            for (row, value) in rows.iter_mut().zip(lane) {
                row[i] = value;
            }
        }
        let row = |k: usize| Vec4::from_array(rows[k]);
        Some(Rays4 {
            org: [row(0), row(1), row(2)],
            dir: [row(3), row(4), row(5)],
            shear: [row(6), row(7), row(8)],
            range: (row(9), row(10)),
            axes,
        })
    }

    /// The lanes that hit the triangle `tri` in their `(t_min, t_max)` (bits), and those
    /// whose edge functions the scalar test must decide.
    #[inline(always)]
    pub fn hit(&self, tri: [Vec3; 3]) -> (u32, u32) {
        let rel = |v: Vec3| {
            let [x, y, z] = self.axes.map(|a| v[a]);
            [
                Vec4::splat(x) - self.org[0],
                Vec4::splat(y) - self.org[1],
                Vec4::splat(z) - self.org[2],
            ]
        };
        let lanes = sheared_lanes(
            [rel(tri[0]), rel(tri[1]), rel(tri[2])],
            self.shear,
            self.range,
        );
        (lanes.hit, lanes.on_edge)
    }

    /// The lanes whose ray a one-sided surface of front normal `n` faces, as `faces_ray`
    /// decides each (its products summed in its order).
    #[inline(always)]
    pub fn faces(&self, n: Vec3) -> u32 {
        let dot = Vec4::splat(n.x) * self.dir[0]
            + Vec4::splat(n.y) * self.dir[1]
            + Vec4::splat(n.z) * self.dir[2];
        dot.cmplt(Vec4::ZERO).bitmask()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::scene::{PrimKind, PrimRef};

    fn prim(index: u32) -> PackedPrim {
        PackedPrim::new(PrimRef {
            kind: PrimKind::Triangle,
            index,
        })
    }

    /// Every lane's answer, bit for bit, is `intersect_triangle_sheared`'s: random triangles
    /// (some sharing vertices, some degenerate), rays aimed at random points, at the
    /// triangles' vertices and at their edges' midpoints (where edge functions are zero and
    /// the scalar test goes to f64), and limits that cut some hits off.
    #[test]
    fn every_lane_answers_as_the_scalar_test() {
        let mut rng = Rng::new(7, 0, 0);
        let point = |rng: &mut Rng| {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE
        };
        let (mut checked, mut hits, mut on_edges) = (0, 0, 0);
        for case in 0..4000u32 {
            let count = 1 + case as usize % 4;
            let mut tris: Vec<([Vec3; 3], PackedPrim)> = (0..count)
                .map(|i| {
                    (
                        [point(&mut rng), point(&mut rng), point(&mut rng)],
                        prim(i as u32),
                    )
                })
                .collect();
            if case % 5 == 0 && count > 1 {
                // Two triangles sharing an edge, as in a mesh.
                tris[1].0[0] = tris[0].0[1];
                tris[1].0[1] = tris[0].0[0];
            }
            if case % 7 == 0 {
                // A degenerate triangle: all three vertices on a line.
                let [a, b, _] = tris[0].0;
                tris[0].0[2] = a + (b - a) * 0.5;
            }
            let pack = Tri4::new(&tris);
            let origin = point(&mut rng) * 3.0;
            let [a, b, c] = tris[rng.next_u64() as usize % count].0;
            let target = match case % 4 {
                0 => a,
                1 => (a + b) * 0.5,
                2 => point(&mut rng),
                _ => (a + b + c) / 3.0,
            };
            let ray = Ray::new(origin, target - origin);
            let shear = RayShear::new(&ray);
            let pack_ray = Tri4Ray::new(&ray, &shear);
            for limit in [f32::INFINITY, 1.0, 0.999] {
                let got = pack.intersect(&pack_ray, &ray, &shear, limit);
                for (i, (v, p)) in tris.iter().enumerate() {
                    let want = intersect_triangle_sheared(&ray, &shear, limit, v[0], v[1], v[2]);
                    let lane = match got.mask >> i & 1 {
                        1 => Some((got.t[i], got.u[i], got.v[i])),
                        _ => None,
                    };
                    let bits = |h: Option<(f32, f32, f32)>| {
                        h.map(|(t, u, v)| (t.to_bits(), u.to_bits(), v.to_bits()))
                    };
                    assert_eq!(
                        bits(lane),
                        bits(want),
                        "case {case}, lane {i}, limit {limit}"
                    );
                    assert_eq!(pack.prim(i), *p);
                    checked += 1;
                    hits += want.is_some() as u32;
                }
                // The padding lanes repeat the last triangle.
                for i in count..4 {
                    assert_eq!(got.mask >> i & 1, got.mask >> (count - 1) & 1);
                    assert_eq!(pack.prim(i), tris[count - 1].1);
                }
            }
            let edge = |p: Vec3, q: Vec3, r: Vec3| {
                let rel = |x: Vec3| x - origin;
                let (p, q, r) = (rel(p), rel(q), rel(r));
                p.cross(q).dot(ray.direction) == 0.0
                    || q.cross(r).dot(ray.direction) == 0.0
                    || r.cross(p).dot(ray.direction) == 0.0
            };
            on_edges += tris.iter().any(|(v, _)| edge(v[0], v[1], v[2])) as u32;
        }
        // The cases reached what they are for: hits, misses, and rays along edges.
        assert!(
            hits > 2000 && checked - hits > 2000,
            "{hits} hits of {checked}"
        );
        assert!(
            on_edges > 100,
            "{on_edges} rays through a vertex or along an edge"
        );
    }

    /// Four rays against one triangle (`Rays4`, the batched occlusion's quad test): every
    /// lane not handed back as on an edge decides as `intersect_triangle_sheared` does, and
    /// `faces` as `faces_ray`. The rays start near one point and aim at the triangle's
    /// vertices, edges, inside and around it, with t ranges that cut some hits off.
    #[test]
    fn four_rays_answer_as_the_scalar_test() {
        use crate::geometry::faces_ray;
        let mut rng = Rng::new(11, 0, 0);
        let point = |rng: &mut Rng| {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE
        };
        let (mut checked, mut hits, mut on_edges, mut apart) = (0, 0, 0, 0);
        for case in 0..4000u32 {
            let tri = [point(&mut rng), point(&mut rng), point(&mut rng)];
            let eye = point(&mut rng) * 3.0;
            let rays: Vec<Ray> = (0..4)
                .map(|i| {
                    let [a, b, c] = tri;
                    let target = match (case as usize + i) % 5 {
                        0 => a,
                        1 => (b + c) * 0.5,
                        2 => point(&mut rng),
                        3 => (a + b + c) / 3.0,
                        _ => a + (a - b) * 0.01,
                    };
                    let origin = eye + point(&mut rng) * 0.05;
                    let mut ray = Ray::new(origin, target - origin);
                    ray.t_max = [f32::INFINITY, 1.0, 0.999, 0.5][(case as usize + i) % 4];
                    ray
                })
                .collect();
            let shears: Vec<RayShear> = rays.iter().map(RayShear::new).collect();
            let lanes = std::array::from_fn(|i| (&rays[i], &shears[i]));
            let Some(rays4) = Rays4::new(lanes) else {
                assert!(shears.iter().any(|s| s.axes() != shears[0].axes()));
                apart += 1;
                continue;
            };
            let (hit, on_edge) = rays4.hit(tri);
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let facing = rays4.faces(n);
            for (i, (ray, shear)) in rays.iter().zip(&shears).enumerate() {
                let want =
                    intersect_triangle_sheared(ray, shear, ray.t_max, tri[0], tri[1], tri[2]);
                if on_edge >> i & 1 == 0 {
                    assert_eq!(hit >> i & 1 == 1, want.is_some(), "case {case}, lane {i}");
                } else {
                    on_edges += 1;
                }
                assert_eq!(facing >> i & 1 == 1, faces_ray(n, ray.direction));
                checked += 1;
                hits += want.is_some() as u32;
            }
        }
        println!("{hits} hits of {checked}, {on_edges} on an edge, {apart} apart");
        assert!(
            hits > 1000 && checked - hits > 1000,
            "{hits} hits of {checked}"
        );
        assert!(on_edges > 100, "{on_edges} lanes on an edge");
        assert!(apart < 2000, "{apart} cases of rays with different axes");
    }

    /// `triangles()` gives back what was packed, without the padding.
    #[test]
    fn a_pack_gives_back_its_triangles() {
        let tris: Vec<([Vec3; 3], PackedPrim)> = (0..3)
            .map(|i| {
                let o = Vec3::splat(i as f32);
                ([o, o + Vec3::X, o + Vec3::Y], prim(i))
            })
            .collect();
        let pack = Tri4::new(&tris);
        let back: Vec<_> = pack.triangles().collect();
        assert_eq!(back.len(), 3);
        for ((v, p), (w, q)) in back.iter().zip(&tris) {
            assert_eq!((v, p), (w, q));
        }
    }
}
