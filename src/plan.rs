//! The plan of a render: which structures and stages it needs, decided from the scene and the
//! settings before anything is built ("pay only for what the scene uses"). `render --plan`
//! prints it.

use std::fmt;

use crate::accel::AccelKind;
pub use crate::bytes::{human_bytes, parse_bytes};
use crate::engines::{self, EngineKind, RenderSettings};
use crate::geometry::Shape;
use crate::scene::{CulledBacks, Scene};

#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub engine: EngineKind,
    pub accel: AccelKind,
    pub quads: usize,
    pub triangles: usize,
    /// Which of them a ray passes through from behind (`Scene::culled_backs`).
    pub culled: CulledBacks,
    /// Instancing (Mitsuba's shapegroups and instances), when the scene has instances:
    /// instances, groups, triangles the groups store, triangles the instances place.
    pub instancing: Option<(usize, usize, usize, usize)>,
    /// Analytic shapes by kind name ("sphere"), in the order the kinds first appear.
    pub shapes: Vec<(&'static str, usize)>,
    /// Textures decoded: those of materials some primitive uses.
    pub textures: usize,
    /// Height images of `bump_file`s decoded: those of materials some primitive uses.
    pub height_maps: usize,
    /// The procedural textures and bump maps of the materials some primitive uses
    /// ("material 3: wood texture, scale 0.15"), one per material that has either.
    pub patterns: Vec<String>,
    pub emitters: usize,
    /// Point, spot and directional lights (a Mitsuba scene's).
    pub lights_without_area: usize,
    /// The fog the render traces through ("medium 0: σa …, σs …, g …"), None without one.
    pub fog: Option<String>,
    /// The Mitsuba BSDF of each used material that has one and what the engine renders of
    /// it (`material 3 "coat" twosided(roughplastic): roughplastic approximated as …`).
    pub bsdfs: Vec<String>,
    /// The media on either side of boundaries ("material 6: medium 1 inside", "… medium 0
    /// outside"), one per material that has either, and the camera's where it is not the fog.
    pub boundary_media: Vec<String>,
    /// The materials whose emitted radiance is a texture, and what the engine emits of it.
    pub emission_textures: Vec<String>,
    /// The sky that lights the render ("uniform …", "gradient …"), None without one.
    pub sky: Option<String>,
    /// What the engine builds beyond the image and the Accel, by name, and "no" for what
    /// the other engines would build (every name any engine reports, in engine order).
    pub structures: Vec<(&'static str, String)>,
    /// Estimated peak memory, in bytes, and its largest parts (name, bytes).
    pub memory: u64,
    pub memory_parts: Vec<(&'static str, u64)>,
}

/// Bytes per pixel of the image, and per camera sample in flight (ray, generator, hit; one
/// chunk of a row per core, `render::CHUNK_SAMPLES` samples or one pixel's).
const FILM_BYTES_PER_PIXEL: u64 = 12;
const SAMPLE_BYTES_IN_FLIGHT: u64 = 96;
/// Bytes per primitive of either Accel (nodes, references, Embree's copies).
const ACCEL_BYTES_PER_PRIMITIVE: u64 = 256;

impl Plan {
    pub fn new(
        scene: &Scene,
        engine: EngineKind,
        accel: AccelKind,
        settings: &RenderSettings,
    ) -> Plan {
        let emitters = scene
            .quads
            .iter()
            .map(|q| q.material)
            .chain(scene.triangles.materials.iter().copied())
            .chain(scene.shapes.iter().map(|s| s.material))
            .filter(|&m| scene.materials[m as usize].is_emissive())
            .count();
        let engine_plan = engines::engine(engine).plan(scene, settings);
        // Every structure some engine can build, so that the plan also says what is not built.
        let mut structures: Vec<(&'static str, String)> = Vec::new();
        for other in engines::all() {
            for &name in other.structures() {
                if !structures.iter().any(|s| s.0 == name) {
                    let built = engine_plan.structures.iter().find(|s| s.0 == name);
                    structures.push((name, built.map_or("no".into(), |s| s.1.clone())));
                }
            }
        }
        let mut memory_parts = image_and_accel_memory(scene, settings);
        memory_parts.extend(engine_plan.memory);
        Plan {
            memory: memory_parts.iter().fold(0u64, |a, p| a.saturating_add(p.1)),
            memory_parts,
            engine,
            accel,
            quads: scene.quads.len(),
            triangles: scene.triangles.len(),
            culled: scene.culled_backs(),
            instancing: (!scene.instancing.instances.is_empty()).then(|| {
                let i = &scene.instancing;
                (
                    i.instances.len(),
                    i.groups.len(),
                    i.stored_triangle_count(),
                    i.triangle_count(),
                )
            }),
            shapes: shape_counts(scene),
            textures: scene.textures.len(),
            height_maps: scene.height_maps.len(),
            patterns: patterns(scene),
            bsdfs: bsdfs(scene, engine),
            emitters,
            lights_without_area: scene.delta_lights.len(),
            fog: scene.fog.map(|k| {
                let m = &scene.media[k];
                let v = |c: crate::geometry::Vec3| format!("{} {} {}", c.x, c.y, c.z);
                let what = if engine == EngineKind::Radiosity {
                    "transmittance on form factors and camera rays; the light it scatters in is left to the other engines (path, raytrace, photon)"
                } else {
                    "transmittance on every segment, scattering traced"
                };
                format!(
                    "medium {k} (sigma_a {}, sigma_s {}, g {}): {what}",
                    v(m.sigma_a),
                    v(m.sigma_s),
                    m.g
                )
            }),
            boundary_media: boundary_media(scene),
            emission_textures: scene
                .materials
                .iter()
                .enumerate()
                .filter(|(_, m)| m.emission_texture.is_some())
                .map(|(i, m)| {
                    let what = if engine == EngineKind::Path {
                        "read where paths meet it and where they sample it".to_string()
                    } else {
                        format!("its mean, {}, everywhere", m.emitted)
                    };
                    format!("material {i}: {what}")
                })
                .collect(),
            sky: scene.sky.as_ref().map(|sky| {
                let v = |c: crate::geometry::Vec3| format!("{} {} {}", c.x, c.y, c.z);
                match sky {
                    crate::scene::sky::Sky::Uniform(c) => format!("uniform {}: lights the scene", v(*c)),
                    crate::scene::sky::Sky::Map(map) => format!(
                        "map {} ({}×{}, scale {}): lights the scene, sampled by its importance",
                        map.file.display(),
                        map.width,
                        map.height,
                        map.scale
                    ),
                    crate::scene::sky::Sky::Gradient { zenith, horizon, nadir } => format!(
                        "gradient (zenith {}, horizon {}, nadir {}): lights the scene",
                        v(*zenith),
                        v(*horizon),
                        v(*nadir)
                    ),
                }
            }),
            structures,
        }
    }
}

/// What each used material with a procedural texture or a bump map evaluates at its hits.
fn patterns(scene: &Scene) -> Vec<String> {
    use crate::scene::procedural::BumpSource;
    let used = scene.used_materials();
    let mut lines = Vec::new();
    for (i, m) in scene.materials.iter().enumerate() {
        if !used[i] {
            continue;
        }
        let mut parts = Vec::new();
        if let Some(t) = &m.procedural {
            parts.push(format!("{} texture, scale {}", t.pattern.name(), t.scale));
        }
        if let Some(b) = &m.bump {
            parts.push(match &b.source {
                BumpSource::Procedural { pattern, scale, .. } => format!(
                    "{} bump, scale {scale}, amplitude {}",
                    pattern.name(),
                    b.amplitude
                ),
                BumpSource::File { file, .. } => {
                    format!("bump image {}, amplitude {}", file.display(), b.amplitude)
                }
            });
        }
        if !parts.is_empty() {
            lines.push(format!("material {i}: {}", parts.join(", ")));
        }
    }
    lines
}

/// What `engine` renders of each used material made of a Mitsuba BSDF: exactly, or which
/// plugins it approximates and by what (the record the reader's warnings come from).
fn bsdfs(scene: &Scene, engine: EngineKind) -> Vec<String> {
    let used = scene.used_materials();
    scene
        .mitsuba_bsdfs
        .iter()
        .filter(|(&k, _)| used[k as usize])
        .map(|(k, b)| {
            let id =
                b.id.as_ref()
                    .map_or(String::new(), |id| format!(" \"{id}\""));
            let rendering = b.rendering(engine == EngineKind::Path);
            format!("material {k}{id} {}: {rendering}", b.kinds())
        })
        .collect()
}

/// The memory every render needs, estimated before anything is allocated (so that a huge
/// request is refused, not killed): the image with the samples in flight, and the Accel.
fn image_and_accel_memory(scene: &Scene, settings: &RenderSettings) -> Vec<(&'static str, u64)> {
    let (w, h) = (settings.width as u64, settings.height as u64);
    let spp = settings.num_antialias_samples.max(1) as u64;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get() as u64);
    let in_flight = spp.max(crate::render::CHUNK_SAMPLES as u64);
    let image = w
        .saturating_mul(h)
        .saturating_mul(FILM_BYTES_PER_PIXEL)
        .saturating_add(in_flight.saturating_mul(SAMPLE_BYTES_IN_FLIGHT * cores.min(h.max(1))));
    // An instanced group's tree is built once; each instance is one primitive of the top tree.
    let instancing = &scene.instancing;
    let primitives = scene.primitive_count() - instancing.triangle_count()
        + instancing.stored_triangle_count()
        + instancing.instances.len();
    let accel = (primitives as u64).saturating_mul(ACCEL_BYTES_PER_PRIMITIVE);
    vec![("image", image), ("acceleration structure", accel)]
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

/// `Plan::boundary_media`: each material's media inside and outside, and the camera's.
fn boundary_media(scene: &Scene) -> Vec<String> {
    let sides = |i: usize, m: &crate::scene::Material| {
        let side = |k: Option<usize>, side: &str| k.map(|k| format!("medium {k} {side}"));
        let both: Vec<String> = [
            side(m.interior_medium, "inside"),
            side(m.exterior_medium, "outside"),
        ]
        .into_iter()
        .flatten()
        .collect();
        (!both.is_empty()).then(|| format!("material {i}: {}", both.join(", ")))
    };
    let camera = scene
        .camera_medium
        .map(|k| format!("the camera in medium {k}"));
    scene
        .materials
        .iter()
        .enumerate()
        .filter_map(|(i, m)| sides(i, m))
        .chain(camera)
        .collect()
}

fn shape_counts(scene: &Scene) -> Vec<(&'static str, usize)> {
    let mut counts: Vec<(&'static str, usize)> = Vec::new();
    for s in &scene.shapes {
        let name = s.shape.name();
        match counts.iter_mut().find(|c| c.0 == name) {
            Some(c) => c.1 += 1,
            None => counts.push((name, 1)),
        }
    }
    counts
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
        let sided = |one_sided| if one_sided { "one-sided" } else { "two-sided" };
        if self.quads > 0 {
            writeln!(
                f,
                "quad geometry: {} ({})",
                plural(self.quads, "quad", "quads"),
                sided(self.culled.quads)
            )?;
        } else {
            writeln!(f, "quad geometry: none")?;
        }
        if self.triangles > 0 {
            writeln!(
                f,
                "triangle geometry: {} ({})",
                plural(self.triangles, "triangle", "triangles"),
                sided(self.culled.triangles)
            )?;
        } else {
            writeln!(f, "triangle geometry: none")?;
        }
        if let Some((instances, groups, stored, placed)) = self.instancing {
            writeln!(
                f,
                "instancing: {} of {}: {} stored, {} instanced",
                plural(instances, "instance", "instances"),
                plural(groups, "shapegroup", "shapegroups"),
                plural(stored, "triangle", "triangles"),
                plural(placed, "triangle", "triangles"),
            )?;
        }
        let mut user = Vec::new();
        for &(name, count) in &self.shapes {
            user.push(plural(count, name, &format!("{name}s")));
        }
        if user.is_empty() {
            writeln!(f, "user geometry: none")?;
        } else {
            writeln!(f, "user geometry: {}", user.join(", "))?;
        }
        writeln!(f, "textures decoded: {}", self.textures)?;
        if self.height_maps > 0 {
            writeln!(f, "bump height images decoded: {}", self.height_maps)?;
        }
        // Nothing of procedural patterns is evaluated for a scene without them.
        if self.patterns.is_empty() {
            writeln!(f, "procedural textures and bumps: none")?;
        } else {
            writeln!(
                f,
                "procedural textures and bumps: {} (filtered over each pixel's footprint)",
                self.patterns.join("; ")
            )?;
        }
        if !self.bsdfs.is_empty() {
            writeln!(
                f,
                "mitsuba bsdfs, as the {} engine renders them:",
                self.engine.name()
            )?;
            for line in &self.bsdfs {
                writeln!(f, "  {line}")?;
            }
        }
        write!(f, "emitters: {}", self.emitters)?;
        if self.lights_without_area > 0 {
            write!(f, ", lights without area: {}", self.lights_without_area)?;
        }
        writeln!(f)?;
        // Nothing of media or skies is built or traced for a scene without them.
        writeln!(f, "fog: {}", self.fog.as_deref().unwrap_or("none"))?;
        if !self.boundary_media.is_empty() {
            writeln!(f, "media at boundaries: {}", self.boundary_media.join("; "))?;
        }
        if !self.emission_textures.is_empty() {
            writeln!(
                f,
                "textured radiance: {}",
                self.emission_textures.join("; ")
            )?;
        }
        writeln!(f, "sky: {}", self.sky.as_deref().unwrap_or("none"))?;
        for (name, what) in &self.structures {
            writeln!(f, "{name}: {what}")?;
        }
        writeln!(f, "memory estimate: {}", self.memory_summary())?;
        Ok(())
    }
}
