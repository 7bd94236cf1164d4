//! Photon mapping (Jensen): photons traced from the lights into a global map (indirect
//! diffuse light) and a caustic map (light that reached a diffuse surface through mirrors or
//! glass only), looked up by k-nearest density estimation. The ray tracer computes direct light
//! and mirrors itself and takes its diffuse indirect light from the maps — by direct lookup, or
//! by final gathering accelerated by an irradiance cache (`-gather_indirect`).

pub mod file;
pub mod gather;
pub mod map;
pub mod trace;

use std::sync::atomic::Ordering::Relaxed;

pub use gather::IrradianceCache;
pub use map::PhotonMap;
pub use trace::{Aim, PathKind, Photon};

use super::{RenderSettings, Visualize};
use crate::accel::Accel;
use crate::film::Film;
use crate::geometry::{Bounds3, Vec3};
use crate::scene::{Color, Scene};

/// Settings only the photon engine reads.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photons emitted (`-num_photons_to_shoot`, default 0: no photon map).
    pub num_photons_to_shoot: u64,
    /// Photons aimed at the mirrors and glass for the caustic map (`--caustic-photons`,
    /// default None: as many as `num_photons_to_shoot`). 0 turns the caustic pass off; the
    /// caustic map then holds the caustic photons of the main pass.
    pub caustic_photons: Option<u64>,
    /// Photons per density estimate (`-num_photons_to_collect`, default 100).
    pub num_photons_to_collect: u32,
    /// Bounces a photon may make (`--max-photon-depth`, default 10).
    pub max_photon_depth: u32,
    /// Largest radius of a density estimate, as a fraction of the scene's diagonal
    /// (`--photon-max-radius`, default 0.1).
    pub max_radius: f32,
    /// Final gathering for indirect light (`-gather_indirect`, default off: direct lookup).
    pub gather_indirect: bool,
    /// Hemisphere rays per final gather (`--final-gather-rays`, default 128).
    pub final_gather_rays: u32,
    /// Ward's irradiance cache error a (`--irradiance-cache-error`, default 0.15).
    pub irradiance_cache_error: f32,
    /// Write the maps to this file after tracing (`--save-photons`).
    pub save: Option<std::path::PathBuf>,
    /// Read the maps from this file instead of tracing (`--load-photons`).
    pub load: Option<std::path::PathBuf>,
    /// Cache records are computed at every n-th pixel in x and y (`--irradiance-cache-spacing`,
    /// default 4); the rest interpolate, or gather afresh where no record is close enough.
    pub irradiance_cache_spacing: u32,
}

impl Default for PhotonSettings {
    fn default() -> Self {
        PhotonSettings {
            num_photons_to_shoot: 0,
            caustic_photons: None,
            num_photons_to_collect: 100,
            max_photon_depth: 10,
            max_radius: 0.1,
            gather_indirect: false,
            final_gather_rays: 128,
            irradiance_cache_error: 0.15,
            irradiance_cache_spacing: 4,
            save: None,
            load: None,
        }
    }
}

impl PhotonSettings {
    /// Photons of the caustic pass: `--caustic-photons`, else as many as the main pass.
    pub fn caustic_photons(&self) -> u64 {
        self.caustic_photons.unwrap_or(self.num_photons_to_shoot)
    }
}

/// The two photon maps of a scene and what the lookups need.
pub struct PhotonMaps {
    /// Indirect photons (all photons when final gathering: gather rays look up the full
    /// light at the surfaces they reach).
    pub global: PhotonMap,
    pub caustic: PhotonMap,
    /// Photons emitted by the main pass and by the caustic pass, and photon rays cast.
    pub emitted: u64,
    pub caustic_emitted: u64,
    pub rays: u64,
    /// Photons stopped by `--max-photon-depth` while still carrying power.
    pub truncated: u64,
    /// Wall time of photon tracing and of building the two kd-trees.
    pub trace_seconds: f64,
    pub build_seconds: f64,
    /// Photons per estimate and the largest radius (absolute).
    pub collect: usize,
    pub max_radius: f32,
}

