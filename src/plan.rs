//! The plan of a render: which structures and stages it needs, decided from the scene and the
//! settings before anything is built ("pay only for what the scene uses"). `render --plan`
//! prints it.

use std::fmt;

use crate::accel::AccelKind;
use crate::engines::{EngineKind, IndirectKind, RenderSettings};
use crate::scene::Scene;

#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub engine: EngineKind,
    pub accel: AccelKind,
    pub quads: usize,
    pub one_sided_quads: bool,
    pub triangles: usize,
    pub spheres: usize,
    pub rings: usize,
    /// Textures decoded: those of materials some primitive uses.
    pub textures: usize,
    pub emitters: usize,
    pub photon_map: bool,
    pub caustic_map: bool,
    pub radiosity_mesh: bool,
    /// Patches of the radiosity mesh before adaptive subdivision (0 without a mesh).
    pub radiosity_patches: u64,
    /// Whether form factors cast visibility rays, and why (not).
    pub radiosity_visibility: &'static str,
    /// Why a stage the settings ask for is not run.
    pub notes: Vec<String>,
    /// Estimated peak memory, in bytes, and its largest parts (name, bytes).
    pub memory: u64,
    pub memory_parts: Vec<(&'static str, u64)>,
}

/// Bytes per pixel of the image, and per camera sample in flight (ray, generator, hit; one
/// chunk of a row per core, `engines::CHUNK_SAMPLES` samples or one pixel's).
const FILM_BYTES_PER_PIXEL: u64 = 12;
const SAMPLE_BYTES_IN_FLIGHT: u64 = 96;
/// Bytes per primitive of either Accel (nodes, references, Embree's copies).
const ACCEL_BYTES_PER_PRIMITIVE: u64 = 256;
/// Bytes per stored photon: the photon (52) while traced, its copy in a map, the kd-tree.
const PHOTON_BYTES: u64 = 52 + 52 + 16;
/// Bytes per radiosity patch: mesh face and its links, patch, solver state, interpolation.
const PATCH_BYTES: u64 = 640;

impl Plan {
    pub fn new(
        scene: &Scene,
        engine: EngineKind,
        accel: AccelKind,
        settings: &RenderSettings,
    ) -> Plan {
        let used = scene.used_materials();
        let emitters = scene
            .quads
            .iter()
            .map(|q| q.material)
            .chain(scene.triangles.materials.iter().copied())
            .chain(scene.spheres.iter().map(|s| s.material))
            .chain(scene.rings.iter().map(|r| r.material))
            .filter(|&m| scene.materials[m as usize].is_emissive())
            .count();
        let any_specular = scene
            .materials
            .iter()
            .zip(&used)
            .any(|(m, &u)| u && m.is_specular());
        let photon_engine = engine == EngineKind::Photon;
        let radiosity_mesh = engine == EngineKind::Radiosity
            || (engine == EngineKind::Raytrace && settings.indirect == IndirectKind::Radiosity);
        let mut notes = Vec::new();
        if settings.photon.num_photons_to_shoot > 0 && !photon_engine {
            notes.push(format!(
                "-num_photons_to_shoot {} is ignored: the {} engine reads no photon map",
                settings.photon.num_photons_to_shoot,
                engine.name()
            ));
        }
        let radiosity_patches = if radiosity_mesh {
            radiosity_patches(scene, settings)
        } else {
            0
        };
        let memory_parts = memory_parts(scene, settings, photon_engine, radiosity_patches);
        Plan {
            memory: memory_parts.iter().fold(0u64, |a, p| a.saturating_add(p.1)),
            memory_parts,
            engine,
            accel,
            quads: scene.quads.len(),
            one_sided_quads: !scene.two_sided_quads,
            triangles: scene.triangles.len(),
            spheres: scene.spheres.len(),
            rings: scene.rings.len(),
            textures: scene.textures.len(),
            emitters,
            photon_map: photon_engine && settings.photon.num_photons_to_shoot > 0,
            caustic_map: photon_engine && settings.photon.num_photons_to_shoot > 0 && any_specular,
            radiosity_mesh,
            radiosity_patches,
            radiosity_visibility: if !radiosity_mesh {
                "none"
            } else if settings.num_shadow_samples == 0 {
                "off (-num_shadow_samples 0)"
            } else if crate::engines::radiosity::convex_enclosure(scene) {
                "skipped: the scene is a convex enclosure"
            } else {
                "one occlusion ray per point pair"
            },
            notes,
        }
    }
}

