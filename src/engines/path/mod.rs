//! The unbiased reference path tracer, the yardstick every error figure is measured against.
//!
//! At each diffuse vertex: next-event estimation (one light chosen in proportion to its power,
//! one point on it by the solid angle it subtends — rectangles uniform across and by the
//! receiver's cosine along, spheres uniform in their cone — or by area for the rest)
//! combined with cosine-weighted sampling of the Lambertian BRDF by multiple importance
//! sampling (power heuristic); glossy lobes likewise, against their Phong lobe. Mirrors,
//! glossy lobes and glass are sampled as in the ray tracer, one branch at a time (glass
//! chooses reflection with the Fresnel probability). Paths end by Russian roulette on their
//! throughput from the sixth vertex on (`ROULETTE_FROM`), which keeps the estimate unbiased,
//! and at once when their throughput turns black.
//! `-num_antialias_samples` is the number of paths per pixel; every random number comes from
//! (seed, pixel, sample): after the camera ray, each draw of a path from a dimension of its
//! own of the pixel's scrambled Sobol points (`PathSamples`), so that a pixel's paths spread
//! their light points and bounce directions evenly. The background colour is seen, not a
//! light: a path that leaves the scene after a diffuse bounce brings nothing back.

mod wavefront;

use super::engine::{Budget, Engine, EngineKind, RenderSettings, Rendered};
use super::scattering::{
    delta_arrivals, diffuse_sample, orthonormal_basis, power_heuristic, reflect, Dielectric,
    GlossyLobe,
};
use crate::accel::{closest_surface, Accel};
use crate::film::Film;
use crate::geometry::{offset_ray_origin, shadow_ray, Ray, Vec3};
use crate::render::lights::{Light, LightPower};
use crate::render::{render_pixel_batches, render_pixels, Counts, RenderStats};
use crate::sampling::{LightSampling, PathSamples};
use crate::scene::bsdf::Bsdf;
use crate::scene::medium::{Flight, Medium};
use crate::scene::sky::Sky;
use crate::scene::{Color, PrimRef, Scene, ShadingTilt, SurfaceHit};

/// Vertices after which Russian roulette may end a path (0-based: the sixth vertex is the
/// first it may end at). From the third, the Cornell box's relMSE at 64
/// paths a pixel was 22–24% higher (by solid angle 5.37e-3 against 4.33e-3, by area 7.83e-3
/// against 6.39e-3) for somewhat less time a path. Mitsuba 3's `rr_depth = 5` is one vertex
/// earlier (its depth is counted after the bounce, `depth >= rr_depth`): 4 here. Measured
/// by area at 64 paths a pixel against a 16k-path Mitsuba reference, 4 gave
/// Mitsuba's relMSE (0.99× its 7.10e-3, against 0.90×) in 0.94× the time: time × error no
/// better (0.59 of Mitsuba's efficiency against 0.61), so 5 stays.
const ROULETTE_FROM: u32 = 5;

/// The path tracer's light sampling when `--light-sampling` is not given: by area (`random`).
/// A point by solid angle (the spherical rectangle's inversion at every vertex) costs a
/// rendered path about twice the time of a point by area, more than it saves in error: by
/// area, time × relMSE was 0.73–0.96 of solid angle's on every course scene (BENCHMARKS.md,
/// "Light sampling in the path tracer").
pub const DEFAULT_LIGHT_SAMPLING: LightSampling = LightSampling::Random;
/// The largest survival probability of Russian roulette. Survival is the path throughput's
/// largest channel, so the throughput stays near 1 and the estimate has no heavy tail; the cap
/// only keeps a perfectly white closed room finite. (A cap of 0.95 let throughput grow as
/// (ρ/0.95)^k: the ρ = 0.99 furnace came out at 90.4 instead of 100 with 4096 paths a pixel.)
const MAX_SURVIVAL: f32 = 0.999;
/// Paths the wavefront follows together (`wavefront.rs`). On the Cornell box
/// without the vertex kernel, 256 took 0.88× the time of 4096 (the whole chunk of camera
/// samples of `render_pixels`, whose state no longer fits the caches) and 16 took 1.18×;
/// with it, 128, 512 and 1024 were within 3% of 256.
const WAVEFRONT_PATHS: usize = 256;
/// Index-matched boundaries a shadow ray crosses at most (it is blocked after them).
const MAX_CROSSINGS: u32 = 64;
/// A hard bound on path length, far beyond what roulette lets through (reached with
/// probability 0.999^20000 < 1e-8 even in a closed white room).
const MAX_VERTICES: u32 = 20_000;

/// The path tracer's estimator, for callers that want the radiance along rays of their own:
/// `render` follows camera rays with it; a per-patch reference for radiosity follows rays
/// that end on the patches' points (tests/hierarchical.rs).
pub struct PathTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    lights: Vec<Light>,
    /// Which light next-event estimation takes.
    power: LightPower,
    /// Scatterings a path may take (`--max-depth`; default `MAX_VERTICES`, which roulette
    /// never lets a path reach).
    max_depth: u32,
    /// Next-event estimation by area on every light (`--light-sampling random`), as Mitsuba
    /// and pbrt's path tracers do, rather than by solid angle and the receiver's cosine on
    /// rectangles and spheres (the default): on the Cornell box about 0.6× the time a path
    /// for 1.5× the relMSE at equal paths, and no bound on a sample's weight near a light.
    by_area: bool,
    /// The scene has index-matched boundaries (Mitsuba's `null`): shadow rays cross them,
    /// taking each medium's transmittance on the way, as Mitsuba's volumetric path tracer's
    /// do; elsewhere a surface in the way blocks a shadow ray. Set too where a medium is
    /// heterogeneous, whose transmittance `crossing_transmittance` estimates along the ray
    /// (the other shadow rays take a homogeneous medium's from the distance alone).
    crosses_boundaries: bool,
    /// The widest SIMD instructions this processor has (the wavefront's vertex kernel).
    arch: pulp::Arch,
}

/// The random numbers of one light sample (`PathTracer::draw_light`): the light's index and
/// the point's (u, v).
#[derive(Clone, Copy)]
struct LightDraw {
    k: usize,
    u: f32,
    v: f32,
}

/// The lobes of a material a path may scatter in.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Lobe {
    Diffuse,
    /// A mirror or a glossy lobe.
    Reflective,
    /// Glass.
    Transmitted,
}

