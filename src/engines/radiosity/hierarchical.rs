//! Hierarchical radiosity with clustering (Hanrahan, Salzman & Aupperle 1991; Smits, Arvo &
//! Greenberg 1994; Sillion 1995), the second `RadiositySolver`.
//!
//! Nodes are of two kinds. Each input patch is the root of a quadtree of elements; above the
//! patches, a cluster hierarchy (a median-split BVH over the patches' centres) groups them up
//! to one root cluster. Light is carried by links: a link from source S to receiver R holds
//! the form factor F_RS, so that R gathers F_RS · B_S. Linking starts with the root cluster
//! linked to itself (or, up to `cluster_above` patches, with every pair of patches); a link
//! is refined — the node with the larger bounding radius split into its children, and the
//! link replaced by links between the children and the other node — while a cluster at
//! either end is not well separated from the other end (centres farther apart than
//! `SEPARATION` times the sum of the radii), or while the light the link gets wrong exceeds
//! `link_error` times the largest emitted power: A_R · F_RS · B_S for links with a cluster
//! at an end, A_R · (spread of F over R) · B_S between elements. Elements smaller than
//! `min_element_area` are not split. Between refinements, Jacobi sweeps gather at every node,
//! push the gathered light down (clusters to their members, elements to their children) and
//! pull the radiosity back up, until the change of power falls under the tolerance; then the
//! links are refined again with the new radiosities, until none needs it.
//!
//! Form factors: between elements, the exact point-to-polygon form factor averaged over four
//! points of the receiver, each counted where its visibility pair is unblocked; with a
//! cluster at an end, the isotropic-cluster estimate cos⁺θ_R · P_S / (π d²), P_S the
//! source's area projected towards R (a cluster's from its patches' area-weighted normals
//! in 26 direction buckets) and cos⁺θ_R at a cluster receiver its projected area towards S
//! over its area. What a cluster sends along a link is the mean
//! radiosity of its patches that face the receiver, each facing weighted by the area it
//! shows (`sent`), and a cluster holding an emitter sends nothing as one: it is split until
//! its emitters send as patches (`Hierarchy::holds_emitter`). Visibility: four point pairs
//! (cluster points chosen among its members by area, facing the other end) cast as
//! occlusion rays, a batch per 256 links, against the original geometry.
//!
//! Each leaf's gathered light is scaled, per channel, by what its links carry with their
//! form factors taken at its centre over what they carry as they are — the light straight
//! from the emission by one ratio, the light the sources reflect (weighted by the last
//! solution) by another (`update_leaf_scales`) — so that links at different levels do not
//! drift: a closed box then neither loses nor creates light. A leaf that is its whole patch
//! has links at one level only, taken at the same four points: they are kept as they are.
//! What the clusters above a patch hand down to a leaf is kept only up to the part of the
//! leaf's hemisphere its element links leave uncovered (`Carried::share_of_clusters`).
//!
//! Patches of no area (coincident twins, see `patch::twins`) take no part.
//!
//! Parameters (defaults in `RadiositySettings`): `--link-error` (1e-4), `--min-element-area`
//! (1e-5 of the scene's area), `--cluster-above` (2000), `--radiosity-tolerance`.

use std::ops::Range;
use std::sync::atomic::Ordering::Relaxed;
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::patch::{on_primitive, Patch};
use super::solver::{
    Element, FormFactorSampler, PatchLight, RadiositySolver, ShotRecord, SolveLimits, Solved, Step,
    Stop,
};
use crate::geometry::form_factor::point_to_polygon;
use crate::geometry::{quad_normal, shadow_ray, Bounds3, Ray, Vec3};
use crate::sampling::Rng;
use crate::scene::Color;

/// No node.
const NONE: u32 = u32::MAX;
/// Point pairs per link.
const PAIRS: usize = 4;
/// Links evaluated by one parallel task (their rays go to the Accel as one batch).
const LINK_CHUNK: usize = 256;
/// Candidate pairs a thread sorts into split and evaluated at a time.
const SPLIT_CHUNK: usize = 4096;
/// Refinement rounds at most (each followed by a solve).
const MAX_ROUNDS: u32 = 12;
/// Most patches a cluster holds directly.
const CLUSTER_LEAF: usize = 4;
/// A link with a cluster at an end needs its ends' centres farther apart than this many
/// times the sum of their radii. At 2 the isotropic estimate lost 1.1% of the reflected
/// power on the Cornell box with the sphere, linked from the root cluster (against the
/// progressive solver), and the clustered radiosity image of the course's sphere box strayed
/// 5.5% from the path tracer's on the back wall; at 4, +0.1% and 3.2%, for about 1.4× the
/// hospital's time (3 rather than 4: -0.1%, 3.8%, but 5.2% on the floor).
const SEPARATION: f32 = 4.0;
/// Draws of a cluster's patch that must face the link's other end before any is taken.
const CLUSTER_TRIES: usize = 8;

pub struct Hierarchical {
    /// Refine a link carrying more than this fraction of the largest emitted power.
    pub link_error: f32,
    /// Elements smaller than this fraction of the scene's area are not split.
    pub min_element_area: f32,
    /// Above this many input patches linking starts from the root cluster, up to it from
    /// every pair of patches.
    pub cluster_above: usize,
    /// Refinement stops splitting once the links and nodes would take more bytes than this.
    pub memory_budget: u64,
}

/// Bytes a link costs the solve at its peak: itself, the scratch of the stable sort by
/// receiver (half a link), and in the leaf scales what a link into a cluster carries
/// (`IntoCluster`, counted for every link).
const LINK_BYTES: usize = std::mem::size_of::<Link>() * 3 / 2 + std::mem::size_of::<IntoCluster>();
/// Bytes a node costs the solve: itself, its radiance and emission, the sweeps' incident,
/// gathered (direct and reflected) and new radiance, and its leaf scales.
const NODE_BYTES: usize = std::mem::size_of::<Node>()
    + 6 * std::mem::size_of::<Color>()
    + std::mem::size_of::<LeafScale>();

/// A node: an element of a patch's quadtree, or a cluster of patches.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// The input patch of an element; `NONE` for a cluster.
    patch: u32,
    /// An element's corners (a cluster's are its centre).
    corners: [Vec3; 4],
    area: f32,
    /// An element's unit normal (zero for a cluster).
    normal: Vec3,
    centre: Vec3,
    /// Radius of a sphere about `centre` holding the node.
    radius: f32,
    /// Elements: the first of four consecutive children, or `NONE` for a leaf. Clusters: the
    /// index of the cluster in `Hierarchy::clusters`.
    children: u32,
    /// The cluster this node is a member of (`NONE` for the root and for elements below
    /// a patch).
    parent: u32,
}

impl Node {
    fn element(patch: u32, corners: [Vec3; 4], normal: Vec3) -> Node {
        let centre = bilinear(&corners, 0.5, 0.5);
        let radius = corners
            .iter()
            .map(|&c| (c - centre).length())
            .fold(0.0, f32::max);
        Node {
            patch,
            corners,
            area: 0.5 * quad_normal(&corners).length(),
            normal,
            centre,
            radius,
            children: NONE,
            parent: NONE,
        }
    }

