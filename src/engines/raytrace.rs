//! Whitted and distribution ray tracing, physically based: `emitted` is radiance, `diffuse`
//! is albedo, a Lambertian surface of albedo ρ under irradiance E has radiance ρE/π.
//!
//! Direct light comes from every emitter by the area estimator `Le·cosθ·cosθ'·A / (N·r²)`,
//! with N shadow rays per light (`-num_shadow_samples`: 0 = the light's centre, unoccluded;
//! 1 = one shadow ray to the centre; N > 1 = N points placed by `--light-sampling`). Mirrors,
//! glossy reflection and glass recurse to `-num_bounces`; the diffuse indirect rest is the
//! constant `-ambient_light`, or the radiosity solution's indirect light (`--indirect
//! radiosity`).

use super::engine::RenderSettings;
use super::scattering::{glossy_reflection, reflect, Dielectric};
use crate::accel::Accel;
use crate::film::ray_tree::{Segment, SegmentKind};
use crate::film::Film;
use crate::geometry::{offset_ray_origin, shadow_ray, vec3, Ray, Vec3};
use crate::render::lights::{Light, LightPoint, LightShape, PointBlock, LANES};
use crate::render::{render_pixels, Ambient, CameraSampler, Counts, IndirectLight, RenderStats};
use crate::sampling::{LightSampling, Rng, Strata};
use crate::scene::{Color, Scene, SurfaceHit};

/// Branches of the ray tree whose weight falls below this are not traced: their
/// contribution cannot reach 1e-4 of the pixel.
const MIN_WEIGHT: f32 = 1e-4;

struct Tracer<'a> {
    /// Diffuse indirect light: the ambient term, a radiosity solution or photon maps.
    indirect: &'a dyn IndirectLight,
    scene: &'a Scene,
    accel: &'a dyn Accel,
    settings: &'a RenderSettings,
    lights: Vec<Light>,
    /// Where the N points on each light go (`--light-sampling`, `-num_shadow_samples`).
    light_strata: Strata,
    /// The rays traced, when recording a ray tree (`--ray-tree`); None while rendering.
    tree: Option<std::sync::Mutex<Vec<Segment>>>,
}

