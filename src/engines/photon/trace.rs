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
use crate::geometry::{offset_ray_origin, point_error, Bounds3, Ray, Vec3};
use crate::render::lights::Light;
use crate::sampling::{orthonormal_basis, sample_disk, Rng};
use crate::scene::medium::Flight;
use crate::scene::sky::Sky;
use crate::scene::{Color, DeltaKind, DeltaLight, Scene, Texture};

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

/// The sky as a photon source: photons from a disk the size of a sphere around the scene,
/// facing the direction they come from, so every line through the sphere is as likely.
struct SkySource {
    sky: Sky,
    centre: Vec3,
    radius: f32,
}

impl SkySource {
    /// The flux the sky sends through a sphere of radius R: π·R²·∫ L dω.
    fn flux(&self) -> Color {
        self.sky.integral() * (std::f32::consts::PI * self.radius * self.radius)
    }

    /// A photon from the sky through the sphere (`centre`, `radius`): a direction uniform over
    /// the sphere of directions (by the map's importance for a map), a point uniform on the
    /// disk across it. Returns its ray and its power for a unit chance of being chosen:
    /// L(ω)·π·r²/p(ω) (uniform directions: p = 1/(4π)), or None for a black map.
    fn emit(&self, centre: Vec3, radius: f32, rng: &mut Rng) -> Option<(Ray, Color)> {
        let (u, v) = (rng.next_f32(), rng.next_f32());
        // The direction, and 1/density (the uniform sphere's: 4π).
        let (towards, per_density) = match self.sky.map() {
            Some(map) => {
                let (d, density) = map.sample(u, v)?;
                (d, density.recip())
            }
            None => (sample_cone(Vec3::Y, -1.0, u, v), 4.0 * std::f32::consts::PI),
        };
        let ray = ray_through_disk((centre, radius), towards, rng.next_f32(), rng.next_f32());
        let area = std::f32::consts::PI * radius * radius;
        let power = self.sky.radiance(towards) * (per_density * area);
        Some((ray, power))
    }
}

/// A light without area as a photon source (a Mitsuba scene's point, spot or directional
/// light); a directional light's photons cross the disk across the sphere around the scene
/// (`centre`, `radius`), as the sky's do.
struct DeltaSource {
    light: DeltaLight,
    centre: Vec3,
    radius: f32,
}

impl DeltaSource {
    /// The cone a point or spot light's photons leave in, uniformly: its axis and the cosine
    /// of its half-angle (the whole sphere for a point light). Caustic photons leave in it
    /// too: aimed or not, each carries the power its direction's density leaves it.
    fn cone(&self) -> (Vec3, f32) {
        match self.light.kind {
            DeltaKind::Spot { axis, cutoff, .. } => (axis, cutoff.cos()),
            _ => (Vec3::Y, -1.0),
        }
    }

    /// The flux the source is chosen by: a point or spot light's intensity over its cone
    /// (a spot's ramp and texture only lower it: the photons' own power is exact), a
    /// directional light's irradiance over the disk.
    fn flux(&self) -> Color {
        match self.light.kind {
            DeltaKind::Directional { .. } => {
                self.light.intensity * (std::f32::consts::PI * self.radius * self.radius)
            }
            _ => self.light.intensity * (std::f32::consts::TAU * (1.0 - self.cone().1)),
        }
    }

    /// A photon: its ray and its power for a unit chance of being chosen. From a point or a
    /// spot, I(ω)·Ω over the cone of solid angle Ω; through the disk, E·π·r².
    fn emit(&self, textures: &[Texture], rng: &mut Rng) -> Option<(Ray, Color)> {
        let (u, v) = (rng.next_f32(), rng.next_f32());
        match self.light.kind {
            DeltaKind::Directional { direction } => {
                let ray = ray_through_disk((self.centre, self.radius), -direction, u, v);
                Some((ray, self.flux()))
            }
            DeltaKind::Point { position } | DeltaKind::Spot { position, .. } => {
                let (axis, cos_max) = self.cone();
                let dir = sample_cone(axis, cos_max, u, v);
                // The irradiance at unit distance along `dir` is the intensity there.
                let (_, _, intensity) = self.light.towards(position + dir, textures)?;
                let solid_angle = std::f32::consts::TAU * (1.0 - cos_max);
                Some((Ray::new(position, dir), intensity * solid_angle))
            }
        }
    }
}