    fn is_cluster(&self) -> bool {
        self.patch == NONE
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

/// The index of the item `u` ∈ [0, 1) falls on when the items take shares of [0, 1) by
/// `weight` (some weight positive); rounding past the end gives the last weighted item.
fn by_weight<T>(items: &[T], weight: impl Fn(&T) -> f32, u: f32) -> usize {
    let total: f32 = items.iter().map(&weight).sum();
    let mut left = total * u;
    let mut last = 0;
    for (i, item) in items.iter().enumerate() {
        let w = weight(item);
        if w > 0.0 {
            if left < w {
                return i;
            }
            left -= w;
            last = i;
        }
    }
    last
}

/// Which of the 26 directions (i, j, k) ∈ {−1, 0, 1}³ other than 0, in that order, lies nearest to the
/// unit vector `n`.
fn nearest_direction(n: Vec3) -> usize {
    let mut best = (0, f32::NEG_INFINITY);
    let mut k = 0;
    for i in -1i32..=1 {
        for j in -1i32..=1 {
            for l in -1i32..=1 {
                if (i, j, l) == (0, 0, 0) {
                    continue;
                }
                let d = Vec3::new(i as f32, j as f32, l as f32);
                let c = n.dot(d) / d.length();
                if c > best.1 {
                    best = (k, c);
                }
                k += 1;
            }
        }
    }
    best.0
}

/// The bilinear point of a quad at (s, t) ∈ [0,1]².
fn bilinear(c: &[Vec3; 4], s: f32, t: f32) -> Vec3 {
    let [a, b, q, d] = *c;
    (a * (1.0 - s) + b * s) * (1.0 - t) + (d * (1.0 - s) + q * s) * t
}

/// A cluster: its members (nodes) and the range of `Hierarchy::members` its patches fill.
#[derive(Clone, Debug)]
struct Cluster {
    kids: Vec<u32>,
    bounds: Bounds3,
    /// Its patches grouped by the nearest of 26 directions (the faces, edges and corners of a
    /// cube), the groups that hold any, as a range of `Hierarchy::facings`: what its
    /// projected area in any direction is made of.
    facings: std::ops::Range<usize>,
    /// Whether one of its patches emits (see `Hierarchy::holds_emitter`).
    emits: bool,
    first: u32,
    end: u32,
}

/// A cluster's patches that face about one way (see `Cluster::facings`).
#[derive(Clone, Copy, Debug)]
struct Facing {
    /// Their area-weighted normals summed.
    normal: Vec3,
    area: f32,
    /// Which of the 26 directions (`nearest_direction`).
    direction: u8,
    /// Its patches, as a range of `Hierarchy::facing_members` (and `facing_areas`).
    first: u32,
    end: u32,
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
    /// The share of the form factor that reaches the receiver: the fraction of point pairs
    /// found unblocked, times their mean transmittance through a fog (1 without), as
    /// `half_bits` (exact for the fractions k/PAIRS).
    reach: u16,
}

const _: () = assert!(std::mem::size_of::<Link>() == 16);

impl Link {
    fn spread(&self) -> f32 {
        f32::from_bits((self.spread as u32) << 16)
    }
    fn visible(&self) -> f32 {
        f32::from_bits((self.reach as u32) << 16)
    }
}

/// The top half of an f32's bits (bfloat16: 8 bits of mantissa), rounded to the nearest:
/// truncated, every partly visible link's stored reach would lose up to 0.8%, always the
/// same way.
fn half_bits(x: f32) -> u16 {
    (x.to_bits().saturating_add(0x8000) >> 16) as u16
}

/// The clusters, the quadtrees and their light.
struct Hierarchy<'a> {
    patches: &'a [Patch],
    /// Patch roots first (node i is patch i), then clusters and elements as they are made.
    nodes: Vec<Node>,
    clusters: Vec<Cluster>,
    /// The root: the top cluster, or the one patch.
    top: u32,
    /// Patch indices in cluster order: every cluster's patches are a range of it.
    members: Vec<u32>,
    /// Each facing's patches (`Facing::first..end`), one facing's after another's.
    facing_members: Vec<u32>,
    /// Running sums of the areas of `facing_members` within each facing (the first
    /// patch's area, the first two's, …).
    facing_areas: Vec<f32>,
    /// Outgoing radiance of each node (inner nodes: the area mean of their children).
    radiance: Vec<Color>,
    /// Per patch, the nearest of the 26 directions to its normal (`nearest_direction`).
    patch_direction: Vec<u8>,
    /// The clusters' facings (`Cluster::facings`), one cluster's after another's.
    facings: Vec<Facing>,
}

impl<'a> Hierarchy<'a> {
    fn new(patches: &'a [Patch]) -> Hierarchy<'a> {
        let nodes: Vec<Node> = patches
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let mut node = Node::element(i as u32, p.corners, p.normal);
                // A patch of no area (a twin, see `patch::twins`) takes no part.
                if p.area <= 0.0 {
                    node.area = 0.0;
                }
                node
            })
            .collect();
        let mut h = Hierarchy {
            patches,
            nodes,
            clusters: Vec::new(),
            top: NONE,
            members: (0..patches.len() as u32).collect(),
            facing_members: Vec::new(),
            facing_areas: Vec::new(),
            radiance: Vec::new(),
            patch_direction: patches
                .iter()
                .map(|p| nearest_direction(p.normal) as u8)
                .collect(),
            facings: Vec::new(),
        };
        if !patches.is_empty() {
            let mut order = std::mem::take(&mut h.members);
            h.top = h.cluster(&mut order, 0);
            h.members = order;
        }
        // `sent` tells clusters by index: they follow the patches' roots, in their order.
        debug_assert!((0..h.clusters.len()).all(|c| {
            let node = h.node((patches.len() + c) as u32);
            node.is_cluster() && node.children as usize == c
        }));
        h.radiance = h.emission();
        for (node, e) in h.nodes.iter().zip(&h.radiance) {
            if node.is_cluster() {
                h.clusters[node.children as usize].emits = e.max_element() > 0.0;
            }
        }
        h
    }

    /// The node over `order` (patch indices, reordered in place so that each cluster's
    /// patches are consecutive), which starts at `first` of the whole order.
    fn cluster(&mut self, order: &mut [u32], first: u32) -> u32 {
        if order.len() == 1 {
            return order[0];
        }
        let bounds = order.iter().fold(Bounds3::default(), |b, &p| {
            b.union(Bounds3::from_points(&self.patches[p as usize].corners))
        });
        let kids = if order.len() <= CLUSTER_LEAF {
            order.to_vec()
        } else {
            let centres = order.iter().fold(Bounds3::default(), |b, &p| {
                b.union_point(self.nodes[p as usize].centre)
            });
            let axis = centres.extent().max_position();
            let half = order.len() / 2;
            order.select_nth_unstable_by(half, |&a, &b| {
                let (a, b) = (self.nodes[a as usize].centre, self.nodes[b as usize].centre);
                a[axis].total_cmp(&b[axis])
            });
            let (left, right) = order.split_at_mut(half);
            let l = self.cluster(left, first);
            let r = self.cluster(right, first + half as u32);
            vec![l, r]
        };
        let id = self.nodes.len() as u32;
        let area = kids.iter().map(|&k| self.nodes[k as usize].area).sum();
        let centre = bounds.centre();
        for &k in &kids {
            self.nodes[k as usize].parent = id;
        }
        self.nodes.push(Node {
            patch: NONE,
            corners: [centre; 4],
            area,
            normal: Vec3::ZERO,
            centre,
            radius: 0.5 * bounds.extent().length(),
            children: self.clusters.len() as u32,
            parent: NONE,
        });
        let mut normals = [Vec3::ZERO; 26];
        let mut areas = [0.0; 26];
        for &p in order.iter() {
            let patch = &self.patches[p as usize];
            let d = self.patch_direction[p as usize] as usize;
            normals[d] += patch.normal * patch.area;
            areas[d] += patch.area;
        }
        let start = self.facings.len();
        for d in (0..26).filter(|&d| areas[d] > 0.0) {
            let first = self.facing_members.len() as u32;
            let mut sum = 0.0;
            for &p in order.iter() {
                let area = self.patches[p as usize].area;
                if self.patch_direction[p as usize] as usize == d && area > 0.0 {
                    sum += area;
                    self.facing_members.push(p);
                    self.facing_areas.push(sum);
                }
            }
            self.facings.push(Facing {
                normal: normals[d],
                area: areas[d],
                direction: d as u8,
                first,
                end: self.facing_members.len() as u32,
            });
        }
        let facings = start..self.facings.len();
        self.clusters.push(Cluster {
            kids,
            bounds,
            facings,
            emits: false,
            first,
            end: first + order.len() as u32,
        });
        id
    }

    /// The emitted radiance of every node (area means above the patches).
    fn emission(&self) -> Vec<Color> {
        let mut e: Vec<Color> = self
            .nodes
            .iter()
            .map(|n| {
                if n.is_cluster() {
                    Vec3::ZERO
                } else {
                    self.patches[n.patch as usize].emitted
                }
            })
            .collect();
        // A cluster is made after its members, so in node order its members come first.
        for (k, node) in self.nodes.iter().enumerate() {
            if node.is_cluster() {
                let c = &self.clusters[node.children as usize];
                let sum = c
                    .kids
                    .iter()
                    .map(|&m| e[m as usize] * self.nodes[m as usize].area)
                    .fold(Vec3::ZERO, |a, b| a + b);
                e[k] = if node.area > 0.0 {
                    sum * node.area.recip()
                } else {
                    Vec3::ZERO
                };
            }
        }
        e
    }

    /// The elements, for display and export: the patches' roots first, then every element
    /// below them (clusters, which were made between the two, left out).
    fn elements(&self, incident: &[Color]) -> Vec<Element> {
        let (patches, clusters) = (self.patches.len(), self.clusters.len() as u32);
        // Clusters fill the nodes from the patches to the first element below a patch.
        let index = |n: u32| if n == NONE { NONE } else { n - clusters };
        self.nodes
            .iter()
            .enumerate()
            .filter(|(k, node)| *k < patches || !node.is_cluster())
            .map(|(k, node)| Element {
                patch: node.patch,
                corners: node.corners,
                children: index(node.children),
                radiance: self.radiance[k],
                incident: incident[k],
            })
            .collect()
    }

    fn node(&self, n: u32) -> &Node {
        &self.nodes[n as usize]
    }

    /// Makes an element's four children if it has none yet (a cluster's members exist from
    /// the start). Children are numbered in the order they are made, and the visibility
    /// points are drawn per node number: so they are made in one thread, in the order the
    /// refinement meets them.
    fn make_children(&mut self, n: u32) {
        let node = self.nodes[n as usize];
        if node.is_cluster() || node.children != NONE {
            return;
        }
        let first = self.nodes.len() as u32;
        for corners in node.split() {
            self.nodes
                .push(Node::element(node.patch, corners, node.normal));
            self.radiance.push(self.radiance[n as usize]);
        }
        self.nodes[n as usize].children = first;
    }

