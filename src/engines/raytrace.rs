//! Whitted and distribution ray tracing, physically based: `emitted` is radiance, `diffuse`
//! is albedo, a Lambertian surface of albedo ρ under irradiance E has radiance ρE/π.
//!
//! Direct light comes from every emitter, with N shadow rays per light
//! (`-num_shadow_samples`: 0 = the light's centre, unoccluded; 1 = one shadow ray to the
//! centre; N > 1 = N points placed by `--light-sampling`). By default (`solid-angle`)
//! rectangles are sampled across by solid angle and along by the receiver's cosine, spheres
//! by their cone, with multi-jittered points; the course's patterns (`random`, `stratified`,
//! `jittered`) place points by area for the estimator `Le·cosθ·cosθ'·A / (N·r²)`. Mirrors,
//! glossy reflection and glass recurse to `-num_bounces`; the diffuse indirect rest is the
//! constant `-ambient_light`, or the radiosity solution's indirect light (`--indirect
//! radiosity`).

use super::engine::RenderSettings;
use super::scattering::{
    delta_arrivals, power_heuristic, reflect, sky_lighting_sample, Dielectric, GlossyLobe,
};
use crate::accel::Accel;
use crate::film::ray_tree::{Segment, SegmentKind};
use crate::film::Film;
use crate::geometry::{offset_ray_origin, shadow_ray, vec3, Ray, Vec3};
use crate::render::adaptive::visible_form_factor;
use crate::render::lights::{
    Light, LightPoint, LightPower, LightShape, PointBlock, EVERY_LIGHT_UP_TO, LANES,
};
use crate::render::{render_pixels, Ambient, CameraSampler, Counts, IndirectLight, RenderStats};
use crate::sampling::{LightSampling, Rng, Strata};
use crate::scene::medium::Medium;
use crate::scene::{Camera, Color, Scene, SurfaceHit};

/// Branches of the ray tree whose weight falls below this are not traced: their
/// contribution cannot reach 1e-4 of the pixel.
const MIN_WEIGHT: f32 = 1e-4;

/// The ray tracer's light sampling when `--light-sampling` is not given: by solid angle. Its N
/// shadow rays a light are strata of the solid angle, which resolve the edges where walls meet
/// a large light, where points by area put fireflies (BENCHMARKS.md, "Light sampling").
pub const DEFAULT_LIGHT_SAMPLING: LightSampling = LightSampling::SolidAngle;

struct Tracer<'a> {
    /// Diffuse indirect light: the ambient term, a radiosity solution or photon maps.
    indirect: &'a dyn IndirectLight,
    scene: &'a Scene,
    accel: &'a dyn Accel,
    settings: &'a RenderSettings,
    lights: Vec<Light>,
    /// On scenes of more than `EVERY_LIGHT_UP_TO` lights, each light sample goes to a light
    /// chosen by its power (`pick`); on the rest every light takes its samples.
    power: Option<LightPower>,
    /// How the points on each light are placed (`--light-sampling`, default
    /// `DEFAULT_LIGHT_SAMPLING`).
    light_sampling: LightSampling,
    /// Where the N points on each light go (`--light-sampling`, `-num_shadow_samples`).
    light_strata: Strata,
    /// The rays traced, when recording a ray tree (`--ray-tree`); None while rendering.
    tree: Option<std::sync::Mutex<Vec<Segment>>>,
    /// Where the directions towards the sky go (`-num_shadow_samples`, at least one).
    sky_strata: Strata,
}

/// How a ray was chosen, for weighing the emitter it finds: from the camera or by a delta
/// (mirror, glass: the emission counts in full), or by a glossy lobe whose reflection of the
/// lights is also sampled from the lights, to be weighed against that by the power heuristic.
#[derive(Clone, Copy)]
enum Arrival {
    Delta,
    Glossy {
        /// The point it left and the normal there (light sampling's density depends on it).
        from: Vec3,
        normal: Vec3,
        /// The lobe's density in solid angle for its direction.
        pdf: f32,
    },
}

impl<'a> Tracer<'a> {
    fn new(
        scene: &'a Scene,
        accel: &'a dyn Accel,
        settings: &'a RenderSettings,
        indirect: &'a dyn IndirectLight,
        tree: Option<std::sync::Mutex<Vec<Segment>>>,
    ) -> Tracer<'a> {
        let lights = Light::collect(scene);
        let light_sampling = settings.light_sampling.unwrap_or(DEFAULT_LIGHT_SAMPLING);
        Tracer {
            indirect,
            scene,
            accel,
            settings,
            power: Some(LightPower::new(&lights))
                .filter(|p| lights.len() > EVERY_LIGHT_UP_TO && p.any()),
            lights,
            light_sampling,
            light_strata: Strata::new(light_sampling.pattern(), settings.num_shadow_samples),
            tree,
            sky_strata: Strata::new(
                crate::sampling::Pattern::Jittered,
                settings.num_shadow_samples.max(1),
            ),
        }
    }
}