/// A ray arriving from the unit direction `towards` through a point uniform (from `u`, `v`) on
/// the disk across the sphere (`centre`, `radius`) that faces it: every line through the
/// sphere in that direction is as likely. The sky's photons and a directional light's.
fn ray_through_disk((centre, radius): (Vec3, f32), towards: Vec3, u: f32, v: f32) -> Ray {
    let (dx, dy) = sample_disk(u, v);
    let (t, b) = orthonormal_basis(towards);
    let origin = centre + (towards + t * dx + b * dy) * radius;
    Ray::new(origin, -towards)
}

/// The emitters as photon sources: each light, each light without area, and the sky, chosen
/// in proportion to its flux.
pub struct Emitters {
    lights: Vec<Light>,
    deltas: Vec<DeltaSource>,
    /// The sky, unless there is none or the fog hides it (it is infinite).
    sky: Option<SkySource>,
    /// Flux of each light: π·Le·A for a one-sided Lambertian emitter, twice that for two
    /// sides; then each light without area's (`DeltaSource::flux`); then the sky's.
    flux: Vec<Color>,
    /// The probability of choosing each source, and their running sum.
    probability: Vec<f32>,
    cdf: Vec<f64>,
}

impl Emitters {
    pub fn new(scene: &Scene) -> Emitters {
        let lights = Light::collect(scene);
        let bounds = scene.bounds();
        // A little beyond the bounds, so that no photon from the sky or a directional light
        // starts inside the scene.
        let (centre, radius) = (bounds.centre(), 0.5 * bounds.extent().length() * 1.01);
        let deltas: Vec<DeltaSource> = scene
            .delta_lights
            .iter()
            .map(|&light| DeltaSource {
                light,
                centre,
                radius,
            })
            .collect();
        let sky = scene
            .sky
            .as_ref()
            .filter(|_| scene.fog.is_none())
            .map(|sky| SkySource {
                sky: sky.clone(),
                centre,
                radius,
            });
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
            .chain(deltas.iter().map(DeltaSource::flux))
            .chain(sky.as_ref().map(SkySource::flux))
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
            deltas,
            sky,
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
    /// reaches and every point where it scatters in the fog. Returns the rays it cast and
    /// whether the depth limit stopped it.
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
        // A scene with nothing that emits has no source to pick: no photon, rather than an
        // index into an empty list.
        let Some(last) = self.flux.len().checked_sub(1) else {
            return (0, false);
        };
        let pick = rng.next_f32() as f64;
        let l = self.cdf.iter().position(|&c| pick < c).unwrap_or(last);
        let chosen = (self.probability[l] * count as f32).recip();
        let delta = l
            .checked_sub(self.lights.len())
            .and_then(|k| self.deltas.get(k));
        let emitted = match (self.lights.get(l), delta, &self.sky) {
            (Some(light), _, _) => emit_from_light(light, aim, rng)
                .map(|(ray, factor)| (ray, self.flux[l] * factor * chosen)),
            (None, Some(source), _) => source
                .emit(&scene.textures, rng)
                .map(|(ray, power)| (ray, power * chosen)),
            (None, None, Some(sky)) => {
                // Caustic photons come through the sphere around the mirrors and glass.
                let (centre, radius) = match aim {
                    Aim::Caustics { centre, radius } => (centre, radius),
                    Aim::Everywhere => (sky.centre, sky.radius),
                };
                sky.emit(centre, radius, rng)
                    .map(|(ray, power)| (ray, power * chosen))
            }
            (None, None, None) => None,
        };
        let Some((ray, power)) = emitted else {
            return (0, false);
        };
        let caustics_only = matches!(aim, Aim::Caustics { .. });
        follow(
            scene,
            accel,
            ray,
            power,
            max_depth,
            caustics_only,
            rng,
            visit,
        )
    }
}

