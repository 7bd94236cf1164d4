//! `--save-radiosity` / `--load-radiosity`: a solved radiosity solution in a versioned binary
//! file (little-endian) with a fingerprint of the scene and of the settings that shape the
//! solution, so that a render farm solves once and every task renders from the same light, and
//! a file made for another scene or other settings is refused with a clear error.
//!
//! The mesh is not stored: it is rebuilt from the scene and the settings (the shapes'
//! tessellation), the level the faces were subdivided to and the faces each round of splits
//! split (where lights without area light them unevenly, then `--adaptive-subdivide`'s), which
//! the file keeps. Layout: magic `TRILUXRS`, version (u32), fingerprint (u64), solver (u8: 1
//! progressive, 2 hierarchical), stop (u8), visibility rays (u64), steps (u64), residual (f32),
//! ambient (3 × f32), patches (u64), elements (u64), rounds of splits (u32) each as a count
//! (u32) and its faces (u32 each), how many of them were `--adaptive-subdivide`'s (u32), the
//! subdivision level (u32), the solver's report (u32 length, UTF-8), then per patch its
//! radiance, undistributed, incident and direct incident radiance (4 × 3 × f32), then per
//! element its patch (u32), corners (4 × 3 × f32), first child (u32), radiance and incident
//! radiance (2 × 3 × f32).

use std::path::Path;

use super::solver::{Element, PatchLight, Stop};
use super::{patch, patch_of_face, RadiositySettings, Solution, SolverKind};
use crate::engines::engine::RenderSettings;
use crate::geometry::{vec3, Vec3};
use crate::output::{write_atomically, OutputError};
use crate::scene::Scene;

const MAGIC: &[u8; 8] = b"TRILUXRS";
/// 2: the level the mesh was subdivided to is stored (`subdivide_to_fit` chooses it).
const VERSION: u32 = 3;

/// A hash of the loaded scene (`Scene::content_hash`) and of every setting that shapes the
/// solution: the radiosity settings but those of the display and the output, whether form
/// factors test visibility (`-num_shadow_samples` > 0) and the seed.
pub fn fingerprint(scene: &Scene, settings: &RenderSettings) -> u64 {
    let r = RadiositySettings {
        interpolate: false,
        wireframe: false,
        ff_source: None,
        log_convergence: false,
        display: Default::default(),
        export: None,
        save: None,
        load: None,
        ff_cache_mb: 0,
        memory_budget: 0,
        ..settings.radiosity.clone()
    };
    crate::scene::hash_text(&format!(
        "{:016x} {r:?} visibility {} seed {}",
        scene.content_hash(),
        settings.num_shadow_samples > 0,
        settings.seed
    ))
}

fn stop_code(stop: Stop) -> u8 {
    match stop {
        Stop::Converged => 0,
        Stop::Iterations => 1,
        Stop::Cap => 2,
        Stop::NoLight => 3,
        Stop::Interrupted => 4,
        Stop::TimeLimit => 5,
        Stop::Diverged => 6,
    }
}

/// The bytes of a file, written in order.
#[derive(Default)]
struct Bytes(Vec<u8>);

impl Bytes {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn vec(&mut self, v: Vec3) {
        v.to_array().into_iter().for_each(|c| self.f32(c));
    }
}

/// Reads a file's bytes in order; running past the end is the file's fault, reported.
struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let bytes = self
            .data
            .get(self.at..self.at + N)
            .ok_or("the file is truncated")?;
        self.at += N;
        Ok(bytes.try_into().unwrap_or([0; N]))
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.take()?))
    }
    fn vec(&mut self) -> Result<Vec3, String> {
        Ok(vec3(self.f32()?, self.f32()?, self.f32()?))
    }
    /// A count of items of at least `bytes` each that the rest of the file can hold.
    fn count(&mut self, bytes: usize) -> Result<usize, String> {
        let n = self.u64()?;
        usize::try_from(n)
            .ok()
            .filter(|n| n.saturating_mul(bytes) <= self.data.len() - self.at)
            .ok_or_else(|| format!("the file announces {n} items it cannot hold (truncated?)"))
    }
}

impl Solution {
    /// Writes the solution (atomically) with the fingerprint of its scene and settings.
    pub fn save(&self, path: &Path, fingerprint: u64) -> Result<(), OutputError> {
        let mut b = Bytes::default();
        b.0.extend_from_slice(MAGIC);
        b.u32(VERSION);
        b.u64(fingerprint);
        b.u8(match self.solver {
            SolverKind::Hierarchical => 2,
            _ => 1,
        });
        b.u8(stop_code(self.stop));
        b.u64(self.rays);
        b.u64(self.state.iterations);
        b.f32(self.state.residual);
        b.vec(self.ambient);
        b.u64(self.patches.len() as u64);
        b.u64(self.state.elements.len() as u64);
        b.u32(self.splits.len() as u32);
        for round in &self.splits {
            b.u32(round.len() as u32);
            round.iter().for_each(|&f| b.u32(f));
        }
        b.u32(self.adaptive_rounds);
        b.u32(self.subdivide);
        b.u32(self.solver_report.len() as u32);
        b.0.extend_from_slice(self.solver_report.as_bytes());
        let s = &self.state;
        for k in 0..self.patches.len() {
            for v in [
                s.radiance[k],
                s.undistributed[k],
                s.incident[k],
                s.incident_direct[k],
            ] {
                b.vec(v);
            }
        }
        for e in &s.elements {
            b.u32(e.patch);
            e.corners.iter().for_each(|&c| b.vec(c));
            b.u32(e.children);
            b.vec(e.radiance);
            b.vec(e.incident);
        }
        write_atomically(path, |w| {
            use std::io::Write;
            w.write_all(&b.0).map_err(OutputError::io(path))
        })
    }

