//! What the photon engine reads besides the scene and the common settings: its flags' values,
//! with their defaults. A leaf: it imports nothing of the engines, so the common settings can
//! hold it.

/// What the photon engine shows (`--visualize`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Display {
    /// The ray-traced image with the photon maps as its indirect light.
    #[default]
    Image,
    /// The photons projected through the camera, coloured by power.
    Photons,
    /// The photons with the cells of a balanced kd-tree over them drawn in green.
    Kdtree,
}

/// The bounces a photon may make by default: roulette ends paths long before (it keeps a
/// photon with at most `MAX_SURVIVAL`, so fewer than 1e-4 of them pass 10,000 bounces even in
/// a closed white room).
pub const SAFETY_DEPTH: u32 = 10_000;

/// The largest probability with which Russian roulette keeps a photon going: below 1, so that
/// photon paths end even between surfaces that reflect everything (as the path tracer's).
pub const MAX_SURVIVAL: f32 = 0.999;

/// The most lookups of the volume photon map along one ray (`--volume-steps`): a bound on the
/// time a pixel can take.
pub const MAX_VOLUME_STEPS: u32 = 4096;

/// CPU seconds a lookup of the volume map takes per photon of its estimate
/// (`volume_steps_for_time`): on the fog Cornell box (100 photons an estimate, 54,000 in the
/// volume map, EPYC), 15 more lookups along each camera ray of a 512×512 image took 9.4 s more
/// on 2 threads, 4.8 µs of CPU a lookup.
const VOLUME_LOOKUP_SECONDS_PER_PHOTON: f64 = 4.8e-8;

/// The share of `--time-limit` that the first pass's lookups of the volume map may take
/// (`volume_steps_for_time`).
const TIME_LIMITED_VOLUME_SHARE: f64 = 0.25;

/// `--volume-steps` under a time limit of `seconds` where it is not given: as many lookups
/// along each camera ray as let the first pass (one camera sample for each of `pixels`)
/// spend `TIME_LIMITED_VOLUME_SHARE` of the limit on them on `threads` threads, `k` photons
/// an estimate; at least 1, at most the default. The first pass is whole whatever the limit:
/// with the default's 16 lookups, the fog Cornell box at 512×512 under `--time-limit 0.5` took
/// 12.5 s.
pub fn volume_steps_for_time(seconds: f64, threads: usize, pixels: u64, k: u32) -> u32 {
    let lookup = VOLUME_LOOKUP_SECONDS_PER_PHOTON * f64::from(k.max(1));
    let steps = TIME_LIMITED_VOLUME_SHARE * seconds * threads.max(1) as f64
        / (pixels.max(1) as f64 * lookup);
    let most = PhotonSettings::default().volume_steps;
    (steps.min(f64::from(most)) as u32).max(1)
}

/// Settings only the photon engine reads.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photons emitted (`-num_photons_to_shoot`, default None: `photons_for_image` of the
    /// image's pixels). 0 makes no photon map.
    pub num_photons_to_shoot: Option<u64>,
    /// Photons aimed at the mirrors and glass for the caustic map (`--caustic-photons`,
    /// default None: as many as the main pass). 0 turns the caustic pass off; the caustic map
    /// then holds the caustic photons of the main pass.
    pub caustic_photons: Option<u64>,
    /// Photons per density estimate (`-num_photons_to_collect`, default 100).
    pub num_photons_to_collect: u32,
    /// Bounces a photon may make (`--max-photon-depth`, default `SAFETY_DEPTH`): a safety cap
    /// far beyond what Russian roulette lets through, so that it cuts no light (the course's
    /// 10 cut 0.9% of the Cornell box's photons).
    pub max_photon_depth: u32,
    /// Largest radius of a density estimate, as a fraction of the scene's diagonal
    /// (`--photon-max-radius`, default 0.1).
    pub max_radius: f32,
    /// Final gathering for indirect light (`-gather_indirect`, default off: direct lookup).
    pub gather_indirect: bool,
    /// Points per camera or mirror ray in the fog at which the volume photon map is looked up
    /// (`--volume-steps`, default 16; at most `MAX_VOLUME_STEPS`).
    pub volume_steps: u32,
    /// Hemisphere rays per final gather (`--final-gather-rays`, default 128).
    pub final_gather_rays: u32,
    /// Ward's irradiance cache error a (`--irradiance-cache-error`, default 0.15).
    pub irradiance_cache_error: f32,
    /// Write the maps to this file after tracing (`--save-photons`).
    pub save: Option<std::path::PathBuf>,
    /// Read the maps from this file instead of tracing (`--load-photons`).
    pub load: Option<std::path::PathBuf>,
    /// The irradiance cache's first pass visits every n-th pixel centre in x and y, finest
    /// level (`--irradiance-cache-spacing`, default 1); records are made where a visited point
    /// is not covered, and the pixels interpolate, or gather afresh where no record is close
    /// enough.
    pub irradiance_cache_spacing: u32,
    /// What the image shows (`--visualize photons|kdtree`, default the image).
    pub display: Display,
    /// SPPM: photons traced a pass (`--sppm-photons`, default None: one per pixel of the
    /// image).
    pub sppm_photons: Option<u64>,
    /// SPPM: the initial gathering radius, as a fraction of the scene's diagonal
    /// (`--sppm-radius`, default 0.01).
    pub sppm_radius: f32,
}