    /// The children of a node (made, see `make_children`): a cluster's members, or an
    /// element's four children.
    fn children(&self, n: u32) -> impl Iterator<Item = u32> + Clone + '_ {
        let node = self.node(n);
        let (members, quad): (&[u32], Range<u32>) = if node.is_cluster() {
            (&self.clusters[node.children as usize].kids, 0..0)
        } else {
            debug_assert!(node.children != NONE, "the children of {n} are not made");
            (&[], node.children..node.children + 4)
        };
        members.iter().copied().chain(quad)
    }

    /// Point `k` of node `n` and the patch it lies on. Elements: the centres of their 2×2
    /// strata, jittered a little so that points of regular scenes do not fall exactly on
    /// other geometry's edges. Clusters: a point of a member patch that faces `towards` (the
    /// other end of the link), chosen by area — a facing among those turned towards it
    /// as seen from the cluster's centre, then a patch of it, a few tries until the point
    /// itself faces `towards`; with no facing turned that way, any patch by area. A point on
    /// a patch turned away would find its own object in the way. (Drawing among all the
    /// patches until one faced took 3.5 draws a point on the hospital, each a wait for
    /// memory: a sixth of its solve.)
    fn sample(&self, n: u32, k: usize, seed: u64, towards: Vec3) -> (Vec3, u32) {
        let mut rng = Rng::new(seed ^ 0x41e7_a2c1, n as u64, k as u64);
        let node = self.node(n);
        if node.is_cluster() {
            let facings = &self.facings[self.clusters[node.children as usize].facings.clone()];
            let to = towards - node.centre;
            let turned = |f: &Facing| f.normal.dot(to) > 0.0;
            let none_turned = !facings.iter().any(turned);
            let mut pick = || {
                let weight = |f: &Facing| {
                    if none_turned || turned(f) {
                        f.area
                    } else {
                        0.0
                    }
                };
                let f = &facings[by_weight(facings, weight, rng.next_f32())];
                let sums = &self.facing_areas[f.first as usize..f.end as usize];
                let target = sums[sums.len() - 1] * rng.next_f32();
                let at = sums.partition_point(|&a| a <= target).min(sums.len() - 1);
                let patch = self.facing_members[f.first as usize + at];
                let p = &self.patches[patch as usize];
                (p.point(rng.next_f32(), rng.next_f32()), patch)
            };
            let mut found = pick();
            let tries = if none_turned { 0 } else { CLUSTER_TRIES };
            for _ in 0..tries {
                let p = &self.patches[found.1 as usize];
                if (towards - found.0).dot(p.normal) > 0.0 {
                    break;
                }
                found = pick();
            }
            return found;
        }
        let jitter = |r: f32| 0.25 + 0.5 * (r - 0.5) * 0.2;
        let (s, t) = ((k % 2) as f32 * 0.5, (k / 2) as f32 * 0.5);
        let point = bilinear(
            &node.corners,
            s + jitter(rng.next_f32()),
            t + jitter(rng.next_f32()),
        );
        (point, node.patch)
    }

    /// Whether light leaving `b` could reach the front of `a`: some point of `b`'s hull lies
    /// strictly in front of `a`'s plane (always, for a cluster `a`).
    fn in_front(&self, a: u32, b: u32) -> bool {
        let (a, b) = (self.node(a), self.node(b));
        if a.is_cluster() {
            return true;
        }
        let ahead = |p: Vec3| (p - a.centre).dot(a.normal) > 0.0;
        if b.is_cluster() {
            let bounds = self.clusters[b.children as usize].bounds;
            (0..8).any(|k| {
                let pick = |bit: usize, axis: usize| {
                    if k >> bit & 1 == 1 {
                        bounds.max[axis]
                    } else {
                        bounds.min[axis]
                    }
                };
                ahead(Vec3::new(pick(0, 0), pick(1, 1), pick(2, 2)))
            })
        } else {
            b.corners.iter().any(|&p| ahead(p))
        }
    }

    /// The largest form factor from a corner of element `r` (moved a hundredth of the way
    /// towards its centre) to element `s`; 0 when either is a cluster.
    fn corner_form_factor(&self, r: u32, s: u32) -> f32 {
        let node = self.node(r);
        if node.is_cluster() || self.node(s).is_cluster() {
            return 0.0;
        }
        node.corners
            .iter()
            .map(|&c| {
                let x = c + (node.centre - c) * 0.01;
                self.point_form_factor(x, r, Some(node.normal), s)
            })
            .fold(0.0, f32::max)
    }

    /// Whether `n` is a cluster holding an emitting patch: such a cluster never sends light
    /// as one, but is split until its emitters send as patches. As one, its visibility
    /// points are drawn by area, so a lamp's bulb shone through the outside of its shade,
    /// and the light of a ceiling panel left from the ceiling beside it: office3 lit only
    /// straight from its lamps had light on its ceiling, which none reaches, and its
    /// reflected power was 3.7% over the diffuse path tracer's (+1.3% with the split; L1
    /// 8.95% → 6.90%).
    fn holds_emitter(&self, n: u32) -> bool {
        let node = self.node(n);
        node.is_cluster() && self.clusters[node.children as usize].emits
    }

    /// Whether node `n` is an input patch never split: a leaf with no ancestors (see
    /// `update_leaf_scales`).
    fn is_whole_patch(&self, n: u32) -> bool {
        (n as usize) < self.patches.len() && self.node(n).children == NONE
    }

    fn may_see(&self, r: u32, s: u32) -> bool {
        let (a, b) = (self.node(r), self.node(s));
        a.area > 0.0 && b.area > 0.0 && self.in_front(r, s) && self.in_front(s, r)
    }

    /// Bounding spheres apart: a cluster's isotropic estimate then holds.
    fn separated(&self, r: u32, s: u32) -> bool {
        let (a, b) = (self.node(r), self.node(s));
        (a.centre - b.centre).length() > SEPARATION * (a.radius + b.radius)
    }

    /// The area of node `n` projected on the plane across `dir` (a unit vector), counting
    /// only surfaces that face along `dir`: A·cos⁺ for an element; for a cluster, Σ A·cos⁺
    /// over its patches, taken per direction bucket (exact where a bucket's patches are
    /// parallel, as in rooms of axis-aligned walls; a little under where they are not).
    fn projected_area(&self, n: u32, dir: Vec3) -> f32 {
        let node = self.node(n);
        if !node.is_cluster() {
            return node.area * node.normal.dot(dir).max(0.0);
        }
        self.facings[self.clusters[node.children as usize].facings.clone()]
            .iter()
            .map(|f| f.normal.dot(dir).max(0.0))
            .sum()
    }

    /// The form factor from point `x` of receiver `r` to node `s`: with `normal`, that of a
    /// surface at `x` (a leaf's points); without, `r`'s own (a cluster's mean over its
    /// patches).
    fn point_form_factor(&self, x: Vec3, r: u32, normal: Option<Vec3>, s: u32) -> f32 {
        let node = self.node(s);
        let normal = normal.or_else(|| (!self.node(r).is_cluster()).then(|| self.node(r).normal));
        if let (Some(n), false) = (normal, node.is_cluster()) {
            // An element sends light from its front only: a point behind its plane (under a
            // block standing on the floor, or in front of a two-sided wall's other side)
            // gets none of it, whatever the visibility rays, which start on the element's
            // lit side, would say.
            if (x - node.centre).dot(node.normal) <= 0.0 {
                return 0.0;
            }
            return point_to_polygon(x, n, &node.corners);
        }
        let (dir, shown) = self.towards(x, s);
        let receiver = match normal {
            Some(n) => n.dot(dir).max(0.0),
            None => {
                let a = self.node(r).area;
                if a > 0.0 {
                    self.projected_area(r, dir) / a
                } else {
                    0.0
                }
            }
        };
        receiver * shown
    }

    /// Node `s` seen from `x` as the isotropic estimate sees it: the direction to its centre
    /// (unit, or shorter within its bounding sphere), and its area projected that way over
    /// π d², so that a receiver at `x` facing along n gets the form factor cos⁺ × that.
    fn towards(&self, x: Vec3, s: u32) -> (Vec3, f32) {
        let node = self.node(s);
        let d = node.centre - x;
        let d2 = d.length_squared().max(node.radius * node.radius);
        let dir = d * d2.sqrt().recip();
        // A cluster's patches hide one another (the floors of a building stacked in one
        // cluster): what it shows is at most its bounding sphere's cross-section.
        let shown = self
            .projected_area(s, -dir)
            .min(std::f32::consts::PI * node.radius * node.radius);
        (dir, shown / (std::f32::consts::PI * d2))
    }
}

/// The most a leaf's form factors may sum to (see `update_leaf_scales`).
const MAX_COVERAGE: f64 = 1.2;

