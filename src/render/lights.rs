//! The scene's emitters as area lights: every primitive whose material emits. Each can be
//! sampled uniformly by area, and has a centre for the course's one-shadow-ray mode.

use super::solid_angle::{SphericalRectangle, MIN_SOLID_ANGLE};
use crate::geometry::{AnalyticShape, Shape, Vec3};
use crate::scene::{Color, PrimKind, PrimRef, Scene};

/// Points on a light, a block at a time, as a structure of arrays: the loops over a block's
/// lanes compile to vector instructions.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointBlock {
    pub x: [f32; LANES],
    pub y: [f32; LANES],
    pub z: [f32; LANES],
}

/// Points in a `PointBlock`.
pub const LANES: usize = 8;

/// A planar parallelogram `origin + u·edge_u + v·edge_v`, emitting on its front side (on both
/// with `two_sided`); the first sampling axis runs along the longer edge (`swap_axes`: that
/// is `edge_v`), for N×1 strata.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parallelogram {
    origin: Vec3,
    edge_u: Vec3,
    edge_v: Vec3,
    normal: Vec3,
    /// It emits from its back too (`--two-sided`, as the quad is seen to glow and as
    /// radiosity's back patches emit).
    two_sided: bool,
    swap_axes: bool,
    /// The edges are perpendicular: the light can be sampled by solid angle.
    rectangle: bool,
}

impl Parallelogram {
    /// The parallelogram `origin + u·edge_u + v·edge_v` emitting towards its unit `normal`,
    /// and away from it too if `two_sided`.
    pub fn new(
        origin: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        normal: Vec3,
        two_sided: bool,
    ) -> Parallelogram {
        Parallelogram {
            origin,
            edge_u,
            edge_v,
            normal,
            two_sided,
            swap_axes: edge_v.length() > edge_u.length(),
            rectangle: edge_u.dot(edge_v).abs() <= 1e-5 * edge_u.length() * edge_v.length(),
        }
    }

    /// The point at (u, v) in [0,1)² of the sampling axes: uniform by area for uniform (u, v).
    #[inline(always)]
    pub fn sample(&self, u: f32, v: f32) -> LightPoint {
        let (u, v) = if self.swap_axes { (v, u) } else { (u, v) };
        LightPoint {
            point: self.origin + self.edge_u * u + self.edge_v * v,
            normal: self.normal,
            one_sided: !self.two_sided,
        }
    }

    /// The points `sample` gives for (`u[i]`, `v[i]`), lane by lane (the same arithmetic, so
    /// the same bits).
    #[inline(always)]
    pub fn sample_block(&self, u: &[f32; LANES], v: &[f32; LANES]) -> PointBlock {
        let (u, v) = if self.swap_axes { (v, u) } else { (u, v) };
        let (o, a, b) = (self.origin, self.edge_u, self.edge_v);
        let mut p = PointBlock::default();
        for i in 0..LANES {
            p.x[i] = o.x + a.x * u[i] + b.x * v[i];
            p.y[i] = o.y + a.y * u[i] + b.y * v[i];
            p.z[i] = o.z + a.z * u[i] + b.z * v[i];
        }
        p
    }

    /// The unit normal of the side that faces `x`, if that side emits: the front's, or the
    /// back's (the front's negated) on a two-sided light; None where `x` lies in its plane or
    /// behind a one-sided light (it sends `x` nothing).
    #[inline]
    pub fn normal_towards(&self, x: Vec3) -> Option<Vec3> {
        let side = (x - self.origin).dot(self.normal);
        if side > 0.0 {
            Some(self.normal)
        } else if side < 0.0 && self.two_sided {
            Some(-self.normal)
        } else {
            None
        }
    }

