//! trilux's own BVH: a binary tree built by binned SAH (in parallel near the root), flattened
//! into one array with the two children of a node side by side, and traversed iteratively,
//! nearer child first. Leaves hold copies of their primitives in leaf order, so a leaf's
//! primitives are read from consecutive memory: triangles in packs of four tested at once
//! (`tri4`), quads and analytic shapes one by one.

use rayon::prelude::*;

use super::tri4::{Tri4, Tri4Ray};
use super::{Accel, AccelError, PackedPrim};
use crate::geometry::{
    faces_ray, intersect_quad_sheared, AnalyticShape, Bounds3, Ray, RayShear, Shape, Vec3,
};
use crate::scene::{PrimHit, PrimKind, PrimRef, Scene};

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Largest leaf the SAH may choose.
const MAX_LEAF: usize = 8;
/// Deeper than this the build makes a leaf whatever its size, so traversal's fixed stack
/// (one entry per level) cannot overflow.
const MAX_DEPTH: usize = 60;
/// Subtrees with more primitives than this are built on two threads.
const PARALLEL_THRESHOLD: usize = 8192;
/// Relative cost of visiting a node against intersecting one triangle.
const TRAVERSAL_COST: f32 = 1.0;

/// Relative cost of intersecting a quad or an analytic shape, one watertight triangle test
/// being 1: a quad is two triangle tests, a sphere's quadratic about as dear. Counting every
/// kind as one left the Cornell box's seven primitives in one leaf (no split of its walls,
/// whose boxes are as large as the room, looked cheaper); counted so, each wall gets a leaf of
/// its own, and one thread's incoherent closest hits there went from about 5.5 to 8 Mrays/s
/// and its shadow rays from about 6 to 10–13 (session 23, interleaved rounds).
const SINGLE_PRIM_COST: f32 = 2.0;
/// Relative cost of testing a pack of up to four triangles at once (`tri4`): a leaf's
/// triangles cost by the pack, so the SAH makes leaves of about four.
const TRI4_COST: f32 = 2.0;

/// What testing a leaf of `triangles` triangles and `singles` other primitives costs.
fn leaf_cost(triangles: u32, singles: u32) -> f32 {
    triangles.div_ceil(4) as f32 * TRI4_COST + singles as f32 * SINGLE_PRIM_COST
}

/// One flattened node: its box, and either the index of its first child (the second follows
/// it) when `count == 0`, or the range `first .. first + count` of its primitives.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug)]
struct Node {
    min: Vec3,
    first: u32,
    max: Vec3,
    count: u32,
}

/// A primitive tested on its own, copied into leaf order: a quad's four vertices and its
/// front normal, or for an analytic shape just the reference into `shapes`.
#[derive(Clone, Copy, Debug)]
struct LeafPrim {
    v: [Vec3; 4],
    normal: Vec3,
    prim: PackedPrim,
}

/// What a leaf holds, in leaf order: its triangles in packs of four, then its other
/// primitives one by one.
#[derive(Clone, Copy, Debug)]
enum LeafItem {
    Triangles(Tri4),
    Single(LeafPrim),
}

pub struct Bvh {
    nodes: Vec<Node>,
    /// The leaves' contents; a leaf node's `first .. first + count` indexes this.
    items: Vec<LeafItem>,
    /// How many primitives the tree holds (those with finite bounds).
    prim_count: usize,
    shapes: Vec<AnalyticShape>,
    one_sided_quads: bool,
    /// The deepest leaf's depth (the root is at 0): how many far children traversal may
    /// hold at once.
    depth: usize,
}

/// A primitive during the build.
#[derive(Clone, Copy)]
struct BuildPrim {
    bounds: Bounds3,
    centroid: Vec3,
    prim: PrimRef,
}

enum BuildNode {
    Leaf {
        bounds: Bounds3,
        first: usize,
        count: usize,
    },
    Interior {
        bounds: Bounds3,
        children: Box<[BuildNode; 2]>,
    },
}

impl BuildNode {
    fn bounds(&self) -> Bounds3 {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
        }
    }
}