/// A light sample before its shadow ray is traced: the ray, and the radiance the sample
/// brings (weighted) if nothing blocks it.
struct ShadowedSample<'m> {
    shadow_ray: Ray,
    radiance: Color,
    /// The medium the ray starts in, where shadow rays cross boundaries (`crosses_boundaries`:
    /// the radiance is then without its transmittance, which the crossing gives).
    medium: Option<&'m Medium>,
}

/// What the previous vertex of a path tells the next: where it was and with what density the
/// direction was chosen (None after a specular bounce or at the camera).
#[derive(Clone, Copy)]
struct Previous {
    point: Vec3,
    /// The normal the direction was sampled about (light sampling's density depends on it).
    normal: Vec3,
    bsdf_pdf: Option<f32>,
    /// The vertex scattered in a medium: lights were sampled from it by `sample_from_medium`.
    in_medium: bool,
}

impl PathTracer<'_> {
    pub fn new<'a>(scene: &'a Scene, accel: &'a dyn Accel) -> PathTracer<'a> {
        let lights = Light::collect(scene);
        PathTracer {
            scene,
            accel,
            power: LightPower::new(&lights),
            lights,
            max_depth: MAX_VERTICES,
            by_area: false,
            crosses_boundaries: scene
                .materials
                .iter()
                .any(|m| m.straight_transmission(1.0) != Color::ZERO)
                || scene.media.iter().any(|m| m.heterogeneous.is_some()),
            arch: crate::simd::arch(),
        }
    }

    /// The same tracer with the lights sampled as `--light-sampling` says: by area for
    /// `random`, by solid angle (where a light's shape allows) otherwise.
    pub fn with_light_sampling(self, sampling: LightSampling) -> Self {
        PathTracer {
            by_area: !sampling.by_solid_angle(),
            ..self
        }
    }

    /// The same tracer with paths cut after `max_depth` scatterings (surface bounces of every
    /// kind and scatterings in a medium; pbrt's `maxdepth`): 0 shows what emits, 1 direct
    /// light and single scattering. None: no limit but roulette's.
    pub fn with_max_depth(self, max_depth: Option<u32>) -> Self {
        PathTracer {
            max_depth: max_depth.map_or(MAX_VERTICES, |d| d.min(MAX_VERTICES)),
            ..self
        }
    }

    fn selection_probability(&self, k: usize) -> f32 {
        self.power.probability(k)
    }

    /// Solid-angle density with which next-event estimation picks the direction from `from`
    /// to `hit` on light `k`.
    fn light_pdf(&self, k: usize, from: &Previous, hit: &SurfaceHit) -> f32 {
        let light = &self.lights[k];
        self.selection_probability(k)
            * if from.in_medium {
                light.pdf_from_medium(from.point, hit.point, hit.geometric_normal)
            } else if self.by_area {
                light.pdf_by_area(from.point, hit.point, hit.geometric_normal)
            } else {
                light.pdf_towards(from.point, from.normal, hit.point, hit.geometric_normal)
            }
    }

    /// One light, chosen in proportion to its power, and its index (the only light without a
    /// draw).
    fn choose_light(&self, samples: &mut PathSamples) -> Option<usize> {
        if !self.power.any() {
            return None;
        }
        if self.lights.len() == 1 {
            return Some(0);
        }
        Some(self.power.choose(samples.next_1d()))
    }

    /// Next-event estimation at a point `x` of `medium` reached travelling along the unit
    /// `travel`: in-scattered radiance per unit σs-weighted throughput from one light point
    /// (uniform in a rectangle's solid angle, by area on other lights), with the
    /// transmittance to it, weighted against sampling the phase function by the power
    /// heuristic.
    fn sample_light_in_medium(
        &self,
        x: Vec3,
        travel: Vec3,
        medium: &Medium,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let from_lights = self.sample_area_light_in_medium(x, travel, medium, samples, counts);
        let Some((sky, (u, v))) = self.scene.sky.as_ref().zip(self.draw_sky(samples)) else {
            return from_lights;
        };
        let Some((dir, pdf)) = medium_sky_sample(sky, u, v) else {
            return from_lights;
        };
        let phase = medium.phase(travel, dir);
        let seen = self.shadow_transmittance(
            &Ray::new(x, dir),
            f32::INFINITY,
            Some(medium),
            samples,
            counts,
        );
        from_lights + sky.radiance(dir) * seen * (phase / pdf * power_heuristic(pdf, phase))
    }

    /// `sample_light_in_medium`'s light sample on the area lights.
    fn sample_area_light_in_medium(
        &self,
        x: Vec3,
        travel: Vec3,
        medium: &Medium,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let Some(k) = self.choose_light(samples) else {
            return Vec3::ZERO;
        };
        let light = &self.lights[k];
        let (u, v) = samples.next_2d();
        let Some(d) = light.sample_from_medium(x, u, v) else {
            return Vec3::ZERO;
        };
        let to_light = d.point - x;
        let distance = to_light.length();
        let phase = medium.phase(travel, to_light / distance);
        let light_pdf = self.selection_probability(k) * d.pdf;
        self.scene.emitted_at(light.prim, d.point)
            * self.shadow_transmittance(
                &shadow_ray(x, d.point),
                distance,
                Some(medium),
                samples,
                counts,
            )
            * (phase / light_pdf * power_heuristic(light_pdf, phase))
    }

    /// The random numbers of next-event estimation at a surface point of primitive `prim`:
    /// the light, and the point on it (None without lights, or when the light chosen is the
    /// surface itself, which draws no point).
    fn draw_light(&self, prim: PrimRef, samples: &mut PathSamples) -> Option<LightDraw> {
        let k = self.choose_light(samples)?;
        if self.lights[k].prim == prim {
            return None;
        }
        let (u, v) = samples.next_2d();
        Some(LightDraw { k, u, v })
    }

    /// The random numbers of `sample_sky` (None without a sky).
    fn draw_sky(&self, samples: &mut PathSamples) -> Option<(f32, f32)> {
        self.scene.sky.as_ref().map(|_| samples.next_2d())
    }

    /// What the light sample `sample` brings where its shadow ray is not blocked (nothing
    /// without a sample).
    fn unblocked(
        &self,
        sample: Option<ShadowedSample>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let Some(sample) = sample else {
            return Vec3::ZERO;
        };
        if self.crosses_boundaries {
            return sample.radiance
                * self.crossing_transmittance(&sample.shadow_ray, sample.medium, samples, counts);
        }
        counts.shadow += 1;
        if self.accel.occluded(&sample.shadow_ray) {
            return Vec3::ZERO;
        }
        sample.radiance
    }

    /// Next-event estimation at a diffuse point (`lobe` None) or in a glossy lobe, from the
    /// numbers `draw_light` drew, up to its shadow ray: the ray, and the radiance reflected
    /// per unit albedo (or reflectance) from one light sample, weighted against sampling the
    /// lobe by the power heuristic, if nothing blocks it (None: the sample brings nothing,
    /// and casts no ray).
    fn light_sample<'m>(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        lobe: Option<&GlossyLobe>,
        medium: Option<&'m Medium>,
        draw: Option<LightDraw>,
    ) -> Option<ShadowedSample<'m>> {
        let LightDraw { k, u, v } = draw?;
        let light = &self.lights[k];
        // By area with `--light-sampling random`; else by solid angle for rectangles and
        // spheres that subtend enough, by area for the rest.
        let sample = if self.by_area {
            light.sample_by_area_towards(s.point, n, u, v)
        } else {
            light.sample_towards(s.point, n, u, v)
        };
        let d = sample?;
        if !(d.weight.is_finite() && d.pdf > 0.0) {
            return None;
        }
        let light_pdf = self.selection_probability(k) * d.pdf;
        // The lobe's density in that direction, and what the sample brings unweighted:
        // diffuse, the receiver's cosine over π and the sample's weight (which is that over
        // the light's density, computed exactly); glossy, the lobe's density over the light's.
        let (bsdf_pdf, value) = match lobe {
            None => (d.weight * d.pdf, d.weight),
            Some(lobe) => lobe_against(lobe, (d.point - s.point).normalize_or_zero(), d.pdf),
        };
        if bsdf_pdf <= 0.0 {
            return None;
        }
        let mis = power_heuristic(light_pdf, bsdf_pdf);
        let origin = offset_ray_origin(s.point, n, s.error);
        let transmittance = match medium {
            Some(m) if !self.crosses_boundaries => m.transmittance(s.point.distance(d.point)),
            _ => Vec3::ONE,
        };
        Some(ShadowedSample {
            shadow_ray: shadow_ray(origin, d.point),
            radiance: self.scene.emitted_at(light.prim, d.point)
                * transmittance
                * (value * mis / self.selection_probability(k)),
            medium,
        })
    }

    /// Next-event estimation of the sky at a diffuse point (`lobe` None) or in a glossy lobe,
    /// from the numbers `draw_sky` drew: one direction by the cosine about `n` (exact for a
    /// uniform sky over a diffuse surface), weighed against sampling the lobe by the power
    /// heuristic; a medium around the point lets through only its channels without extinction.
    #[allow(clippy::too_many_arguments)]
    fn sample_sky(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        lobe: Option<&GlossyLobe>,
        medium: Option<&Medium>,
        draw: Option<(f32, f32)>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let (Some(sky), Some((u, v))) = (&self.scene.sky, draw) else {
            return Vec3::ZERO;
        };
        let Some((dir, pdf)) = sky_sample(sky, n, u, v) else {
            return Vec3::ZERO;
        };
        // Diffuse: (cos/π)/pdf per unit albedo (1 for the cosine's own samples); glossy: the
        // lobe's density over this one.
        let (lobe_pdf, value) = match lobe {
            None if sky.map().is_none() => (pdf, 1.0),
            None => {
                let cos_pdf = n.dot(dir).max(0.0) / std::f32::consts::PI;
                (cos_pdf, cos_pdf / pdf)
            }
            Some(lobe) => lobe_against(lobe, dir, pdf),
        };
        if pdf <= 0.0 || lobe_pdf <= 0.0 {
            return Vec3::ZERO;
        }
        let transmittance =
            self.shadow_transmittance(&s.spawn_ray(dir), f32::INFINITY, medium, samples, counts);
        sky.radiance(dir) * transmittance * (value * power_heuristic(pdf, lobe_pdf))
    }

    /// What the lights without area send a diffuse point (`lobe` None, per unit albedo:
    /// irradiance × cos/π) or a glossy lobe (per unit reflectance: irradiance × the lobe's
    /// density, which is its BRDF × cos), one shadow ray each: no other strategy finds them.
    fn delta_lights(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        lobe: Option<&GlossyLobe>,
        medium: Option<&Medium>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let mut sum = Vec3::ZERO;
        for a in delta_arrivals(self.scene, s, n) {
            let value = a.value(lobe);
            if value <= 0.0 {
                continue;
            }
            sum += a.irradiance
                * value
                * self.shadow_transmittance(&a.ray, a.distance, medium, samples, counts);
        }
        sum
    }

    /// The emitted radiance a path of `throughput` arriving at `s` along `dir` from `previous`
    /// takes in: what the surface emits towards it, weighed against next-event estimation
    /// (which could have found the point from `previous`) by the power heuristic.
    ///
    /// The test is inlined and the weighing is not: most vertices meet a surface that emits
    /// nothing, and as one call the weighing's large frame was set up for every vertex.
    #[inline(always)]
    fn emission(&self, s: &SurfaceHit, dir: Vec3, previous: &Previous, throughput: Color) -> Color {
        if !self.scene.sees_emission(s, dir) {
            return Vec3::ZERO;
        }
        self.weighed_emission(s, previous, throughput)
    }

    /// `emission` at a surface that emits towards the path.
    #[inline(never)]
    fn weighed_emission(&self, s: &SurfaceHit, previous: &Previous, throughput: Color) -> Color {
        let weight = match (previous.bsdf_pdf, Light::index_of(&self.lights, s.prim)) {
            (Some(bsdf_pdf), Some(k)) => {
                let light_pdf = self.light_pdf(k, previous, s);
                power_heuristic(bsdf_pdf, light_pdf)
            }
            _ => 1.0,
        };
        throughput * self.scene.emitted(s) * weight
    }

    /// The lobe a path scatters in at `s`, each chosen in proportion to its largest albedo
    /// channel (a material with one lobe takes it without a draw), and the factor the path's
    /// throughput takes: the lobe's albedo over the probability of taking it. None where the
    /// material reflects and transmits nothing.
    fn choose_lobe(&self, s: &SurfaceHit, samples: &mut PathSamples) -> Option<(Lobe, Color)> {
        let m = &self.scene.materials[s.material as usize];
        let albedo = self.scene.albedo(s);
        let (d, r, t) = (
            albedo.max_element(),
            m.reflective.max_element(),
            m.transmitted.max_element(),
        );
        let total = d + r + t;
        if total <= 0.0 {
            return None;
        }
        let lobes = (d > 0.0) as u32 + (r > 0.0) as u32 + (t > 0.0) as u32;
        let choice = if lobes > 1 {
            samples.next_1d() * total
        } else {
            0.0
        };
        Some(if choice < d {
            (Lobe::Diffuse, albedo * (total / d))
        } else if choice < d + r {
            (Lobe::Reflective, m.reflective * (total / r))
        } else {
            (Lobe::Transmitted, m.transmitted * (total / t))
        })
    }

    /// The radiance arriving along `ray`, from one path.
    pub fn along(&self, ray: &Ray, samples: &mut PathSamples) -> Color {
        let first = closest_surface(self.accel, self.scene, ray);
        self.radiance(ray, first, samples, &mut Counts::default())
    }

    fn radiance(
        &self,
        camera_ray: &Ray,
        first: Option<SurfaceHit>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        let mut ray = *camera_ray;
        let mut hit = first;
        let mut previous = Previous {
            point: ray.origin,
            normal: ray.direction,
            bsdf_pdf: None,
            in_medium: false,
        };
        // The medium the path is in: the camera's until it passes through a glass or
        // index-matched boundary (`Scene::medium_beyond`).
        let mut medium = self.scene.camera_medium();
        // The background is what a ray leaving the scene shows, seen directly or through
        // mirrors and glass; it does not light diffuse surfaces (as in the course program and
        // the other engines, which take light from the emitters only).
        let mut diffuse_bounce = false;
        // Scatterings so far: what `--max-depth` and roulette count. A boundary that changes
        // nothing (index-matched, clear: Mitsuba's `null`) is crossed without counting, as
        // Mitsuba's volumetric path tracer crosses it.
        let mut depth = 0u32;
        for _ in 0..MAX_VERTICES {
            if let Some(m) = medium {
                let travel = ray.direction.normalize();
                let t_surface = hit
                    .as_ref()
                    .map_or(f32::INFINITY, |s| s.point.distance(ray.origin));
                match m.free_flight(ray.origin, travel, t_surface, throughput, samples) {
                    // A path at its depth limit takes no more scatterings (those that pass are
                    // weighed for the ones that would not have).
                    Flight::Scattered { .. } if depth >= self.max_depth => break,
                    Flight::Scattered { t, weight } => {
                        throughput *= weight;
                        let x = ray.origin + travel * t;
                        radiance +=
                            throughput * self.sample_light_in_medium(x, travel, m, samples, counts);
                        let (u, v) = samples.next_2d();
                        let (dir, pdf) = m.sample_phase(travel, u, v);
                        // The phase function's value equals its density: the throughput
                        // keeps what the flight gave it.
                        previous = Previous {
                            point: x,
                            normal: dir,
                            bsdf_pdf: Some(pdf),
                            in_medium: true,
                        };
                        diffuse_bounce = true;
                        if !survives_roulette(depth, &mut throughput, samples) {
                            break;
                        }
                        depth += 1;
                        ray = Ray::new(x, dir);
                        counts.secondary += 1;
                        samples.prepare();
                        hit = closest_surface(self.accel, self.scene, &ray);
                        continue;
                    }
                    Flight::Passed { weight } => throughput *= weight,
                }
            }
            // What emits, hidden from the camera: seen through until the path scatters.
            let hidden = depth == 0 && self.scene.hide_emitters;
            let Some(s) = hit else {
                match &self.scene.sky {
                    Some(_) if hidden => {}
                    Some(sky) => {
                        let towards = ray.direction.normalize();
                        let weight = match previous.bsdf_pdf {
                            Some(pdf) if !previous.in_medium => {
                                power_heuristic(pdf, sky_pdf(sky, previous.normal, towards))
                            }
                            Some(pdf) => power_heuristic(pdf, medium_sky_pdf(sky, towards)),
                            None => 1.0,
                        };
                        radiance += throughput * sky.radiance(towards) * weight;
                    }
                    None if !diffuse_bounce => radiance += throughput * self.scene.background,
                    None => {}
                }
                break;
            };
            let m = &self.scene.materials[s.material as usize];
            if hidden && m.is_emissive() {
                ray = s.spawn_ray(ray.direction);
                counts.secondary += 1;
                samples.prepare();
                hit = closest_surface(self.accel, self.scene, &ray);
                continue;
            }
            let (front, n) = s.facing(ray.direction);
            radiance += self.emission(&s, ray.direction, &previous, throughput);
            // An index-matched boundary changes only the medium: the path goes on as it was
            // (its previous vertex still the one whose density weighs what it meets next).
            // So does what a thin sheet lets through; what it does not, it reflects.
            let sheet = m
                .bsdf
                .as_ref()
                .and_then(|b| b.null_lobe(ray.direction.normalize().dot(s.shading_normal)));
            let passes = m.is_index_matched()
                || match sheet {
                    Some((pass, colour)) if samples.next_1d() < pass => {
                        throughput *= colour;
                        true
                    }
                    _ => false,
                };
            if passes {
                medium = self
                    .scene
                    .medium_beyond(m, ray.direction.dot(s.geometric_normal) < 0.0);
                ray = s.spawn_ray(ray.direction);
                counts.secondary += 1;
                samples.prepare();
                hit = closest_surface(self.accel, self.scene, &ray);
                continue;
            }
            if depth >= self.max_depth {
                break;
            }
            // Where a mask is transparent the path goes straight on, as through Mitsuba's
            // `mask`, whose path tracer counts it as a scattering.
            if let Some(k) = m.opacity {
                let alpha = self.scene.textures[k].lookup(self.scene.tex_coords(&s)).x;
                if samples.next_1d() >= alpha {
                    previous.bsdf_pdf = None;
                    if !survives_roulette(depth, &mut throughput, samples) {
                        break;
                    }
                    depth += 1;
                    ray = s.spawn_ray(ray.direction);
                    counts.secondary += 1;
                    samples.prepare();
                    hit = closest_surface(self.accel, self.scene, &ray);
                    continue;
                }
            }
            let dir;
            if let (Some(Bsdf::ThinDielectric { reflectance, .. }), Some(_)) = (&m.bsdf, sheet) {
                // The sheet's other lobe, chosen with the probability it has.
                throughput *= *reflectance;
                previous.bsdf_pdf = None;
                dir = reflect(ray.direction, s.shading_normal);
            } else if let Some(bsdf) = &m.bsdf {
                let (light, scattered) = self.bsdf_vertex(
                    &s,
                    ray.direction,
                    bsdf,
                    m.two_sided,
                    medium,
                    samples,
                    counts,
                );
                radiance += throughput * light;
                let Some((sampled, weight, pdf)) = scattered else {
                    break;
                };
                throughput *= weight;
                previous = Previous {
                    point: s.point,
                    normal: s.shading_normal,
                    bsdf_pdf: pdf,
                    in_medium: true,
                };
                diffuse_bounce = true;
                if sampled.dot(s.geometric_normal) * ray.direction.dot(s.geometric_normal) > 0.0 {
                    medium = self.scene.medium_beyond(m, front);
                }
                dir = sampled;
            } else {
                let Some((lobe, weight)) = self.choose_lobe(&s, samples) else {
                    break;
                };
                throughput *= weight;
                // A path this bounce turns black ends here (see `survives_roulette`), before it
                // spends a shadow ray on a sample it would weigh by zero.
                if throughput.max_element() == 0.0 {
                    break;
                }
                if lobe == Lobe::Diffuse {
                    // The light sample's numbers come first in the path's sequence, but the next
                    // direction is computed before the light sample: its long chain (a division,
                    // sincos) then runs while the shadow ray is traced, not after it (0.95× the
                    // time on the Cornell box; the same numbers, so the same image).
                    let light_draw = self.draw_light(s.prim, samples);
                    let sky_draw = self.draw_sky(samples);
                    let (u, v) = samples.next_2d();
                    let (sampled, pdf) = diffuse_sample(n, u, v);
                    radiance += throughput
                        * (self.unblocked(
                            self.light_sample(&s, n, None, medium, light_draw),
                            samples,
                            counts,
                        ) + self.sample_sky(&s, n, None, medium, sky_draw, samples, counts)
                            + self.delta_lights(&s, n, None, medium, samples, counts));
                    if m.bump.is_some() && !s.leaves_on_side_of(n, sampled) {
                        break;
                    }
                    dir = sampled;
                    diffuse_bounce = true;
                    previous = Previous {
                        point: s.point,
                        normal: n,
                        bsdf_pdf: Some(pdf),
                        in_medium: false,
                    };
                } else if lobe == Lobe::Reflective {
                    match GlossyLobe::new(ray.direction, n, m.roughness) {
                        // A mirror: a delta no light sample finds.
                        None => {
                            dir = reflect(ray.direction, n);
                            previous.bsdf_pdf = None;
                        }
                        Some(glossy) => {
                            let light_draw = self.draw_light(s.prim, samples);
                            let sky_draw = self.draw_sky(samples);
                            radiance += throughput
                                * (self.unblocked(
                                    self.light_sample(&s, n, Some(&glossy), medium, light_draw),
                                    samples,
                                    counts,
                                ) + self.sample_sky(
                                    &s,
                                    n,
                                    Some(&glossy),
                                    medium,
                                    sky_draw,
                                    samples,
                                    counts,
                                ) + self.delta_lights(
                                    &s,
                                    n,
                                    Some(&glossy),
                                    medium,
                                    samples,
                                    counts,
                                ));
                            let (u, v) = samples.next_2d();
                            let (sampled, pdf) = glossy.sample(u, v);
                            dir = sampled;
                            previous = Previous {
                                point: s.point,
                                normal: n,
                                bsdf_pdf: pdf,
                                in_medium: false,
                            };
                        }
                    }
                } else {
                    dir =
                        Dielectric::at(m, front, ray.direction, n)
                            .sample(ray.direction, n, || samples.next_1d());
                    previous.bsdf_pdf = None;
                    // Through the boundary (n faces the side the ray came from): into a closed
                    // object from its front, out of it from its back.
                    if dir.dot(n) < 0.0 {
                        medium = self.scene.medium_beyond(m, front);
                    }
                }
            }
            if !survives_roulette(depth, &mut throughput, samples) {
                break;
            }
            depth += 1;
            ray = s.spawn_ray(dir);
            counts.secondary += 1;
            samples.prepare();
            hit = closest_surface(self.accel, self.scene, &ray);
        }
        radiance
    }
}