    /// The light as a spherical rectangle seen from `x`, to be sampled by solid angle; None
    /// when the side `x` is on does not emit (`normal_towards`), when its edges are not
    /// perpendicular (a parallelogram that is no rectangle: sampled by area), or when it
    /// subtends less than `MIN_SOLID_ANGLE`. The first sampling axis runs along the longer
    /// edge, as in `sample`.
    #[inline]
    pub fn spherical_rectangle(&self, x: Vec3) -> Option<SphericalRectangle> {
        self.normal_towards(x)?;
        if !self.rectangle {
            return None;
        }
        let (a, b) = (self.edge_u, self.edge_v);
        let (first, second) = if self.swap_axes { (b, a) } else { (a, b) };
        SphericalRectangle::new(x, self.origin, first, second)
            .filter(|r| r.solid_angle() >= MIN_SOLID_ANGLE)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightShape {
    Parallelogram(Parallelogram),
    /// A triangle `v0 + u·e1 + v·e2` (u + v ≤ 1), emitting from the side its `normal`
    /// (e1 × e2) faces, or from both with `two_sided`: as it is seen (`Scene::sees_emission`)
    /// and as radiosity's patches emit.
    Triangle {
        v0: Vec3,
        e1: Vec3,
        e2: Vec3,
        normal: Vec3,
        two_sided: bool,
    },
    /// An analytic shape, emitting outwards.
    Shape(AnalyticShape),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub shape: LightShape,
    /// Emitted radiance.
    pub emitted: Color,
    pub area: f32,
    pub prim: PrimRef,
}

/// The light of triangle `prim` of world vertices `[a, b, c]`, emitting `emitted` (from both
/// sides with `--two-sided`).
fn triangle_light(scene: &Scene, [a, b, c]: [Vec3; 3], emitted: Color, prim: PrimRef) -> Light {
    let n = (b - a).cross(c - a);
    let two_sided = scene.two_sided_quads;
    Light {
        shape: LightShape::Triangle {
            v0: a,
            e1: b - a,
            e2: c - a,
            normal: n.normalize_or_zero(),
            two_sided,
        },
        emitted,
        area: 0.5 * n.length(),
        prim,
    }
}

/// The lights chosen in proportion to their power, max(Le) × area: next-event estimation's
/// choice of light in the path tracer, and in SPPM and the ray tracer on scenes of more
/// than `EVERY_LIGHT_UP_TO` lights.
pub struct LightPower {
    /// The running sum of the probabilities, light by light (all 0 where nothing emits).
    cdf: Vec<f32>,
}

/// Scenes with at most this many lights sample every light at every point (SPPM, the ray
/// tracer): choosing one of a few lights at random multiplies the noise (SPPM's furnace of
/// six walls gave pixels 12% off after 32 passes, where a point on each gave a few
/// percent); choosing among many keeps the cost per point bounded (an emitting mesh of 32,512
/// triangles took the ray tracer over 300 s for 16 samples of 128×128 pixels).
pub const EVERY_LIGHT_UP_TO: usize = 64;

impl LightPower {
    pub fn new(lights: &[Light]) -> LightPower {
        let mut cdf = Vec::with_capacity(lights.len());
        let mut total = 0.0;
        for l in lights {
            total += l.emitted.max_element() * l.area;
            cdf.push(total);
        }
        if total > 0.0 {
            cdf.iter_mut().for_each(|c| *c /= total);
        }
        LightPower { cdf }
    }

    /// Whether any light emits, so that there is one to choose. A total that overflowed
    /// (NaN once divided) still counts: the samples it gives are non-finite, and so counted
    /// and left out where the image is made, not silently dark.
    pub fn any(&self) -> bool {
        self.cdf.last().is_some_and(|&t| t > 0.0 || t.is_nan())
    }

    /// The probability of choosing light `k`.
    pub fn probability(&self, k: usize) -> f32 {
        self.cdf[k] - if k == 0 { 0.0 } else { self.cdf[k - 1] }
    }

    /// The light `x` in [0, 1) chooses (where `any`).
    pub fn choose(&self, x: f32) -> usize {
        self.cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1)
    }
}

/// A point on a light with its outward unit normal; `one_sided` lights emit only where
/// `normal · direction > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    pub point: Vec3,
    pub normal: Vec3,
    pub one_sided: bool,
}

