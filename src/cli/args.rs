//! The render command's flags: one clap group per engine, each converting itself into that
//! engine's settings. Every default is read from the settings' `Default`, so it is written
//! once; a flag's help says what it does and why its default is the default: `VALUE: why`
//! in the text, before the `[default: VALUE]` clap adds, or `[default: VALUE: why]` written
//! by hand for an `Option` (`tests/cli.rs` checks every flag that shows a default).
//!
//! Adding a flag to an engine: a field in that engine's group here (with its help line) and
//! the field it sets in the engine's settings; nothing else. The group a flag is in decides
//! which engine it implies and when it is reported as having had no effect.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::accel::{AccelKind, AccelOptions, EmbreeQuality};
use crate::engines::photon::{self, PhotonSettings};
use crate::engines::radiosity::{
    self, settings::SolverKind, solver::Relaxation, RadiositySettings,
};
use crate::engines::{EngineKind, IndirectKind, RenderSettings};
use crate::film::part::Window;
use crate::geometry::{vec3, Vec3};
use crate::sampling::{LightSampling, PathSampler};
use crate::scene::{Camera, Projection};

fn rs() -> RenderSettings {
    RenderSettings::default()
}
fn radiosity_defaults() -> RadiositySettings {
    RadiositySettings::default()
}
fn photon_defaults() -> PhotonSettings {
    PhotonSettings::default()
}

/// Everything `render -input SCENE …` reads.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub ray_trace: RayTraceArgs,
    #[command(flatten)]
    pub radiosity: RadiosityArgs,
    #[command(flatten)]
    pub photon: PhotonArgs,
    #[command(flatten)]
    pub sppm: SppmArgs,
    #[command(flatten)]
    pub path: PathArgs,
    #[command(flatten)]
    pub part: PartArgs,
    /// The argument ids given on the command line (filled from clap's value sources after
    /// parsing), by group.
    #[arg(skip)]
    pub given: Vec<(String, String)>,
}

/// Flags every engine reads.
#[derive(Args, Debug)]
#[command(next_help_heading = "Scene, output and run")]
pub struct CommonArgs {
    /// The scene file: course dialect or standard OBJ (`.obj`), MGF (`.mgf`), Mitsuba 3
    /// (`.xml`).
    #[arg(long, required = true)]
    pub input: Option<PathBuf>,
    /// Output image: .png or .jpg (sRGB 8-bit), .exr or .pfm (linear float) [default: the
    /// scene's name with .png (cornell_box.obj: cornell_box.png): the course's command lines
    /// name no output].
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the variance of each pixel's samples, per colour channel, to this .exr or
    /// .pfm: the unbiased estimate (n − 1) from the samples the image averages. It is the
    /// variance of one sample, not of the pixel's mean: divide by the samples per pixel for
    /// that (with stratified samples, such as the path tracer's sobol sampler, that quotient
    /// overstates the mean's variance). Only engines whose pixels are means of samples; a
    /// split render's parts keep what `render merge --variance` needs [default: none: its
    /// sums cost memory only when asked].
    #[arg(long, value_name = "FILE")]
    pub variance: Option<PathBuf>,
    /// Image size in pixels (256 256: the course's size).
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [rs().width, rs().height])]
    pub size: Vec<u32>,
    /// Lighting engine [default: photon when a photon flag is given, radiosity when a
    /// radiosity flag is given, as the course's command lines name no engine; path for a
    /// Mitsuba scene, written for a path tracer; else raytrace].
    #[arg(long, value_enum)]
    pub engine: Option<EngineKind>,
    /// What to show instead of the rendered image: a radiosity mode (implies the radiosity
    /// engine) or photons/kdtree (implies the photon engine) [default: the image, which a
    /// view replaces only when asked].
    #[arg(long, value_enum)]
    pub visualize: Option<Visualize>,
    /// Visibility backend [default: bvh for a scene of at most 1,000 primitives, where it was
    /// as fast as Embree or faster in every engine measured; else embree, whose build and
    /// traversal win on large scenes, when this build has it].
    #[arg(long, value_enum)]
    pub accel: Option<AccelKind>,
    /// Worker threads (0: one per core, so that a render uses the whole machine; at most
    /// 1024).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Seed of every random number; the same seed gives the same image at any thread count
    /// (0: a fixed seed, so that a command line renders the same image every run).
    #[arg(long, default_value_t = rs().seed)]
    pub seed: u64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the stages and structures this render would build, and exit.
    #[arg(long)]
    pub plan: bool,
    /// Refuse renders estimated to need more memory than this (e.g. 512M, 8G) [default: 80%
    /// of physical memory: a render that would not fit is refused before anything is built,
    /// with room left for the rest of the machine].
    #[arg(long, value_name = "SIZE", value_parser = crate::bytes::parse_bytes)]
    pub max_memory: Option<u64>,
    /// Print counters (rays cast, build and render time) after rendering.
    #[arg(long)]
    pub stats: bool,
    /// Render for about this many seconds, from the start (scene loading included): engines
    /// that can refine add pixel samples (passes of -num_antialias_samples), SPPM passes or
    /// radiosity shots until the time is spent, then write the image and say what they
    /// reached. The ray tracer and the engines built on it choose each quality setting not
    /// given (16 shadow rays, passes of 4 camera samples; the photon engine final gathering,
    /// 50,000 photons a second and, in fog, its volume lookups; radiosity interpolated) and
    /// say so.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub time_limit: Option<f64>,
    /// Make quads (and MGF's triangles) opaque from both sides, each side lit on its own.
    #[arg(long)]
    pub two_sided: bool,
    /// A parameter of a Mitsuba scene: what `$NAME` stands for, over the scene's own
    /// `<default>` (Mitsuba's -D); may be given more than once.
    #[arg(long, value_name = "NAME=VALUE", value_parser = parse_define)]
    pub define: Vec<(String, String)>,
    /// Embree's build quality (medium: Embree's own default, a compromise between build and
    /// render time).
    #[arg(long, value_enum, default_value_t = AccelOptions::default().embree_quality)]
    pub embree_quality: EmbreeQuality,
    /// Embree's robust (watertight) mode: on by default; `--embree-robust false` trades
    /// cracks along quad diagonals and shared edges for a little speed.
    #[arg(long, default_value_t = AccelOptions::default().embree_robust, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    pub embree_robust: bool,
    /// Embree's candidate hits decided by trilux's exact routines (the BVH's): on by default,
    /// so that both backends render the same images; `--embree-exact false` lets Embree's own
    /// test decide, which is faster and may differ at shared edges.
    #[arg(long, default_value_t = AccelOptions::default().embree_exact, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    pub embree_exact: bool,
}

