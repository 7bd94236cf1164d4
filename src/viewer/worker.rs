//! The viewer's render thread: it takes the newest job, renders it with the library's engines
//! — the same `engines::render` the offline command runs — and hands each image to the
//! window as it comes. A newer job supersedes the one running (`interrupt::submit_job`):
//! every long loop stops within a chunk of samples, and the superseded job's images are
//! never shown.
//!
//! A progressive trace ('r') renders first with one sample per 16×16 block of pixels (the
//! image at a sixteenth of the resolution, each pixel drawn as its block), then 8×8, 4×4 and
//! 2×2, then the full image with every setting as given. That last stage is the offline
//! render itself: its pixels equal those of the printed command line's image.

use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread::JoinHandle;
use std::time::Instant;

use crate::accel::Accel;
use crate::engines::{self, EngineKind, RenderSettings};
use crate::film::Film;
use crate::scene::{Camera, Scene};

/// The block sides of a progressive trace's coarse stages, coarsest first.
const BLOCKS: [u32; 4] = [16, 8, 4, 2];

/// What the window asks for.
pub enum Job {
    /// The MATERIALS view (`--engine raycast`) from this camera.
    Preview(Camera),
    /// A progressive render with the session's engine from this camera.
    Trace(Camera),
}

/// One image for the window.
pub struct Frame {
    /// At the session's full resolution (coarse stages drawn block by block).
    pub film: Film,
    pub camera: Camera,
    /// The engine that rendered it.
    pub engine: EngineKind,
    /// What it is: "MATERIALS", "16×16 blocks", "4 spp".
    pub stage: String,
    /// This stage's number and the number of stages (1 of 1 for a preview).
    pub step: (usize, usize),
    /// Whether this is the job's last stage: the image the offline command renders.
    pub finished: bool,
    /// Seconds since the job started.
    pub seconds: f64,
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

/// What the render thread owns.
pub struct Renderer {
    pub scene: Scene,
    pub accel: Box<dyn Accel>,
    pub settings: RenderSettings,
    /// Seconds of `--time-limit`, counted from the start of each trace.
    pub time_limit: Option<f64>,
    pub engine: EngineKind,
    pub pool: rayon::ThreadPool,
}

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
        let result = match job.1 {
            Job::Preview(camera) => renderer.preview(camera, &report),
            Job::Trace(camera) => renderer.trace(camera, &report),
        };
        if let Err(message) = result {
            report(Report::Failed(message));
        }
    }
}

impl Renderer {
    fn preview(&mut self, camera: Camera, report: &impl Fn(Report)) -> Result<(), String> {
        let start = Instant::now();
        let settings = self.settings.clone();
        if let Some(film) = self.render(EngineKind::Raycast, camera, &settings)? {
            report(Report::Frame(Box::new(Frame {
                film,
                camera,
                engine: EngineKind::Raycast,
                stage: "MATERIALS".into(),
                step: (1, 1),
                finished: true,
                seconds: start.elapsed().as_secs_f64(),
            })));
        }
        Ok(())
    }

    fn trace(&mut self, camera: Camera, report: &impl Fn(Report)) -> Result<(), String> {
        let start = Instant::now();
        let (width, height) = (self.settings.width, self.settings.height);
        // Engines with a pre-pass (photon maps, a radiosity solve) would compute it again
        // for every coarse stage: they go straight to the full image.
        let coarse: Vec<u32> = if engines::engine(self.engine)
            .pre_pass(&self.settings)
            .is_some()
        {
            Vec::new()
        } else {
            BLOCKS
                .into_iter()
                .filter(|&b| b < width.max(height))
                .collect()
        };
        let stages = coarse.len() + 1;
        for (k, &block) in coarse.iter().enumerate() {
            let settings = RenderSettings {
                width: width.div_ceil(block),
                height: height.div_ceil(block),
                num_antialias_samples: 1,
                ..self.settings.clone()
            };
            let Some(low) = self.render(self.engine, camera, &settings)? else {
                return Ok(());
            };
            report(Report::Frame(Box::new(Frame {
                film: blocks(&low, block, width, height),
                camera,
                engine: self.engine,
                stage: format!("{block}×{block} blocks"),
                step: (k + 1, stages),
                finished: false,
                seconds: start.elapsed().as_secs_f64(),
            })));
        }
        let settings = RenderSettings {
            deadline: self
                .time_limit
                .map(|t| Instant::now() + std::time::Duration::from_secs_f64(t)),
            ..self.settings.clone()
        };
        if let Some(film) = self.render(self.engine, camera, &settings)? {
            report(Report::Frame(Box::new(Frame {
                film,
                camera,
                engine: self.engine,
                stage: format!("{} spp", settings.num_antialias_samples),
                step: (stages, stages),
                finished: true,
                seconds: start.elapsed().as_secs_f64(),
            })));
        }
        Ok(())
    }

    /// The image `engine` renders from `camera`, or None if the job was superseded.
    fn render(
        &mut self,
        engine: EngineKind,
        camera: Camera,
        settings: &RenderSettings,
    ) -> Result<Option<Film>, String> {
        if crate::interrupt::superseded() {
            return Ok(None);
        }
        self.scene.camera = Some(camera);
        let (scene, accel) = (&self.scene, self.accel.as_ref());
        let rendered = self
            .pool
            .install(|| engines::render(engine, scene, accel, settings))?;
        Ok((!crate::interrupt::superseded()).then_some(rendered.film))
    }
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