impl PathTracer<'_> {
    /// A vertex at a surface of a Mitsuba BSDF, met by a ray travelling along `incoming` in
    /// `medium`: the light it reflects from one sample of the area lights, one of the sky
    /// and every light without area, each weighed against sampling the BSDF by the power
    /// heuristic (the lights sampled as from a point in a medium, without the receiver's
    /// cosine, since a BSDF may transmit), per unit throughput; and the direction the BSDF
    /// samples next with the throughput's factor and its density (None for a delta lobe).
    /// `two_sided`: the BSDF's front is the side the ray arrives on.
    #[allow(clippy::too_many_arguments)]
    fn bsdf_vertex(
        &self,
        s: &SurfaceHit,
        incoming: Vec3,
        bsdf: &Bsdf,
        two_sided: bool,
        medium: Option<&Medium>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> (Color, Option<(Vec3, Color, Option<f32>)>) {
        // Mitsuba's shading frame: the normal, its first tangent along ∂p/∂u where the
        // surface has texture coordinates (an anisotropic BSDF is aligned with them). A
        // two-sided BSDF seen from behind is the frame mirrored through the tangent plane.
        let n = s.shading_normal;
        let tangents = self.scene.tangents(s);
        let (t, b) = match tangents {
            Some((dpdu, _)) => {
                let t = (dpdu - n * n.dot(dpdu)).normalize_or_zero();
                if t == Vec3::ZERO {
                    orthonormal_basis(n)
                } else {
                    (t, n.cross(t))
                }
            }
            None => orthonormal_basis(n),
        };
        let n = if two_sided && n.dot(incoming) > 0.0 {
            -n
        } else {
            n
        };
        let textured = self.scene.textured_bsdf(s, bsdf);
        let mut at = BsdfAt {
            bsdf: textured.as_ref().unwrap_or(bsdf),
            frame: (t, b, n),
            perturbed: None,
            wi: Vec3::ZERO,
        };
        let wi = at.local(-incoming);
        match self.scene.materials[s.material as usize].tilt {
            None => {}
            Some(ShadingTilt::NormalMap(k)) => {
                let texel = self.scene.textures[k].lookup(self.scene.tex_coords(s));
                at.tilt(texel * 2.0 - Vec3::ONE, Vec3::X, wi);
            }
            Some(ShadingTilt::BumpMap { heights, scale }) => {
                // Mitsuba's `bumpmap`: the tangents lifted along the normal by the heights'
                // gradient, the normal across them turned to the surface's outside.
                if let Some((dpdu, dpdv)) = tangents {
                    let g = self.scene.textures[heights].gradient(self.scene.tex_coords(s)) * scale;
                    let du = dpdu + n * (g.x - n.dot(dpdu));
                    let dv = dpdv + n * (g.y - n.dot(dpdv));
                    let mut bumped = du.cross(dv);
                    if bumped.dot(s.geometric_normal) < 0.0 {
                        bumped = -bumped;
                    }
                    let local = at.local(bumped);
                    at.tilt(local * local.z.signum(), at.local(dpdu), wi);
                }
            }
        }
        at.wi = wi;
        // The medium on the side a direction leaves into: a transmitted direction is in the
        // object's interior (from its front) or outside it (from its back).
        let front = s.geometric_normal.dot(incoming) < 0.0;
        let m = &self.scene.materials[s.material as usize];
        let medium_towards = |dir: Vec3| {
            if dir.dot(s.geometric_normal) * incoming.dot(s.geometric_normal) > 0.0 {
                self.scene.medium_beyond(m, front)
            } else {
                medium
            }
        };
        let mut light = Vec3::ZERO;
        if !at.bsdf.is_delta() {
            if let Some(k) = self.choose_light(samples) {
                let (u, v) = samples.next_2d();
                let emitter = &self.lights[k];
                if let Some(d) = emitter
                    .sample_from_medium(s.point, u, v)
                    .filter(|_| emitter.prim != s.prim)
                {
                    let to = d.point - s.point;
                    let dir = to.normalize_or_zero();
                    let f = at.eval(dir);
                    let light_pdf = self.selection_probability(k) * d.pdf;
                    if f.max_element() > 0.0 && light_pdf > 0.0 {
                        let mis = power_heuristic(light_pdf, at.pdf(dir));
                        let origin = s.spawn_ray(dir).origin;
                        let seen = self.shadow_transmittance(
                            &shadow_ray(origin, d.point),
                            to.length(),
                            medium_towards(dir),
                            samples,
                            counts,
                        );
                        light += self.scene.emitted_at(emitter.prim, d.point)
                            * f
                            * seen
                            * (mis / light_pdf);
                    }
                }
            }
            if let Some((sky, (u, v))) = self.scene.sky.as_ref().zip(self.draw_sky(samples)) {
                if let Some((dir, pdf)) = medium_sky_sample(sky, u, v) {
                    let f = at.eval(dir);
                    if f.max_element() > 0.0 {
                        let mis = power_heuristic(pdf, at.pdf(dir));
                        let seen = self.shadow_transmittance(
                            &s.spawn_ray(dir),
                            f32::INFINITY,
                            medium_towards(dir),
                            samples,
                            counts,
                        );
                        light += sky.radiance(dir) * f * seen * (mis / pdf);
                    }
                }
            }
            for delta in &self.scene.delta_lights {
                let Some((dir, distance, irradiance)) =
                    delta.towards(s.point, &self.scene.textures)
                else {
                    continue;
                };
                let f = at.eval(dir);
                if f.max_element() <= 0.0 {
                    continue;
                }
                let origin = s.spawn_ray(dir).origin;
                let ray = if distance.is_finite() {
                    shadow_ray(origin, s.point + dir * distance)
                } else {
                    Ray::new(origin, dir)
                };
                light += irradiance
                    * f
                    * self.shadow_transmittance(
                        &ray,
                        distance,
                        medium_towards(dir),
                        samples,
                        counts,
                    );
            }
        }
        let u = samples.next_1d();
        let u2 = samples.next_2d();
        (light, at.sample(u, u2))
    }

    /// What a shadow ray lets through, starting in `medium` and `distance` long in the scene
    /// (∞ to the sky): the medium's transmittance if nothing blocks it, 0 if something does;
    /// across index-matched boundaries where the scene has them (`crossing_transmittance`).
    fn shadow_transmittance(
        &self,
        ray: &Ray,
        distance: f32,
        medium: Option<&Medium>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        if self.crosses_boundaries {
            return self.crossing_transmittance(ray, medium, samples, counts);
        }
        counts.shadow += 1;
        if self.accel.occluded(ray) {
            return Vec3::ZERO;
        }
        medium.map_or(Vec3::ONE, |m| m.transmittance(distance))
    }

    /// The transmittance along a shadow ray that starts in `medium`, crossing index-matched
    /// boundaries and thin sheets (each into the medium `Scene::medium_beyond` says; a sheet
    /// lets through what `straight_transmission` says) and multiplying the media's transmittance over each stretch (a heterogeneous medium's
    /// estimated from `samples`); 0 where any other surface is in the way, or after
    /// `MAX_CROSSINGS` boundaries.
    fn crossing_transmittance(
        &self,
        ray: &Ray,
        medium: Option<&Medium>,
        samples: &mut PathSamples,
        counts: &mut Counts,
    ) -> Color {
        let mut medium = medium;
        let scale = ray.direction.length();
        let direction = ray.direction / scale;
        let mut ray = *ray;
        let mut transmittance = Vec3::ONE;
        for _ in 0..MAX_CROSSINGS {
            counts.shadow += 1;
            let hit = closest_surface(self.accel, self.scene, &ray);
            // The surface met and what it lets straight through (nothing: it blocks the ray).
            let met = hit.as_ref().map(|hit| {
                let m = &self.scene.materials[hit.material as usize];
                let cos = ray.direction.dot(hit.shading_normal) / scale;
                (m, m.straight_transmission(cos))
            });
            if met.is_some_and(|(_, straight)| straight == Color::ZERO) {
                return Vec3::ZERO;
            }
            let length = match &hit {
                Some(hit) => hit.t * scale,
                None => (ray.t_max - ray.t_min) * scale,
            };
            let through = medium.map_or(Vec3::ONE, |md| {
                md.transmittance_along(ray.origin, direction, length, samples)
            });
            let (Some(hit), Some((m, straight))) = (hit, met) else {
                return transmittance * through;
            };
            transmittance *= straight * through;
            medium = self
                .scene
                .medium_beyond(m, ray.direction.dot(hit.geometric_normal) < 0.0);
            let next = hit.spawn_ray(ray.direction);
            ray = Ray::with_range(next.origin, ray.direction, 0.0, ray.t_max - hit.t);
        }
        Vec3::ZERO
    }
}

