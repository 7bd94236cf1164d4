//! Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991), the second `RadiositySolver`.
//!
//! Each input patch is the root of a quadtree of elements. Light is carried by links between
//! elements: a link from source S to receiver R holds the form factor F_RS, so that R gathers
//! F_RS · B_S. Links start between every pair of input patches that can see each other and
//! are refined while the light a link gets wrong by carrying one value over its receiver,
//! A_R · (spread of F over R) · B_S, exceeds `link_error` times the largest emitted power:
//! the larger of the two elements (if it is still larger than `min_element_area`) is split
//! into four and the link replaced by links to its children. Between refinements, Jacobi
//! sweeps over the fixed links gather at every element, push the gathered light down the
//! quadtrees and pull the radiosity back up, until the change of power falls under the
//! tolerance; then the links are refined again with the new radiosities, until none needs it.
//!
//! A link's form factor is the exact point-to-polygon form factor averaged over four points of
//! the receiver, times the fraction of four point pairs an occlusion ray finds unblocked; the
//! rays of a refinement pass go to the Accel in batches. Each leaf's gathered light is scaled
//! so that its links' form factors are those of its own points (`leaf_scales`): a closed box
//! then neither loses nor creates light.
//!
//! Parameters (defaults in `RadiositySettings`): `--link-error` (1e-4), `--min-element-area`
//! (1e-5 of the scene's area), `--radiosity-tolerance`.
//!
//! Not yet here: clustering (Smits, Arvo & Greenberg 1994), so the initial linking is k² in
//! the input patches; that is what large scenes still need.

use std::sync::atomic::Ordering::Relaxed;
use std::time::Instant;

use rayon::prelude::*;

use super::form_factor::point_to_polygon;
use super::patch::{on_primitive, Patch};
use super::solver::{
    FormFactorSampler, PatchLight, RadiositySolver, ShotRecord, SolveLimits, Solved, Stop,
};
use crate::geometry::{quad_normal, shadow_ray, Ray, Vec3};
use crate::sampling::Rng;
use crate::scene::Color;

/// No element.
const NONE: u32 = u32::MAX;
/// Point pairs per link.
const PAIRS: usize = 4;
/// Links evaluated by one parallel task (their rays go to the Accel as one batch).
const LINK_CHUNK: usize = 256;
/// Refinement rounds at most (each followed by a solve).
const MAX_ROUNDS: u32 = 12;

pub struct Hierarchical {
    /// Refine a link carrying more than this fraction of the largest emitted power.
    pub link_error: f32,
    /// Elements smaller than this fraction of the scene's area are not split.
    pub min_element_area: f32,
}

/// One node of a patch's quadtree.
#[derive(Clone, Copy, Debug)]
struct Element {
    patch: u32,
    corners: [Vec3; 4],
    area: f32,
    normal: Vec3,
    /// The bilinear point at (0.5, 0.5).
    centre: Vec3,
    /// The first of four consecutive children, or `NONE` for a leaf.
    children: u32,
}

impl Element {
    fn new(patch: u32, corners: [Vec3; 4], normal: Vec3) -> Element {
        Element {
            patch,
            corners,
            area: 0.5 * quad_normal(&corners).length(),
            normal,
            centre: bilinear(&corners, 0.5, 0.5),
            children: NONE,
        }
    }

    /// The bilinear point at (s, t) ∈ [0,1]².
    fn point(&self, s: f32, t: f32) -> Vec3 {
        bilinear(&self.corners, s, t)
    }

    /// Four children along the midpoints of the edges (a triangle, stored as [a, b, c, c],
    /// gives two triangles and two quads covering it).
    fn split(&self) -> [[Vec3; 4]; 4] {
        let [a, b, c, d] = self.corners;
        let mid = |p: Vec3, q: Vec3| (p + q) * 0.5;
        let (ab, bc, cd, da) = (mid(a, b), mid(b, c), mid(c, d), mid(d, a));
        let m = self.centre;
        [
            [a, ab, m, da],
            [ab, b, bc, m],
            [m, bc, c, cd],
            [da, m, cd, d],
        ]
    }
}

fn bilinear(corners: &[Vec3; 4], s: f32, t: f32) -> Vec3 {
    let [a, b, c, d] = *corners;
    (a * (1.0 - s) + b * s) * (1.0 - t) + (d * (1.0 - s) + c * s) * t
}

