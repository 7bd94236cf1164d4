//! The lighting engines. Each takes the scene, an `Accel` and the settings and fills a `Film`:
//! `raycast` (the course's MATERIALS view), `raytrace`, `radiosity`, `photon` and the
//! reference `path` tracer. `render` is the one entry point that picks among them.

pub mod lights;
pub mod optics;
pub mod path;
pub mod photon;
pub mod radiosity;
pub mod raycast;
pub mod raytrace;

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use rayon::prelude::*;

use crate::accel::Accel;
use crate::film::Film;
use crate::geometry::Ray;
use crate::sampling::{Pattern, Rng, Strata};
use crate::scene::{Camera, Color, Scene, SurfaceHit, View};

use crate::geometry::Vec3;

/// The engines of trilux (`--engine`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EngineKind {
    /// The first visible surface's emitted radiance plus its albedo (texture looked up).
    Raycast,
    /// Whitted and distribution ray tracing.
    Raytrace,
    /// Radiosity on the quad mesh.
    Radiosity,
    /// Photon mapping: ray tracing with global and caustic photon maps as indirect light.
    Photon,
    /// The unbiased reference path tracer.
    Path,
}

impl EngineKind {
    pub fn name(self) -> &'static str {
        match self {
            EngineKind::Raycast => "raycast",
            EngineKind::Raytrace => "raytrace",
            EngineKind::Radiosity => "radiosity",
            EngineKind::Photon => "photon",
            EngineKind::Path => "path",
        }
    }
}

impl std::fmt::Display for EngineKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What one render produced: the image, its counters, and the radiosity solution or photon
/// maps it came from, for the caller to report on.
pub struct Rendered {
    pub film: Film,
    pub stats: RenderStats,
    pub solution: Option<radiosity::Solution>,
    pub maps: Option<photon::PhotonMaps>,
}

/// Renders the scene with the engine asked for (the ray tracer with the radiosity solution as
/// its indirect light when `settings.indirect` says so). Fails only where the photon engine
/// cannot read `--load-photons`.
pub fn render(
    engine: EngineKind,
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<Rendered, String> {
    let plain = |(film, stats)| Rendered {
        film,
        stats,
        solution: None,
        maps: None,
    };
    Ok(match engine {
        EngineKind::Raycast => {
            let film = raycast::render(scene, accel, settings);
            let stats = RenderStats::default();
            stats
                .camera_rays
                .store(settings.width as u64 * settings.height as u64, Relaxed);
            plain((film, stats))
        }
        EngineKind::Path => plain(path::render(scene, accel, settings)),
        EngineKind::Radiosity => {
            let (film, stats, solution) = radiosity::render(scene, accel, settings);
            Rendered {
                solution: Some(solution),
                ..plain((film, stats))
            }
        }
        EngineKind::Photon => {
            let (film, stats, maps) = photon::render(scene, accel, settings)?;
            Rendered {
                maps: Some(maps),
                ..plain((film, stats))
            }
        }
        EngineKind::Raytrace if settings.indirect == IndirectKind::Radiosity => {
            let solution = radiosity::solve_with_progress(scene, accel, settings);
            let indirect = raytrace::Indirect::radiosity(&solution, settings.radiosity.interpolate);
            let (film, stats) = raytrace::render_with(scene, accel, settings, indirect);
            stats.form_factor_rays.store(solution.rays, Relaxed);
            Rendered {
                solution: Some(solution),
                ..plain((film, stats))
            }
        }
        EngineKind::Raytrace => plain(raytrace::render(scene, accel, settings)),
    })
}

/// What an engine shows instead of the rendered image (`--visualize`): the radiosity
/// engine's modes, and the photon engine's `photons` and `kdtree`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Visualize {
    /// The solution: radiance of each patch plus the ambient term for light not yet shot.
    #[default]
    Radiance,
    /// Each patch's albedo.
    Materials,
    /// Form factors from one patch (`--ff-source`) to every other, grey by relative size.
    FormFactors,
    /// Emitted radiance.
    Lights,
    /// Radiance received but not yet shot.
    Undistributed,
    /// Radiance absorbed: (1 − ρ) × incident.
    Absorbed,
    /// The photon engine's photons projected through the camera, coloured by power.
    Photons,
    /// The photons with the cells of a balanced kd-tree over them drawn in green.
    Kdtree,
}