/// A Mitsuba BSDF at a surface point: its shading frame (tangent, bitangent, normal in the
/// world), the frame a normal or bump map tilts it to (within the first), and the direction towards
/// the path's previous vertex in the BSDF's own frame.
struct BsdfAt<'b> {
    bsdf: &'b Bsdf,
    frame: (Vec3, Vec3, Vec3),
    /// A normal or bump map's frame, in `frame`'s coordinates (Mitsuba's `normalmap`,
    /// `bumpmap`).
    perturbed: Option<(Vec3, Vec3, Vec3)>,
    wi: Vec3,
}

impl BsdfAt<'_> {
    /// A world direction in the shading frame.
    fn local(&self, v: Vec3) -> Vec3 {
        let (t, b, n) = self.frame;
        Vec3::new(v.dot(t), v.dot(b), v.dot(n))
    }

    /// Tilts the frame to `normal` (in the shading frame, not unit), mirrored to face `wi`
    /// where it would not, its tangent the part of `along` across it, as Mitsuba's
    /// `normalmap` (along its first axis) and `bumpmap` (along ∂p/∂u) do.
    fn tilt(&mut self, normal: Vec3, along: Vec3, wi: Vec3) {
        let mut normal = normal;
        if wi.z * wi.dot(normal) <= 0.0 {
            normal = Vec3::new(-normal.x, -normal.y, normal.z);
        }
        let n = normal.normalize_or_zero();
        let s = (along - n * n.dot(along)).normalize_or_zero();
        if n == Vec3::ZERO || s == Vec3::ZERO {
            return;
        }
        self.perturbed = Some((s, n.cross(s), n));
    }

    /// A shading-frame direction in the BSDF's frame: the tilted one where there is one.
    fn in_bsdf_frame(&self, v: Vec3) -> Vec3 {
        match self.perturbed {
            None => v,
            Some((s, t, n)) => Vec3::new(v.dot(s), v.dot(t), v.dot(n)),
        }
    }

    /// A tilted frame's attenuation of light leaving along `wo` (shading frame): Estevez et
    /// al.'s shadowing term for bump terminators, which Mitsuba's normal and bump maps apply.
    fn terminator(&self, wo: Vec3) -> f32 {
        let Some((_, _, n)) = self.perturbed else {
            return 1.0;
        };
        let tan2 = |v: Vec3| (1.0 - v.z * v.z).max(0.0) / (v.z * v.z);
        let alpha2 = (0.125 * tan2(n)).min(1.0);
        2.0 / (1.0 + (1.0 + alpha2 * tan2(wo)).sqrt())
    }

    /// The BSDF's f·|cos| towards the world direction `dir`.
    fn eval(&self, dir: Vec3) -> Color {
        let wo = self.local(dir);
        let tilted = self.in_bsdf_frame(wo);
        if self.perturbed.is_some() && wo.z * tilted.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.bsdf.eval(self.wi_tilted(), tilted) * self.terminator(wo)
    }

    /// The density with which `sample` picks the world direction `dir`.
    fn pdf(&self, dir: Vec3) -> f32 {
        let wo = self.local(dir);
        let tilted = self.in_bsdf_frame(wo);
        if self.perturbed.is_some() && wo.z * tilted.z <= 0.0 {
            return 0.0;
        }
        self.bsdf.pdf(self.wi_tilted(), tilted)
    }

    fn wi_tilted(&self) -> Vec3 {
        self.in_bsdf_frame(self.wi)
    }

    /// A direction (world) sampled from the BSDF, the throughput's factor, and its density
    /// (None for a delta lobe); None where it scatters nothing.
    fn sample(&self, u: f32, u2: (f32, f32)) -> Option<(Vec3, Color, Option<f32>)> {
        let bs = self.bsdf.sample(self.wi_tilted(), u, u2)?;
        let wo = match self.perturbed {
            None => bs.wo,
            Some((s, t, n)) => s * bs.wo.x + t * bs.wo.y + n * bs.wo.z,
        };
        if self.perturbed.is_some() && bs.wo.z * wo.z <= 0.0 {
            return None;
        }
        let weight = bs.weight * self.terminator(wo);
        let (t, b, n) = self.frame;
        let dir = (t * wo.x + b * wo.y + n * wo.z).normalize_or_zero();
        let usable = weight.is_finite() && weight.max_element() > 0.0;
        usable.then_some((dir, weight, (!bs.delta).then_some(bs.pdf)))
    }
}