/// What a leaf's gathered light is multiplied by, per channel (see `update_leaf_scales`):
/// the light that left its sources as emission, and the light they reflected.
#[derive(Clone, Copy, Debug)]
struct LeafScale {
    direct: Color,
    reflected: Color,
    /// The share of the light handed down by the clusters above the leaf's patch that the
    /// leaf keeps (see `Carried::share_of_clusters`).
    from_clusters: f32,
}

/// What the links that reach a leaf carry, of the direct and of the reflected light: each
/// pair is (with the form factors taken at the leaf, as they are). Taken at the leaf: at its
/// centre, or for a leaf that is its whole patch as they are (see `update_leaf_scales`).
#[derive(Clone, Copy, Default)]
struct Carried {
    direct: (DVec3, DVec3),
    reflected: (DVec3, DVec3),
    /// The links' form factors summed as they are.
    covered: f64,
    /// The links' form factors taken at the leaf and summed, visibility included.
    at_leaf: f64,
}

impl Carried {
    /// Adds what link `l` carries as it is; `weights` per source: (emission, reflected
    /// radiosity).
    fn add_as_is(&mut self, l: &Link, weights: &[(Color, Color)]) {
        let (emitted, b) = weights[l.source as usize];
        let as_is = l.form_factor as f64;
        self.direct.1 += emitted.as_dvec3() * as_is;
        self.reflected.1 += b.as_dvec3() * as_is;
        self.covered += as_is;
    }

    /// Adds what link `l` carries taken at the leaf, where its form factor (visibility
    /// included) is `at_leaf`.
    fn add_at_leaf(&mut self, l: &Link, at_leaf: f32, weights: &[(Color, Color)]) {
        let (emitted, b) = weights[l.source as usize];
        let at_leaf = at_leaf as f64;
        self.direct.0 += emitted.as_dvec3() * at_leaf;
        self.reflected.0 += b.as_dvec3() * at_leaf;
        self.at_leaf += at_leaf;
    }

    /// Adds `other` times `share`.
    fn add_carried(&mut self, other: &Carried, share: f64) {
        self.direct.0 += other.direct.0 * share;
        self.direct.1 += other.direct.1 * share;
        self.reflected.0 += other.reflected.0 * share;
        self.reflected.1 += other.reflected.1 * share;
        self.covered += other.covered * share;
        self.at_leaf += other.at_leaf * share;
    }

    /// The share of `clusters` (what the clusters above a leaf hand down to it) a leaf keeps
    /// beside `self` (what its own and its ancestor elements' links bring): no more than
    /// the part of its hemisphere the elements' sources leave, measured at the leaf. A
    /// cluster's visibility points lie on the members that face its source, and it hands
    /// the light down to every member by orientation alone, so a member that sees only the
    /// inside of an object took the light the object's outside sees: the narrow top of
    /// office3's desk-lamp shade, a tube whose element links cover 0.83 of its hemisphere,
    /// took 0.55 more from the room through the clusters, and its reflected light, held at
    /// `MAX_COVERAGE`, came out at half the path tracer's.
    fn share_of_clusters(&self, clusters: &Carried) -> f64 {
        if clusters.at_leaf <= 0.0 {
            return 1.0;
        }
        ((1.0 - self.at_leaf).max(0.0) / clusters.at_leaf).min(1.0)
    }

    /// The leaf's scales, from what its element links carry (`self`) and what the clusters
    /// above its patch hand down (`clusters`, of which it keeps `share_of_clusters`): per
    /// channel, what the links carry taken at the leaf over what they carry as they are,
    /// the reflected light's held so that the scaled form factors sum to at most
    /// `MAX_COVERAGE`.
    fn scale(mut self, clusters: &Carried) -> LeafScale {
        let share = self.share_of_clusters(clusters);
        self.add_carried(clusters, share);
        // A point sees at most its whole hemisphere, but the scaled form factors can sum
        // past 1: clusters' isotropic estimates take them to 1.18 on the Cornell box with the
        // sphere, and overlapping surfaces (graz's desks, modelled through each other) to
        // about 2, where loops of links gained light and two-sided graz diverged. With the
        // reflected light's scaled form factors held at MAX_COVERAGE, a loop can gain only
        // between surfaces of albedo above 1/MAX_COVERAGE. (The direct light takes part in
        // no loop.)
        let most = MAX_COVERAGE / self.covered;
        let ratio = |(at_leaf, as_is): (DVec3, DVec3)| {
            let one = |a: f64, b: f64| if b > 0.0 { (a / b) as f32 } else { 1.0 };
            Vec3::new(
                one(at_leaf.x, as_is.x),
                one(at_leaf.y, as_is.y),
                one(at_leaf.z, as_is.z),
            )
        };
        LeafScale {
            direct: ratio(self.direct),
            reflected: ratio(self.reflected).min(Vec3::splat(most as f32)),
            from_clusters: share as f32,
        }
    }
}

/// A link into a cluster as the leaves below the cluster take it: the direction towards its
/// source from the cluster's centre, and its form factor there onto a surface facing that
/// way, so that a leaf of normal n takes cos⁺(n, dir) of what it carries (see
/// `update_leaf_scales`). What it carries is taken from its source's weights as it is added:
/// 16 bytes a link into a cluster (12 million of them in sixteen hospitals) rather than 40.
struct IntoCluster {
    dir: Vec3,
    /// The form factor onto a surface facing `dir`, visibility included.
    form_factor: f32,
}

impl IntoCluster {
    fn new(h: &Hierarchy, l: &Link) -> IntoCluster {
        let (dir, shown) = h.towards(h.node(l.receiver).centre, l.source);
        IntoCluster {
            dir,
            form_factor: shown * l.visible(),
        }
    }

    /// Adds what link `l` (the link this was made from) carries onto a leaf of normal
    /// `normal` to `to`; `weights` per source: (emission, reflected radiosity).
    fn add_at(&self, l: &Link, normal: Vec3, weights: &[(Color, Color)], to: &mut Carried) {
        let cos = normal.dot(self.dir).max(0.0) as f64;
        let (emitted, b) = weights[l.source as usize];
        to.direct.0 += (emitted * self.form_factor).as_dvec3() * cos;
        to.reflected.0 += (b * self.form_factor).as_dvec3() * cos;
        to.at_leaf += self.form_factor as f64 * cos;
    }
}

/// Calls `visit(leaf, chain)` for each leaf element below `root` (an input patch), depth
/// first, with the leaf's ancestors from `root` down and itself.
fn each_leaf(h: &Hierarchy, root: u32, mut visit: impl FnMut(u32, &[u32])) {
    let mut chain: Vec<u32> = Vec::new();
    let mut stack = vec![(root, 0)];
    while let Some((e, depth)) = stack.pop() {
        chain.truncate(depth);
        chain.push(e);
        let el = h.node(e);
        if el.children != NONE {
            let depth = chain.len();
            stack.extend((el.children..el.children + 4).map(|c| (c, depth)));
        } else {
            visit(e, &chain);
        }
    }
}

/// The form factors from each leaf's centre to the sources of the links that reach it (what
/// `update_leaf_scales` weighs; none for a leaf that is its whole patch), kept from one
/// update to the next: such a value depends only on the leaf and the source, and a
/// refinement keeps most links as they were, while the weights change every round. Kept
/// only while they fit in what `--max-memory` leaves beside the links and nodes.
struct CentreFormFactors {
    /// Per input patch, its leaves' values in the order `each_leaf` visits them, each leaf's
    /// in the order of its chain's links.
    per_patch: Vec<Vec<f32>>,
    /// Per node, where its values start in its patch's if it was a leaf at the last update
    /// (`NONE` if not).
    start: Vec<u32>,
    /// The links at the last update, if a refinement changed them since.
    previous: Option<Previous>,
    /// False once they did not fit: then taken afresh every time.
    keep: bool,
}

/// The links at the last update, as a refinement left them (see `CentreFormFactors`).
struct Previous {
    /// A bit per link: whether the refinement took it out to split it.
    refined: Vec<u64>,
    /// Their receivers' starts (`receiver_starts`).
    starts: Vec<u32>,
}

impl Previous {
    fn was_kept(&self, j: usize) -> bool {
        !bit(&self.refined, j)
    }

    /// Where the links of receiver `a` were.
    fn of(&self, a: u32) -> Range<usize> {
        self.starts[a as usize] as usize..self.starts[a as usize + 1] as usize
    }
}

impl CentreFormFactors {
    fn new(patches: usize) -> CentreFormFactors {
        CentreFormFactors {
            per_patch: vec![Vec::new(); patches],
            start: Vec::new(),
            previous: None,
            keep: true,
        }
    }

