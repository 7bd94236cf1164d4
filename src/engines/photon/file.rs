//! `--save-photons` / `--load-photons`: both maps in a versioned binary file (little-endian)
//! with a fingerprint of the scene file and the settings that shaped the photons, so that a file
//! made for another scene or other settings is refused with a clear error.
//!
//! Layout: magic `TRILUXPM`, version (u32), fingerprint (u64), photons emitted by the main and
//! by the caustic pass, photon rays, photons cut by the depth limit, global, caustic and volume
//! counts (u64 each), then each photon: position, direction, power, normal (3 × f32 each) and
//! its path kind (u8). Version 2 added the caustic pass; version 3 keys the file by the loaded
//! scene (materials, textures, `--two-sided`, media, sky), not the scene file's bytes; version
//! 4 added the volume map.

use std::io::{Read, Write};
use std::path::Path;

use super::{PathKind, Photon, PhotonMaps};
use crate::engines::engine::RenderSettings;
use crate::geometry::vec3;
use crate::output::{write_atomically, OutputError};
use crate::sampling::mix64;
use crate::scene::Scene;

const MAGIC: &[u8; 8] = b"TRILUXPM";
const VERSION: u32 = 4;
const HEADER_BYTES: usize = 8 + 4 + 8 * 8;
const PHOTON_BYTES: usize = 12 * 4 + 1;

/// A hash of the loaded scene (materials with their `.mtl` file, textures, `--two-sided`:
/// `Scene::content_hash`) and of every setting that changes which photons are stored: their
/// numbers (main and caustic pass), the depth limit, the seed, and whether the global map
/// keeps all photons (final gathering).
pub fn fingerprint(scene: &Scene, settings: &RenderSettings) -> u64 {
    let p = &settings.photon;
    let mut h = scene.content_hash();
    for v in [
        settings.photons(),
        settings.caustic_photons(),
        p.max_photon_depth as u64,
        settings.seed,
        p.gather_indirect as u64,
    ] {
        h = mix64(h ^ v);
    }
    h
}

impl PhotonMaps {
    pub fn save(&self, path: &Path, fingerprint: u64) -> Result<(), OutputError> {
        write_atomically(path, |w| {
            let io = |source| OutputError::Io {
                path: path.to_path_buf(),
                source,
            };
            w.write_all(MAGIC).map_err(io)?;
            w.write_all(&VERSION.to_le_bytes()).map_err(io)?;
            for v in [
                fingerprint,
                self.emitted,
                self.caustic_emitted,
                self.rays,
                self.truncated,
                self.global.len() as u64,
                self.caustic.len() as u64,
                self.volume.len() as u64,
            ] {
                w.write_all(&v.to_le_bytes()).map_err(io)?;
            }
            let maps = [&self.global, &self.caustic, &self.volume];
            for p in maps.iter().flat_map(|m| &m.photons) {
                for v in [p.position, p.direction, p.power, p.normal] {
                    for c in v.to_array() {
                        w.write_all(&c.to_le_bytes()).map_err(io)?;
                    }
                }
                w.write_all(&[p.kind as u8]).map_err(io)?;
            }
            Ok(())
        })
    }

    /// Reads maps saved for this scene and these settings; lookups use the current settings.
    pub fn load(
        path: &Path,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> Result<PhotonMaps, String> {
        let name = path.display();
        let mut data = Vec::new();
        std::fs::File::open(path)
            .and_then(|mut f| f.read_to_end(&mut data))
            .map_err(|e| format!("{name}: cannot read photon file: {e}"))?;
        if data.len() < HEADER_BYTES || &data[..8] != MAGIC {
            return Err(format!("{name}: not a trilux photon file"));
        }
        let u32_at = |o: usize| u32::from_le_bytes(data[o..o + 4].try_into().unwrap_or_default());
        let u64_at = |o: usize| u64::from_le_bytes(data[o..o + 8].try_into().unwrap_or_default());
        let version = u32_at(8);
        if version != VERSION {
            return Err(format!(
                "{name}: photon file version {version}; this trilux reads version {VERSION}"
            ));
        }
        let expected = fingerprint(scene, settings);
        if u64_at(12) != expected {
            return Err(format!(
                "{name}: these photons were made for another scene or other settings (scene file, -num_photons_to_shoot, --caustic-photons, --max-photon-depth, --seed and -gather_indirect must match {})",
                scene.path.display()
            ));
        }
        let (emitted, caustic_emitted) = (u64_at(20), u64_at(28));
        let (rays, truncated) = (u64_at(36), u64_at(44));
        let (n_global, n_caustic, n_volume) = (u64_at(52), u64_at(60), u64_at(68));
        let count = n_global
            .checked_add(n_caustic)
            .and_then(|n| n.checked_add(n_volume))
            .and_then(|n| usize::try_from(n).ok())
            .filter(|&n| n.checked_mul(PHOTON_BYTES) == Some(data.len() - HEADER_BYTES))
            .ok_or_else(|| {
                format!("{name}: the file is truncated or damaged ({n_global} + {n_caustic} + {n_volume} photons announced, {} bytes of photons)", data.len() - HEADER_BYTES)
            })?;
        let f32_at = |o: usize| f32::from_le_bytes(data[o..o + 4].try_into().unwrap_or_default());
        let vec_at = |o: usize| vec3(f32_at(o), f32_at(o + 4), f32_at(o + 8));
        let mut photons: Vec<Photon> = Vec::with_capacity(count);
        for k in 0..count {
            let o = HEADER_BYTES + k * PHOTON_BYTES;
            let kind = match data[o + 48] {
                0 => PathKind::Direct,
                1 => PathKind::Caustic,
                2 => PathKind::Indirect,
                other => return Err(format!("{name}: photon {k} has unknown kind {other}")),
            };
            let photon = Photon {
                position: vec_at(o),
                direction: vec_at(o + 12),
                power: vec_at(o + 24),
                normal: vec_at(o + 36),
                kind,
            };
            if !(photon.position.is_finite() && photon.power.is_finite()) {
                return Err(format!("{name}: photon {k} is not finite"));
            }
            photons.push(photon);
        }
        let volume = photons.split_off((n_global + n_caustic) as usize);
        let caustic = photons.split_off(n_global as usize);
        let mut maps = PhotonMaps::from_photons(scene, settings, [photons, caustic, volume]);
        maps.emitted = emitted;
        maps.caustic_emitted = caustic_emitted;
        maps.rays = rays;
        maps.truncated = truncated;
        Ok(maps)
    }
}
