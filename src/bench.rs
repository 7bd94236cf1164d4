//! Ray sets and the measurements of `render bench-accel`: Mrays/s of closest-hit and
//! occlusion queries, single and batched, on one thread and on all, for each backend, beside
//! the shim's plain C loops over Embree as the baseline. The backends' repetitions of a cell
//! (and of the build) alternate, so that a slow spell of the machine falls on both: measured
//! one backend after the other, the same binary's BVH/Embree ratio on the terrain moved
//! between 0.48 and 0.73 from run to run.

use std::time::Instant;

use rayon::prelude::*;

use crate::accel::{self, Accel, AccelKind, AccelOptions};
use crate::geometry::{vec3, Ray, Vec3};
use crate::sampling::Rng;
use crate::scene::{Camera, Scene};

/// One ray per pixel of a `side`×`side` image through the scene's camera, row by row.
pub fn camera_rays(scene: &Scene, side: u32) -> Vec<Ray> {
    let view = scene.camera().view();
    let mut rays = Vec::with_capacity((side * side) as usize);
    for j in 0..side {
        for i in 0..side {
            let (x, y) = Camera::screen_point(i, j, 0.5, 0.5, side, side);
            rays.push(view.ray(x, y));
        }
    }
    rays
}

/// A uniformly random direction.
pub fn uniform_direction(rng: &mut Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.next_f32();
    vec3(r * phi.cos(), r * phi.sin(), z)
}

/// `n` incoherent rays: origins uniform in the scene's bounds (slightly enlarged), directions
/// uniform on the sphere. Deterministic for a seed.
pub fn incoherent_rays(scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
    let b = scene.bounds();
    let pad = b.extent().max_element() * 0.05;
    let lo = b.min - Vec3::splat(pad);
    let size = b.extent() + Vec3::splat(2.0 * pad);
    (0..n)
        .map(|i| {
            let mut rng = Rng::new(seed, i as u64, 0);
            let o = lo
                + vec3(
                    rng.next_f32() * size.x,
                    rng.next_f32() * size.y,
                    rng.next_f32() * size.z,
                );
            Ray::new(o, uniform_direction(&mut rng))
        })
        .collect()
}

/// The rays of a query set, their t_max limited for occlusion queries: half reach to a random
/// fraction of the scene's diagonal, half are unbounded.
pub fn occlusion_rays(scene: &Scene, rays: &[Ray], seed: u64) -> Vec<Ray> {
    let diag = scene.bounds().extent().length();
    rays.iter()
        .enumerate()
        .map(|(i, r)| {
            let mut rng = Rng::new(seed ^ 0x0cc1, i as u64, 1);
            let t_max = if i % 2 == 0 {
                f32::INFINITY
            } else {
                rng.next_f32() * diag
            };
            Ray { t_max, ..*r }
        })
        .collect()
}

/// Shadow rays as the ray tracer casts them: from the surface each camera ray sees (on the
/// side it sees) to a uniformly chosen point of a uniformly chosen light, stopping short of it.
/// Empty when the scene has no light.
pub fn shadow_rays(
    scene: &Scene,
    camera: &[Ray],
    seed: u64,
) -> Result<Vec<Ray>, accel::AccelError> {
    let lights = crate::render::lights::Light::collect(scene);
    if lights.is_empty() {
        return Ok(Vec::new());
    }
    let finder = accel::bvh::Bvh::build(scene)?;
    let mut rays = Vec::with_capacity(camera.len());
    for (i, ray) in camera.iter().enumerate() {
        let Some(s) = accel::closest_surface(&finder, scene, ray) else {
            continue;
        };
        if scene.materials[s.material as usize].is_emissive() {
            continue;
        }
        let mut rng = Rng::new(seed, i as u64, 0);
        let k = ((rng.next_f32() * lights.len() as f32) as usize).min(lights.len() - 1);
        let p = lights[k].sample(rng.next_f32(), rng.next_f32());
        let n = s.facing(ray.direction).1;
        if n.dot(p.point - s.point) > 0.0 {
            let origin = crate::geometry::offset_ray_origin(s.point, n, s.error);
            rays.push(crate::geometry::shadow_ray(origin, p.point));
        }
    }
    Ok(rays)
}

