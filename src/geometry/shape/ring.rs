//! The cylindrical ring of the course dialect: the solid between two coaxial cylinders, with
//! four parts (outer wall, inner wall, bottom and top annulus), each parameterized by the
//! angle u around the axis and by the height (walls) or the radial position (caps) v.

use super::{Shape, Tessellation};
use crate::geometry::{vec3, Bounds3, Ray, Vec3};

/// Which surface of a ring a point lies on; `part as u32` is its `Shape` part number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RingPart {
    Outer,
    Inner,
    Bottom,
    Top,
}

impl RingPart {
    /// Every part, in the order of their numbers.
    pub const ALL: [RingPart; 4] = [
        RingPart::Outer,
        RingPart::Inner,
        RingPart::Bottom,
        RingPart::Top,
    ];

    /// The part numbered `part`; a number a ring does not have is a bug, not a fifth part.
    fn of(part: u32) -> RingPart {
        RingPart::ALL[part as usize]
    }
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
    /// The areas of the four parts, in part order.
    pub fn part_areas(&self) -> [f32; 4] {
        let tau = std::f32::consts::TAU;
        let cap = 0.5 * tau * (self.r_out * self.r_out - self.r_in * self.r_in);
        [
            tau * self.r_out * self.height,
            tau * self.r_in * self.height,
            cap,
            cap,
        ]
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
}

impl Shape for RingShape {
    fn name(&self) -> &'static str {
        "ring"
    }

    fn part_count(&self) -> u32 {
        4
    }

    fn bounds(&self) -> Bounds3 {
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

    /// The nearest hit over the four surfaces.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut limit = t_max;
        for (radius, part) in [(self.r_out, RingPart::Outer), (self.r_in, RingPart::Inner)] {
            if let Some(t) = self.intersect_wall(ray, limit, radius) {
                best = Some((t, part as u32));
                limit = t;
            }
        }
        for (y, part) in [
            (self.base.y, RingPart::Bottom),
            (self.base.y + self.height, RingPart::Top),
        ] {
            if let Some(t) = self.intersect_cap(ray, limit, y) {
                best = Some((t, part as u32));
                limit = t;
            }
        }
        best
    }

    fn nearest_part(&self, p: Vec3) -> u32 {
        let rho = ((p.x - self.base.x).powi(2) + (p.z - self.base.z).powi(2)).sqrt();
        let distances = [
            (rho - self.r_out).abs(),
            (rho - self.r_in).abs(),
            (p.y - self.base.y).abs(),
            (p.y - self.base.y - self.height).abs(),
        ];
        (0..4)
            .min_by(|&a, &b| distances[a].total_cmp(&distances[b]))
            .unwrap_or(0) as u32
    }

    fn project(&self, p: Vec3, part: u32) -> (Vec3, Vec3) {
        let q = match RingPart::of(part) {
            part @ (RingPart::Outer | RingPart::Inner) => {
                let radius = if part == RingPart::Outer {
                    self.r_out
                } else {
                    self.r_in
                };
                let radial = vec3(p.x - self.base.x, 0.0, p.z - self.base.z).normalize_or_zero();
                vec3(
                    self.base.x + radial.x * radius,
                    p.y,
                    self.base.z + radial.z * radius,
                )
            }
            RingPart::Bottom => Vec3 {
                y: self.base.y,
                ..p
            },
            RingPart::Top => Vec3 {
                y: self.base.y + self.height,
                ..p
            },
        };
        (q, self.normal_at(q, part))
    }

    fn normal_at(&self, p: Vec3, part: u32) -> Vec3 {
        let radial = vec3(p.x - self.base.x, 0.0, p.z - self.base.z).normalize_or_zero();
        match RingPart::of(part) {
            RingPart::Outer => radial,
            RingPart::Inner => -radial,
            RingPart::Bottom => vec3(0.0, -1.0, 0.0),
            RingPart::Top => vec3(0.0, 1.0, 0.0),
        }
    }

    fn uv_at(&self, p: Vec3, part: u32) -> (f32, f32) {
        let (x, z) = (p.x - self.base.x, p.z - self.base.z);
        let u = (z.atan2(x) / std::f32::consts::TAU).rem_euclid(1.0);
        let v = match RingPart::of(part) {
            RingPart::Outer | RingPart::Inner => (p.y - self.base.y) / self.height,
            RingPart::Bottom | RingPart::Top => {
                ((x * x + z * z).sqrt() - self.r_in) / (self.r_out - self.r_in)
            }
        };
        (u, v.clamp(0.0, 1.0))
    }

    fn point_at(&self, part: u32, u: f32, v: f32) -> Vec3 {
        let phi = std::f32::consts::TAU * u;
        let (sin_p, cos_p) = phi.sin_cos();
        let (radius, y) = match RingPart::of(part) {
            RingPart::Outer => (self.r_out, self.height * v),
            RingPart::Inner => (self.r_in, self.height * v),
            RingPart::Bottom => (self.r_in + (self.r_out - self.r_in) * v, 0.0),
            RingPart::Top => (self.r_in + (self.r_out - self.r_in) * v, self.height),
        };
        self.base + vec3(radius * cos_p, y, radius * sin_p)
    }

    fn magnitude(&self) -> f32 {
        self.base.abs().max_element() + self.r_out + self.height
    }

    fn area(&self) -> f32 {
        self.part_areas().iter().sum()
    }

    /// `u` picks the part in proportion to its area and is then reused within it.
    fn sample(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        let areas = self.part_areas();
        let total: f32 = areas.iter().sum();
        let mut x = u * total;
        let mut part = 3;
        for (k, a) in areas.iter().enumerate() {
            if x < *a {
                part = k;
                break;
            }
            x -= a;
        }
        let w = (x / areas[part]).clamp(0.0, 1.0);
        let phi = std::f32::consts::TAU * v;
        let radial = vec3(phi.cos(), 0.0, phi.sin());
        let point = match RingPart::ALL[part] {
            p @ (RingPart::Outer | RingPart::Inner) => {
                let radius = if p == RingPart::Outer {
                    self.r_out
                } else {
                    self.r_in
                };
                self.base + radial * radius + vec3(0.0, w * self.height, 0.0)
            }
            p @ (RingPart::Bottom | RingPart::Top) => {
                // Uniform in the annulus: radius² uniform between r_in² and r_out².
                let r2 = self.r_in * self.r_in;
                let rho = (r2 + w * (self.r_out * self.r_out - r2)).sqrt();
                let y = if p == RingPart::Top { self.height } else { 0.0 };
                self.base + radial * rho + vec3(0.0, y, 0.0)
            }
        };
        (point, self.normal_at(point, part as u32))
    }

    /// The point of the outer wall at mid-height nearest to `towards`.
    fn point_towards(&self, towards: Vec3) -> (Vec3, Vec3) {
        let n = vec3(towards.x - self.base.x, 0.0, towards.z - self.base.z).normalize_or_zero();
        let middle = vec3(self.base.x, self.base.y + 0.5 * self.height, self.base.z);
        (middle + n * self.r_out, n)
    }

    fn grid(&self, tessellation: &Tessellation) -> (u32, u32) {
        (tessellation.ring.max(3), 1)
    }

    fn scaled(&self, scale: f32, offset: Vec3) -> Self {
        RingShape {
            base: self.base * scale + offset,
            height: self.height * scale,
            r_in: self.r_in * scale,
            r_out: self.r_out * scale,
        }
    }
}