/// A glossy lobe's density for the direction `dir` that another strategy picked with density
/// `pdf`, and what that sample brings per unit reflectance (the lobe's density over `pdf`).
fn lobe_against(lobe: &GlossyLobe, dir: Vec3, pdf: f32) -> (f32, f32) {
    let lobe_pdf = lobe.pdf(dir);
    (lobe_pdf, lobe_pdf / pdf)
}

/// A direction `sample_sky` takes towards `sky` from a point of normal `n`, and its density:
/// the map's importance for a map, the cosine about `n` for the smooth skies (exact for a
/// uniform sky over a diffuse surface). None where a map is black.
fn sky_sample(sky: &Sky, n: Vec3, u: f32, v: f32) -> Option<(Vec3, f32)> {
    match sky.map() {
        Some(map) => map.sample(u, v),
        None => Some(diffuse_sample(n, u, v)),
    }
}

/// A direction towards `sky` from a point in a medium, and its density: the map's importance
/// for a map, uniform over the sphere for the smooth skies. None where a map is black.
fn medium_sky_sample(sky: &Sky, u: f32, v: f32) -> Option<(Vec3, f32)> {
    match sky.map() {
        Some(map) => map.sample(u, v),
        None => {
            let z = 1.0 - 2.0 * u;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * v;
            Some((
                Vec3::new(r * phi.cos(), r * phi.sin(), z),
                0.25 * std::f32::consts::FRAC_1_PI,
            ))
        }
    }
}