impl Default for PhotonSettings {
    fn default() -> Self {
        PhotonSettings {
            num_photons_to_shoot: None,
            caustic_photons: None,
            num_photons_to_collect: 100,
            max_photon_depth: SAFETY_DEPTH,
            max_radius: 0.1,
            gather_indirect: false,
            volume_steps: 16,
            final_gather_rays: 128,
            irradiance_cache_error: 0.15,
            irradiance_cache_spacing: 1,
            save: None,
            load: None,
            display: Display::Image,
            sppm_photons: None,
            sppm_radius: 0.01,
        }
    }
}

/// Shadow rays a light when `-num_shadow_samples` is not given (and neither `--time-limit`
/// nor the scene file chooses): 8, where the course's 0 takes each light as a point at its
/// centre, unoccluded. On the Cornell box with the diffuse sphere at 256×256, against the
/// path tracer at 2,048 paths: relMSE 6.6e-2 with 0 (mean 4.7% high), 1.06e-2 with 4,
/// 9.5e-3 with 8, 9.2e-3 with 16, in 0.50, 0.48, 0.48 and 0.62 s (the photon map's
/// tracing is most of the time up to 8).
pub const SHADOW_SAMPLES: u32 = 8;

/// Mirror and refraction depth when `-num_bounces` is not given (and the scene file does not
/// choose): pbrt's Whitted depth, as on MGF scenes, where the course's 0 shows no reflection
/// and no refraction. With 8 shadow rays, relMSE against the path tracer on the Cornell box
/// with the mirror sphere 7.2e-2 → 9.8e-3 (1 bounce gives the same); with the course's 0
/// shadow rays and bounces before, 1.08e-1. The glass sphere's caustic: 2.5e-1 → 3.9e-3,
/// 0.34 → 0.51 s.
pub const NUM_BOUNCES: u32 = 5;

/// Photons emitted a pixel of the image when no count is given.
pub const PHOTONS_PER_PIXEL: u64 = 4;

/// The fewest and the most photons emitted when no count is given.
pub const PHOTONS_FOR_IMAGE: (u64, u64) = (100_000, 1_000_000);

/// Photons emitted when `-num_photons_to_shoot` is not given: `PHOTONS_PER_PIXEL` a pixel of
/// the whole image (every tile of a split render traces the same maps), at least
/// `PHOTONS_FOR_IMAGE.0` and at most `PHOTONS_FOR_IMAGE.1`. Measured on the Cornell box with
/// the diffuse sphere at 64×64 (16 shadow rays, 4 camera samples, against the path tracer at
/// 1,024 paths): relMSE 2.23e-2 at 50,000 photons, 2.08e-2 at 200,000, 2.01e-2 at 1,000,000,
/// in 0.5, 1.3 and 5.5 s on 2 shared cores — the density estimate's blur, not the count,
/// limits it past about 100,000, so more photons are worth their time only as the image's
/// pixels grow finer. The image's mean is the path tracer's within 0.7% at any of these
/// counts (without photons it is 18% low: no indirect light).
pub fn photons_for_image(pixels: u64) -> u64 {
    pixels
        .saturating_mul(PHOTONS_PER_PIXEL)
        .clamp(PHOTONS_FOR_IMAGE.0, PHOTONS_FOR_IMAGE.1)
}

impl PhotonSettings {
    /// Photons of the main pass for an image of `pixels`: `-num_photons_to_shoot`, else
    /// `photons_for_image`.
    pub fn photons(&self, pixels: u64) -> u64 {
        self.num_photons_to_shoot
            .unwrap_or_else(|| photons_for_image(pixels))
    }

    /// Photons of the caustic pass for an image of `pixels`: `--caustic-photons`, else as
    /// many as the main pass.
    pub fn caustic_photons(&self, pixels: u64) -> u64 {
        self.caustic_photons.unwrap_or(self.photons(pixels))
    }
}