impl Tracer<'_> {
    /// Radiance arriving along `ray` whose closest hit is `hit`; `depth` specular bounces so
    /// far, `weight` the product of the specular weights above (to prune faint branches).
    fn shade(
        &self,
        ray: &Ray,
        hit: Option<SurfaceHit>,
        depth: u32,
        weight: f32,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        let Some(s) = hit else {
            return self.scene.background;
        };
        let m = &self.scene.materials[s.material as usize];
        let (front, n) = s.facing(ray.direction);
        let mut radiance = Vec3::ZERO;
        if self.scene.sees_emission(&s, ray.direction) {
            radiance += m.emitted;
        }
        let albedo = self.scene.albedo(&s);
        if albedo.max_element() > 0.0 {
            let irradiance_over_pi = self.direct(&s, n, rng, counts);
            let indirect = self
                .indirect
                .incident(self.scene, self.accel, &s, n, depth, rng);
            radiance += albedo * (irradiance_over_pi + indirect);
        }
        if depth >= self.settings.num_bounces {
            return radiance;
        }
        if m.reflective.max_element() > 0.0 && weight * m.reflective.max_element() > MIN_WEIGHT {
            let dir = glossy_reflection(
                ray.direction,
                n,
                m.roughness,
                rng.next_f32(),
                rng.next_f32(),
            );
            let w = weight * m.reflective.max_element();
            radiance += m.reflective * self.trace(&s.spawn_ray(dir), depth + 1, w, rng, counts);
        }
        if m.transmitted.max_element() > 0.0 && weight * m.transmitted.max_element() > MIN_WEIGHT {
            let glass = Dielectric::at(m, front, ray.direction, n);
            let f = glass.reflectance;
            let w = weight * m.transmitted.max_element();
            let mut through = Vec3::ZERO;
            if f > 0.0 && w * f > MIN_WEIGHT {
                let r = s.spawn_ray(reflect(ray.direction, n));
                through += self.trace(&r, depth + 1, w * f, rng, counts) * f;
            }
            if f < 1.0 && w * (1.0 - f) > MIN_WEIGHT {
                if let Some(t) = glass.refracted(ray.direction, n) {
                    let r = s.spawn_ray(t);
                    through += self.trace(&r, depth + 1, w * (1.0 - f), rng, counts) * (1.0 - f);
                }
            }
            radiance += m.transmitted * through;
        }
        radiance
    }

    fn trace(
        &self,
        ray: &Ray,
        depth: u32,
        weight: f32,
        rng: &mut Rng,
        counts: &mut Counts,
    ) -> Color {
        counts.secondary += 1;
        let hit = crate::accel::closest_surface(self.accel, self.scene, ray);
        self.record(ray, hit.as_ref(), SegmentKind::Specular);
        self.shade(ray, hit, depth, weight, rng, counts)
    }

    /// Adds a ray to the ray tree, when one is being recorded.
    fn record(&self, ray: &Ray, hit: Option<&SurfaceHit>, kind: SegmentKind) {
        if let Some(tree) = &self.tree {
            let to = match hit {
                Some(s) => s.point,
                // A ray that leaves the scene is drawn out to twice the scene's size.
                None => {
                    ray.at(2.0 * self.scene.bounds().extent().length() / ray.direction.length())
                }
            };
            if let Ok(mut t) = tree.lock() {
                t.push(Segment {
                    from: ray.origin,
                    to,
                    kind,
                });
            }
        }
    }

    /// Direct irradiance at a surface point divided by π, so that albedo × this is the
    /// reflected radiance. `n`: the normal on the side being lit.
    fn direct(&self, s: &SurfaceHit, n: Vec3, rng: &mut Rng, counts: &mut Counts) -> Color {
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
                if let Some(g) = geometric_term(s.point, n, &light.centre(s.point)) {
                    total += light.emitted * (g * per_sample);
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
            } else {
                let by_solid_angle = if self.settings.light_sampling == LightSampling::SolidAngle {
                    light.solid_angle_sampler(s.point)
                } else {
                    None
                };
                match (light.shape, by_solid_angle) {
                    // Uniform in solid angle (rectangles, spheres by their cone) every point
                    // weighs Ω/(N·π) times the receiver's cosine: bounded, however near the
                    // light the point is.
                    (_, Some(rect)) => {
                        batch.per_sample =
                            (rect.solid_angle() / (count as f64 * std::f64::consts::PI)) as f32;
                        for (u, v) in self.light_strata.samples(rng) {
                            batch.push_in_solid_angle(rect.sample(u, v));
                        }
                    }
                    // Quad lights sampled by area take their own loop with the parallelogram
                    // copied out of the light, held in registers: read through `light` the
                    // normal was re-read for every ray, and the read stalled on store
                    // forwarding (perf: a fifth of `shade`).
                    (LightShape::Parallelogram(quad), None) => {
                        let mut samples = self.light_strata.samples(rng);
                        let (mut u, mut v) = ([0.0; LANES], [0.0; LANES]);
                        let mut left = count;
                        while left > 0 {
                            let m = left.min(LANES);
                            for (i, (ui, vi)) in samples.by_ref().take(m).enumerate() {
                                (u[i], v[i]) = (ui, vi);
                            }
                            batch.push_block(&quad.sample_block(&u, &v), quad.normal(), m);
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
                let visible: f32 = counts.shadow_weights[..n_rays]
                    .iter()
                    .zip(blocked.iter())
                    .filter(|(_, &b)| !b)
                    .map(|(w, _)| w)
                    .sum();
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
    /// Each ray's share of the light's contribution: area / (N·π).
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

    /// Adds the ray to `point`, sampled uniformly in the solid angle of its light: its weight
    /// is the receiver's cosine (times `per_sample`, Ω/(N·π)), nothing if it lies below the
    /// surface.
    #[inline(always)]
    fn push_in_solid_angle(&mut self, point: Vec3) {
        let w = point - self.x;
        let along_surface = self.n.dot(w);
        if along_surface > 0.0 {
            self.add(point, along_surface / w.length());
        }
    }

    /// `push` for the first `m` points of a block on a one-sided planar light of unit normal
    /// `normal`: the geometric terms lane by lane (vector instructions, the same arithmetic
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
        if let Some(tree) = self.tree {
            if let Ok(mut t) = tree.lock() {
                t.push(Segment {
                    from: ray.origin,
                    to: point,
                    kind: SegmentKind::Shadow,
                });
            }
        }
        self.rays[self.len] = ray;
        self.weights[self.len] = g * self.per_sample;
        self.len += 1;
    }
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
    let tracer = Tracer {
        indirect,
        scene,
        accel,
        settings,
        lights: Light::collect(scene),
        light_strata: Strata::new(
            settings.light_sampling.pattern(),
            settings.num_shadow_samples,
        ),
        tree: None,
    };
    render_pixels(
        scene,
        accel,
        &settings.image(),
        "raytrace",
        |ray, hit, rng, counts| tracer.shade(ray, hit, 0, 1.0, rng, counts),
    )
}

/// The ray tree of pixel (x, y) (column from the left, row from the bottom, as the course's
/// screen coordinates): every ray its samples trace, in the order traced. The samples are
/// those of `render` with the same settings, so the tree explains that pixel of the image.
pub fn ray_tree(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    x: u32,
    y: u32,
) -> Vec<Segment> {
    let tracer = Tracer {
        indirect: &Ambient(settings.ambient_light),
        scene,
        accel,
        settings,
        lights: Light::collect(scene),
        light_strata: Strata::new(
            settings.light_sampling.pattern(),
            settings.num_shadow_samples,
        ),
        tree: Some(std::sync::Mutex::new(Vec::new())),
    };
    let camera = CameraSampler::new(scene, &settings.image());
    let spp = settings.num_antialias_samples.max(1);
    let mut counts = Counts::default();
    for k in 0..spp {
        let (ray, mut rng) = camera.sample((x, y), k);
        let hit = crate::accel::closest_surface(accel, scene, &ray);
        tracer.record(&ray, hit.as_ref(), SegmentKind::Eye);
        tracer.shade(&ray, hit, 0, 1.0, &mut rng, &mut counts);
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
    /// away and are left out: a 2×0.5 light, tilted, above surface points on every side of it.
    #[test]
    fn block_of_light_samples_matches_point_by_point() {
        let text = "material\ndiffuse 0 0 0\nemitted 1 1 1\n\
                    m 0\nv -1 1 0.2\nv -1 1.3 -0.3\nv 1 1.3 -0.3\nv 1 1 0.2\nf 1 2 3 4\n";
        let scene = Scene::parse_dialect(std::path::Path::new("t.obj"), text).expect("parses");
        let light = Light::collect(&scene)[0];
        let LightShape::Parallelogram(quad) = light.shape else {
            panic!("a quad light");
        };
        let mut rng = Rng::new(11, 0, 0);
        let (mut kept, mut tried) = (0, 0);
        for _ in 0..200 {
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
                block.push_block(&quad.sample_block(&u, &v), quad.normal(), m);
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