    /// Decides whether they are kept through the next `update_leaf_scales`: while one f32 a
    /// leaf for each link reaching it from its patch's elements fits in `budget` beside the
    /// links and nodes.
    fn plan(&mut self, h: &Hierarchy, links: &[Link], budget: u64) {
        // Leaves below each element; children are made after their parents.
        let mut leaves = vec![0u64; h.nodes.len()];
        for n in (0..h.nodes.len()).rev() {
            let node = &h.nodes[n];
            if node.is_cluster() {
                continue;
            }
            leaves[n] = if node.children == NONE {
                1
            } else {
                (node.children..node.children + 4)
                    .map(|c| leaves[c as usize])
                    .sum()
            };
        }
        // A leaf that is its whole patch needs none.
        let values: u64 = (links.iter())
            .filter(|l| !h.is_whole_patch(l.receiver))
            .map(|l| leaves[l.receiver as usize])
            .sum();
        let previous = self
            .previous
            .as_ref()
            .map_or(0, |p| 8 * p.refined.len() + 4 * p.starts.len());
        let held = links.len() * LINK_BYTES + h.nodes.len() * NODE_BYTES + previous;
        self.keep = self.keep && values * 4 <= budget.saturating_sub(held as u64);
        if !self.keep {
            self.per_patch = vec![Vec::new(); self.per_patch.len()];
            self.previous = None;
        }
    }
}

/// Each node's scales (`update_leaf_scales`) and the centre form factors kept for them.
struct LeafScales {
    scales: Vec<LeafScale>,
    centre_form_factors: CentreFormFactors,
    /// What `--max-memory` leaves the solve (`Hierarchical::memory_budget`).
    budget: u64,
}

impl LeafScales {
    fn new(patches: usize, budget: u64) -> LeafScales {
        LeafScales {
            scales: Vec::new(),
            centre_form_factors: CentreFormFactors::new(patches),
            budget,
        }
    }

    /// See `update_leaf_scales`.
    fn update(
        &mut self,
        h: &Hierarchy,
        links: &[Link],
        starts: &[u32],
        emission: &[Color],
        weighted: bool,
    ) {
        self.centre_form_factors.plan(h, links, self.budget);
        update_leaf_scales(
            h,
            links,
            starts,
            emission,
            weighted,
            &mut self.centre_form_factors,
            &mut self.scales,
        );
    }

    /// Notes the receivers' starts of the links the last update took, and which of those
    /// links a refinement takes out, a bit each (see `CentreFormFactors::previous`).
    fn before_refinement(&mut self, starts: Vec<u32>, refined: Vec<u64>) {
        // Not needed once the values are no longer kept.
        if self.centre_form_factors.keep {
            self.centre_form_factors.previous = Some(Previous { refined, starts });
        }
    }
}

