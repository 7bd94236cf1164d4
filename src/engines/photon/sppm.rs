//! Stochastic progressive photon mapping (`--engine sppm`; Hachisuka & Jensen 2009, as in
//! pbrt-v4's SPPM): photon mapping that converges to the right image instead of levelling off
//! at the bias of a fixed density estimate.
//!
//! Each pass takes one camera sample per pixel (pass k is pixel sample k of
//! `-num_antialias_samples` passes): the camera ray is followed through mirrors and glass to
//! its first diffuse surface, the *visible point*, where the light straight from the emitters
//! is added by a shadow ray to a point on each light (by solid angle for rectangles; in
//! scenes of many lights, to one light chosen by power) and to each light without area. Then
//! `--sppm-photons` photons are traced from the lights, and every photon that reaches a
//! diffuse surface after at least one bounce adds its power to the visible points within
//! their pixel's radius. Each pixel's radius then shrinks as photons arrive (α = 2/3):
//! N' = N + αM, R' = R·√(N'/(N + M)), and its flux τ is rescaled by R'²/R², so that the bias
//! falls to zero while the variance does too. The image is the mean direct light plus
//! τ / (passes · π R²).
//!
//! Parameters: `-num_antialias_samples` passes (default 1), `--sppm-photons` per pass
//! (default: one per pixel of the image), `--sppm-radius` the initial radius as a fraction of
//! the scene's diagonal (default 0.01). Photons of pass k draw from hash(seed, pass, photon);
//! their contributions are added to the visible points in photon order, so the image does not
//! depend on the thread count. The radii of a pixel depend on its own samples only, so a
//! `--crop-window` tile is the same pixels as the whole image.

use std::sync::atomic::Ordering::Relaxed;

use rayon::prelude::*;

use super::settings::SAFETY_DEPTH;
use super::trace::{Aim, Emitters, Hit, PathKind};
use crate::accel::{closest_surface, Accel};
use crate::engines::engine::{Budget, Engine, EngineKind, EnginePlan, RenderSettings, Rendered};
use crate::engines::scattering::{
    delta_arrivals, glossy_reflection, sky_lighting_sample, Dielectric,
};
use crate::film::Film;
use crate::geometry::{offset_ray_origin, shadow_ray, Vec3};
use crate::render::lights::{Light, LightPower, EVERY_LIGHT_UP_TO};
use crate::render::{CameraSampler, RenderStats};
use crate::sampling::Rng;
use crate::scene::{Color, Scene, SurfaceHit};

/// The exponent of the radius reduction: the share of each pass's photons a pixel keeps.
const ALPHA: f64 = 2.0 / 3.0;
/// Specular bounces a camera path may make before its visible point (Russian roulette ends
/// most far earlier, as in the path tracer).
const MAX_SPECULAR: u32 = 64;
/// Photons per parallel task.
const PHOTON_BLOCK: u64 = 4096;
/// Bytes per pixel: its state, visible point, grid entries and a pass's contributions.
const PIXEL_BYTES: u64 = 256;

/// Bytes a pass holds for each of its photons, at least: what each gave which visible point
/// (a `(u32, Color)`), listed by block until the pass adds them up. It grows with
/// `--sppm-photons`, so `--max-memory` must see it (a pass of 2^64 photons asked for 2^57
/// bytes at once).
const PASS_PHOTON_BYTES: u64 = 16;

/// Where a pixel's camera path met its first diffuse surface in this pass.
#[derive(Clone, Copy, Debug)]
struct VisiblePoint {
    point: Vec3,
    /// The normal on the side the camera path arrived from.
    normal: Vec3,
    /// The diffuse BRDF there (albedo / π) times the camera path's throughput.
    weight: Color,
}

/// What a pixel has gathered over the passes.
#[derive(Clone, Copy, Debug)]
struct PixelState {
    /// The photon-gathering radius, squared.
    radius2: f64,
    /// Photons it has kept (N).
    photons: f64,
    /// Flux gathered, rescaled with the radius (τ).
    tau: [f64; 3],
    /// Light seen along the camera paths and straight from the lights at the visible points,
    /// summed over passes.
    direct: [f64; 3],
}

/// The visible points of a pass in a hashed grid of cells the size of the largest radius:
/// each point listed in every cell its sphere overlaps, so a photon looks in its own cell.
struct Grid {
    cell: f32,
    /// For each bucket, its entries' range in `entries` (`start[b]..start[b + 1]`).
    start: Vec<u32>,
    entries: Vec<u32>,
}