/// The path tracer's flags.
#[derive(Args, Debug)]
#[command(next_help_heading = "Path tracer (--engine path)")]
pub struct PathArgs {
    /// Scatterings a path may take, surface bounces of every kind and scatterings in a medium
    /// (pbrt's maxdepth): 0 shows what emits, 1 direct light and single scattering
    /// [default: no limit; Russian roulette ends paths without bias].
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    /// Where a path's numbers come from: sobol stratifies a pixel's paths together (each
    /// light point and bounce direction of the pixel's paths spread over the square),
    /// independent draws every number on its own (Mitsuba 3's default sampler); sobol: on
    /// the Cornell box 0.64× the relMSE of independent numbers at equal paths.
    #[arg(long, value_enum, default_value_t = rs().path_sampler)]
    pub sampler: PathSampler,
}

/// The SPPM engine's flags (its passes are -num_antialias_samples).
#[derive(Args, Debug)]
#[command(next_help_heading = "Stochastic progressive photon mapping (--engine sppm)")]
pub struct SppmArgs {
    /// Photons traced a pass [default: one per pixel of the image, so that a pass's photons
    /// grow with its camera samples].
    #[arg(long, value_name = "N")]
    pub sppm_photons: Option<u64>,
    /// The initial gathering radius, as a fraction of the scene's diagonal (each pixel's
    /// radius then shrinks as photons arrive; 0.01: radii only shrink from it, so it bounds
    /// the blur of the first passes).
    #[arg(long, value_name = "F", default_value_t = photon_defaults().sppm_radius, allow_negative_numbers = true)]
    pub sppm_radius: f32,
}

/// Splitting a render over machines: a part of the image or of its samples, and the
/// pre-pass a farm computes once (read by every engine; `render farm` writes them).
#[derive(Args, Debug)]
#[command(next_help_heading = "Splitting a render (render farms)")]
pub struct PartArgs {
    /// Render only this window of the image, as fractions (x from the left, y from the top,
    /// as pbrt; each edge at ⌈side × fraction⌉). Written to .exr, it is a part for `render
    /// merge`; to another format, the window's pixels alone.
    #[arg(long, num_args = 4, value_names = ["X0", "X1", "Y0", "Y1"], allow_negative_numbers = true)]
    pub crop_window: Option<Vec<f64>>,
    /// Take only samples A ≤ s < B of each pixel's -num_antialias_samples (the same samples
    /// the whole render takes). Written to .exr, it is a part for `render merge`.
    #[arg(long, num_args = 2, value_names = ["A", "B"])]
    pub pixel_samples: Option<Vec<u32>>,
    /// Compute the engine's pre-pass (photon maps, radiosity solution), save it with
    /// --save-photons or --save-radiosity, and render no image.
    #[arg(long)]
    pub pre_pass_only: bool,
}

impl PartArgs {
    /// The window `--crop-window` names, in pixels of a `width` × `height` image.
    pub fn window(&self, width: u32, height: u32) -> Option<Window> {
        self.crop_window
            .as_ref()
            .map(|f| Window::from_fractions([f[0], f[1], f[2], f[3]], width, height))
    }

    fn validate(&self, width: u32, height: u32, spp: u32) -> Result<(), String> {
        if let Some(f) = &self.crop_window {
            if f.iter()
                .any(|v| !(v.is_finite() && (0.0..=1.0).contains(v)))
                || f[0] >= f[1]
                || f[2] >= f[3]
            {
                return Err(format!(
                    "--crop-window {} {} {} {}: expected fractions X0 < X1 and Y0 < Y1 in [0, 1]",
                    f[0], f[1], f[2], f[3]
                ));
            }
            let window = self.window(width, height).unwrap_or(Window::full(0, 0));
            if window.is_empty() {
                return Err(format!(
                    "--crop-window {} {} {} {}: holds no pixel of the {width}×{height} image",
                    f[0], f[1], f[2], f[3]
                ));
            }
        }
        if let Some(s) = &self.pixel_samples {
            if !(s[0] < s[1] && s[1] <= spp) {
                return Err(format!(
                    "--pixel-samples {} {}: expected A < B ≤ -num_antialias_samples ({spp})",
                    s[0], s[1]
                ));
            }
        }
        Ok(())
    }
}

/// What `--visualize` can show: the radiosity engine's modes and the photon engine's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Visualize {
    /// The radiosity solution: radiance of each patch plus the ambient term for light not
    /// yet shot.
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

impl Visualize {
    /// The radiosity engine's mode, if this is one.
    fn radiosity(self) -> Option<radiosity::Display> {
        use radiosity::Display as D;
        Some(match self {
            Visualize::Radiance => D::Radiance,
            Visualize::Materials => D::Materials,
            Visualize::FormFactors => D::FormFactors,
            Visualize::Lights => D::Lights,
            Visualize::Undistributed => D::Undistributed,
            Visualize::Absorbed => D::Absorbed,
            Visualize::Photons | Visualize::Kdtree => return None,
        })
    }

    /// The photon engine's mode, if this is one.
    fn photon(self) -> Option<photon::Display> {
        match self {
            Visualize::Photons => Some(photon::Display::Photons),
            Visualize::Kdtree => Some(photon::Display::Kdtree),
            _ => None,
        }
    }

    /// The engine whose mode this is.
    pub fn engine(self) -> EngineKind {
        if self.photon().is_some() {
            EngineKind::Photon
        } else {
            EngineKind::Radiosity
        }
    }
}