/// Brings each leaf element's scales up to date: per colour channel, what the links that
/// reach it — its own, its ancestors' and its clusters' — carry when each is taken at the
/// leaf's centre, over what they carry as they are: Σ F(centre, S)·V·w_S over Σ F_RS·V·w_S.
/// Taken at one point, the form factors to the sources of those links (a partition of what
/// the point can see) sum to exactly that point's coverage; taken at the points of coarser
/// receivers they drift near edges (leaves of the closed cube otherwise sum to between 0.91
/// and 1.5). Scaling a leaf's gathered light by the ratio gives it what its centre gathers,
/// so a closed scene neither loses nor creates light.
///
/// A leaf that is its whole patch (never split) has no ancestors, and its own links were
/// all taken at the same four points: their form factors already partition what those
/// points see, so they are taken as they are (only the clusters' light is scaled). Taken at
/// the centre, a leaf whose form factors vary along it by more than their mean lost light:
/// office3's lamp shade, whose tube above the bulb is 16 strips 0.9 cm × 7.6 cm lit through
/// their lower ends, got 0.45 of the path tracer's light (0.62 of its direct light); as they
/// are, with each visibility pair counted with its own point's form factor
/// (`Hierarchical::links`), 0.68 (0.83).
///
/// Two ratios, each weighted by what the links carry: for the direct light w is the
/// sources' emission (exact from the start), for the reflected light their reflected
/// radiosity B − E, 1 before the first solve (`weighted` false) and the last solution's
/// after. One unweighted ratio for all the light let a coarse link that carries little (the
/// floor under a block's side, in a scene lit from the back wall) rescale the light of the
/// fine links that carry the rest: the Cornell MGF's blocks, lit one face at a time, were
/// up to 30% off per source. One ratio weighted by the radiosities let a lamp's ratio rescale
/// the light reflected onto the leaf too (office3's power −0.89% off the path tracer, −0.08%
/// with two ratios), and one weighted by the emission alone made the hospital's sweeps
/// diverge. Other nodes keep 1.
fn update_leaf_scales(
    h: &Hierarchy,
    links: &[Link],
    starts: &[u32],
    emission: &[Color],
    weighted: bool,
    centre_form_factors: &mut CentreFormFactors,
    scales: &mut Vec<LeafScale>,
) {
    let n = h.nodes.len();
    scales.clear();
    scales.resize(
        n,
        LeafScale {
            direct: Vec3::ONE,
            reflected: Vec3::ONE,
            from_clusters: 1.0,
        },
    );
    let by_receiver = |e: u32| starts[e as usize] as usize..starts[e as usize + 1] as usize;
    // Per source, the weights of what its links carry: (emission, reflected radiosity).
    let weights: Vec<(Color, Color)> = emission
        .iter()
        .zip(&h.radiance)
        .map(|(&e, &b)| {
            (
                e,
                if weighted {
                    (b - e).max(Vec3::ZERO)
                } else {
                    Vec3::ONE
                },
            )
        })
        .collect();
    // The links into clusters: each cluster's links lie together, the clusters' after the
    // patches' (nodes P..P+C, see `Hierarchy::new`).
    let (patches, clusters) = (h.patches.len(), h.clusters.len());
    let cluster_links = starts[patches] as usize..starts[patches + clusters] as usize;
    let into_clusters: Vec<IntoCluster> = links[cluster_links.clone()]
        .par_iter()
        .map(|l| IntoCluster::new(h, l))
        .collect();
    // Per cluster, what its links carry as they are, and the same summed over the clusters
    // above it (a cluster comes after its members, see `Hierarchy::cluster`).
    let mut cluster_as_is: Vec<Carried> = (0..clusters)
        .into_par_iter()
        .map(|c| {
            let mut sum = Carried::default();
            for l in &links[by_receiver((patches + c) as u32)] {
                sum.add_as_is(l, &weights);
            }
            sum
        })
        .collect();
    for c in (0..clusters).rev() {
        let parent = h.node((patches + c) as u32).parent;
        if parent != NONE {
            let above = cluster_as_is[parent as usize - patches];
            cluster_as_is[c].add_carried(&above, 1.0);
        }
    }
    let cache = &mut *centre_form_factors;
    cache.start.resize(n, NONE);
    let (keep, start, previous) = (cache.keep, &cache.start, &cache.previous);
    let per_patch: Vec<Vec<(u32, LeafScale, u32)>> = cache
        .per_patch
        .par_iter_mut()
        .enumerate()
        .map(|(root, kept)| {
            let root = root as u32;
            // A link into a cluster reaches its members' leaves as it reaches the cluster's
            // centre, from the same direction and distance, each leaf taking its share by
            // its orientation (as an isotropic cluster hands its light to its members): alike
            // for all the leaves of a patch, so summed once for the patch.
            let normal = h.node(root).normal;
            let parent = h.node(root).parent;
            let mut above = if parent == NONE {
                Carried::default()
            } else {
                cluster_as_is[parent as usize - patches]
            };
            let mut c = parent;
            while c != NONE {
                let range = by_receiver(c);
                let into = range.start - cluster_links.start..range.end - cluster_links.start;
                for (link, l) in into_clusters[into].iter().zip(&links[range]) {
                    link.add_at(l, normal, &weights, &mut above);
                }
                c = h.node(c).parent;
            }
            let old = std::mem::take(kept);
            let mut out = Vec::new();
            each_leaf(h, root, |e, chain| {
                let begins = kept.len() as u32;
                let mut carried = Carried::default();
                if h.is_whole_patch(e) {
                    // Its links as they are (see above).
                    for l in &links[by_receiver(e)] {
                        carried.add_as_is(l, &weights);
                        carried.add_at_leaf(l, l.form_factor, &weights);
                    }
                    out.push((e, carried.scale(&above), begins));
                    return;
                }
                let el = h.node(e);
                // The leaf's values at the last update, receiver by receiver of its chain.
                let mut from =
                    (keep && start[e as usize] != NONE).then(|| start[e as usize] as usize);
                for &a in chain {
                    let now = &links[by_receiver(a)];
                    // The last update's values of `a`'s links at this leaf, and where those
                    // links were if a refinement changed them since.
                    let (before, values) = match from {
                        None => (None, None),
                        Some(at) => {
                            let before = previous.as_ref().map(|p| p.of(a));
                            let count = before.as_ref().map_or(now.len(), |b| b.len());
                            from = Some(at + count);
                            (before, Some(&old[at..at + count]))
                        }
                    };
                    // After a refinement, `a`'s kept links come first, in their order
                    // (`Vec::retain`, then a stable sort by receiver), the links added since
                    // after them: the values of the kept links' places, in order.
                    let mut kept_places = (before.iter().cloned().flatten())
                        .filter(|&j| previous.as_ref().is_some_and(|p| p.was_kept(j)))
                        .map(|j| j - before.as_ref().map_or(0, |b| b.start));
                    for (k, l) in now.iter().enumerate() {
                        // The value depends only on the leaf and the source.
                        let kept_value = match (values, &before) {
                            (Some(v), None) => Some(v[k]),
                            (Some(v), Some(_)) => kept_places.next().map(|j| v[j]),
                            (None, _) => None,
                        };
                        let f = kept_value.unwrap_or_else(|| {
                            h.point_form_factor(el.centre, e, Some(el.normal), l.source)
                        });
                        if keep {
                            kept.push(f);
                        }
                        carried.add_as_is(l, &weights);
                        carried.add_at_leaf(l, f * l.visible(), &weights);
                    }
                }
                out.push((e, carried.scale(&above), begins));
            });
            // Kept until the next update: without the slack of its growth (up to as much
            // again as its values).
            kept.shrink_to_fit();
            out
        })
        .collect();
    for (e, scale, begins) in per_patch.into_iter().flatten() {
        scales[e as usize] = scale;
        if keep {
            cache.start[e as usize] = begins;
        }
    }
    cache.previous = None;
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
                reach: half_bits(1.0),
            })
            .collect();
        out.par_chunks_mut(LINK_CHUNK).for_each(|out| {
            let mut rays: Vec<Ray> = Vec::new();
            // Each pair's transmittance through a fog (1 without).
            let mut transmitted: Vec<f32> = Vec::new();
            let mut owners: Vec<usize> = Vec::new();
            // Each pair's receiver point's form factor.
            let mut pair_form_factors: Vec<f32> = Vec::new();
            for (o, link) in out.iter_mut().enumerate() {
                let (r, s) = (link.receiver, link.source);
                let xs: [(Vec3, u32); PAIRS] =
                    std::array::from_fn(|k| h.sample(r, k, seed, h.node(s).centre));
                let fs: [f32; PAIRS] = xs.map(|(x, _)| h.point_form_factor(x, r, None, s));
                let (lo, hi) = fs.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), &f| {
                    (lo.min(f), hi.max(f))
                });
                link.form_factor = fs.iter().sum::<f32>() / PAIRS as f32;
                link.spread = half_bits(hi - lo);
                if hi <= 0.0 {
                    // Every point missed the source, but a receiver reaching in front of it
                    // from behind (the floor under a block, for the block's side) may see it
                    // from its other part: the largest form factor at its corners says how
                    // much is at stake.
                    link.spread = half_bits(h.corner_form_factor(r, s));
                }
                if link.form_factor <= 0.0 || !sampler.visibility() {
                    // No pairs traced: through a fog, the centres' transmittance.
                    if sampler.in_fog() {
                        let t = sampler.transmittance(h.node(r).centre, h.node(s).centre);
                        link.form_factor *= t;
                        link.reach = half_bits(t);
                    }
                    continue;
                }
                // Pair receiver point k with a source point whose index is shifted per link,
                // so that no stratum pairs only with its mirror image.
                let shift = 1 + (r ^ s) as usize;
                for (k, &(x, rp)) in xs.iter().enumerate() {
                    let (y, sp) = h.sample(s, (k + shift) % PAIRS, seed, x);
                    let (rp, sp) = (&h.patches[rp as usize], &h.patches[sp as usize]);
                    let from = on_primitive(scene, rp, x, y - x);
                    let to = on_primitive(scene, sp, y, x - y);
                    rays.push(shadow_ray(from, to));
                    transmitted.push(sampler.transmittance(from, to));
                    owners.push(o);
                    pair_form_factors.push(fs[k]);
                }
            }
            if rays.is_empty() {
                return;
            }
            let mut blocked = vec![false; rays.len()];
            sampler.accel().occluded_batch(&rays, &mut blocked);
            sampler.rays.fetch_add(rays.len() as u64, Relaxed);
            // Each link's unblocked pairs, their transmittances summed, and their points' form
            // factors summed, each times its pair's transmittance.
            let mut open = vec![0u16; out.len()];
            let mut through = vec![0.0f32; out.len()];
            let mut reaching = vec![0.0f32; out.len()];
            let pairs = owners.iter().zip(&blocked).zip(&transmitted);
            for (((&o, b), &t), &f) in pairs.zip(&pair_form_factors) {
                if !b {
                    open[o] += 1;
                    through[o] += t;
                    reaching[o] += f * t;
                }
            }
            for &o in owners.iter().step_by(PAIRS) {
                let l = &mut out[o];
                // Some pairs blocked, or all of them: the rest of the receiver may see more
                // (or less) than its four points did, so the whole form factor is at stake.
                if open[o] < PAIRS as u16 {
                    l.spread = half_bits(l.form_factor.max(l.spread()));
                }
                let reach = if sampler.in_fog() {
                    through[o] / PAIRS as f32
                } else {
                    open[o] as f32 / PAIRS as f32
                };
                // Each point's form factor counts where its pair is unblocked, not the mean
                // form factor times the share unblocked: the points that see more of a
                // source often see it unblocked more often too. Inside office3's lamp shade,
                // the tube's points nearest the opening below it have both the largest form
                // factors to the bulb and its unblocked pairs; with a whole patch's links
                // taken as they are (`update_leaf_scales`), the product of the means gave
                // the tube 0.55 of the path tracer's light and the cone below it 0.95,
                // counted per pair 0.68 and 0.97.
                l.form_factor = reaching[o] / PAIRS as f32;
                l.reach = half_bits(reach);
            }
        });
        out
    }

    /// Refines `candidates` (pairs of nodes) into final links (see the module's text).
    fn refine(
        &self,
        h: &mut Hierarchy,
        sampler: &FormFactorSampler,
        mut candidates: Vec<(u32, u32)>,
        rule: SplitRule,
        links: &mut Vec<Link>,
    ) -> bool {
        let SplitRule {
            threshold,
            min_area,
        } = rule;
        let mut capped = false;
        // The node of a pair to split, if either can be (none once over the memory budget
        // or after Ctrl-C).
        let pick = |h: &Hierarchy, r: u32, s: u32, stop: bool| -> Option<u32> {
            if stop {
                return None;
            }
            let splittable = |n: u32| {
                let node = h.node(n);
                node.is_cluster() || node.area > min_area
            };
            let (a, b) = (h.node(r), h.node(s));
            let first = if a.radius >= b.radius { r } else { s };
            let second = if first == r { s } else { r };
            [first, second].into_iter().find(|&n| splittable(n))
        };
        while !candidates.is_empty() {
            // Stop splitting once what is held — links, nodes, and the candidates, each of
            // which may become a link — passes the budget. Checked once per level of the
            // breadth-first refinement, so a level may overshoot it by what it adds.
            let bytes = (links.len() + candidates.len()) * LINK_BYTES + h.nodes.len() * NODE_BYTES;
            capped |= bytes as u64 > self.memory_budget;
            // After Ctrl-C nothing is split further: the pairs at hand become links as they
            // are, so the light they carry is kept, and the solve stops at its next sweep.
            let stop = capped || crate::interrupt::requested();
            // Which pairs are split before any form factor is taken: any towards a cluster
            // holding an emitter, a node linked to itself, clusters too near for their
            // isotropic estimate. Decided in parallel; `Some(n)` splits node n.
            let pairs = std::mem::take(&mut candidates);
            let split_first: Vec<Option<u32>> = pairs
                .par_iter()
                .map(|&(r, s)| {
                    if r != s && h.holds_emitter(s) && !stop {
                        return Some(s);
                    }
                    let clustered = h.node(r).is_cluster() || h.node(s).is_cluster();
                    if r == s || (clustered && !h.separated(r, s)) {
                        pick(h, r, s, stop)
                    } else {
                        None
                    }
                })
                .collect();
            for &n in split_first.iter().flatten() {
                h.make_children(n);
            }
            // The pairs that replace the split ones, and those to evaluate, in the
            // candidates' order.
            let h_read: &Hierarchy = h;
            let (parts, to_evaluate): (Vec<NodePairs>, Vec<NodePairs>) = pairs
                .par_chunks(SPLIT_CHUNK)
                .zip(split_first.par_chunks(SPLIT_CHUNK))
                .map(|(chunk, split)| {
                    let (mut next, mut evaluate) = (Vec::new(), Vec::new());
                    for (&(r, s), &n) in chunk.iter().zip(split) {
                        match n {
                            Some(n) => split_pair(h_read, r, s, n, &mut next),
                            None => evaluate.push((r, s)),
                        }
                    }
                    (next, evaluate)
                })
                .unzip();
            drop((pairs, split_first));
            let (mut next, evaluate) = (parts.concat(), to_evaluate.concat());
            drop((parts, to_evaluate));
            for link in self.links(h, sampler, &evaluate) {
                // A link that carries nothing is refined while what is at stake (its spread)
                // matters, and dropped once it does not: dropped at once, the parts of its
                // elements its points missed lost that light (the Cornell MGF's floor summed
                // its form factors 8.5% short).
                if link.form_factor <= 0.0 && link.spread() <= 0.0 {
                    continue;
                }
                let (r, s) = (link.receiver, link.source);
                match pick(h, r, s, stop).filter(|_| link_error(h, &link) > threshold) {
                    Some(n) => {
                        h.make_children(n);
                        split_pair(h, r, s, n, &mut next);
                    }
                    None if link.form_factor > 0.0 => links.push(link),
                    None => {}
                }
            }
            candidates = next;
        }
        // Sorted by receiver (stably: a receiver's links keep their order, and so its
        // gathered sums), each receiver's links lie together for `update_leaf_scales`.
        links.sort_by_key(|l| l.receiver);
        capped
    }
}

