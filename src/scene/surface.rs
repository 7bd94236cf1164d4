//! From "ray r hit primitive p at t" to everything shading needs. Both backends report only the
//! primitive and t; the surface is then recomputed here with the shared exact routines, so the
//! two backends give bit-identical surfaces whenever they agree on the primitive.

use super::procedural::{bumped_normal, Bump, BumpSource};
use super::{Color, PrimKind, PrimRef, Scene};
use crate::geometry::{
    intersect_quad, point_error, spawn_ray, triangle_normal, vec2, Bounds3, Ray, Shape, Vec2, Vec3,
};
use crate::sampling::orthonormal_basis;

impl SurfaceHit {
    /// Whether a ray travelling along `dir` arrives at the front side (by the geometric
    /// normal), and the shading normal turned towards the side it arrives from.
    pub fn facing(&self, dir: Vec3) -> (bool, Vec3) {
        let front = self.geometric_normal.dot(dir) < 0.0;
        let n = if front {
            self.shading_normal
        } else {
            -self.shading_normal
        };
        (front, n)
    }

    /// The geometric normal turned to the side of `n` (a shading normal from `facing`): what
    /// photons are stored and looked up by, so that a bump map's tilts, which differ from
    /// point to point, do not keep neighbouring photons apart.
    pub fn geometric_side(&self, n: Vec3) -> Vec3 {
        if self.geometric_normal.dot(n) >= 0.0 {
            self.geometric_normal
        } else {
            -self.geometric_normal
        }
    }

    /// Whether `dir` leaves the surface on the side `n` (from `facing`) faces, by the
    /// geometric normal: a bump map's tilted normal lets sampled directions dip below the
    /// surface, and the light there is absorbed, not passed through it.
    pub fn leaves_on_side_of(&self, n: Vec3, dir: Vec3) -> bool {
        self.geometric_normal.dot(dir) * self.geometric_normal.dot(n) > 0.0
    }

    /// A ray leaving this surface point in direction `dir`, offset so it cannot hit the
    /// surface it leaves.
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        spawn_ray(self.point, self.geometric_normal, self.error, dir)
    }
}

/// The vertex normals `[a, b, c]` of a triangle interpolated at barycentric (b1, b2), on the
/// side of the geometric normal `ng` (a mesh whose normals disagree with its winding, or an
/// instance that mirrors, is shaded from the side it is hit on); `ng` where they cancel.
#[inline]
fn smooth_normal([a, b, c]: [Vec3; 3], b1: f32, b2: f32, ng: Vec3) -> Vec3 {
    let n = (a * (1.0 - b1 - b2) + b * b1 + c * b2).normalize_or_zero();
    match n.dot(ng) {
        d if d > 0.0 => n,
        d if d < 0.0 => -n,
        _ => ng,
    }
}

fn max_abs(points: &[Vec3]) -> f32 {
    points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f32::max)
}

/// What an acceleration structure reports for a closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    pub t: f32,
    pub prim: PrimRef,
    /// The backend's surface parameters (used only when the exact routine disagrees).
    pub u: f32,
    pub v: f32,
    /// Whether t, u and v are the exact routines' and the primitive the nearest by the shared
    /// tie rule (the BVH's hits, and Embree's with `--embree-exact`): the surface then takes
    /// them as they are, where a hit from elsewhere is settled among the quad's neighbours
    /// (`settle_quad_hit`), which re-ran the exact test on every hit.
    pub exact: bool,
}

