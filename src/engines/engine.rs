//! The interface every engine implements, and what every engine reads and returns: the
//! common settings (holding each engine's own settings, leaf modules of their engines), the
//! plan, the budgets of the report's ladder, the rendered result.

use crate::accel::Accel;
use crate::film::part::Window;
use crate::film::Film;
use crate::geometry::Vec3;
use crate::render::{ImageSettings, RenderStats};
use crate::scene::Scene;

use super::photon::settings as photon;
use super::radiosity::settings as radiosity;

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
    /// Stochastic progressive photon mapping: photon passes with shrinking radii, which
    /// converges to the reference.
    Sppm,
}

impl EngineKind {
    pub fn name(self) -> &'static str {
        match self {
            EngineKind::Raycast => "raycast",
            EngineKind::Raytrace => "raytrace",
            EngineKind::Radiosity => "radiosity",
            EngineKind::Photon => "photon",
            EngineKind::Path => "path",
            EngineKind::Sppm => "sppm",
        }
    }

    /// Shadow rays a light when neither `-num_shadow_samples`, `--time-limit` nor the scene
    /// file chooses, with `indirect` the ray tracer's indirect light: the photon engine's,
    /// radiosity's and the ray tracer's with a radiosity solution their own
    /// (`photon::settings::SHADOW_SAMPLES`, `radiosity::settings::SHADOW_SAMPLES`,
    /// `radiosity::settings::INDIRECT_SHADOW_SAMPLES`), else the course's 0 (each light a
    /// point at its centre, unoccluded), which the course's command lines expect of the ray
    /// tracer.
    pub fn default_shadow_samples(self, indirect: IndirectKind) -> u32 {
        match (self, indirect) {
            (EngineKind::Photon, _) => super::photon::settings::SHADOW_SAMPLES,
            (EngineKind::Radiosity, _) => super::radiosity::settings::SHADOW_SAMPLES,
            (EngineKind::Raytrace, IndirectKind::Radiosity) => {
                super::radiosity::settings::INDIRECT_SHADOW_SAMPLES
            }
            _ => RenderSettings::default().num_shadow_samples,
        }
    }

    /// Mirror and refraction depth when neither `-num_bounces` nor the scene file chooses:
    /// the photon engine's own (`photon::settings::NUM_BOUNCES`), else the course's 0.
    pub fn default_num_bounces(self) -> u32 {
        match self {
            EngineKind::Photon => super::photon::settings::NUM_BOUNCES,
            _ => RenderSettings::default().num_bounces,
        }
    }
}

impl std::fmt::Display for EngineKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One lighting engine: what `render` runs, what `--plan` and `render report` ask it.
/// Adding an engine: its module with a type implementing this, a variant of `EngineKind`,
/// and its line in `engine()`.
pub trait Engine: Sync {
    /// Which engine this is.
    fn kind(&self) -> EngineKind;

    /// The names of the structures it may build beyond the image and the Accel ("photon
    /// map"), so that `--plan` can say of each whether the chosen engine builds it.
    fn structures(&self) -> &'static [&'static str] {
        &[]
    }

    /// The shared ray-tracing and camera flags this engine does not read, by argument id
    /// (`num_bounces`), so that the command can say they had no effect.
    fn unread_flags(&self) -> &'static [&'static str] {
        &[]
    }

    /// What the engine would build for this scene and these settings, decided before
    /// anything is built: its `--plan` lines and its memory estimate (default: nothing
    /// beyond the image and the Accel).
    fn plan(&self, _scene: &Scene, _settings: &RenderSettings) -> EnginePlan {
        EnginePlan::default()
    }

    /// Renders the scene. Fails only on input the engine reads itself (`--load-photons`).
    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String>;

    /// Whether the image is the mean of camera samples taken by the shared pixel loop, and
    /// nothing drawn over them, so that `--pixel-samples` can split a pixel's samples between
    /// renders (default yes; no for the MATERIALS view, drawings such as `--wireframe`, and
    /// the photons shown as they are).
    fn samples_pixels(&self, _settings: &RenderSettings) -> bool {
        true
    }

    /// What this engine computes before its pixels that a render farm computes once and
    /// every task loads (photon maps, a radiosity solution), or None.
    fn pre_pass(&self, _settings: &RenderSettings) -> Option<PrePass> {
        None
    }

    /// Computes the pre-pass and saves it where the settings say (`--pre-pass-only`);
    /// returns what the engine has to say. Only called when `pre_pass` is Some.
    fn run_pre_pass(
        &self,
        _scene: &Scene,
        _accel: &dyn Accel,
        _settings: &RenderSettings,
    ) -> Result<Vec<String>, String> {
        Err(format!("the {} engine has no pre-pass", self.kind()))
    }

    /// The settings of budget `level` (0, 1, 2, …) of the report's error-against-time
    /// ladder, each about twice the work of the one before; None past the last level.
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget>;

    /// The colour of the engine's curve in the report's plot (sRGB).
    fn colour(&self) -> (u8, u8, u8);
}