/// The camera's samples and lens: read by every engine that samples pixels.
#[derive(Args, Debug)]
#[command(next_help_heading = "Camera")]
pub struct CameraArgs {
    /// Samples per pixel, at least 1 (1: the course's value).
    #[arg(long, default_value_t = rs().num_antialias_samples)]
    pub num_antialias_samples: u32,
    /// Thin-lens radius for depth of field (0: pinhole, the course's camera).
    #[arg(long, default_value_t = rs().aperture, allow_negative_numbers = true)]
    pub aperture: f32,
    /// Distance of the plane in focus [default: the camera's point of interest, so that what
    /// it looks at is sharp].
    #[arg(long, allow_negative_numbers = true)]
    pub focus_distance: Option<f32>,
    /// Camera position, overriding (or supplying) the scene's camera [default: the scene's, as
    /// its file sets it].
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub camera_position: Option<Vec<f32>>,
    /// The point the camera looks at [default: the scene's point of interest, as its file
    /// sets it].
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub look_at: Option<Vec<f32>>,
    /// The camera's up direction [default: the scene's, as its file sets it].
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub up: Option<Vec<f32>>,
    /// Field of view in degrees across the larger image side (makes the camera perspective)
    /// [default: the scene's, as its file sets it].
    #[arg(long, value_name = "DEGREES", allow_negative_numbers = true)]
    pub fov: Option<f32>,
}

impl CameraArgs {
    /// The scene's camera with the flags given applied to it.
    pub fn apply(&self, camera: Camera) -> Camera {
        let v = |a: &Option<Vec<f32>>, d: Vec3| a.as_ref().map_or(d, |a| vec3(a[0], a[1], a[2]));
        Camera {
            position: v(&self.camera_position, camera.position),
            point_of_interest: v(&self.look_at, camera.point_of_interest),
            up: v(&self.up, camera.up),
            projection: self
                .fov
                .map_or(camera.projection, |deg| Projection::Perspective {
                    angle: deg.to_radians(),
                }),
        }
    }

    /// Whether any camera flag was given (then the scene's camera is replaced).
    pub fn overrides(&self) -> bool {
        self.camera_position.is_some()
            || self.look_at.is_some()
            || self.up.is_some()
            || self.fov.is_some()
    }

    /// Camera flags that cannot make a camera: non-finite numbers, a field of view outside
    /// (0°, 180°), an up direction along the line of sight or of zero length.
    fn validate(&self, camera: &Camera) -> Result<(), String> {
        for (id, a) in [
            ("camera_position", &self.camera_position),
            ("look_at", &self.look_at),
            ("up", &self.up),
        ] {
            if let Some(a) = a {
                if a.iter().any(|v| !v.is_finite()) {
                    return Err(format!(
                        "{} {} {} {}: expected three finite numbers",
                        super::flag_name(id),
                        a[0],
                        a[1],
                        a[2]
                    ));
                }
            }
        }
        if let Some(f) = self.fov {
            if !(f > 0.0 && f < 180.0) {
                return Err(format!("--fov {f}: expected degrees in (0, 180)"));
            }
        }
        let c = self.apply(*camera);
        let forward = c.point_of_interest - c.position;
        if forward.length() == 0.0 {
            return Err(
                "--camera-position and --look-at: the camera looks at the point it stands on"
                    .into(),
            );
        }
        if forward.normalize_or_zero().cross(c.up).length() < 1e-6 {
            return Err(format!(
                "--up {} {} {}: expected a direction not along the line of sight",
                c.up.x, c.up.y, c.up.z
            ));
        }
        Ok(())
    }
}

/// The ray tracer's flags (the photon engine and the radiosity display read some of them).
#[derive(Args, Debug)]
#[command(next_help_heading = "Ray tracing")]
pub struct RayTraceArgs {
    /// Mirror/refraction recursion depth [default: 0, the course's value; the photon engine
    /// and MGF scenes 5, pbrt's, so that mirrors, glossy floors and glass reflect].
    #[arg(long)]
    pub num_bounces: Option<u32>,
    /// Shadow rays per light (radiosity: visibility in form factors when > 0) [default: 0,
    /// the light's centre with no shadow ray, the course's value; the photon engine 8, soft
    /// shadows for no measurable time beside its photons; radiosity and MGF scenes 1, so that
    /// they have shadows and radiosity visibility, as in RenderPark; Mitsuba scenes and the
    /// ray tracer with `--indirect radiosity` 16, soft shadows at the lowest time × error
    /// measured].
    #[arg(long)]
    pub num_shadow_samples: Option<u32>,
    /// Ambient radiance R G B [default: 0.1 0.1 0.1, the course's value; 0 0 0 for a Mitsuba
    /// scene, which has no such term: its lights are all its light].
    #[arg(long, num_args = 3, value_names = ["R", "G", "B"], allow_negative_numbers = true)]
    pub ambient_light: Option<Vec<f32>>,
    /// Placement of the points on each light for soft shadows: uniform in the solid angle a
    /// rectangular light subtends, or by area (random, stratified or jittered, as in the
    /// course) [default: solid-angle in the ray tracer, whose strata of N shadow rays then
    /// resolve a large light's edges; random in the path tracer, where a point by area costs
    /// half the time and the error per time was lower on every course scene].
    #[arg(long, value_enum)]
    pub light_sampling: Option<LightSampling>,
    /// With --light-sampling adaptive: how many times a light may be split in four where
    /// its corners disagree (2: up to 5×5 points; each level more can quadruple the shadow
    /// rays).
    #[arg(long, value_name = "N", default_value_t = rs().adaptive_depth,
          value_parser = clap::value_parser!(u32).range(0..=crate::render::adaptive::MAX_DEPTH as i64))]
    pub adaptive_depth: u32,
    /// Diffuse indirect light: the constant -ambient_light, or the radiosity solution
    /// (ambient: the course program's, and no solve to wait for).
    #[arg(long, value_enum, default_value_t = rs().indirect)]
    pub indirect: IndirectKind,
    /// Trace pixel (X, Y) (column from the left, row from the bottom) and write its rays
    /// beside the image: OUT.raytree.png (eye rays white, reflected/refracted red, shadow
    /// green) and OUT.raytree.obj (the segments as OBJ lines).
    #[arg(long, num_args = 2, value_names = ["X", "Y"])]
    pub ray_tree: Option<Vec<u32>>,
}