/// A ray's closest hit with its surface: point, normals, parameters, material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub t: f32,
    pub point: Vec3,
    /// Unit geometric normal: the front normal of quads and triangles, outward on closed
    /// surfaces. It does not depend on the side the ray came from.
    pub geometric_normal: Vec3,
    /// Unit shading normal: the geometric normal tilted by the material's bump map, if any,
    /// or a mesh's vertex normals interpolated where the scene asks for it
    /// (`Scene::smooth_normals`), on the same side of the surface.
    pub shading_normal: Vec3,
    /// Bound on the absolute error of `point` in each coordinate (see `offset_ray_origin`).
    pub error: f32,
    /// A polygon's own parameters in \[0,1\]² (a quad's (u, v), a triangle's barycentric
    /// (b1, b2)); (0, 0) on an analytic shape, whose parameters take inverse trigonometric
    /// functions that most hits never need. Read them with `Scene::parameters`, texture
    /// coordinates with `Scene::tex_coords`.
    pub(in crate::scene) uv: (f32, f32),
    pub prim: PrimRef,
    /// The part of an analytic shape the point lies on (see `Shape`); 0 on polygons.
    pub part: u32,
    pub material: u32,
}

impl Scene {
    /// Whether a ray travelling along `dir` sees the emission of the surface it hit: quads
    /// emit from their front side only (unless `--two-sided`), closed surfaces from all sides.
    #[inline]
    pub fn sees_emission(&self, s: &SurfaceHit, dir: Vec3) -> bool {
        let closed = s.prim.kind == PrimKind::Shape;
        self.materials[s.material as usize].is_emissive()
            && (closed || self.two_sided_quads || s.facing(dir).0)
    }

    /// The surface at a backend's hit, its shading normal tilted by its material's bump map.
    ///
    /// Inlined, with `flat_surface`, so that the hit is built where the caller keeps it: as
    /// calls, the path tracer's wavefront copied each hit twice through the stack, and read
    /// the copies back wider than they were written, a store-forwarding stall (0.98× the
    /// time inlined, 0.985× more without the bump map's copy).
    #[inline(always)]
    pub fn surface(&self, ray: &Ray, hit: &PrimHit) -> SurfaceHit {
        let s = self.flat_surface(ray, hit);
        // Without a bump map the hit is returned as built, never borrowed: so it need not
        // be kept in memory first, and copied from there.
        let Some(bump) = &self.materials[s.material as usize].bump else {
            return s;
        };
        SurfaceHit {
            shading_normal: self.bumped(&s, bump),
            ..s
        }
    }

    /// The shading normal of `s` under `bump`: heights differenced across two tangent
    /// directions, a footprint apart where the footprint is known and larger than a
    /// hundredth of the pattern (a thousandth of the primitive, for a height image). A
    /// thousandth of the pattern made the bumped normals follow the rounding of the point:
    /// the scene scaled by 1e-4 gave relMSE 2.2e-10 against the unscaled one, where the
    /// geometry alone gives 3e-11.
    fn bumped(&self, s: &SurfaceHit, bump: &Bump) -> Vec3 {
        let n = s.geometric_normal;
        let tangents = orthonormal_basis(n);
        let w = self.footprint.half_widths(s.point, n).max_element();
        let difference = |step: f32, height: &dyn Fn(Vec3) -> f32| {
            let across = |t: Vec3| height(s.point + t * step) - height(s.point - t * step);
            (across(tangents.0), across(tangents.1))
        };
        let (dh, step) = match &bump.source {
            BumpSource::Procedural {
                pattern,
                scale,
                origin,
            } => {
                let step = w.max(1e-2 * scale);
                let height =
                    |p: Vec3| pattern.value((p - *origin) / *scale, Vec3::splat(w / scale));
                (difference(step, &height), step)
            }
            BumpSource::File { map: Some(k), .. } => {
                let map = &self.height_maps[*k];
                let step = w.max(1e-3 * self.primitive_extent(s.prim));
                // The texture coordinates of a point beside the hit: where a ray along the
                // normal meets the same primitive.
                let height = |p: Vec3| {
                    let probe = Ray::new(p + n * step, -n);
                    let near = PrimHit {
                        t: step,
                        prim: s.prim,
                        u: s.uv.0,
                        v: s.uv.1,
                        exact: false,
                    };
                    let tc = self.tex_coords(&self.flat_surface(&probe, &near));
                    let h = map.lookup(tc);
                    (h.x + h.y + h.z) / 3.0
                };
                (difference(step, &height), step)
            }
            BumpSource::File { map: None, .. } => return s.shading_normal,
        };
        bumped_normal(n, tangents, dh, bump.amplitude, 2.0 * step)
    }