/// An engine's pre-pass as a render farm runs it: what it is, and the flags that save and
/// load it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrePass {
    /// "photon maps", "radiosity solution".
    pub name: &'static str,
    /// The flag that saves it (`--save-photons`) and the one that loads it.
    pub save_flag: &'static str,
    pub load_flag: &'static str,
    /// Whether the settings already ask to save it.
    pub saved: bool,
}

/// What an engine would build, for `--plan` and `--max-memory`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnginePlan {
    /// The structures it builds beyond the image and the Accel, by name ("photon map",
    /// "radiosity mesh") with what `--plan` says of each ("yes", "yes (224 patches; …)").
    /// `--plan` prints "no" for the names other engines would build.
    pub structures: Vec<(&'static str, String)>,
    /// Estimated peak bytes of those structures, by part.
    pub memory: Vec<(&'static str, u64)>,
}

/// One budget of the report's ladder: what it counts, how many, and the settings.
pub struct Budget {
    /// What the budget counts ("spp", "photons", "subdivide").
    pub counts: &'static str,
    pub value: u64,
    pub settings: RenderSettings,
}

impl Budget {
    /// Budget `level` of a ladder of samples per pixel doubling from 1 up to 2^`last`, the
    /// other settings `base`'s; None past the last level.
    pub fn samples_per_pixel(level: u32, last: u32, base: &RenderSettings) -> Option<Budget> {
        (level <= last).then(|| {
            let spp = 1u32 << level;
            Budget {
                counts: "spp",
                value: spp as u64,
                settings: RenderSettings {
                    num_antialias_samples: spp,
                    ..base.clone()
                },
            }
        })
    }
}

/// What one render produced: the image, its counters, and what the engine has to say.
pub struct Rendered {
    pub film: Film,
    pub stats: RenderStats,
    /// Lines on what was built and how it went ("photons: …", "radiosity: …"), printed
    /// unless `--quiet`.
    pub summary: Vec<String>,
    /// Printed whatever `--quiet` says.
    pub warnings: Vec<String>,
    /// The solver's convergence log as CSV, for `--log-convergence`.
    pub convergence_log: Option<String>,
    /// Named counters of what the engine built (`--stats`): a label and (name, count) pairs.
    pub counters: Option<(&'static str, Vec<(&'static str, u64)>)>,
}

