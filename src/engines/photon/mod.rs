//! Photon mapping (Jensen): photons traced from the lights into a global map (indirect
//! diffuse light) and a caustic map (light that reached a diffuse surface through mirrors or
//! glass only), looked up by k-nearest density estimation. The ray tracer computes direct light
//! and mirrors itself and takes its diffuse indirect light from the maps — by direct lookup, or
//! by final gathering accelerated by an irradiance cache (`-gather_indirect`).

pub mod file;
pub mod gather;
pub mod kdtree;
pub mod map;
pub mod settings;
pub mod sppm;
pub mod trace;

pub use gather::IrradianceCache;
pub use map::PhotonMap;
pub use settings::{Display, PhotonSettings};
pub use trace::{Aim, PathKind, Photon};

use super::engine::{EnginePlan, PrePass, RenderSettings};
use crate::accel::Accel;
use crate::film::Film;
use crate::geometry::{Bounds3, Vec3};
use crate::render::IndirectLight;
use crate::sampling::Rng;
use crate::scene::medium::Medium;
use crate::scene::{Color, Scene, SurfaceHit};

/// The rays the volume map is looked up along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Along {
    /// Camera, mirror and glass rays: the light scattered in besides the lights' single
    /// scattering (the ray tracer's), at `--volume-steps` points.
    CameraRay,
    /// Final-gather rays: all the light scattered in, single scattering included (the map
    /// holds every scattering when gathering), at one point, as a gather averages hundreds of
    /// rays.
    GatherRay,
}

/// The two photon maps of a scene and what the lookups need.
pub struct PhotonMaps {
    /// Indirect photons (all photons when final gathering: gather rays look up the full
    /// light at the surfaces they reach).
    pub global: PhotonMap,
    pub caustic: PhotonMap,
    /// Where photons scattered in the fog after a bounce or an earlier scattering (the ray
    /// tracer scatters the lights' own light itself) — with final gathering, every scattering
    /// (gather rays need the full light the fog scatters into them) — and the box their
    /// lookups reach (theirs padded by `max_radius`).
    pub volume: PhotonMap,
    volume_bounds: Bounds3,
    /// Lookups of the volume map along a ray (`--volume-steps`).
    volume_steps: u32,
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
            Some(_) => settings.caustic_photons(),
            None => 0,
        };
        let emitted = settings.photons();
        let blocks = emitted.div_ceil(4096) + caustic_emitted.div_ceil(4096);
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
        let main = trace(emitted, Aim::Everywhere);
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
        let volume = main
            .volume
            .into_iter()
            .filter(|ph| p.gather_indirect || ph.kind != PathKind::Direct)
            .collect();
        let mut maps = PhotonMaps::from_photons(scene, settings, [global, caustic, volume]);
        maps.trace_seconds = trace_seconds;
        maps.build_seconds = clock.elapsed().as_secs_f64();
        maps.emitted = emitted;
        maps.caustic_emitted = caustic_emitted;
        maps.rays = rays;
        maps.truncated = truncated;
        maps
    }

    /// The maps of the global, caustic and volume photons, looked up as `settings` say, with
    /// their counters zero.
    pub(super) fn from_photons(
        scene: &Scene,
        settings: &RenderSettings,
        [global, caustic, volume]: [Vec<Photon>; 3],
    ) -> PhotonMaps {
        let p = &settings.photon;
        let positions: Vec<Vec3> = volume.iter().map(|ph| ph.position).collect();
        let max_radius = p.max_radius * scene.bounds().extent().length();
        let photons_box = Bounds3::from_points(&positions);
        PhotonMaps {
            global: PhotonMap::new(global),
            caustic: PhotonMap::new(caustic),
            // Lookups reach `max_radius` beyond the outermost photons.
            volume_bounds: Bounds3 {
                min: photons_box.min - Vec3::splat(max_radius),
                max: photons_box.max + Vec3::splat(max_radius),
            },
            volume: PhotonMap::new(volume),
            volume_steps: p.volume_steps.max(1),
            emitted: 0,
            caustic_emitted: 0,
            rays: 0,
            truncated: 0,
            trace_seconds: 0.0,
            build_seconds: 0.0,
            collect: p.num_photons_to_collect.max(1) as usize,
            max_radius,
        }
    }

    /// Radiance the fog `medium` scatters into `ray` over its first `length` of distance
    /// from the volume map: lookups evenly spaced over the part of the ray in
    /// `volume_bounds`, jittered together, each weighed by the transmittance from the ray's
    /// origin (a midpoint rule with a random offset: its mean is the integral of the smooth
    /// estimate along the ray). What is counted, and how many lookups, depends on the ray:
    /// see `Along`.
    pub fn volume_in_scattered(
        &self,
        medium: &Medium,
        ray: &crate::geometry::Ray,
        length: f32,
        along: Along,
        rng: &mut Rng,
    ) -> Color {
        let (steps, first_scatterings) = match along {
            Along::CameraRay => (self.volume_steps, false),
            Along::GatherRay => (1, true),
        };
        let scale = ray.direction.length();
        if self.volume.is_empty() || scale.is_nan() || scale <= 0.0 {
            return Color::ZERO;
        }
        let travel = ray.direction / scale;
        let reach = self.max_radius;
        let Some((near, far)) = self.volume_bounds.clip(ray.origin, travel, length) else {
            return Color::ZERO;
        };
        let step = (far - near) / steps as f32;
        let offset = rng.next_f32();
        let mut total = Color::ZERO;
        for k in 0..steps {
            let t = near + (k as f32 + offset) * step;
            let x = ray.origin + travel * t;
            total += medium.transmittance(t)
                * self.volume.in_scattered(
                    (x, -travel),
                    medium,
                    self.collect,
                    reach,
                    first_scatterings,
                );
        }
        total * step
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
        .map(|c| c.max_element())
        .fold(0.0f32, f32::max);
    if brightest > 0.0 {
        film.pixels.iter_mut().for_each(|c| *c *= brightest.recip());
    }
    film
}

