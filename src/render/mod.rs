//! The floor every engine stands on: the pixel loop and the camera sampler that the sampling
//! engines share, the counters of a render, the lights as the engines sample them, and the
//! interface through which the ray tracer asks for diffuse indirect light. Nothing here knows
//! any engine.

pub mod adaptive;
pub mod indirect;
pub mod lights;
pub mod solid_angle;

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Instant;

use rayon::prelude::*;

pub use indirect::{Ambient, IndirectLight};

use crate::accel::Accel;
use crate::color::Color;
use crate::film::part::{SampleSums, Window};
use crate::film::Film;
use crate::geometry::Ray;
use crate::sampling::{Pattern, Rng, SampleId, Strata};
use crate::scene::{Camera, Scene, SurfaceHit, View};

/// What the pixel loop and the camera read: the image, its samples, the lens, the seed.
/// `engines::RenderSettings` holds the same values (defaults there) and makes this with
/// `image()`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageSettings {
    /// Image width and height in pixels (`-size W H`).
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (`-num_antialias_samples`).
    pub num_antialias_samples: u32,
    /// Thin-lens radius (`--aperture`; 0: a pinhole camera).
    pub aperture: f32,
    /// Distance of the plane in focus (`--focus-distance`; None: the camera's distance to
    /// its point of interest).
    pub focus_distance: Option<f32>,
    /// Seed of every random number (`--seed`).
    pub seed: u64,
    /// No progress bars (`--quiet`).
    pub quiet: bool,
    /// Only the pixels of this window (`--crop-window`; None: every pixel).
    pub window: Option<Window>,
    /// Only samples `first ≤ s < end` of each pixel's `num_antialias_samples`
    /// (`--pixel-samples`; None: all of them).
    pub samples: Option<(u32, u32)>,
    /// Render until then (`--time-limit`): passes of `num_antialias_samples` samples per
    /// pixel, as many as fit (None: exactly `num_antialias_samples`).
    pub deadline: Option<Instant>,
    /// Keep each pixel's sums in the film for the variance of its samples (`--variance`;
    /// false: only a part of a split render keeps them).
    pub variance: bool,
}

impl ImageSettings {
    /// The pixels to render: the window, or the whole image.
    pub fn window(&self) -> Window {
        self.window
            .unwrap_or_else(|| Window::full(self.width, self.height))
    }

    /// The samples of each pixel to take: the range asked for, or all of them.
    pub fn sample_range(&self) -> std::ops::Range<u32> {
        let (first, end) = self
            .samples
            .unwrap_or((0, self.num_antialias_samples.max(1)));
        first..end
    }

    /// Whether this render is one part of a split render: then the film keeps the sums of
    /// its samples, for `render merge`.
    pub fn is_part(&self) -> bool {
        self.window.is_some() || self.samples.is_some()
    }

    /// Whether the film keeps the sums of its samples: for a part, or for `--variance`.
    pub fn keeps_sums(&self) -> bool {
        self.is_part() || self.variance
    }
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
    /// Under `--time-limit`: the samples per pixel (or passes) reached.
    pub samples_reached: AtomicU64,
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

/// Ray counts of one row of pixels, added to the shared counters once per row, and scratch
/// buffers for shadow rays (reused from one shading point to the next).
#[derive(Default)]
pub struct Counts {
    pub camera: u64,
    pub shadow: u64,
    pub secondary: u64,
    pub non_finite: u64,
    pub shadow_rays: Vec<Ray>,
    pub shadow_weights: Vec<f32>,
    pub blocked: Vec<bool>,
    /// Which corners see the shading point (`--light-sampling adaptive`).
    pub corners: Vec<u8>,
}

/// The camera samples of an image: the view, the pixel strata and the lens, worked out once.
pub struct CameraSampler {
    view: View,
    pixel_strata: Strata,
    /// Per pixel, 1 for one ray through the centre.
    spp: u32,
    /// Samples without a known count (`--time-limit`): sample k of a pixel is point k of the
    /// R2 sequence (Roberts 2018), shifted by a random offset per pixel, so that any number
    /// of them is spread evenly over the pixel.
    open_ended: bool,
    aperture: f32,
    focus_distance: f32,
    seed: u64,
    width: u32,
    height: u32,
}

impl CameraSampler {
    pub fn new(scene: &Scene, settings: &ImageSettings) -> CameraSampler {
        CameraSampler::with_camera(&scene.camera(), settings)
    }