/// The ray sets of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RaySet {
    /// One ray per pixel through the scene's camera.
    Camera,
    /// Random origins in the scene's bounds, random directions.
    Incoherent,
    /// From the surfaces the camera rays see to random points on the lights.
    Shadow,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Query {
    /// The closest hit.
    Closest,
    /// Whether anything is hit (the ray's t range limited for the camera and incoherent sets).
    Occluded,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Mode {
    /// One ray per call.
    Single,
    /// Slices of rays per call (packets of 8 in Embree).
    Batched,
}

/// Which cells of the table to measure: every combination of these (`--sets`, `--queries`,
/// `--modes`; all by default).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cells {
    pub sets: Vec<RaySet>,
    pub queries: Vec<Query>,
    pub modes: Vec<Mode>,
}

impl Default for Cells {
    fn default() -> Cells {
        Cells {
            sets: vec![RaySet::Camera, RaySet::Incoherent, RaySet::Shadow],
            queries: vec![Query::Closest, Query::Occluded],
            modes: vec![Mode::Single, Mode::Batched],
        }
    }
}

impl RaySet {
    fn name(self) -> &'static str {
        match self {
            RaySet::Camera => "camera",
            RaySet::Incoherent => "incoherent",
            RaySet::Shadow => "shadow",
        }
    }
}

impl Query {
    fn name(self) -> &'static str {
        match self {
            Query::Closest => "closest",
            Query::Occluded => "occluded",
        }
    }
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Single => "single",
            Mode::Batched => "batched",
        }
    }
}

/// Traces `rays` once through the API; returns the number of hits (so nothing is optimised
/// away).
pub fn trace(accel: &dyn Accel, rays: &[Ray], query: Query, mode: Mode, parallel: bool) -> usize {
    let chunk = 4096;
    let work = |rays: &[Ray]| -> usize {
        match (query, mode) {
            (Query::Closest, Mode::Single) => {
                rays.iter().filter(|r| accel.intersect(r).is_some()).count()
            }
            (Query::Occluded, Mode::Single) => rays.iter().filter(|r| accel.occluded(r)).count(),
            (Query::Closest, Mode::Batched) => {
                let mut hits = vec![None; rays.len()];
                accel.intersect_batch(rays, &mut hits);
                hits.iter().filter(|h| h.is_some()).count()
            }
            (Query::Occluded, Mode::Batched) => {
                let mut occ = vec![false; rays.len()];
                accel.occluded_batch(rays, &mut occ);
                occ.iter().filter(|&&o| o).count()
            }
        }
    };
    if parallel {
        rays.par_chunks(chunk).map(work).sum()
    } else {
        rays.chunks(chunk).map(work).sum()
    }
}

/// Median of `repeats` timings of `f`, in seconds.
pub fn median_seconds(repeats: usize, mut f: impl FnMut()) -> f64 {
    median((0..repeats.max(1)).map(|_| seconds(&mut f)).collect())
}

/// Medians of `repeats` timings of each of `fs`, the functions taken in turn within each
/// repetition; in seconds.
fn interleaved_median_seconds<F: FnMut()>(repeats: usize, fs: &mut [F]) -> Vec<f64> {
    let mut times = vec![Vec::new(); fs.len()];
    for _ in 0..repeats.max(1) {
        for (f, t) in fs.iter_mut().zip(&mut times) {
            t.push(seconds(f));
        }
    }
    times.into_iter().map(median).collect()
}

fn seconds(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64()
}

fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// One line of the benchmark table.
#[derive(Clone, Debug)]
pub struct Row {
    pub backend: String,
    pub rays: &'static str,
    pub query: &'static str,
    pub mode: &'static str,
    pub threads: usize,
    pub mrays_per_s: f64,
}

