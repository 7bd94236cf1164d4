//! Final gathering with an irradiance cache (Ward, Rubinstein & Clear 1988). A final gather
//! sends cosine-distributed rays over the hemisphere of a point and looks up the global map
//! where they land; the cache keeps gathers made at a grid of pixels and interpolates them
//! with Ward's weights w = 1/(‖x−xᵢ‖/Rᵢ + √(1−n·nᵢ)) wherever some record has w > 1/a. To
//! keep images independent of thread scheduling, the records are all made first, in a fixed
//! order; a point no record covers gathers afresh without adding a record.

use std::num::NonZero;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use rayon::prelude::*;

use super::PhotonMaps;
use crate::accel::Accel;
use crate::engines::engine::RenderSettings;
use crate::engines::scattering::sample_lobe;
use crate::geometry::{spawn_ray, Ray, Vec3};
use crate::sampling::{Pattern, Rng, Strata};
use crate::scene::{Camera, Color, Scene};

/// Records consulted per lookup.
const NEIGHBOURS: usize = 16;

#[derive(Clone, Copy, Debug)]
pub struct Record {
    position: Vec3,
    normal: Vec3,
    /// Irradiance / π gathered there.
    value: Color,
    /// Harmonic mean distance of the gather rays' hits.
    radius: f32,
}

pub struct IrradianceCache {
    pub records: Vec<Record>,
    tree: ImmutableKdTree<f32, u32, 3, 32>,
    error: f32,
    gather_rays: u32,
    /// Rays cast by gathers (records and fresh ones).
    pub rays: AtomicU64,
    /// Wall time of making the records.
    pub build_seconds: f64,
    /// Lookups answered by interpolation, and by a fresh gather.
    pub interpolated: AtomicU64,
    pub fresh: AtomicU64,
}

/// Irradiance / π at `x` (unit normal `n` on the lit side, point error `error`) by a final
/// gather of `count` rays, and the harmonic mean distance to what the rays hit.
pub fn final_gather(
    scene: &Scene,
    accel: &dyn Accel,
    maps: &PhotonMaps,
    (x, n, error): (Vec3, Vec3, f32),
    count: u32,
    rng: &mut Rng,
) -> (Color, f32) {
    let strata = Strata::new(Pattern::Jittered, count);
    let rays: Vec<Ray> = strata
        .samples(rng)
        .map(|(u, v)| spawn_ray(x, n, error, sample_lobe(n, 1.0, u, v)))
        .collect();
    let mut hits = vec![None; rays.len()];
    accel.intersect_batch(&rays, &mut hits);
    let (mut sum, mut inverse_distance) = (Vec3::ZERO, 0.0f32);
    for (ray, hit) in rays.iter().zip(&hits) {
        let Some(h) = hit else {
            continue;
        };
        let s = scene.surface(ray, h);
        inverse_distance += 1.0 / (s.t * ray.direction.length()).max(1e-12);
        let albedo = scene.albedo(&s);
        if albedo.max_element() > 0.0 {
            let (_, ny) = s.facing(ray.direction);
            sum += albedo * maps.global_at(s.point, ny);
        }
    }
    let radius = if inverse_distance > 0.0 {
        count as f32 / inverse_distance
    } else {
        f32::INFINITY
    };
    (sum * (count.max(1) as f32).recip(), radius)
}

impl IrradianceCache {
    /// Gathers at the first diffuse surface seen through every `spacing`-th pixel.
    pub fn build(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
        maps: &PhotonMaps,
    ) -> IrradianceCache {
        let clock = std::time::Instant::now();
        let p = &settings.photon;
        let spacing = p.irradiance_cache_spacing.max(1);
        let (w, h) = (settings.width, settings.height);
        let view = scene.camera().view();
        let extent = scene.bounds().extent().length();
        let pixels: Vec<(u32, u32)> = (0..h)
            .step_by(spacing as usize)
            .flat_map(|j| (0..w).step_by(spacing as usize).map(move |i| (i, j)))
            .collect();
        let bar = crate::progress::bar(pixels.len() as u64, "gather", settings.quiet);
        let rays = AtomicU64::new(0);
        let records: Vec<Record> = pixels
            .par_iter()
            .filter_map(|&(i, j)| {
                bar.inc(1);
                let (sx, sy) = Camera::screen_point(i, j, 0.5, 0.5, w, h);
                let ray = view.ray(sx, sy);
                let s = crate::accel::closest_surface(accel, scene, &ray)?;
                if scene.albedo(&s).max_element() <= 0.0 {
                    return None;
                }
                let (_, n) = s.facing(ray.direction);
                let mut rng = Rng::new(settings.seed ^ 0xcace, (j * w + i) as u64, 0);
                let (value, radius) = final_gather(
                    scene,
                    accel,
                    maps,
                    (s.point, n, s.error),
                    p.final_gather_rays,
                    &mut rng,
                );
                rays.fetch_add(p.final_gather_rays as u64, Relaxed);
                Some(Record {
                    position: s.point,
                    normal: n,
                    value,
                    // Ward's bounds on the record's reach, relative to the scene.
                    radius: radius.clamp(1e-3 * extent, 0.1 * extent),
                })
            })
            .collect();
        bar.finish_and_clear();
        let points: Vec<[f32; 3]> = records.iter().map(|r| r.position.to_array()).collect();
        IrradianceCache {
            tree: ImmutableKdTree::new_from_slice(&points),
            build_seconds: clock.elapsed().as_secs_f64(),
            records,
            error: p.irradiance_cache_error,
            gather_rays: p.final_gather_rays,
            rays,
            interpolated: AtomicU64::new(0),
            fresh: AtomicU64::new(0),
        }
    }

    /// Irradiance / π at a surface point: interpolated from the records that cover it, else a
    /// fresh gather.
    pub fn irradiance_over_pi(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        maps: &PhotonMaps,
        (x, n, error): (Vec3, Vec3, f32),
        rng: &mut Rng,
    ) -> Color {
        if let (Some(k), false) = (NonZero::new(NEIGHBOURS), self.records.is_empty()) {
            let (mut sum, mut weights) = (Vec3::ZERO, 0.0f32);
            for f in self.tree.nearest_n::<SquaredEuclidean>(&x.to_array(), k) {
                let r = &self.records[f.item as usize];
                let facing = r.normal.dot(n);
                if facing <= 0.0 {
                    continue;
                }
                let e = f.distance.sqrt() / r.radius + (1.0 - facing).max(0.0).sqrt();
                if e < self.error {
                    let w = 1.0 / e.max(1e-6);
                    sum += r.value * w;
                    weights += w;
                }
            }
            if weights > 0.0 {
                self.interpolated.fetch_add(1, Relaxed);
                return sum * weights.recip();
            }
        }
        self.fresh.fetch_add(1, Relaxed);
        self.rays.fetch_add(self.gather_rays as u64, Relaxed);
        final_gather(scene, accel, maps, (x, n, error), self.gather_rays, rng).0
    }
}
