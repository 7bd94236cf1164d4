//! The viewer's render thread: it takes the newest job, renders it with the library's engines
//! — the same `engines::render` the offline command runs — and hands each image to the
//! window as it comes. A newer job supersedes the one running (`interrupt::submit_job`):
//! every long loop stops within a chunk of samples, and the superseded job's images are
//! never shown.
//!
//! What a pre-pass makes is kept between jobs while what it reads stays the same: the radiosity
//! solve (more shots shoot on from it, a solve cut short by a newer job keeping the shots it
//! took) and the photon maps. The image drawn from them is the one the offline command
//! renders: a solve shot on is, after n shots, the solve of n shots in one go. With the solve
//! goes what the camera samples of its last image saw of its mesh: the next image from the
//! same camera (a shot more, another mode) looks the solution up there and traces no ray.
//!
//! A progressive trace ('r') renders first with one sample per 16×16 block of pixels (the
//! image at a sixteenth of the resolution, each pixel drawn as its block), then 8×8, 4×4 and
//! 2×2, then every pixel with one sample (when more are asked for), then the full image with
//! every setting as given. That last stage is the offline render itself: its pixels equal
//! those of the printed command line's image.

use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, RwLock};
use std::thread::JoinHandle;
use std::time::Instant;

use crate::accel::{Accel, AccelKind, AccelOptions};
use crate::engines::photon::{self, PhotonMaps};
use crate::engines::radiosity::{self, ProgressiveSolve, Samples, SeenMesh, Solution};
use crate::engines::{self, compose, EngineKind, RenderSettings, Rendered};
use crate::film::Film;
use crate::geometry::Vec3;
use crate::render::ImageSettings;
use crate::scene::{Camera, Scene};

/// The block sides of a progressive trace's coarse stages (one sample each), coarsest first;
/// 1 is the full resolution, a stage of its own when the image asks for more samples.
const BLOCKS: [u32; 5] = [16, 8, 4, 2, 1];

/// What the window asks for: an image of `engine` with `settings` from `camera`.
#[derive(Clone)]
pub struct Job {
    pub camera: Camera,
    pub engine: EngineKind,
    pub settings: RenderSettings,
    /// Coarse stages first ('r'), or the image at once (the views).
    pub progressive: bool,
    /// The seconds of `--time-limit`, counted from the start of the last stage.
    pub time_limit: Option<f64>,
    /// Quads opaque from both sides (`--two-sided`; 'b').
    pub two_sided: bool,
    /// What the window calls it: "MATERIALS (raycast)", "RADIANCE (radiosity, 16 shots)".
    pub label: String,
    /// The flags that make the offline command render this job's image besides the
    /// session's: the names it sets (removed from the session's flags) and the words added.
    pub controls: &'static [&'static str],
    pub flags: Vec<String>,
}

/// One image for the window.
pub struct Frame {
    /// At the session's full resolution (coarse stages drawn block by block).
    pub film: Film,
    /// The job it is an image of.
    pub job: Job,
    /// This stage: "16×16 blocks", "64 spp".
    pub stage: String,
    /// This stage's number and the number of stages (1 of 1 for a view).
    pub step: (usize, usize),
    /// Whether this is the job's last stage: the image the offline command renders.
    pub finished: bool,
    /// Seconds since the job started.
    pub seconds: f64,
    /// What the engine said of the render (the radiosity solve's summary: how it stopped).
    pub summary: Vec<String>,
}

/// What the render thread tells the window.
pub enum Report {
    Frame(Box<Frame>),
    /// A render failed (an input the engine reads itself, such as `--load-photons`).
    Failed(String),
}

/// The render thread and the way to it.
pub struct Worker {
    jobs: Sender<(u64, Job)>,
    thread: JoinHandle<()>,
}

/// The scene and its Accel. The render thread alone changes them, between renders (a job's
/// camera; the quads' sides, rebuilding the Accel); the window reads them for ray trees.
pub struct World {
    pub scene: Scene,
    pub accel: Box<dyn Accel>,
}

/// What the render thread works with.
pub struct Renderer {
    pub world: Arc<RwLock<World>>,
    pub pool: rayon::ThreadPool,
    /// How to build the Accel again when a job turns `--two-sided` on or off.
    pub accel_kind: AccelKind,
    pub accel_options: AccelOptions,
    /// The last radiosity solve: another view of it or another camera renders it without
    /// solving again, and more shots shoot on from it.
    pub radiosity: Option<KeptRadiosity>,
    /// The last photon maps, and what they were traced with (see `photon_key`): another
    /// camera or display of them renders them without tracing again.
    pub photons: Option<(PhotonKey, PhotonMaps)>,
}