impl Light {
    /// Emitters of the scene, in primitive order.
    pub fn collect(scene: &Scene) -> Vec<Light> {
        let mut lights = Vec::new();
        let emitted = |m: u32| scene.materials[m as usize].emitted;
        for (i, q) in scene.quads.iter().enumerate() {
            let e = emitted(q.material);
            if e.max_element() > 0.0 {
                let [v0, v1, _, v3] = q.vertices;
                lights.push(Light {
                    shape: LightShape::Parallelogram(Parallelogram::new(
                        v0,
                        v1 - v0,
                        v3 - v0,
                        q.normal,
                        scene.two_sided_quads,
                    )),
                    emitted: e,
                    area: q.area(),
                    prim: prim(PrimKind::Quad, i),
                });
            }
        }
        for i in 0..scene.triangles.len() {
            let e = emitted(scene.triangles.materials[i]);
            if e.max_element() > 0.0 {
                let vertices = scene.triangles.vertices(i);
                lights.push(triangle_light(
                    scene,
                    vertices,
                    e,
                    prim(PrimKind::Triangle, i),
                ));
            }
        }
        for (i, s) in scene.shapes.iter().enumerate() {
            let e = emitted(s.material);
            if e.max_element() > 0.0 {
                lights.push(Light {
                    shape: LightShape::Shape(s.shape),
                    emitted: e,
                    area: s.shape.area(),
                    prim: prim(PrimKind::Shape, i),
                });
            }
        }
        // Instanced triangles last, as their kind orders (the Mitsuba reader refuses emitters
        // in a shapegroup, but a light is whatever emits). A group's emitting triangles are
        // found once, however many instances place it: asking each instanced triangle's
        // material took 1.3 s of a 1.5 s render of 1,024 instances of a 69k-triangle mesh.
        let instancing = &scene.instancing;
        let emitting: Vec<Vec<usize>> = instancing
            .groups
            .iter()
            .map(|g| {
                (0..g.mesh.len())
                    .filter(|&j| emitted(g.mesh.materials[j]).max_element() > 0.0)
                    .collect()
            })
            .collect();
        for instance in &instancing.instances {
            let group = instancing.group_of(instance);
            for &j in &emitting[instance.group as usize] {
                lights.push(triangle_light(
                    scene,
                    instancing.placed(instance, j),
                    emitted(group.mesh.materials[j]),
                    prim(PrimKind::Instanced, instance.first as usize + j),
                ));
            }
        }
        lights
    }

    /// The index in `lights` (from `collect`, so in primitive order) of the light that is
    /// primitive `prim`: how a ray that finds an emitter learns which light's sampling could
    /// have chosen it. A binary search: hashing the primitive cost the path tracer 0.8% of
    /// its time on the Cornell box.
    pub fn index_of(lights: &[Light], prim: PrimRef) -> Option<usize> {
        lights.binary_search_by_key(&prim, |l| l.prim).ok()
    }

    /// The point used by the course's single shadow ray (and by the unshadowed mode): the
    /// centre of a planar light, the point of a sphere or ring nearest to `towards`.
    pub fn centre(&self, towards: Vec3) -> LightPoint {
        match self.shape {
            LightShape::Parallelogram(q) => q.sample(0.5, 0.5),
            LightShape::Triangle {
                v0,
                e1,
                e2,
                normal,
                two_sided,
            } => LightPoint {
                point: v0 + (e1 + e2) * (1.0 / 3.0),
                normal,
                one_sided: !two_sided,
            },
            LightShape::Shape(shape) => {
                let (point, normal) = shape.point_towards(towards);
                LightPoint {
                    point,
                    normal,
                    one_sided: true,
                }
            }
        }
    }