/// The radiosity engine's flags (also read by the ray tracer with `--indirect radiosity`).
#[derive(Args, Debug)]
#[command(next_help_heading = "Radiosity")]
pub struct RadiosityArgs {
    /// Point pairs per form factor (1: the patch centres, the course's value).
    #[arg(long, default_value_t = radiosity_defaults().num_form_factor_samples)]
    pub num_form_factor_samples: u32,
    /// Sphere tessellation H V (8 6: the course's value).
    #[arg(long, num_args = 2, value_names = ["H", "V"], default_values_t = [radiosity_defaults().sphere_rasterization.0, radiosity_defaults().sphere_rasterization.1])]
    pub sphere_rasterization: Vec<u32>,
    /// Ring tessellation around the axis (20: the course's value).
    #[arg(long, default_value_t = radiosity_defaults().cylinder_ring_rasterization)]
    pub cylinder_ring_rasterization: u32,
    /// Smooth display: bilinear between values averaged at patch corners.
    #[arg(long)]
    pub interpolate: bool,
    /// Split every quad into four this many times, keeping the parents (0: the scene's own
    /// quads, as the course's command lines solve them).
    #[arg(long, default_value_t = radiosity_defaults().subdivide)]
    pub subdivide: u32,
    /// Stop when undistributed / emitted power falls to this (0.001: a thousandth of the
    /// emitted power left unshot, which the display adds back as an ambient term).
    #[arg(long, default_value_t = radiosity_defaults().tolerance, allow_negative_numbers = true)]
    pub radiosity_tolerance: f32,
    /// Stop after exactly K shots, e.g. 16 for the course's "after the top 16 patches have
    /// shot".
    #[arg(long, value_name = "K")]
    pub radiosity_iterations: Option<u64>,
    /// Safety cap: at most this many shots per patch before giving up, reported (1000: the
    /// stiffest case measured, a furnace of albedo 0.999, needed 170 a patch).
    #[arg(long, default_value_t = radiosity_defaults().max_shots_per_patch)]
    pub radiosity_max_shots_per_patch: u64,
    /// Over-relaxation of each shot: auto (from how much of each shot comes back), or a
    /// fixed ω in [1, 2), 1 being plain progressive refinement (auto: fewer shots on every
    /// scene tried, for the same images).
    #[arg(long, default_value_t = radiosity_defaults().relaxation)]
    pub radiosity_relaxation: Relaxation,
    /// The solver: progressive refinement (shooting), hierarchical radiosity with
    /// clustering (links between clusters and element quadtrees, refined by the power they
    /// carry), or auto: hierarchical above 5,000 input patches, progressive up to it, so that
    /// the course's scenes keep their images and buildings get the solver whose cost grows
    /// about linearly; MGF and Mitsuba scenes hierarchical at any size, which splits their
    /// large faces where the light changes.
    #[arg(long, default_value_t = radiosity_defaults().solver)]
    pub radiosity_solver: SolverKind,
    /// Hierarchical: refine a link carrying more than this fraction of the largest emitted
    /// power (0.0001: smaller refines more links, for more time and memory).
    #[arg(long, default_value_t = radiosity_defaults().link_error, allow_negative_numbers = true)]
    pub link_error: f32,
    /// Hierarchical: do not split elements smaller than this fraction of the scene's area
    /// (0.00001: a floor, so that refinement ends however much power a link carries).
    #[arg(long, default_value_t = radiosity_defaults().min_element_area, allow_negative_numbers = true)]
    pub min_element_area: f32,
    /// Hierarchical: with more input patches than this, start linking from the root
    /// cluster; up to it, from every pair of patches (2000: the pairs need no cluster
    /// estimate, but their number grows as the square of the patches).
    #[arg(long, value_name = "PATCHES", default_value_t = radiosity_defaults().cluster_above)]
    pub cluster_above: usize,
    /// Memory for cached rows of form factors, MiB (1024: a bound on the cache's memory;
    /// rows that do not fit are computed again when their patch shoots).
    #[arg(long, default_value_t = radiosity_defaults().ff_cache_mb)]
    pub ff_cache_mb: usize,
    /// Split patches whose radiance differs from a neighbour's by more than this, and solve
    /// again.
    #[arg(long, value_name = "THRESHOLD", allow_negative_numbers = true)]
    pub adaptive_subdivide: Option<f32>,
    /// Rounds of adaptive subdivision (3: each round splits and solves again, so the rounds
    /// bound the time).
    #[arg(long, default_value_t = radiosity_defaults().adaptive_rounds)]
    pub adaptive_rounds: u32,
    /// Draw patch outlines over the radiosity image.
    #[arg(long)]
    pub wireframe: bool,
    /// The patch whose form factors `--visualize form-factors` shows [default: the one with
    /// the most undistributed light, which shoots next].
    #[arg(long, value_name = "PATCH")]
    pub ff_source: Option<u32>,
    /// Write one CSV line per radiosity shot: residual, wall time, rays cast.
    #[arg(long, value_name = "FILE.csv")]
    pub log_convergence: Option<PathBuf>,
    /// Write the solved patches as a binary PLY mesh, their radiosity (linear radiance) as
    /// vertex colours.
    #[arg(long, value_name = "FILE.ply")]
    pub export_radiosity: Option<PathBuf>,
    /// Write the solution to FILE (versioned, with a fingerprint of scene and settings), so
    /// that other renders can load it.
    #[arg(long, value_name = "FILE")]
    pub save_radiosity: Option<PathBuf>,
    /// Read the solution from FILE instead of solving; refused if made for another scene or
    /// other settings.
    #[arg(long, value_name = "FILE")]
    pub load_radiosity: Option<PathBuf>,
}