impl Bvh {
    pub fn build(scene: &Scene) -> Result<Bvh, AccelError> {
        let total = scene.primitive_count();
        if total > PackedPrim::MAX_INDEX as usize {
            return Err(AccelError::TooLarge(total));
        }
        // Made on every thread, as the leaves' copies below (the two together: the 1M-triangle
        // terrain's build on two threads 0.917 → 0.842 s, medians of interleaved rounds).
        let build_prim = |bounds: Bounds3, kind: PrimKind, index: usize| BuildPrim {
            bounds,
            centroid: bounds.centre(),
            prim: PrimRef {
                kind,
                index: index as u32,
            },
        };
        let mut build: Vec<BuildPrim> = Vec::with_capacity(total);
        build.par_extend(
            scene
                .quads
                .par_iter()
                .enumerate()
                .map(|(i, q)| build_prim(Bounds3::from_points(&q.vertices), PrimKind::Quad, i)),
        );
        build.par_extend((0..scene.triangles.len()).into_par_iter().map(|i| {
            build_prim(
                Bounds3::from_points(&scene.triangles.vertices(i)),
                PrimKind::Triangle,
                i,
            )
        }));
        build.extend(
            scene
                .shapes
                .iter()
                .enumerate()
                .map(|(i, s)| build_prim(s.shape.bounds(), PrimKind::Shape, i)),
        );
        // Primitives with non-finite bounds can never be hit; leaving them out keeps every
        // box finite.
        build.retain(|p| p.bounds.min.is_finite() && p.bounds.max.is_finite());

        let root = build_node(&mut build, 0, 0);
        let mut nodes = Vec::with_capacity(2 * build.len() / 2 + 1);
        nodes.push(Node {
            min: Vec3::ZERO,
            first: 0,
            max: Vec3::ZERO,
            count: 0,
        });
        let mut leaves = Vec::new();
        let depth = flatten(&root, 0, &build, &mut nodes, &mut leaves, &mut 0);
        if build.is_empty() {
            // An empty tree: a root leaf with no primitives and an empty box.
            nodes[0] = Node {
                min: Vec3::splat(f32::INFINITY),
                first: 0,
                max: Vec3::splat(f32::NEG_INFINITY),
                count: 0,
            };
        }

        let items = leaves
            .par_iter()
            .flat_map_iter(|leaf| leaf_items(scene, &build[leaf.clone()]))
            .collect();
        Ok(Bvh {
            nodes,
            items,
            prim_count: build.len(),
            shapes: scene.shapes.iter().map(|s| s.shape).collect(),
            one_sided_quads: !scene.two_sided_quads,
            depth,
        })
    }