impl Grid {
    fn bucket(&self, c: [i32; 3]) -> usize {
        let h = (c[0] as u32).wrapping_mul(73_856_093)
            ^ (c[1] as u32).wrapping_mul(19_349_663)
            ^ (c[2] as u32).wrapping_mul(83_492_791);
        h as usize % (self.start.len() - 1)
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = p * self.cell.recip();
        [c.x.floor() as i32, c.y.floor() as i32, c.z.floor() as i32]
    }

    fn build(points: &[Option<VisiblePoint>], radius2: &[f64]) -> Grid {
        let largest = points
            .iter()
            .zip(radius2)
            .filter(|(p, _)| p.is_some())
            .map(|(_, &r2)| r2.sqrt())
            .fold(0.0f64, f64::max) as f32;
        let mut grid = Grid {
            cell: largest.max(f32::MIN_POSITIVE),
            start: vec![0; points.len().max(1) + 1],
            entries: Vec::new(),
        };
        let cells = |grid: &Grid, p: &VisiblePoint, r: f32| {
            let lo = grid.cell_of(p.point - Vec3::splat(r));
            let hi = grid.cell_of(p.point + Vec3::splat(r));
            let mut out = Vec::with_capacity(8);
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        out.push(grid.bucket([x, y, z]));
                    }
                }
            }
            out.sort_unstable();
            out.dedup();
            out
        };
        let listed: Vec<(u32, Vec<usize>)> = points
            .iter()
            .enumerate()
            .filter_map(|(k, p)| {
                p.as_ref()
                    .map(|p| (k as u32, cells(&grid, p, radius2[k].sqrt() as f32)))
            })
            .collect();
        let buckets = grid.start.len() - 1;
        let mut counts = vec![0u32; buckets + 1];
        for (_, bs) in &listed {
            bs.iter().for_each(|&b| counts[b + 1] += 1);
        }
        for b in 0..buckets {
            counts[b + 1] += counts[b];
        }
        grid.start.copy_from_slice(&counts);
        let mut fill = counts;
        grid.entries = vec![0; grid.start[buckets] as usize];
        for (k, bs) in &listed {
            for &b in bs {
                grid.entries[fill[b] as usize] = *k;
                fill[b] += 1;
            }
        }
        grid
    }

    /// The visible points listed in the cell of `p` (a superset of those near it).
    fn near(&self, p: Vec3) -> &[u32] {
        let b = self.bucket(self.cell_of(p));
        &self.entries[self.start[b] as usize..self.start[b + 1] as usize]
    }
}

/// Next-event estimation at the visible points: one point on every light (by solid angle for
/// rectangles), or, in scenes of more than `EVERY_LIGHT_UP_TO` lights, on one light chosen in
/// proportion to its power.
struct DirectLight {
    lights: Vec<Light>,
    power: LightPower,
}

impl DirectLight {
    fn new(scene: &Scene) -> DirectLight {
        let lights = Light::collect(scene);
        DirectLight {
            power: LightPower::new(&lights),
            lights,
        }
    }

    /// What reaches `s` (normal `n`) straight from the lights, per unit albedo, as
    /// irradiance / π; `rays` counts the shadow rays.
    fn sample(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        accel: &dyn Accel,
        rng: &mut Rng,
        rays: &mut u64,
    ) -> Color {
        let one = |light: &Light, rng: &mut Rng, rays: &mut u64| {
            let (u, v) = (rng.next_f32(), rng.next_f32());
            if light.prim == s.prim {
                return Vec3::ZERO;
            }
            let Some(d) = light.sample_towards(s.point, n, u, v) else {
                return Vec3::ZERO;
            };
            *rays += 1;
            let origin = offset_ray_origin(s.point, n, s.error);
            if accel.occluded(&shadow_ray(origin, d.point)) {
                return Vec3::ZERO;
            }
            light.emitted * d.weight
        };
        if self.lights.len() <= EVERY_LIGHT_UP_TO {
            return self
                .lights
                .iter()
                .fold(Vec3::ZERO, |sum, light| sum + one(light, rng, rays));
        }
        if !self.power.any() {
            return Vec3::ZERO;
        }
        let k = self.power.choose(rng.next_f32());
        let probability = self.power.probability(k);
        if probability <= 0.0 {
            return Vec3::ZERO;
        }
        one(&self.lights[k], rng, rays) * probability.recip()
    }
}