/// Where a ray sits in the ray tree: how it was chosen, after how many specular bounces
/// (`depth`), and the product of the specular weights above it (`weight`, to prune faint
/// branches).
#[derive(Clone, Copy)]
struct Branch {
    arrival: Arrival,
    depth: u32,
    weight: f32,
    /// The medium the ray travels through (index into the scene's media): the fog outside
    /// closed objects, a material's `interior_medium` inside a glass one.
    medium: Option<usize>,
}

impl Branch {
    /// The camera's ray, in the fog if the scene has one.
    fn primary(scene: &Scene) -> Branch {
        Branch {
            arrival: Arrival::Delta,
            depth: 0,
            weight: 1.0,
            medium: scene.fog,
        }
    }

    /// A ray one bounce below this one, chosen as `arrival` says, carrying `factor` of its
    /// weight, on the same side of the surface (reflected).
    fn child(&self, arrival: Arrival, factor: f32) -> Branch {
        Branch {
            arrival,
            depth: self.depth + 1,
            weight: self.weight * factor,
            medium: self.medium,
        }
    }
}

impl Tracer<'_> {
    /// Radiance arriving along `ray` (on `branch` of the ray tree) whose closest hit is
    /// `hit`: what leaves the hit, and in the fog, that attenuated along the way plus the
    /// light the fog scatters into the ray.
    fn shade(
        &self,
        ray: &Ray,
        hit: Option<SurfaceHit>,
        branch: Branch,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        let Some(fog) = self.medium_of(branch) else {
            return self.leaving(ray, hit, branch, rng, counts);
        };
        let length = hit
            .as_ref()
            .map_or(f32::INFINITY, |s| s.point.distance(ray.origin));
        let in_scattered = self.in_scattered(fog, ray, length, rng, counts)
            + self.indirect.in_scattered(fog, ray, length, rng);
        let leaving = self.leaving(ray, hit, branch, rng, counts);
        fog.transmittance(length) * leaving + in_scattered
    }

    /// The fog `branch`'s ray travels through, if any.
    fn medium_of(&self, branch: Branch) -> Option<&Medium> {
        branch.medium.map(|k| &self.scene.media[k])
    }

    /// Radiance leaving the closest hit `hit` back along `ray` (the background where there
    /// is none).
    fn leaving(
        &self,
        ray: &Ray,
        hit: Option<SurfaceHit>,
        branch: Branch,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        let Some(s) = hit else {
            return self.scene.sky_or_background(ray.direction);
        };
        let m = &self.scene.materials[s.material as usize];
        let (front, n) = s.facing(ray.direction);
        let mut radiance = Vec3::ZERO;
        if self.scene.sees_emission(&s, ray.direction) {
            radiance += m.emitted * self.emission_weight(branch.arrival, &s);
        }
        let albedo = self.scene.albedo(&s);
        if albedo.max_element() > 0.0 {
            let fog = self.medium_of(branch);
            let irradiance_over_pi = self.direct(&s, n, fog, rng, counts)
                + self.sky_light(&s, n, fog, rng, counts)
                + self.delta_direct(&s, n, None, fog, counts);
            let indirect =
                self.indirect
                    .incident(self.scene, self.accel, &s, (n, fog), branch.depth, rng);
            radiance += albedo * (irradiance_over_pi + indirect);
        }
        if branch.depth >= self.settings.num_bounces {
            return radiance;
        }
        let reflective = m.reflective.max_element();
        if reflective > 0.0 && branch.weight * reflective > MIN_WEIGHT {
            let reflected = match GlossyLobe::new(ray.direction, n, m.roughness) {
                None => {
                    let r = s.spawn_ray(reflect(ray.direction, n));
                    self.trace(&r, branch.child(Arrival::Delta, reflective), rng, counts)
                }
                Some(lobe) => {
                    let fog = self.medium_of(branch);
                    let lit = self.glossy_direct(&s, n, &lobe, fog, rng, counts)
                        + self.delta_direct(&s, n, Some(&lobe), fog, counts);
                    let (dir, pdf) = lobe.sample(rng.next_f32(), rng.next_f32());
                    let arrival = match pdf {
                        Some(pdf) if self.samples_glossy_lights() => Arrival::Glossy {
                            from: s.point,
                            normal: n,
                            pdf,
                        },
                        _ => Arrival::Delta,
                    };
                    let r = s.spawn_ray(dir);
                    lit + self.trace(&r, branch.child(arrival, reflective), rng, counts)
                }
            };
            radiance += m.reflective * reflected;
        }
        let transmitted = m.transmitted.max_element();
        if transmitted > 0.0 && branch.weight * transmitted > MIN_WEIGHT {
            let glass = Dielectric::at(m, front, ray.direction, n);
            let f = glass.reflectance;
            let w = branch.weight * transmitted;
            let mut through = Vec3::ZERO;
            if f > 0.0 && w * f > MIN_WEIGHT {
                let r = s.spawn_ray(reflect(ray.direction, n));
                let child = branch.child(Arrival::Delta, transmitted * f);
                through += self.trace(&r, child, rng, counts) * f;
            }
            if f < 1.0 && w * (1.0 - f) > MIN_WEIGHT {
                if let Some(t) = glass.refracted(ray.direction, n) {
                    let r = s.spawn_ray(t);
                    let mut child = branch.child(Arrival::Delta, transmitted * (1.0 - f));
                    // Through glass the ray passes into the object's interior medium (none
                    // without one) or comes back into the fog (leaving it).
                    child.medium = if front {
                        m.interior_medium
                    } else {
                        self.scene.fog
                    };
                    through += self.trace(&r, child, rng, counts) * (1.0 - f);
                }
            }
            radiance += m.transmitted * through;
        }
        radiance
    }

    fn trace(&self, ray: &Ray, branch: Branch, rng: &mut Rng, counts: &mut Counts) -> Color {
        counts.secondary += 1;
        let hit = crate::accel::closest_surface(self.accel, self.scene, ray);
        self.record(ray, hit.as_ref(), SegmentKind::Specular);
        self.shade(ray, hit, branch, rng, counts)
    }

    /// Whether glossy lobes take light samples (weighed against the lobe's own samples by
    /// multiple importance sampling): with area lights sampled (N > 1 shadow rays); the
    /// course's one-ray modes leave glossy reflections of the lights to the lobe alone.
    fn samples_glossy_lights(&self) -> bool {
        self.settings.num_shadow_samples > 1
    }

    /// What share of an emitter's radiance a ray that arrived as `arrival` at its point `s`
    /// brings: all of it, unless a glossy lobe chose it and the lights were sampled too;
    /// then the power heuristic's share against the light sample's density.
    fn emission_weight(&self, arrival: Arrival, s: &SurfaceHit) -> f32 {
        let Arrival::Glossy { from, normal, pdf } = arrival else {
            return 1.0;
        };
        let Some(k) = Light::index_of(&self.lights, s.prim) else {
            return 1.0;
        };
        let light_pdf = self.choice_probability(k)
            * self.lights[k].pdf_towards(from, normal, s.point, s.geometric_normal);
        power_heuristic(pdf, light_pdf)
    }

    /// The lights' direct reflection in a glossy lobe at `s` (normal `n` on the lit side):
    /// one light sample per light, each weighed against the lobe's sampling by the power
    /// heuristic; the lobe's own samples bring the rest (`emission_weight`).
    fn glossy_direct(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        lobe: &GlossyLobe,
        fog: Option<&Medium>,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        if !self.samples_glossy_lights() {
            return Vec3::ZERO;
        }
        let origin = offset_ray_origin(s.point, n, s.error);
        let mut total = Vec3::ZERO;
        for i in 0..self.picks(1) {
            let (light, chosen) = self.pick(i, 1, rng);
            let (u, v) = (rng.next_f32(), rng.next_f32());
            if light.prim == s.prim {
                continue;
            }
            let Some(d) = light.sample_towards(s.point, n, u, v) else {
                continue;
            };
            let dir = (d.point - s.point).normalize_or_zero();
            let lobe_pdf = lobe.pdf(dir);
            let light_pdf = chosen * d.pdf;
            if !(lobe_pdf > 0.0 && light_pdf > 0.0 && light_pdf.is_finite()) {
                continue;
            }
            let ray = shadow_ray(origin, d.point);
            record_segment(self.tree.as_ref(), origin, d.point, SegmentKind::Shadow);
            counts.shadow += 1;
            if !self.accel.occluded(&ray) {
                total += light.emitted
                    * transmittance(fog, origin.distance(d.point))
                    * (lobe_pdf / light_pdf * power_heuristic(light_pdf, lobe_pdf));
            }
        }
        total
    }

    /// How many light samples a point takes for `per_light` samples a light: every light's,
    /// or, on scenes of many lights, as many as one light takes (`pick` chooses their lights).
    fn picks(&self, per_light: usize) -> usize {
        match self.power {
            None => self.lights.len() * per_light,
            Some(_) => per_light,
        }
    }

    /// The light of a point's light sample `i` (of `picks(per_light)`) and the probability
    /// it was chosen with: on scenes of few lights, each light in turn for its `per_light`
    /// samples (probability 1); on scenes of many, a light drawn by its power from `rng`.
    fn pick(&self, i: usize, per_light: usize, rng: &mut Rng) -> (&Light, f32) {
        match &self.power {
            None => (&self.lights[i / per_light], 1.0),
            Some(power) => {
                let k = power.choose(rng.next_f32());
                (&self.lights[k], power.probability(k))
            }
        }
    }

    /// The probability with which a light sample chooses light `k` (`pick`).
    fn choice_probability(&self, k: usize) -> f32 {
        self.power.as_ref().map_or(1.0, |p| p.probability(k))
    }

    /// What the lights without area send a surface point (normal `n` on the lit side)
    /// through `fog`: per unit albedo, irradiance × cos/π (`lobe` None); per unit
    /// reflectance of a glossy `lobe`, irradiance × its density. One shadow ray each (none
    /// with `-num_shadow_samples 0`, which leaves every light unoccluded); neither the lobe's
    /// samples nor any other find them.
    fn delta_direct(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        lobe: Option<&GlossyLobe>,
        fog: Option<&Medium>,
        counts: &mut Counts,
    ) -> Color {
        let mut total = Vec3::ZERO;
        for a in delta_arrivals(self.scene, s, n) {
            let value = a.value(lobe);
            if value <= 0.0 {
                continue;
            }
            if self.settings.num_shadow_samples > 0 {
                if a.distance.is_finite() {
                    // The shadow ray spans origin + t·d for t < 1, to the light.
                    let light = a.ray.at(1.0);
                    record_segment(self.tree.as_ref(), a.ray.origin, light, SegmentKind::Shadow);
                } else {
                    self.record(&a.ray, None, SegmentKind::Shadow);
                }
                counts.shadow += 1;
                if self.accel.occluded(&a.ray) {
                    continue;
                }
            }
            total += a.irradiance * (value * transmittance(fog, a.distance));
        }
        total
    }

    /// The sky's irradiance at a surface point divided by π (`n`: the normal on the lit
    /// side): `-num_shadow_samples` directions (at least one) stratified in the cosine about
    /// `n`, each bringing the sky's radiance where its shadow ray leaves the scene (with 0,
    /// unoccluded, as the lights are), through the fog if any (which then hides it: the fog
    /// is infinite). The mean is exact under a uniform sky that nothing hides.
    fn sky_light(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        fog: Option<&Medium>,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        let Some(sky) = &self.scene.sky else {
            return Vec3::ZERO;
        };
        let samples = self.settings.num_shadow_samples;
        let count = samples.max(1);
        let mut total = Vec3::ZERO;
        for (u, v) in self.sky_strata.samples(rng) {
            let Some((dir, weight)) = sky_lighting_sample(sky, n, u, v) else {
                continue;
            };
            if samples > 0 {
                counts.shadow += 1;
                if self.accel.occluded(&s.spawn_ray(dir)) {
                    continue;
                }
            }
            total += sky.radiance(dir) * weight;
        }
        total * transmittance(fog, f32::INFINITY) / count as f32
    }

    /// The light `fog` scatters into `ray` over its first `length` (∞: the ray leaves the
    /// scene): single scattering of every light, each by `-num_shadow_samples` points
    /// (the centre for 0 and 1, 0 leaving visibility out as at surfaces; on scenes of many
    /// lights, that many points on lights chosen by their power) with the distance
    /// along the ray sampled equiangularly about each point (Kulla & Fajardo 2012: the
    /// density follows the 1/r² of the light's falloff, so a small light's glow costs no
    /// more samples than a surface's shadow). The indirect light's share (the ambient term,
    /// the volume photons) is `IndirectLight::in_scattered`'s.
    fn in_scattered(
        &self,
        fog: &Medium,
        ray: &Ray,
        length: f32,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        let scale = ray.direction.length();
        if fog.sigma_s.max_element() <= 0.0 || scale.is_nan() || scale <= 0.0 {
            return Vec3::ZERO;
        }
        let travel = ray.direction / scale;
        let mut total = Vec3::ZERO;
        let samples = self.settings.num_shadow_samples;
        let count = samples.max(1);
        for i in 0..self.picks(count as usize) {
            let (light, chosen) = self.pick(i, count as usize, rng);
            let (u, v, w) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
            let point = if samples <= 1 {
                light.centre(ray.origin)
            } else {
                light.sample(u, v)
            };
            let Some((t, pdf)) = equiangular(ray.origin, travel, length, point.point, w) else {
                continue;
            };
            let x = ray.origin + travel * t;
            let to_light = point.point - x;
            let r2 = to_light.length_squared();
            let r = r2.sqrt();
            let cos_light = -point.normal.dot(to_light) / r;
            let cos_light = if point.one_sided {
                cos_light
            } else {
                cos_light.abs()
            };
            if cos_light.is_nan() || cos_light <= 0.0 || r2 <= 0.0 {
                continue;
            }
            if samples > 0 {
                counts.shadow += 1;
                if self.accel.occluded(&shadow_ray(x, point.point)) {
                    continue;
                }
            }
            // Area-sampled point: radiance × cos' × area / r² is the light's solid angle
            // integral of its radiance, one point's share.
            let geometry = cos_light * light.area / r2 / count as f32 / chosen;
            total += light.emitted
                * fog.sigma_s
                * fog.transmittance(t)
                * fog.transmittance(r)
                * (fog.phase(travel, to_light / r) * geometry / pdf);
        }
        total
    }

    /// Adds a ray to the ray tree, when one is being recorded.
    fn record(&self, ray: &Ray, hit: Option<&SurfaceHit>, kind: SegmentKind) {
        if self.tree.is_none() {
            return;
        }
        let to = match hit {
            Some(s) => s.point,
            // A ray that leaves the scene is drawn out to twice the scene's size.
            None => ray.at(2.0 * self.scene.bounds().extent().length() / ray.direction.length()),
        };
        record_segment(self.tree.as_ref(), ray.origin, to, kind);
    }

    /// `direct` on scenes of more than `EVERY_LIGHT_UP_TO` lights: each of the
    /// `-num_shadow_samples` points (at least one) on a light chosen by its power, the light's
    /// centre for 0 and 1 (0 unoccluded), else a point as `Light::sample_towards` takes it.
    fn direct_by_power(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        fog: Option<&Medium>,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        let samples = self.settings.num_shadow_samples;
        let count = samples.max(1) as usize;
        let origin = offset_ray_origin(s.point, n, s.error);
        let mut total = Vec3::ZERO;
        for i in 0..self.picks(count) {
            let (light, chosen) = self.pick(i, count, rng);
            let (u, v) = (rng.next_f32(), rng.next_f32());
            if light.prim == s.prim {
                continue;
            }
            let (point, weight) = if samples <= 1 {
                let centre = light.centre(s.point);
                let Some(g) = geometric_term(s.point, n, &centre) else {
                    continue;
                };
                (centre.point, g * light.area / std::f32::consts::PI)
            } else {
                let Some(d) = light.sample_towards(s.point, n, u, v) else {
                    continue;
                };
                (d.point, d.weight)
            };
            if samples > 0 {
                record_segment(self.tree.as_ref(), origin, point, SegmentKind::Shadow);
                counts.shadow += 1;
                if self.accel.occluded(&shadow_ray(origin, point)) {
                    continue;
                }
            }
            total += light.emitted
                * transmittance(fog, s.point.distance(point))
                * (weight / (count as f32 * chosen));
        }
        total
    }

    /// Direct irradiance at a surface point divided by π, so that albedo × this is the
    /// reflected radiance. `n`: the normal on the side being lit; `fog`: the medium the
    /// light crosses to reach it, if any. On scenes of many lights, `direct_by_power`.
    fn direct(
        &self,
        s: &SurfaceHit,
        n: Vec3,
        fog: Option<&Medium>,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        if self.power.is_some() {
            return self.direct_by_power(s, n, fog, rng, counts);
        }
        let samples = self.settings.num_shadow_samples;
        let count = samples.max(1) as usize;
        // Every shadow ray leaves on the lit side (n · dir > 0): one offset origin serves all.
        let origin = offset_ray_origin(s.point, n, s.error);
        counts
            .shadow_rays
            .resize(count, shadow_ray(origin, s.point));
        counts.shadow_weights.resize(count, 0.0);
        counts.blocked.resize(count, false);
        let mut total = Vec3::ZERO;
        for light in &self.lights {
            if light.prim == s.prim {
                continue;
            }
            let per_sample = light.area / count as f32 / std::f32::consts::PI;
            if samples == 0 {
                let centre = light.centre(s.point);
                if let Some(g) = geometric_term(s.point, n, &centre) {
                    total += light.emitted
                        * transmittance(fog, s.point.distance(centre.point))
                        * (g * per_sample);
                }
                continue;
            }
            let mut batch = ShadowBatch {
                x: s.point,
                n,
                origin,
                per_sample,
                rays: &mut counts.shadow_rays[..count],
                weights: &mut counts.shadow_weights[..count],
                len: 0,
                tree: self.tree.as_ref(),
            };
            if samples == 1 {
                batch.push(light.centre(s.point));
            } else if let (LightSampling::Adaptive, LightShape::Parallelogram(quad), None) =
                (self.light_sampling, &light.shape, fog)
            {
                // (In fog the light's corners do not bound what each point brings through
                // the medium: the points are sampled by solid angle below instead.)
                let mut rays = 0;
                let visible = visible_form_factor(
                    s.point,
                    n,
                    quad,
                    self.settings.adaptive_depth,
                    &mut counts.corners,
                    |p| {
                        rays += 1;
                        record_segment(self.tree.as_ref(), origin, p, SegmentKind::Shadow);
                        !self.accel.occluded(&shadow_ray(origin, p))
                    },
                );
                counts.shadow += rays;
                total += light.emitted * visible;
                continue;
            } else {
                let by_solid_angle = if self.light_sampling.by_solid_angle()
                    || (self.light_sampling == LightSampling::Adaptive && fog.is_some())
                {
                    light.solid_angle_sampler(s.point)
                } else {
                    None
                };
                match (light.shape, by_solid_angle) {
                    // By solid angle (rectangles, spheres by their cone) each point carries
                    // its own weight, bounded however near the light the point is.
                    (_, Some(sampler)) => {
                        batch.per_sample = 1.0 / count as f32;
                        for (u, v) in self.light_strata.samples(rng) {
                            if let Some(d) = sampler.sample_towards(n, u, v) {
                                batch.add(d.point, d.weight);
                            }
                        }
                    }
                    // Quad lights sampled by area take their own loop with the parallelogram
                    // copied out of the light, held in registers: read through `light` the
                    // normal was re-read for every ray, and the read stalled on store
                    // forwarding (perf: a fifth of `shade`).
                    // The numbers are drawn even where the light's side facing the point
                    // does not emit, so that the next light's are the same either way.
                    (LightShape::Parallelogram(quad), None) => {
                        let facing = quad.normal_towards(s.point);
                        let mut samples = self.light_strata.samples(rng);
                        let (mut u, mut v) = ([0.0; LANES], [0.0; LANES]);
                        let mut left = count;
                        while left > 0 {
                            let m = left.min(LANES);
                            for (i, (ui, vi)) in samples.by_ref().take(m).enumerate() {
                                (u[i], v[i]) = (ui, vi);
                            }
                            if let Some(normal) = facing {
                                batch.push_block(&quad.sample_block(&u, &v), normal, m);
                            }
                            left -= m;
                        }
                    }
                    _ => {
                        for (u, v) in self.light_strata.samples(rng) {
                            batch.push(light.sample(u, v));
                        }
                    }
                }
            }
            let n_rays = batch.len;
            if n_rays > 0 {
                let blocked = &mut counts.blocked[..n_rays];
                self.accel
                    .occluded_batch(&counts.shadow_rays[..n_rays], blocked);
                counts.shadow += n_rays as u64;
                let unblocked = counts.shadow_weights[..n_rays]
                    .iter()
                    .zip(&counts.shadow_rays[..n_rays])
                    .zip(blocked.iter())
                    .filter(|(_, &b)| !b)
                    .map(|(wr, _)| wr);
                let visible = match fog {
                    // Each shadow ray spans the way to its light point: attenuated by that.
                    Some(fog) => unblocked
                        .map(|(w, ray)| fog.transmittance(ray.direction.length()) * *w)
                        .sum(),
                    None => Vec3::splat(unblocked.map(|(w, _)| w).sum()),
                };
                total += light.emitted * visible;
            }
        }
        total
    }
}

