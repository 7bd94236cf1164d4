//! How surfaces scatter light, the one place every engine takes it from: the Lambertian lobe
//! (cosine-distributed sampling, its density), mirror reflection and the glossy Phong lobe
//! around it, and smooth dielectrics (glass: refraction, the exact Fresnel reflectance, total
//! internal reflection, one branch chosen by it or both weighted by it), and what a light
//! without area sends a surface.
//!
//! What each engine decides itself is which lobe to follow: the ray tracer follows mirrors
//! and both branches of glass and takes diffuse light from its indirect source; the path
//! tracer chooses a lobe in proportion to its largest channel, the photon tracer in proportion
//! to its mean (so that photon power stays unweighted). The photon tracer samples the diffuse
//! lobe as a Phong lobe of exponent 1 (`sample_lobe`), the path tracer by the concentric-disk
//! mapping (`diffuse_sample`): the same distribution through two mappings, kept so that the
//! images stay as they were; one mapping for both is a change of images to make on purpose.

use crate::geometry::{offset_ray_origin, shadow_ray, Ray, Vec3};
pub use crate::sampling::{orthonormal_basis, sample_cone};
use crate::scene::sky::Sky;
use crate::scene::{Color, DeltaLight, Material, Scene, SurfaceHit};

/// What a light without area sends the point of `s` lit on the side of unit normal `n`.
pub struct DeltaArrival {
    /// The unit direction towards the light.
    pub direction: Vec3,
    /// n · direction, above zero.
    pub cos: f32,
    /// The irradiance on a surface facing the light.
    pub irradiance: Color,
    /// The shadow ray to the light (along `direction` for a directional light) and the
    /// distance it spans (∞ for a directional light).
    pub ray: Ray,
    pub distance: f32,
}

impl DeltaArrival {
    /// What a surface takes of the irradiance: per unit albedo of a Lambertian one
    /// (`lobe` None), cos/π; per unit reflectance of a glossy `lobe`, its density.
    pub fn value(&self, lobe: Option<&GlossyLobe>) -> f32 {
        match lobe {
            None => self.cos / std::f32::consts::PI,
            Some(lobe) => lobe.pdf(self.direction),
        }
    }
}

/// What `light` sends the point of `s` lit on the side of `n`; None where it sends nothing
/// there or lies behind the surface. One shadow ray finds it: no sampling does.
pub fn delta_arrival(
    scene: &Scene,
    light: &DeltaLight,
    s: &SurfaceHit,
    n: Vec3,
) -> Option<DeltaArrival> {
    let origin = offset_ray_origin(s.point, n, s.error);
    delta_arrival_at(scene, light, (s.point, n), origin)
}

/// What `light` sends the surface point `x` lit on the side of unit normal `n`, its shadow
/// ray leaving from `origin` (`x` offset off the surface); None where it sends nothing there
/// or lies behind the surface.
pub fn delta_arrival_at(
    scene: &Scene,
    light: &DeltaLight,
    (x, n): (Vec3, Vec3),
    origin: Vec3,
) -> Option<DeltaArrival> {
    let (direction, distance, irradiance) = light.towards(x, &scene.textures)?;
    let cos = n.dot(direction);
    if cos.is_nan() || cos <= 0.0 {
        return None;
    }
    let ray = if distance.is_finite() {
        shadow_ray(origin, x + direction * distance)
    } else {
        Ray::new(origin, direction)
    };
    Some(DeltaArrival {
        direction,
        cos,
        irradiance,
        ray,
        distance,
    })
}

/// What each light without area sends the point of `s` lit on the side of `n`
/// (`delta_arrival`), for those that send it anything.
pub fn delta_arrivals<'a>(
    scene: &'a Scene,
    s: &'a SurfaceHit,
    n: Vec3,
) -> impl Iterator<Item = DeltaArrival> + 'a {
    (scene.delta_lights.iter()).filter_map(move |light| delta_arrival(scene, light, s, n))
}

/// A cosine-distributed direction about the unit normal `n`, from (u, v) in [0,1)², and its
/// density in solid angle, cos θ / π.
#[inline(always)]
pub fn diffuse_sample(n: Vec3, u: f32, v: f32) -> (Vec3, f32) {
    let (x, y) = crate::sampling::sample_disk(u, v);
    let cos = (1.0 - x * x - y * y).max(0.0).sqrt();
    let (tx, ty) = orthonormal_basis(n);
    (tx * x + ty * y + n * cos, cos / std::f32::consts::PI)
}

/// A direction from which `sky` lights a surface of unit normal `n`, from (u, v) in [0,1)²,
/// with the weight its radiance takes in the surface's irradiance over π, (cos/π)/density: a
/// map's directions by its importance (a bright sun would rarely be met by the cosine's), the
/// smooth skies' by the cosine, which weighs each by 1 (exact under a uniform sky). None for a
/// map's direction below the surface, or a black map.
pub fn sky_lighting_sample(sky: &Sky, n: Vec3, u: f32, v: f32) -> Option<(Vec3, f32)> {
    match sky.map() {
        Some(map) => map.sample_above(n, u, v),
        None => Some((diffuse_sample(n, u, v).0, 1.0)),
    }
}

