//! The `render` command: parses the command line (the course's single-dash flags included),
//! calls the library, reports progress. No rendering logic lives here.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Parser, Subcommand};

use std::sync::atomic::Ordering::Relaxed;
use trilux::accel::{self, AccelKind, AccelOptions, EmbreeQuality};

use trilux::engines::photon::{self, PhotonSettings};
use trilux::engines::radiosity::{self, RadiositySettings};
use trilux::engines::{
    self, raytrace, EngineKind, IndirectKind, RenderSettings, Rendered, Visualize,
};
use trilux::geometry::vec3;
use trilux::plan::Plan;
use trilux::sampling::Pattern;
use trilux::scene::Scene;

/// The course program's flags, accepted with one dash and underscores (`-num_bounces 3`) as
/// well as in their `--kebab-case` form.
const COURSE_FLAGS: [&str; 15] = [
    "input",
    "output",
    "size",
    "num_bounces",
    "num_shadow_samples",
    "num_antialias_samples",
    "ambient_light",
    "num_form_factor_samples",
    "sphere_rasterization",
    "cylinder_ring_rasterization",
    "num_photons_to_shoot",
    "num_photons_to_collect",
    "gather_indirect",
    "interpolate",
    "two_sided",
];

/// Rewrites `-num_bounces` and `--num_bounces` to `--num-bounces`; everything else as it is.
fn normalize_args(args: impl Iterator<Item = String>) -> Vec<String> {
    args.map(|a| {
        let name = a.strip_prefix("--").or_else(|| a.strip_prefix('-'));
        match name {
            Some(n) if COURSE_FLAGS.contains(&n) => format!("--{}", n.replace('_', "-")),
            _ => a,
        }
    })
    .collect()
}

#[derive(Parser, Debug)]
#[command(
    name = "render",
    version,
    about = "trilux: ray tracing, radiosity and photon mapping on Embree or a built-in BVH"
)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    render: RenderArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Measures the Accel backends: Mrays/s of closest-hit and occlusion queries.
    BenchAccel(BenchArgs),
    /// Compares an image with a reference: RMSE, relMSE (ε = 1e-2), MAPE, largest error.
    Compare {
        /// The image.
        image: PathBuf,
        /// The reference.
        reference: PathBuf,
        /// Also write a heat map of the per-pixel error.
        #[arg(long)]
        heatmap: Option<PathBuf>,
    },
    /// Each engine's error against run time on a scene, and Embree against the BVH: a CSV, a
    /// log-log plot (PNG) and a markdown summary.
    Report(ReportArgs),
    /// Writes a height-field terrain of at least N triangles as standard OBJ.
    GenTerrain {
        /// Number of triangles (at least).
        triangles: usize,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Writes a room of about N quads (walls and boxes, one light) in the course dialect: a
    /// radiosity scene where visibility matters, for scaling runs.
    GenRoom {
        /// Number of quads (about).
        patches: usize,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Writes a procedural texture as PPM (P6).
    GenTexture {
        #[arg(value_enum)]
        kind: trilux::generate::TextureKind,
        /// Side in pixels.
        #[arg(long, default_value_t = 256)]
        size: u32,
        #[arg(short, long)]
        output: PathBuf,
    },
}

#[derive(Args, Debug)]
struct BenchArgs {
    /// A scene file, or `terrain:N` for a generated terrain of N triangles.
    scene: String,
    /// Rays per ray set.
    #[arg(long, default_value_t = 1_000_000)]
    rays: usize,
    /// Timings per cell; the median is reported.
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Worker threads for the "all threads" rows (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Embree's robust (watertight) mode, as for rendering.
    #[arg(long, default_value_t = true, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    embree_robust: bool,
    /// Backends to measure.
    #[arg(long, value_delimiter = ',', default_values_t = default_bench_accels())]
    accel: Vec<AccelKind>,
    /// Ray sets to measure.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["camera", "incoherent", "shadow"])]
    sets: Vec<trilux::bench::RaySet>,
    /// Queries to measure.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["closest", "occluded"])]
    queries: Vec<trilux::bench::Query>,
    /// Single rays per call, batches, or both.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["single", "batched"])]
    modes: Vec<trilux::bench::Mode>,
}

#[derive(Args, Debug)]
struct ReportArgs {
    /// The scene file.
    scene: PathBuf,
    /// Engines to measure.
    #[arg(long, value_delimiter = ',', default_values_t = [EngineKind::Raytrace, EngineKind::Radiosity, EngineKind::Photon, EngineKind::Path])]
    engines: Vec<EngineKind>,
    /// Accels to run each engine on.
    #[arg(long, value_delimiter = ',', default_values_t = default_bench_accels())]
    accel: Vec<AccelKind>,
    /// Image width and height.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [96, 96])]
    size: Vec<u32>,
    /// Seeds per budget; errors are averaged over them, a budget's time is the fastest seed's.
    #[arg(long, default_value_t = 2)]
    seeds: u32,
    /// Wall-time limit of the whole report in seconds, reference render included.
    #[arg(long, default_value_t = 600.0)]
    time_limit: f64,
    /// Reference image (PFM, EXR or PNG); default: a path-traced render, cached in the
    /// output directory.
    #[arg(long, value_name = "FILE")]
    reference: Option<PathBuf>,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 4096)]
    reference_samples: u32,
    /// Output directory (default: report-<scene name>).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn default_bench_accels() -> Vec<AccelKind> {
    if cfg!(feature = "embree") {
        vec![AccelKind::Embree, AccelKind::Bvh]
    } else {
        vec![AccelKind::Bvh]
    }
}

