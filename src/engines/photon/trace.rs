//! Photon tracing: photons leave the emitters with probability proportional to emitted
//! power, from uniform points, in cosine-weighted directions, all with equal power; at each
//! surface a photon on a diffuse surface is stored, then Russian roulette on the albedos
//! (diffuse, mirror, transmitted) decides whether it goes on, with its power rescaled so the
//! estimate stays unbiased.
//!
//! A second pass (Jensen's caustic photons) aims photons only at a sphere around the mirrors
//! and glass, each carrying the power that the narrower choice of directions leaves it, and
//! follows them only until their first diffuse hit: the same count puts many times more
//! photons into the caustics, so the caustic estimate gathers from a smaller radius.

use rayon::prelude::*;

use crate::accel::{closest_surface, Accel};
use crate::engines::scattering::{glossy_reflection, sample_cone, sample_lobe, Dielectric};
use crate::geometry::{offset_ray_origin, point_error, Ray, Vec3};
use crate::render::lights::Light;
use crate::sampling::Rng;
use crate::scene::{Color, Scene};

/// How a stored photon got where it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum PathKind {
    /// Straight from a light (L D): the ray tracer computes this light itself.
    Direct = 0,
    /// Through one or more mirrors or glass only (L S+ D): a caustic.
    Caustic = 1,
    /// After at least one diffuse bounce (L .* D .* D).
    Indirect = 2,
}

/// A photon stored on a diffuse surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    pub position: Vec3,
    /// Direction of travel (unit).
    pub direction: Vec3,
    /// Power (flux, W) per channel.
    pub power: Color,
    /// Geometric normal of the surface, turned towards the side the photon came from.
    pub normal: Vec3,
    pub kind: PathKind,
}

/// Where photons leave the lights for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    /// Cosine-weighted over each emitter's hemisphere, followed until absorbed: every path.
    Everywhere,
    /// Uniformly within the cone from the emitting point to this sphere (which bounds the
    /// specular surfaces), and followed only while no diffuse bounce has happened: the
    /// caustic paths L S+ D. Photons that leave from inside the sphere use the full
    /// cosine-weighted hemisphere.
    Caustics { centre: Vec3, radius: f32 },
}

/// Photons emitted per parallel task.
const BLOCK: u64 = 4096;

/// Mean of the three channels: the probability Russian roulette gives an albedo.
fn mean(c: Color) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// What tracing the photons gave: those stored, in a fixed order, and counters.
pub struct Traced {
    pub photons: Vec<Photon>,
    pub rays: u64,
    /// Photons still carrying power when `--max-photon-depth` stopped them: their light is
    /// lost (a bias the furnace shows at high albedo), so it is reported.
    pub truncated: u64,
}

/// Traces `count` photons aimed as `aim` says. Photon k draws from hash(seed, k): the result
/// does not depend on threads.
pub fn trace_photons(
    scene: &Scene,
    accel: &dyn Accel,
    count: u64,
    max_depth: u32,
    aim: Aim,
    seed: u64,
    on_block: impl Fn() + Sync,
) -> Traced {
    let lights = Light::collect(scene);
    // Flux of each light: π·Le·A for a one-sided Lambertian emitter, twice that for two sides.
    let flux: Vec<Color> = lights
        .iter()
        .map(|l| {
            let sides = if l.sample(0.5, 0.5).one_sided {
                1.0
            } else {
                2.0
            };
            l.emitted * (std::f32::consts::PI * l.area * sides)
        })
        .collect();
    let weights: Vec<f64> = flux.iter().map(|f| mean(*f) as f64).collect();
    let total: f64 = weights.iter().sum();
    if count == 0 || total <= 0.0 {
        return Traced {
            photons: Vec::new(),
            rays: 0,
            truncated: 0,
        };
    }
    let cdf: Vec<f64> = weights
        .iter()
        .scan(0.0, |acc, w| {
            *acc += w / total;
            Some(*acc)
        })
        .collect();
    let blocks = count.div_ceil(BLOCK);
    let results: Vec<Traced> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            let mut stored = Vec::new();
            let (mut rays, mut truncated) = (0, 0);
            // After Ctrl-C the blocks not yet traced are skipped.
            let end = if crate::interrupt::requested() {
                b * BLOCK
            } else {
                ((b + 1) * BLOCK).min(count)
            };
            for k in b * BLOCK..end {
                let stream = match aim {
                    Aim::Everywhere => 0x9407,
                    Aim::Caustics { .. } => 0xca05,
                };
                let mut rng = Rng::new(seed, k, stream);
                let pick = rng.next_f32() as f64;
                let l = cdf
                    .iter()
                    .position(|&c| pick < c)
                    .unwrap_or(lights.len() - 1);
                let probability = (weights[l] / total) as f32;
                let power = flux[l] * (probability * count as f32).recip();
                let (r, cut) = trace_one(
                    scene,
                    accel,
                    &lights[l],
                    power,
                    max_depth,
                    aim,
                    &mut rng,
                    &mut stored,
                );
                rays += r;
                truncated += cut as u64;
            }
            on_block();
            Traced {
                photons: stored,
                rays,
                truncated,
            }
        })
        .collect();
    Traced {
        rays: results.iter().map(|r| r.rays).sum(),
        truncated: results.iter().map(|r| r.truncated).sum(),
        photons: results.into_iter().flat_map(|r| r.photons).collect(),
    }
}