    /// Checks the tree's invariants: every child box inside its parent's, every primitive's
    /// box inside its leaf's, every primitive in exactly one leaf. Returns what is wrong.
    pub fn validate(&self, scene: &Scene) -> Result<(), String> {
        let mut seen = std::collections::HashMap::<u32, u32>::new();
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            if depth > MAX_DEPTH + 1 {
                return Err(format!("node {i} is deeper than {MAX_DEPTH}"));
            }
            if depth > self.depth {
                return Err(format!(
                    "node {i} is at depth {depth}, deeper than the {} levels traversal's stack holds",
                    self.depth
                ));
            }
            let b = Bounds3 {
                min: n.min,
                max: n.max,
            };
            if n.count > 0 || (i == 0 && self.items.is_empty()) {
                let items = self
                    .items
                    .get(n.first as usize..(n.first + n.count) as usize)
                    .ok_or(format!("leaf {i} runs past the leaves' contents"))?;
                for prim in items.iter().flat_map(LeafItem::prims) {
                    let pb = prim_bounds(scene, prim.unpack());
                    if !contains(&b, &pb) {
                        return Err(format!(
                            "primitive {:?} sticks out of leaf {i}",
                            prim.unpack()
                        ));
                    }
                    *seen.entry(prim.raw()).or_default() += 1;
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    let cn = self
                        .nodes
                        .get(c)
                        .ok_or(format!("node {i}: child {c} missing"))?;
                    let cb = Bounds3 {
                        min: cn.min,
                        max: cn.max,
                    };
                    if !contains(&b, &cb) {
                        return Err(format!("node {c} sticks out of its parent {i}"));
                    }
                    stack.push((c, depth + 1));
                }
            }
        }
        if let Some((&raw, &count)) = seen.iter().find(|(_, &count)| count != 1) {
            return Err(format!("primitive {raw:#x} is in {count} leaves"));
        }
        if seen.len() != self.prim_count {
            return Err(format!(
                "the leaves hold {} primitives of {}",
                seen.len(),
                self.prim_count
            ));
        }
        Ok(())
    }

    /// The items of a leaf node.
    #[inline(always)]
    fn leaf(&self, node: &Node) -> &[LeafItem] {
        &self.items[node.first as usize..(node.first + node.count) as usize]
    }

    /// Tests the primitives of one leaf; keeps in `best` the closest hit (primitive, u, v)
    /// and shrinks `t_max` to it.
    #[inline(always)]
    fn leaf_closest(
        &self,
        node: &Node,
        rays: (&Ray, &RayShear, &Tri4Ray),
        t_max: &mut f32,
        best: &mut Option<(PackedPrim, f32, f32)>,
    ) {
        let (ray, shear, pack_ray) = rays;
        for item in self.leaf(node) {
            // A hit at exactly the current t may still win by the tie rule (`keep_closest`).
            let limit = match best {
                Some(_) => t_max.next_up(),
                None => *t_max,
            };
            match item {
                LeafItem::Triangles(pack) => {
                    let hits = pack.intersect(pack_ray, ray, shear, limit);
                    for i in (0..4).filter(|i| hits.mask >> i & 1 != 0) {
                        let hit = (pack.prim(i), hits.t[i], hits.u[i], hits.v[i]);
                        keep_closest(best, t_max, hit);
                    }
                }
                LeafItem::Single(p) => {
                    if let Some((t, u, v)) = self.hit_single(p, ray, shear, limit) {
                        keep_closest(best, t_max, (p.prim, t, u, v));
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn hit_single(
        &self,
        p: &LeafPrim,
        ray: &Ray,
        shear: &RayShear,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        match p.prim.kind() {
            PrimKind::Triangle => unreachable!("triangles are tested in packs of four"),
            PrimKind::Quad => {
                if self.one_sided_quads && !faces_ray(p.normal, ray.direction) {
                    return None;
                }
                intersect_quad_sheared(ray, shear, t_max, &p.v)
            }
            PrimKind::Shape => self.shapes[p.prim.index() as usize]
                .intersect(ray, t_max)
                .map(|(t, _)| (t, 0.0, 0.0)),
        }
    }

    /// Walks the tree nearer child first. `visit` tests a leaf and returns true to stop.
    #[inline(always)]
    fn traverse(&self, ray: &Ray, t_max: &mut f32, visit: impl FnMut(&Node, &mut f32) -> bool) {
        // The stack of far children is an array filled afresh for each ray: a small tree
        // takes a short one (filling all 64 entries was 6% of the Cornell box's rays).
        if self.depth < SHALLOW_STACK {
            self.traverse_with::<SHALLOW_STACK>(ray, t_max, visit)
        } else {
            self.traverse_with::<{ MAX_DEPTH + 4 }>(ray, t_max, visit)
        }
    }

    /// `traverse` with a stack of `STACK` entries, at least the tree's depth.
    #[inline(always)]
    fn traverse_with<const STACK: usize>(
        &self,
        ray: &Ray,
        t_max: &mut f32,
        mut visit: impl FnMut(&Node, &mut f32) -> bool,
    ) {
        if self.items.is_empty() {
            return;
        }
        // A zero direction component becomes a tiny one of the same sign: the slab test
        // then never computes 0·∞ = NaN, and can use plain comparisons.
        let safe = |d: f32| {
            if d.abs() < 1e-30 {
                1e-30f32.copysign(d)
            } else {
                d
            }
        };
        let inv = Vec3 {
            x: 1.0 / safe(ray.direction.x),
            y: 1.0 / safe(ray.direction.y),
            z: 1.0 / safe(ray.direction.z),
        };
        let org = ray.origin;
        // Boxes are kept up to `BOX_REACH` beyond the current hit: see there.
        let reach = |t: f32| t * BOX_REACH;
        let root = &self.nodes[0];
        if slab(root, org, inv, ray.t_min, reach(*t_max)).is_none() {
            return;
        }
        // Far children wait with their entry distance: a closer hit found meanwhile lets
        // them be skipped without testing their box again.
        let mut stack = [(0u32, 0f32); STACK];
        let mut top = 0usize;
        let mut current = 0u32;
        loop {
            let node = &self.nodes[current as usize];
            if node.count > 0 {
                if visit(node, t_max) {
                    return;
                }
            } else {
                let (a, b) = (node.first, node.first + 1);
                let da = slab(&self.nodes[a as usize], org, inv, ray.t_min, reach(*t_max));
                let db = slab(&self.nodes[b as usize], org, inv, ray.t_min, reach(*t_max));
                match (da, db) {
                    (Some(x), Some(y)) => {
                        let (near, far, far_t) = if x <= y { (a, b, y) } else { (b, a, x) };
                        stack[top] = (far, far_t);
                        top += 1;
                        current = near;
                        continue;
                    }
                    (Some(_), None) => {
                        current = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        current = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let (candidate, entry) = stack[top];
                if entry <= reach(*t_max) {
                    current = candidate;
                    break;
                }
            }
        }
    }
}

/// Keeps `hit` (primitive, t, u, v) in `best` if it is nearer than `t_max`, and shrinks
/// `t_max` to it. Of equally near hits the smaller packed reference wins, whatever the order
/// the tree met them in: Embree's shim applies the same rule, so both backends answer the same
/// primitive where a ray meets an edge two primitives share.
#[inline(always)]
fn keep_closest(
    best: &mut Option<(PackedPrim, f32, f32)>,
    t_max: &mut f32,
    (prim, t, u, v): (PackedPrim, f32, f32, f32),
) {
    let wins = match best {
        Some((b, ..)) => t < *t_max || (t == *t_max && prim.raw() < b.raw()),
        None => t < *t_max,
    };
    if wins {
        *t_max = t;
        *best = Some((prim, u, v));
    }
}

/// Trees shallower than this are traversed with a stack of this many entries.
const SHALLOW_STACK: usize = 16;

/// How far beyond the current hit a box is still opened, as a factor. The slab test's entry
/// distance is rounded otherwise than a primitive's exact t: a quad met exactly at its edge,
/// a few ulps nearer than the hit found first, lay in a box whose computed entry was a few
/// ulps beyond that hit, and was culled (three camera rays along the fog box's edges in
/// 262,144, caught once the surface stopped re-settling the BVH's hits); and a hit at the
/// current t still competes by the tie rule. Embree's filter keeps the same room.
const BOX_REACH: f32 = 1.0 + 1e-5;

/// Ray–box slab test. The far distance is enlarged by 2γ₃ (Ize, "Robust BVH ray traversal")
/// so that rounding never culls a box the ray touches.
#[inline(always)]
fn slab(n: &Node, org: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
    const ROBUST: f32 = 1.0 + 2.0 * 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);
    let tx0 = (n.min.x - org.x) * inv.x;
    let tx1 = (n.max.x - org.x) * inv.x;
    let ty0 = (n.min.y - org.y) * inv.y;
    let ty1 = (n.max.y - org.y) * inv.y;
    let tz0 = (n.min.z - org.z) * inv.z;
    let tz1 = (n.max.z - org.z) * inv.z;
    let near = max(max(min(tx0, tx1), min(ty0, ty1)), max(min(tz0, tz1), t_min));
    let far = min(min(max(tx0, tx1), max(ty0, ty1)), max(tz0, tz1)) * ROBUST;
    let far = min(far, t_max);
    (near <= far).then_some(near)
}

/// Plain comparisons (minss/maxss); the slab test feeds them no NaN.
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

impl Accel for Bvh {
    fn name(&self) -> &'static str {
        "bvh"
    }

    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        let shear = RayShear::new(ray);
        let pack_ray = Tri4Ray::new(ray, &shear);
        let mut t_max = ray.t_max;
        let mut best = None;
        self.traverse(ray, &mut t_max, |node, t_max| {
            self.leaf_closest(node, (ray, &shear, &pack_ray), t_max, &mut best);
            false
        });
        best.map(|(prim, u, v)| PrimHit {
            t: t_max,
            prim: prim.unpack(),
            u,
            v,
            exact: true,
        })
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let shear = RayShear::new(ray);
        let pack_ray = Tri4Ray::new(ray, &shear);
        let mut t_max = ray.t_max;
        let mut hit = false;
        self.traverse(ray, &mut t_max, |node, t_max| {
            hit = self.leaf(node).iter().any(|item| match item {
                LeafItem::Triangles(pack) => {
                    pack.intersect(&pack_ray, ray, &shear, *t_max).mask != 0
                }
                LeafItem::Single(p) => self.hit_single(p, ray, &shear, *t_max).is_some(),
            });
            hit
        });
        hit
    }
}

fn contains(outer: &Bounds3, inner: &Bounds3) -> bool {
    inner.is_empty()
        || (outer.min.x <= inner.min.x
            && outer.min.y <= inner.min.y
            && outer.min.z <= inner.min.z
            && outer.max.x >= inner.max.x
            && outer.max.y >= inner.max.y
            && outer.max.z >= inner.max.z)
}

fn prim_bounds(scene: &Scene, prim: PrimRef) -> Bounds3 {
    let i = prim.index as usize;
    match prim.kind {
        PrimKind::Quad => Bounds3::from_points(&scene.quads[i].vertices),
        PrimKind::Triangle => Bounds3::from_points(&scene.triangles.vertices(i)),
        PrimKind::Shape => scene.shapes[i].shape.bounds(),
    }
}

impl LeafItem {
    /// The primitives the item holds.
    fn prims(&self) -> Vec<PackedPrim> {
        match self {
            LeafItem::Triangles(pack) => pack.triangles().map(|(_, prim)| prim).collect(),
            LeafItem::Single(p) => vec![p.prim],
        }
    }
}

/// A leaf's contents: its triangles in packs of four, then its other primitives.
fn leaf_items(scene: &Scene, leaf: &[BuildPrim]) -> Vec<LeafItem> {
    let triangles: Vec<([Vec3; 3], PackedPrim)> = leaf
        .iter()
        .filter(|p| p.prim.kind == PrimKind::Triangle)
        .map(|p| {
            let vertices = scene.triangles.vertices(p.prim.index as usize);
            (vertices, PackedPrim::new(p.prim))
        })
        .collect();
    let singles = leaf.iter().filter_map(|p| {
        let i = p.prim.index as usize;
        let (v, normal) = match p.prim.kind {
            PrimKind::Triangle => return None,
            PrimKind::Quad => (scene.quads[i].vertices, scene.quads[i].normal),
            PrimKind::Shape => ([Vec3::ZERO; 4], Vec3::ZERO),
        };
        Some(LeafItem::Single(LeafPrim {
            v,
            normal,
            prim: PackedPrim::new(p.prim),
        }))
    });
    triangles
        .chunks(4)
        .map(|pack| LeafItem::Triangles(Tri4::new(pack)))
        .chain(singles)
        .collect()
}

/// How many items `leaf_items` makes of a leaf, and the leaf's cost.
fn leaf_shape(leaf: &[BuildPrim]) -> (usize, f32) {
    let triangles = leaf
        .iter()
        .filter(|p| p.prim.kind == PrimKind::Triangle)
        .count();
    let singles = leaf.len() - triangles;
    (
        triangles.div_ceil(4) + singles,
        leaf_cost(triangles as u32, singles as u32),
    )
}

fn union_bounds(prims: &[BuildPrim]) -> (Bounds3, Bounds3) {
    prims
        .iter()
        .fold((Bounds3::EMPTY, Bounds3::EMPTY), |(b, c), p| {
            (b.union(p.bounds), c.union_point(p.centroid))
        })
}

/// Builds the subtree over `prims`, which start at `offset` in the final primitive order.
fn build_node(prims: &mut [BuildPrim], offset: usize, depth: usize) -> BuildNode {
    let (bounds, centroids) = union_bounds(prims);
    let n = prims.len();
    let leaf = BuildNode::Leaf {
        bounds,
        first: offset,
        count: n,
    };
    if n <= 1 || depth >= MAX_DEPTH {
        return leaf;
    }
    let split = match best_split(prims, &bounds, &centroids) {
        Some((axis, bin, cost)) => {
            if n <= MAX_LEAF && cost >= leaf_shape(prims).1 {
                return leaf;
            }
            let scale = BINS as f32 / (centroids.max[axis] - centroids.min[axis]);
            let lo = centroids.min[axis];
            partition(prims, |p| bin_of(p.centroid[axis], lo, scale) <= bin)
        }
        // All centroids coincide: split by count so that no leaf grows without bound.
        None if n <= MAX_LEAF => return leaf,
        None => n / 2,
    };
    let split = if split == 0 || split == n {
        n / 2
    } else {
        split
    };
    let (left, right) = prims.split_at_mut(split);
    let (l, r) = if n > PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(left, offset, depth + 1),
            || build_node(right, offset + split, depth + 1),
        )
    } else {
        (
            build_node(left, offset, depth + 1),
            build_node(right, offset + split, depth + 1),
        )
    };
    BuildNode::Interior {
        bounds,
        children: Box::new([l, r]),
    }
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// The cheapest SAH split: (axis, last bin of the left side, cost relative to one triangle
/// intersection). None when all centroids coincide.
fn best_split(
    prims: &[BuildPrim],
    bounds: &Bounds3,
    centroids: &Bounds3,
) -> Option<(usize, usize, f32)> {
    let extent = centroids.extent();
    let parent_area = bounds.area().max(f32::MIN_POSITIVE);
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        // Extents are finite (primitives with non-finite bounds are left out).
        if extent[axis] <= 0.0 {
            continue;
        }
        let lo = centroids.min[axis];
        let scale = BINS as f32 / extent[axis];
        let mut counts = [0u32; BINS];
        let mut triangles = [0u32; BINS];
        let mut boxes = [Bounds3::EMPTY; BINS];
        for p in prims {
            let b = bin_of(p.centroid[axis], lo, scale);
            counts[b] += 1;
            triangles[b] += (p.prim.kind == PrimKind::Triangle) as u32;
            boxes[b] = boxes[b].union(p.bounds);
        }
        // Sweep from the right, then from the left.
        let mut right_area = [0f32; BINS];
        let mut acc = Bounds3::EMPTY;
        for b in (1..BINS).rev() {
            acc = acc.union(boxes[b]);
            right_area[b] = acc.area();
        }
        let (mut left_box, mut left_count, mut left_triangles) = (Bounds3::EMPTY, 0u32, 0u32);
        let total = prims.len() as u32;
        let total_triangles: u32 = triangles.iter().sum();
        for b in 0..BINS - 1 {
            left_box = left_box.union(boxes[b]);
            left_count += counts[b];
            left_triangles += triangles[b];
            let right_count = total - left_count;
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let right_triangles = total_triangles - left_triangles;
            let left_cost = leaf_cost(left_triangles, left_count - left_triangles);
            let right_cost = leaf_cost(right_triangles, right_count - right_triangles);
            let cost = TRAVERSAL_COST
                + (left_box.area() * left_cost + right_area[b + 1] * right_cost) / parent_area;
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, b, cost));
            }
        }
    }
    best
}