/// The density with which `medium_sky_sample` picks the unit direction `towards`.
fn medium_sky_pdf(sky: &Sky, towards: Vec3) -> f32 {
    match sky.map() {
        Some(map) => map.pdf(towards),
        None => 0.25 * std::f32::consts::FRAC_1_PI,
    }
}

/// The density with which `sample_sky` at a point of normal `n` picks the unit direction
/// `towards` (see `sky_sample`).
fn sky_pdf(sky: &Sky, n: Vec3, towards: Vec3) -> f32 {
    match sky.map() {
        Some(map) => map.pdf(towards),
        None => n.dot(towards).max(0.0) / std::f32::consts::PI,
    }
}

/// Russian roulette from the `ROULETTE_FROM`th vertex on: whether the path goes on, its
/// throughput divided by the probability that it did. A path whose throughput is black ends
/// at any vertex, as Mitsuba's does: all it could still bring is zero (on the Cornell box,
/// a bounce off the red wall and then the blue one), and its random numbers are its own, so
/// the image is the same without its rays.
fn survives_roulette(depth: u32, throughput: &mut Color, samples: &mut PathSamples) -> bool {
    let largest = throughput.max_element();
    if largest == 0.0 {
        return false;
    }
    if depth < ROULETTE_FROM {
        return true;
    }
    roulette(throughput, samples.next_1d())
}