/// Follows one photon from a light until it is absorbed; returns the rays it cast and whether
/// the depth limit stopped it.
#[allow(clippy::too_many_arguments)]
fn trace_one(
    scene: &Scene,
    accel: &dyn Accel,
    light: &Light,
    mut power: Color,
    max_depth: u32,
    aim: Aim,
    rng: &mut Rng,
    stored: &mut Vec<Photon>,
) -> (u64, bool) {
    let p = light.sample(rng.next_f32(), rng.next_f32());
    let mut normal = p.normal;
    if !p.one_sided && rng.next_f32() < 0.5 {
        normal = -normal;
    }
    let (u, v) = (rng.next_f32(), rng.next_f32());
    // Towards the specular sphere: the cone's axis and the sine of its half-angle, unless
    // the photon leaves from inside the sphere.
    let cone = match aim {
        Aim::Caustics { centre, radius } => {
            let to = centre - p.point;
            let d = to.length();
            (d > radius).then(|| (to * d.recip(), radius / d))
        }
        Aim::Everywhere => None,
    };
    let dir = match cone {
        Some((axis, sin_max)) => {
            // Uniform in the cone of solid angle Ω: the power becomes Le·cosθ·A·Ω per photon
            // instead of the cosine-weighted photon's π·Le·A (per side), a factor cosθ·Ω/π.
            let cos_max = (1.0 - sin_max * sin_max).max(0.0).sqrt();
            let dir = sample_cone(axis, cos_max, u, v);
            let facing = p.normal.dot(dir);
            if facing == 0.0 || (p.one_sided && facing < 0.0) {
                return (0, false);
            }
            normal = if facing > 0.0 { p.normal } else { -p.normal };
            let solid_angle = std::f32::consts::TAU * (1.0 - cos_max);
            let sides = if p.one_sided { 1.0 } else { 2.0 };
            power *= facing.abs() * solid_angle / (std::f32::consts::PI * sides);
            dir
        }
        None => sample_lobe(normal, 1.0, u, v),
    };
    let caustics_only = matches!(aim, Aim::Caustics { .. });
    let origin = offset_ray_origin(p.point, normal, point_error(p.point.abs().max_element()));
    let mut ray = Ray::new(origin, dir);
    let mut any_diffuse = false;
    let mut rays = 0;
    for depth in 0..=max_depth {
        rays += 1;
        let Some(s) = closest_surface(accel, scene, &ray) else {
            break;
        };
        let m = &scene.materials[s.material as usize];
        let (front, n) = s.facing(ray.direction);
        let albedo = scene.albedo(&s);
        if albedo.max_element() > 0.0 && !(caustics_only && depth == 0) {
            let kind = if depth == 0 {
                PathKind::Direct
            } else if any_diffuse {
                PathKind::Indirect
            } else {
                PathKind::Caustic
            };
            stored.push(Photon {
                position: s.point,
                direction: ray.direction,
                power,
                normal: n,
                kind,
            });
        }
        if depth == max_depth {
            return (rays, true);
        }
        let (pd, pr, pt) = (mean(albedo), mean(m.reflective), mean(m.transmitted));
        let xi = rng.next_f32();
        let dir = if xi < pd {
            if caustics_only {
                // Every later hit would be indirect light: not this pass's business.
                break;
            }
            power = power * albedo * pd.recip();
            any_diffuse = true;
            sample_lobe(n, 1.0, rng.next_f32(), rng.next_f32())
        } else if xi < pd + pr {
            power = power * m.reflective * pr.recip();
            glossy_reflection(
                ray.direction,
                n,
                m.roughness,
                rng.next_f32(),
                rng.next_f32(),
            )
        } else if xi < pd + pr + pt {
            power = power * m.transmitted * pt.recip();
            Dielectric::at(m, front, ray.direction, n).sample(ray.direction, n, rng)
        } else {
            break;
        };
        ray = s.spawn_ray(dir);
    }
    (rays, false)
}