/// Moves the elements for which `left` holds to the front; returns how many there are.
fn partition(prims: &mut [BuildPrim], left: impl Fn(&BuildPrim) -> bool) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        if left(&prims[j]) {
            prims.swap(i, j);
            i += 1;
        }
    }
    i
}

/// Writes `node` at `slot`, allocating its children as an adjacent pair, and appends each
/// leaf's range of `prims` to `leaves` in the order their items will be stored (`item_count`
/// items so far); returns the
/// depth of its deepest leaf below it (0 for a leaf).
fn flatten(
    node: &BuildNode,
    slot: usize,
    prims: &[BuildPrim],
    nodes: &mut Vec<Node>,
    leaves: &mut Vec<std::ops::Range<usize>>,
    item_count: &mut usize,
) -> usize {
    let b = node.bounds();
    match node {
        BuildNode::Leaf { first, count, .. } => {
            let range = *first..first + count;
            let items = leaf_shape(&prims[range.clone()]).0;
            nodes[slot] = Node {
                min: b.min,
                first: *item_count as u32,
                max: b.max,
                count: items as u32,
            };
            leaves.push(range);
            *item_count += items;
            0
        }
        BuildNode::Interior { children, .. } => {
            let first = nodes.len();
            let empty = Node {
                min: Vec3::ZERO,
                first: 0,
                max: Vec3::ZERO,
                count: 0,
            };
            nodes.push(empty);
            nodes.push(empty);
            nodes[slot] = Node {
                min: b.min,
                first: first as u32,
                max: b.max,
                count: 0,
            };
            let left = flatten(&children[0], first, prims, nodes, leaves, item_count);
            let right = flatten(&children[1], first + 1, prims, nodes, leaves, item_count);
            1 + left.max(right)
        }
    }
}