/// What `bench_accel` measured.
#[derive(Clone, Debug, Default)]
pub struct Report {
    pub rows: Vec<Row>,
    /// Build time of each backend, in seconds.
    pub builds: Vec<(String, f64)>,
}

impl Report {
    /// Our BVH's rows, each with its throughput over Embree's in the same cell (through the
    /// same `Accel` calls), for every cell both were measured in: the lines BENCHMARKS.md's
    /// comparisons of the two backends are stated in.
    pub fn ratios(&self) -> Vec<(&Row, f64)> {
        let (bvh, embree) = (AccelKind::Bvh.to_string(), AccelKind::Embree.to_string());
        let cell = |r: &Row| (r.rays, r.query, r.mode, r.threads);
        self.rows
            .iter()
            .filter(|r| r.backend == bvh)
            .filter_map(|r| {
                let e = self
                    .rows
                    .iter()
                    .find(|e| e.backend == embree && cell(e) == cell(r))?;
                Some((r, r.mrays_per_s / e.mrays_per_s))
            })
            .collect()
    }

    /// Our BVH's build time over Embree's, when both were built (and Embree's took a
    /// measurable time).
    pub fn build_ratio(&self) -> Option<f64> {
        let time = |kind: AccelKind| {
            let name = kind.to_string();
            self.builds.iter().find(|(n, _)| *n == name).map(|b| b.1)
        };
        let (bvh, embree) = (time(AccelKind::Bvh)?, time(AccelKind::Embree)?);
        (embree > 0.0).then(|| bvh / embree)
    }
}

