//! Progressive refinement (Cohen, Chen, Wallace & Greenberg 1988): repeatedly shoot the patch
//! with the most undistributed power to every other patch. The form factors of one shot are
//! gathered at the receivers (Wallace, Elmquist & Haines 1989): each receiver averages the
//! exact point-to-patch form factor over its sample points, which keeps every receiver's
//! form factors to a closed enclosure summing to one. Rows are computed when a patch shoots
//! and kept in a cache of bounded size, never as an N×N matrix.

use std::collections::HashMap;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Instant;

use rayon::prelude::*;

use super::form_factor::point_to_polygon;
use super::patch::{on_primitive, Patch};
use crate::accel::Accel;
use crate::geometry::{shadow_ray, Ray, Vec3};
use crate::sampling::{Pattern, Rng, Strata};
use crate::scene::{Color, Scene};

/// Receivers handled by one parallel task (their visibility rays go to the Accel as a batch).
const RECEIVER_CHUNK: usize = 64;

/// What the form factors of a shot are computed from.
pub struct FormFactorSampler<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    patches: &'a [Patch],
    /// Point pairs per form factor (1: the centres).
    samples: u32,
    /// Test each pair with an occlusion ray.
    visibility: bool,
    seed: u64,
    /// With one sample per form factor: where each patch's visibility rays start and end.
    anchors: Vec<Vec3>,
    /// Visibility rays cast so far.
    pub rays: AtomicU64,
}

impl<'a> FormFactorSampler<'a> {
    pub fn new(
        scene: &'a Scene,
        accel: &'a dyn Accel,
        patches: &'a [Patch],
        samples: u32,
        visibility: bool,
        seed: u64,
    ) -> FormFactorSampler<'a> {
        let samples = samples.max(1);
        let anchors = if visibility && samples == 1 {
            patches
                .iter()
                .enumerate()
                .map(|(k, p)| on_primitive(scene, p, nudge(seed, k, p), p.normal))
                .collect()
        } else {
            Vec::new()
        };
        FormFactorSampler {
            scene,
            accel,
            patches,
            samples,
            visibility,
            seed,
            anchors,
            rays: AtomicU64::new(0),
        }
    }

    /// Point `k` of receiver `j`: the same points whichever patch shoots, so that a receiver's
    /// form factors to a closed enclosure sum to exactly one.
    fn receiver_point(&self, j: usize, k: u32) -> Vec3 {
        let p = &self.patches[j];
        if self.samples <= 1 {
            return p.centre;
        }
        let mut rng = Rng::new(self.seed, j as u64, k as u64);
        let (s, t) = Strata::new(Pattern::Jittered, self.samples).sample(k, &mut rng);
        p.point(s, t)
    }

    /// Point `k` of shooter `i` paired with receiver `j`: its stratum is shifted by a random
    /// offset per pair, so every pair of strata is equally likely.
    fn shooter_point(&self, i: usize, j: usize, k: u32) -> Vec3 {
        let p = &self.patches[i];
        let n = self.samples;
        if n <= 1 {
            return p.centre;
        }
        let pair = (i as u64) << 32 | j as u64;
        let mut rng = Rng::new(self.seed ^ 0x5eed_5eed, pair, 0);
        let shift = (rng.next_u64() % n as u64) as u32;
        let mut rng = Rng::new(self.seed ^ 0x5eed_5eed, pair, k as u64 + 1);
        let (s, t) = Strata::new(Pattern::Jittered, n).sample((k + shift) % n, &mut rng);
        p.point(s, t)
    }

    /// F_ji for every receiver j with shooter i: the fraction of the light leaving j that
    /// arrives at i (0 for i itself).
    pub fn row(&self, i: usize) -> Vec<f32> {
        let n = self.patches.len();
        let mut out = vec![0.0f32; n];
        let shooter = &self.patches[i];
        if shooter.area <= 0.0 {
            return out;
        }
        out.par_chunks_mut(RECEIVER_CHUNK)
            .enumerate()
            .for_each(|(c, out)| {
                let mut rays: Vec<Ray> = Vec::new();
                let mut owners: Vec<(usize, f32)> = Vec::new();
                for (o, slot) in out.iter_mut().enumerate() {
                    let j = c * RECEIVER_CHUNK + o;
                    let r = &self.patches[j];
                    if j == i || r.area <= 0.0 || !may_see(r, shooter) {
                        continue;
                    }
                    for k in 0..self.samples.max(1) {
                        let x = self.receiver_point(j, k);
                        // Light leaves the shooter from its front side only.
                        if (x - shooter.centre).dot(shooter.normal) <= 0.0 {
                            continue;
                        }
                        let f = point_to_polygon(x, r.normal, &shooter.corners);
                        if f <= 0.0 {
                            continue;
                        }
                        if !self.visibility {
                            *slot += f;
                            continue;
                        }
                        let (from, to) = if self.samples == 1 {
                            (self.anchors[j], self.anchors[i])
                        } else {
                            let y = self.shooter_point(i, j, k);
                            let from = on_primitive(self.scene, r, x, y - x);
                            (from, on_primitive(self.scene, shooter, y, x - y))
                        };
                        rays.push(shadow_ray(from, to));
                        owners.push((o, f));
                    }
                }
                if !rays.is_empty() {
                    let mut blocked = vec![false; rays.len()];
                    self.accel.occluded_batch(&rays, &mut blocked);
                    self.rays.fetch_add(rays.len() as u64, Relaxed);
                    for (&(o, f), b) in owners.iter().zip(blocked) {
                        if !b {
                            out[o] += f;
                        }
                    }
                }
                let scale = 1.0 / self.samples.max(1) as f32;
                out.iter_mut().for_each(|f| *f *= scale);
            });
        out
    }
}