/// (receiver, source) pairs of nodes.
type NodePairs = Vec<(u32, u32)>;

/// When `Hierarchical::refine` splits a link.
#[derive(Clone, Copy)]
struct SplitRule {
    /// The largest `link_error` a link may keep.
    threshold: f32,
    /// The area below which an element is not split.
    min_area: f32,
}

/// What a link gets wrong by carrying one value over its receiver: A_R × (the spread of the
/// form factor over R between elements, the whole form factor with a cluster at an end) × B_S.
fn link_error(h: &Hierarchy, l: &Link) -> f32 {
    let clustered = h.node(l.receiver).is_cluster() || h.node(l.source).is_cluster();
    let varies = if clustered { l.form_factor } else { l.spread() };
    h.node(l.receiver).area * varies * h.radiance[l.source as usize].max_element()
}

/// Whether bit `j` of the bit set `bits` is set.
fn bit(bits: &[u64], j: usize) -> bool {
    bits[j / 64] >> (j % 64) & 1 == 1
}

/// The pairs that replace (r, s) when node `n` (one of them, its children made) is split; a
/// node linked to itself becomes every pair of its children.
fn split_pair(h: &Hierarchy, r: u32, s: u32, n: u32, out: &mut Vec<(u32, u32)>) {
    let kids = h.children(n);
    if r == s {
        for a in kids.clone() {
            for b in kids.clone() {
                // A flat element cannot light itself; a cluster's members can light each other.
                let linked = if a == b {
                    h.node(a).is_cluster()
                } else {
                    h.may_see(a, b)
                };
                if linked {
                    out.push((a, b));
                }
            }
        }
        return;
    }
    for c in kids {
        let pair = if n == r { (c, s) } else { (r, c) };
        if h.may_see(pair.0, pair.1) {
            out.push(pair);
        }
    }
}

/// Per facing of every cluster (`Hierarchy::facings`), the area mean of `values` (one per
/// node; the patches' are read) over its patches.
fn by_direction(h: &Hierarchy, values: &[Color]) -> Vec<Color> {
    h.clusters
        .par_iter()
        .flat_map_iter(|c| {
            let mut sums = [Vec3::ZERO; 26];
            for &p in &h.members[c.first as usize..c.end as usize] {
                let patch = &h.patches[p as usize];
                sums[h.patch_direction[p as usize] as usize] += values[p as usize] * patch.area;
            }
            h.facings[c.facings.clone()]
                .iter()
                .map(move |f| sums[f.direction as usize] / f.area)
        })
        .collect()
}

/// What source `s` sends towards receiver `r`, of `values` (one per node; `directed` their
/// means over the clusters' facings, `by_direction`): an element its own value; a cluster
/// the value of the patches that face `r`, each facing weighted by the area it shows towards
/// `r`. A cluster's plain area mean sent the floor's light sideways from the walls in its
/// cluster and the walls' light up from the floor: office3's walls came out 4.9% bright
/// against the diffuse path tracer (3.7% with this; L1 6.90% → 5.89%).
fn sent(h: &Hierarchy, values: &[Color], directed: &[Color], r: u32, s: u32) -> Color {
    // Clusters are the nodes after the patches' roots, made in `Hierarchy::new` before any
    // element below a patch: telling them by index spares most links a look at the node.
    let Some(cluster) = (s as usize)
        .checked_sub(h.patches.len())
        .filter(|&c| c < h.clusters.len())
    else {
        return values[s as usize];
    };
    let range = h.clusters[cluster].facings.clone();
    let dir = h.node(r).centre - h.node(s).centre;
    let (mut sum, mut shown) = (Vec3::ZERO, 0.0f32);
    for (f, v) in h.facings[range.clone()].iter().zip(&directed[range]) {
        let w = f.normal.dot(dir);
        if w > 0.0 {
            sum += *v * w;
            shown += w;
        }
    }
    if shown > 0.0 {
        sum / shown
    } else {
        values[s as usize]
    }
}

/// Per node: what its own links gather of `sources` (F × what the source sends towards the
/// receiver, `sent`, summed; in a coloured fog, F per channel by `FormFactorSampler::tint`).
/// `links` are sorted by receiver, node r's at `starts[r]..starts[r + 1]`
/// (`receiver_starts`): each node sums its own, in parallel.
fn gather(
    h: &Hierarchy,
    sampler: &FormFactorSampler,
    links: &[Link],
    starts: &[u32],
    sources: &[Color],
) -> Vec<Color> {
    let directed = by_direction(h, sources);
    let mut gathered = vec![Vec3::ZERO; h.nodes.len()];
    gathered
        .par_iter_mut()
        .with_min_len(1024)
        .enumerate()
        .for_each(|(r, gathered)| {
            for l in &links[starts[r] as usize..starts[r + 1] as usize] {
                let s = l.source;
                let mut light = sent(h, sources, &directed, r as u32, s) * l.form_factor;
                if sampler.tinted() {
                    light *= sampler.tint(h.node(r as u32).centre, h.node(s).centre);
                }
                *gathered += light;
            }
        });
    gathered
}

/// Where each of `nodes` nodes' links start in `links` (sorted by receiver, see
/// `Hierarchical::refine`), and one past the last: node r's are `starts[r]..starts[r + 1]`.
fn receiver_starts(nodes: usize, links: &[Link]) -> Vec<u32> {
    debug_assert!(links.is_sorted_by_key(|l| l.receiver));
    let mut starts = vec![0u32; nodes + 1];
    for l in links {
        starts[l.receiver as usize + 1] += 1;
    }
    for i in 0..nodes {
        starts[i + 1] += starts[i];
    }
    starts
}

/// Pushes what the links gathered — of the sources' emission and of what they reflect,
/// apart for the leaf scales — down (scaled at the leaves by `scales`, see
/// `update_leaf_scales`) and pulls the radiosity back up. Returns each node's incident
/// radiance (at a leaf its own and its ancestors' gathering; above, the area mean of its
/// leaves') and the new radiance of every node.
fn sweep(h: &Hierarchy, scales: &[LeafScale], gathered: &Gathered) -> (Vec<Color>, Vec<Color>) {
    let mut light = Light {
        incident: vec![Vec3::ZERO; h.nodes.len()],
        radiance: vec![Vec3::ZERO; h.nodes.len()],
    };
    if h.top != NONE {
        push_pull(h, h.top, FromAbove::default(), gathered, scales, &mut light);
    }
    (light.incident, light.radiance)
}

/// Per node: the light gathered over its own links, from the sources' emission and from
/// what they reflect.
struct Gathered<'a> {
    direct: &'a [Color],
    reflected: &'a [Color],
}

/// Per node: incident and outgoing radiance.
struct Light {
    incident: Vec<Color>,
    radiance: Vec<Color>,
}

/// What a node's ancestors gathered, as `push_pull` hands it down: (direct, reflected), from
/// the clusters above its patch and from the elements above it, apart for the leaf's share of
/// the clusters' (`LeafScale::from_clusters`).
#[derive(Clone, Copy, Default)]
struct FromAbove {
    clusters: (Color, Color),
    elements: (Color, Color),
}