impl PhotonMaps {
    /// Traces the photons (the main pass, then the caustic pass when the scene has mirrors or
    /// glass) and builds both maps.
    pub fn build(scene: &Scene, accel: &dyn Accel, settings: &RenderSettings) -> PhotonMaps {
        let p = &settings.photon;
        let clock = std::time::Instant::now();
        let caustic_aim = scene.specular_bounds().map(|b| Aim::Caustics {
            centre: b.centre(),
            radius: 0.5 * b.extent().length(),
        });
        let caustic_emitted = match caustic_aim {
            Some(_) => p.caustic_photons(),
            None => 0,
        };
        let blocks = p.num_photons_to_shoot.div_ceil(4096) + caustic_emitted.div_ceil(4096);
        let bar = crate::progress::bar(blocks, "photons", settings.quiet);
        let trace = |count, aim| {
            trace::trace_photons(
                scene,
                accel,
                count,
                p.max_photon_depth,
                aim,
                settings.seed,
                || bar.inc(1),
            )
        };
        let main = trace(p.num_photons_to_shoot, Aim::Everywhere);
        let aimed = caustic_aim
            .filter(|_| caustic_emitted > 0)
            .map(|aim| trace(caustic_emitted, aim));
        bar.finish_and_clear();
        let trace_seconds = clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let (mut global, mut caustic) = (Vec::new(), Vec::new());
        for ph in main.photons {
            match ph.kind {
                PathKind::Caustic => {
                    if aimed.is_none() {
                        caustic.push(ph);
                    }
                    if p.gather_indirect {
                        global.push(ph);
                    }
                }
                PathKind::Indirect => global.push(ph),
                PathKind::Direct if p.gather_indirect => global.push(ph),
                PathKind::Direct => {}
            }
        }
        let (mut rays, mut truncated) = (main.rays, main.truncated);
        if let Some(aimed) = aimed {
            caustic = aimed.photons;
            rays += aimed.rays;
            truncated += aimed.truncated;
        }
        let (global, caustic) = (PhotonMap::new(global), PhotonMap::new(caustic));
        PhotonMaps {
            global,
            caustic,
            trace_seconds,
            build_seconds: clock.elapsed().as_secs_f64(),
            emitted: p.num_photons_to_shoot,
            caustic_emitted,
            rays,
            truncated,
            collect: p.num_photons_to_collect.max(1) as usize,
            max_radius: p.max_radius * scene.bounds().extent().length(),
        }
    }

    /// Irradiance / π at a surface point from the global map.
    pub fn global_at(&self, x: crate::geometry::Vec3, n: crate::geometry::Vec3) -> Color {
        self.global
            .irradiance_over_pi(x, n, self.collect, self.max_radius)
            .0
    }

    /// Irradiance / π at a surface point from the caustic map.
    pub fn caustic_at(&self, x: crate::geometry::Vec3, n: crate::geometry::Vec3) -> Color {
        self.caustic
            .irradiance_over_pi(x, n, self.collect, self.max_radius)
            .0
    }
}

/// The photons of a map seen from the camera (`--visualize photons`): each photon's power
/// splatted into the pixel it projects to, scaled so the brightest pixel is 1.
pub fn visualize(scene: &Scene, maps: &PhotonMaps, settings: &RenderSettings) -> Film {
    let camera = scene.camera();
    let mut film = Film::new(settings.width, settings.height);
    for p in maps.global.photons.iter().chain(&maps.caustic.photons) {
        if let Some(idx) = film.pixel_of(&camera, p.position) {
            film.pixels[idx] += p.power;
        }
    }
    let brightest = film
        .pixels
        .iter()
        .map(|c| c.max_elem())
        .fold(0.0f32, f32::max);
    if brightest > 0.0 {
        film.pixels.iter_mut().for_each(|c| *c = *c / brightest);
    }
    film
}