/// The ray tracer's source of diffuse indirect light (`--indirect`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum IndirectKind {
    /// The constant `-ambient_light`, as the course program.
    #[default]
    Ambient,
    /// The radiosity solution of the scene (solved first, with the radiosity settings).
    Radiosity,
}

/// Counters of one render, printed by `--stats`.
#[derive(Debug, Default)]
pub struct RenderStats {
    pub camera_rays: AtomicU64,
    pub shadow_rays: AtomicU64,
    pub secondary_rays: AtomicU64,
    /// Visibility rays between patches (radiosity form factors).
    pub form_factor_rays: AtomicU64,
    /// Rays cast by photons.
    pub photon_rays: AtomicU64,
    /// Samples that came out NaN or infinite: excluded from the image, and counted here.
    pub non_finite_samples: AtomicU64,
}

impl RenderStats {
    pub fn total_rays(&self) -> u64 {
        self.camera_rays.load(Relaxed)
            + self.shadow_rays.load(Relaxed)
            + self.secondary_rays.load(Relaxed)
            + self.form_factor_rays.load(Relaxed)
            + self.photon_rays.load(Relaxed)
    }
}

/// Everything an engine reads besides the scene. Defaults are those of the course program
/// where it has one.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width and height in pixels (`-size W H`, default 256 256).
    pub width: u32,
    pub height: u32,
    /// Mirror/refraction recursion depth (`-num_bounces`, default 0).
    pub num_bounces: u32,
    /// Shadow rays per light (`-num_shadow_samples`, default 0: lights unoccluded).
    pub num_shadow_samples: u32,
    /// Samples per pixel (`-num_antialias_samples`, default 1).
    pub num_antialias_samples: u32,
    /// Constant ambient radiance for diffuse indirect light (`-ambient_light`, default 0.1).
    pub ambient_light: Vec3,
    /// What to show instead of the rendered image (`--visualize`, default radiance: the
    /// image itself).
    pub visualize: Visualize,
    /// What the radiosity engine reads (mesh, form factors, solver, display).
    pub radiosity: radiosity::RadiositySettings,
    /// Where the ray tracer's diffuse indirect light comes from (`--indirect`, default
    /// ambient).
    pub indirect: IndirectKind,
    /// What the photon engine reads (photon count, density estimates, final gathering).
    pub photon: photon::PhotonSettings,
    /// Placement of points on lights (`--light-sampling`, default jittered).
    pub light_sampling: crate::sampling::Pattern,
    /// Thin-lens radius (`--aperture`, default 0: a pinhole camera).
    pub aperture: f32,
    /// Distance of the plane in focus (`--focus-distance`, default: the camera's distance
    /// to its point of interest).
    pub focus_distance: Option<f32>,
    /// Seed of every random number (`--seed`, default 0).
    pub seed: u64,
    /// No progress bars (`--quiet`).
    pub quiet: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            num_bounces: 0,
            num_shadow_samples: 0,
            num_antialias_samples: 1,
            ambient_light: Vec3::splat(0.1),
            visualize: Visualize::Radiance,
            radiosity: Default::default(),
            indirect: IndirectKind::Ambient,
            photon: Default::default(),
            light_sampling: crate::sampling::Pattern::Jittered,
            aperture: 0.0,
            focus_distance: None,
            seed: 0,
            quiet: false,
        }
    }
}

/// Ray counts of one row of pixels, added to the shared counters once per row, and scratch
/// buffers for shadow rays (reused from one shading point to the next).
#[derive(Default)]
pub(crate) struct Counts {
    pub camera: u64,
    pub shadow: u64,
    pub secondary: u64,
    pub non_finite: u64,
    pub shadow_rays: Vec<Ray>,
    pub shadow_weights: Vec<f32>,
    pub blocked: Vec<bool>,
}

/// The camera samples of an image: the view, the pixel strata and the lens, worked out once.
pub(crate) struct CameraSampler {
    view: View,
    pixel_strata: Strata,
    /// Per pixel, 1 for one ray through the centre.
    spp: u32,
    aperture: f32,
    focus_distance: f32,
    seed: u64,
    width: u32,
    height: u32,
}

impl CameraSampler {
    pub fn new(scene: &Scene, settings: &RenderSettings) -> CameraSampler {
        let camera = scene.camera();
        let spp = settings.num_antialias_samples.max(1);
        CameraSampler {
            view: camera.view(),
            pixel_strata: Strata::new(Pattern::Jittered, spp),
            spp,
            aperture: settings.aperture,
            focus_distance: settings
                .focus_distance
                .unwrap_or_else(|| camera.focus_distance()),
            seed: settings.seed,
            width: settings.width,
            height: settings.height,
        }
    }