/// A link: `receiver` gathers `form_factor` × the radiosity of `source`. 16 bytes (checked
/// below).
#[derive(Clone, Copy, Debug)]
struct Link {
    receiver: u32,
    source: u32,
    /// Visibility included.
    form_factor: f32,
    /// How much the form factor varies over the receiver (what the oracle weighs), as the
    /// top half of an f32's bits: the oracle needs no more than its first digits.
    spread: u16,
    /// Point pairs found unblocked, of `PAIRS`.
    open: u16,
}

const _: () = assert!(std::mem::size_of::<Link>() == 16);

impl Link {
    fn spread(&self) -> f32 {
        f32::from_bits((self.spread as u32) << 16)
    }
    fn visible(&self) -> f32 {
        self.open as f32 / PAIRS as f32
    }
}

/// The quadtrees and their light.
struct Hierarchy<'a> {
    patches: &'a [Patch],
    elements: Vec<Element>,
    /// Outgoing radiance of each element (inner elements: the area mean of their children).
    radiance: Vec<Color>,
}

impl<'a> Hierarchy<'a> {
    fn new(patches: &'a [Patch]) -> Hierarchy<'a> {
        let elements: Vec<Element> = patches
            .iter()
            .enumerate()
            .map(|(i, p)| Element::new(i as u32, p.corners, p.normal))
            .collect();
        let radiance = patches.iter().map(|p| p.emitted).collect();
        Hierarchy {
            patches,
            elements,
            radiance,
        }
    }

    /// The children of `e`, made on first use.
    fn children(&mut self, e: u32) -> u32 {
        let el = self.elements[e as usize];
        if el.children != NONE {
            return el.children;
        }
        let first = self.elements.len() as u32;
        for corners in el.split() {
            self.elements
                .push(Element::new(el.patch, corners, el.normal));
            self.radiance.push(self.radiance[e as usize]);
        }
        self.elements[e as usize].children = first;
        first
    }

    /// Receiver point `k` of element `e`: the centres of its 2×2 strata, jittered a little
    /// so that points of regular scenes do not fall exactly on other geometry's edges.
    fn sample(&self, e: u32, k: usize, seed: u64) -> Vec3 {
        let mut rng = Rng::new(seed ^ 0x41e7_a2c1, e as u64, k as u64);
        let jitter = |r: f32| 0.25 + 0.5 * (r - 0.5) * 0.2;
        let (s, t) = ((k % 2) as f32 * 0.5, (k / 2) as f32 * 0.5);
        self.elements[e as usize].point(s + jitter(rng.next_f32()), t + jitter(rng.next_f32()))
    }
}

/// The top half of an f32's bits (bfloat16): 8 bits of mantissa.
fn half_bits(x: f32) -> u16 {
    (x.to_bits() >> 16) as u16
}

/// For each leaf, how the form factors of the links that reach it — its own and its
/// ancestors' — change when they are all taken at the leaf's own points: Σ F(leaf points,
/// S)·V over Σ F̄(receiver points, S)·V. Taken at one point, the form factors to the sources of
/// those links (a partition of what the point can see) sum to exactly that point's coverage;
/// taken at the points of coarser receivers they drift near edges (leaves of the closed cube
/// otherwise sum to between 0.91 and 1.5). Scaling a leaf's gathered light by the ratio gives
/// every leaf its own points' coverage, so a closed scene neither loses nor creates light,
/// while the share of each source stays the coarse link's. Elements that are not leaves get 1.
fn leaf_scales(h: &Hierarchy, links: &[Link], seed: u64) -> Vec<f32> {
    let n = h.elements.len();
    // The links of each receiver, as ranges of `order`.
    let mut start = vec![0u32; n + 1];
    for l in links {
        start[l.receiver as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut order = vec![0u32; links.len()];
    for (k, l) in links.iter().enumerate() {
        let slot = &mut fill[l.receiver as usize];
        order[*slot as usize] = k as u32;
        *slot += 1;
    }
    let by_receiver = |e: u32| &order[start[e as usize] as usize..start[e as usize + 1] as usize];
    let per_root: Vec<Vec<(u32, f32)>> = (0..h.patches.len() as u32)
        .into_par_iter()
        .map(|root| {
            let mut out = Vec::new();
            let mut chain = Vec::new();
            let mut stack = vec![(root, 0usize)];
            // Depth first; `chain` holds the links of the element's ancestors and its own.
            while let Some((e, depth)) = stack.pop() {
                chain.truncate(depth);
                chain.extend_from_slice(by_receiver(e));
                let el = &h.elements[e as usize];
                if el.children != NONE {
                    let depth = chain.len();
                    stack.extend((el.children..el.children + 4).map(|c| (c, depth)));
                    continue;
                }
                let points: [Vec3; PAIRS] = std::array::from_fn(|k| h.sample(e, k, seed));
                let (mut coarse, mut own) = (0.0f64, 0.0f64);
                for &k in &chain {
                    let l = &links[k as usize];
                    coarse += l.form_factor as f64;
                    if l.receiver == e {
                        own += l.form_factor as f64;
                        continue;
                    }
                    let source = &h.elements[l.source as usize].corners;
                    let f: f32 = points
                        .iter()
                        .map(|&x| point_to_polygon(x, el.normal, source))
                        .sum();
                    own += (f / PAIRS as f32 * l.visible()) as f64;
                }
                let scale = if coarse > 1e-9 {
                    (own / coarse) as f32
                } else {
                    1.0
                };
                out.push((e, scale));
            }
            out
        })
        .collect();
    let mut scales = vec![1.0f32; n];
    for (e, scale) in per_root.into_iter().flatten() {
        scales[e as usize] = scale;
    }
    scales
}

/// Whether some corner of each element lies strictly in front of the other's plane.
fn may_see(r: &Element, s: &Element) -> bool {
    let in_front = |a: &Element, b: &Element| {
        let c = a.centre;
        b.corners.iter().any(|&p| (p - c).dot(a.normal) > 0.0)
    };
    in_front(r, s) && in_front(s, r)
}

impl Hierarchical {
    /// The link of each (receiver, source) pair: its form factor, visibility included, and
    /// how much it varies over the receiver (the spread of the point form factors, or the
    /// whole form factor where some point pairs are blocked and others not).
    fn links(&self, h: &Hierarchy, sampler: &FormFactorSampler, pairs: &[(u32, u32)]) -> Vec<Link> {
        let scene = sampler.scene();
        let seed = sampler.seed();
        let mut out: Vec<Link> = pairs
            .iter()
            .map(|&(receiver, source)| Link {
                receiver,
                source,
                form_factor: 0.0,
                spread: 0,
                open: PAIRS as u16,
            })
            .collect();
        out.par_chunks_mut(LINK_CHUNK)
            .zip(pairs.par_chunks(LINK_CHUNK))
            .for_each(|(out, pairs)| {
                let mut rays: Vec<Ray> = Vec::new();
                let mut owners: Vec<usize> = Vec::new();
                for (o, &(r, s)) in pairs.iter().enumerate() {
                    let (re, se) = (&h.elements[r as usize], &h.elements[s as usize]);
                    let xs: [Vec3; PAIRS] = std::array::from_fn(|k| h.sample(r, k, seed));
                    let (mut sum, mut lo, mut hi) = (0.0f32, f32::INFINITY, 0.0f32);
                    for &x in &xs {
                        let f = point_to_polygon(x, re.normal, &se.corners);
                        (sum, lo, hi) = (sum + f, lo.min(f), hi.max(f));
                    }
                    out[o].form_factor = sum / PAIRS as f32;
                    out[o].spread = half_bits(hi - lo);
                    if out[o].form_factor <= 0.0 || !sampler.visibility() {
                        continue;
                    }
                    let (rp, sp) = (&h.patches[re.patch as usize], &h.patches[se.patch as usize]);
                    // Pair receiver point k with a source point whose index is shifted per
                    // link, so that no stratum pairs only with its mirror image.
                    let shift = 1 + (r ^ s) as usize;
                    for (k, &x) in xs.iter().enumerate() {
                        let y = h.sample(s, (k + shift) % PAIRS, seed);
                        let from = on_primitive(scene, rp, x, y - x);
                        rays.push(shadow_ray(from, on_primitive(scene, sp, y, x - y)));
                        owners.push(o);
                    }
                }
                if rays.is_empty() {
                    return;
                }
                let mut blocked = vec![false; rays.len()];
                sampler.accel().occluded_batch(&rays, &mut blocked);
                sampler.rays.fetch_add(rays.len() as u64, Relaxed);
                for &o in owners.iter().step_by(PAIRS) {
                    out[o].open = 0;
                }
                for (&o, b) in owners.iter().zip(&blocked) {
                    out[o].open += u16::from(!b);
                }
                for &o in owners.iter().step_by(PAIRS) {
                    let l = &mut out[o];
                    if l.open > 0 && l.open < PAIRS as u16 {
                        l.spread = half_bits(l.form_factor.max(l.spread()));
                    }
                    l.form_factor *= l.visible();
                }
            });
        out
    }

    /// Refines `candidates` (pairs to evaluate) into final links: a pair carrying more than
    /// `threshold` power is replaced by pairs with the children of its larger element.
    fn refine(
        &self,
        h: &mut Hierarchy,
        sampler: &FormFactorSampler,
        mut candidates: Vec<(u32, u32)>,
        threshold: f32,
        min_area: f32,
        links: &mut Vec<Link>,
    ) {
        while !candidates.is_empty() {
            let evaluated = self.links(h, sampler, &candidates);
            let mut next = Vec::new();
            for link in evaluated {
                if link.form_factor <= 0.0 {
                    continue;
                }
                let (r, s) = (link.receiver, link.source);
                let (re, se) = (h.elements[r as usize], h.elements[s as usize]);
                // What the link gets wrong by carrying one value over the receiver.
                let error = re.area * link.spread() * h.radiance[s as usize].max_element();
                let split_receiver = re.area >= se.area;
                let larger = if split_receiver { re } else { se };
                if error > threshold && larger.area > min_area {
                    let first = h.children(if split_receiver { r } else { s });
                    for c in first..first + 4 {
                        let pair = if split_receiver { (c, s) } else { (r, c) };
                        let (a, b) = (&h.elements[pair.0 as usize], &h.elements[pair.1 as usize]);
                        if a.area > 0.0 && b.area > 0.0 && may_see(a, b) {
                            next.push(pair);
                        }
                    }
                } else {
                    links.push(link);
                }
            }
            candidates = next;
        }
    }
}

/// Gathers over the links, pushes the gathered radiance down each quadtree (scaled at the
/// leaves by `scales`, see `leaf_scales`) and pulls the radiosity back up. Returns each
/// element's incident radiance (at a leaf its own and its ancestors' gathering; above, the
/// area mean of its leaves') and the new radiance of every element.
fn sweep(
    h: &Hierarchy,
    links: &[Link],
    scales: &[f32],
    sources: &[Color],
) -> (Vec<Color>, Vec<Color>) {
    let mut gathered = vec![Vec3::ZERO; h.elements.len()];
    for l in links {
        gathered[l.receiver as usize] += sources[l.source as usize] * l.form_factor;
    }
    let mut light = Light {
        incident: vec![Vec3::ZERO; h.elements.len()],
        radiance: vec![Vec3::ZERO; h.elements.len()],
    };
    for root in 0..h.patches.len() as u32 {
        push_pull(h, root, Vec3::ZERO, &gathered, scales, &mut light);
    }
    (light.incident, light.radiance)
}

/// Per element: incident and outgoing radiance.
struct Light {
    incident: Vec<Color>,
    radiance: Vec<Color>,
}

/// Pushes `from_above` plus `e`'s own gathering down to the leaves below `e`, and returns
/// the area means of their (incident, outgoing) radiance.
fn push_pull(
    h: &Hierarchy,
    e: u32,
    from_above: Color,
    gathered: &[Color],
    scales: &[f32],
    light: &mut Light,
) -> (Color, Color) {
    let el = &h.elements[e as usize];
    let total = from_above + gathered[e as usize];
    let (incident, radiance) = if el.children == NONE {
        let p = &h.patches[el.patch as usize];
        let total = total * scales[e as usize];
        (total, p.emitted + p.albedo * total)
    } else {
        let (mut incident, mut radiance) = (Vec3::ZERO, Vec3::ZERO);
        let mut area = 0.0;
        for c in el.children..el.children + 4 {
            let a = h.elements[c as usize].area;
            let (i, b) = push_pull(h, c, total, gathered, scales, light);
            incident += i * a;
            radiance += b * a;
            area += a;
        }
        if area > 0.0 {
            (incident * area.recip(), radiance * area.recip())
        } else {
            (total, Vec3::ZERO)
        }
    };
    light.incident[e as usize] = incident;
    light.radiance[e as usize] = radiance;
    (incident, radiance)
}

impl RadiositySolver for Hierarchical {
    fn solve(
        &self,
        sampler: &FormFactorSampler,
        limits: &SolveLimits,
        on_step: &dyn Fn(f32),
    ) -> Solved {
        let start = Instant::now();
        let patches = sampler.patches();
        let mut h = Hierarchy::new(patches);
        let power = |l: &[Color]| -> f32 {
            patches
                .iter()
                .zip(l)
                .map(|(p, c)| p.area * c.max_element())
                .sum()
        };
        let emitted_power: Vec<f32> = patches
            .iter()
            .map(|p| p.area * p.emitted.max_element())
            .collect();
        let largest = emitted_power.iter().copied().fold(0.0, f32::max);
        let total_emitted: f32 = emitted_power.iter().sum();
        let scene_area: f32 = patches.iter().map(|p| p.area).sum();
        let threshold = self.link_error * largest;
        let min_area = self.min_element_area * scene_area;

        // Every pair of input patches that can see each other, refined with B = emission.
        let n = patches.len() as u32;
        let initial: Vec<(u32, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|r| {
                let h = &h;
                (0..n).filter_map(move |s| {
                    let (a, b) = (&h.elements[r as usize], &h.elements[s as usize]);
                    (r != s && a.area > 0.0 && b.area > 0.0 && may_see(a, b)).then_some((r, s))
                })
            })
            .collect();
        let mut links = Vec::new();
        self.refine(&mut h, sampler, initial, threshold, min_area, &mut links);
        let mut scales = leaf_scales(&h, &links, sampler.seed());

        let mut light = PatchLight::default();
        // Set by every sweep; the loop below makes at least one.
        let mut incident;
        let mut stop = Stop::Converged;
        let mut sweeps = 0u64;
        let mut rounds = 0;
        loop {
            // Sweeps over the fixed links until the change of power is under the tolerance.
            loop {
                let (inc, radiance) = sweep(&h, &links, &scales, &h.radiance);
                let before = power(&h.radiance[..patches.len()]);
                let change = (power(&radiance[..patches.len()]) - before).abs();
                h.radiance = radiance;
                incident = inc;
                sweeps += 1;
                light.residual = if total_emitted > 0.0 {
                    change / total_emitted
                } else {
                    0.0
                };
                on_step(light.residual);
                if limits.log {
                    light.log.push(ShotRecord {
                        shot: sweeps,
                        patch: links.len() as u32,
                        residual: light.residual,
                        seconds: start.elapsed().as_secs_f64(),
                        rays: sampler.rays.load(Relaxed),
                    });
                }
                if light.residual <= limits.tolerance {
                    break;
                }
                if limits.iterations.is_some_and(|k| sweeps >= k) || sweeps >= limits.cap {
                    stop = Stop::Cap;
                    break;
                }
            }
            rounds += 1;
            if stop == Stop::Cap || rounds >= MAX_ROUNDS {
                break;
            }
            // Refine the links that now carry too much (their sources have brightened).
            let (keep, again): (Vec<Link>, Vec<Link>) = links.iter().partition(|l| {
                let re = &h.elements[l.receiver as usize];
                re.area * l.spread() * h.radiance[l.source as usize].max_element() <= threshold
            });
            if again.is_empty() {
                break;
            }
            links = keep;
            let candidates = again.iter().map(|l| (l.receiver, l.source)).collect();
            self.refine(&mut h, sampler, candidates, threshold, min_area, &mut links);
            scales = leaf_scales(&h, &links, sampler.seed());
        }

        // What came straight from the emitters: one gather of the emission alone.
        let emission: Vec<Color> = h
            .elements
            .iter()
            .map(|e| patches[e.patch as usize].emitted)
            .collect();
        let (direct, _) = sweep(&h, &links, &scales, &emission);
        light.radiance = h.radiance[..patches.len()].to_vec();
        light.incident = incident[..patches.len()].to_vec();
        light.incident_direct = direct[..patches.len()].to_vec();
        light.undistributed = vec![Vec3::ZERO; patches.len()];
        light.iterations = sweeps;
        let leaves = h.elements.iter().filter(|e| e.children == NONE).count();
        Solved {
            light,
            stop,
            report: format!(
                "hierarchical: {} input patches, {} elements ({} leaves), {} links ({:.1} MiB), {} sweeps in {} refinement rounds",
                patches.len(),
                h.elements.len(),
                leaves,
                links.len(),
                (links.len() * std::mem::size_of::<Link>()) as f64 / (1 << 20) as f64,
                sweeps,
                rounds
            ),
        }
    }
}