/// What reaches `s` (normal `n`) from the lights without area, per unit albedo, as
/// irradiance / π: one shadow ray each, which `rays` counts. Their photons are skipped where
/// they first land, as the other lights' are.
fn delta_lights(
    scene: &Scene,
    accel: &dyn Accel,
    (s, n): (&SurfaceHit, Vec3),
    rays: &mut u64,
) -> Color {
    let mut sum = Vec3::ZERO;
    for a in delta_arrivals(scene, s, n) {
        *rays += 1;
        if !accel.occluded(&a.ray) {
            sum += a.irradiance * a.value(None);
        }
    }
    sum
}

/// What reaches `s` (normal `n`) from the sky, per unit albedo, as irradiance / π: one
/// direction by `sky_lighting_sample` and its shadow ray, which `rays` counts (no draw without
/// a sky). The sky's photons are skipped where they first land, as the lights' are.
fn sky_light(
    scene: &Scene,
    accel: &dyn Accel,
    (s, n): (&SurfaceHit, Vec3),
    rng: &mut Rng,
    rays: &mut u64,
) -> Color {
    let Some(sky) = &scene.sky else {
        return Vec3::ZERO;
    };
    let (u, v) = (rng.next_f32(), rng.next_f32());
    let Some((dir, weight)) = sky_lighting_sample(sky, n, u, v) else {
        return Vec3::ZERO;
    };
    *rays += 1;
    if accel.occluded(&s.spawn_ray(dir)) {
        return Vec3::ZERO;
    }
    sky.radiance(dir) * weight
}

/// Follows camera sample `pass` of pixel (i, j) to its visible point; adds the light seen on
/// the way and the direct light at the visible point to `direct`.
#[allow(clippy::too_many_arguments)]
fn visible_point(
    scene: &Scene,
    accel: &dyn Accel,
    camera: &CameraSampler,
    lights: &DirectLight,
    pixel: (u32, u32),
    pass: u32,
    direct: &mut [f64; 3],
    counts: &mut [u64; 3],
) -> Option<VisiblePoint> {
    let (mut ray, mut rng) = camera.sample(pixel, pass);
    let mut throughput = Vec3::ONE;
    let mut add = |c: Color| {
        for (d, v) in direct.iter_mut().zip(c.to_array()) {
            *d += v as f64;
        }
    };
    counts[0] += 1;
    let mut hit = closest_surface(accel, scene, &ray);
    for bounce in 0..=MAX_SPECULAR {
        let Some(s) = hit else {
            add(throughput * scene.sky_or_background(ray.direction));
            return None;
        };
        let m = &scene.materials[s.material as usize];
        let (front, n) = s.facing(ray.direction);
        if scene.sees_emission(&s, ray.direction) {
            add(throughput * m.emitted);
        }
        let albedo = scene.albedo(&s);
        let (d, r, t) = (
            albedo.max_element(),
            m.reflective.max_element(),
            m.transmitted.max_element(),
        );
        let total = d + r + t;
        if total <= 0.0 || bounce == MAX_SPECULAR {
            return None;
        }
        // One lobe, chosen in proportion to its largest channel (as the path tracer).
        let choice = rng.next_f32() * total;
        if choice < d {
            let lobe = throughput * albedo * (total / d);
            add(lobe * lights.sample(&s, n, accel, &mut rng, &mut counts[1]));
            add(lobe * sky_light(scene, accel, (&s, n), &mut rng, &mut counts[1]));
            add(lobe * delta_lights(scene, accel, (&s, n), &mut counts[1]));
            return Some(VisiblePoint {
                point: s.point,
                normal: s.geometric_side(n),
                weight: lobe * std::f32::consts::FRAC_1_PI,
            });
        }
        let dir = if choice < d + r {
            throughput *= m.reflective * (total / r);
            glossy_reflection(
                ray.direction,
                n,
                m.roughness,
                rng.next_f32(),
                rng.next_f32(),
            )
        } else {
            throughput *= m.transmitted * (total / t);
            Dielectric::at(m, front, ray.direction, n).sample(ray.direction, n, || rng.next_f32())
        };
        if bounce >= 3 {
            let survive = throughput.max_element().min(0.999);
            if rng.next_f32() >= survive {
                return None;
            }
            throughput *= survive.recip();
        }
        ray = s.spawn_ray(dir);
        counts[2] += 1;
        hit = closest_surface(accel, scene, &ray);
    }
    None
}

/// What an SPPM render made: the image and its counters.
pub struct Sppm {
    pub film: Film,
    pub stats: RenderStats,
    pub passes: u32,
    pub photons_per_pass: u64,
    /// The mean radius at the end, and at the start (absolute).
    pub mean_radius: f64,
    pub initial_radius: f64,
}