/// The measurement over one scene: the `cells` chosen, `n_rays` per ray set, `repeats`
/// timings per cell.
pub fn bench_accel(
    scene: &Scene,
    kinds: &[AccelKind],
    options: &AccelOptions,
    cells: &Cells,
    n_rays: usize,
    repeats: usize,
    threads: usize,
) -> Result<Report, accel::AccelError> {
    let side = (n_rays as f64).sqrt().ceil() as u32;
    let camera = camera_rays(scene, side);
    let mut sets = Vec::new();
    for &set in &cells.sets {
        // Each set's rays for closest-hit queries and for occlusion queries.
        let (closest, occluded) = match set {
            RaySet::Camera => (camera.clone(), occlusion_rays(scene, &camera, 2)),
            RaySet::Incoherent => {
                let rays = incoherent_rays(scene, n_rays, 1);
                let occluded = occlusion_rays(scene, &rays, 3);
                (rays, occluded)
            }
            RaySet::Shadow => {
                let rays = shadow_rays(scene, &camera, 4)?;
                (rays.clone(), rays)
            }
        };
        if !closest.is_empty() {
            sets.push((set.name(), closest, occluded));
        }
    }
    let chosen =
        |query: Query, mode: Mode| cells.queries.contains(&query) && cells.modes.contains(&mode);
    let mut rows = Vec::new();
    let mut built: Vec<Option<Result<Box<dyn Accel>, accel::AccelError>>> =
        kinds.iter().map(|_| None).collect();
    let mut build_each: Vec<_> = kinds
        .iter()
        .zip(&mut built)
        .map(|(&kind, slot)| move || *slot = Some(accel::build(scene, kind, options)))
        .collect();
    let build_s = interleaved_median_seconds(repeats, &mut build_each);
    drop(build_each);
    let builds = kinds.iter().map(|k| k.to_string()).zip(build_s).collect();
    let accels = built
        .into_iter()
        .map(|b| b.expect("built at least once"))
        .collect::<Result<Vec<_>, _>>()?;
    for (set_name, closest_rays, occl_rays) in &sets {
        for (query, rays) in [(Query::Closest, closest_rays), (Query::Occluded, occl_rays)] {
            for mode in [Mode::Single, Mode::Batched] {
                if !chosen(query, mode) {
                    continue;
                }
                // One thread, then all of them (once, when that is one).
                let runs: &[(bool, usize)] = if threads > 1 {
                    &[(false, 1), (true, threads)]
                } else {
                    &[(false, 1)]
                };
                for &(parallel, t) in runs {
                    let mut trace_each: Vec<_> = accels
                        .iter()
                        .map(|a| {
                            || {
                                std::hint::black_box(trace(
                                    a.as_ref(),
                                    rays,
                                    query,
                                    mode,
                                    parallel,
                                ));
                            }
                        })
                        .collect();
                    let seconds = interleaved_median_seconds(repeats, &mut trace_each);
                    for (&kind, s) in kinds.iter().zip(seconds) {
                        rows.push(Row {
                            backend: kind.to_string(),
                            rays: set_name,
                            query: query.name(),
                            mode: mode.name(),
                            threads: t,
                            mrays_per_s: rays.len() as f64 / s / 1e6,
                        });
                    }
                }
            }
        }
    }
    // The table lists each backend's rows together, in the order the backends were asked for.
    rows.sort_by_key(|r| kinds.iter().position(|k| k.to_string() == r.backend));
    // The shim's plain C loops over Embree, after Embree's rows.
    #[cfg(feature = "embree")]
    if kinds.contains(&AccelKind::Embree) {
        use crate::accel::embree::{Baseline, EmbreeAccel};
        let e = EmbreeAccel::build(scene, options)?;
        for (set_name, closest_rays, occl_rays) in &sets {
            for (b, query, mode, rays) in [
                (
                    Baseline::Intersect1,
                    Query::Closest,
                    Mode::Single,
                    closest_rays,
                ),
                (
                    Baseline::Occluded1,
                    Query::Occluded,
                    Mode::Single,
                    occl_rays,
                ),
                (
                    Baseline::Intersect8,
                    Query::Closest,
                    Mode::Batched,
                    closest_rays,
                ),
                (
                    Baseline::Occluded8,
                    Query::Occluded,
                    Mode::Batched,
                    occl_rays,
                ),
            ] {
                if !chosen(query, mode) {
                    continue;
                }
                let s = median_seconds(repeats, || {
                    std::hint::black_box(e.baseline(rays, b));
                });
                rows.push(Row {
                    backend: "embree C loop".into(),
                    rays: set_name,
                    query: query.name(),
                    mode: mode.name(),
                    threads: 1,
                    mrays_per_s: rays.len() as f64 / s / 1e6,
                });
            }
        }
    }
    Ok(Report { rows, builds })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(backend: &str, rays: &'static str, threads: usize, mrays_per_s: f64) -> Row {
        Row {
            backend: backend.into(),
            rays,
            query: "closest",
            mode: "single",
            threads,
            mrays_per_s,
        }
    }

    #[test]
    fn ratios_pair_the_same_cell_of_both_backends() {
        let report = Report {
            rows: vec![
                row("bvh", "terrain", 1, 1.0),
                row("bvh", "terrain", 2, 3.0),
                row("bvh", "camera", 1, 9.0),
                row("embree", "terrain", 2, 4.0),
                row("embree", "terrain", 1, 2.0),
                row("embree C loop", "camera", 1, 3.0),
            ],
            builds: vec![("bvh".into(), 1.5), ("embree".into(), 0.5)],
        };
        let ratios = report.ratios();
        // The camera cell has no Embree row through the Accel (the C loop is another thing).
        assert_eq!(ratios.len(), 2);
        assert_eq!((ratios[0].0.threads, ratios[0].1), (1, 0.5));
        assert_eq!((ratios[1].0.threads, ratios[1].1), (2, 0.75));
        assert_eq!(report.build_ratio(), Some(3.0));
        let only_bvh = Report {
            rows: vec![row("bvh", "terrain", 1, 1.0)],
            builds: vec![("bvh".into(), 1.0)],
        };
        assert!(only_bvh.ratios().is_empty());
        assert_eq!(only_bvh.build_ratio(), None);
    }
}