/// Pushes `from_above` plus `n`'s own gathering down to the leaves below `n` (a cluster's
/// members, an element's children), and returns the area means of their (incident, outgoing)
/// radiance.
fn push_pull(
    h: &Hierarchy,
    n: u32,
    mut from_above: FromAbove,
    gathered: &Gathered,
    scales: &[LeafScale],
    light: &mut Light,
) -> (Color, Color) {
    let node = h.node(n);
    let own = if node.is_cluster() {
        &mut from_above.clusters
    } else {
        &mut from_above.elements
    };
    own.0 += gathered.direct[n as usize];
    own.1 += gathered.reflected[n as usize];
    let quad: [u32; 4];
    let kids: &[u32] = if node.is_cluster() {
        &h.clusters[node.children as usize].kids
    } else if node.children != NONE {
        quad = std::array::from_fn(|k| node.children + k as u32);
        &quad
    } else {
        // A leaf element.
        let p = &h.patches[node.patch as usize];
        let scale = scales[n as usize];
        let FromAbove { clusters, elements } = from_above;
        let share = scale.from_clusters;
        let total = (elements.0 + clusters.0 * share) * scale.direct
            + (elements.1 + clusters.1 * share) * scale.reflected;
        let radiance = p.emitted + p.albedo * total;
        light.incident[n as usize] = total;
        light.radiance[n as usize] = radiance;
        return (total, radiance);
    };
    let (mut incident, mut radiance) = (Vec3::ZERO, Vec3::ZERO);
    let mut area = 0.0f32;
    for &c in kids {
        let a = h.node(c).area;
        let (i, b) = push_pull(h, c, from_above, gathered, scales, light);
        incident += i * a;
        radiance += b * a;
        area += a;
    }
    let (incident, radiance) = if area > 0.0 {
        (incident * area.recip(), radiance * area.recip())
    } else {
        let FromAbove { clusters, elements } = from_above;
        (
            clusters.0 + clusters.1 + elements.0 + elements.1,
            Vec3::ZERO,
        )
    };
    light.incident[n as usize] = incident;
    light.radiance[n as usize] = radiance;
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
        if total_emitted <= 0.0 {
            // Nothing emits (the sky's light is emission here too): every patch is dark. The
            // rule below would split every link to the smallest elements for nothing.
            let dark = vec![Vec3::ZERO; patches.len()];
            return Solved {
                light: PatchLight {
                    radiance: dark.clone(),
                    undistributed: dark.clone(),
                    incident: dark.clone(),
                    incident_direct: dark,
                    ..PatchLight::default()
                },
                stop: Stop::NoLight,
                report: "nothing emits".to_string(),
                counters: Vec::new(),
                warning: None,
            };
        }
        let scene_area: f32 = patches.iter().map(|p| p.area).sum();
        let threshold = self.link_error * largest;
        let rule = SplitRule {
            threshold,
            min_area: self.min_element_area * scene_area,
        };

        // The root linked to itself, refined with B = emission.
        // Few patches: every pair of them, which needs no cluster estimate. Many: the root
        // cluster linked to itself.
        let n = patches.len() as u32;
        let initial: Vec<(u32, u32)> = if patches.len() <= self.cluster_above {
            (0..n)
                .flat_map(|r| (0..n).map(move |s| (r, s)))
                .filter(|&(r, s)| r != s && h.may_see(r, s))
                .collect()
        } else if h.top != NONE && h.node(h.top).is_cluster() {
            vec![(h.top, h.top)]
        } else {
            Vec::new()
        };
        let mut links = Vec::new();
        let mut capped = self.refine(&mut h, sampler, initial, rule, &mut links);
        let mut emission = h.emission();
        // What the links gather of the emission changes only with the links.
        let mut starts = receiver_starts(h.nodes.len(), &links);
        let mut direct = gather(&h, sampler, &links, &starts, &emission);
        let mut scales = LeafScales::new(patches.len(), self.memory_budget);
        scales.update(&h, &links, &starts, &emission, false);

        let mut light = PatchLight::default();
        // Set by every sweep; the loop below makes at least one.
        let mut incident;
        let mut stop = Stop::Converged;
        let mut sweeps = 0u64;
        let mut rounds = 0;
        loop {
            // The change of power the round's first sweep made: after a refinement, what the
            // refinement moved.
            let mut first_change = None;
            // Sweeps over the fixed links until the change of power is under the tolerance.
            loop {
                let reflected: Vec<Color> = h
                    .radiance
                    .iter()
                    .zip(&emission)
                    .map(|(&b, &e)| b - e)
                    .collect();
                let gathered = Gathered {
                    direct: &direct,
                    reflected: &gather(&h, sampler, &links, &starts, &reflected),
                };
                let (inc, radiance) = sweep(&h, &scales.scales, &gathered);
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
                first_change.get_or_insert(light.residual);
                on_step(light.residual);
                if limits.log {
                    light.log.push(ShotRecord {
                        shot: sweeps,
                        step: Step::Sweep {
                            round: rounds + 1,
                            links: links.len() as u64,
                            elements: (h.nodes.len() - h.clusters.len()) as u64,
                        },
                        residual: light.residual,
                        seconds: start.elapsed().as_secs_f64(),
                        rays: sampler.rays.load(Relaxed),
                    });
                }
                if crate::interrupt::requested() {
                    stop = Stop::Interrupted;
                    break;
                }
                if limits.out_of_time() {
                    stop = Stop::TimeLimit;
                    break;
                }
                // `--radiosity-iterations K` stops after K sweeps, refinement rounds included.
                match limits.iterations {
                    Some(k) if sweeps >= k => stop = Stop::Iterations,
                    None if sweeps >= limits.cap => stop = Stop::Cap,
                    _ if light.residual <= limits.tolerance => {}
                    _ => continue,
                }
                break;
            }
            rounds += 1;
            // A refinement that moved the power by less than the tolerance ends the solve:
            // the links are as fine as the tolerance can tell.
            let settled = rounds > 1 && first_change.is_some_and(|c| c <= limits.tolerance);
            if stop != Stop::Converged || rounds >= MAX_ROUNDS || settled || capped {
                break;
            }
            // Refine the links that now carry too much (their sources have brightened).
            // Refining links whose errors add up to less than the tolerance cannot move the
            // solution by more than the tolerance.
            // Each link's error is found once (its nodes and source are read from all over
            // memory): a bit per link says whether it is refined.
            let mut refined = vec![0u64; links.len().div_ceil(64)];
            let (mut count, mut pending) = (0usize, 0.0f32);
            for (j, l) in links.iter().enumerate() {
                let error = link_error(&h, l);
                if error > threshold {
                    refined[j / 64] |= 1 << (j % 64);
                    count += 1;
                    pending += error;
                }
            }
            if count > 0 && pending > limits.tolerance * total_emitted {
                // The links to refine leave as pairs of nodes; the rest stay in place, in
                // their order (no second copy of the links at the peak of the solve).
                let mut candidates = Vec::with_capacity(count);
                candidates.extend(
                    (links.iter().enumerate())
                        .filter(|&(j, _)| bit(&refined, j))
                        .map(|(_, l)| (l.receiver, l.source)),
                );
                // `retain` visits the links once each, in order.
                let mut j = 0;
                links.retain(|_| {
                    j += 1;
                    !bit(&refined, j - 1)
                });
                // The links as the leaf scales last took them, for their values kept.
                scales.before_refinement(std::mem::take(&mut starts), refined);
                capped |= self.refine(&mut h, sampler, candidates, rule, &mut links);
                emission = h.emission();
                starts = receiver_starts(h.nodes.len(), &links);
                direct = gather(&h, sampler, &links, &starts, &emission);
            }
            // Whether or not links were refined, the leaf scales now weigh the links by the
            // radiosities just solved for; the next round's first sweep says how much that
            // moved, and the rule above ends the solve once it is under the tolerance.
            scales.update(&h, &links, &starts, &emission, true);
        }

        // The links (counted) and the centre form factors are done with: freed before the
        // solution is made, so that its making is not the peak of the solve.
        let clustered = links
            .iter()
            .filter(|l| h.node(l.receiver).is_cluster() || h.node(l.source).is_cluster())
            .count();
        let link_count = links.len();
        drop((links, starts));
        let scales = scales.scales;
        // What came straight from the emitters: one gather of the emission alone.
        let none = vec![Vec3::ZERO; h.nodes.len()];
        let gathered = Gathered {
            direct: &direct,
            reflected: &none,
        };
        let (incident_direct, _) = sweep(&h, &scales, &gathered);
        light.radiance = h.radiance[..patches.len()].to_vec();
        light.incident = incident[..patches.len()].to_vec();
        light.incident_direct = incident_direct[..patches.len()].to_vec();
        light.undistributed = vec![Vec3::ZERO; patches.len()];
        light.iterations = sweeps;
        light.elements = h.elements(&incident);
        let elements = h.nodes.len() - h.clusters.len();
        let leaves = h
            .nodes
            .iter()
            .filter(|e| !e.is_cluster() && e.children == NONE)
            .count();
        let link_bytes = link_count * std::mem::size_of::<Link>();
        let warning = capped.then(|| format!(
            "hierarchical refinement stopped at the memory budget ({} of --max-memory left after the rest of the render) with {} links: the solution is coarser than --link-error asks",
            crate::bytes::human_bytes(self.memory_budget),
            link_count
        ));
        Solved {
            light,
            stop,
            warning,
            counters: vec![
                ("clusters", h.clusters.len() as u64),
                ("elements", elements as u64),
                ("leaves", leaves as u64),
                ("links", link_count as u64),
                ("cluster links", clustered as u64),
                ("link bytes", link_bytes as u64),
                ("sweeps", sweeps),
                ("refinement rounds", rounds as u64),
            ],
            report: format!(
                "hierarchical: {} input patches, {} clusters, {} elements ({} leaves), {} links ({} with a cluster at an end; {:.1} MiB), {} sweeps in {} refinement rounds",
                patches.len(),
                h.clusters.len(),
                elements,
                leaves,
                link_count,
                clustered,
                link_bytes as f64 / (1 << 20) as f64,
                sweeps,
                rounds
            ),
        }
    }
}