/// The shadow rays from one surface point to one light, gathered to be traced as one batch.
/// Written into slices rather than pushed onto vectors: a vector's length and buffer, which
/// the stored rays might overwrite as far as the compiler knows, were re-read for every ray.
struct ShadowBatch<'a> {
    /// The surface point and its unit normal on the lit side.
    x: Vec3,
    n: Vec3,
    /// Where every ray starts: `x` moved off the surface on the lit side.
    origin: Vec3,
    /// Each ray's share of the light's contribution: area / (N·π) by area, 1/N by solid
    /// angle.
    per_sample: f32,
    rays: &'a mut [Ray],
    /// The unoccluded contribution of each ray (geometric term × `per_sample`).
    weights: &'a mut [f32],
    /// Rays gathered so far.
    len: usize,
    /// The ray tree being recorded (`--ray-tree`), None while rendering.
    tree: Option<&'a std::sync::Mutex<Vec<Segment>>>,
}

impl ShadowBatch<'_> {
    /// Adds the ray to the light point `p`, unless either side faces away.
    #[inline(always)]
    fn push(&mut self, p: LightPoint) {
        if let Some(g) = geometric_term(self.x, self.n, &p) {
            self.add(p.point, g);
        }
    }

    /// `push` for the first `m` points of a block on a planar light whose side of unit normal
    /// `normal` emits: the geometric terms lane by lane (vector instructions, the same arithmetic
    /// as `geometric_term`), then the rays of the lanes that face each other.
    #[inline(always)]
    fn push_block(&mut self, p: &PointBlock, normal: Vec3, m: usize) {
        let (x, n) = (self.x, self.n);
        let mut g = [0.0f32; LANES];
        let mut facing = [false; LANES];
        for i in 0..LANES {
            let (wx, wy, wz) = (p.x[i] - x.x, p.y[i] - x.y, p.z[i] - x.z);
            let r2 = wx * wx + wy * wy + wz * wz;
            let along_surface = n.x * wx + n.y * wy + n.z * wz;
            let along_light = -(normal.x * wx + normal.y * wy + normal.z * wz);
            facing[i] = r2 > 0.0 && along_surface > 0.0 && along_light > 0.0;
            g[i] = along_surface * along_light / (r2 * r2);
        }
        for i in 0..m {
            if facing[i] {
                self.add(vec3(p.x[i], p.y[i], p.z[i]), g[i]);
            }
        }
    }

    /// Adds the ray to `point`, of geometric term `g`.
    #[inline(always)]
    fn add(&mut self, point: Vec3, g: f32) {
        let ray = shadow_ray(self.origin, point);
        record_segment(self.tree, ray.origin, point, SegmentKind::Shadow);
        self.rays[self.len] = ray;
        self.weights[self.len] = g * self.per_sample;
        self.len += 1;
    }
}