/// A photon where it is stored: on a diffuse surface, or where it scattered in the fog.
pub struct Hit {
    pub point: Vec3,
    /// The normal on the side the photon arrived from (zero in the fog).
    pub normal: Vec3,
    pub direction: Vec3,
    pub power: Color,
    pub kind: PathKind,
    /// Whether it scattered in the fog (a volume photon) rather than met a surface.
    pub in_medium: bool,
}

/// The photons traced: those stored on surfaces and in the fog, in a fixed order, and
/// counters.
pub struct Traced {
    pub photons: Vec<Photon>,
    /// Where photons scattered in the fog.
    pub volume: Vec<Photon>,
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
    let emitters = Emitters::new(scene);
    if count == 0 || !emitters.any() {
        return Traced {
            photons: Vec::new(),
            volume: Vec::new(),
            rays: 0,
            truncated: 0,
        };
    }
    // Volume photons are kept only where camera and mirror rays can look them up: in the
    // scene's bounds and the camera's, padded. Photons that wander into the fog beyond are
    // still followed (they may come back), but not stored: in an open scene most of an
    // infinite fog's scattering happens there (on the fog Cornell box, 10M of 1M photons'
    // events), and its light reaches the image only along rays that leave the scene.
    let region = {
        let b = scene.bounds().union_point(scene.camera().position);
        let pad = Vec3::splat(0.05 * b.extent().length());
        Bounds3 {
            min: b.min - pad,
            max: b.max + pad,
        }
    };
    let blocks = count.div_ceil(BLOCK);
    let results: Vec<Traced> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            let (mut stored, mut volume) = (Vec::new(), Vec::new());
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
                        let photon = Photon {
                            position: hit.point,
                            direction: hit.direction,
                            power: hit.power,
                            normal: hit.normal,
                            kind: hit.kind,
                        };
                        if hit.in_medium {
                            if region.contains(hit.point) {
                                volume.push(photon);
                            }
                        } else {
                            stored.push(photon);
                        }
                    },
                );
                rays += r;
                truncated += cut as u64;
            }
            on_block();
            Traced {
                photons: stored,
                volume,
                rays,
                truncated,
            }
        })
        .collect();
    let mut traced = Traced {
        photons: Vec::new(),
        volume: Vec::new(),
        rays: results.iter().map(|r| r.rays).sum(),
        truncated: results.iter().map(|r| r.truncated).sum(),
    };
    for r in results {
        traced.photons.extend(r.photons);
        traced.volume.extend(r.volume);
    }
    traced
}

/// A photon leaving `light`: its ray, and the factor its share of the light's flux is
/// multiplied by (1 for the cosine-weighted hemisphere; see below for the cone towards the
/// mirrors and glass); None when the chosen direction does not leave the light.
fn emit_from_light(light: &Light, aim: Aim, rng: &mut Rng) -> Option<(Ray, f32)> {
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
    let (dir, factor) = match cone {
        Some((axis, sin_max)) => {
            // Uniform in the cone of solid angle Ω: the power becomes Le·cosθ·A·Ω per photon
            // instead of the cosine-weighted photon's π·Le·A (per side), a factor cosθ·Ω/π.
            let cos_max = (1.0 - sin_max * sin_max).max(0.0).sqrt();
            let dir = sample_cone(axis, cos_max, u, v);
            let facing = p.normal.dot(dir);
            if facing == 0.0 || (p.one_sided && facing < 0.0) {
                return None;
            }
            normal = if facing > 0.0 { p.normal } else { -p.normal };
            let solid_angle = std::f32::consts::TAU * (1.0 - cos_max);
            let sides = if p.one_sided { 1.0 } else { 2.0 };
            (
                dir,
                facing.abs() * solid_angle / (std::f32::consts::PI * sides),
            )
        }
        None => (sample_lobe(normal, 1.0, u, v), 1.0),
    };
    let origin = offset_ray_origin(p.point, normal, point_error(p.point.abs().max_element()));
    Some((Ray::new(origin, dir), factor))
}