/// Renders by stochastic progressive photon mapping.
pub fn render(scene: &Scene, accel: &dyn Accel, settings: &RenderSettings) -> Sppm {
    let image = settings.image();
    let (w, h) = (settings.width, settings.height);
    let window = image.window();
    let passes = settings.num_antialias_samples.max(1);
    let camera = CameraSampler::new(scene, &image);
    let lights = DirectLight::new(scene);
    let emitters = Emitters::new(scene);
    // Nothing emits: no photon to trace, and the image is the direct light (none) alone.
    let photons = if emitters.any() {
        settings
            .photon
            .sppm_photons
            .unwrap_or(w as u64 * h as u64)
            .max(1)
    } else {
        0
    };
    let initial_radius =
        settings.photon.sppm_radius as f64 * scene.bounds().extent().length() as f64;
    let pixels = window.pixels();
    let mut state = vec![
        PixelState {
            radius2: initial_radius * initial_radius,
            photons: 0.0,
            tau: [0.0; 3],
            direct: [0.0; 3],
        };
        pixels
    ];
    let stats = RenderStats::default();
    // Under --time-limit, passes until the time is spent (a pass starts only if the last
    // one's time still fits), the bar showing the time.
    let start = std::time::Instant::now();
    let (passes, bar) = match settings.deadline {
        Some(_) => (u32::MAX, crate::progress::bar(1000, "sppm", settings.quiet)),
        None => (
            passes,
            crate::progress::bar(passes as u64, "sppm", settings.quiet),
        ),
    };
    let mut last_pass = std::time::Duration::ZERO;
    let mut done = 0;
    for pass in 0..passes {
        let pass_start = std::time::Instant::now();
        let out_of_time = settings
            .deadline
            .is_some_and(|d| done > 0 && pass_start + last_pass > d);
        if crate::interrupt::requested() || out_of_time {
            break;
        }
        // Visible points, row by row; each pixel's direct light added to its state.
        let points: Vec<Option<VisiblePoint>> = state
            .par_chunks_mut(window.width() as usize)
            .enumerate()
            .flat_map_iter(|(r, row)| {
                let j = h - 1 - (window.y0 + r as u32);
                let mut counts = [0u64; 3];
                let out: Vec<Option<VisiblePoint>> = row
                    .iter_mut()
                    .enumerate()
                    .map(|(c, st)| {
                        let i = window.x0 + c as u32;
                        visible_point(
                            scene,
                            accel,
                            &camera,
                            &lights,
                            (i, j),
                            pass,
                            &mut st.direct,
                            &mut counts,
                        )
                    })
                    .collect();
                stats.camera_rays.fetch_add(counts[0], Relaxed);
                stats.shadow_rays.fetch_add(counts[1], Relaxed);
                stats.secondary_rays.fetch_add(counts[2], Relaxed);
                out
            })
            .collect();
        let radius2: Vec<f64> = state.iter().map(|s| s.radius2).collect();
        let grid = Grid::build(&points, &radius2);
        // Photons in blocks; each block lists what it gives which visible point, in photon
        // order, and the lists are added in block order.
        let blocks = photons.div_ceil(PHOTON_BLOCK);
        let given: Vec<(Vec<(u32, Color)>, u64)> = (0..blocks)
            .into_par_iter()
            .map(|b| {
                let mut out = Vec::new();
                let mut rays = 0;
                for k in b * PHOTON_BLOCK..((b + 1) * PHOTON_BLOCK).min(photons) {
                    let mut rng = Rng::new(settings.seed ^ 0x5ee9_0000, pass as u64, k);
                    let (r, _) = emitters.trace(
                        scene,
                        accel,
                        photons,
                        SAFETY_DEPTH,
                        Aim::Everywhere,
                        &mut rng,
                        &mut |hit: &Hit| {
                            // The light straight from the emitters is the shadow rays'.
                            // (SPPM refuses fog: no photon scatters in a medium.)
                            if hit.kind == PathKind::Direct || hit.in_medium {
                                return;
                            }
                            let x = hit.point;
                            for &v in grid.near(x) {
                                let Some(vp) = &points[v as usize] else {
                                    continue;
                                };
                                if (vp.point - x).length_squared() as f64 <= radius2[v as usize]
                                    && vp.normal.dot(hit.direction) < 0.0
                                {
                                    out.push((v, hit.power));
                                }
                            }
                        },
                    );
                    rays += r;
                }
                (out, rays)
            })
            .collect();
        let mut flux = vec![[0.0f64; 3]; pixels];
        let mut arrived = vec![0u32; pixels];
        for (list, rays) in &given {
            stats.photon_rays.fetch_add(*rays, Relaxed);
            for &(v, power) in list {
                let f = &mut flux[v as usize];
                for (f, p) in f.iter_mut().zip(power.to_array()) {
                    *f += p as f64;
                }
                arrived[v as usize] += 1;
            }
        }
        // Each pixel: keep α of the photons that arrived, shrink the radius to match.
        for (k, st) in state.iter_mut().enumerate() {
            let (Some(vp), m) = (&points[k], arrived[k] as f64) else {
                continue;
            };
            if m == 0.0 {
                continue;
            }
            let kept = st.photons + ALPHA * m;
            let shrink = kept / (st.photons + m);
            let weight = vp.weight.to_array();
            for c in 0..3 {
                st.tau[c] = (st.tau[c] + weight[c] as f64 * flux[k][c]) * shrink;
            }
            st.photons = kept;
            st.radius2 *= shrink;
        }
        done += 1;
        last_pass = pass_start.elapsed();
        match settings.deadline {
            Some(d) => {
                let budget = d.saturating_duration_since(start).as_secs_f64().max(1e-9);
                bar.set_position(
                    (1000.0 * start.elapsed().as_secs_f64() / budget).min(1000.0) as u64,
                )
            }
            None => bar.inc(1),
        }
    }
    bar.finish_and_clear();
    if settings.deadline.is_some() {
        stats.samples_reached.store(done as u64, Relaxed);
    }
    let mut film = Film::new(w, h);
    let passes_done = done.max(1) as f64;
    for (k, st) in state.iter().enumerate() {
        let (x, row) = (
            window.x0 + (k % window.width() as usize) as u32,
            window.y0 + (k / window.width() as usize) as u32,
        );
        let area = std::f64::consts::PI * st.radius2;
        let value = |c: usize| ((st.direct[c] + st.tau[c] / area) / passes_done) as f32;
        film.pixels[row as usize * w as usize + x as usize] =
            Color::new(value(0), value(1), value(2));
    }
    let mean_radius = state.iter().map(|s| s.radius2.sqrt()).sum::<f64>() / pixels.max(1) as f64;
    Sppm {
        film,
        stats,
        passes: done,
        photons_per_pass: photons,
        mean_radius,
        initial_radius,
    }
}