    /// A point uniformly distributed by area, from (u, v) in [0,1)².
    ///
    /// Always inlined: as a call, the path tracer's wavefront, which draws one at every
    /// vertex, took the point back through memory.
    #[inline(always)]
    pub fn sample(&self, u: f32, v: f32) -> LightPoint {
        match self.shape {
            LightShape::Parallelogram(q) => q.sample(u, v),
            LightShape::Triangle {
                v0,
                e1,
                e2,
                normal,
                two_sided,
            } => {
                // Fold the unit square onto the triangle.
                let (a, b) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                LightPoint {
                    point: v0 + e1 * a + e2 * b,
                    normal,
                    one_sided: !two_sided,
                }
            }
            LightShape::Shape(shape) => {
                let (point, normal) = shape.sample(u, v);
                LightPoint {
                    point,
                    normal,
                    one_sided: true,
                }
            }
        }
    }
}

/// A light seen from a shading point, sampled by the solid angle it subtends there: the
/// weights stay bounded however near the light the shading point is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolidAngleSampler {
    /// A rectangle: Ureña, Fajardo & King's spherical rectangle.
    Rectangle(SphericalRectangle),
    /// A sphere seen from outside: the cone of directions that meet it (pbrt's and Mitsuba's
    /// sphere sampling), Ω = 2π(1 − cos θmax).
    Cone {
        origin: Vec3,
        centre: Vec3,
        radius: f32,
        axis: Vec3,
        cos_max: f32,
        solid_angle: f64,
    },
}

impl SolidAngleSampler {
    /// The solid angle the light subtends (steradians).
    pub fn solid_angle(&self) -> f64 {
        match self {
            SolidAngleSampler::Rectangle(r) => r.solid_angle(),
            SolidAngleSampler::Cone { solid_angle, .. } => *solid_angle,
        }
    }

    /// A point of the light for the shading point of unit normal `n` (on its lit side), from
    /// (u, v) in [0,1)²; None where it lies below the receiver's horizon. Rectangles: uniform
    /// in solid angle across the longer edge and in proportion to the receiver's cosine
    /// along it, so that unoccluded the estimate varies only with u. Spheres: uniform in the
    /// cone, each point weighing cosθ·Ω/π. Bounded weights however near the light `x` is.
    pub fn sample_towards(&self, n: Vec3, u: f32, v: f32) -> Option<DirectSample> {
        match *self {
            SolidAngleSampler::Rectangle(r) => {
                let s = r.sample_cosine(n, u, v)?;
                Some(DirectSample {
                    point: s.point,
                    weight: s.weight as f32,
                    pdf: s.pdf as f32,
                })
            }
            SolidAngleSampler::Cone {
                origin,
                centre,
                radius,
                axis,
                cos_max,
                solid_angle,
            } => {
                // The nearer crossing of the sphere along the direction, the discriminant held
                // at zero where rounding puts a direction at the rim just outside.
                let dir = crate::sampling::sample_cone(axis, cos_max, u, v);
                let to_centre = centre - origin;
                let b = dir.dot(to_centre);
                let c = to_centre.length_squared() - radius * radius;
                let t = b - (b * b - c).max(0.0).sqrt();
                let cos = n.dot(dir);
                (cos > 0.0).then(|| DirectSample {
                    point: origin + dir * t,
                    weight: (solid_angle / std::f64::consts::PI) as f32 * cos,
                    pdf: (1.0 / solid_angle) as f32,
                })
            }
        }
    }

    /// The density in solid angle with which `sample_towards` (receiver normal `n`) gives
    /// the direction towards `p`, a point of the light.
    pub fn pdf_towards(&self, n: Vec3, p: Vec3) -> f32 {
        match self {
            SolidAngleSampler::Rectangle(r) => r.pdf_cosine(n, p) as f32,
            SolidAngleSampler::Cone { solid_angle, .. } => (1.0 / solid_angle) as f32,
        }
    }
}

/// A point on a light for next-event estimation from a shading point: where the shadow ray
/// goes, what the light sends through it per unit of emitted radiance, as irradiance / π (so
/// that reflected radiance is albedo × Le × `weight`, unoccluded), and the density in solid
/// angle with which its direction was chosen (for multiple importance sampling).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSample {
    pub point: Vec3,
    pub weight: f32,
    pub pdf: f32,
}