/// Follows a photon from where it was emitted until it is absorbed; returns the rays it cast
/// and whether the depth limit stopped it. In the fog each segment's free flight is sampled
/// (`Medium::sample_flight`): where it scatters, the photon is stored and goes on in a
/// direction of the phase function, after Russian roulette on the scattering's weight.
/// Every surface bounce and every scattering counts towards `max_depth`.
#[allow(clippy::too_many_arguments)]
fn follow(
    scene: &Scene,
    accel: &dyn Accel,
    mut ray: Ray,
    mut power: Color,
    max_depth: u32,
    caustics_only: bool,
    rng: &mut Rng,
    visit: &mut dyn FnMut(&Hit),
) -> (u64, bool) {
    let fog = scene.fog.map(|k| &scene.media[k]);
    // Lights and the camera are in the fog; glass carries a photon into an object's interior
    // medium (or none) and back.
    let mut medium = fog;
    // Inside glass of index n the photons are stored with power/n²: the ray tracer carries
    // radiance through refraction without the n² factors (as the path tracer does, whose
    // factors cancel over a closed path), so its lookups inside must be in those units. The
    // physical radiance inside is n² times larger (the same flux in a narrower cone); without
    // this the glass sphere filled with a medium came out 2.0× the path tracer's inside.
    let mut radiance_scale = 1.0f32;
    // Whether a diffuse bounce or a scattering in the fog has happened.
    let mut any_diffuse = false;
    let mut rays = 0;
    for depth in 0..=max_depth {
        // A photon that carries nothing (on the Cornell box, one the red wall left red, after
        // the blue wall) would only be stored as zeros that take places among a lookup's k
        // nearest: it ends, as the path tracer's black paths do.
        if power.max_element() == 0.0 {
            break;
        }
        rays += 1;
        let hit = closest_surface(accel, scene, &ray);
        let kind = if depth == 0 {
            PathKind::Direct
        } else if any_diffuse {
            PathKind::Indirect
        } else {
            PathKind::Caustic
        };
        if let Some(medium) = medium {
            let t_surface = hit
                .as_ref()
                .map_or(f32::INFINITY, |s| s.point.distance(ray.origin));
            match medium.sample_flight(t_surface, power, rng.next_f32(), rng.next_f32()) {
                Flight::Scattered { t, weight } => {
                    if caustics_only {
                        // A scattered photon's later hits are not caustics.
                        break;
                    }
                    power *= weight;
                    let point = ray.origin + ray.direction * t;
                    visit(&Hit {
                        point,
                        normal: Vec3::ZERO,
                        direction: ray.direction,
                        power: power * radiance_scale,
                        kind,
                        in_medium: true,
                    });
                    if depth == max_depth {
                        return (rays, true);
                    }
                    // Roulette on the scattering's weight (the medium's albedo in a grey fog).
                    let survive = weight.max_element().min(MAX_SURVIVAL);
                    if rng.next_f32() >= survive {
                        break;
                    }
                    power *= survive.recip();
                    any_diffuse = true;
                    let (dir, _) =
                        medium.sample_phase(ray.direction, rng.next_f32(), rng.next_f32());
                    ray = Ray::new(point, dir);
                    continue;
                }
                Flight::Passed { weight } => power *= weight,
            }
        }
        let Some(s) = hit else {
            break;
        };
        let m = &scene.materials[s.material as usize];
        let (front, n) = s.facing(ray.direction);
        let albedo = scene.albedo(&s);
        if albedo.max_element() > 0.0 && !(caustics_only && depth == 0) {
            visit(&Hit {
                point: s.point,
                normal: s.geometric_side(n),
                direction: ray.direction,
                power: power * radiance_scale,
                kind,
                in_medium: false,
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
            let dir = sample_lobe(n, 1.0, rng.next_f32(), rng.next_f32());
            if m.bump.is_some() && !s.leaves_on_side_of(n, dir) {
                break;
            }
            dir
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
            let dir = Dielectric::at(m, front, ray.direction, n)
                .sample(ray.direction, n, || rng.next_f32());
            if dir.dot(n) < 0.0 {
                // Refracted: into an object (its interior medium), or out of one.
                medium = scene.medium_beyond(m, front);
                radiance_scale = if front { (m.ior * m.ior).recip() } else { 1.0 };
            }
            dir
        } else {
            break;
        };
        ray = s.spawn_ray(dir);
    }
    (rays, false)
}
