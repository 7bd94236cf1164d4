//! The lighting engines. Each takes the scene, an `Accel` and the settings and fills a `Film`.
//! So far: `raycast`, the course's MATERIALS view (first surface's emitted + albedo).

pub mod lights;
pub mod optics;
pub mod raycast;
pub mod raytrace;

use crate::geometry::Vec3;

/// The engines of trilux (`--engine`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EngineKind {
    /// The first visible surface's emitted radiance plus its albedo (texture looked up).
    Raycast,
    /// Whitted and distribution ray tracing (not implemented yet).
    Raytrace,
    /// Radiosity on the quad mesh (not implemented yet).
    Radiosity,
    /// Photon mapping (not implemented yet).
    Photon,
    /// The unbiased reference path tracer (not implemented yet).
    Path,
}

impl EngineKind {
    pub fn is_implemented(self) -> bool {
        matches!(self, EngineKind::Raycast | EngineKind::Raytrace)
    }
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

/// Counters of one render, printed by `--stats`.
#[derive(Debug, Default)]
pub struct RenderStats {
    pub camera_rays: std::sync::atomic::AtomicU64,
    pub shadow_rays: std::sync::atomic::AtomicU64,
    pub secondary_rays: std::sync::atomic::AtomicU64,
    /// Samples that came out NaN or infinite: excluded from the image, and counted here.
    pub non_finite_samples: std::sync::atomic::AtomicU64,
}

impl RenderStats {
    pub fn total_rays(&self) -> u64 {
        use std::sync::atomic::Ordering::Relaxed;
        self.camera_rays.load(Relaxed)
            + self.shadow_rays.load(Relaxed)
            + self.secondary_rays.load(Relaxed)
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
    /// Point pairs per form factor (`-num_form_factor_samples`, default 1).
    pub num_form_factor_samples: u32,
    /// Sphere tessellation for radiosity (`-sphere_rasterization H V`, default 8 6).
    pub sphere_rasterization: (u32, u32),
    /// Ring tessellation for radiosity (`-cylinder_ring_rasterization`, default 20).
    pub cylinder_ring_rasterization: u32,
    /// Photons emitted (`-num_photons_to_shoot`, default 0: no photon map).
    pub num_photons_to_shoot: u64,
    /// Photons per density estimate (`-num_photons_to_collect`, default 100).
    pub num_photons_to_collect: u32,
    /// Final gathering for indirect light (`-gather_indirect`, default off).
    pub gather_indirect: bool,
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
            num_form_factor_samples: 1,
            sphere_rasterization: (8, 6),
            cylinder_ring_rasterization: 20,
            num_photons_to_shoot: 0,
            num_photons_to_collect: 100,
            gather_indirect: false,
            light_sampling: crate::sampling::Pattern::Jittered,
            aperture: 0.0,
            focus_distance: None,
            seed: 0,
            quiet: false,
        }
    }
}