/// The photon engine's flags. Each help line gives the default and why it is the default.
#[derive(Args, Debug)]
#[command(next_help_heading = "Photon mapping")]
pub struct PhotonArgs {
    /// Photons to emit; 0: no photon map [default: 4 a pixel of the image, 100,000 to
    /// 1,000,000: past 100,000 the estimates' blur, not the count, limits a small image].
    #[arg(long, value_name = "N")]
    pub num_photons_to_shoot: Option<u64>,
    /// Photons aimed at the mirrors and glass for the caustic map; 0: caustics from the main
    /// pass only [default: as many as -num_photons_to_shoot: the few photons of the main pass
    /// that reach a mirror make a blotchy caustic].
    #[arg(long, value_name = "N")]
    pub caustic_photons: Option<u64>,
    /// Photons per density estimate (100: fewer is noisier, more blurs light across
    /// edges).
    #[arg(long, default_value_t = photon_defaults().num_photons_to_collect)]
    pub num_photons_to_collect: u32,
    /// Final gathering for indirect light; `=false` to keep it off under --time-limit
    /// [default: off (on under --time-limit): the map's own estimate costs no rays, and the
    /// course's images use it].
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true,
          default_missing_value = "true")]
    pub gather_indirect: Option<bool>,
    /// Bounces a photon may make: a safety cap (10000: Russian roulette ends photon paths
    /// long before it, so that it cuts no light).
    #[arg(long, default_value_t = photon_defaults().max_photon_depth)]
    pub max_photon_depth: u32,
    /// Largest radius of a photon density estimate, as a fraction of the scene's diagonal
    /// (0.1: where photons are sparse, an estimate from afar beats none).
    #[arg(long, default_value_t = photon_defaults().max_radius, allow_negative_numbers = true)]
    pub photon_max_radius: f32,
    /// Points per camera or mirror ray in the fog at which the volume photon map is looked
    /// up (jittered, evenly spaced over the part of the ray among the volume photons; 16:
    /// more points are less noise in the fog and more time a ray; under --time-limit, as many
    /// as let the first pass's lookups take a quarter of the limit, 1 to 16).
    #[arg(long, default_value_t = photon_defaults().volume_steps)]
    pub volume_steps: u32,
    /// Hemisphere rays per final gather (-gather_indirect; 128: more rays are less noise in
    /// each cache record and more time a record).
    #[arg(long, default_value_t = photon_defaults().final_gather_rays)]
    pub final_gather_rays: u32,
    /// Ward's irradiance-cache error a: records are used where their weight exceeds 1/a
    /// (0.15: smaller makes more records, less interpolation error and more time).
    #[arg(long, default_value_t = photon_defaults().irradiance_cache_error, allow_negative_numbers = true)]
    pub irradiance_cache_error: f32,
    /// The irradiance cache's first pass visits every n-th pixel centre in x and y (its finest
    /// level): a record is gathered where a visited point is not covered (1: every pixel's
    /// point is visited, so no small feature is missed).
    #[arg(long, default_value_t = photon_defaults().irradiance_cache_spacing)]
    pub irradiance_cache_spacing: u32,
    /// Write both photon maps to FILE (versioned, with a fingerprint of scene and settings)
    /// [default: not written: costs nothing unless asked].
    #[arg(long, value_name = "FILE")]
    pub save_photons: Option<PathBuf>,
    /// Read the photon maps from FILE instead of tracing them; refused if made for another
    /// scene or other settings [default: traced, which needs no file].
    #[arg(long, value_name = "FILE")]
    pub load_photons: Option<PathBuf>,
}

impl RadiosityArgs {
    fn settings(&self, visualize: Option<Visualize>) -> RadiositySettings {
        RadiositySettings {
            num_form_factor_samples: self.num_form_factor_samples,
            sphere_rasterization: (self.sphere_rasterization[0], self.sphere_rasterization[1]),
            cylinder_ring_rasterization: self.cylinder_ring_rasterization,
            subdivide: self.subdivide,
            // Set by `choose_for_time_limit`.
            subdivide_to_fit: None,
            interpolate: self.interpolate,
            tolerance: self.radiosity_tolerance,
            solver: self.radiosity_solver,
            link_error: self.link_error,
            min_element_area: self.min_element_area,
            cluster_above: self.cluster_above,
            // Set by the render from --max-memory and the plan.
            memory_budget: radiosity_defaults().memory_budget,
            iterations: self.radiosity_iterations,
            max_shots_per_patch: self.radiosity_max_shots_per_patch,
            relaxation: self.radiosity_relaxation,
            ff_cache_mb: self.ff_cache_mb,
            adaptive_threshold: self.adaptive_subdivide,
            adaptive_rounds: self.adaptive_rounds,
            wireframe: self.wireframe,
            ff_source: self.ff_source,
            log_convergence: self.log_convergence.is_some(),
            display: visualize.and_then(Visualize::radiosity).unwrap_or_default(),
            export: self.export_radiosity.clone(),
            save: self.save_radiosity.clone(),
            load: self.load_radiosity.clone(),
        }
    }
}

impl PhotonArgs {
    fn settings(&self, visualize: Option<Visualize>) -> PhotonSettings {
        PhotonSettings {
            num_photons_to_shoot: self.num_photons_to_shoot,
            caustic_photons: self.caustic_photons,
            num_photons_to_collect: self.num_photons_to_collect,
            max_photon_depth: self.max_photon_depth,
            max_radius: self.photon_max_radius,
            gather_indirect: self
                .gather_indirect
                .unwrap_or(photon_defaults().gather_indirect),
            volume_steps: self.volume_steps,
            final_gather_rays: self.final_gather_rays,
            irradiance_cache_error: self.irradiance_cache_error,
            irradiance_cache_spacing: self.irradiance_cache_spacing,
            save: self.save_photons.clone(),
            load: self.load_photons.clone(),
            display: visualize.and_then(Visualize::photon).unwrap_or_default(),
            // Set from the SPPM group by `RenderArgs::settings`.
            sppm_photons: photon_defaults().sppm_photons,
            sppm_radius: photon_defaults().sppm_radius,
        }
    }
}

/// The clap group of each engine's own flags, and the engine it implies.
pub const ENGINE_GROUPS: [(&str, EngineKind); 4] = [
    ("PhotonArgs", EngineKind::Photon),
    ("RadiosityArgs", EngineKind::Radiosity),
    ("SppmArgs", EngineKind::Sppm),
    ("PathArgs", EngineKind::Path),
];

