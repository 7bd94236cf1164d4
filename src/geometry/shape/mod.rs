//! Analytic shapes: surfaces given by an equation rather than by polygons. Both Accels
//! intersect them with the same exact routine (the BVH directly, Embree through its
//! user-geometry callbacks), and every engine asks them through the one `Shape` trait for
//! their surface, their samples and their tessellation.
//!
//! Adding a kind: a file here with its struct and `impl Shape`, a variant of `AnalyticShape`
//! and its arm in `each_shape!` (the compiler then points at nothing else), and the scene
//! keyword that makes one.

mod ring;
mod sphere;

pub use ring::{RingPart, RingShape};
pub use sphere::SphereShape;

use super::{Bounds3, Ray, Vec3};

/// How finely the radiosity mesh approximates each kind: the course's rasterization flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tessellation {
    /// Sphere: faces around the axis and from pole to pole (`-sphere_rasterization H V`,
    /// at least 3 × 2).
    pub sphere: (u32, u32),
    /// Ring: faces around the axis on each of its four surfaces
    /// (`-cylinder_ring_rasterization N`, at least 3).
    pub ring: u32,
}

/// A closed analytic surface made of one or more smooth parts (a sphere has one; a ring its
/// outer and inner walls and two caps), each parameterized over (u, v) ∈ \[0,1\]². Normals
/// point out of the solid.
pub trait Shape {
    /// The name `--plan` counts it under ("sphere").
    fn name(&self) -> &'static str;
    /// How many smooth parts it has; parts are numbered from 0.
    fn part_count(&self) -> u32;
    fn bounds(&self) -> Bounds3;
    /// The nearest hit in `(ray.t_min, t_max)` and the part it lies on.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)>;
    /// The part whose surface is nearest to `p` (for a hit a backend reported at the very
    /// edge of a part, where the exact routine misses).
    fn nearest_part(&self, p: Vec3) -> u32;
    /// `p` (near the surface) moved onto `part`, with the outward unit normal there.
    fn project(&self, p: Vec3, part: u32) -> (Vec3, Vec3);
    /// The outward unit normal at a point of `part`.
    fn normal_at(&self, p: Vec3, part: u32) -> Vec3;
    /// The parameters of a point of `part`; the inverse of `point_at`.
    fn uv_at(&self, p: Vec3, part: u32) -> (f32, f32);
    /// The point of `part` at parameters (u, v), exactly on the surface.
    fn point_at(&self, part: u32, u: f32, v: f32) -> Vec3;
    /// The size of the coordinates of its points, for their rounding-error bound.
    fn magnitude(&self) -> f32;
    fn area(&self) -> f32;
    /// A point uniformly distributed by area from (u, v) ∈ [0,1)², with its outward normal.
    fn sample(&self, u: f32, v: f32) -> (Vec3, Vec3);
    /// The point the course's single shadow ray aims at from `towards`, with its normal.
    fn point_towards(&self, towards: Vec3) -> (Vec3, Vec3);
    /// The radiosity mesh's grid of faces on each part: (columns in u, rows in v).
    fn grid(&self, tessellation: &Tessellation) -> (u32, u32);
    /// The shape under `p ↦ p · scale + offset` (`scale` > 0).
    fn scaled(&self, scale: f32, offset: Vec3) -> Self
    where
        Self: Sized;
}

/// Every kind of analytic shape a scene can hold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnalyticShape {
    Sphere(SphereShape),
    Ring(RingShape),
}

/// `$body` with `$s` bound to the shape inside whichever variant `$shape` is.
macro_rules! each_shape {
    ($shape:expr, $s:ident => $body:expr) => {
        match $shape {
            AnalyticShape::Sphere($s) => $body,
            AnalyticShape::Ring($s) => $body,
        }
    };
}