#[derive(Args, Debug)]
struct RenderArgs {
    /// The scene file (course dialect or standard OBJ).
    #[arg(long, required = true)]
    input: Option<PathBuf>,
    /// Output image: .png (sRGB 8-bit), .exr or .pfm (linear float). Default: <scene stem>.png.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [256, 256])]
    size: Vec<u32>,
    /// Lighting engine (default: radiosity when a radiosity-only flag is given, else
    /// raytrace).
    #[arg(long, value_enum)]
    engine: Option<EngineKind>,
    /// Visibility backend (default: embree when this build has it).
    #[arg(long, value_enum)]
    accel: Option<AccelKind>,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Seed of every random number; the same seed gives the same image at any thread count.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Print the stages and structures this render would build, and exit.
    #[arg(long)]
    plan: bool,
    /// Refuse renders estimated to need more memory than this (e.g. 512M, 8G; default 80% of
    /// physical memory).
    #[arg(long, value_name = "SIZE", value_parser = trilux::plan::parse_bytes)]
    max_memory: Option<u64>,
    /// Print counters (rays cast, build and render time) after rendering.
    #[arg(long)]
    stats: bool,
    /// Make quads opaque from both sides.
    #[arg(long)]
    two_sided: bool,
    /// Embree's build quality.
    #[arg(long, value_enum, default_value_t = EmbreeQuality::Medium)]
    embree_quality: EmbreeQuality,
    /// Embree's robust (watertight) mode: on by default; `--embree-robust false` trades
    /// cracks along quad diagonals and shared edges for a little speed.
    #[arg(long, default_value_t = true, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    embree_robust: bool,
    /// Mirror/refraction recursion depth (ray tracing engine).
    #[arg(long, default_value_t = 0)]
    num_bounces: u32,
    /// Shadow rays per light.
    #[arg(long, default_value_t = 0)]
    num_shadow_samples: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 1)]
    num_antialias_samples: u32,
    /// Ambient radiance R G B.
    #[arg(long, num_args = 3, value_names = ["R", "G", "B"], allow_negative_numbers = true)]
    ambient_light: Option<Vec<f32>>,
    /// Placement of the points on each light for soft shadows.
    #[arg(long, value_enum, default_value_t = Pattern::Jittered)]
    light_sampling: Pattern,
    /// Thin-lens radius for depth of field (0: pinhole).
    #[arg(long, default_value_t = 0.0)]
    aperture: f32,
    /// Distance of the plane in focus (default: the camera's point of interest).
    #[arg(long)]
    focus_distance: Option<f32>,
    /// Trace pixel (X, Y) (column from the left, row from the bottom) and write its rays
    /// beside the image: OUT.raytree.png (eye rays white, reflected/refracted red, shadow
    /// green) and OUT.raytree.obj (the segments as OBJ lines).
    #[arg(long, num_args = 2, value_names = ["X", "Y"])]
    ray_tree: Option<Vec<u32>>,
    /// Point pairs per form factor (radiosity engine).
    #[arg(long)]
    num_form_factor_samples: Option<u32>,
    /// Sphere tessellation H V (radiosity engine).
    #[arg(long, num_args = 2, value_names = ["H", "V"])]
    sphere_rasterization: Option<Vec<u32>>,
    /// Ring tessellation (radiosity engine).
    #[arg(long)]
    cylinder_ring_rasterization: Option<u32>,
    /// Photons to emit (photon engine).
    #[arg(long)]
    num_photons_to_shoot: Option<u64>,
    /// Photons aimed at the mirrors and glass for the caustic map (photon engine; default: as
    /// many as -num_photons_to_shoot; 0: caustics from the main pass only).
    #[arg(long)]
    caustic_photons: Option<u64>,
    /// Photons per density estimate (photon engine).
    #[arg(long)]
    num_photons_to_collect: Option<u32>,
    /// Final gathering for indirect light (photon engine).
    #[arg(long)]
    gather_indirect: bool,
    /// Bounces a photon may make (photon engine).
    #[arg(long, default_value_t = 10)]
    max_photon_depth: u32,
    /// Largest radius of a photon density estimate, as a fraction of the scene's diagonal.
    #[arg(long, default_value_t = 0.1)]
    photon_max_radius: f32,
    /// Hemisphere rays per final gather (-gather_indirect).
    #[arg(long, default_value_t = 128)]
    final_gather_rays: u32,
    /// Ward's irradiance-cache error a: records are used where their weight exceeds 1/a.
    #[arg(long, default_value_t = 0.15)]
    irradiance_cache_error: f32,
    /// Irradiance-cache records are gathered at every n-th pixel in x and y.
    #[arg(long, default_value_t = 4)]
    irradiance_cache_spacing: u32,
    /// Write both photon maps to FILE (versioned, with a fingerprint of scene and settings).
    #[arg(long, value_name = "FILE")]
    save_photons: Option<PathBuf>,
    /// Read the photon maps from FILE instead of tracing them; refused if made for another
    /// scene or other settings.
    #[arg(long, value_name = "FILE")]
    load_photons: Option<PathBuf>,
    /// Smooth radiosity display: bilinear between values averaged at patch corners.
    #[arg(long)]
    interpolate: bool,
    /// Split every quad into four this many times, keeping the parents (radiosity) [default: 0].
    #[arg(long)]
    subdivide: Option<u32>,
    /// Stop when undistributed / emitted power falls to this (radiosity).
    #[arg(long, default_value_t = 1e-3)]
    radiosity_tolerance: f32,
    /// Stop after exactly K shots, e.g. 16 for the course's "after the top 16 patches have
    /// shot" (radiosity).
    #[arg(long, value_name = "K")]
    radiosity_iterations: Option<u64>,
    /// Safety cap: at most this many shots per patch before giving up, reported (radiosity).
    #[arg(long, default_value_t = 1000)]
    radiosity_max_shots_per_patch: u64,
    /// Over-relaxation of each radiosity shot: auto (from how much of each shot comes back),
    /// or a fixed ω in [1, 2), 1 being plain progressive refinement.
    #[arg(long, default_value = "auto")]
    radiosity_relaxation: radiosity::solver::Relaxation,

    /// Memory for cached rows of form factors, MiB (radiosity).
    #[arg(long, default_value_t = 1024)]
    ff_cache_mb: usize,
    /// Split patches whose radiance differs from a neighbour's by more than this, and solve
    /// again (radiosity).
    #[arg(long, value_name = "THRESHOLD")]
    adaptive_subdivide: Option<f32>,
    /// Rounds of adaptive subdivision (radiosity).
    #[arg(long, default_value_t = 3)]
    adaptive_rounds: u32,
    /// What the radiosity engine shows [default: radiance].
    #[arg(long, value_enum)]
    visualize: Option<Visualize>,
    /// Draw patch outlines over the radiosity image.
    #[arg(long)]
    wireframe: bool,
    /// The patch whose form factors `--visualize form-factors` shows (default: the one with
    /// the most undistributed light).
    #[arg(long, value_name = "PATCH")]
    ff_source: Option<u32>,
    /// Write one CSV line per radiosity shot: residual, wall time, rays cast.
    #[arg(long, value_name = "FILE.csv")]
    log_convergence: Option<PathBuf>,
    /// Diffuse indirect light of the ray tracer: the constant -ambient_light, or the
    /// radiosity solution.
    #[arg(long, value_enum, default_value_t = IndirectKind::Ambient)]
    indirect: IndirectKind,
}