/// One game of Russian roulette on a path of `throughput` (not black) with the uniform number
/// `draw`: whether it goes on, its throughput divided by the probability that it did.
#[inline(always)]
fn roulette(throughput: &mut Color, draw: f32) -> bool {
    let survive = throughput.max_element().min(MAX_SURVIVAL);
    if draw >= survive {
        return false;
    }
    *throughput *= survive.recip();
    true
}

/// Renders the scene by path tracing; returns the film and the counters of the render.
pub fn render(scene: &Scene, accel: &dyn Accel, settings: &RenderSettings) -> (Film, RenderStats) {
    let tracer = PathTracer::new(scene, accel)
        .with_max_depth(settings.max_depth)
        .with_light_sampling(settings.light_sampling.unwrap_or(DEFAULT_LIGHT_SAMPLING));
    if tracer.wavefront_applies() {
        return render_pixel_batches(
            scene,
            accel,
            &settings.image(),
            "path",
            |batch, counts, out| {
                for (c, out) in out.chunks_mut(WAVEFRONT_PATHS).enumerate() {
                    let paths = c * WAVEFRONT_PATHS..c * WAVEFRONT_PATHS + out.len();
                    let samples = batch.ids[paths.clone()]
                        .iter()
                        .zip(&batch.rngs[paths.clone()])
                        .map(|(&id, rng)| PathSamples::new(settings.path_sampler, id, rng.clone()));
                    let (rays, hits) = (&batch.rays[paths.clone()], &batch.hits[paths]);
                    tracer.radiance_batch(rays, hits, samples, counts, out);
                }
            },
        );
    }
    render_pixels(
        scene,
        accel,
        &settings.image(),
        "path",
        |ray, hit, rng, id, counts| {
            let mut samples = PathSamples::new(settings.path_sampler, id, rng.clone());
            tracer.radiance(ray, hit, &mut samples, counts)
        },
    )
}

