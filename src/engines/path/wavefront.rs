//! The path tracer's wavefront: a batch of camera paths advanced together, one vertex at a
//! time. Each step runs one stage over every path still going: shade the hits (emission, the
//! lobe, the numbers of the vertex and the light point), then run the vertex kernel on them 16
//! at a time (next-event estimation's weight and shadow ray, the next direction, roulette, in
//! SIMD lanes: AVX-512 where the processor has it, by `pulp`'s run-time dispatch), then trace
//! all the shadow rays, then all the next rays, as batches.
//!
//! Why: one path at a time, each vertex's arithmetic is a long chain of dependent divisions
//! and square roots between two ray queries, and the processor waits on each in turn; 16
//! lanes run 16 vertices' chains at once. On the Cornell box at 64 paths a pixel the path
//! tracer took 0.88× the time (`scripts/path-time-vs-mitsuba.sh`). Without the kernel (the same
//! stages, scalar) it took 1.05×: the gain is the lanes, not the reordering.
//!
//! It follows exactly the paths `PathTracer::radiance` follows, drawing the same numbers in
//! the same order and computing with the same operations, so the image is the same bit for
//! bit (tested below). It serves the scenes whose every material is diffuse (or black),
//! without bump maps, media or sky; the rest go one path at a time. Lights sampled by area
//! (`--light-sampling random`) are weighed in the lanes; by solid angle (the default), the
//! point is drawn before, one path at a time, and only weighed in the lanes.

use super::{roulette, PathTracer, Previous, MAX_VERTICES};
use crate::engines::scattering::{diffuse_sample, power_heuristic};
use crate::geometry::{offset_ray_origin, shadow_ray, spawn_ray, vec3, Ray, Vec3};
use crate::render::Counts;
use crate::sampling::{PathSamples, SobolLanes, SOBOL_LANES};
use crate::scene::{Color, SurfaceHit};

/// One path of the batch between two vertices.
struct Path {
    throughput: Color,
    /// The ray that found the path's next vertex.
    ray: Ray,
    previous: Previous,
    samples: PathSamples,
}

impl PathTracer<'_> {
    /// Whether `radiance_batch` follows this tracer's paths: no medium, no sky, and every
    /// material reflects only diffusely (or not at all), without a bump map, and emits the
    /// same radiance all over (the lanes take a light's `emitted`).
    pub(super) fn wavefront_applies(&self) -> bool {
        let scene = self.scene;
        scene.media.is_empty()
            && scene.sky.is_none()
            && scene.delta_lights.is_empty()
            && !scene.smooth_normals
            && scene.materials.iter().all(|m| {
                m.reflective.max_element() <= 0.0
                    && m.transmitted.max_element() <= 0.0
                    && m.bump.is_none()
                    && m.bsdf.is_none()
                    && m.emission_texture.is_none()
                    && m.opacity.is_none()
                    && m.tilt.is_none()
            })
    }

    /// The radiance along each of the camera `rays` (whose closest hits are `hits`) into
    /// `out`, from one path each drawing its numbers from `samples`: what `radiance` gives
    /// each path alone.
    pub(super) fn radiance_batch(
        &self,
        rays: &[Ray],
        hits: &[Option<SurfaceHit>],
        samples: impl Iterator<Item = PathSamples>,
        counts: &mut Counts,
        out: &mut [Color],
    ) {
        let mut paths: Vec<Path> = rays
            .iter()
            .zip(samples)
            .map(|(ray, samples)| Path {
                throughput: Vec3::ONE,
                ray: *ray,
                previous: Previous {
                    point: ray.origin,
                    normal: ray.direction,
                    bsdf_pdf: None,
                    in_medium: false,
                },
                samples,
            })
            .collect();
        let mut hits = hits.to_vec();
        out.fill(Vec3::ZERO);
        // The paths still going.
        let mut active: Vec<u32> = (0..paths.len() as u32).collect();
        let mut taken = Taken::default();
        let mut blocked = Vec::new();
        let mut next_rays = Vec::with_capacity(active.len());
        let mut prim_hits = Vec::new();
        let mut block = VertexIn::default();
        let mut lane_path = [0u32; LANES];
        let mut filled = 0;
        for vertex in 0..MAX_VERTICES {
            if active.is_empty() {
                break;
            }
            taken.next.clear();
            taken.shadow_rays.clear();
            taken.shadowed.clear();
            for &i in &active {
                let (path, radiance) = (&mut paths[i as usize], &mut out[i as usize]);
                let Some(s) = &hits[i as usize] else {
                    // Only a camera ray sees the background; a bounce that leaves the scene
                    // brings nothing.
                    if vertex == 0 {
                        *radiance += path.throughput * self.scene.background;
                    }
                    continue;
                };
                if !self.begin_vertex(vertex, s, path, radiance, (&mut block, filled)) {
                    continue;
                }
                lane_path[filled] = i;
                filled += 1;
                if filled == LANES {
                    self.finish_block(&block, &lane_path[..filled], &mut paths, &mut taken);
                    filled = 0;
                }
            }
            if filled > 0 {
                for l in filled..LANES {
                    block.has_light[l] = 0.0;
                }
                self.finish_block(&block, &lane_path[..filled], &mut paths, &mut taken);
                filled = 0;
            }
            counts.shadow += taken.shadow_rays.len() as u64;
            blocked.clear();
            blocked.resize(taken.shadow_rays.len(), false);
            self.accel.occluded_batch(&taken.shadow_rays, &mut blocked);
            for (&(i, l), &b) in taken.shadowed.iter().zip(&blocked) {
                if !b {
                    out[i as usize] += l;
                }
            }
            counts.secondary += taken.next.len() as u64;
            next_rays.clear();
            next_rays.extend(taken.next.iter().map(|&i| paths[i as usize].ray));
            prim_hits.clear();
            prim_hits.resize(next_rays.len(), None);
            self.accel.intersect_batch(&next_rays, &mut prim_hits);
            for ((&i, ray), h) in taken.next.iter().zip(&next_rays).zip(&prim_hits) {
                hits[i as usize] = h.as_ref().map(|h| self.scene.surface(ray, h));
            }
            std::mem::swap(&mut active, &mut taken.next);
        }
    }
}