/// A radiosity solve the render thread keeps, and what it keeps to draw it.
pub struct KeptRadiosity {
    /// What it was solved with: the settings with their display fields and shots reset (see
    /// `solve_key`), and the quads' sides.
    key: (RenderSettings, bool),
    solve: KeptSolve,
    /// What the camera samples of its last image saw of its mesh, and their camera and image
    /// settings: the next image from that camera, after a shot more or in another view, is
    /// drawn from it without tracing (the mesh is the solve's, which shots do not change).
    seen: Option<((Camera, ImageSettings), SeenMesh)>,
}

/// A radiosity solve the render thread keeps.
pub enum KeptSolve {
    /// Shot on a few shots at a time (space, 'a').
    Shooting(Box<ProgressiveSolve>),
    /// Solved in one go for the shots it was asked (`--radiosity-iterations`, None: until
    /// converged): the solves `ProgressiveSolve` cannot take a few shots at a time.
    Solved(Option<u64>, Box<Solution>),
}

impl KeptSolve {
    /// Whether this solve gives the solution of `iterations` shots: one shot on, from no
    /// more shots than those; one solved in one go, for those shots only.
    fn reaches(&self, iterations: Option<u64>) -> bool {
        match self {
            KeptSolve::Shooting(solve) => iterations.is_none_or(|n| solve.shots() <= n),
            KeptSolve::Solved(solved_for, _) => *solved_for == iterations,
        }
    }

    fn solution(&self) -> &Solution {
        match self {
            KeptSolve::Shooting(solve) => solve.solution(),
            KeptSolve::Solved(_, solution) => solution.as_ref(),
        }
    }
}

/// What photon maps are traced with: the settings with those of the image but its size
/// reset (see `photon_key`), the quads' sides, and — in a fog, whose photons are kept only
/// in reach of the camera — the camera's position.
pub type PhotonKey = (RenderSettings, bool, Option<Vec3>);

impl Worker {
    /// Starts the render thread; `report` hands what it makes to the window.
    pub fn start(renderer: Renderer, report: impl Fn(Report) + Send + 'static) -> Worker {
        let (jobs, inbox) = channel();
        let thread = std::thread::spawn(move || serve(renderer, inbox, report));
        Worker { jobs, thread }
    }

    /// Asks for `job`, superseding the job in flight.
    pub fn submit(&self, job: Job) {
        let number = crate::interrupt::submit_job();
        // The thread ends only when `jobs` is dropped: sending cannot fail before that.
        let _ = self.jobs.send((number, job));
    }

    /// Stops the job in flight and waits for the render thread to end.
    pub fn stop(self) {
        crate::interrupt::submit_job();
        drop(self.jobs);
        let _ = self.thread.join();
    }
}

/// The render thread: the newest job each time, until the window drops its end.
fn serve(mut renderer: Renderer, inbox: Receiver<(u64, Job)>, report: impl Fn(Report)) {
    crate::parallel::worker_start();
    while let Ok(mut job) = inbox.recv() {
        while let Ok(newer) = inbox.try_recv() {
            job = newer;
        }
        crate::interrupt::start_job(job.0);
        if let Err(message) = renderer.run(job.1, &report) {
            report(Report::Failed(message));
        }
    }
}