    /// The samples of `camera` (the viewer's ray tree: the camera of the image on screen,
    /// which need not be the scene's).
    pub fn with_camera(camera: &Camera, settings: &ImageSettings) -> CameraSampler {
        let spp = settings.num_antialias_samples.max(1);
        CameraSampler {
            view: camera.view(),
            pixel_strata: Strata::new(Pattern::Jittered, spp),
            spp,
            open_ended: settings.deadline.is_some(),
            aperture: settings.aperture,
            focus_distance: settings
                .focus_distance
                .unwrap_or_else(|| camera.focus_distance()),
            seed: settings.seed,
            width: settings.width,
            height: settings.height,
        }
    }

    /// Pixel (i, j)'s number, row-major from the bottom row: what its numbers hash.
    #[inline]
    fn pixel_number(&self, (i, j): (u32, u32)) -> u64 {
        j as u64 * self.width as u64 + i as u64
    }

    /// What the numbers of the path from camera sample `k` of pixel (i, j) are drawn from
    /// (`PathSamples`): the sample's index among the pixel's `-num_antialias_samples` (all of
    /// them, also in a part of a split render), none under `--time-limit`.
    #[inline]
    pub fn sample_id(&self, (i, j): (u32, u32), k: u32) -> SampleId {
        SampleId {
            seed: self.seed,
            pixel: self.pixel_number((i, j)),
            index: k,
            count: (!self.open_ended).then_some(self.spp),
        }
    }

    /// Camera ray `k` of pixel (i, j) (j from the bottom) and the generator that the rest of
    /// its path draws from: both depend only on (seed, pixel, sample).
    ///
    /// Always inlined: as a call, its ray came back through memory and was read wider than
    /// it was written, a store-forwarding stall (1% of the path tracer's time).
    #[inline(always)]
    pub fn sample(&self, (i, j): (u32, u32), k: u32) -> (Ray, Rng) {
        let (w, h) = (self.width, self.height);
        let pixel = self.pixel_number((i, j));
        let mut rng = Rng::new(self.seed, pixel, k as u64);
        let (dx, dy) = if self.open_ended {
            // The R2 sequence's steps are the inverse powers of the plastic number.
            const STEP: (f64, f64) = (0.754_877_666_246_692_8, 0.569_840_290_998_053_3);
            let mut shift = Rng::new(self.seed ^ 0x0b2e_5eed, pixel, 0);
            let (sx, sy) = (shift.next_f32() as f64, shift.next_f32() as f64);
            let k = k as f64;
            (
                (sx + k * STEP.0).fract() as f32,
                (sy + k * STEP.1).fract() as f32,
            )
        } else if self.spp == 1 {
            (0.5, 0.5)
        } else {
            self.pixel_strata.sample(k, &mut rng)
        };
        let screen = Camera::screen_point(i, j, dx, dy, w, h);
        // The lens point's two numbers are drawn whatever the aperture, so that the rest of
        // the path draws the same numbers; a pinhole only steps past them.
        if self.aperture <= 0.0 {
            rng.skip(2);
            return (self.view.ray(screen.0, screen.1), rng);
        }
        let lens = (rng.next_f32(), rng.next_f32());
        let ray = self
            .view
            .lens_ray(screen, self.aperture, self.focus_distance, lens);
        (ray, rng)
    }
}

/// Camera samples traced as one batch (a row's samples are cut into chunks of at most this
/// many).
pub const CHUNK_SAMPLES: usize = 4096;

/// A pixel's finite samples: their sum and the sum of their squares (in f64, per channel), and
/// how many there were. The squares cost three multiply-adds a sample, nothing beside a path,
/// and give the samples' variance (`--variance`) exactly however the samples are split.
#[derive(Clone, Copy, Debug, Default)]
struct PixelSum {
    sum: [f64; 3],
    squares: [f64; 3],
    count: u32,
}

impl PixelSum {
    fn add_sample(&mut self, l: Color) {
        for ((s, q), c) in self.sum.iter_mut().zip(&mut self.squares).zip(l.to_array()) {
            let c = c as f64;
            *s += c;
            *q += c * c;
        }
        self.count += 1;
    }