impl PathTracer<'_> {
    /// The scalar part of a vertex of `path` at the surface `s`: adds what the surface emits
    /// to `radiance`, chooses the lobe, draws the vertex's numbers and the light point, and
    /// writes them into lane `l` of `block` for the vertex kernel. False where the path ends
    /// here (its depth, a black surface or a black throughput).
    fn begin_vertex(
        &self,
        vertex: u32,
        s: &SurfaceHit,
        path: &mut Path,
        radiance: &mut Color,
        (block, l): (&mut VertexIn, usize),
    ) -> bool {
        let direction = path.ray.direction;
        let (_, n) = s.facing(direction);
        *radiance += self.emission(s, direction, &path.previous, path.throughput);
        if vertex >= self.max_depth {
            return false;
        }
        // Every material here reflects diffusely only (`wavefront_applies`): `choose_lobe`
        // takes the diffuse lobe without a draw, and its weight, the albedo times total / d
        // with total = d, is the albedo itself.
        let albedo = self.scene.albedo(s);
        if albedo.max_element() <= 0.0 {
            return false;
        }
        path.throughput *= albedo;
        if path.throughput.max_element() == 0.0 {
            return false;
        }
        // The numbers in the order `radiance` draws them.
        let light_draw = self.draw_light(s.prim, &mut path.samples);
        let (du, dv) = path.samples.next_2d();
        let roulette = vertex >= super::ROULETTE_FROM;
        let draw = if roulette {
            path.samples.next_1d()
        } else {
            0.0
        };
        put(&mut block.x, l, s.point);
        put(&mut block.n, l, n);
        put(&mut block.ng, l, s.geometric_normal);
        block.error[l] = s.error;
        put(&mut block.throughput, l, path.throughput);
        block.has_light[l] = 0.0;
        if let Some(super::LightDraw { k, u, v }) = light_draw {
            let light = &self.lights[k];
            block.selection[l] = self.selection_probability(k);
            put(&mut block.emitted, l, light.emitted);
            block.has_light[l] = 1.0;
            block.drawn[l] = 0.0;
            if self.by_area {
                let q = light.sample(u, v);
                put(&mut block.light_point, l, q.point);
                put(&mut block.light_normal, l, q.normal);
                block.two_sided[l] = if q.one_sided { 0.0 } else { 1.0 };
                block.area[l] = light.area;
            } else {
                match light.sample_towards(s.point, n, u, v) {
                    Some(d) => {
                        put(&mut block.light_point, l, d.point);
                        block.drawn[l] = 1.0;
                        block.drawn_weight[l] = d.weight;
                        block.drawn_pdf[l] = d.pdf;
                    }
                    None => block.has_light[l] = 0.0,
                }
            }
        }
        block.du[l] = du;
        block.dv[l] = dv;
        block.draw[l] = draw;
        block.roulette[l] = if roulette { 1.0 } else { 0.0 };
        true
    }

    /// Runs the vertex kernel on `block`, whose lanes are the paths `lanes`, and takes what
    /// it gives into `taken`.
    fn finish_block(&self, block: &VertexIn, lanes: &[u32], paths: &mut [Path], taken: &mut Taken) {
        let mut out = VertexOut::default();
        vertex_kernel(self.arch, block, &mut out);
        // The numbers of the next vertex of the paths that go on, made ahead in lanes.
        let mut sobol = SobolLanes::default();
        for (l, &i) in lanes.iter().enumerate() {
            if out.alive[l] > 0.0 {
                sobol.load(l, &paths[i as usize].samples);
            }
        }
        sobol.make(self.arch);
        for (l, &i) in lanes.iter().enumerate() {
            let path = &mut paths[i as usize];
            if out.lit[l] > 0.0 {
                taken.shadow_rays.push(Ray::with_range(
                    get(&out.shadow_origin, l),
                    get(&out.shadow_direction, l),
                    0.0,
                    out.shadow_t_max[l],
                ));
                taken.shadowed.push((i, get(&out.contribution, l)));
            }
            path.previous = Previous {
                point: get(&block.x, l),
                normal: get(&block.n, l),
                bsdf_pdf: Some(out.pdf[l]),
                in_medium: false,
            };
            if out.alive[l] > 0.0 {
                path.throughput = get(&out.throughput, l);
                path.ray = Ray::new(get(&out.spawn_origin, l), get(&out.direction, l));
                sobol.store(l, &mut path.samples);
                taken.next.push(i);
            }
        }
    }
}