/// Adds the segment from `from` to `to` to the ray tree being recorded, if any.
fn record_segment(
    tree: Option<&std::sync::Mutex<Vec<Segment>>>,
    from: Vec3,
    to: Vec3,
    kind: SegmentKind,
) {
    if let Some(Ok(mut t)) = tree.map(|t| t.lock()) {
        t.push(Segment { from, to, kind });
    }
}

/// The transmittance of `fog` over `distance`; 1 without fog.
#[inline]
fn transmittance(fog: Option<&Medium>, distance: f32) -> Color {
    fog.map_or(Vec3::ONE, |m| m.transmittance(distance))
}

/// A distance t in [0, `length`) along the unit `travel` from `origin`, sampled with density
/// proportional to 1/r² of the distance r to `point` (equiangular sampling: uniform in the
/// angle subtended at `point`), from a uniform `u`; with its density. None where the ray
/// passes through the point.
fn equiangular(origin: Vec3, travel: Vec3, length: f32, point: Vec3, u: f32) -> Option<(f32, f32)> {
    let along = (point - origin).dot(travel);
    let distance = ((point - origin).length_squared() - along * along)
        .max(0.0)
        .sqrt();
    if distance.is_nan() || distance <= 1e-7 {
        return None;
    }
    let first = (-along / distance).atan();
    let last = if length.is_finite() {
        ((length - along) / distance).atan()
    } else {
        std::f32::consts::FRAC_PI_2
    };
    let span = last - first;
    if span.is_nan() || span <= 0.0 {
        return None;
    }
    let t = (along + distance * (first + u * span).tan()).clamp(0.0, length);
    let offset = t - along;
    let pdf = distance / (span * (distance * distance + offset * offset));
    (pdf > 0.0 && pdf.is_finite() && t.is_finite()).then_some((t, pdf))
}