    fn add(&mut self, other: &PixelSum) {
        for c in 0..3 {
            self.sum[c] += other.sum[c];
            self.squares[c] += other.squares[c];
        }
        self.count += other.count;
    }

    /// The samples' mean (black without samples).
    fn mean(&self) -> Color {
        let n = self.count.max(1) as f64;
        crate::geometry::vec3(
            (self.sum[0] / n) as f32,
            (self.sum[1] / n) as f32,
            (self.sum[2] / n) as f32,
        )
    }
}

/// The pixel loop every sampling engine shares: rows in parallel, the camera rays of a row
/// traced as one batch, `-num_antialias_samples` per pixel averaged with a box filter, and
/// samples that come out NaN or infinite left out and counted. `radiance` gives the radiance
/// along a camera ray from its closest hit. Only the pixels of the settings' window and the
/// samples of their range are taken; a part of a split render keeps its sums in the film.
/// Under `--time-limit` the samples come in passes until the deadline: one sample a pixel,
/// then `-num_antialias_samples` a pass, or as many as the time left fits at the last
/// pass's rate (none: the render ends).
pub fn render_pixels(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &ImageSettings,
    label: &str,
    radiance: impl Fn(&Ray, Option<SurfaceHit>, &mut Rng, SampleId, &mut Counts) -> Color + Sync,
) -> (Film, RenderStats) {
    render_pixel_batches(scene, accel, settings, label, |batch, counts, out| {
        for (k, l) in out.iter_mut().enumerate() {
            *l = radiance(
                &batch.rays[k],
                batch.hits[k],
                &mut batch.rngs[k],
                batch.ids[k],
                counts,
            );
        }
    })
}

/// One batch of camera samples (a chunk of a row): their rays, closest hits, generators and
/// ids, in the same order.
pub struct CameraBatch<'a> {
    pub rays: &'a [Ray],
    pub hits: &'a [Option<SurfaceHit>],
    pub rngs: &'a mut [Rng],
    pub ids: &'a [SampleId],
}

/// What each camera sample of a whole image saw (`render_keeping_samples`): images drawn
/// from it again take no ray. A pixel's samples lie together, pixels in the order of their
/// numbers (row-major from the bottom row).
pub struct SampleGrid<T> {
    width: u32,
    height: u32,
    spp: u32,
    samples: Vec<T>,
}