/// What the vertex kernel gave at one vertex of the wavefront's paths.
#[derive(Default)]
struct Taken {
    /// The shadow rays, with the path each belongs to and what it brings if not blocked.
    shadow_rays: Vec<Ray>,
    shadowed: Vec<(u32, Color)>,
    /// The paths that go on to the next vertex.
    next: Vec<u32>,
}

/// Paths a vertex kernel takes at once (their numbers are made ahead together too).
const LANES: usize = 16;
const _: () = assert!(LANES <= SOBOL_LANES);

type Lanes = [f32; LANES];

/// What the diffuse vertex kernel reads, lane by lane.
#[derive(Clone, Copy, Default)]
struct VertexIn {
    /// The shading point, its normal on the side the path came from, its geometric normal and
    /// the bound on its rounding error.
    x: [Lanes; 3],
    n: [Lanes; 3],
    ng: [Lanes; 3],
    error: Lanes,
    /// The throughput after this vertex's albedo.
    throughput: [Lanes; 3],
    /// The light point, its normal, whether it emits from both sides (1) or one (0), the
    /// light's area, its selection probability and its radiance; `has_light` 0 where no
    /// light point was drawn. `drawn` 1 where the point was sampled by solid angle, with
    /// its weight and density (else the kernel works out the point's by area).
    light_point: [Lanes; 3],
    light_normal: [Lanes; 3],
    two_sided: Lanes,
    area: Lanes,
    selection: Lanes,
    emitted: [Lanes; 3],
    has_light: Lanes,
    drawn: Lanes,
    drawn_weight: Lanes,
    drawn_pdf: Lanes,
    /// The numbers of the next direction, and of roulette (`roulette` 1 where it is played).
    du: Lanes,
    dv: Lanes,
    draw: Lanes,
    roulette: Lanes,
}