/// The centre of patch `k` moved a tenth of the way towards a random point of the patch:
/// where its visibility rays start and end when form factors take one sample. Patch centres
/// of regular scenes lie exactly on the planes and edges of other geometry (in the course's
/// L-shaped room, rays between centres pass through its inner corner; in a room of boxes on
/// a grid, floor centres lie on the boxes' side faces), where Embree's and our BVH's edge
/// rules decide differently. Moved a thousandth of a patch, 5 of 9.7 million rays of l.obj
/// (subdivided 4 times) and 18 of 12.7 million of a 4,820-patch room still disagreed; moved
/// a tenth, none did.
fn nudge(seed: u64, k: usize, p: &Patch) -> Vec3 {
    let mut rng = Rng::new(seed ^ 0x00d6_e000, k as u64, 0);
    let towards = p.point(rng.next_f32(), rng.next_f32());
    p.centre + (towards - p.centre) * 0.1
}

/// Whether any point of `r` could receive light from the front of `s`: some corner of each
/// is strictly in front of the other's plane.
fn may_see(r: &Patch, s: &Patch) -> bool {
    let in_front = |a: &Patch, b: &Patch| {
        b.corners
            .iter()
            .any(|&p| (p - a.centre).dot(a.normal) > 0.0)
    };
    in_front(r, s) && in_front(s, r)
}

/// Rows of form factors kept between shots, within a memory budget. Progressive refinement
/// revisits its shooters in a roughly cyclic order, which defeats least-recently-used
/// eviction (measured: 101 hits in 22,249 shots of a 4,820-patch room with room for a fifth
/// of the rows); the rows kept are instead those of the patches that have shot most often
/// (least-frequently-used eviction), since a patch that shot often will shoot again.
pub struct RowCache {
    rows: HashMap<usize, Rc<[f32]>>,
    /// Times each patch has asked for its row.
    uses: Vec<u32>,
    budget_bytes: usize,
    bytes: usize,
    pub hits: u64,
    pub misses: u64,
    pub peak_bytes: usize,
}

impl RowCache {
    pub fn new(patches: usize, budget_bytes: usize) -> RowCache {
        RowCache {
            rows: HashMap::new(),
            uses: vec![0; patches],
            budget_bytes,
            bytes: 0,
            hits: 0,
            misses: 0,
            peak_bytes: 0,
        }
    }