impl Renderer {
    /// Renders `job`, stage by stage, reporting each image; stops where it is superseded.
    fn run(&mut self, job: Job, report: &impl Fn(Report)) -> Result<(), String> {
        let start = Instant::now();
        let (width, height) = (job.settings.width, job.settings.height);
        // Engines with a pre-pass (photon maps, a radiosity solve) would compute it again
        // for every coarse stage: they go straight to the full image.
        let coarse: Vec<u32> = if !job.progressive
            || engines::engine(job.engine)
                .pre_pass(&job.settings)
                .is_some()
        {
            Vec::new()
        } else {
            BLOCKS
                .into_iter()
                .filter(|&b| b < width.max(height))
                .filter(|&b| b > 1 || job.settings.num_antialias_samples > 1)
                .collect()
        };
        let stages = coarse.len() + 1;
        for (k, &block) in coarse.iter().enumerate() {
            let settings = RenderSettings {
                width: width.div_ceil(block),
                height: height.div_ceil(block),
                num_antialias_samples: 1,
                ..job.settings.clone()
            };
            let Some(low) = self.render(&job, &settings)? else {
                return Ok(());
            };
            report(Report::Frame(Box::new(Frame {
                film: blocks(&low.film, block, width, height),
                job: job.clone(),
                stage: if block == 1 {
                    "1 spp".to_string()
                } else {
                    format!("{block}×{block} blocks")
                },
                step: (k + 1, stages),
                finished: false,
                seconds: start.elapsed().as_secs_f64(),
                summary: Vec::new(),
            })));
        }
        let settings = RenderSettings {
            deadline: job
                .time_limit
                .map(|t| Instant::now() + std::time::Duration::from_secs_f64(t)),
            ..job.settings.clone()
        };
        if let Some(rendered) = self.render(&job, &settings)? {
            report(Report::Frame(Box::new(Frame {
                film: rendered.film,
                stage: format!("{} spp", settings.num_antialias_samples),
                job,
                step: (stages, stages),
                finished: true,
                seconds: start.elapsed().as_secs_f64(),
                summary: rendered.summary,
            })));
        }
        Ok(())
    }

    /// The image `job.engine` renders with `settings`, or None if the job was superseded.
    fn render(&mut self, job: &Job, settings: &RenderSettings) -> Result<Option<Rendered>, String> {
        if crate::interrupt::superseded() {
            return Ok(None);
        }
        const POISONED: &str = "the scene's lock was poisoned by a failed render";
        {
            let mut world = self.world.write().map_err(|_| POISONED)?;
            world.scene.camera = Some(job.camera);
            world
                .scene
                .filter_textures_for(settings.width, settings.height);
            if world.scene.two_sided_quads != job.two_sided {
                world.scene.two_sided_quads = job.two_sided;
                let scene = &world.scene;
                let accel = self
                    .pool
                    .install(|| crate::accel::build(scene, self.accel_kind, &self.accel_options))
                    .map_err(|e| e.to_string())?;
                world.accel = accel;
            }
        }
        let world = self.world.read().map_err(|_| POISONED)?;
        let (scene, accel): (&Scene, &dyn Accel) = (&world.scene, world.accel.as_ref());
        let pool = &self.pool;
        engines::check_camera(scene)?;
        // A radiosity image of a solve kept from the last one (no time limit: a deadline
        // makes the solve depend on the clock).
        if job.engine == EngineKind::Radiosity && settings.deadline.is_none() {
            // One call into the pool for the shots and the image: a press costs a millisecond
            // or two, of which each hand-over between threads would take its share.
            let kept = &mut self.radiosity;
            return pool.install(|| radiosity_image(kept, scene, accel, job, settings));
        }
        if job.engine == EngineKind::Photon {
            let key = (
                photon_key(settings),
                job.two_sided,
                scene.fog.map(|_| job.camera.position),
            );
            let maps = match self.photons.take().filter(|(k, _)| *k == key) {
                Some((_, maps)) => maps,
                None => pool.install(|| photon::maps(scene, accel, settings))?,
            };
            if crate::interrupt::superseded() {
                // Maps cut short hold fewer photons than the settings ask for.
                return Ok(None);
            }
            let rendered =
                pool.install(|| compose::render_with_maps(scene, accel, settings, &maps));
            self.photons = Some((key, maps));
            return Ok((!crate::interrupt::superseded()).then_some(rendered));
        }
        let rendered =
            pool.install(|| engines::engine(job.engine).render(scene, accel, settings))?;
        Ok((!crate::interrupt::superseded()).then_some(rendered))
    }
}