/// What the diffuse vertex kernel gives, lane by lane.
#[derive(Clone, Copy, Default)]
struct VertexOut {
    shadow_origin: [Lanes; 3],
    shadow_direction: [Lanes; 3],
    shadow_t_max: Lanes,
    /// 1 where the light sample casts its shadow ray.
    lit: Lanes,
    contribution: [Lanes; 3],
    direction: [Lanes; 3],
    pdf: Lanes,
    spawn_origin: [Lanes; 3],
    throughput: [Lanes; 3],
    alive: Lanes,
}

#[inline(always)]
fn get(a: &[Lanes; 3], k: usize) -> Vec3 {
    vec3(a[0][k], a[1][k], a[2][k])
}

#[inline(always)]
fn put(a: &mut [Lanes; 3], k: usize, v: Vec3) {
    a[0][k] = v.x;
    a[1][k] = v.y;
    a[2][k] = v.z;
}

/// Lane `k` of the diffuse vertex kernel: the rest of `PathTracer::radiance`'s diffuse vertex
/// once its numbers are drawn and its light point chosen, in the same operations, so that
/// each lane gives the bits the tracer gives alone (`the_wavefront_gives_the_bits_of_one_path_
/// at_a_time` holds the two together). The direction, the ray origins and roulette call the
/// tracer's own functions, inlined and branch-free. The by-area sample and its weighing are
/// written out here: they mirror `Light::sample_by_area_towards` (with `point_towards`) and
/// `PathTracer::light_sample`, whose chains of `Option`s kept LLVM from vectorising the lanes
/// (1.18× the time instead of 0.88×).
#[inline(always)]
fn vertex_lane(i: &VertexIn, o: &mut VertexOut, k: usize) {
    let (x, n, ng, error) = (get(&i.x, k), get(&i.n, k), get(&i.ng, k), i.error[k]);
    let throughput = get(&i.throughput, k);
    // Next-event estimation: by area here, or the sample drawn by solid angle before.
    let p = get(&i.light_point, k);
    let w = p - x;
    let r2 = w.length_squared();
    let r = r2.sqrt();
    let cos_light = -get(&i.light_normal, k).dot(w) / r;
    let cos_light = if i.two_sided[k] > 0.0 {
        cos_light.abs()
    } else {
        cos_light
    };
    let cos = n.dot(w) / r;
    let area = i.area[k];
    let drawn = i.drawn[k] > 0.0;
    let weight = if drawn {
        i.drawn_weight[k]
    } else {
        cos * cos_light * area / (std::f32::consts::PI * r2)
    };
    let pdf = if drawn {
        i.drawn_pdf[k]
    } else {
        r2 / (cos_light * area)
    };
    let selection = i.selection[k];
    let bsdf_pdf = weight * pdf;
    let mis = power_heuristic(selection * pdf, bsdf_pdf);
    let lit = i.has_light[k] > 0.0
        && (drawn || (r2 > 0.0 && cos_light > 0.0 && cos > 0.0))
        && weight.is_finite()
        && pdf > 0.0
        && bsdf_pdf > 0.0;
    let shadow_ray = shadow_ray(offset_ray_origin(x, n, error), p);
    let radiance = get(&i.emitted, k) * (weight * mis / selection);
    let lit = if lit { 1.0 } else { 0.0 };
    o.lit[k] = lit;
    put(&mut o.shadow_origin, k, shadow_ray.origin);
    put(&mut o.shadow_direction, k, shadow_ray.direction);
    o.shadow_t_max[k] = shadow_ray.t_max;
    put(&mut o.contribution, k, throughput * radiance);
    // The next direction, by the cosine.
    let (dir, pdf) = diffuse_sample(n, i.du[k], i.dv[k]);
    o.pdf[k] = pdf;
    put(&mut o.direction, k, dir);
    let mut throughput = throughput;
    let alive = i.roulette[k] == 0.0 || roulette(&mut throughput, i.draw[k]);
    o.alive[k] = if alive { 1.0 } else { 0.0 };
    put(&mut o.throughput, k, throughput);
    put(&mut o.spawn_origin, k, spawn_ray(x, ng, error, dir).origin);
}