/// The path tracer (`--engine path`).
pub struct PathEngine;

impl Engine for PathEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Path
    }

    fn unread_flags(&self) -> &'static [&'static str] {
        // The path tracer follows every bounce and samples the lights itself.
        &[
            "num_bounces",
            "num_shadow_samples",
            "ambient_light",
            "indirect",
        ]
    }

    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        let (film, stats) = render(scene, accel, settings);
        Ok(Rendered::plain(film, stats))
    }

    /// Paths per pixel doubling.
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget> {
        Budget::samples_per_pixel(level, 16, base)
    }

    fn colour(&self) -> (u8, u8, u8) {
        (20, 20, 20)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{build, AccelKind, AccelOptions};
    use std::sync::atomic::Ordering::Relaxed;

    /// A closed box with a red floor and green walls, lit by its ceiling, seen from just below
    /// the ceiling looking straight down: every path meets the floor, samples the light once,
    /// and its bounce meets a green face, where red times green leaves it nothing to carry.
    /// So it ends there, having spent one shadow ray and one bounce ray and no more (the
    /// path does not go on to the sixth vertex and its roulette).
    const RED_FLOOR_GREEN_WALLS: &str = "
material
diffuse 1 0 0
emitted 0 0 0
material
diffuse 0 1 0
emitted 0 0 0
material
diffuse 0 1 0
emitted 1 1 1
v -1 -1 -1
v  1 -1 -1
v -1  1 -1
v  1  1 -1
v -1 -1  1
v  1 -1  1
v -1  1  1
v  1  1  1
m 0
f 1 5 6 2
m 1
f 1 2 4 3
f 5 7 8 6
f 1 3 7 5
f 2 6 8 4
m 2
f 3 4 8 7
PerspectiveCamera {
camera_position 0 0.9 0
point_of_interest 0 -1 0
up 0 0 1
angle 0.35
}
";

    #[test]
    fn a_path_that_turns_black_spends_no_more_rays() {
        let scene = Scene::parse_dialect(std::path::Path::new("box.obj"), RED_FLOOR_GREEN_WALLS)
            .expect("parses");
        let accel = build(&scene, AccelKind::Bvh, &AccelOptions::default()).expect("builds");
        let settings = RenderSettings {
            width: 16,
            height: 16,
            num_antialias_samples: 8,
            quiet: true,
            ..RenderSettings::default()
        };
        let (film, stats) = render(&scene, accel.as_ref(), &settings);
        let paths = stats.camera_rays.load(Relaxed);
        assert_eq!(paths, 16 * 16 * 8);
        assert_eq!(
            stats.shadow_rays.load(Relaxed),
            paths,
            "one light sample a path"
        );
        assert_eq!(
            stats.secondary_rays.load(Relaxed),
            paths,
            "one bounce a path"
        );
        // The floor is lit: what the paths did bring is there.
        assert!(film
            .pixels
            .iter()
            .all(|p| p.x > 0.0 && p.y == 0.0 && p.z == 0.0));
    }
}