    /// Reads a solution saved for this scene and these settings, rebuilding its mesh.
    pub fn load(path: &Path, scene: &Scene, settings: &RenderSettings) -> Result<Solution, String> {
        let name = path.display();
        let data = std::fs::read(path)
            .map_err(|e| format!("{name}: cannot read the radiosity file: {e}"))?;
        if data.len() < 12 || &data[..8] != MAGIC {
            return Err(format!("{name}: not a trilux radiosity file"));
        }
        let mut r = Reader { data: &data, at: 8 };
        let read = |r: &mut Reader| -> Result<Solution, String> {
            let version = r.u32()?;
            if version != VERSION {
                return Err(format!(
                    "radiosity file version {version}; this trilux reads version {VERSION}"
                ));
            }
            if r.u64()? != fingerprint(scene, settings) {
                return Err(format!(
                    "this solution was made for another scene or other settings (the scene {}, the radiosity flags that shape the solution, -num_shadow_samples on or off and --seed must match)",
                    scene.path.display()
                ));
            }
            let solver = match r.u8()? {
                2 => SolverKind::Hierarchical,
                _ => SolverKind::Progressive,
            };
            let code = r.u8()?;
            let stop = [
                Stop::Converged,
                Stop::Iterations,
                Stop::Cap,
                Stop::NoLight,
                Stop::Interrupted,
                Stop::TimeLimit,
                Stop::Diverged,
            ]
            .into_iter()
            .find(|&s| stop_code(s) == code)
            .ok_or_else(|| format!("unknown stop code {code}"))?;
            let rays = r.u64()?;
            let iterations = r.u64()?;
            let residual = r.f32()?;
            let ambient = r.vec()?;
            let n_patches = r.count(48)?;
            let n_elements = r.count(80)?;
            let rounds = r.u32()?;
            let mut splits = Vec::new();
            for _ in 0..rounds {
                let n = r.u32()? as usize;
                if n.saturating_mul(4) > r.data.len() - r.at {
                    return Err("the file is truncated".into());
                }
                splits.push((0..n).map(|_| r.u32()).collect::<Result<Vec<_>, _>>()?);
            }
            let adaptive_rounds = r.u32()?.min(rounds);
            let subdivide = r.u32()?;
            let report_len = r.u32()? as usize;
            let report = r
                .data
                .get(r.at..r.at + report_len)
                .ok_or("the file is truncated")?;
            let report = String::from_utf8_lossy(report).into_owned();
            r.at += report_len;

            // Each face becomes 4^subdivide patches: more than the file holds is damage, and
            // is not built.
            if 4u64
                .checked_pow(subdivide)
                .is_none_or(|p| p > n_patches as u64)
            {
                return Err(format!(
                    "the mesh subdivided {subdivide} times, for {n_patches} patches (damaged?)"
                ));
            }
            let (mut mesh, _) = Solution::initial_mesh(scene, &settings.radiosity, subdivide);
            for round in &splits {
                if round.iter().any(|&f| f as usize >= mesh.faces.len()) {
                    return Err("a split face is not in the mesh".into());
                }
                mesh.split_many(round);
            }
            let patches = patch::patches(scene, &mesh);
            if patches.len() != n_patches {
                return Err(format!(
                    "the file holds {n_patches} patches, the scene's mesh has {}",
                    patches.len()
                ));
            }
            let mut state = PatchLight {
                iterations,
                residual,
                ..Default::default()
            };
            for _ in 0..n_patches {
                state.radiance.push(r.vec()?);
                state.undistributed.push(r.vec()?);
                state.incident.push(r.vec()?);
                state.incident_direct.push(r.vec()?);
            }
            for _ in 0..n_elements {
                let patch = r.u32()?;
                let corners = [r.vec()?, r.vec()?, r.vec()?, r.vec()?];
                let children = r.u32()?;
                let (radiance, incident) = (r.vec()?, r.vec()?);
                let child_ok = children == super::NONE
                    || children
                        .checked_add(3)
                        .is_some_and(|last| (last as usize) < n_elements);
                if patch as usize >= n_patches || !child_ok {
                    return Err("an element refers past the elements".into());
                }
                state.elements.push(Element {
                    patch,
                    corners,
                    children,
                    radiance,
                    incident,
                });
            }
            if r.at != r.data.len() {
                return Err(format!(
                    "{} bytes after the solution (damaged?)",
                    r.data.len() - r.at
                ));
            }
            let (visibility, visibility_reason) = Solution::visibility(scene, settings);
            let twins = patch::twins(&patches)
                .iter()
                .filter(|&&t| t != super::NONE)
                .count();
            Ok(Solution {
                patch_of_face: patch_of_face(&mesh, &patches),
                mesh,
                patches,
                state,
                stop,
                ambient,
                visibility,
                visibility_reason,
                rays,
                solver_report: format!("loaded from {name} ({report})"),
                solver_counters: Vec::new(),
                solver_warning: None,
                adaptive_rounds,
                subdivide,
                splits,
                solver,
                twins,
            })
        };
        read(&mut r).map_err(|e| format!("{name}: {e}"))
    }
}
