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

use super::settings::MAX_SURVIVAL;
use crate::accel::{closest_surface, Accel};
use crate::engines::scattering::{glossy_reflection, sample_cone, sample_lobe, Dielectric};
use crate::geometry::{offset_ray_origin, point_error, Ray, Vec3};
use crate::render::lights::Light;
use crate::sampling::Rng;
use crate::scene::{Color, Scene, SurfaceHit};

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

/// The emitters as photon sources: each chosen in proportion to its flux.
pub struct Emitters {
    lights: Vec<Light>,
    /// Flux of each light: π·Le·A for a one-sided Lambertian emitter, twice that for two
    /// sides.
    flux: Vec<Color>,
    /// The probability of choosing each light, and their running sum.
    probability: Vec<f32>,
    cdf: Vec<f64>,
}

impl Emitters {
    pub fn new(scene: &Scene) -> Emitters {
        let lights = Light::collect(scene);
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
        let probability = weights
            .iter()
            .map(|w| if total > 0.0 { (w / total) as f32 } else { 0.0 })
            .collect();
        let cdf = weights
            .iter()
            .scan(0.0, |acc, w| {
                *acc += w / total;
                Some(*acc)
            })
            .collect();
        Emitters {
            lights,
            flux,
            probability,
            cdf,
        }
    }

    /// Whether anything emits.
    pub fn any(&self) -> bool {
        self.flux.iter().any(|f| mean(*f) > 0.0)
    }

    /// Photon `k` of `count` with the generator it draws from, aimed as `aim` says, followed
    /// until absorbed (or `max_depth` bounces); `visit` hears every diffuse surface it
    /// reaches. Returns the rays it cast and whether the depth limit stopped it.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        count: u64,
        max_depth: u32,
        aim: Aim,
        rng: &mut Rng,
        visit: &mut dyn FnMut(&Hit),
    ) -> (u64, bool) {
        let pick = rng.next_f32() as f64;
        let l = self
            .cdf
            .iter()
            .position(|&c| pick < c)
            .unwrap_or(self.lights.len() - 1);
        let power = self.flux[l] * (self.probability[l] * count as f32).recip();
        trace_one(
            scene,
            accel,
            &self.lights[l],
            power,
            max_depth,
            aim,
            rng,
            visit,
        )
    }
}

/// A photon at a diffuse surface, as photon tracing reports it.
pub struct Hit<'a> {
    pub surface: &'a SurfaceHit,
    /// The normal on the side the photon arrived from.
    pub normal: Vec3,
    pub direction: Vec3,
    pub power: Color,
    pub kind: PathKind,
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
    let emitters = Emitters::new(scene);
    if count == 0 || !emitters.any() {
        return Traced {
            photons: Vec::new(),
            rays: 0,
            truncated: 0,
        };
    }
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
                let (r, cut) = emitters.trace(
                    scene,
                    accel,
                    count,
                    max_depth,
                    aim,
                    &mut rng,
                    &mut |hit: &Hit| {
                        stored.push(Photon {
                            position: hit.surface.point,
                            direction: hit.direction,
                            power: hit.power,
                            normal: hit.normal,
                            kind: hit.kind,
                        })
                    },
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
    visit: &mut dyn FnMut(&Hit),
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
            visit(&Hit {
                surface: &s,
                normal: n,
                direction: ray.direction,
                power,
                kind,
            });
        }
        if depth == max_depth {
            return (rays, true);
        }
        let (mut pd, mut pr, mut pt) = (
            albedo.max_element(),
            m.reflective.max_element(),
            m.transmitted.max_element(),
        );
        // Roulette keeps the photon with probability pd + pr + pt, at most MAX_SURVIVAL.
        let survive = pd + pr + pt;
        if survive > MAX_SURVIVAL {
            let cut = MAX_SURVIVAL / survive;
            (pd, pr, pt) = (pd * cut, pr * cut, pt * cut);
        }
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