impl Shape for AnalyticShape {
    fn name(&self) -> &'static str {
        each_shape!(self, s => s.name())
    }
    fn part_count(&self) -> u32 {
        each_shape!(self, s => s.part_count())
    }
    fn bounds(&self) -> Bounds3 {
        each_shape!(self, s => s.bounds())
    }
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        each_shape!(self, s => s.intersect(ray, t_max))
    }
    fn nearest_part(&self, p: Vec3) -> u32 {
        each_shape!(self, s => s.nearest_part(p))
    }
    fn project(&self, p: Vec3, part: u32) -> (Vec3, Vec3) {
        each_shape!(self, s => s.project(p, part))
    }
    fn normal_at(&self, p: Vec3, part: u32) -> Vec3 {
        each_shape!(self, s => s.normal_at(p, part))
    }
    fn uv_at(&self, p: Vec3, part: u32) -> (f32, f32) {
        each_shape!(self, s => s.uv_at(p, part))
    }
    fn point_at(&self, part: u32, u: f32, v: f32) -> Vec3 {
        each_shape!(self, s => s.point_at(part, u, v))
    }
    fn magnitude(&self) -> f32 {
        each_shape!(self, s => s.magnitude())
    }
    fn area(&self) -> f32 {
        each_shape!(self, s => s.area())
    }
    fn sample(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        each_shape!(self, s => s.sample(u, v))
    }
    fn point_towards(&self, towards: Vec3) -> (Vec3, Vec3) {
        each_shape!(self, s => s.point_towards(towards))
    }
    fn grid(&self, tessellation: &Tessellation) -> (u32, u32) {
        each_shape!(self, s => s.grid(tessellation))
    }
    fn scaled(&self, scale: f32, offset: Vec3) -> Self {
        match self {
            AnalyticShape::Sphere(s) => AnalyticShape::Sphere(s.scaled(scale, offset)),
            AnalyticShape::Ring(s) => AnalyticShape::Ring(s.scaled(scale, offset)),
        }
    }
}

impl From<SphereShape> for AnalyticShape {
    fn from(s: SphereShape) -> Self {
        AnalyticShape::Sphere(s)
    }
}

impl From<RingShape> for AnalyticShape {
    fn from(s: RingShape) -> Self {
        AnalyticShape::Ring(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    fn shapes() -> [AnalyticShape; 2] {
        [
            SphereShape {
                centre: vec3(1.0, -2.0, 0.5),
                radius: 1.5,
            }
            .into(),
            RingShape {
                base: vec3(-1.0, 0.5, 2.0),
                height: 0.8,
                r_in: 0.6,
                r_out: 1.1,
            }
            .into(),
        ]
    }

    /// Parameters, points, normals and projection agree with each other on every part, and
    /// a ray aimed at a point of the surface from outside along its normal hits that point.
    #[test]
    fn every_shape_is_consistent_on_every_part() {
        for shape in shapes() {
            for part in 0..shape.part_count() {
                for (u, v) in [(0.1, 0.2), (0.4, 0.5), (0.85, 0.7)] {
                    let p = shape.point_at(part, u, v);
                    let (pu, pv) = shape.uv_at(p, part);
                    assert!(
                        (pu - u).abs() < 1e-4 && (pv - v).abs() < 1e-4,
                        "{shape:?} {part}"
                    );
                    let (q, n) = shape.project(p, part);
                    // Measured at most 1.2e-7 for both: one f32 spacing at 1. The bounds
                    // here are ten of those.
                    assert!((q - p).length() < 1.2e-6);
                    assert!((n - shape.normal_at(p, part)).length() < 1.2e-6);
                    assert_eq!(shape.nearest_part(p), part);
                    let n = shape.normal_at(p, part);
                    assert!((n.length() - 1.0).abs() < 1.2e-6);
                    let ray = Ray::new(p + n * 0.01, -n);
                    let (t, hit_part) = shape.intersect(&ray, f32::INFINITY).expect("hit");
                    // Measured at most 8.2e-8; the bound is ten times that.
                    assert!((t - 0.01).abs() < 8e-7, "{shape:?} part {part}: t {t}");
                    assert_eq!(hit_part, part);
                }
            }
        }
    }

    /// Samples lie on the surface, spread over the parts in proportion to their areas.
    #[test]
    fn samples_are_on_the_surface_and_uniform_by_area() {
        for shape in shapes() {
            let n = 4096;
            let mut per_part = vec![0u32; shape.part_count() as usize];
            for i in 0..n {
                let u = (i as f32 + 0.5) / n as f32;
                let v = ((i * 7919) % n) as f32 / n as f32;
                let (p, normal) = shape.sample(u, v);
                let part = shape.nearest_part(p);
                // Measured at most 2.9e-7; the bounds are ten times that.
                assert!((shape.project(p, part).0 - p).length() < 3e-6);
                assert!((shape.normal_at(p, part) - normal).length() < 3e-6);
                per_part[part as usize] += 1;
            }
            if let AnalyticShape::Ring(r) = shape {
                let areas = r.part_areas();
                for (k, &count) in per_part.iter().enumerate() {
                    let expected = areas[k] / shape.area() * n as f32;
                    assert!(
                        (count as f32 - expected).abs() < 0.02 * n as f32,
                        "part {k}"
                    );
                }
            }
        }
    }
}