impl Rendered {
    /// A render with nothing to report beyond its image and counters.
    pub fn plain(film: Film, stats: RenderStats) -> Rendered {
        Rendered {
            film,
            stats,
            summary: Vec::new(),
            warnings: Vec::new(),
            convergence_log: None,
            counters: None,
        }
    }
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

/// Everything an engine reads besides the scene. Defaults are those of the course program
/// where it has one.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width and height in pixels (`-size W H`, default 256 256).
    pub width: u32,
    pub height: u32,
    /// Mirror/refraction recursion depth (`-num_bounces`, default 0; `render`'s default is
    /// the engine's, `EngineKind::default_num_bounces`).
    pub num_bounces: u32,
    /// Shadow rays per light (`-num_shadow_samples`, default 0: lights unoccluded; `render`'s
    /// default is the engine's, `EngineKind::default_shadow_samples`).
    pub num_shadow_samples: u32,
    /// Samples per pixel (`-num_antialias_samples`, default 1).
    pub num_antialias_samples: u32,
    /// Scatterings a path-traced path may take (`--max-depth`, default None: Russian roulette
    /// alone ends paths).
    pub max_depth: Option<u32>,
    /// Constant ambient radiance for diffuse indirect light (`-ambient_light`, default 0.1).
    pub ambient_light: Vec3,
    /// What the radiosity engine reads (mesh, form factors, solver, display).
    pub radiosity: radiosity::RadiositySettings,
    /// Where the ray tracer's diffuse indirect light comes from (`--indirect`, default
    /// ambient).
    pub indirect: IndirectKind,
    /// What the photon engine reads (photon count, density estimates, final gathering).
    pub photon: photon::PhotonSettings,
    /// Placement of points on lights (`--light-sampling`); None: the engine's own default,
    /// `raytrace::DEFAULT_LIGHT_SAMPLING` or `path::DEFAULT_LIGHT_SAMPLING` [default: None].
    pub light_sampling: Option<crate::sampling::LightSampling>,
    /// Where the path tracer's numbers come from (`--sampler`, default sobol).
    pub path_sampler: crate::sampling::PathSampler,
    /// Levels of splitting with `--light-sampling adaptive` (`--adaptive-depth`, default 2:
    /// up to 5×5 points on a light).
    pub adaptive_depth: u32,
    /// Thin-lens radius (`--aperture`, default 0: a pinhole camera).
    pub aperture: f32,
    /// Distance of the plane in focus (`--focus-distance`, default: the camera's distance
    /// to its point of interest).
    pub focus_distance: Option<f32>,
    /// Seed of every random number (`--seed`, default 0).
    pub seed: u64,
    /// No progress bars (`--quiet`).
    pub quiet: bool,
    /// Only the pixels of this window (`--crop-window`, default None: the whole image).
    pub window: Option<Window>,
    /// Only samples `first ≤ s < end` of each pixel (`--pixel-samples`, default None: all).
    pub pixel_samples: Option<(u32, u32)>,
    /// Render until then (`--time-limit`, default None): engines that can refine go on
    /// refining (samples, passes, shots) until the time is spent.
    pub deadline: Option<std::time::Instant>,
    /// Keep each pixel's sums in the film for the variance of its samples (`--variance FILE`,
    /// default false).
    pub variance: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            num_bounces: 0,
            num_shadow_samples: 0,
            num_antialias_samples: 1,
            max_depth: None,
            ambient_light: Vec3::splat(0.1),
            radiosity: Default::default(),
            indirect: IndirectKind::Ambient,
            photon: Default::default(),
            light_sampling: None,
            path_sampler: crate::sampling::PathSampler::Sobol,
            adaptive_depth: 2,
            aperture: 0.0,
            focus_distance: None,
            seed: 0,
            quiet: false,
            window: None,
            pixel_samples: None,
            deadline: None,
            variance: false,
        }
    }
}

impl RenderSettings {
    /// The photon engine's main pass: `-num_photons_to_shoot`, else chosen from the whole
    /// image's pixels (`photon::settings::photons_for_image`).
    pub fn photons(&self) -> u64 {
        self.photon.photons(self.width as u64 * self.height as u64)
    }

    /// The photon engine's caustic pass: `--caustic-photons`, else as many as the main pass.
    pub fn caustic_photons(&self) -> u64 {
        self.photon
            .caustic_photons(self.width as u64 * self.height as u64)
    }

    /// What the pixel loop and the camera read.
    pub fn image(&self) -> ImageSettings {
        ImageSettings {
            width: self.width,
            height: self.height,
            num_antialias_samples: self.num_antialias_samples,
            aperture: self.aperture,
            focus_distance: self.focus_distance,
            seed: self.seed,
            quiet: self.quiet,
            window: self.window,
            samples: self.pixel_samples,
            deadline: self.deadline,
            variance: self.variance,
        }
    }

    /// A hash of the scene and of every setting that changes a pixel's value, for the parts
    /// of a split render (`render merge` refuses parts whose fingerprints differ). Left out:
    /// the window and the sample range (what tells parts apart), the output and progress,
    /// whether the variance is kept, the files pre-passes are saved to or loaded from (a
    /// loaded pre-pass equals the computed one: its own fingerprint is checked), and the
    /// memory budget. Settings are hashed as
    /// their Debug text, which prints every field and floats in their shortest exact form.
    pub fn fingerprint(&self, scene: &Scene) -> u64 {
        let mut s = self.clone();
        s.quiet = false;
        s.window = None;
        s.pixel_samples = None;
        s.deadline = None;
        s.variance = false;
        s.photon.save = None;
        s.photon.load = None;
        s.radiosity.save = None;
        s.radiosity.load = None;
        s.radiosity.export = None;
        s.radiosity.log_convergence = false;
        s.radiosity.memory_budget = 0;
        crate::scene::hash_text(&format!(
            "trilux {} {:016x} {:?} {:?} {s:?}",
            env!("CARGO_PKG_VERSION"),
            scene.content_hash(),
            scene.camera(),
            scene.background
        ))
    }
}