impl RenderArgs {
    /// Everything the engines read.
    pub fn settings(&self) -> RenderSettings {
        let visualize = self.common.visualize;
        RenderSettings {
            width: self.common.size[0],
            height: self.common.size[1],
            // The engine's own where not given: `render::engine_defaults`, once the scene's
            // hints are known.
            num_bounces: self.ray_trace.num_bounces.unwrap_or(rs().num_bounces),
            num_shadow_samples: self
                .ray_trace
                .num_shadow_samples
                .unwrap_or(rs().num_shadow_samples),
            num_antialias_samples: self.camera.num_antialias_samples,
            max_depth: self.path.max_depth,
            path_sampler: self.path.sampler,
            ambient_light: self
                .ray_trace
                .ambient_light
                .as_ref()
                .map_or(rs().ambient_light, |a| vec3(a[0], a[1], a[2])),
            radiosity: self.radiosity.settings(visualize),
            indirect: self.ray_trace.indirect,
            photon: PhotonSettings {
                sppm_photons: self.sppm.sppm_photons,
                sppm_radius: self.sppm.sppm_radius,
                ..self.photon.settings(visualize)
            },
            light_sampling: self.ray_trace.light_sampling,
            adaptive_depth: self.ray_trace.adaptive_depth,
            aperture: self.camera.aperture,
            focus_distance: self.camera.focus_distance,
            seed: self.common.seed,
            quiet: self.common.quiet,
            window: self.part.window(self.common.size[0], self.common.size[1]),
            pixel_samples: self.part.pixel_samples.as_ref().map(|s| (s[0], s[1])),
            // Set by the render command when it starts the clock (`--time-limit`).
            deadline: None,
            variance: self.common.variance.is_some(),
        }
    }

    /// With `--time-limit`, the settings the engine chooses where their flags were not given:
    /// the course's defaults (one shadow ray to the light's centre, one camera sample, no
    /// final gathering) suit its command lines, not "the best image in T seconds". Measured
    /// on the Cornell box with the diffuse sphere against Mitsuba 3's reference (BENCHMARKS.md,
    /// "Error against time, against Mitsuba 3"):
    /// - the ray tracer and the engines built on it (photon, ray tracer + radiosity): 16
    ///   shadow rays a light (soft shadows by solid angle; relMSE of direct light 1.2e-4 at
    ///   256×256 in 0.4 s) and passes of 4 camera samples;
    /// - the photon engine, each unless given: final gathering, and 50,000 photons per second
    ///   of the limit (at least 20,000, at most 2,000,000; 50,000 in 1.09 s gave relMSE
    ///   9.2e-4); in fog also `--volume-steps`, once the scene is read
    ///   (`choose_volume_steps`);
    /// - radiosity: interpolated display.
    ///
    /// The path tracer and SPPM choose nothing: they add passes until the time is spent.
    /// Returns the flags chosen, as a user would type them, to be reported.
    pub fn choose_for_time_limit(&self, settings: &mut RenderSettings) -> Vec<String> {
        let Some(seconds) = self.common.time_limit else {
            return Vec::new();
        };
        let given = |id: &str| self.flag_given(id);
        let engine = self.engine();
        let mut chosen = Vec::new();
        let traces = matches!(
            engine,
            EngineKind::Raytrace | EngineKind::Photon | EngineKind::Radiosity
        );
        if traces && !given("num_shadow_samples") {
            settings.num_shadow_samples = TIME_LIMITED_SHADOW_SAMPLES;
            chosen.push(format!("-num_shadow_samples {TIME_LIMITED_SHADOW_SAMPLES}"));
        }
        if traces && !given("num_antialias_samples") {
            settings.num_antialias_samples = TIME_LIMITED_PASS_SAMPLES;
            chosen.push(format!(
                "-num_antialias_samples {TIME_LIMITED_PASS_SAMPLES}"
            ));
        }
        // The photon engine's own settings, each unless given: final gathering (off with
        // `-gather_indirect=false`) and a photon count from the time.
        if engine == EngineKind::Photon && settings.photon.display == Default::default() {
            if !given("gather_indirect") {
                settings.photon.gather_indirect = true;
                chosen.push("-gather_indirect".to_string());
            }
            if !given("num_photons_to_shoot") && settings.photon.load.is_none() {
                let photons = (TIME_LIMITED_PHOTONS_PER_SECOND * seconds)
                    .clamp(TIME_LIMITED_PHOTONS.0, TIME_LIMITED_PHOTONS.1)
                    as u64;
                settings.photon.num_photons_to_shoot = Some(photons);
                chosen.push(format!("-num_photons_to_shoot {photons}"));
            }
        }
        let radiosity =
            engine == EngineKind::Radiosity || settings.indirect == IndirectKind::Radiosity;
        if radiosity && !given("interpolate") {
            settings.radiosity.interpolate = true;
            chosen.push("-interpolate".to_string());
        }
        // The mesh level needs the scene: the solve chooses it (`subdivide_to_fit`).
        if radiosity && !given("subdivide") && !given("adaptive_subdivide") {
            settings.radiosity.subdivide_to_fit = Some(if engine == EngineKind::Radiosity {
                TIME_LIMITED_SOLVE_SHARE
            } else {
                TIME_LIMITED_SOLVE_SHARE_UNDER_RAYS
            });
            chosen.push("--subdivide as far as the time allows".to_string());
        }
        chosen
    }

    /// With `--time-limit` on the photon engine, `--volume-steps` unless given, once the scene
    /// is read: where it has fog, `volume_steps_for_time` of the limit, the image and
    /// `threads`. Returns the flag chosen, to be reported.
    pub fn choose_volume_steps(
        &self,
        scene: &crate::scene::Scene,
        threads: usize,
        settings: &mut RenderSettings,
    ) -> Option<String> {
        let seconds = self.common.time_limit?;
        if self.engine() != EngineKind::Photon
            || self.flag_given("volume_steps")
            || scene.fog.is_none()
            || settings.photon.display != Default::default()
        {
            return None;
        }
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        let steps = photon::settings::volume_steps_for_time(
            seconds,
            threads,
            pixels,
            settings.photon.num_photons_to_collect,
        );
        settings.photon.volume_steps = steps;
        Some(format!("--volume-steps {steps}"))
    }

    /// The backend for `scene`: `--accel`, else `AccelKind::default_for` the scene and
    /// whether its rays are radiosity's.
    pub fn accel_kind(&self, scene: &crate::scene::Scene) -> AccelKind {
        let radiosity = self.engine() == EngineKind::Radiosity;
        self.common
            .accel
            .unwrap_or_else(|| AccelKind::default_for(scene, radiosity))
    }