/// `render_pixels` with each sample's radiance found in two steps, `look` at its ray and
/// closest hit, then `radiance` of what it saw, keeping what every sample saw: the image and
/// that grid, to draw images from again without a camera ray. No grid where the settings
/// ask for what a grid does not draw (a part of a split render, passes until a deadline, the
/// samples' sums kept), or where the render was superseded or interrupted before every
/// sample was taken.
pub fn render_keeping_samples<T: Send + Sync>(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &ImageSettings,
    label: &str,
    look: impl Fn(&Ray, Option<SurfaceHit>) -> T + Sync,
    radiance: impl Fn(&T) -> Color + Sync,
) -> (Film, RenderStats, Option<SampleGrid<T>>) {
    let keep = !settings.keeps_sums() && settings.deadline.is_none();
    let spp = settings.num_antialias_samples.max(1);
    let count = settings.width as usize * settings.height as usize * spp as usize;
    // Each slot is set once, by the row that owns its pixel.
    let slots: Vec<std::sync::OnceLock<T>> = (0..if keep { count } else { 0 })
        .map(|_| Default::default())
        .collect();
    let (film, stats) = render_pixel_batches(scene, accel, settings, label, |batch, _, out| {
        for (k, l) in out.iter_mut().enumerate() {
            let seen = look(&batch.rays[k], batch.hits[k]);
            *l = radiance(&seen);
            if keep {
                let id = batch.ids[k];
                let _ = slots[id.pixel as usize * spp as usize + id.index as usize].set(seen);
            }
        }
    });
    let samples = keep
        .then(|| {
            slots
                .into_iter()
                .map(std::sync::OnceLock::into_inner)
                .collect::<Option<Vec<T>>>()
        })
        .flatten();
    let grid = samples.map(|samples| SampleGrid {
        width: settings.width,
        height: settings.height,
        spp,
        samples,
    });
    (film, stats, grid)
}

impl<T: Sync> SampleGrid<T> {
    /// The image whose samples' radiance `radiance` gives: each pixel the mean of its finite
    /// samples, summed as `render_pixels` sums them, so that a grid drawn with the radiance
    /// `render_pixels` would compute from the same rays gives its pixels, bit for bit.
    pub fn film(&self, radiance: impl Fn(&T) -> Color + Sync) -> (Film, RenderStats) {
        let (w, h, spp) = (self.width, self.height, self.spp as usize);
        let stats = RenderStats::default();
        let mut film = Film::new(w, h);
        film.pixels
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(row, out)| {
                let j = h - 1 - row as u32;
                let first = (j as usize * w as usize) * spp;
                let samples = &self.samples[first..first + out.len() * spp];
                let mut non_finite = 0;
                if spp == 1 {
                    // One sample a pixel: its mean is the sample itself (-0 made +0, as the
                    // sum from +0 makes it), or black where it is not finite.
                    for (pixel, sample) in out.iter_mut().zip(samples) {
                        let l = radiance(sample);
                        *pixel = if l.is_finite() {
                            l + Color::ZERO
                        } else {
                            non_finite += 1;
                            Color::ZERO
                        };
                    }
                    stats.non_finite_samples.fetch_add(non_finite, Relaxed);
                    return;
                }
                for (pixel, samples) in out.iter_mut().zip(samples.chunks(spp)) {
                    let mut sum = PixelSum::default();
                    for l in samples.iter().map(&radiance) {
                        if l.is_finite() {
                            sum.add_sample(l);
                        } else {
                            non_finite += 1;
                        }
                    }
                    *pixel = sum.mean();
                }
                stats.non_finite_samples.fetch_add(non_finite, Relaxed);
            });
        (film, stats)
    }
}