    /// The primitive's own parameters at a hit, in \[0,1\]²: a quad's (u, v), a triangle's
    /// barycentric (b1, b2), an analytic shape's (`Shape::uv_at`) on the hit's part.
    pub fn parameters(&self, hit: &SurfaceHit) -> (f32, f32) {
        match hit.prim.kind {
            PrimKind::Shape => self.shapes[hit.prim.index as usize]
                .shape
                .uv_at(hit.point, hit.part),
            PrimKind::Quad | PrimKind::Triangle | PrimKind::Instanced => hit.uv,
        }
    }

    /// The directions in which the texture's coordinates (s, t) grow at a hit, ∂p/∂s and
    /// ∂p/∂t (not unit): on triangles with texture coordinates, where they are not
    /// degenerate; None elsewhere. An anisotropic BSDF's frame is aligned with the first,
    /// as in Mitsuba; a bump map tilts both.
    pub fn tangents(&self, hit: &SurfaceHit) -> Option<(Vec3, Vec3)> {
        let (mesh, i, [p0, p1, p2], _) = self.triangle_of(hit.prim)?;
        if mesh.tex_coords.is_empty() {
            return None;
        }
        let [t0, t1, t2] = mesh.indices[i].map(|k| mesh.tex_coords[k as usize]);
        let (du1, du2) = (t1 - t0, t2 - t0);
        let det = du1.x * du2.y - du1.y * du2.x;
        let dpdu = ((p1 - p0) * du2.y - (p2 - p0) * du1.y) / det;
        let dpdv = ((p2 - p0) * du1.x - (p1 - p0) * du2.x) / det;
        (det != 0.0 && dpdu.is_finite() && dpdv.is_finite() && dpdu != Vec3::ZERO)
            .then_some((dpdu, dpdv))
    }