/// cosθ·cosθ'/r² between the surface point `x` (normal `n`, on the lit side) and the light
/// point `p`, or None where either faces away. With w unnormalised it is (n·w)(−n'·w)/r⁴: no
/// square root.
#[inline(always)]
fn geometric_term(x: Vec3, n: Vec3, p: &LightPoint) -> Option<f32> {
    let w = p.point - x;
    let r2 = w.length_squared();
    let along_surface = n.dot(w);
    let along_light = -p.normal.dot(w);
    let along_light = if p.one_sided {
        along_light
    } else {
        along_light.abs()
    };
    if r2.is_nan() || r2 <= 0.0 || along_surface <= 0.0 || along_light <= 0.0 {
        return None;
    }
    Some(along_surface * along_light / (r2 * r2))
}

/// Renders the scene by ray tracing with `-ambient_light` as the indirect light.
pub fn render(scene: &Scene, accel: &dyn Accel, settings: &RenderSettings) -> (Film, RenderStats) {
    render_with(scene, accel, settings, &Ambient(settings.ambient_light))
}

/// Renders the scene by ray tracing with the given indirect light; returns the film and the
/// counters of the render.
pub fn render_with(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    indirect: &dyn IndirectLight,
) -> (Film, RenderStats) {
    let tracer = Tracer::new(scene, accel, settings, indirect, None);
    render_pixels(
        scene,
        accel,
        &settings.image(),
        "raytrace",
        |ray, hit, rng, _, counts| tracer.shade(ray, hit, Branch::primary(scene), rng, counts),
    )
}