    pub fn get_or_insert(&mut self, i: usize, compute: impl FnOnce() -> Vec<f32>) -> Rc<[f32]> {
        self.uses[i] += 1;
        if let Some(row) = self.rows.get(&i) {
            self.hits += 1;
            return row.clone();
        }
        self.misses += 1;
        let row: Rc<[f32]> = compute().into();
        let size = std::mem::size_of_val(&*row);
        if size > self.budget_bytes {
            return row;
        }
        if self.bytes + size > self.budget_bytes {
            // Replace the least used cached row, if this patch has been used more.
            let Some((&victim, _)) = self.rows.iter().min_by_key(|(&k, _)| (self.uses[k], k))
            else {
                return row;
            };
            if self.uses[victim] >= self.uses[i] {
                return row;
            }
            if let Some(r) = self.rows.remove(&victim) {
                self.bytes -= std::mem::size_of_val(&*r);
            }
        }
        self.bytes += size;
        self.peak_bytes = self.peak_bytes.max(self.bytes);
        self.rows.insert(i, row.clone());
        row
    }
}

/// Why the solver stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// Undistributed power fell below the tolerance.
    Converged,
    /// The number of shots asked for (`--radiosity-iterations`) was reached.
    Iterations,
    /// The safety cap on shots was reached before the tolerance: the solution is incomplete.
    Cap,
    /// Nothing emits: the solution is dark.
    NoLight,
    /// Ctrl-C stopped the solve: the solution is incomplete.
    Interrupted,
}

/// One line of `--log-convergence`.
#[derive(Clone, Copy, Debug)]
pub struct ShotRecord {
    pub shot: u64,
    pub patch: u32,
    pub residual: f32,
    pub seconds: f64,
    pub rays: u64,
}

/// The state of a progressive solve: radiance per patch and what is left to shoot.
#[derive(Clone, Debug, Default)]
pub struct SolverState {
    /// Outgoing radiance L_i = Le_i + ρ_i · incident_i.
    pub radiance: Vec<Color>,
    /// Radiance received but not yet shot.
    pub unshot: Vec<Color>,
    /// Part of `unshot` that is emission (shot once, at the emitter's first shot).
    unshot_emission: Vec<Color>,
    /// Incident radiance averaged over the hemisphere (irradiance / π) gathered so far.
    pub incident: Vec<Color>,
    /// The part of `incident` that came straight from emitters.
    pub incident_direct: Vec<Color>,
    pub shots: u64,
    /// Undistributed power over emitted power.
    pub residual: f32,
    pub log: Vec<ShotRecord>,
}

pub struct SolveLimits {
    pub tolerance: f32,
    /// Stop after exactly this many shots (as the course's "after the top 16 patches have shot").
    pub iterations: Option<u64>,
    /// Safety cap when no iteration count is given.
    pub cap: u64,
    pub cache_bytes: usize,
    pub log: bool,
    /// Over-relaxation of each shot.
    pub relaxation: Relaxation,
}

/// The over-relaxation factor ω of each shot (`--radiosity-relaxation`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Relaxation {
    /// ω from the solve itself: the fraction μ of a shot's power that comes back as unshot
    /// power (a running mean over the shots: ρ in a furnace, less where light escapes) gives
    /// successive over-relaxation's ω = 2 / (1 + √(1 − μ²)), at most 1.95. Open and dark
    /// scenes get ω near 1 (plain shooting); bright closed rooms get ω near 2.
    Auto,
    /// A fixed ω in [1, 2); 1 is plain progressive refinement.
    Fixed(f32),
}

impl std::str::FromStr for Relaxation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Relaxation::Auto);
        }
        match s.parse::<f32>() {
            Ok(w) if (1.0..2.0).contains(&w) => Ok(Relaxation::Fixed(w)),
            _ => Err(format!("expected auto or a number in [1, 2), found {s}")),
        }
    }
}

/// Weight of each shot in the running mean of the returned fraction μ.
const RETURN_MEAN_WEIGHT: f32 = 0.02;

/// Power of a (possibly negative, when over-relaxing) radiance over an area, all channels.
fn power(c: Color, area: f32) -> f32 {
    (c.x.abs() + c.y.abs() + c.z.abs()) * area
}