    /// A triangle primitive's mesh, its index there, its world vertices and its instance: a
    /// triangle of `triangles` (no instance), or an instanced one (its group's mesh, its
    /// vertices placed by its instance); None for other primitives.
    #[inline]
    fn triangle_of(&self, prim: PrimRef) -> Option<TriangleOf<'_>> {
        let i = prim.index as usize;
        match prim.kind {
            PrimKind::Triangle => Some((&self.triangles, i, self.triangles.vertices(i), None)),
            PrimKind::Instanced => {
                let (instance, j) = self.instancing.locate(prim.index);
                let mesh = &self.instancing.group_of(instance).mesh;
                let vertices = mesh.vertices(j).map(|p| instance.place(p));
                Some((mesh, j, vertices, Some(instance)))
            }
            PrimKind::Quad | PrimKind::Shape => None,
        }
    }

    /// The texture coordinates at a hit: interpolated from the primitive's `vt` where it has
    /// them, else its parameters.
    pub fn tex_coords(&self, hit: &SurfaceHit) -> Vec2 {
        self.tex_coords_at(hit.prim, self.parameters(hit))
    }

    /// The texture coordinates of the point of `prim` at its own parameters `(u, v)` (as
    /// `parameters` gives them: a quad's (u, v), a triangle's barycentric (b1, b2)).
    pub fn tex_coords_at(&self, prim: PrimRef, (u, v): (f32, f32)) -> Vec2 {
        let i = prim.index as usize;
        match prim.kind {
            PrimKind::Quad => match &self.quads[i].tex_coords {
                Some(tc) => bilinear(tc, u, v),
                None => vec2(u, v),
            },
            PrimKind::Triangle => triangle_tex_coords(&self.triangles, i, u, v),
            PrimKind::Instanced => {
                let (instance, j) = self.instancing.locate(prim.index);
                triangle_tex_coords(&self.instancing.group_of(instance).mesh, j, u, v)
            }
            PrimKind::Shape => vec2(u, v),
        }
    }

    /// The radiance the surface at a hit emits: its material's `emission_texture` there, or
    /// its `emitted`.
    pub fn emitted(&self, hit: &SurfaceHit) -> Color {
        let m = &self.materials[hit.material as usize];
        match m.emission_texture {
            Some(k) => self.textures[k].lookup(self.tex_coords(hit)),
            None => m.emitted,
        }
    }

    /// The radiance emitted at `point`, a point on the emitting primitive `prim` (a light
    /// sample): as `emitted` gives it at a hit there. Only triangles carry an
    /// `emission_texture` (the Mitsuba reader gives it to meshes alone).
    pub fn emitted_at(&self, prim: PrimRef, point: Vec3) -> Color {
        let m = &self.materials[self.material_of(prim) as usize];
        let (Some(k), PrimKind::Triangle) = (m.emission_texture, prim.kind) else {
            return m.emitted;
        };
        let i = prim.index as usize;
        let [a, b, c] = self.triangles.vertices(i);
        // The point's barycentric parameters, from the normal equations of
        // point − a = u·e1 + v·e2.
        let (e1, e2, w) = (b - a, c - a, point - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (w1, w2) = (w.dot(e1), w.dot(e2));
        let det = d11 * d22 - d12 * d12;
        let (u, v) = if det > 0.0 {
            ((d22 * w1 - d12 * w2) / det, (d11 * w2 - d12 * w1) / det)
        } else {
            (0.0, 0.0)
        };
        self.textures[k].lookup(triangle_tex_coords(&self.triangles, i, u, v))
    }

    /// The size of a primitive: the longest side of its bounding box.
    fn primitive_extent(&self, prim: PrimRef) -> f32 {
        let i = prim.index as usize;
        let bounds = match prim.kind {
            PrimKind::Quad => Bounds3::from_points(&self.quads[i].vertices),
            PrimKind::Triangle => Bounds3::from_points(&self.triangles.vertices(i)),
            PrimKind::Shape => self.shapes[i].shape.bounds(),
            PrimKind::Instanced => Bounds3::from_points(&self.instanced_vertices(prim.index)),
        };
        bounds.extent().max_element()
    }

    /// The surface at a backend's hit, with the geometric normal for shading normal.
    #[inline(always)]
    fn flat_surface(&self, ray: &Ray, hit: &PrimHit) -> SurfaceHit {
        let i = hit.prim.index as usize;
        let t_max = f32::INFINITY;
        match hit.prim.kind {
            PrimKind::Quad => {
                let (index, (t, u, v)) = self.settle_quad_hit(ray, i, hit);
                let q = &self.quads[index];
                let vs = &q.vertices;
                // The point from the triangle the parameters lie in: exact to the vertices'
                // precision, not the ray's.
                let point = if u + v <= 1.0 {
                    vs[0] + (vs[1] - vs[0]) * u + (vs[3] - vs[0]) * v
                } else {
                    vs[2] + (vs[3] - vs[2]) * (1.0 - u) + (vs[1] - vs[2]) * (1.0 - v)
                };
                SurfaceHit {
                    t,
                    point,
                    error: point_error(max_abs(vs)),
                    geometric_normal: q.normal,
                    shading_normal: q.normal,
                    uv: (u, v),
                    prim: PrimRef {
                        kind: PrimKind::Quad,
                        index: index as u32,
                    },
                    part: 0,
                    material: q.material,
                }
            }
            PrimKind::Triangle | PrimKind::Instanced => {
                let (mesh, j, [p0, p1, p2], instance) = self
                    .triangle_of(hit.prim)
                    .expect("a triangle kind has a triangle");
                // An exact hit is the routine's own answer: testing again would give it back.
                // (An instanced triangle's exact answer is its test in the group's space, whose
                // t is the world's: `Instance::ray_to_group`.)
                let (t, b1, b2) = if hit.exact {
                    (hit.t, hit.u, hit.v)
                } else {
                    crate::geometry::intersect_triangle(ray, t_max, p0, p1, p2)
                        .unwrap_or((hit.t, hit.u, hit.v))
                };
                let point = p0 + (p1 - p0) * b1 + (p2 - p0) * b2;
                let ng = triangle_normal(&[p0, p1, p2]).normalize_or_zero();
                let shading_normal = if self.smooth_normals && !mesh.normals.is_empty() {
                    let normals = mesh.indices[j].map(|k| mesh.normals[k as usize]);
                    let normals = match instance {
                        Some(instance) => normals.map(|n| instance.turn(n)),
                        None => normals,
                    };
                    smooth_normal(normals, b1, b2, ng)
                } else {
                    ng
                };
                SurfaceHit {
                    t,
                    point,
                    error: point_error(max_abs(&[p0, p1, p2])),
                    geometric_normal: ng,
                    shading_normal,
                    uv: (b1, b2),
                    prim: hit.prim,
                    part: 0,
                    material: mesh.materials[j],
                }
            }
            PrimKind::Shape => {
                let prim = &self.shapes[i];
                let shape = &prim.shape;
                // An exact hit is the routine's own t (its roots do not depend on the limit it
                // was called with); only a shape of several parts needs the test again, for
                // the part.
                let (t, part) = if hit.exact && shape.part_count() == 1 {
                    (hit.t, 0)
                } else {
                    shape
                        .intersect(ray, t_max)
                        .unwrap_or_else(|| (hit.t, shape.nearest_part(ray.at(hit.t))))
                };
                // Moved onto the surface: the point's error is then that of the shape's size.
                let (point, n) = shape.project(ray.at(t), part);
                SurfaceHit {
                    t,
                    point,
                    error: point_error(shape.magnitude()),
                    geometric_normal: n,
                    shading_normal: n,
                    uv: (0.0, 0.0),
                    prim: hit.prim,
                    part,
                    material: prim.material,
                }
            }
        }
    }
}