    /// Camera ray `k` of pixel (i, j) (j from the bottom) and the generator that the rest of
    /// its path draws from: both depend only on (seed, pixel, sample).
    #[inline]
    pub fn sample(&self, (i, j): (u32, u32), k: u32) -> (Ray, Rng) {
        let (w, h) = (self.width, self.height);
        let mut rng = Rng::new(self.seed, j as u64 * w as u64 + i as u64, k as u64);
        let (dx, dy) = if self.spp == 1 {
            (0.5, 0.5)
        } else {
            self.pixel_strata.sample(k, &mut rng)
        };
        let screen = Camera::screen_point(i, j, dx, dy, w, h);
        let lens = (rng.next_f32(), rng.next_f32());
        let ray = self
            .view
            .lens_ray(screen, self.aperture, self.focus_distance, lens);
        (ray, rng)
    }
}

/// Camera samples traced as one batch (a row is cut into chunks of about this many).
pub const CHUNK_SAMPLES: usize = 4096;

/// The pixel loop every sampling engine shares: rows in parallel, the camera rays of a row
/// traced as one batch, `-num_antialias_samples` per pixel averaged with a box filter, and
/// samples that come out NaN or infinite left out and counted. `radiance` gives the radiance
/// along a camera ray from its closest hit.
pub(crate) fn render_pixels(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    label: &str,
    radiance: impl Fn(&Ray, Option<SurfaceHit>, &mut Rng, &mut Counts) -> Color + Sync,
) -> (Film, RenderStats) {
    let (w, h) = (settings.width, settings.height);
    let camera = CameraSampler::new(scene, settings);
    let spp = settings.num_antialias_samples.max(1) as usize;
    let stats = RenderStats::default();
    let mut film = Film::new(w, h);
    let bar = crate::progress::bar(h as u64, label, settings.quiet);
    film.pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(row, out)| {
            let j = h - 1 - row as u32;
            let mut counts = Counts::default();
            // A row in chunks of about CHUNK_SAMPLES camera samples: one batch of camera rays
            // each, memory bounded whatever the samples per pixel, and Ctrl-C heard between
            // chunks (the pixels not yet rendered stay black).
            let chunk = (CHUNK_SAMPLES / spp).max(1);
            for (c, pixels) in out.chunks_mut(chunk).enumerate() {
                if crate::interrupt::requested() {
                    break;
                }
                let first = (c * chunk) as u32;
                let mut rngs = Vec::with_capacity(pixels.len() * spp);
                let mut rays = Vec::with_capacity(pixels.len() * spp);
                for i in first..first + pixels.len() as u32 {
                    for k in 0..spp as u32 {
                        let (ray, rng) = camera.sample((i, j), k);
                        rays.push(ray);
                        rngs.push(rng);
                    }
                }
                let mut hits = vec![None; rays.len()];
                accel.intersect_batch(&rays, &mut hits);
                counts.camera += rays.len() as u64;
                for (i, pixel) in pixels.iter_mut().enumerate() {
                    // Summed in f64: finite samples near f32's largest value must not add up
                    // to infinity; their mean is again a finite f32.
                    let mut sum = [0.0f64; 3];
                    let mut good = 0u32;
                    for idx in i * spp..(i + 1) * spp {
                        let ray = &rays[idx];
                        let hit = hits[idx].map(|h| scene.surface(ray, &h));
                        let l = radiance(ray, hit, &mut rngs[idx], &mut counts);
                        if l.is_finite() {
                            for (s, c) in sum.iter_mut().zip(l.to_array()) {
                                *s += c as f64;
                            }
                            good += 1;
                        } else {
                            counts.non_finite += 1;
                        }
                    }
                    let n = good.max(1) as f64;
                    *pixel = crate::geometry::vec3(
                        (sum[0] / n) as f32,
                        (sum[1] / n) as f32,
                        (sum[2] / n) as f32,
                    );
                }
            }
            stats.camera_rays.fetch_add(counts.camera, Relaxed);
            stats.shadow_rays.fetch_add(counts.shadow, Relaxed);
            stats.secondary_rays.fetch_add(counts.secondary, Relaxed);
            stats
                .non_finite_samples
                .fetch_add(counts.non_finite, Relaxed);
            bar.inc(1);
        });
    bar.finish_and_clear();
    (film, stats)
}