/// Levels of the kd-tree drawn by `--visualize kdtree` (2⁶ = 64 cells).
const KD_VIEW_DEPTH: u32 = 6;

/// The cells of a balanced kd-tree over all photons, `depth` levels deep: each cell split at
/// the median photon along its longest axis, as kiddo's `ImmutableKdTree` balances its own
/// (whose nodes it does not expose). Cells are the photons' bounding boxes.
fn kd_cells(maps: &PhotonMaps, depth: u32) -> Vec<Bounds3> {
    fn split(points: &mut [Vec3], depth: u32, out: &mut Vec<Bounds3>) {
        let bounds = Bounds3::from_points(points);
        if depth == 0 || points.len() < 2 {
            out.push(bounds);
            return;
        }
        let axis = bounds.extent().max_axis();
        let middle = points.len() / 2;
        points.select_nth_unstable_by(middle, |a, b| a[axis].total_cmp(&b[axis]));
        let (low, high) = points.split_at_mut(middle);
        split(low, depth - 1, out);
        split(high, depth - 1, out);
    }
    let mut points: Vec<Vec3> = maps
        .global
        .photons
        .iter()
        .chain(&maps.caustic.photons)
        .map(|p| p.position)
        .collect();
    let mut out = Vec::new();
    if !points.is_empty() {
        split(&mut points, depth, &mut out);
    }
    out
}

/// The twelve edges of a box.
fn box_edges(b: &Bounds3) -> [(Vec3, Vec3); 12] {
    let corner = |i: u32| {
        crate::geometry::vec3(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    };
    let pairs = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    pairs.map(|(a, c)| (corner(a), corner(c)))
}

/// Renders with the photon engine: traces the maps (or loads them), then ray traces with them as the indirect
/// light (and, with `-gather_indirect`, an irradiance cache of final gathers).
pub fn render(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<(Film, super::RenderStats, PhotonMaps), String> {
    let p = &settings.photon;
    let maps = match &p.load {
        Some(path) => PhotonMaps::load(path, scene, settings)?,
        None => PhotonMaps::build(scene, accel, settings),
    };
    if let Some(path) = &p.save {
        maps.save(path, file::fingerprint(scene, settings))
            .map_err(|e| e.to_string())?;
    }
    let mode = settings.visualize;
    if matches!(mode, Visualize::Photons | Visualize::Kdtree) {
        let stats = super::RenderStats::default();
        stats.photon_rays.store(maps.rays, Relaxed);
        let mut film = visualize(scene, &maps, settings);
        if mode == Visualize::Kdtree {
            let camera = scene.camera();
            let green = crate::geometry::vec3(0.0, 1.0, 0.0);
            let cells = kd_cells(&maps, KD_VIEW_DEPTH);
            crate::film::draw_lines(
                &mut film,
                &camera,
                cells
                    .iter()
                    .flat_map(|b| box_edges(b).map(|(a, c)| (a, c, green))),
            );
        }
        return Ok((film, stats, maps));
    }
    let cache = settings
        .photon
        .gather_indirect
        .then(|| IrradianceCache::build(scene, accel, settings, &maps));
    let indirect = super::raytrace::Indirect::Photons {
        maps: &maps,
        cache: cache.as_ref(),
    };
    let (film, stats) = super::raytrace::render_with(scene, accel, settings, indirect);
    stats.photon_rays.store(maps.rays, Relaxed);
    if let Some(c) = &cache {
        stats
            .secondary_rays
            .fetch_add(c.rays.load(Relaxed), Relaxed);
        if !settings.quiet {
            eprintln!(
                "irradiance cache: {} records in {:.3} s; lookups interpolated {}, gathered afresh {}",
                c.records.len(),
                c.build_seconds,
                c.interpolated.load(Relaxed),
                c.fresh.load(Relaxed)
            );
        }
    }
    Ok((film, stats, maps))
}