/// What `Scene::triangle_of` answers: mesh, index in it, world vertices, instance.
type TriangleOf<'a> = (
    &'a super::TriangleMesh,
    usize,
    [Vec3; 3],
    Option<&'a super::Instance>,
);

/// The texture coordinates of `mesh`'s triangle `i` at the point of barycentric parameters
/// (u, v) (the point a + u·(b − a) + v·(c − a)): its vertices' interpolated where the mesh has
/// them, else (u, v).
fn triangle_tex_coords(mesh: &super::TriangleMesh, i: usize, u: f32, v: f32) -> Vec2 {
    if mesh.tex_coords.is_empty() {
        return vec2(u, v);
    }
    let [a, b, c] = mesh.indices[i].map(|k| mesh.tex_coords[k as usize]);
    let b0 = 1.0 - u - v;
    vec2(a.x * b0 + b.x * u + c.x * v, a.y * b0 + b.y * u + c.y * v)
}

/// Derived data of a scene: for each quad, the quads sharing a vertex position with it.
/// Built on first use, so scenes are still made with plain struct literals.
#[derive(Clone, Debug, Default)]
pub struct QuadNeighbours(std::sync::OnceLock<Vec<Vec<u32>>>);

/// Hits this close to a quad's border (in its parameters) may lie on an edge it shares.
const EDGE_BAND: f32 = 1e-4;

impl Scene {
    fn quad_neighbours(&self) -> &[Vec<u32>] {
        self.quad_neighbours
            .0
            .get_or_init(|| quad_adjacency(&self.quads))
    }

    /// The quad a hit on quad `i` belongs to, with its exact (t, u, v). A ray through an edge
    /// or corner shared by several quads hits each of them at nearly the same t, and which
    /// one a backend reports depends on its arithmetic and traversal order. Such hits are
    /// settled here by the shared exact routine: the smallest t among the quads sharing a
    /// vertex with quad i, ties to the lowest index, so both backends give the same surface.
    ///
    /// An exact hit (the BVH's, Embree's with `--embree-exact`) is its own answer, inline: as
    /// a call, the answer came back through memory and was read wider than it was written, a
    /// store-forwarding stall.
    #[inline(always)]
    fn settle_quad_hit(&self, ray: &Ray, i: usize, hit: &PrimHit) -> (usize, (f32, f32, f32)) {
        if hit.exact {
            return (i, (hit.t, hit.u, hit.v));
        }
        self.settle_inexact_quad_hit(ray, i, hit)
    }