/// The ray tree of pixel (x, y) (column from the left, row from the bottom, as the course's
/// screen coordinates) seen through `camera`: every ray its samples trace, in the order
/// traced. The samples are those of `render` with the same settings and camera, so the tree
/// explains that pixel of the image.
pub fn ray_tree(
    scene: &Scene,
    camera: &Camera,
    accel: &dyn Accel,
    settings: &RenderSettings,
    (x, y): (u32, u32),
) -> Vec<Segment> {
    let ambient = Ambient(settings.ambient_light);
    let tree = Some(std::sync::Mutex::new(Vec::new()));
    let tracer = Tracer::new(scene, accel, settings, &ambient, tree);
    let camera = CameraSampler::with_camera(camera, &settings.image());
    let spp = settings.num_antialias_samples.max(1);
    let mut counts = Counts::default();
    for k in 0..spp {
        let (ray, mut rng) = camera.sample((x, y), k);
        let hit = crate::accel::closest_surface(accel, scene, &ray);
        tracer.record(&ray, hit.as_ref(), SegmentKind::Eye);
        tracer.shade(&ray, hit, Branch::primary(scene), &mut rng, &mut counts);
    }
    tracer
        .tree
        .and_then(|t| t.into_inner().ok())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    /// The block path gives the same rays and weights, bit for bit, as point-by-point
    /// `push` (the per-point path every other light takes), including the points that face
    /// away and are left out: a 2×0.5 light, tilted, one-sided and then two-sided, above
    /// surface points on every side of it.
    #[test]
    fn block_of_light_samples_matches_point_by_point() {
        let text = "material\ndiffuse 0 0 0\nemitted 1 1 1\n\
                    m 0\nv -1 1 0.2\nv -1 1.3 -0.3\nv 1 1.3 -0.3\nv 1 1 0.2\nf 1 2 3 4\n";
        let mut scene = Scene::parse_dialect(std::path::Path::new("t.obj"), text).expect("parses");
        let mut rng = Rng::new(11, 0, 0);
        let (mut kept, mut tried) = (0, 0);
        for round in 0..400 {
            // One-sided, then two-sided (`--two-sided`: the back emits too).
            scene.two_sided_quads = round >= 200;
            let light = Light::collect(&scene)[0];
            let LightShape::Parallelogram(quad) = light.shape else {
                panic!("a quad light");
            };
            let x = vec3(
                4.0 * rng.next_f32() - 2.0,
                2.0 * rng.next_f32(),
                4.0 * rng.next_f32() - 2.0,
            );
            let n = vec3(rng.next_f32() - 0.5, 1.0, rng.next_f32() - 0.5).normalize_or_zero();
            let (u, v): ([f32; LANES], [f32; LANES]) = (
                std::array::from_fn(|_| rng.next_f32()),
                std::array::from_fn(|_| rng.next_f32()),
            );
            for m in [LANES, 3] {
                let mut rays = [[shadow_ray(x, x); LANES]; 2];
                let mut weights = [[0.0f32; LANES]; 2];
                let [rays_a, rays_b] = &mut rays;
                let [weights_a, weights_b] = &mut weights;
                let batch = |rays, weights| ShadowBatch {
                    x,
                    n,
                    origin: x + n * 1e-3,
                    per_sample: 0.25,
                    rays,
                    weights,
                    len: 0,
                    tree: None,
                };
                let mut one_by_one = batch(&mut rays_a[..], &mut weights_a[..]);
                for i in 0..m {
                    one_by_one.push(quad.sample(u[i], v[i]));
                }
                let mut block = batch(&mut rays_b[..], &mut weights_b[..]);
                if let Some(normal) = quad.normal_towards(x) {
                    block.push_block(&quad.sample_block(&u, &v), normal, m);
                }
                assert_eq!(one_by_one.len, block.len);
                let len = block.len;
                (kept, tried) = (kept + len, tried + m);
                assert_eq!(rays_a[..len], rays_b[..len]);
                assert_eq!(weights_a[..len], weights_b[..len]);
            }
        }
        // Both kinds of point occur: rays kept and rays left out.
        assert!(
            kept > tried / 10 && kept < tried * 9 / 10,
            "{kept} of {tried}"
        );
    }
}