/// The memory a render will need, part by part, estimated from the scene and the settings
/// before anything is allocated (so that a huge request is refused, not killed).
fn memory_parts(
    scene: &Scene,
    settings: &RenderSettings,
    photon_engine: bool,
    patches: u64,
) -> Vec<(&'static str, u64)> {
    let (w, h) = (settings.width as u64, settings.height as u64);
    let spp = settings.num_antialias_samples.max(1) as u64;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get() as u64);
    let in_flight = spp.max(crate::engines::CHUNK_SAMPLES as u64);
    let image = w
        .saturating_mul(h)
        .saturating_mul(FILM_BYTES_PER_PIXEL)
        .saturating_add(in_flight.saturating_mul(SAMPLE_BYTES_IN_FLIGHT * cores.min(h.max(1))));
    let accel = (scene.primitive_count() as u64).saturating_mul(ACCEL_BYTES_PER_PRIMITIVE);
    let mut parts = vec![("image", image), ("acceleration structure", accel)];
    if photon_engine {
        let p = &settings.photon;
        // Photons are stored once per diffuse bounce: about 1/(1 − ρ̄) of them per photon
        // emitted, ρ̄ the area-weighted mean albedo, within the depth limit.
        let bounces = (1.0 / (1.0 - mean_albedo(scene).min(0.95)))
            .min(p.max_photon_depth as f64 + 1.0)
            .max(1.0);
        let emitted = p.num_photons_to_shoot.saturating_add(p.caustic_photons());
        let stored = (emitted as f64 * bounces).min(u64::MAX as f64 / PHOTON_BYTES as f64);
        parts.push(("photon maps", (stored * PHOTON_BYTES as f64) as u64));
    }
    if patches > 0 {
        let cache = patches
            .saturating_mul(patches)
            .saturating_mul(4)
            .min((settings.radiosity.ff_cache_mb as u64).saturating_mul(1 << 20));
        parts.push(("radiosity mesh", patches.saturating_mul(PATCH_BYTES)));
        parts.push(("form-factor cache", cache));
    }
    parts
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

/// Patches of the radiosity mesh: every primitive's top-level faces, times 4 per subdivision.
fn radiosity_patches(scene: &Scene, settings: &RenderSettings) -> u64 {
    let r = &settings.radiosity;
    let (h, v) = r.sphere_rasterization;
    let top = scene.quads.len() as u64
        + scene.triangles.len() as u64
        + scene.spheres.len() as u64 * h.max(3) as u64 * v.max(2) as u64
        + scene.rings.len() as u64 * 4 * r.cylinder_ring_rasterization.max(3) as u64;
    top.saturating_mul(4u64.saturating_pow(r.subdivide))
}

impl Plan {
    /// The memory estimate and its parts, e.g. `1.2 GiB (image 816 KiB, photon maps 1.2 GiB)`.
    pub fn memory_summary(&self) -> String {
        let parts: Vec<String> = self
            .memory_parts
            .iter()
            .map(|(name, b)| format!("{name} {}", human_bytes(*b)))
            .collect();
        format!("{} ({})", human_bytes(self.memory), parts.join(", "))
    }
}

/// Bytes as KiB, MiB, GiB or TiB with three significant digits.
pub fn human_bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.3} {}", units[u])
    }
}

/// Parses a memory size: a number with an optional K, M, G or T suffix (powers of 1024).
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let (number, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let v: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("expected a size such as 512M or 8G, found {text}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("expected a positive size, found {text}"));
    }
    Ok((v * (1u64 << shift) as f64) as u64)
}

/// 80% of the machine's physical memory (Linux: MemTotal of /proc/meminfo), the default of
/// `--max-memory`; 8 GiB where it cannot be read.
pub fn default_max_memory() -> u64 {
    let total_kib = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        m.lines()
            .find(|l| l.starts_with("MemTotal:"))?
            .split_whitespace()
            .nth(1)?
            .parse::<u64>()
            .ok()
    });
    total_kib.map_or(8 << 30, |k| k * 1024 / 10 * 8)
}

fn yes_no(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "engine: {}", self.engine.name())?;
        writeln!(f, "accel: {}", self.accel)?;
        #[cfg(feature = "embree")]
        if self.accel == AccelKind::Embree {
            writeln!(
                f,
                "embree version: {}",
                crate::accel::embree::embree_major()
            )?;
        }
        let sided = if self.one_sided_quads {
            "one-sided"
        } else {
            "two-sided"
        };
        if self.quads > 0 {
            writeln!(
                f,
                "quad geometry: {} ({sided})",
                plural(self.quads, "quad", "quads")
            )?;
        } else {
            writeln!(f, "quad geometry: none")?;
        }
        if self.triangles > 0 {
            writeln!(
                f,
                "triangle geometry: {}",
                plural(self.triangles, "triangle", "triangles")
            )?;
        } else {
            writeln!(f, "triangle geometry: none")?;
        }
        let mut user = Vec::new();
        if self.spheres > 0 {
            user.push(plural(self.spheres, "sphere", "spheres"));
        }
        if self.rings > 0 {
            user.push(plural(self.rings, "ring", "rings"));
        }
        if user.is_empty() {
            writeln!(f, "user geometry: none")?;
        } else {
            writeln!(f, "user geometry: {}", user.join(", "))?;
        }
        writeln!(f, "textures decoded: {}", self.textures)?;
        writeln!(f, "emitters: {}", self.emitters)?;
        writeln!(f, "photon map: {}", yes_no(self.photon_map))?;
        writeln!(f, "caustic map: {}", yes_no(self.caustic_map))?;
        if self.radiosity_mesh {
            writeln!(
                f,
                "radiosity mesh: yes ({} patches; visibility: {})",
                self.radiosity_patches, self.radiosity_visibility
            )?;
        } else {
            writeln!(f, "radiosity mesh: no")?;
        }
        writeln!(f, "memory estimate: {}", self.memory_summary())?;
        for note in &self.notes {
            writeln!(f, "note: {note}")?;
        }
        Ok(())
    }
}