/// `render_pixels` for engines that follow a chunk's camera samples together (the path
/// tracer's wavefront): `radiance` writes the radiance along each of the batch's rays into
/// `out`, in the batch's order.
pub fn render_pixel_batches(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &ImageSettings,
    label: &str,
    radiance: impl Fn(CameraBatch, &mut Counts, &mut [Color]) + Sync,
) -> (Film, RenderStats) {
    let camera = CameraSampler::new(scene, settings);
    let window = settings.window();
    let stats = RenderStats::default();
    let mut film = Film::new(settings.width, settings.height);
    let Some(deadline) = settings.deadline else {
        let bar = crate::progress::bar(window.height() as u64, label, settings.quiet);
        let rows = take_samples(
            scene,
            accel,
            &camera,
            (window, settings.sample_range()),
            &mut film,
            &stats,
            &bar,
            settings.keeps_sums(),
            &radiance,
        );
        bar.finish_and_clear();
        if settings.keeps_sums() {
            film.samples = Some(sample_sums(window, rows));
        }
        return (film, stats);
    };
    let per_pass = settings.num_antialias_samples.max(1);
    let start = Instant::now();
    let budget = deadline.saturating_duration_since(start).as_secs_f64();
    let bar = crate::progress::bar(1000, label, settings.quiet);
    let mut total = vec![PixelSum::default(); window.pixels()];
    let mut taken = 0u32;
    // The first pass takes one sample a pixel, so that an engine whose samples are dear (final
    // gathering: 4 samples a pixel took half a second at 256×256) overruns a short limit by
    // one sample's pass at most; later passes take `per_pass`, or as many as the time left
    // fits at the last pass's rate.
    let mut pass = 1;
    loop {
        let pass_start = Instant::now();
        let rows = take_samples(
            scene,
            accel,
            &camera,
            (window, taken..taken + pass),
            &mut film,
            &stats,
            &indicatif::ProgressBar::hidden(),
            true,
            &radiance,
        );
        for (t, pass_sum) in total.iter_mut().zip(rows.into_iter().flatten()) {
            t.add(&pass_sum);
        }
        taken += pass;
        let now = Instant::now();
        bar.set_position(
            (1000.0 * (now - start).as_secs_f64() / budget.max(1e-9)).min(1000.0) as u64,
        );
        let per_sample = (now - pass_start).as_secs_f64() / pass as f64;
        let left = deadline.saturating_duration_since(now).as_secs_f64();
        let fits = (left / per_sample.max(1e-12)).floor().min(per_pass as f64) as u32;
        if crate::interrupt::requested() || fits == 0 {
            break;
        }
        pass = fits;
    }
    bar.finish_and_clear();
    stats.samples_reached.store(taken as u64, Relaxed);
    for (k, pixel) in total.iter().enumerate() {
        let (x, row) = (
            window.x0 as usize + k % window.width() as usize,
            window.y0 as usize + k / window.width() as usize,
        );
        film.pixels[row * settings.width as usize + x] = pixel.mean();
    }
    if settings.keeps_sums() {
        film.samples = Some(sample_sums(
            window,
            total
                .chunks(window.width() as usize)
                .map(<[PixelSum]>::to_vec)
                .collect(),
        ));
    }
    (film, stats)
}

/// The (pixel, sample) pairs, both counted from 0, of the samples `run` of a row taken in
/// order, `spp` a pixel: sample n is sample n mod spp of pixel n / spp, divided once per run
/// and not once per sample.
fn pixels_and_samples(
    run: std::ops::Range<usize>,
    spp: usize,
) -> impl Iterator<Item = (usize, usize)> {
    let pixels = if run.is_empty() {
        0..0
    } else {
        run.start / spp..(run.end - 1) / spp + 1
    };
    pixels.flat_map(move |p| {
        let first = p * spp;
        (run.start.max(first) - first..run.end.min(first + spp) - first).map(move |k| (p, k))
    })
}

/// The sums of a window's pixels, row by row (a row Ctrl-C cut short took no samples in its
/// remaining pixels).
fn sample_sums(window: Window, rows: Vec<Vec<PixelSum>>) -> SampleSums {
    let mut sums = SampleSums {
        window,
        sums: Vec::with_capacity(window.pixels()),
        squares: Vec::with_capacity(window.pixels()),
        counts: Vec::with_capacity(window.pixels()),
    };
    for mut row in rows {
        row.resize(window.width() as usize, PixelSum::default());
        for pixel in row {
            sums.sums.push(pixel.sum);
            sums.squares.push(pixel.squares);
            sums.counts.push(pixel.count);
        }
    }
    sums
}