/// A smooth dielectric boundary (glass) met by a ray: the indices on the side it arrives from
/// and beyond, and the Fresnel reflectance there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    pub eta_i: f32,
    pub eta_t: f32,
    /// Fresnel reflectance for the ray's angle: 1 under total internal reflection.
    pub reflectance: f32,
}

impl Dielectric {
    /// The boundary of material `m` met by a ray of direction `d` at a surface whose normal
    /// `n` faces the ray, from the front side (`front`: from the air into the material).
    pub fn at(m: &Material, front: bool, d: Vec3, n: Vec3) -> Dielectric {
        // Entering a closed surface from outside goes from air into the material.
        let (eta_i, eta_t) = if front { (1.0, m.ior) } else { (m.ior, 1.0) };
        Dielectric {
            eta_i,
            eta_t,
            reflectance: fresnel_dielectric(-d.dot(n), eta_i, eta_t),
        }
    }

    /// The refracted direction (unit), None under total internal reflection.
    pub fn refracted(&self, d: Vec3, n: Vec3) -> Option<Vec3> {
        refract(d, n, self.eta_i, self.eta_t).map(|t| t.normalize_or_zero())
    }

    /// One branch chosen with the Fresnel probability: the refracted direction with
    /// probability 1 − F, else the mirror direction (always under total internal reflection,
    /// where no random number is drawn). `next` draws the number in [0, 1).
    pub fn sample(&self, d: Vec3, n: Vec3, next: impl FnOnce() -> f32) -> Vec3 {
        match refract(d, n, self.eta_i, self.eta_t) {
            Some(t) if next() >= self.reflectance => t.normalize_or_zero(),
            _ => reflect(d, n),
        }
    }
}

/// `d` reflected about the unit normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

/// `d` (unit) refracted through a surface with unit normal `n` facing the incoming side, from
/// index `eta_i` into `eta_t`; None on total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta_i: f32, eta_t: f32) -> Option<Vec3> {
    let eta = eta_i / eta_t;
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(d * eta + n * (eta * cos_i - cos_t))
}

/// Fresnel reflectance of an unpolarised ray at a smooth dielectric boundary (the exact
/// formula, not Schlick's): `cos_i` of the incoming ray, indices on both sides. 1 under total
/// internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t = eta_i / eta_t * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let parallel = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    let perpendicular = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

/// The direction a mirror of the given roughness reflects `d` into about the unit normal
/// `n`: the mirror direction for roughness 0, else a sample of its `GlossyLobe`. (u, v) in
/// [0,1)².
pub fn glossy_reflection(d: Vec3, n: Vec3, roughness: f32, u: f32, v: f32) -> Vec3 {
    match GlossyLobe::new(d, n, roughness) {
        Some(lobe) => lobe.sample(u, v).0,
        None => reflect(d, n),
    }
}

/// The glossy lobe of a rough mirror: the Phong lobe of exponent 2/roughness² − 2 around the
/// mirror direction, a sample that falls below the surface taking the mirror direction
/// itself. Above the surface it is a density, which multiple importance sampling weighs
/// light samples against; the mirror direction's share is a delta no light sample can find.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlossyLobe {
    mirror: Vec3,
    n: Vec3,
    exponent: f32,
}

impl GlossyLobe {
    /// The lobe for direction `d` arriving at a surface of unit normal `n` (facing `d`);
    /// None for roughness 0, a perfect mirror.
    pub fn new(d: Vec3, n: Vec3, roughness: f32) -> Option<GlossyLobe> {
        (roughness > 0.0).then(|| GlossyLobe {
            mirror: reflect(d, n),
            n,
            exponent: (2.0 / (roughness * roughness) - 2.0).max(0.0),
        })
    }

    /// A direction from (u, v) in [0,1)², with its density in solid angle; None with the
    /// mirror direction when the lobe's sample fell below the surface.
    pub fn sample(&self, u: f32, v: f32) -> (Vec3, Option<f32>) {
        let g = sample_lobe(self.mirror, self.exponent, u, v);
        if g.dot(self.n) <= 0.0 {
            (self.mirror, None)
        } else {
            (g, Some(self.pdf(g)))
        }
    }

    /// The density in solid angle of the unit direction `w`, (e + 1)/(2π)·cos^e of its angle
    /// to the mirror direction; 0 below the surface.
    pub fn pdf(&self, w: Vec3) -> f32 {
        let cos = w.dot(self.mirror);
        if w.dot(self.n) <= 0.0 || cos <= 0.0 {
            return 0.0;
        }
        (self.exponent + 1.0) / std::f32::consts::TAU * cos.powf(self.exponent)
    }
}

/// The power heuristic's weight (β = 2) for a sample drawn with density `a` when another
/// strategy would have drawn it with density `b`.
#[inline(always)]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// A direction in the Phong lobe `cosⁿ` around the unit vector `axis`, from (u, v) in [0,1)².
pub fn sample_lobe(axis: Vec3, exponent: f32, u: f32, v: f32) -> Vec3 {
    let cos_t = u.powf(1.0 / (exponent + 1.0));
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    let (t, b) = orthonormal_basis(axis);
    (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize_or_zero()
}