/// The kernel over one block, for `pulp::Arch::dispatch` (a closure would not be inlined
/// into the dispatched function, and so not compiled for its instructions).
struct VertexKernel<'a>(&'a VertexIn, &'a mut VertexOut);

impl pulp::WithSimd for VertexKernel<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        for k in 0..LANES {
            vertex_lane(self.0, self.1, k);
        }
    }
}

fn vertex_kernel(arch: pulp::Arch, i: &VertexIn, o: &mut VertexOut) {
    arch.dispatch(VertexKernel(i, o))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{build, closest_surface, AccelKind, AccelOptions};
    use crate::render::{CameraSampler, ImageSettings};
    use crate::sampling::{LightSampling, PathSampler};
    use crate::scene::Scene;

    /// On our Cornell box with the diffuse sphere (quads and a sphere, one light, paths long
    /// enough for roulette), 64×64 pixels at 4 paths each, with the light sampled by area
    /// and by solid angle: every path's radiance from the wavefront has the bits of the same
    /// path followed alone by `PathTracer::radiance` (a different draw order, a lane
    /// computing otherwise, would show in the last bits at least), and the wavefront did
    /// follow them.
    #[test]
    fn the_wavefront_gives_the_bits_of_one_path_at_a_time() {
        let file = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/cornell_box_diffuse_sphere.obj"
        );
        let scene = Scene::load(std::path::Path::new(file)).expect("loads");
        let accel = build(&scene, AccelKind::Bvh, &AccelOptions::default()).expect("builds");
        for sampling in [LightSampling::Random, LightSampling::SolidAngle] {
            let tracer = PathTracer::new(&scene, accel.as_ref()).with_light_sampling(sampling);
            assert!(tracer.wavefront_applies());
            let (alone, together, counts) = both_ways(&scene, accel.as_ref(), &tracer);
            let paths = alone.len();
            assert!(counts.shadow > paths as u64 && counts.secondary > paths as u64);
            let bits = |c: &Color| c.to_array().map(f32::to_bits);
            let differ = alone
                .iter()
                .zip(&together)
                .filter(|(a, b)| bits(a) != bits(b))
                .count();
            assert_eq!(
                differ, 0,
                "{sampling:?}: paths whose radiance differs in a bit"
            );
            assert!(alone.iter().filter(|c| c.max_element() > 0.0).count() > paths / 2);
        }
    }

    /// The radiance of 64×64 pixels' 4 paths each, one path at a time and by the wavefront
    /// (in batches of 1000), and the wavefront's counts.
    fn both_ways(
        scene: &Scene,
        accel: &dyn crate::accel::Accel,
        tracer: &PathTracer,
    ) -> (Vec<Color>, Vec<Color>, Counts) {
        let settings = ImageSettings {
            width: 64,
            height: 64,
            num_antialias_samples: 4,
            aperture: 0.0,
            focus_distance: None,
            seed: 7,
            quiet: true,
            window: None,
            samples: None,
            deadline: None,
            variance: false,
        };
        let camera = CameraSampler::new(scene, &settings);
        let (mut rays, mut samples, mut alone) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..64 {
            for i in 0..64 {
                for k in 0..4 {
                    let (ray, rng) = camera.sample((i, j), k);
                    let id = camera.sample_id((i, j), k);
                    rays.push(ray);
                    samples.push(PathSamples::new(PathSampler::Sobol, id, rng.clone()));
                    let mut own = PathSamples::new(PathSampler::Sobol, id, rng);
                    let hit = closest_surface(accel, scene, &ray);
                    alone.push(tracer.radiance(&ray, hit, &mut own, &mut Counts::default()));
                }
            }
        }
        let hits: Vec<_> = rays
            .iter()
            .map(|ray| closest_surface(accel, scene, ray))
            .collect();
        let mut together = vec![Vec3::ZERO; rays.len()];
        let mut counts = Counts::default();
        for (c, out) in together.chunks_mut(1000).enumerate() {
            let range = c * 1000..c * 1000 + out.len();
            let own = samples.drain(..out.len());
            tracer.radiance_batch(&rays[range.clone()], &hits[range], own, &mut counts, out);
        }
        (alone, together, counts)
    }
}