/// Takes samples `samples` of every pixel of `window`, rows in parallel, and writes each
/// pixel's mean into `film`; with `keep`, returns each pixel's sum and count too, row by row.
#[allow(clippy::too_many_arguments)]
fn take_samples(
    scene: &Scene,
    accel: &dyn Accel,
    camera: &CameraSampler,
    (window, samples): (Window, std::ops::Range<u32>),
    film: &mut Film,
    stats: &RenderStats,
    bar: &indicatif::ProgressBar,
    keep: bool,
    radiance: &(impl Fn(CameraBatch, &mut Counts, &mut [Color]) + Sync),
) -> Vec<Vec<PixelSum>> {
    let (w, h) = (film.width, film.height);
    let spp = samples.len();
    // Ctrl-C during what came before (a radiosity solve, photon tracing) stopped that, and
    // the pixels show what it made; Ctrl-C during the pixels stops them. A superseded
    // viewer job stops wherever it is: nobody will see its image.
    let interrupted_before = crate::interrupt::ctrl_c();
    film.pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .skip(window.y0 as usize)
        .take(window.height() as usize)
        .map(|(row, out)| {
            let j = h - 1 - row as u32;
            let mut counts = Counts::default();
            let out = &mut out[window.x0 as usize..window.x1 as usize];
            // The row's camera samples, pixel by pixel and within a pixel sample by sample,
            // in chunks of at most CHUNK_SAMPLES: one batch of camera rays each, memory
            // bounded and Ctrl-C heard between chunks whatever the samples per pixel (a
            // reference of ten million a pixel is cut inside a pixel). A pixel Ctrl-C cut
            // short keeps the mean of the samples it took; those not reached stay black,
            // with no samples.
            let mut sums: Vec<PixelSum> = vec![PixelSum::default(); out.len()];
            let total = out.len() * spp;
            let mut done = 0;
            while done < total {
                if crate::interrupt::superseded()
                    || (!interrupted_before && crate::interrupt::requested())
                {
                    break;
                }
                let chunk = done..(done + CHUNK_SAMPLES).min(total);
                let mut rngs = Vec::with_capacity(chunk.len());
                let mut rays = Vec::with_capacity(chunk.len());
                let mut ids = Vec::with_capacity(chunk.len());
                for (p, k) in pixels_and_samples(chunk.clone(), spp) {
                    let (i, k) = (window.x0 + p as u32, samples.start + k as u32);
                    let (ray, rng) = camera.sample((i, j), k);
                    rays.push(ray);
                    rngs.push(rng);
                    ids.push(camera.sample_id((i, j), k));
                }
                let mut prim_hits = vec![None; rays.len()];
                accel.intersect_batch(&rays, &mut prim_hits);
                counts.camera += rays.len() as u64;
                let hits: Vec<_> = rays
                    .iter()
                    .zip(&prim_hits)
                    .map(|(ray, h)| h.as_ref().map(|h| scene.surface(ray, h)))
                    .collect();
                let mut radiances = vec![Color::ZERO; rays.len()];
                let batch = CameraBatch {
                    rays: &rays,
                    hits: &hits,
                    rngs: &mut rngs,
                    ids: &ids,
                };
                radiance(batch, &mut counts, &mut radiances);
                // Summed in f64: finite samples near f32's largest value must not add up to
                // infinity; their mean is again a finite f32.
                for ((p, _), l) in pixels_and_samples(chunk.clone(), spp).zip(&radiances) {
                    if l.is_finite() {
                        sums[p].add_sample(*l);
                    } else {
                        counts.non_finite += 1;
                    }
                }
                done = chunk.end;
            }
            let reached = done.div_ceil(spp.max(1));
            for (pixel, sum) in out.iter_mut().zip(&sums).take(reached) {
                *pixel = sum.mean();
            }
            let row_sums = if keep {
                sums.truncate(reached);
                sums
            } else {
                Vec::new()
            };
            stats.camera_rays.fetch_add(counts.camera, Relaxed);
            stats.shadow_rays.fetch_add(counts.shadow, Relaxed);
            stats.secondary_rays.fetch_add(counts.secondary, Relaxed);
            stats
                .non_finite_samples
                .fetch_add(counts.non_finite, Relaxed);
            bar.inc(1);
            row_sums
        })
        .collect()
}