impl RenderArgs {
    fn settings(&self) -> RenderSettings {
        let d = RenderSettings::default();
        RenderSettings {
            width: self.size[0],
            height: self.size[1],
            num_bounces: self.num_bounces,
            num_shadow_samples: self.num_shadow_samples,
            num_antialias_samples: self.num_antialias_samples.max(1),
            ambient_light: self
                .ambient_light
                .as_ref()
                .map_or(d.ambient_light, |a| vec3(a[0], a[1], a[2])),
            visualize: self.visualize.unwrap_or_default(),
            radiosity: self.radiosity_settings(),
            indirect: self.indirect,
            photon: self.photon_settings(),
            light_sampling: self.light_sampling,
            aperture: self.aperture,
            focus_distance: self.focus_distance,
            seed: self.seed,
            quiet: self.quiet,
        }
    }

    fn radiosity_settings(&self) -> RadiositySettings {
        let d = RadiositySettings::default();
        RadiositySettings {
            num_form_factor_samples: self
                .num_form_factor_samples
                .unwrap_or(d.num_form_factor_samples),
            sphere_rasterization: self
                .sphere_rasterization
                .as_ref()
                .map_or(d.sphere_rasterization, |s| (s[0], s[1])),
            cylinder_ring_rasterization: self
                .cylinder_ring_rasterization
                .unwrap_or(d.cylinder_ring_rasterization),
            subdivide: self.subdivide.unwrap_or(d.subdivide),
            interpolate: self.interpolate,
            tolerance: self.radiosity_tolerance,
            iterations: self.radiosity_iterations,
            max_shots_per_patch: self.radiosity_max_shots_per_patch,
            relaxation: self.radiosity_relaxation,
            ff_cache_mb: self.ff_cache_mb,
            adaptive_threshold: self.adaptive_subdivide,
            adaptive_rounds: self.adaptive_rounds,
            wireframe: self.wireframe,
            ff_source: self.ff_source,
            log_convergence: self.log_convergence.is_some(),
        }
    }