/// Solves by progressive refinement until the limits stop it.
pub fn solve(
    sampler: &FormFactorSampler,
    limits: &SolveLimits,
    on_shot: impl Fn(f32),
) -> (SolverState, Stop, RowCache) {
    let patches = sampler.patches;
    let emitted: Vec<Color> = patches.iter().map(|p| p.emitted).collect();
    let mut s = SolverState {
        radiance: emitted.clone(),
        unshot: emitted.clone(),
        unshot_emission: emitted,
        incident: vec![Vec3::ZERO; patches.len()],
        incident_direct: vec![Vec3::ZERO; patches.len()],
        ..Default::default()
    };
    let mut cache = RowCache::new(patches.len(), limits.cache_bytes);
    let total_emitted: f64 = patches
        .iter()
        .map(|p| power(p.emitted, p.area) as f64)
        .sum();
    if total_emitted <= 0.0 {
        return (s, Stop::NoLight, cache);
    }
    let start = Instant::now();
    let mut returned: Option<f32> = None;
    let stop = loop {
        let (mut best, mut best_power, mut undistributed) = (0usize, -1.0f32, 0.0f64);
        for (i, (u, p)) in s.unshot.iter().zip(patches).enumerate() {
            let pw = power(*u, p.area);
            undistributed += pw as f64;
            if pw > best_power {
                best = i;
                best_power = pw;
            }
        }
        s.residual = (undistributed / total_emitted) as f32;
        on_shot(s.residual);
        if crate::interrupt::requested() {
            break Stop::Interrupted;
        }
        match limits.iterations {
            Some(k) if s.shots >= k => break Stop::Iterations,
            None if s.residual <= limits.tolerance => break Stop::Converged,
            None if s.shots >= limits.cap => break Stop::Cap,
            _ => {}
        }
        if best_power <= 0.0 {
            break Stop::Converged;
        }
        let row = cache.get_or_insert(best, || sampler.row(best));
        // Over-relaxation (ω > 1) shoots more than the patch holds; what it shot too much
        // stays behind as negative unshot radiance, shot back later. The patch's own
        // radiance is what it received, unchanged by shooting.
        let omega = match (limits.relaxation, returned) {
            (Relaxation::Fixed(w), _) => w,
            (Relaxation::Auto, None) => 1.0,
            (Relaxation::Auto, Some(mu)) => {
                (2.0 / (1.0 + (1.0 - mu * mu).max(0.0).sqrt())).min(1.95)
            }
        };
        let shot = s.unshot[best] * omega;
        let mut returned_power = 0.0f64;
        let shot_emission = s.unshot_emission[best] * omega;
        s.unshot[best] -= shot;
        s.unshot_emission[best] *= 1.0 - omega;
        for (j, &f) in row.iter().enumerate() {
            if f <= 0.0 {
                continue;
            }
            let arriving = shot * f;
            s.incident[j] += arriving;
            s.incident_direct[j] += shot_emission * f;
            let reflected = patches[j].albedo.mul_elem(arriving);
            returned_power += power(reflected, patches[j].area) as f64;
            s.radiance[j] += reflected;
            s.unshot[j] += reflected;
        }
        let shot_power = power(shot, patches[best].area) as f64;
        if shot_power > 0.0 {
            let mu = (returned_power / shot_power) as f32;
            returned = Some(returned.map_or(mu, |m| m + RETURN_MEAN_WEIGHT * (mu - m)));
        }
        s.shots += 1;
        if limits.log {
            s.log.push(ShotRecord {
                shot: s.shots,
                patch: best as u32,
                residual: s.residual,
                seconds: start.elapsed().as_secs_f64(),
                rays: sampler.rays.load(Relaxed),
            });
        }
    };
    (s, stop, cache)
}

/// The ambient term of Cohen et al. 1988 for display: the light not yet shot, spread evenly
/// and reflected by the average albedo, ambient = Σ ΔL_j A_j / Σ A_j / (1 − ρ_avg).
pub fn ambient(patches: &[Patch], unshot: &[Color]) -> Color {
    let area: f32 = patches.iter().map(|p| p.area).sum();
    if area <= 0.0 {
        return Vec3::ZERO;
    }
    let rho_avg = patches
        .iter()
        .map(|p| p.albedo * p.area)
        .fold(Vec3::ZERO, |a, b| a + b)
        / area;
    let undistributed = patches
        .iter()
        .zip(unshot)
        .map(|(p, u)| *u * p.area)
        .fold(Vec3::ZERO, |a, b| a + b)
        / area;
    let r = |rho: f32, u: f32| if rho < 1.0 { u / (1.0 - rho) } else { 0.0 };
    crate::geometry::vec3(
        r(rho_avg.x, undistributed.x),
        r(rho_avg.y, undistributed.y),
        r(rho_avg.z, undistributed.z),
    )
}
