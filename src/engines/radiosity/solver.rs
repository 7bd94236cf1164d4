//! The solver interface of the radiosity engine and what every solver shares: the form factors
//! between patches (`FormFactorSampler`: exact point-to-patch integration, visibility rays
//! through the Accel), the solver-neutral result (`PatchLight`, `Stop`), and the ambient term.
//! The solvers themselves are beside it (`progressive.rs`).
//!
//! Form factors are gathered at the receivers (Wallace, Elmquist & Haines 1989): each receiver
//! averages the exact point-to-patch form factor over its sample points, which keeps every
//! receiver's form factors to a closed enclosure summing to one.

use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use rayon::prelude::*;

use super::mesh::NONE;
use super::patch::{on_primitive, Patch};
pub use super::settings::Relaxation;
use crate::accel::Accel;
use crate::geometry::form_factor::point_to_polygon;
use crate::geometry::{shadow_ray, Ray, Vec3};
use crate::sampling::{Pattern, Rng, Strata};
use crate::scene::{Color, Scene};

/// A fog whose channels' σt differ from their mean by at most this share of it is grey.
const GREY_FOG: f32 = 1e-6;
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
    anchors: Cow<'a, [Vec3]>,
    /// The fog's extinction σt (its channels' mean; 0 without fog): every form factor is
    /// attenuated by exp(−σt·d) along its point pairs.
    extinction: f32,
    /// A coloured fog's σt per channel less `extinction` (None for a grey fog or none): form
    /// factors are one number for all channels, so each channel's own share,
    /// exp(−Δσt·d), is applied where light is carried, at the distance between the two
    /// patches' centres (`tint`).
    tint_extinction: Option<Vec3>,
    /// Visibility rays cast so far.
    pub rays: AtomicU64,
}

impl<'a> FormFactorSampler<'a> {
    /// The sampler of the form factors between `patches`, `samples` point pairs each, with
    /// visibility rays if `visibility`, its points drawn from `seed`. `kept`: the anchors
    /// (`FormFactorSampler::anchors`) of these same arguments, where a caller keeps them
    /// between samplers; None: found here.
    pub fn new(
        scene: &'a Scene,
        accel: &'a dyn Accel,
        patches: &'a [Patch],
        samples: u32,
        visibility: bool,
        seed: u64,
        kept: Option<&'a [Vec3]>,
    ) -> FormFactorSampler<'a> {
        let anchors = match kept {
            Some(anchors) => Cow::Borrowed(anchors),
            None => Cow::Owned(Self::anchors(scene, patches, samples, visibility, seed)),
        };
        let samples = samples.max(1);
        let sigma_t = scene.fog.map_or(Vec3::ZERO, |k| scene.media[k].sigma_t());
        let extinction = sigma_t.element_sum() / 3.0;
        let tint_extinction = Some(sigma_t - Vec3::splat(extinction))
            .filter(|d| d.abs().max_element() > GREY_FOG * extinction);
        FormFactorSampler {
            scene,
            accel,
            patches,
            samples,
            visibility,
            seed,
            anchors,
            extinction,
            tint_extinction,
            rays: AtomicU64::new(0),
        }
    }

    /// What `new` finds first, which a caller may keep between samplers of the same patches
    /// and settings (a solve shot on a shot at a time, one sampler a shot): where each
    /// patch's visibility rays start and end, with one sample per form factor and visibility
    /// on; else nothing.
    pub fn anchors(
        scene: &Scene,
        patches: &[Patch],
        samples: u32,
        visibility: bool,
        seed: u64,
    ) -> Vec<Vec3> {
        if visibility && samples.max(1) == 1 {
            patches
                .iter()
                .enumerate()
                .map(|(k, p)| on_primitive(scene, p, nudge(seed, k, p), p.normal))
                .collect()
        } else {
            Vec::new()
        }
    }

    /// The patches the form factors connect.
    pub fn patches(&self) -> &'a [Patch] {
        self.patches
    }

    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// What visibility rays are cast against.
    pub fn accel(&self) -> &'a dyn Accel {
        self.accel
    }

    /// Whether form factors are tested for occlusion.
    pub fn visibility(&self) -> bool {
        self.visibility
    }

    /// Whether form factors are attenuated by a fog.
    pub fn in_fog(&self) -> bool {
        self.extinction > 0.0
    }

    /// The fog's transmittance between points `a` and `b` (1 without fog, the distance then
    /// not even computed: this runs for every point pair).
    pub fn transmittance(&self, a: Vec3, b: Vec3) -> f32 {
        if self.extinction > 0.0 {
            (-self.extinction * a.distance(b)).exp()
        } else {
            1.0
        }
    }

    /// Whether the fog is coloured: form factors then carry each channel by `tint`.
    pub fn tinted(&self) -> bool {
        self.tint_extinction.is_some()
    }

    /// Each channel's transmittance between the centres `a` and `b` relative to the mean
    /// channel's, which the form factors hold: exp(−(σt,c − σ̄t)·d), 1 in a grey fog. Taken at
    /// the centres rather than per point pair, it is exact where the pairs' distances agree —
    /// as they come to as patches shrink against their distance.
    pub fn tint(&self, a: Vec3, b: Vec3) -> Color {
        match self.tint_extinction {
            Some(d) => {
                let distance = a.distance(b);
                Vec3::new(
                    (-d.x * distance).exp(),
                    (-d.y * distance).exp(),
                    (-d.z * distance).exp(),
                )
            }
            None => Vec3::ONE,
        }
    }

    /// The seed of every sample point.
    pub fn seed(&self) -> u64 {
        self.seed
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
                            *slot += f * self.transmittance(x, shooter.centre);
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
                        owners.push((o, f * self.transmittance(from, to)));
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
    /// `--time-limit` stopped the solve (the ambient term shows the light not yet shot).
    TimeLimit,
    /// The undistributed light grew without bound (past the progressive solver's
    /// `DIVERGED_RESIDUAL` times what was emitted, or to NaN): no solution.
    Diverged,
}