impl Light {
    /// The light seen from `x`, to be sampled by solid angle: a rectangle (seen from its
    /// front, subtending at least `MIN_SOLID_ANGLE`) or a sphere seen from outside (likewise);
    /// None for the rest, which are sampled by area.
    #[inline]
    pub fn solid_angle_sampler(&self, x: Vec3) -> Option<SolidAngleSampler> {
        match self.shape {
            LightShape::Parallelogram(quad) => quad
                .spherical_rectangle(x)
                .map(SolidAngleSampler::Rectangle),
            LightShape::Shape(AnalyticShape::Sphere(sphere)) => {
                let to_centre = (sphere.centre - x).as_dvec3();
                let d2 = to_centre.length_squared();
                let r2 = (sphere.radius as f64).powi(2);
                if d2 <= r2 * (1.0 + 1e-4) {
                    return None;
                }
                // 1 − cos θmax without the cancellation of 1 − √(1 − sin²).
                let sin2 = r2 / d2;
                let cos_max = (1.0 - sin2).sqrt();
                let solid_angle = std::f64::consts::TAU * sin2 / (1.0 + cos_max);
                (solid_angle >= MIN_SOLID_ANGLE).then(|| SolidAngleSampler::Cone {
                    origin: x,
                    centre: sphere.centre,
                    radius: sphere.radius,
                    axis: (to_centre / d2.sqrt()).as_vec3(),
                    cos_max: cos_max as f32,
                    solid_angle,
                })
            }
            _ => None,
        }
    }

    /// One point of this light for next-event estimation from `x` inside a medium (no
    /// receiver cosine to follow): uniform in the solid angle a rectangle subtends, which
    /// keeps the weight bounded however near the light `x` is; by area on other lights. The
    /// density is in solid angle (`pdf_from_medium` gives it for any point).
    pub fn sample_from_medium(&self, x: Vec3, u: f32, v: f32) -> Option<DirectSample> {
        let Some(SolidAngleSampler::Rectangle(rect)) = self.solid_angle_sampler(x) else {
            return self.sample_by_area(x, u, v);
        };
        let pdf = (1.0 / rect.solid_angle()) as f32;
        (pdf.is_finite() && pdf > 0.0).then(|| DirectSample {
            point: rect.sample(u, v),
            weight: pdf.recip(),
            pdf,
        })
    }

    /// The density in solid angle with which `sample_from_medium` from `x` gives the point
    /// `p` of this light, of unit normal `normal` there.
    pub fn pdf_from_medium(&self, x: Vec3, p: Vec3, normal: Vec3) -> f32 {
        match self.solid_angle_sampler(x) {
            Some(SolidAngleSampler::Rectangle(rect)) => (1.0 / rect.solid_angle()) as f32,
            _ => self.pdf_by_area(x, p, normal),
        }
    }

    /// One point of this light for the shading point `x` with unit normal `n` (on its lit
    /// side), from (u, v) in [0,1)²: by `SolidAngleSampler::sample_towards` where
    /// `solid_angle_sampler` gives one, else uniform by area (cosθ·cosθ'·A/(π·r²)). None
    /// where the point sends `x` nothing (behind either surface).
    pub fn sample_towards(&self, x: Vec3, n: Vec3, u: f32, v: f32) -> Option<DirectSample> {
        match self.solid_angle_sampler(x) {
            Some(sampler) => sampler.sample_towards(n, u, v),
            None => self.sample_by_area_towards(x, n, u, v),
        }
    }

    /// One point of this light uniform by area for the shading point `x` with unit normal
    /// `n` (on its lit side), whatever the light's shape: weight cosθ·cosθ'·A/(π·r²), which
    /// grows without bound near the light, density r²/(cosθ'·A). None where the point sends
    /// `x` nothing.
    pub fn sample_by_area_towards(&self, x: Vec3, n: Vec3, u: f32, v: f32) -> Option<DirectSample> {
        let (point, w, r2, cos_light) = self.area_point(x, u, v)?;
        let cos = n.dot(w) / r2.sqrt();
        (cos > 0.0).then(|| DirectSample {
            point,
            weight: cos * cos_light * self.area / (std::f32::consts::PI * r2),
            pdf: r2 / (cos_light * self.area),
        })
    }