/// Levels of the kd-tree drawn by `--visualize kdtree` (2⁶ = 64 cells).
const KD_VIEW_DEPTH: u32 = 6;

/// The cells of a balanced kd-tree over all photons, `depth` levels deep: each cell split at
/// the median photon along its longest axis, as `kdtree::KdTree` splits each map's (here
/// over both maps' photons at once). Cells are the photons' bounding boxes.
fn kd_cells(maps: &PhotonMaps, depth: u32) -> Vec<Bounds3> {
    fn split(points: &mut [Vec3], depth: u32, out: &mut Vec<Bounds3>) {
        let bounds = Bounds3::from_points(points);
        if depth == 0 || points.len() < 2 {
            out.push(bounds);
            return;
        }
        let axis = bounds.extent().max_position();
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

/// Bytes per stored photon: the photon (52) while traced, its copy in a map, the kd-tree.
const PHOTON_BYTES: u64 = 52 + 52 + 16;

/// What the photon engine builds, for `--plan`: the two maps and their memory.
pub fn plan(scene: &Scene, settings: &RenderSettings) -> EnginePlan {
    let p = &settings.photon;
    let shot = settings.photons();
    let traced = shot > 0;
    let used = scene.used_materials();
    let any_specular = scene
        .materials
        .iter()
        .zip(&used)
        .any(|(m, &u)| u && m.is_specular());
    // Photons are stored once per diffuse bounce: about 1/(1 − ρ̄) of them per photon
    // emitted, ρ̄ the area-weighted mean albedo, within the depth limit.
    let bounces = (1.0 / (1.0 - mean_albedo(scene).min(0.95)))
        .min(p.max_photon_depth as f64 + 1.0)
        .max(1.0);
    let emitted = shot.saturating_add(settings.caustic_photons());
    let volume = volume_events_per_photon(scene, bounces) * shot as f64;
    let stored = (emitted as f64 * bounces + volume).min(u64::MAX as f64 / PHOTON_BYTES as f64);
    let yes_no = |b: bool| if b { "yes" } else { "no" }.to_string();
    EnginePlan {
        structures: vec![
            ("photon map", yes_no(traced)),
            ("caustic map", yes_no(traced && any_specular)),
            ("volume photon map", yes_no(traced && volume > 0.0)),
        ],
        memory: vec![("photon maps", (stored * PHOTON_BYTES as f64) as u64)],
    }
}

/// Scatterings in the fog per photon emitted, for the plan: a photon crosses the scene's box
/// along chords of mean length 4V/S (Cauchy), scattering on one with probability
/// P = 1 − e^{−σt·chord} (σt's largest channel); its `bounces` surface hits then take
/// bounces/(1 − P) segments, P of them ending in a scattering. 0 without fog. (On the fog
/// Cornell box: 2.2 a photon, where 1.6 were kept.)
fn volume_events_per_photon(scene: &Scene, bounces: f64) -> f64 {
    let Some(fog) = scene.fog.map(|k| &scene.media[k]) else {
        return 0.0;
    };
    let b = scene.bounds();
    let e = b.extent();
    let (volume, area) = ((e.x * e.y * e.z) as f64, b.area() as f64);
    let chord = if area > 0.0 { 4.0 * volume / area } else { 0.0 };
    let p = 1.0 - (-(fog.sigma_t().max_element() as f64) * chord).exp();
    bounces / (1.0 - p).max(1e-3) * p
}

/// Area-weighted mean of the quads' albedos (mean channel; textures count as 0.5).
fn mean_albedo(scene: &Scene) -> f64 {
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    for q in &scene.quads {
        let m = &scene.materials[q.material as usize];
        let rho = if m.texture.is_some() {
            0.5
        } else {
            (m.diffuse.x + m.diffuse.y + m.diffuse.z) as f64 / 3.0
        };
        sum += rho * q.area() as f64;
        area += q.area() as f64;
    }
    if area > 0.0 {
        sum / area
    } else {
        0.5
    }
}

/// The photon maps of a render: loaded from `--load-photons`, else traced; written to
/// `--save-photons` when asked.
pub fn maps(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<PhotonMaps, String> {
    let p = &settings.photon;
    let maps = match &p.load {
        Some(path) => PhotonMaps::load(path, scene, settings)?,
        None => PhotonMaps::build(scene, accel, settings),
    };
    // Maps Ctrl-C cut short are not saved: a farm's tasks must not take them as the maps.
    if let (Some(path), false) = (&p.save, crate::interrupt::requested()) {
        maps.save(path, file::fingerprint(scene, settings))
            .map_err(|e| e.to_string())?;
    }
    Ok(maps)
}

/// The photon maps as a render farm's pre-pass.
pub fn pre_pass(settings: &RenderSettings) -> PrePass {
    PrePass {
        name: "photon maps",
        save_flag: "--save-photons",
        load_flag: "--load-photons",
        saved: settings.photon.save.is_some(),
    }
}

/// The image of a display mode other than `Display::Image` (`--visualize photons|kdtree`),
/// None for the image itself (the ray tracer renders that with `PhotonIndirect`).
pub fn display(scene: &Scene, maps: &PhotonMaps, settings: &RenderSettings) -> Option<Film> {
    let mode = settings.photon.display;
    if mode == Display::Image {
        return None;
    }
    let mut film = visualize(scene, maps, settings);
    if mode == Display::Kdtree {
        let camera = scene.camera();
        let green = crate::geometry::vec3(0.0, 1.0, 0.0);
        let cells = kd_cells(maps, KD_VIEW_DEPTH);
        crate::film::draw_lines(
            &mut film,
            &camera,
            cells
                .iter()
                .flat_map(|b| box_edges(b).map(|(a, c)| (a, c, green))),
        );
    }
    Some(film)
}

/// The photon maps as the ray tracer's indirect light: the global map's density estimate (or,
/// with an irradiance cache, final gathers at the surfaces the camera sees) plus the caustic
/// map's.
pub struct PhotonIndirect<'a> {
    pub maps: &'a PhotonMaps,
    pub cache: Option<&'a IrradianceCache>,
}

impl IndirectLight for PhotonIndirect<'_> {
    fn incident(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        s: &SurfaceHit,
        (n, medium): (Vec3, Option<&Medium>),
        _depth: u32,
        rng: &mut Rng,
    ) -> Color {
        let global = match self.cache {
            // Final gathering wherever the camera's rays reach a diffuse surface, behind
            // mirrors and glass too. With final gathering the global map holds every photon
            // (the gather rays need the full light where they land), so its own estimate
            // there would count direct light and caustics twice: it did, and on the
            // glass-sphere scene what the camera saw through the glass came out up to 2× too
            // bright (relMSE 2.1e-2 against Mitsuba's reference, against 4.7e-4 without
            // final gathering).
            Some(c) => c.irradiance_over_pi(
                (scene, accel, self.maps),
                (s.point, n, s.error),
                medium,
                rng,
            ),
            None => self.maps.global_at(s.point, s.geometric_side(n)),
        };
        global + self.maps.caustic_at(s.point, s.geometric_side(n))
    }

    fn in_scattered(
        &self,
        medium: &Medium,
        ray: &crate::geometry::Ray,
        length: f32,
        rng: &mut Rng,
    ) -> Color {
        self.maps
            .volume_in_scattered(medium, ray, length, Along::CameraRay, rng)
    }
}

impl PhotonMaps {
    /// One line on the maps for the user.
    pub fn summary(&self) -> String {
        format!(
            "photons: {} emitted, {} more aimed at mirrors and glass, {} photon rays in {:.3} s; global map {} photons, caustic map {}{} (kd-trees built in {:.3} s); {} per estimate within {:.3}",
            self.emitted,
            self.caustic_emitted,
            self.rays,
            self.trace_seconds,
            self.global.len(),
            self.caustic.len(),
            if self.volume.is_empty() {
                String::new()
            } else {
                format!(", volume map {}", self.volume.len())
            },
            self.build_seconds,
            self.collect,
            self.max_radius
        )
    }

    /// A warning when the depth limit cut more than one photon in a thousand short.
    pub fn truncation_warning(&self, max_photon_depth: u32) -> Option<String> {
        let emitted = self.emitted + self.caustic_emitted;
        (self.truncated * 1000 > emitted).then(|| format!(
            "{} of {emitted} photons were still carrying light when --max-photon-depth {max_photon_depth} stopped them; their light is missing from the image (raise the depth: Russian roulette alone keeps paths finite)",
            self.truncated
        ))
    }
}