/// One line of `--log-convergence`: a step of the solver (a shot, a sweep), with the
/// residual after it, the time and the visibility rays cast so far.
#[derive(Clone, Copy, Debug)]
pub struct ShotRecord {
    pub shot: u64,
    pub step: Step,
    pub residual: f32,
    pub seconds: f64,
    pub rays: u64,
}

/// What a step of the log was.
#[derive(Clone, Copy, Debug)]
pub enum Step {
    /// Progressive refinement: the patch that shot.
    Shot { patch: u32 },
    /// Hierarchical: a Jacobi sweep in refinement round `round`, over `links` links between
    /// `elements` elements.
    Sweep {
        round: u32,
        links: u64,
        elements: u64,
    },
}

/// What a solver found, in terms every solver gives: per-patch light, what the display
/// modes and the ray tracer read.
#[derive(Clone, Debug, Default)]
pub struct PatchLight {
    /// Outgoing radiance L_i = Le_i + ρ_i · incident_i.
    pub radiance: Vec<Color>,
    /// Radiance received but not yet distributed (progressive refinement's unshot radiance;
    /// `--visualize undistributed`, and the ambient term of the display).
    pub undistributed: Vec<Color>,
    /// Incident radiance averaged over the hemisphere (irradiance / π) gathered so far.
    pub incident: Vec<Color>,
    /// The part of `incident` that came straight from emitters.
    pub incident_direct: Vec<Color>,
    /// Steps taken: shots of progressive refinement, sweeps of an iterative solver.
    pub iterations: u64,
    /// Undistributed power over emitted power.
    pub residual: f32,
    /// One record per step, when asked (`--log-convergence`).
    pub log: Vec<ShotRecord>,
    /// A solver that splits patches (hierarchical): the quadtree of elements over each
    /// patch, patch k's root being element k. Empty when the patches are the elements.
    pub elements: Vec<Element>,
}

/// An element of a patch's quadtree, with its light.
#[derive(Clone, Copy, Debug)]
pub struct Element {
    /// The input patch it lies on.
    pub patch: u32,
    /// Corners in the patch's order (a triangle's as [a, b, c, c]); its four children cover
    /// the quarters (s, t) ∈ \[0,½\]², \[½,1\]×\[0,½\], \[½,1\]², \[0,½\]×\[½,1\] of its bilinear
    /// parameters, in that order.
    pub corners: [Vec3; 4],
    /// The first of four consecutive children, or `NONE` for a leaf.
    pub children: u32,
    pub radiance: Color,
    pub incident: Color,
}