    pub fn accel_options(&self) -> AccelOptions {
        AccelOptions {
            embree_quality: self.common.embree_quality,
            embree_robust: self.common.embree_robust,
            embree_exact: self.common.embree_exact,
        }
    }

    /// Whether the flag of id `id` (as clap names it) was given on the command line.
    pub fn flag_given(&self, id: &str) -> bool {
        self.given.iter().any(|(_, g)| g == id)
    }

    /// Whether a flag of this clap group was given on the command line.
    fn group_given(&self, group: &str) -> bool {
        self.given.iter().any(|(g, _)| g == group)
    }

    /// Whether `engine` reads the flags of clap group `group`: an engine's own group is read
    /// by that engine, and the radiosity group also by the ray tracer with `--indirect
    /// radiosity`; the shared groups by every engine.
    fn reads_group(&self, engine: EngineKind, group: &str) -> bool {
        match ENGINE_GROUPS.iter().find(|(g, _)| *g == group) {
            None => true,
            Some(&(_, owner)) => {
                owner == engine
                    || (owner == EngineKind::Radiosity
                        && engine == EngineKind::Raytrace
                        && self.ray_trace.indirect == IndirectKind::Radiosity)
            }
        }
    }

    /// The engine asked for, or the one the flags given imply: a flag or `--visualize` mode
    /// of an engine's own group means that engine, unless the ray tracer reads that group
    /// too (`--indirect radiosity`).
    pub fn engine(&self) -> EngineKind {
        if let Some(e) = self.common.engine {
            return e;
        }
        let visualize = self.common.visualize.map(Visualize::engine);
        for (group, owner) in ENGINE_GROUPS {
            let implied = self.group_given(group) || visualize == Some(owner);
            if implied && !self.reads_group(EngineKind::Raytrace, group) {
                return owner;
            }
        }
        // A Mitsuba scene is written for a path tracer: its integrator is one.
        let mitsuba = self
            .common
            .input
            .as_ref()
            .and_then(|p| p.extension())
            .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
        if mitsuba {
            EngineKind::Path
        } else {
            EngineKind::Raytrace
        }
    }

    /// Flags given that the chosen engine does not read, as the user would type them.
    pub fn unused_flags(&self) -> Vec<String> {
        let engine = self.engine();
        self.given
            .iter()
            .filter(|(group, id)| !self.reads(engine, group, id))
            .map(|(_, id)| super::flag_name(id))
            .collect()
    }

    /// Whether `engine` reads the render flag of id `id` (as clap names it).
    pub fn reads_flag(&self, engine: EngineKind, id: &str) -> bool {
        super::flag_group(id).is_none_or(|group| self.reads(engine, &group, id))
    }

    /// Whether `engine` reads the flag `id` of clap group `group`: its group's, unless the
    /// engine leaves it unread.
    fn reads(&self, engine: EngineKind, group: &str, id: &str) -> bool {
        self.reads_group(engine, group)
            && !crate::engines::engine(engine).unread_flags().contains(&id)
    }
}

/// `RenderArgs::choose_for_time_limit`'s choices.
const TIME_LIMITED_SHADOW_SAMPLES: u32 = 16;
const TIME_LIMITED_PASS_SAMPLES: u32 = 4;
const TIME_LIMITED_PHOTONS_PER_SECOND: f64 = 50_000.0;
const TIME_LIMITED_PHOTONS: (f64, f64) = (20_000.0, 2_000_000.0);
/// The share of the time left that the radiosity mesh's solve may take (`subdivide_to_fit`):
/// most of it for the radiosity engine, whose pixels only look the solution up; half with
/// `--indirect radiosity`, whose ray-traced direct light needs the rest. Measured on the
/// Cornell box (BENCHMARKS.md, "The radiosity mesh under `--time-limit`"): these choose the
/// level of lower error at 1 s and at 2 s for both.
const TIME_LIMITED_SOLVE_SHARE: f64 = 0.8;
const TIME_LIMITED_SOLVE_SHARE_UNDER_RAYS: f64 = 0.5;

/// The most worker threads `--threads` accepts: far above any machine's cores, far below
/// what would exhaust the process's threads.
pub const MAX_THREADS: usize = 1024;
pub use crate::scene::MAX_IMAGE_SIDE;

/// `--define NAME=VALUE`.
fn parse_define(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((name, value))
            if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') =>
        {
            Ok((name.to_string(), value.to_string()))
        }
        _ => Err(format!(
            "\"{text}\": expected NAME=VALUE, NAME of letters, digits and _"
        )),
    }
}

/// `value` must be finite and at least `min` (`open`: greater than `min`).
/// The longest `--time-limit`, in seconds: a deadline beyond it does not fit the clock's
/// `Instant` on every platform (1e30 panicked making the `Duration`).
pub const MAX_TIME_LIMIT: f64 = 1e9;

fn check_number(id: &str, value: f32, min: f32, open: bool) -> Result<(), String> {
    let ok = value.is_finite() && if open { value > min } else { value >= min };
    if ok {
        return Ok(());
    }
    let bound = if open { ">" } else { "≥" };
    Err(format!(
        "{} {value}: expected a finite number {bound} {min}",
        super::flag_name(id)
    ))
}

/// A file the render writes besides the image: its extension, and that its folder exists.
fn check_text_output(id: &str, path: &std::path::Path, extension: &str) -> Result<(), String> {
    let flag = super::flag_name(id);
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(extension))
    {
        return Err(format!(
            "{flag} {}: expected a .{extension} file",
            path.display()
        ));
    }
    crate::output::check_folder(path).map_err(|e| format!("{flag}: {e}"))
}

/// A variance image's file: a linear float format (.exr or .pfm), in a folder that exists.
pub fn check_variance_output(path: &std::path::Path) -> Result<(), String> {
    use crate::film::ImageFormat;
    match ImageFormat::check_output(path).map_err(|e| e.to_string())? {
        ImageFormat::Exr | ImageFormat::Pfm => Ok(()),
        _ => Err(format!(
            "{}: expected .exr or .pfm (a variance is a linear float, not an 8-bit sRGB image)",
            path.display()
        )),
    }
}