    fn photon_settings(&self) -> PhotonSettings {
        let d = PhotonSettings::default();
        PhotonSettings {
            num_photons_to_shoot: self.num_photons_to_shoot.unwrap_or(0),
            caustic_photons: self.caustic_photons,
            num_photons_to_collect: self
                .num_photons_to_collect
                .unwrap_or(d.num_photons_to_collect),
            max_photon_depth: self.max_photon_depth,
            max_radius: self.photon_max_radius,
            gather_indirect: self.gather_indirect,
            final_gather_rays: self.final_gather_rays,
            irradiance_cache_error: self.irradiance_cache_error,
            irradiance_cache_spacing: self.irradiance_cache_spacing,
            save: self.save_photons.clone(),
            load: self.load_photons.clone(),
        }
    }

    /// Flags that only the photon engine reads: giving one chooses it.
    fn photon_flags(&self) -> [(&'static str, bool); 6] {
        [
            ("--caustic-photons", self.caustic_photons.is_some()),
            ("--save-photons", self.save_photons.is_some()),
            ("--load-photons", self.load_photons.is_some()),
            ("-num_photons_to_shoot", self.num_photons_to_shoot.is_some()),
            (
                "-num_photons_to_collect",
                self.num_photons_to_collect.is_some(),
            ),
            ("-gather_indirect", self.gather_indirect),
        ]
    }

    /// Flags that only the radiosity engine reads: giving one chooses it.
    fn radiosity_flags(&self) -> [(&'static str, bool); 9] {
        [
            (
                "-num_form_factor_samples",
                self.num_form_factor_samples.is_some(),
            ),
            ("-sphere_rasterization", self.sphere_rasterization.is_some()),
            (
                "-cylinder_ring_rasterization",
                self.cylinder_ring_rasterization.is_some(),
            ),
            ("-interpolate", self.interpolate),
            ("--subdivide", self.subdivide.is_some()),
            (
                "--visualize",
                self.visualize
                    .is_some_and(|v| !matches!(v, Visualize::Photons | Visualize::Kdtree)),
            ),
            ("--wireframe", self.wireframe),
            ("--adaptive-subdivide", self.adaptive_subdivide.is_some()),
            ("--ff-source", self.ff_source.is_some()),
        ]
    }

    /// The engine asked for, or the one the flags given imply.
    fn engine(&self) -> EngineKind {
        match self.engine {
            Some(e) => e,
            None if self.photon_flags().iter().any(|f| f.1)
                || matches!(self.visualize, Some(Visualize::Photons | Visualize::Kdtree)) =>
            {
                EngineKind::Photon
            }
            None if self.indirect == IndirectKind::Ambient
                && self.radiosity_flags().iter().any(|f| f.1) =>
            {
                EngineKind::Radiosity
            }
            None => EngineKind::Raytrace,
        }
    }

    fn accel_options(&self) -> AccelOptions {
        AccelOptions {
            embree_quality: self.embree_quality,
            embree_robust: self.embree_robust,
        }
    }

    /// Flags given that the chosen engine does not read, named so the user knows they had
    /// no effect.
    fn unused_flags(&self) -> Vec<&'static str> {
        let engine = self.engine();
        let ray_tracing = [
            ("-num_bounces", self.num_bounces > 0),
            ("-num_antialias_samples", self.num_antialias_samples > 1),
            ("-ambient_light", self.ambient_light.is_some()),
            ("--aperture", self.aperture > 0.0),
        ];
        let given = |flags: &[(&'static str, bool)]| -> Vec<&'static str> {
            flags.iter().filter(|c| c.1).map(|c| c.0).collect()
        };
        let mut unused = Vec::new();
        if engine != EngineKind::Photon {
            unused.extend(given(&self.photon_flags()));
        }
        let radiosity_read =
            engine == EngineKind::Radiosity || self.indirect == IndirectKind::Radiosity;
        if !radiosity_read {
            unused.extend(given(&self.radiosity_flags()));
        }
        match engine {
            EngineKind::Raycast => {
                unused.extend(given(&ray_tracing));
                if self.num_shadow_samples > 0 {
                    unused.push("-num_shadow_samples");
                }
            }
            // The path tracer follows every bounce and samples the lights itself.
            EngineKind::Path => {
                unused.extend(given(&[ray_tracing[0], ray_tracing[2]]));
                if self.num_shadow_samples > 0 {
                    unused.push("-num_shadow_samples");
                }
            }
            // The radiosity display reads only the antialiasing of the ray tracing flags
            // (-num_shadow_samples turns on visibility in its form factors).
            EngineKind::Radiosity => {
                unused.extend(given(&[ray_tracing[0], ray_tracing[2], ray_tracing[3]]))
            }
            // The photon maps replace the ambient term.
            EngineKind::Photon => unused.extend(given(&[ray_tracing[2]])),
            _ => {}
        }
        unused
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(normalize_args(std::env::args()));
    let result = match &cli.command {
        Some(Command::BenchAccel(args)) => bench_accel(args),
        Some(Command::Report(args)) => report(args),
        Some(Command::Compare {
            image,
            reference,
            heatmap,
        }) => compare(image, reference, heatmap.as_deref()),
        Some(Command::GenTerrain { triangles, output }) => {
            let scene = trilux::generate::terrain(*triangles);
            trilux::generate::write_obj(&scene, output).map_err(|e| e.to_string())
        }
        Some(Command::GenRoom { patches, output }) => {
            let scene = trilux::generate::room(*patches);
            trilux::generate::write_dialect(&scene, output).map_err(|e| e.to_string())
        }
        Some(Command::GenTexture { kind, size, output }) => {
            let rgb = trilux::generate::texture(*kind, *size);
            trilux::generate::write_ppm(&rgb, *size, output).map_err(|e| e.to_string())
        }
        None => render(&cli.render),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

fn render(args: &RenderArgs) -> Result<(), String> {
    let input = args.input.as_ref().ok_or("missing -input")?;
    let settings = args.settings();
    if settings.width == 0 || settings.height == 0 {
        return Err(format!(
            "-size {} {}: both must be at least 1",
            settings.width, settings.height
        ));
    }
    let pool = trilux::parallel::thread_pool(args.threads).map_err(|e| e.to_string())?;
    trilux::parallel::worker_start();

    let load_start = Instant::now();
    let mut scene = Scene::load(input).map_err(|e| e.to_string())?;
    scene.two_sided_quads = args.two_sided;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let load_s = load_start.elapsed().as_secs_f64();
    let kind = args.accel.unwrap_or_else(AccelKind::default_available);
    let options = args.accel_options();
    let engine = args.engine();
    let plan = Plan::new(&scene, engine, kind, &settings);
    if args.plan {
        return emit(&format!("scene: {}\n{plan}", input.display()));
    }
    let max_memory = args
        .max_memory
        .unwrap_or_else(trilux::plan::default_max_memory);
    if plan.memory > max_memory {
        return Err(format!(
            "this render would need about {}, more than --max-memory {}{}; ask for less (-size, -num_photons_to_shoot, --subdivide) or raise --max-memory",
            plan.memory_summary(),
            trilux::plan::human_bytes(max_memory),
            if args.max_memory.is_none() { " (80% of this machine's memory)" } else { "" }
        ));
    }
    trilux::interrupt::install();
    for flag in args.unused_flags() {
        eprintln!(
            "note: {flag} is accepted but has no effect: the {} engine does not read it",
            engine.name()
        );
    }

    let build_start = Instant::now();
    let accel = pool
        .install(|| accel::build(&scene, kind, &options))
        .map_err(|e| e.to_string())?;
    let build_s = build_start.elapsed().as_secs_f64();
    let render_start = Instant::now();
    let accel = accel.as_ref();
    let Rendered {
        film,
        stats,
        solution,
        maps,
    } = pool.install(|| engines::render(engine, &scene, accel, &settings))?;
    if let Some(maps) = &maps {
        report_photons(maps, &settings);
    }
    if let Some(solution) = &solution {
        report_radiosity(solution, &settings);
        if let Some(path) = &args.log_convergence {
            write_convergence_log(path, solution)?;
        }
    }
    let render_s = render_start.elapsed().as_secs_f64();
    let non_finite = stats.non_finite_samples.load(Relaxed);
    if non_finite > 0 {
        eprintln!(
            "warning: {non_finite} samples were NaN or infinite and were left out of the image"
        );
    }

    let output = args.output.clone().unwrap_or_else(|| default_output(input));
    film.write(&output).map_err(|e| e.to_string())?;
    if trilux::interrupt::requested() {
        return Err(format!(
            "interrupted: wrote the image rendered so far to {}",
            output.display()
        ));
    }
    if let Some(xy) = &args.ray_tree {
        write_ray_tree(&scene, accel, &settings, &film, &output, (xy[0], xy[1]))?;
    }
    if args.stats {
        let rays = stats.total_rays();
        eprintln!("stats: scene load {load_s:.3} s, accel build ({kind}) {build_s:.3} s, render {render_s:.3} s");
        eprintln!(
            "stats: rays cast {rays} ({:.2} Mrays/s): camera {}, shadow {}, secondary {}, form factor {}, photon {}",
            rays as f64 / render_s / 1e6,
            stats.camera_rays.load(Relaxed),
            stats.shadow_rays.load(Relaxed),
            stats.secondary_rays.load(Relaxed),
            stats.form_factor_rays.load(Relaxed),
            stats.photon_rays.load(Relaxed)
        );
        eprintln!("stats: non-finite samples {non_finite}");
        if let Some(kib) = peak_memory_kib() {
            eprintln!("stats: peak memory {:.1} MiB", kib as f64 / 1024.0);
        }
    }
    if !args.quiet {
        eprintln!("wrote {}", output.display());
    }
    Ok(())
}

/// One line on the photon maps, and a warning when the depth limit cut photons short.
fn report_photons(maps: &photon::PhotonMaps, settings: &RenderSettings) {
    let emitted = maps.emitted + maps.caustic_emitted;
    if maps.truncated * 1000 > emitted {
        eprintln!(
            "warning: {} of {emitted} photons were still carrying light when --max-photon-depth {} stopped them; their light is missing from the image (raise the depth: Russian roulette alone keeps paths finite)",
            maps.truncated, settings.photon.max_photon_depth
        );
    }
    if !settings.quiet {
        eprintln!(
            "photons: {} emitted, {} more aimed at mirrors and glass, {} photon rays in {:.3} s; global map {} photons, caustic map {} (kd-trees built in {:.3} s); {} per estimate within {:.3}",
            maps.emitted,
            maps.caustic_emitted,
            maps.rays,
            maps.trace_seconds,
            maps.global.len(),
            maps.caustic.len(),
            maps.build_seconds,
            maps.collect,
            maps.max_radius
        );
    }
}

/// One paragraph on how the radiosity solve went; a solve stopped by the safety cap is a
/// warning (its image still holds the ambient estimate of the light not yet shot).
fn report_radiosity(solution: &radiosity::Solution, settings: &RenderSettings) {
    use radiosity::solver::Stop;
    let r = &settings.radiosity;
    let state = &solution.state;
    let stop = match solution.stop {
        Stop::Converged => format!("converged to tolerance {:.1e}", r.tolerance),
        Stop::Iterations => format!("stopped after {} shots as asked", state.shots),
        Stop::NoLight => "nothing emits".to_string(),
        Stop::Interrupted => format!("interrupted after {} shots", state.shots),
        Stop::Cap => String::new(),
    };
    if solution.stop == Stop::Cap {
        eprintln!(
            "warning: radiosity stopped at its cap of {} shots ({} per patch) with residual {:.3e} above the tolerance {:.1e}; the image adds the ambient estimate of the rest (raise --radiosity-max-shots-per-patch to go on)",
            state.shots, r.max_shots_per_patch, state.residual, r.tolerance
        );
    }
    if settings.quiet {
        return;
    }
    let adaptive = if solution.adaptive_rounds > 0 {
        format!(", {} adaptive rounds", solution.adaptive_rounds)
    } else {
        String::new()
    };
    eprintln!(
        "radiosity: {} patches{adaptive}, {} shots, residual {:.3e}{}{stop}; visibility {}; {} visibility rays; form-factor rows {} computed, {} reused (cache peak {:.1} MiB)",
        solution.patches.len(),
        state.shots,
        state.residual,
        if stop.is_empty() { "" } else { ", " },
        solution.visibility_reason,
        solution.rays,
        solution.cache_misses,
        solution.cache_hits,
        solution.cache_peak_bytes as f64 / (1 << 20) as f64
    );
}

/// `--log-convergence`: one CSV line per shot.
fn write_convergence_log(path: &Path, solution: &radiosity::Solution) -> Result<(), String> {
    use std::fmt::Write;
    let mut csv = String::from("shot,patch,residual,seconds,rays\n");
    for r in &solution.state.log {
        let _ = writeln!(
            csv,
            "{},{},{:.6e},{:.6},{}",
            r.shot, r.patch, r.residual, r.seconds, r.rays
        );
    }
    trilux::output::write_text_atomically(path, &csv).map_err(|e| e.to_string())
}

fn default_output(input: &Path) -> PathBuf {
    let stem = input
        .file_stem()
        .map_or("render".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from(format!("{stem}.png"))
}

fn bench_accel(args: &BenchArgs) -> Result<(), String> {
    let scene = match args.scene.strip_prefix("terrain:") {
        Some(n) => trilux::generate::terrain(
            n.parse()
                .map_err(|_| format!("terrain:N needs a number, found {n}"))?,
        ),
        None => Scene::load(Path::new(&args.scene)).map_err(|e| e.to_string())?,
    };
    let pool = trilux::parallel::thread_pool(args.threads).map_err(|e| e.to_string())?;
    trilux::parallel::worker_start();
    let threads = pool.current_num_threads();
    let options = AccelOptions {
        embree_robust: args.embree_robust,
        ..AccelOptions::default()
    };
    let trilux::bench::Report { rows, builds } = pool
        .install(|| {
            trilux::bench::bench_accel(
                &scene,
                &args.accel,
                &options,
                &trilux::bench::Cells {
                    sets: args.sets.clone(),
                    queries: args.queries.clone(),
                    modes: args.modes.clone(),
                },
                args.rays,
                args.repeats,
                threads,
            )
        })
        .map_err(|e| e.to_string())?;
    let mut lines = vec![
        format!(
            "scene: {} ({} primitives), {} rays per set, median of {} runs, embree robust: {}",
            args.scene,
            scene.primitive_count(),
            args.rays,
            args.repeats,
            args.embree_robust
        ),
        String::new(),
        "| backend | build (s) |".into(),
        "|---|---|".into(),
    ];
    lines.extend(
        builds
            .iter()
            .map(|(name, s)| format!("| {name} | {s:.3} |")),
    );
    lines.push(String::new());
    lines.push("| backend | rays | query | mode | threads | Mrays/s |".into());
    lines.push("|---|---|---|---|---|---|".into());
    lines.extend(rows.iter().map(|r| {
        format!(
            "| {} | {} | {} | {} | {} | {:.2} |",
            r.backend, r.rays, r.query, r.mode, r.threads, r.mrays_per_s
        )
    }));
    lines.push(String::new());
    emit(&lines.join("\n"))
}

/// Writes to standard output; a closed pipe (`render --plan | head`) is not an error.
fn emit(text: &str) -> Result<(), String> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(format!("cannot write to standard output: {e}"))
        }
        _ => Ok(()),
    }
}

/// Writes the ray tree of one pixel beside the image (`--ray-tree X Y`).
fn write_ray_tree(
    scene: &Scene,
    accel: &dyn trilux::accel::Accel,
    settings: &RenderSettings,
    film: &trilux::film::Film,
    output: &Path,
    (x, y): (u32, u32),
) -> Result<(), String> {
    if x >= settings.width || y >= settings.height {
        return Err(format!(
            "--ray-tree {x} {y}: the pixel is outside the {}×{} image",
            settings.width, settings.height
        ));
    }
    let segments = raytrace::ray_tree(scene, accel, settings, x, y);
    let stem = output.with_extension("");
    let png = PathBuf::from(format!("{}.raytree.png", stem.display()));
    let obj = PathBuf::from(format!("{}.raytree.obj", stem.display()));
    trilux::film::ray_tree::overlay(film, &scene.camera(), &segments)
        .write(&png)
        .map_err(|e| e.to_string())?;
    trilux::film::ray_tree::write_obj(&segments, &obj).map_err(|e| e.to_string())?;
    if !settings.quiet {
        eprintln!(
            "wrote {} and {} ({} rays)",
            png.display(),
            obj.display(),
            segments.len()
        );
    }
    Ok(())
}

fn report(args: &ReportArgs) -> Result<(), String> {
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let settings = trilux::report::ReportSettings {
        engines: args.engines.clone(),
        accels: args.accel.clone(),
        width: args.size[0],
        height: args.size[1],
        seeds: args.seeds.max(1),
        time_limit: args.time_limit,
        reference: args.reference.clone(),
        reference_samples: args.reference_samples.max(1),
        output: args
            .output
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("report-{stem}"))),
        quiet: args.quiet,
    };
    if settings.width == 0 || settings.height == 0 {
        return Err("--size: both must be at least 1".into());
    }
    let pool = trilux::parallel::thread_pool(args.threads).map_err(|e| e.to_string())?;
    trilux::parallel::worker_start();
    trilux::interrupt::install();
    let report = pool.install(|| trilux::report::run(&args.scene, &settings))?;
    emit(&trilux::report::summary(&report, &settings))?;
    if !args.quiet {
        eprintln!(
            "wrote report.csv, report.png and report.md in {}",
            settings.output.display()
        );
    }
    Ok(())
}

fn compare(image: &Path, reference: &Path, heatmap: Option<&Path>) -> Result<(), String> {
    use trilux::film::metrics;
    let a = metrics::read_image(image)?;
    let b = metrics::read_image(reference)?;
    let m = metrics::compare(&a, &b)?;
    if let Some(path) = heatmap {
        metrics::heatmap(&a, &b)
            .write(path)
            .map_err(|e| e.to_string())?;
    }
    emit(&format!(
        "rmse {:.6e}\nrelmse {:.6e}\nmape {:.6e}\nmax_error {:.6e}\n",
        m.rmse, m.relmse, m.mape, m.max_error
    ))
}

/// The process's peak resident memory (Linux: VmHWM of /proc/self/status), in KiB.
fn peak_memory_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