impl PatchLight {
    /// The leaf element of patch `k` holding its point (s, t), and (s, t) within that leaf;
    /// the patch itself when it has no elements.
    pub fn leaf_at(&self, k: usize, mut s: f32, mut t: f32) -> (usize, f32, f32) {
        if self.elements.is_empty() {
            return (k, s, t);
        }
        let mut e = k;
        while self.elements[e].children != NONE {
            let (right, top) = (s >= 0.5, t >= 0.5);
            let quarter = match (right, top) {
                (false, false) => 0,
                (true, false) => 1,
                (true, true) => 2,
                (false, true) => 3,
            };
            e = self.elements[e].children as usize + quarter;
            s = if right { 2.0 * s - 1.0 } else { 2.0 * s };
            t = if top { 2.0 * t - 1.0 } else { 2.0 * t };
        }
        (e, s, t)
    }
}

impl PatchLight {
    /// Gives each twin patch (see `patch::twins`) its first copy's light.
    pub fn copy_twins(&mut self, twin_of: &[u32]) {
        for (i, &t) in twin_of.iter().enumerate() {
            if t != NONE {
                let t = t as usize;
                for field in [
                    &mut self.radiance,
                    &mut self.undistributed,
                    &mut self.incident,
                    &mut self.incident_direct,
                ] {
                    field[i] = field[t];
                }
                // The twin shows its copy's leaves (their corners are the copy's).
                if !self.elements.is_empty() {
                    self.elements[i] = self.elements[t];
                }
            }
        }
    }
}

/// When a solver stops, whatever the solver.
pub struct SolveLimits {
    /// Stop when the residual falls to this (`--radiosity-tolerance`).
    pub tolerance: f32,
    /// Stop after exactly this many steps (as the course's "after the top 16 patches have
    /// shot").
    pub iterations: Option<u64>,
    /// Safety cap on steps when no iteration count is given.
    pub cap: u64,
    /// Keep a record of every step.
    pub log: bool,
    /// Stop stepping then (`--time-limit`'s share for the solve).
    pub deadline: Option<std::time::Instant>,
}

impl SolveLimits {
    /// Whether the time for the solve is spent.
    pub fn out_of_time(&self) -> bool {
        self.deadline
            .is_some_and(|d| std::time::Instant::now() >= d)
    }
}

/// What a solve returns: the light, why it stopped, and a line of the solver's own counters.
pub struct Solved {
    pub light: PatchLight,
    pub stop: Stop,
    /// E.g. "form-factor rows 12 computed, 3 reused (cache peak 0.1 MiB)".
    pub report: String,
    /// Named counters for `--stats` (rows computed, links, elements, …).
    pub counters: Vec<(&'static str, u64)>,
    /// What the user should know about the solve (e.g. refinement stopped by memory).
    pub warning: Option<String>,
}

/// A radiosity solver: from the patches and their form factors (through the sampler, which
/// casts the visibility rays) to the light of every patch. Progressive refinement
/// (`Progressive`) is the first; the solver-neutral `Solution` holds what any of them found.
pub trait RadiositySolver {
    /// Solves until the limits stop it; `on_step` hears the residual after each step.
    fn solve(
        &self,
        sampler: &FormFactorSampler,
        limits: &SolveLimits,
        on_step: &dyn Fn(f32),
    ) -> Solved;
}

/// The ambient term of Cohen et al. 1988 for display: the light not yet distributed, spread evenly
/// and reflected by the average albedo, ambient = Σ ΔL_j A_j / Σ A_j / (1 − ρ_avg).
pub fn ambient(patches: &[Patch], undistributed: &[Color]) -> Color {
    let area: f32 = patches.iter().map(|p| p.area).sum();
    if area <= 0.0 {
        return Vec3::ZERO;
    }
    let rho_avg = patches
        .iter()
        .map(|p| p.albedo * p.area)
        .fold(Vec3::ZERO, |a, b| a + b)
        * area.recip();
    let mean = patches
        .iter()
        .zip(undistributed)
        .map(|(p, u)| *u * p.area)
        .fold(Vec3::ZERO, |a, b| a + b)
        * area.recip();
    let r = |rho: f32, u: f32| if rho < 1.0 { u / (1.0 - rho) } else { 0.0 };
    crate::geometry::vec3(
        r(rho_avg.x, mean.x),
        r(rho_avg.y, mean.y),
        r(rho_avg.z, mean.z),
    )
}