/// The SPPM engine (`--engine sppm`).
pub struct SppmEngine;

impl Engine for SppmEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Sppm
    }

    fn structures(&self) -> &'static [&'static str] {
        &["visible points"]
    }

    fn unread_flags(&self) -> &'static [&'static str] {
        // Photons bring the indirect light; one shadow ray a pass brings the direct.
        &[
            "ambient_light",
            "indirect",
            "num_bounces",
            "num_shadow_samples",
            "light_sampling",
        ]
    }

    fn plan(&self, _scene: &Scene, settings: &RenderSettings) -> EnginePlan {
        let pixels = settings.image().window().pixels() as u64;
        let photons = settings
            .photon
            .sppm_photons
            .unwrap_or(settings.width as u64 * settings.height as u64);
        EnginePlan {
            structures: vec![(
                "visible points",
                format!(
                    "yes ({pixels} a pass, {} passes of {photons} photons)",
                    settings.num_antialias_samples.max(1)
                ),
            )],
            memory: vec![
                ("visible points", pixels.saturating_mul(PIXEL_BYTES)),
                (
                    "a pass's photons",
                    photons.saturating_mul(PASS_PHOTON_BYTES),
                ),
            ],
        }
    }

    /// The passes are coupled through the radii: the samples of a pixel cannot be split.
    fn samples_pixels(&self, _settings: &RenderSettings) -> bool {
        false
    }

    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        let sppm = render(scene, accel, settings);
        let summary = format!(
            "sppm: {} passes of {} photons, radius {:.3e} at the start, {:.3e} on average at the end",
            sppm.passes, sppm.photons_per_pass, sppm.initial_radius, sppm.mean_radius
        );
        Ok(Rendered {
            summary: vec![summary],
            ..Rendered::plain(sppm.film, sppm.stats)
        })
    }

    /// Passes doubling, with as many photons a pass as pixels.
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget> {
        Budget::samples_per_pixel(level, 10, base).map(|b| Budget {
            counts: "passes",
            ..b
        })
    }

    fn colour(&self) -> (u8, u8, u8) {
        (148, 103, 189)
    }
}