    /// `settle_quad_hit` for a hit the backend's own arithmetic found.
    #[inline(never)]
    fn settle_inexact_quad_hit(
        &self,
        ray: &Ray,
        i: usize,
        hit: &PrimHit,
    ) -> (usize, (f32, f32, f32)) {
        let exact = |k: usize, t_max: f32| {
            let q = &self.quads[k];
            if !self
                .culled_backs()
                .meets(PrimKind::Quad, q.normal, ray.direction)
            {
                return None;
            }
            intersect_quad(ray, t_max, &q.vertices)
        };
        let fallback = (i, (hit.t, hit.u, hit.v));
        let Some(own) = exact(i, f32::INFINITY) else {
            // The exact routine misses where the backend hit (the ray runs along the very
            // border): settle among the neighbours, else keep the backend's answer.
            return self
                .nearest_neighbour_hit(i, ray, &exact)
                .unwrap_or(fallback);
        };
        let (u, v) = (own.1, own.2);
        let near_border =
            u < EDGE_BAND || v < EDGE_BAND || u > 1.0 - EDGE_BAND || v > 1.0 - EDGE_BAND;
        if !near_border {
            return (i, own);
        }
        match self.nearest_neighbour_hit(i, ray, &exact) {
            Some(n) if n.1 .0 < own.0 || (n.1 .0 == own.0 && n.0 < i) => n,
            _ => (i, own),
        }
    }

    /// The closest exact hit among the quads sharing a vertex with quad `i` (ties to the
    /// lowest index).
    fn nearest_neighbour_hit(
        &self,
        i: usize,
        ray: &Ray,
        exact: &impl Fn(usize, f32) -> Option<(f32, f32, f32)>,
    ) -> Option<(usize, (f32, f32, f32))> {
        let mut best: Option<(usize, (f32, f32, f32))> = None;
        for &k in &self.quad_neighbours()[i] {
            let k = k as usize;
            if let Some(h) = exact(k, ray.t_max) {
                if best.is_none_or(|b| h.0 < b.1 .0 || (h.0 == b.1 .0 && k < b.0)) {
                    best = Some((k, h));
                }
            }
        }
        best
    }
}

/// For each quad, the other quads with a vertex at exactly the same position.
fn quad_adjacency(quads: &[super::Quad]) -> Vec<Vec<u32>> {
    use std::collections::HashMap;
    // Bit patterns as keys; adding 0.0 folds -0.0 into 0.0.
    let key = |p: Vec3| {
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]
    };
    let mut at_vertex: HashMap<[u32; 3], Vec<u32>> = HashMap::new();
    for (k, q) in quads.iter().enumerate() {
        for &p in &q.vertices {
            at_vertex.entry(key(p)).or_default().push(k as u32);
        }
    }
    quads
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let mut n: Vec<u32> = q
                .vertices
                .iter()
                .flat_map(|&p| at_vertex[&key(p)].iter().copied())
                .filter(|&j| j as usize != k)
                .collect();
            n.sort_unstable();
            n.dedup();
            n
        })
        .collect()
}

/// Bilinear interpolation of four corner values (corners in order (0,0), (1,0), (1,1), (0,1)).
pub fn bilinear(tc: &[Vec2; 4], u: f32, v: f32) -> Vec2 {
    let w = [(1.0 - u) * (1.0 - v), u * (1.0 - v), u * v, (1.0 - u) * v];
    vec2(
        tc.iter().zip(w).map(|(t, w)| t.x * w).sum(),
        tc.iter().zip(w).map(|(t, w)| t.y * w).sum(),
    )
}