/// A radiosity image of the solve `kept_solve` holds, shot on to the shots `settings` ask
/// for, or of a new solve where it cannot be; None if the job was superseded. Called in the
/// render thread's pool.
fn radiosity_image(
    kept_solve: &mut Option<KeptRadiosity>,
    scene: &Scene,
    accel: &dyn Accel,
    job: &Job,
    settings: &RenderSettings,
) -> Result<Option<Rendered>, String> {
    let iterations = settings.radiosity.iterations;
    let key = (solve_key(settings), job.two_sided);
    let kept = kept_solve
        .take()
        .filter(|kept| kept.key == key && kept.solve.reaches(iterations));
    let mut kept = match kept {
        Some(kept) => kept,
        None => KeptRadiosity {
            key,
            solve: match ProgressiveSolve::new(scene, accel, settings) {
                Some(solve) => KeptSolve::Shooting(Box::new(solve)),
                None => KeptSolve::Solved(
                    iterations,
                    Box::new(radiosity::solve_with_progress(scene, accel, settings)?),
                ),
            },
            seen: None,
        },
    };
    if let KeptSolve::Shooting(solve) = &mut kept.solve {
        solve.shoot_to(scene, accel, settings);
    }
    if crate::interrupt::superseded() {
        // Cut short. The shots a solve shooting on took stand (the next job shoots
        // on from them); a solve in one go is not the one its settings ask for.
        if matches!(kept.solve, KeptSolve::Shooting(_)) {
            *kept_solve = Some(kept);
        }
        return Ok(None);
    }
    let solution = kept.solve.solution();
    let draw = |samples| radiosity::render_solved(scene, accel, settings, solution, samples);
    let seen_key = (job.camera, settings.image());
    let (film, stats) = match &kept.seen {
        Some((key, seen)) if *key == seen_key => draw(Samples::Kept(seen)),
        _ => {
            let mut seen = None;
            let drawn = draw(Samples::Keep(&mut seen));
            kept.seen = seen.map(|seen| (seen_key, seen));
            drawn
        }
    };
    let rendered = solution.rendered(film, stats, settings)?;
    *kept_solve = Some(kept);
    Ok((!crate::interrupt::superseded()).then_some(rendered))
}

/// The settings but those of the image (samples, lens, the time limit) and whether progress
/// is drawn: what a pre-pass (a radiosity solve, photon maps) may read, besides the image's
/// size.
fn pre_pass_key(settings: &RenderSettings) -> RenderSettings {
    let defaults = RenderSettings::default();
    RenderSettings {
        num_antialias_samples: defaults.num_antialias_samples,
        aperture: defaults.aperture,
        focus_distance: defaults.focus_distance,
        quiet: defaults.quiet,
        deadline: defaults.deadline,
        ..settings.clone()
    }
}

/// What a radiosity solve reads of the settings: all of them but the image's, how the
/// solution is shown (display mode, outlines, interpolation, the form factors' source) and
/// the shots (a solve kept shoots on to more).
fn solve_key(settings: &RenderSettings) -> RenderSettings {
    let defaults = RenderSettings::default();
    let mut key = RenderSettings {
        width: defaults.width,
        height: defaults.height,
        ..pre_pass_key(settings)
    };
    let r = &mut key.radiosity;
    r.display = defaults.radiosity.display;
    r.wireframe = defaults.radiosity.wireframe;
    r.interpolate = defaults.radiosity.interpolate;
    r.ff_source = defaults.radiosity.ff_source;
    r.iterations = defaults.radiosity.iterations;
    key
}

/// What photon maps are traced from: all the settings but the image's (its size stays: it
/// sets the photons when `-num_photons_to_shoot` is not given) and how the photons are shown.
fn photon_key(settings: &RenderSettings) -> RenderSettings {
    let mut key = pre_pass_key(settings);
    key.photon.display = RenderSettings::default().photon.display;
    key
}

/// A coarse image drawn at full resolution: each of its pixels as a `block`×`block` square.
fn blocks(low: &Film, block: u32, width: u32, height: u32) -> Film {
    let mut film = Film::new(width, height);
    for row in 0..height {
        for x in 0..width {
            film.pixels[(row * width + x) as usize] =
                low.pixels[((row / block) * low.width + x / block) as usize];
        }
    }
    film
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    #[test]
    fn a_coarse_pixel_fills_its_block_and_the_last_blocks_are_cut() {
        let mut low = Film::new(2, 2);
        low.pixels = vec![
            vec3(1.0, 0.0, 0.0),
            vec3(2.0, 0.0, 0.0),
            vec3(3.0, 0.0, 0.0),
            vec3(4.0, 0.0, 0.0),
        ];
        let film = blocks(&low, 4, 6, 5);
        let red = |x: u32, row: u32| film.pixels[(row * 6 + x) as usize].x;
        assert_eq!(
            (red(0, 0), red(3, 3), red(4, 0), red(5, 3)),
            (1.0, 1.0, 2.0, 2.0)
        );
        assert_eq!((red(0, 4), red(5, 4)), (3.0, 4.0));
    }
}