/// `value` must lie in `range`.
fn check_count<T>(id: &str, value: T, range: std::ops::RangeInclusive<T>) -> Result<(), String>
where
    T: PartialOrd + std::fmt::Display,
{
    if range.contains(&value) {
        return Ok(());
    }
    Err(format!(
        "{} {value}: expected a whole number from {} to {}",
        super::flag_name(id),
        range.start(),
        range.end()
    ))
}

impl RenderArgs {
    /// The camera of the render: the scene's (or its default), with the camera flags applied,
    /// checked.
    pub fn camera(&self, scene_camera: Camera) -> Result<Camera, String> {
        self.camera.validate(&scene_camera)?;
        Ok(self.camera.apply(scene_camera))
    }

    /// Rejects values no engine can use, naming the flag and the allowed range: before the
    /// scene is read, so that nothing is built for a render that cannot run.
    pub fn validate(&self) -> Result<(), String> {
        let c = &self.common;
        for side in &c.size {
            check_count("size", *side, 1..=MAX_IMAGE_SIDE)?;
        }
        check_count("threads", c.threads, 0..=MAX_THREADS)?;
        if let Some(t) = c.time_limit {
            if !(t.is_finite() && t > 0.0 && t <= MAX_TIME_LIMIT) {
                return Err(format!(
                    "--time-limit {t}: expected a number of seconds > 0 and at most {MAX_TIME_LIMIT:e} (about 31 years)"
                ));
            }
            let part = self.part.crop_window.is_some() || self.part.pixel_samples.is_some();
            if part || self.part.pre_pass_only {
                return Err("--time-limit: not with --crop-window, --pixel-samples or --pre-pass-only (the parts of a split render must take known samples)".into());
            }
        }
        check_count(
            "num_antialias_samples",
            self.camera.num_antialias_samples,
            1..=u32::MAX,
        )?;
        check_number("aperture", self.camera.aperture, 0.0, false)?;
        if let Some(d) = self.camera.focus_distance {
            check_number("focus_distance", d, 0.0, true)?;
        }
        if let Some(a) = &self.ray_trace.ambient_light {
            if let Some(bad) = a.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(format!(
                    "{} {} {} {}: expected three finite numbers ≥ 0 ({bad} is not)",
                    super::flag_name("ambient_light"),
                    a[0],
                    a[1],
                    a[2]
                ));
            }
        }
        let r = &self.radiosity;
        check_count(
            "num_form_factor_samples",
            r.num_form_factor_samples,
            1..=u32::MAX,
        )?;
        check_number("radiosity_tolerance", r.radiosity_tolerance, 0.0, true)?;
        check_number("link_error", r.link_error, 0.0, true)?;
        check_number("min_element_area", r.min_element_area, 0.0, false)?;
        if let Some(t) = r.adaptive_subdivide {
            check_number("adaptive_subdivide", t, 0.0, true)?;
        }
        let p = &self.photon;
        check_count(
            "num_photons_to_collect",
            p.num_photons_to_collect,
            1..=u32::MAX,
        )?;
        check_number("photon_max_radius", p.photon_max_radius, 0.0, true)?;
        check_number(
            "irradiance_cache_error",
            p.irradiance_cache_error,
            0.0,
            true,
        )?;
        check_count(
            "irradiance_cache_spacing",
            p.irradiance_cache_spacing,
            1..=u32::MAX,
        )?;
        check_count("final_gather_rays", p.final_gather_rays, 1..=u32::MAX)?;
        check_count(
            "volume_steps",
            p.volume_steps,
            1..=photon::settings::MAX_VOLUME_STEPS,
        )?;
        let sampling = self.ray_trace.light_sampling;
        if let Some(sampling) = sampling.filter(|s| {
            self.engine() == EngineKind::Path
                && !matches!(
                    s,
                    LightSampling::SolidAngle
                        | LightSampling::SolidAngleRandom
                        | LightSampling::Random
                )
        }) {
            return Err(format!(
                "--light-sampling {}: the path tracer takes one independent point on a light at each vertex; expected random (by area, the default) or solid-angle",
                sampling.to_possible_value().map_or_else(String::new, |v| v.get_name().to_owned())
            ));
        }
        check_number("sppm_radius", self.sppm.sppm_radius, 0.0, true)?;
        if let Some(n) = self.sppm.sppm_photons {
            check_count("sppm_photons", n, 1..=u64::MAX)?;
        }
        self.part
            .validate(c.size[0], c.size[1], self.camera.num_antialias_samples)?;
        if let (Some(xy), &[w, h]) = (&self.ray_trace.ray_tree, &c.size[..]) {
            if xy[0] >= w || xy[1] >= h {
                return Err(format!(
                    "--ray-tree {} {}: the pixel is outside the {w}×{h} image",
                    xy[0], xy[1]
                ));
            }
        }
        if let Some(output) = &c.output {
            crate::film::ImageFormat::check_output(output).map_err(|e| e.to_string())?;
        }
        if let Some(path) = &c.variance {
            if self.part.crop_window.is_some() || self.part.pixel_samples.is_some() {
                return Err("--variance: not with --crop-window or --pixel-samples (a part keeps its sums and squares: give --variance to render merge)".into());
            }
            check_variance_output(path).map_err(|e| format!("--variance: {e}"))?;
        }
        for (id, path) in [
            ("save_photons", &p.save_photons),
            ("save_radiosity", &r.save_radiosity),
        ] {
            if let Some(path) = path {
                crate::output::check_folder(path)
                    .map_err(|e| format!("{}: {e}", super::flag_name(id)))?;
            }
        }
        for (id, path, extension) in [
            ("export_radiosity", &r.export_radiosity, "ply"),
            ("log_convergence", &r.log_convergence, "csv"),
        ] {
            if let Some(path) = path {
                check_text_output(id, path, extension)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// The engines name the shared flags they do not read by argument id; each must be a
    /// flag the command has, or a typo would silently keep a note from being printed.
    #[test]
    fn every_unread_flag_an_engine_names_is_a_flag() {
        let command = super::super::Cli::command();
        let ids: Vec<String> = command
            .get_arguments()
            .map(|a| a.get_id().to_string())
            .collect();
        for engine in crate::engines::all() {
            for id in engine.unread_flags() {
                assert!(
                    ids.iter().any(|i| i == id),
                    "{}: no flag {id}",
                    engine.kind()
                );
            }
        }
    }
}
