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
}

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
        if !engine.is_implemented() {
            notes.push(format!(
                "the {} engine is not implemented yet",
                engine.name()
            ));
        }
        Plan {
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
            radiosity_patches: if radiosity_mesh {
                radiosity_patches(scene, settings)
            } else {
                0
            },
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
        for note in &self.notes {
            writeln!(f, "note: {note}")?;
        }
        Ok(())
    }
}