    /// One point of this light uniform by area, for a point `x` in a medium (no surface, no
    /// cosine of its own): `weight` is cosθ'·A/r² (the solid angle per unit of `u, v`), `pdf`
    /// its inverse. None where the point faces away from `x`.
    pub fn sample_by_area(&self, x: Vec3, u: f32, v: f32) -> Option<DirectSample> {
        let (point, _, r2, cos_light) = self.area_point(x, u, v)?;
        let pdf = r2 / (cos_light * self.area);
        (pdf.is_finite() && pdf > 0.0).then(|| DirectSample {
            point,
            weight: pdf.recip(),
            pdf,
        })
    }

    /// The point at (u, v) uniform by area, the vector to it from `x`, its squared length and
    /// the light's cosine towards `x`; None where that cosine is not positive.
    fn area_point(&self, x: Vec3, u: f32, v: f32) -> Option<(Vec3, Vec3, f32, f32)> {
        let p = self.sample(u, v);
        let w = p.point - x;
        let r2 = w.length_squared();
        let cos_light = -p.normal.dot(w) / r2.sqrt();
        let cos_light = if p.one_sided {
            cos_light
        } else {
            cos_light.abs()
        };
        (r2 > 0.0 && cos_light > 0.0).then_some((p.point, w, r2, cos_light))
    }

    /// The density in solid angle with which `sample_by_area` from `x` gives the point `p`
    /// of this light, of unit normal `normal` there.
    pub fn pdf_by_area(&self, x: Vec3, p: Vec3, normal: Vec3) -> f32 {
        let w = p - x;
        let r2 = w.length_squared();
        let cos_light = (normal.dot(w) / r2.sqrt()).abs();
        if cos_light <= 0.0 || r2 <= 0.0 {
            return 0.0;
        }
        r2 / (cos_light * self.area)
    }

    /// The density in solid angle with which `sample_towards` from `x` (receiver normal
    /// `n`) gives the point `p` of this light, of unit normal `normal` there: what multiple
    /// importance sampling weighs a direction that found the light by other means with.
    pub fn pdf_towards(&self, x: Vec3, n: Vec3, p: Vec3, normal: Vec3) -> f32 {
        match self.solid_angle_sampler(x) {
            Some(sampler) => sampler.pdf_towards(n, p),
            None => self.pdf_by_area(x, p, normal),
        }
    }
}

fn prim(kind: PrimKind, index: usize) -> PrimRef {
    PrimRef {
        kind,
        index: index as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `index_of` finds each light of a scene that mixes emitting and dark quads and
    /// spheres, and no light for a dark primitive: `collect` lists the lights in the order
    /// its binary search assumes. (The course dialect has no triangles; `collect` lists
    /// them between the two, as `PrimKind` orders them.)
    #[test]
    fn every_light_is_found_by_its_primitive() {
        let text = "material\ndiffuse 0.5 0.5 0.5\nemitted 0 0 0\n\
                    material\ndiffuse 0 0 0\nemitted 1 1 1\n\
                    v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                    m 1\nf 1 2 3 4\nm 0\nf 1 2 3 4\nm 1\nf 1 2 3 4\n\
                    m 1\ns 0 0 3 0.5\nm 0\ns 0 0 5 0.5\nm 1\ns 0 0 7 0.5\n";
        let scene = Scene::parse_dialect(std::path::Path::new("t.obj"), text).expect("parses");
        let lights = Light::collect(&scene);
        let kinds: Vec<PrimKind> = lights.iter().map(|l| l.prim.kind).collect();
        use PrimKind::{Quad, Shape};
        assert_eq!(kinds, [Quad, Quad, Shape, Shape]);
        for (k, l) in lights.iter().enumerate() {
            assert_eq!(Light::index_of(&lights, l.prim), Some(k));
        }
        for dark in [prim(Quad, 1), prim(PrimKind::Triangle, 0), prim(Shape, 1)] {
            assert_eq!(Light::index_of(&lights, dark), None);
        }
    }
}
