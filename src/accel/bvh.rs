//! trilux's own BVH: a binary tree built by binned SAH, then collapsed into an 8-wide tree
//! whose nodes hold their children's boxes side by side, so that one ray is tested against
//! four at a time (glam's `Vec4`). Traversal is iterative and ordered: the children a ray
//! enters are taken nearest first. On the 1M-triangle terrain a ray's time goes mostly to
//! waiting for nodes and leaves from memory; each halving of the depth paid (the terrain with
//! `bench-accel`: 4-wide nodes about +15% over the binary tree, 8-wide about +25% over 4-wide;
//! no `std::arch` beyond SSE, which would need `unsafe`). Leaves hold copies of their
//! primitives in leaf order, so a leaf's primitives are read from consecutive memory:
//! triangles in packs of four tested at once (`tri4`), quads and analytic shapes one by one.
//! Batched occlusion walks packets of eight rays together (a box tested against all of them
//! at once, a quad against four of them where they share their axes), down to where two or
//! fewer of a packet's rays still go on, which then go on alone: on the course's Cornell box
//! (seven primitives under one node, where a ray's own work is all) that took camera
//! occlusion from 0.8 to 1.3 times Embree's packets (`bench-accel`). The batched queries run
//! through `pulp`'s run-time dispatch, so that the walk inlined into them is compiled for the
//! processor's widest instructions; with the leaf tests inlined too (`LeafVisit`), the
//! Cornell box's batched closest hits gained 16–21% on camera and shadow rays and its path
//! tracer took 0.96× the time. The single-ray queries dispatched so as well measured no
//! faster on the terrain (0.81–0.82 of Embree's closest hits against 0.82–0.84 without, five
//! interleaved runs each; its time is the loads of nodes and leaves, `perf annotate`). What
//! pays there is asking for the memory of every child a ray enters as soon as it is entered
//! (`Bvh::prefetch`, as Embree does), so that the loads overlap: closest hits went from 0.79 to
//! 0.91 of Embree's rate, occlusion from 0.82 to 0.93 (single rays, one thread, medians of
//! five interleaved runs).
//!
//! A tree of at most `LANES_ITEMS` quads and spheres answers batched closest hits without a
//! walk: each of its items is tested against 16 rays at once, a ray a SIMD lane (`lanes`).
//! On the Cornell box with the diffuse sphere (one node over seven leaves of one primitive
//! each) the path tracer's batched closest hits went from 1.05 to 0.57 CPU seconds a render
//! at 64 paths a pixel, and the render from 1.57 to 1.27 s. Its shadow rays stay in packets:
//! tested so they took 0.51 s against the packets' 0.24 (most meet no primitive, and the
//! packets' boxes rule most primitives out). On the course's L-shaped room (14 quads) the
//! lanes gained nothing, so trees of more than 8 items walk.
//!
//! The build holds each primitive as its box's two corners in `Vec4`s (its reference in a
//! spare lane) and makes two passes over a node's primitives, as Embree's builders do: one
//! binning them along all three axes at once, one partitioning them while gathering each
//! side's box of centres (the sides' boxes are the bins'). Nodes of many primitives are binned
//! on every thread, subtrees built in parallel. Against one pass for the node's boxes, one
//! binning pass an axis and one partitioning pass, the 1M-triangle terrain's build on one
//! thread went from 0.73–0.75 to 0.43–0.47 s (`bench-accel`, interleaved).

use std::cell::OnceCell;

use rayon::prelude::*;

use glam::Vec4;

use super::lanes::{self, LaneHits, Limits, RayLanes, LANES};
use super::pages::HugePageArray;
use super::tri4::{Rays4, Tri4, Tri4Ray};
use super::{Accel, AccelError, PackedPrim};
use crate::geometry::{intersect_quad_sheared, AnalyticShape, Bounds3, Ray, RayShear, Shape, Vec3};
use crate::scene::{
    CulledBacks, Instance, PrimHit, PrimKind, PrimRef, Quad, Scene, ShapePrim, TriangleMesh,
};

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Largest leaf the SAH may choose.
const MAX_LEAF: usize = 8;
/// Deeper than this the build makes a leaf whatever its size.
const MAX_DEPTH: usize = 60;
/// Subtrees with more primitives than this are built on two threads.
const PARALLEL_THRESHOLD: usize = 8192;
/// Nodes with more primitives than this are binned on every thread.
const PARALLEL_BINNING: usize = 1 << 16;
/// Relative cost of visiting a node against intersecting one triangle.
const TRAVERSAL_COST: f32 = 1.0;

/// Relative cost of intersecting a quad or an analytic shape, one watertight triangle test
/// being 1: a quad is two triangle tests, a sphere's quadratic about as dear. Counting every
/// kind as one left the Cornell box's seven primitives in one leaf (no split of its walls,
/// whose boxes are as large as the room, looked cheaper); counted so, each wall gets a leaf of
/// its own, and one thread's incoherent closest hits there went from about 5.5 to 8 Mrays/s
/// and its shadow rays from about 6 to 10–13 (`bench-accel`, interleaved rounds).
const SINGLE_PRIM_COST: f32 = 2.0;
/// Relative cost of testing a pack of up to four triangles at once (`tri4`): a leaf's
/// triangles cost by the pack, priced as one triangle test (Embree's ratio of traversal to
/// intersection for its leaves of four). With every entered child's lines prefetched together
/// (`Bvh::prefetch`) the pack's extra lines come at little cost; on the 1M-triangle terrain,
/// against a pack priced as two tests, one thread's incoherent closest hits went from 0.90 to
/// 0.92–0.94 of Embree's rate and its occlusion from 0.91–0.94 to 0.94–0.99 (single rays,
/// medians of interleaved runs). Priced as 1.5 it lay between; leaves of up to 16 gained
/// nothing more. Without the prefetch the same pricing (28% fewer nodes) was no faster: 0.83
/// against 0.82 of Embree's closest hits, eight runs each.
const TRI4_COST: f32 = 1.0;

/// What testing a leaf of `triangles` triangles and `singles` other primitives costs.
fn leaf_cost(triangles: u32, singles: u32) -> f32 {
    triangles.div_ceil(4) as f32 * TRI4_COST + singles as f32 * SINGLE_PRIM_COST
}

/// Children of a node of the traversed tree (a multiple of 4).
const WIDTH: usize = 8;
/// A node's children in groups of four, one `Vec4` lane a child.
const GROUPS: usize = WIDTH / 4;

/// One node of the wide tree: its children's boxes side by side (rows: x, y, z of the
/// minimum corners, then of the maximum ones; one lane a child, four children a group), and
/// per child either the index of its node (`count == 0`) or the range `first .. first +
/// count` of `items`. An unused slot has the empty box (minimum +∞, maximum −∞), which no ray
/// enters. 256 bytes, four cache lines.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Node {
    bounds: [[Vec4; GROUPS]; 6],
    first: [u32; WIDTH],
    count: [u32; WIDTH],
}

impl Node {
    const EMPTY: Node = Node {
        bounds: [
            [Vec4::INFINITY; GROUPS],
            [Vec4::INFINITY; GROUPS],
            [Vec4::INFINITY; GROUPS],
            [Vec4::NEG_INFINITY; GROUPS],
            [Vec4::NEG_INFINITY; GROUPS],
            [Vec4::NEG_INFINITY; GROUPS],
        ],
        first: [0; WIDTH],
        count: [0; WIDTH],
    };

    fn child_bounds(&self, slot: usize) -> Bounds3 {
        let b = |row: usize| self.bounds[row][slot / 4][slot % 4];
        Bounds3 {
            min: Vec3::new(b(0), b(1), b(2)),
            max: Vec3::new(b(3), b(4), b(5)),
        }
    }

    fn set_child(&mut self, slot: usize, bounds: Bounds3, first: u32, count: u32) {
        for axis in 0..3 {
            self.bounds[axis][slot / 4][slot % 4] = bounds.min[axis];
            self.bounds[axis + 3][slot / 4][slot % 4] = bounds.max[axis];
        }
        self.first[slot] = first;
        self.count[slot] = count;
    }
}

/// A child traversal will enter: a node (`count == 0`, `first` its index) or a leaf's items,
/// with the distance at which the ray enters its box.
#[derive(Clone, Copy, Debug)]
struct Entry {
    first: u32,
    count: u32,
    t: f32,
}

/// The root, entered at no particular distance.
const ROOT: Entry = Entry {
    first: 0,
    count: 0,
    t: f32::NEG_INFINITY,
};

/// What fills the slots of traversal's arrays before they are written: all bits zero, so that
/// filling them, for every ray, takes a few wide stores (with `ROOT`'s −∞ it took two scalar
/// stores a slot, 48 for a ray on the Cornell box).
const UNUSED: Entry = Entry {
    first: 0,
    count: 0,
    t: 0.0,
};

/// Entries of traversal's stack kept in an array; deeper ones spill into a vector (a node
/// pushes up to `WIDTH` − 1, and the tree may be `MAX_DEPTH` deep). The array is filled afresh
/// for every ray, so it is kept short: rays on small scenes cost tens of nanoseconds.
const STACK: usize = 16;

/// A ray set up for the wide slab test: origin and inverse direction in every lane, and per
/// axis which row of a node's bounds is the near plane (the minimum when the direction is
/// positive).
struct RayBoxes {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    near: [usize; 3],
}

impl RayBoxes {
    #[inline(always)]
    fn new(ray: &Ray) -> RayBoxes {
        RayBoxes::with_inverse(ray, inverse_direction(ray))
    }

    /// The ray set up with `inv`, its `inverse_direction` made before.
    #[inline(always)]
    fn with_inverse(ray: &Ray, inv: [f32; 3]) -> RayBoxes {
        RayBoxes {
            org: [0, 1, 2].map(|a| Vec4::splat(ray.origin[a])),
            inv: inv.map(Vec4::splat),
            near: [0, 1, 2].map(|a| if inv[a] < 0.0 { a + 3 } else { a }),
        }
    }
}

/// The inverse of each of the ray's direction components, a zero one taken as a tiny one of
/// the same sign: the slab test then never computes 0·∞ = NaN, and can use plain comparisons.
#[inline(always)]
fn inverse_direction(ray: &Ray) -> [f32; 3] {
    let safe = |d: f32| {
        if d.abs() < 1e-30 {
            1e-30f32.copysign(d)
        } else {
            d
        }
    };
    [0, 1, 2].map(|a| 1.0 / safe(ray.direction[a]))
}

/// Trees of at most this many items, quads and spheres, answer batched closest hits by testing
/// every item against `LANES` rays at once (`Bvh::closest_lanes`) instead of walking the tree
/// ray by ray.
const LANES_ITEMS: usize = 8;

/// Rays per packet of the batched occlusion query: two groups of four, one `Vec4` lane a ray.
const PACKET: usize = 8;
/// A packet's entry that this many of its rays or fewer still enter is walked ray by ray
/// (Embree's "single-ray switch"): below it, testing a box against the packet costs more than
/// against the rays that need it, and incoherent rays part after a level or two.
const PACKET_SWITCH: u32 = 2;

/// A packet of rays set up for testing one box against all of them (ray `4g + i` in lane `i`
/// of group `g`): per axis their origins and inverse directions, and the range of t each
/// ray's boxes are tested in.
#[derive(Default)]
struct PacketBoxes {
    org: [[Vec4; 2]; 3],
    inv: [[Vec4; 2]; 3],
    t_min: [Vec4; 2],
    t_max: [Vec4; 2],
}

impl PacketBoxes {
    /// Sets lane `i` to `ray(i)`, every lane. A group's lanes are gathered into arrays and
    /// loaded whole: a `Vec4`'s lane indexed by a number known only at run time is a `match`,
    /// a branch the processor mispredicts.
    #[inline(always)]
    fn load<'r>(&mut self, ray: impl Fn(usize) -> &'r Ray) {
        for g in 0..PACKET / 4 {
            let rays: [&Ray; 4] = std::array::from_fn(|lane| ray(4 * g + lane));
            let inv = rays.map(inverse_direction);
            for a in 0..3 {
                self.org[a][g] = Vec4::from_array(rays.map(|r| r.origin[a]));
                self.inv[a][g] = Vec4::from_array(inv.map(|v| v[a]));
            }
            self.t_min[g] = Vec4::from_array(rays.map(|r| r.t_min));
            self.t_max[g] = Vec4::from_array(rays.map(|r| r.t_max * BOX_REACH));
        }
    }

    /// The inverse direction of the ray in lane `i` (`inverse_direction`'s), read through an
    /// array (see `load`).
    #[inline(always)]
    fn inverse(&self, i: usize) -> [f32; 3] {
        let (g, lane) = (i / 4, i % 4);
        [0, 1, 2].map(|a| self.inv[a][g].to_array()[lane])
    }

    /// The rays (bit `i`: ray `i`) that enter the box of child `slot` of `n`: for each ray
    /// the decision `slab` makes (the near plane the lesser of the two planes' distances
    /// where `slab` picks it by the direction's sign: the same number).
    #[inline(always)]
    fn enter(&self, n: &Node, slot: usize) -> u32 {
        let (g, lane) = (slot / 4, slot % 4);
        let bound = |row: usize| Vec4::splat(n.bounds[row][g][lane]);
        let (lo, hi) = (
            [bound(0), bound(1), bound(2)],
            [bound(3), bound(4), bound(5)],
        );
        let mut mask = 0;
        for h in 0..2 {
            let plane = |bound: Vec4, a: usize| (bound - self.org[a][h]) * self.inv[a][h];
            let ends = |a: usize| (plane(lo[a], a), plane(hi[a], a));
            let (x, y, z) = (ends(0), ends(1), ends(2));
            let entry =
                x.0.min(x.1)
                    .max(y.0.min(y.1))
                    .max(z.0.min(z.1).max(self.t_min[h]));
            let exit = x.0.max(x.1).min(y.0.max(y.1)).min(z.0.max(z.1)) * ROBUST;
            let exit = exit.min(self.t_max[h]);
            mask |= entry.cmple(exit).bitmask() << (4 * h);
        }
        mask
    }
}

/// The slots of `n` that hold a child (an unused slot's box is empty: its minimum above its
/// maximum). `PacketBoxes::enter`, which takes the lesser plane as the near one, would enter
/// an empty box.
#[inline(always)]
fn occupied(n: &Node) -> u32 {
    (0..GROUPS).fold(0, |mask, g| {
        mask | n.bounds[0][g].cmple(n.bounds[3][g]).bitmask() << (4 * g)
    })
}

/// A primitive tested on its own, copied into leaf order: a quad's four vertices and its
/// front normal, or for an analytic shape or an instance just the reference into `shapes` or
/// `instances`.
#[derive(Clone, Copy, Debug)]
struct LeafPrim {
    v: [Vec3; 4],
    normal: Vec3,
    prim: PackedPrim,
}

/// What a leaf holds, in leaf order: its triangles in packs of four, then its other
/// primitives one to an item. Either way an item is a pack's 160 bytes of plain data, so that
/// the leaves can live in huge pages (`pages`): a single primitive's vertices and normal lie
/// in the lanes' first 15 floats, and the kind of the first reference tells the two apart.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
struct LeafItem(Tri4);

/// A leaf item as it is tested.
enum ItemView<'a> {
    Triangles(&'a Tri4),
    Single(LeafPrim),
}

/// Floats of a single primitive's item: four vertices and a normal.
const SINGLE_FLOATS: usize = 15;

impl LeafItem {
    fn triangles(pack: Tri4) -> LeafItem {
        LeafItem(pack)
    }

    fn single(p: &LeafPrim) -> LeafItem {
        let mut floats = [0f32; SINGLE_FLOATS];
        for (k, v) in p.v.iter().chain([&p.normal]).enumerate() {
            floats[3 * k..3 * k + 3].copy_from_slice(&v.to_array());
        }
        LeafItem(Tri4::holding(&floats, p.prim))
    }

    #[inline(always)]
    fn view(&self) -> ItemView<'_> {
        if self.0.prim(0).kind() == PrimKind::Triangle {
            return ItemView::Triangles(&self.0);
        }
        let f = self.0.floats();
        let vec = |k: usize| Vec3::new(f[3 * k], f[3 * k + 1], f[3 * k + 2]);
        ItemView::Single(LeafPrim {
            v: [vec(0), vec(1), vec(2), vec(3)],
            normal: vec(4),
            prim: self.0.prim(0),
        })
    }

    /// The primitives the item holds.
    fn prims(&self) -> Vec<PackedPrim> {
        match self.view() {
            ItemView::Triangles(pack) => pack.triangles().map(|(_, prim)| prim).collect(),
            ItemView::Single(p) => vec![p.prim],
        }
    }
}

/// A tree over a scene's own primitives and its instances, whose leaves hold the instances as
/// single items: a ray that reaches one is taken into its group's space
/// (`Instance::ray_to_group`) and walks the group's tree, built once however many instances
/// place it, with t (and so the closest hit so far) shared between the two levels. Batched
/// queries take an instance's group ray by ray (a packet's rays part there).
pub struct Bvh {
    nodes: HugePageArray<Node>,
    /// The leaves' contents; a leaf node's `first .. first + count` indexes this.
    items: HugePageArray<LeafItem>,
    /// How many primitives the tree holds (those with finite bounds).
    prim_count: usize,
    shapes: Vec<AnalyticShape>,
    /// The scene's instances (what the leaves' `Instanced` items refer to) and a tree per
    /// group (over its triangles, in its space); both empty in a group's tree.
    instances: Vec<Instance>,
    groups: Vec<Bvh>,
    /// The polygons missed from behind (none in a group's tree).
    culled: CulledBacks,
    /// The processor's instructions, for the batched queries' dispatch.
    arch: pulp::Arch,
    /// Whether traversal prefetches the children a ray enters (`Bvh::prefetch`): only trees
    /// larger than `PREFETCH_ABOVE`.
    prefetch: bool,
    /// Whether batched closest hits test every item in lanes (`Bvh::closest_lanes`): trees
    /// of at most `LANES_ITEMS` items, each a quad or a sphere.
    in_lanes: bool,
}

/// A primitive during the build: the corners of its box in two `Vec4`s, so that binning and
/// partitioning take a primitive in two SIMD loads, and its packed reference in the lower
/// corner's fourth lane. The lane is only ever copied, never computed with, so its bits stay as
/// they are even where they read as a NaN (an instance's reference, kind 3, of index 2³⁰ −
/// 2²³ or more).
#[derive(Clone, Copy)]
struct BuildPrim {
    lower: Vec4,
    upper: Vec4,
}

impl BuildPrim {
    fn new(bounds: Bounds3, prim: PackedPrim) -> BuildPrim {
        BuildPrim {
            lower: bounds.min.extend(f32::from_bits(prim.raw())),
            upper: bounds.max.extend(0.0),
        }
    }

    #[inline(always)]
    fn prim(&self) -> PackedPrim {
        bytemuck::cast(self.lower.w.to_bits())
    }

    #[inline(always)]
    fn bounds(&self) -> Bounds3 {
        Bounds3 {
            min: self.lower.truncate(),
            max: self.upper.truncate(),
        }
    }

    /// Twice the box's centre (its corners' sum; the fourth lane means nothing): binning needs
    /// only the centres' order, and the halving would be one more operation a primitive.
    #[inline(always)]
    fn centroid2(&self) -> Vec4 {
        self.lower + self.upper
    }

    #[inline(always)]
    fn is_triangle(&self) -> bool {
        self.prim().kind() == PrimKind::Triangle
    }
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

/// What a tree is built over: a scene's quads, triangles, shapes and its instances' world
/// boxes, or one group's triangles alone.
#[derive(Clone, Copy)]
struct Source<'a> {
    quads: &'a [Quad],
    triangles: &'a TriangleMesh,
    shapes: &'a [ShapePrim],
    instances: &'a [Bounds3],
}

impl<'a> Source<'a> {
    fn group(mesh: &'a TriangleMesh) -> Source<'a> {
        Source {
            quads: &[],
            triangles: mesh,
            shapes: &[],
            instances: &[],
        }
    }

    /// The scene's primitives, with `instances` its instances' world boxes.
    fn scene(scene: &'a Scene, instances: &'a [Bounds3]) -> Source<'a> {
        Source {
            quads: &scene.quads,
            triangles: &scene.triangles,
            shapes: &scene.shapes,
            instances,
        }
    }
}

/// The world boxes of a scene's instances (`Instance::world_bounds`).
fn instance_boxes(scene: &Scene) -> Vec<Bounds3> {
    let instancing = &scene.instancing;
    instancing
        .instances
        .iter()
        .map(|i| i.world_bounds(instancing.group_of(i)))
        .collect()
}

impl Bvh {
    pub fn build(scene: &Scene) -> Result<Bvh, AccelError> {
        let total = scene.primitive_count() + scene.instancing.instances.len();
        if total > PackedPrim::MAX_INDEX as usize {
            return Err(AccelError::TooLarge(total));
        }
        let groups = scene
            .instancing
            .groups
            .par_iter()
            .map(|g| Bvh::build_over(Source::group(&g.mesh), CulledBacks::default()))
            .collect();
        let boxes = instance_boxes(scene);
        let source = Source::scene(scene, &boxes);
        Ok(Bvh {
            instances: scene.instancing.instances.clone(),
            groups,
            ..Bvh::build_over(source, scene.culled_backs())
        })
    }

    /// The tree over `source`'s primitives (no groups yet), missing the backs of `culled`.
    fn build_over(source: Source, culled: CulledBacks) -> Bvh {
        let total = source.quads.len()
            + source.triangles.len()
            + source.shapes.len()
            + source.instances.len();
        // Made on every thread, as the leaves' copies below (the two together: the 1M-triangle
        // terrain's build on two threads 0.917 → 0.842 s, medians of interleaved rounds).
        let build_prim = |bounds: Bounds3, kind: PrimKind, index: usize| {
            BuildPrim::new(
                bounds,
                PackedPrim::new(PrimRef {
                    kind,
                    index: index as u32,
                }),
            )
        };
        // Primitives with non-finite bounds can never be hit; leaving them out keeps every
        // box finite.
        let finite = |p: &BuildPrim| p.bounds().min.is_finite() && p.bounds().max.is_finite();
        let mut build: Vec<BuildPrim> = Vec::with_capacity(total);
        build.par_extend(
            source
                .quads
                .par_iter()
                .enumerate()
                .map(|(i, q)| build_prim(Bounds3::from_points(&q.vertices), PrimKind::Quad, i)),
        );
        build.par_extend((0..source.triangles.len()).into_par_iter().map(|i| {
            build_prim(
                Bounds3::from_points(&source.triangles.vertices(i)),
                PrimKind::Triangle,
                i,
            )
        }));
        build.extend(
            source
                .shapes
                .iter()
                .enumerate()
                .map(|(i, s)| build_prim(s.shape.bounds(), PrimKind::Shape, i)),
        );
        build.extend(
            source
                .instances
                .iter()
                .enumerate()
                .map(|(i, b)| build_prim(*b, PrimKind::Instanced, i)),
        );
        // Looked for on every thread first: the filter's pass is serial, and seldom needed
        // (filtered in the parallel loops, the primitives were gathered into lists of parts
        // and copied).
        if !build.par_iter().all(finite) {
            build.retain(finite);
        }

        let extents = Extents::of_parallel(&build);
        let root = build_node(&mut build, 0, 0, &extents, &mut Bins::new());
        let mut nodes = Vec::with_capacity(build.len() / 4 + 1);
        let mut leaves = Vec::new();
        if build.is_empty() {
            // An empty tree: a root whose slots are all unused.
            nodes.push(Node::EMPTY);
        } else {
            let mut collapse = Collapse {
                prims: &build,
                nodes: &mut nodes,
                leaves: &mut leaves,
                item_count: 0,
            };
            collapse.node(&root);
        }

        // Each leaf's items written straight into their array, in parallel.
        let item_count = leaves.iter().map(|(_, count)| count).sum();
        let items = HugePageArray::filled(item_count, |items| {
            let mut rest = items;
            let mut outs = Vec::with_capacity(leaves.len());
            for (range, count) in &leaves {
                let (out, tail) = rest.split_at_mut(*count);
                outs.push((range.clone(), out));
                rest = tail;
            }
            outs.into_par_iter()
                .for_each(|(range, out)| write_leaf_items(source, &build[range], out));
        });
        let bytes = nodes.len() * size_of::<Node>() + items.len() * size_of::<LeafItem>();
        let shapes: Vec<AnalyticShape> = source.shapes.iter().map(|s| s.shape).collect();
        let in_lanes = items.len() <= LANES_ITEMS
            && items.iter().all(|item| match item.view() {
                ItemView::Single(p) => match p.prim.kind() {
                    PrimKind::Quad => true,
                    PrimKind::Shape => {
                        matches!(shapes[p.prim.index() as usize], AnalyticShape::Sphere(_))
                    }
                    _ => false,
                },
                ItemView::Triangles(_) => false,
            });
        Bvh {
            prefetch: bytes > PREFETCH_ABOVE,
            nodes: HugePageArray::new(nodes),
            items,
            prim_count: build.len(),
            shapes,
            instances: Vec::new(),
            groups: Vec::new(),
            culled,
            arch: crate::simd::arch(),
            in_lanes,
        }
    }

    /// Checks the tree's invariants, and each group's tree's: every child box inside its
    /// parent's, every primitive's box inside its leaf's, every primitive in exactly one leaf,
    /// unused slots empty. Returns what is wrong.
    pub fn validate(&self, scene: &Scene) -> Result<(), String> {
        let boxes = instance_boxes(scene);
        self.validate_over(Source::scene(scene, &boxes))?;
        for (k, (tree, group)) in self.groups.iter().zip(&scene.instancing.groups).enumerate() {
            tree.validate_over(Source::group(&group.mesh))
                .map_err(|e| format!("group {k}: {e}"))?;
        }
        Ok(())
    }

    fn validate_over(&self, source: Source) -> Result<(), String> {
        let mut seen = std::collections::HashMap::<u32, u32>::new();
        let mut stack = vec![(0usize, None::<Bounds3>, 0usize)];
        while let Some((i, parent, depth)) = stack.pop() {
            let n = self.nodes.get(i).ok_or(format!("node {i} missing"))?;
            if depth > MAX_DEPTH + 1 {
                return Err(format!("node {i} is deeper than {MAX_DEPTH}"));
            }
            for slot in 0..WIDTH {
                let b = n.child_bounds(slot);
                if b.is_empty() {
                    if n.count[slot] != 0 || n.first[slot] != 0 {
                        return Err(format!("node {i}: unused slot {slot} refers to something"));
                    }
                    continue;
                }
                if parent.is_some_and(|p| !contains(&p, &b)) {
                    return Err(format!("node {i}: child {slot} sticks out of its parent"));
                }
                if n.count[slot] == 0 {
                    stack.push((n.first[slot] as usize, Some(b), depth + 1));
                    continue;
                }
                let items = self
                    .items
                    .get(n.first[slot] as usize..(n.first[slot] + n.count[slot]) as usize)
                    .ok_or(format!(
                        "node {i}: leaf {slot} runs past the leaves' contents"
                    ))?;
                for prim in items.iter().flat_map(LeafItem::prims) {
                    if !contains(&b, &prim_bounds(source, prim.unpack())) {
                        return Err(format!(
                            "primitive {:?} sticks out of its leaf in node {i}",
                            prim.unpack()
                        ));
                    }
                    *seen.entry(prim.raw()).or_default() += 1;
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

    /// The items of a leaf.
    #[inline(always)]
    fn leaf(&self, leaf: &Entry) -> &[LeafItem] {
        &self.items[leaf.first as usize..(leaf.first + leaf.count) as usize]
    }

    /// Tests the primitives of one leaf; keeps in `best` the closest hit (primitive, u, v)
    /// and shrinks `t_max` to it.
    #[inline(always)]
    fn leaf_closest(
        &self,
        leaf: &Entry,
        rays: (&Ray, &RayShear, &Tri4Ray),
        t_max: &mut f32,
        best: &mut Option<(PackedPrim, f32, f32)>,
        base: Option<u32>,
    ) {
        let (ray, shear, pack_ray) = rays;
        for item in self.leaf(leaf) {
            let limit = closest_limit(*t_max, best.is_some());
            match item.view() {
                ItemView::Triangles(pack) => {
                    let hits = pack.intersect(pack_ray, ray, shear, limit);
                    let mask = self.triangles_met(pack, hits.mask, ray);
                    for i in (0..4).filter(|i| mask >> i & 1 != 0) {
                        let hit = (rebase(pack.prim(i), base), hits.t[i], hits.u[i], hits.v[i]);
                        keep_closest(best, t_max, hit);
                    }
                }
                ItemView::Single(p) if p.prim.kind() == PrimKind::Instanced => {
                    self.instance_closest(p.prim.index(), ray, t_max, best);
                }
                ItemView::Single(p) => {
                    if let Some((t, u, v)) = self.hit_single(&p, ray, || shear, limit) {
                        keep_closest(best, t_max, (p.prim, t, u, v));
                    }
                }
            }
        }
    }

    /// The closest hits of up to `LANES` rays, each item of the tree (`in_lanes`) tested
    /// against all of them at once (`lanes`): what `closest` answers each ray. A lane the
    /// quad test leaves unsure is tested alone.
    #[inline(always)]
    fn closest_lanes(&self, rays: &[Ray], hits: &mut [Option<PrimHit>]) {
        const NONE: u32 = u32::MAX;
        let lanes = RayLanes::new(rays);
        let mut t_max: [f32; LANES] = std::array::from_fn(|k| rays[k.min(rays.len() - 1)].t_max);
        // The closest hit so far, lane by lane: its primitive (`NONE` before one) and (u, v).
        let (mut best, mut best_u, mut best_v) = ([NONE; LANES], [0.0; LANES], [0.0; LANES]);
        let mut found = LaneHits::default();
        for item in self.items.iter() {
            let to_max: [bool; LANES] = std::array::from_fn(|k| best[k] != NONE);
            let limits = Limits {
                t_max: &t_max,
                to_max: &to_max,
            };
            let p = self.item_lanes(item, &lanes, &limits, &mut found);
            for (k, ray) in rays.iter().enumerate().filter(|&(k, _)| found.unsure[k]) {
                let shear = RayShear::new(ray);
                let limit = closest_limit(t_max[k], to_max[k]);
                let hit = self.hit_single(&p, ray, || &shear, limit);
                found.hit[k] = hit.is_some();
                if let Some((t, u, v)) = hit {
                    (found.t[k], found.u[k], found.v[k]) = (t, u, v);
                }
            }
            // `keep_closest`, lane by lane (without branches, as `lanes` joins conditions).
            let raw = p.prim.raw();
            for k in 0..LANES {
                let t = found.t[k];
                let wins = found.hit[k]
                    & ((t < t_max[k]) | ((t == t_max[k]) & (best[k] != NONE) & (raw < best[k])));
                if wins {
                    t_max[k] = t;
                    best[k] = raw;
                    best_u[k] = found.u[k];
                    best_v[k] = found.v[k];
                }
            }
        }
        for (k, (ray, hit)) in rays.iter().zip(hits.iter_mut()).enumerate() {
            *hit = (best[k] != NONE && ray.is_traceable()).then(|| PrimHit {
                t: t_max[k],
                prim: PackedPrim(best[k]).unpack(),
                u: best_u[k],
                v: best_v[k],
                exact: true,
            });
        }
    }

    /// Tests `item`, a quad or a sphere (`in_lanes`), against every lane of `rays` within
    /// `limits` into `found`, and returns it.
    #[inline(always)]
    fn item_lanes(
        &self,
        item: &LeafItem,
        rays: &RayLanes,
        limits: &Limits,
        found: &mut LaneHits,
    ) -> LeafPrim {
        let ItemView::Single(p) = item.view() else {
            unreachable!("trees in lanes hold quads and spheres only");
        };
        match (p.prim.kind(), self.shapes.get(p.prim.index() as usize)) {
            (PrimKind::Quad, _) => {
                lanes::quad(rays, (&p.v, p.normal, self.culled.quads), limits, found);
            }
            (PrimKind::Shape, Some(AnalyticShape::Sphere(s))) => {
                lanes::sphere(rays, s, limits, found);
            }
            _ => unreachable!("trees in lanes hold quads and spheres only"),
        }
        p
    }

    /// The lanes of `hits` (of `pack`) whose triangles `ray` meets: those it hits from the front
    /// where triangles are one-sided (`CulledBacks`), else all.
    #[inline(always)]
    fn triangles_met(&self, pack: &Tri4, hits: u32, ray: &Ray) -> u32 {
        if !self.culled.triangles || hits == 0 {
            return hits;
        }
        pack.facing(hits, ray.direction)
    }

    /// `shear` gives the ray's shear, made when first asked for where the caller makes it
    /// lazily (`RayForms`): a quad facing away, or a shape, does not ask.
    #[inline(always)]
    fn hit_single<'s>(
        &self,
        p: &LeafPrim,
        ray: &Ray,
        shear: impl FnOnce() -> &'s RayShear,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        match p.prim.kind() {
            PrimKind::Triangle => unreachable!("triangles are tested in packs of four"),
            PrimKind::Quad => {
                if !self.culled.meets(PrimKind::Quad, p.normal, ray.direction) {
                    return None;
                }
                intersect_quad_sheared(ray, shear(), t_max, &p.v)
            }
            PrimKind::Shape => self.shapes[p.prim.index() as usize]
                .intersect(ray, t_max)
                .map(|(t, _)| (t, 0.0, 0.0)),
            PrimKind::Instanced => unreachable!("instances are walked into, not tested"),
        }
    }

    /// The closest hit so far (`best`, at `t_max`) against instance `k`'s triangles: its
    /// group's tree walked with the ray in the group's space, the group's triangles' hits
    /// numbered as instanced ones. Not inlined: it walks a tree from within a walk.
    #[inline(never)]
    fn instance_closest(
        &self,
        k: u32,
        ray: &Ray,
        t_max: &mut f32,
        best: &mut Option<(PackedPrim, f32, f32)>,
    ) {
        let instance = &self.instances[k as usize];
        let local = instance.ray_to_group(ray);
        let shear = RayShear::new(&local);
        let pack_ray = Tri4Ray::new(&local, &shear);
        let mut closest = ClosestHit {
            ray: (&local, &shear, &pack_ray),
            best: *best,
            base: Some(instance.first),
        };
        let group = &self.groups[instance.group as usize];
        group.traverse::<true>((&local, &RayBoxes::new(&local)), ROOT, t_max, &mut closest);
        *best = closest.best;
    }

    /// Whether a triangle of instance `k` blocks the ray (in the group's space, as
    /// `instance_closest`).
    #[inline(never)]
    fn instance_blocks(&self, k: u32, ray: &Ray) -> bool {
        let instance = &self.instances[k as usize];
        let local = instance.ray_to_group(ray);
        let group = &self.groups[instance.group as usize];
        group.occluded_below(ROOT, (&local, &OnceCell::new()), inverse_direction(&local))
    }

    /// Asks the processor to bring `e`'s memory (its node, or its leaf's items up to
    /// `PREFETCH_LINES` cache lines) into the cache, as Embree does for every child a ray
    /// enters. A ray's time goes mostly to waiting for nodes and leaves; asked for together,
    /// the loads of every child entered (the one taken next and those pushed for later) and
    /// of every line of each overlap. Small trees, in the cache anyway, skip it.
    #[inline(always)]
    fn prefetch(&self, e: &Entry) {
        if !self.prefetch {
            return;
        }
        let (start, len) = if e.count == 0 {
            let node = self.nodes.as_ptr().wrapping_add(e.first as usize);
            (node.cast::<u8>(), size_of::<Node>())
        } else {
            let items = self.items.as_ptr().wrapping_add(e.first as usize);
            (items.cast::<u8>(), e.count as usize * size_of::<LeafItem>())
        };
        let skew = start as usize % CACHE_LINE;
        let lines = (skew + len).div_ceil(CACHE_LINE).min(PREFETCH_LINES);
        for k in 0..lines {
            prefetch_line(start.wrapping_sub(skew).wrapping_add(k * CACHE_LINE));
        }
    }

    /// Walks the tree below `start` (`ROOT`, or a child the ray was found to enter), the
    /// children a ray enters nearest first when `ORDERED`, else in slot order; `boxes` is
    /// `ray` set up for the slab test. `visit` tests a leaf and returns true to stop.
    #[inline(always)]
    fn traverse<const ORDERED: bool>(
        &self,
        (ray, boxes): (&Ray, &RayBoxes),
        start: Entry,
        t_max: &mut f32,
        visit: &mut impl LeafVisit,
    ) {
        debug_assert!(
            ray.is_traceable(),
            "a ray of inf or NaN reached the BVH: {ray:?}"
        );
        // A ray of inf or NaN misses: its slab test can enter empty slots (whose child index
        // is the root's), and the walk would never end, its stack growing with every lap.
        // Finite rays never enter an empty slot, so the stack holds at most
        // `MAX_DEPTH` × (`WIDTH` − 1) entries.
        if self.items.is_empty() || !ray.is_traceable() {
            return;
        }
        // Boxes are kept up to `BOX_REACH` beyond the current hit: see there.
        let reach = |t: f32| t * BOX_REACH;
        // Children not taken at once wait with their entry distance: a closer hit found
        // meanwhile lets them be skipped without testing their box again.
        let mut stack = [UNUSED; STACK];
        let mut spilled: Vec<Entry> = Vec::new();
        let mut top = 0usize;
        let mut current = start;
        loop {
            if current.count > 0 {
                if visit.visit(self, &current, t_max) {
                    return;
                }
            } else {
                let node = &self.nodes[current.first as usize];
                let (mut mask, near) = slab(node, boxes, ray.t_min, reach(*t_max));
                if mask != 0 {
                    let entry = |slot: usize| {
                        let e = Entry {
                            first: node.first[slot],
                            count: node.count[slot],
                            t: near[slot],
                        };
                        self.prefetch(&e);
                        e
                    };
                    if mask & (mask - 1) == 0 {
                        current = entry(mask.trailing_zeros() as usize);
                        continue;
                    }
                    // Two or more children: sorted nearest first by insertion (for closest
                    // hits; any hit ends an occlusion query, so it takes them as they come),
                    // the first taken now, the others pushed last first.
                    let mut entered = [UNUSED; WIDTH];
                    let mut k = 0;
                    while mask != 0 {
                        let e = entry(mask.trailing_zeros() as usize);
                        mask &= mask - 1;
                        let mut j = k;
                        while ORDERED && j > 0 && entered[j - 1].t > e.t {
                            entered[j] = entered[j - 1];
                            j -= 1;
                        }
                        entered[j] = e;
                        k += 1;
                    }
                    for e in entered[1..k].iter().rev() {
                        match stack.get_mut(top) {
                            Some(slot) => *slot = *e,
                            None => spilled.push(*e),
                        }
                        top += 1;
                    }
                    current = entered[0];
                    continue;
                }
            }
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let e = match stack.get(top) {
                    Some(e) => *e,
                    None => spilled.pop().expect("spilled entries are counted in top"),
                };
                if e.t <= reach(*t_max) {
                    current = e;
                    break;
                }
            }
        }
    }
}

/// Bytes of a cache line.
const CACHE_LINE: usize = 64;
/// Most cache lines `Bvh::prefetch` asks for: a node's four, or a leaf's first.
const PREFETCH_LINES: usize = 6;
/// Trees of more bytes than this prefetch (`Bvh::prefetch`): smaller ones stay in the cache,
/// where the prefetch is pure cost (on the Cornell box, prefetching every child cost its
/// single-ray queries 4–12% of their rate; skipped, they run as without it).
const PREFETCH_ABOVE: usize = 1 << 20;

/// Starts loading the cache line at `p` into every level of the cache (a hint: it neither
/// reads nor faults, whatever the address). `pulp` wraps the instruction safely; its check
/// for SSE is a constant on x86_64, where SSE is baseline, so the hot loop pays no detection.
#[inline(always)]
fn prefetch_line(p: *const u8) {
    #[cfg(target_arch = "x86_64")]
    if let Some(sse) = pulp::core_arch::x86::Sse::try_new() {
        sse._mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast());
    }
    // Elsewhere no hint: the loads are only not overlapped.
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
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

/// How far a primitive's hit may lie for `keep_closest` to weigh it, with the closest hit so
/// far at `t_max` (`found`) or none: a hit at exactly the current t may still win by the tie
/// rule.
#[inline(always)]
fn closest_limit(t_max: f32, found: bool) -> f32 {
    if found {
        t_max.next_up()
    } else {
        t_max
    }
}

/// How far beyond the current hit a box is still opened, as a factor. The slab test's entry
/// distance is rounded otherwise than a primitive's exact t: a quad met exactly at its edge,
/// a few ulps nearer than the hit found first, lay in a box whose computed entry was a few
/// ulps beyond that hit, and was culled (three camera rays along the fog box's edges in
/// 262,144, caught once the surface stopped re-settling the BVH's hits); and a hit at the
/// current t still competes by the tie rule. Embree's filter keeps the same room.
const BOX_REACH: f32 = 1.0 + 1e-5;

/// The slab test's far distance is enlarged by 2γ₃ (Ize, "Robust BVH ray traversal") so that
/// rounding never culls a box the ray touches.
const ROBUST: f32 = 1.0 + 2.0 * 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Ray–box slab test of a node's children, four at once: a bit per child the ray enters
/// within `(t_min, t_max)`, and the distances at which it enters (the far one enlarged by
/// `ROBUST`).
#[inline(always)]
fn slab(n: &Node, ray: &RayBoxes, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
    // The far plane's row is the near plane's other one: 3 apart.
    let far_row = |axis: usize| (ray.near[axis] + 3) % 6;
    let (t_min, t_max) = (Vec4::splat(t_min), Vec4::splat(t_max));
    let mut mask = 0;
    let mut entry = [0.0; WIDTH];
    for g in 0..GROUPS {
        let plane = |axis: usize, row: usize| (n.bounds[row][g] - ray.org[axis]) * ray.inv[axis];
        let near = plane(0, ray.near[0])
            .max(plane(1, ray.near[1]))
            .max(plane(2, ray.near[2]).max(t_min));
        let far = plane(0, far_row(0))
            .min(plane(1, far_row(1)))
            .min(plane(2, far_row(2)))
            * ROBUST;
        let far = far.min(t_max);
        mask |= near.cmple(far).bitmask() << (4 * g);
        entry[4 * g..4 * g + 4].copy_from_slice(&near.to_array());
    }
    (mask, entry)
}

impl Accel for Bvh {
    fn name(&self) -> &'static str {
        "bvh"
    }

    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.closest(ray)
    }

    /// The rays one by one, as `intersect`, in a loop compiled for the processor's widest
    /// instructions (`pulp`'s run-time dispatch): the walk and the tests inlined into it take
    /// the VEX encodings and wider registers.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<PrimHit>]) {
        self.arch.dispatch(ClosestBatch {
            bvh: self,
            rays,
            hits,
        })
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_below(ROOT, (ray, &OnceCell::new()), inverse_direction(ray))
    }

    /// Packets of `PACKET` rays walk the tree together: a box is tested against all the
    /// packet's rays still to be decided that entered its parent, in one pass over the box, and
    /// a leaf's primitives against each of them. The answers are `occluded`'s, ray by ray:
    /// each ray is taken into exactly the boxes it would enter alone. Compiled, as
    /// `intersect_batch`, for the processor's widest instructions.
    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        self.arch.dispatch(OccludedBatch {
            bvh: self,
            rays,
            occluded,
        })
    }
}

impl Bvh {
    /// `intersect`, inlined wherever it is called.
    #[inline(always)]
    fn closest(&self, ray: &Ray) -> Option<PrimHit> {
        let shear = RayShear::new(ray);
        let pack_ray = Tri4Ray::new(ray, &shear);
        let mut t_max = ray.t_max;
        let mut closest = ClosestHit {
            ray: (ray, &shear, &pack_ray),
            best: None,
            base: None,
        };
        self.traverse::<true>((ray, &RayBoxes::new(ray)), ROOT, &mut t_max, &mut closest);
        closest.best.map(|(prim, u, v)| PrimHit {
            t: t_max,
            prim: prim.unpack(),
            u,
            v,
            exact: true,
        })
    }

    /// Whether a primitive below `start` blocks the ray (with its forms, and the inverse of
    /// its direction made before).
    #[inline(always)]
    fn occluded_below(&self, start: Entry, ray: OneRay, inv: [f32; 3]) -> bool {
        let mut t_max = ray.0.t_max;
        let mut any = AnyHit { ray, hit: false };
        let boxes = RayBoxes::with_inverse(ray.0, inv);
        self.traverse::<false>((ray.0, &boxes), start, &mut t_max, &mut any);
        any.hit
    }

    /// Whether `item` blocks the ray (with its forms, made here if it needs them).
    #[inline(always)]
    fn item_blocks(&self, item: &LeafItem, (ray, forms): OneRay) -> bool {
        let forms = || RayForms::of(forms, ray);
        match item.view() {
            ItemView::Triangles(pack) => {
                let RayForms {
                    shear,
                    pack: pack_ray,
                } = forms();
                let hits = pack.intersect(pack_ray, ray, shear, ray.t_max);
                self.triangles_met(pack, hits.mask, ray) != 0
            }
            ItemView::Single(p) if p.prim.kind() == PrimKind::Instanced => {
                self.instance_blocks(p.prim.index(), ray)
            }
            ItemView::Single(p) => self
                .hit_single(&p, ray, || &forms().shear, ray.t_max)
                .is_some(),
        }
    }

    /// `occluded` for up to `PACKET` rays at once (see `occluded_batch`); `stack` is working
    /// space (entries still to visit with the rays that entered them, bit `i` ray `i`).
    #[inline(always)]
    fn occluded_packet(
        &self,
        rays: &[Ray],
        packet: &Packet,
        occluded: &mut [bool],
        stack: &mut Vec<(Entry, u32)>,
    ) {
        let one = |i: usize| packet.one(rays, i);
        // Rays not yet found blocked.
        let mut open: u32 = (1 << rays.len()) - 1;
        // The packet walk takes only occupied slots, so it ends whatever the rays; each ray
        // alone below `PACKET_SWITCH` goes through `traverse`, which misses untraceable rays.
        debug_assert!(
            rays.iter().all(Ray::is_traceable),
            "a ray of inf or NaN reached the BVH"
        );
        if !self.items.is_empty() {
            stack.clear();
            stack.push((ROOT, open));
            while let Some((entry, entered)) = stack.pop() {
                let entered = entered & open;
                if entry.count > 0 {
                    open &= !self.leaf_blocks(&entry, entered, (packet, rays));
                } else if entered.count_ones() <= PACKET_SWITCH {
                    for i in bits(entered) {
                        if self.occluded_below(entry, one(i), packet.boxes.inverse(i)) {
                            open &= !(1 << i);
                        }
                    }
                } else {
                    // Pushed last slot first: taken in slot order, as `occluded` takes them.
                    let node = &self.nodes[entry.first as usize];
                    for slot in bits(occupied(node)).rev() {
                        let inside = packet.boxes.enter(node, slot) & entered;
                        if inside != 0 {
                            let child = Entry {
                                first: node.first[slot],
                                count: node.count[slot],
                                t: 0.0,
                            };
                            stack.push((child, inside));
                        }
                    }
                }
                if open == 0 {
                    break;
                }
            }
        }
        for (i, o) in occluded.iter_mut().enumerate() {
            *o = open >> i & 1 == 0;
        }
    }

    /// The rays of `entered` (bit `i`: ray `i` of the packet) that a primitive of `leaf`
    /// blocks. A quad is tested against four rays at once where they share their axes (the
    /// packet's rays run alike: camera rays, shadow rays to a small light, rays between two
    /// patches), every other primitive ray by ray.
    #[inline(always)]
    fn leaf_blocks(&self, leaf: &Entry, entered: u32, (packet, rays): (&Packet, &[Ray])) -> u32 {
        let one = |i: usize| packet.one(rays, i);
        let mut blocked = 0;
        for item in self.leaf(leaf) {
            let open = entered & !blocked;
            if open == 0 {
                break;
            }
            let quad = match item.view() {
                ItemView::Single(p) if p.prim.kind() == PrimKind::Quad => Some(p),
                _ => None,
            };
            for g in 0..PACKET / 4 {
                let lanes = open >> (4 * g) & 0xf;
                let four = match &quad {
                    Some(p) if lanes.count_ones() > 1 => packet.rays4(rays, g).map(|r| (p, r)),
                    _ => None,
                };
                let hit = match four {
                    Some((p, rays4)) => self.quad_blocks(p, rays4, lanes, |i| one(4 * g + i)),
                    None => bits(lanes)
                        .filter(|&i| self.item_blocks(item, one(4 * g + i)))
                        .fold(0, |m, i| m | 1 << i),
                };
                blocked |= hit << (4 * g);
            }
        }
        blocked
    }

    /// The lanes of `lanes` (bits of the four rays of `rays4`) that the quad `p` blocks,
    /// as `hit_single` decides each: its two triangles tested in all four lanes, and a lane
    /// whose answer hangs on an edge function exactly zero decided by `hit_single` itself.
    #[inline(always)]
    fn quad_blocks<'a>(
        &self,
        p: &LeafPrim,
        rays4: &Rays4,
        lanes: u32,
        one: impl Fn(usize) -> OneRay<'a>,
    ) -> u32 {
        let (first, first_edge) = rays4.hit([p.v[0], p.v[1], p.v[3]]);
        let (second, second_edge) = rays4.hit([p.v[2], p.v[3], p.v[1]]);
        let facing = if self.culled.quads {
            rays4.faces(p.normal)
        } else {
            0xf
        };
        let hit = (first | second) & facing & lanes;
        let unsure = (first_edge | second_edge) & facing & lanes & !hit;
        bits(unsure).fold(hit, |hit, i| {
            let (ray, forms) = one(i);
            let shear = || &RayForms::of(forms, ray).shear;
            match self.hit_single(p, ray, shear, ray.t_max) {
                Some(_) => hit | 1 << i,
                None => hit,
            }
        })
    }
}

/// What a walk of the tree (`Bvh::traverse`) does at each leaf it enters. A trait and not a
/// closure so that the test is inlined into the walk wherever the walk is: a closure was
/// compiled apart, in the baseline instructions, even under the batched queries' dispatch
/// (the path tracer's time, measured with `perf`).
trait LeafVisit {
    /// Tests the items of `leaf` (shrinking `t_max` to a hit found); true stops the walk.
    fn visit(&mut self, bvh: &Bvh, leaf: &Entry, t_max: &mut f32) -> bool;
}

/// The closest hit: primitive, u, v (its t is the walk's `t_max`).
struct ClosestHit<'a> {
    /// The ray with its shear and pack form (a closest hit tests a primitive at once).
    ray: (&'a Ray, &'a RayShear, &'a Tri4Ray),
    best: Option<(PackedPrim, f32, f32)>,
    /// In a group's tree, the `Instanced` index of the instance's first triangle (`rebase`);
    /// None in the scene's.
    base: Option<u32>,
}

/// A triangle's reference as a hit reports it: as it is in the scene's tree, or, in a group's
/// tree walked for an instance, the instanced triangle (`base` its first one).
#[inline(always)]
fn rebase(prim: PackedPrim, base: Option<u32>) -> PackedPrim {
    match base {
        None => prim,
        Some(first) => PackedPrim::new(PrimRef {
            kind: PrimKind::Instanced,
            index: first + prim.index(),
        }),
    }
}

impl LeafVisit for ClosestHit<'_> {
    #[inline(always)]
    fn visit(&mut self, bvh: &Bvh, leaf: &Entry, t_max: &mut f32) -> bool {
        bvh.leaf_closest(leaf, self.ray, t_max, &mut self.best, self.base);
        false
    }
}

/// Whether anything blocks the ray: the first hit stops the walk.
struct AnyHit<'a> {
    ray: OneRay<'a>,
    hit: bool,
}

impl LeafVisit for AnyHit<'_> {
    #[inline(always)]
    fn visit(&mut self, bvh: &Bvh, leaf: &Entry, _: &mut f32) -> bool {
        self.hit = bvh
            .leaf(leaf)
            .iter()
            .any(|item| bvh.item_blocks(item, self.ray));
        self.hit
    }
}

/// `Bvh::intersect_batch`'s loop, for `pulp::Arch::dispatch`.
struct ClosestBatch<'a> {
    bvh: &'a Bvh,
    rays: &'a [Ray],
    hits: &'a mut [Option<PrimHit>],
}

impl pulp::WithSimd for ClosestBatch<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        if self.bvh.in_lanes {
            for (rays, hits) in self.rays.chunks(LANES).zip(self.hits.chunks_mut(LANES)) {
                self.bvh.closest_lanes(rays, hits);
            }
            return;
        }
        for (ray, hit) in self.rays.iter().zip(self.hits.iter_mut()) {
            *hit = self.bvh.closest(ray);
        }
    }
}

/// `Bvh::occluded_batch`'s loop, for `pulp::Arch::dispatch`.
struct OccludedBatch<'a> {
    bvh: &'a Bvh,
    rays: &'a [Ray],
    occluded: &'a mut [bool],
}

impl pulp::WithSimd for OccludedBatch<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let mut stack = Vec::with_capacity(4 * WIDTH);
        let mut packet = Packet::default();
        let chunks = self
            .rays
            .chunks(PACKET)
            .zip(self.occluded.chunks_mut(PACKET));
        for (rays, occluded) in chunks {
            packet.load(rays);
            self.bvh
                .occluded_packet(rays, &packet, occluded, &mut stack);
        }
    }
}

/// A ray's shear and its form for the pack test, as a leaf's primitives take it.
struct RayForms {
    shear: RayShear,
    pack: Tri4Ray,
}

impl RayForms {
    #[inline(always)]
    fn new(ray: &Ray) -> RayForms {
        let shear = RayShear::new(ray);
        let pack = Tri4Ray::new(ray, &shear);
        RayForms { shear, pack }
    }

    /// The forms of `ray` kept in `cell`, made there on first use.
    #[inline(always)]
    fn of<'a>(cell: &'a OnceCell<RayForms>, ray: &Ray) -> &'a RayForms {
        cell.get_or_init(|| RayForms::new(ray))
    }
}

/// A ray of an occlusion query with its forms, made when a primitive test first needs them.
/// Most of a shadow ray's walk meets boxes it misses, quads facing away and shapes, which
/// need no shear: made at once, the three divisions were a quarter of the batched occlusion
/// query's time on the Cornell box.
type OneRay<'a> = (&'a Ray, &'a OnceCell<RayForms>);

/// A packet's rays in every form its tests take, filled afresh for each packet (lanes beyond
/// its rays repeat its last one; no query asks for them); the forms for the primitives' tests
/// when first needed.
#[derive(Default)]
struct Packet {
    forms: [OnceCell<RayForms>; PACKET],
    boxes: PacketBoxes,
    /// Each group of four rays set up for quads (if they share their axes), made when a
    /// quad first needs it: scenes of triangles never do.
    groups: [OnceCell<Option<Rays4>>; PACKET / 4],
}

impl Packet {
    #[inline(always)]
    fn load(&mut self, rays: &[Ray]) {
        self.boxes.load(|i| &rays[i.min(rays.len() - 1)]);
        self.forms = Default::default();
        self.groups = Default::default();
    }

    /// Group `g` of `rays` (the rays loaded) set up for quads, if its rays share their axes.
    #[inline(always)]
    fn rays4(&self, rays: &[Ray], g: usize) -> Option<&Rays4> {
        self.groups[g]
            .get_or_init(|| {
                let lane = |i: usize| {
                    let i = (4 * g + i).min(rays.len() - 1);
                    (&rays[i], &RayForms::of(&self.forms[i], &rays[i]).shear)
                };
                Rays4::new([lane(0), lane(1), lane(2), lane(3)])
            })
            .as_ref()
    }

    /// Ray `i` of `rays` (the rays loaded) with its forms.
    #[inline(always)]
    fn one<'a>(&'a self, rays: &'a [Ray], i: usize) -> OneRay<'a> {
        (&rays[i], &self.forms[i])
    }
}

/// The positions of the set bits of `mask`, lowest first (or highest first, reversed).
fn bits(mask: u32) -> Bits {
    Bits(mask)
}

/// The set bits left of a mask (see `bits`).
struct Bits(u32);

impl Iterator for Bits {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        (self.0 != 0).then(|| {
            let i = self.0.trailing_zeros();
            self.0 &= self.0 - 1;
            i as usize
        })
    }
}

impl DoubleEndedIterator for Bits {
    #[inline(always)]
    fn next_back(&mut self) -> Option<usize> {
        (self.0 != 0).then(|| {
            let i = u32::BITS - 1 - self.0.leading_zeros();
            self.0 &= !(1 << i);
            i as usize
        })
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

/// The box of a tree's primitive (an `Instanced` one an instance, by its world box).
fn prim_bounds(source: Source, prim: PrimRef) -> Bounds3 {
    let i = prim.index as usize;
    match prim.kind {
        PrimKind::Quad => Bounds3::from_points(&source.quads[i].vertices),
        PrimKind::Triangle => Bounds3::from_points(&source.triangles.vertices(i)),
        PrimKind::Shape => source.shapes[i].shape.bounds(),
        PrimKind::Instanced => source.instances[i],
    }
}

/// Writes a leaf's contents into `out` (as many items as `leaf_items` counts): its triangles
/// in packs of four, then its other primitives.
fn write_leaf_items(source: Source, leaf: &[BuildPrim], out: &mut [LeafItem]) {
    let mut out = out.iter_mut();
    let mut pack = [([Vec3::ZERO; 3], leaf[0].prim()); 4];
    let mut in_pack = 0;
    let mut write_pack = |pack: &[([Vec3; 3], PackedPrim)]| {
        let item = out.next().expect("the leaf's items were counted");
        *item = LeafItem::triangles(Tri4::new(pack));
    };
    for p in leaf.iter().filter(|p| p.is_triangle()) {
        let vertices = source.triangles.vertices(p.prim().index() as usize);
        pack[in_pack] = (vertices, p.prim());
        in_pack += 1;
        if in_pack == 4 {
            write_pack(&pack);
            in_pack = 0;
        }
    }
    if in_pack > 0 {
        write_pack(&pack[..in_pack]);
    }
    for p in leaf {
        let i = p.prim().index() as usize;
        let (v, normal) = match p.prim().kind() {
            PrimKind::Triangle => continue,
            PrimKind::Quad => (source.quads[i].vertices, source.quads[i].normal),
            PrimKind::Shape | PrimKind::Instanced => ([Vec3::ZERO; 4], Vec3::ZERO),
        };
        let item = out.next().expect("the leaf's items were counted");
        *item = LeafItem::single(&LeafPrim {
            v,
            normal,
            prim: p.prim(),
        });
    }
}

/// How many items `write_leaf_items` makes of a leaf.
fn leaf_items(leaf: &[BuildPrim]) -> usize {
    let triangles = leaf.iter().filter(|p| p.is_triangle()).count();
    triangles.div_ceil(4) + leaf.len() - triangles
}

/// The box of some primitives and the box of their centres (doubled, as `centroid2`), each
/// as its corners (the fourth lanes mean nothing).
#[derive(Clone, Copy)]
struct Extents {
    lower: Vec4,
    upper: Vec4,
    centre_lower: Vec4,
    centre_upper: Vec4,
}

impl Extents {
    const EMPTY: Extents = Extents {
        lower: Vec4::INFINITY,
        upper: Vec4::NEG_INFINITY,
        centre_lower: Vec4::INFINITY,
        centre_upper: Vec4::NEG_INFINITY,
    };

    #[inline(always)]
    fn add(&mut self, p: &BuildPrim) {
        self.lower = self.lower.min(p.lower);
        self.upper = self.upper.max(p.upper);
        self.add_centre(p.centroid2());
    }

    #[inline(always)]
    fn add_centre(&mut self, c: Vec4) {
        self.centre_lower = self.centre_lower.min(c);
        self.centre_upper = self.centre_upper.max(c);
    }

    fn union(self, o: Extents) -> Extents {
        Extents {
            lower: self.lower.min(o.lower),
            upper: self.upper.max(o.upper),
            centre_lower: self.centre_lower.min(o.centre_lower),
            centre_upper: self.centre_upper.max(o.centre_upper),
        }
    }

    fn of(prims: &[BuildPrim]) -> Extents {
        let mut e = Extents::EMPTY;
        prims.iter().for_each(|p| e.add(p));
        e
    }

    /// `of`, over parts of `prims` on every thread.
    fn of_parallel(prims: &[BuildPrim]) -> Extents {
        prims
            .par_chunks(PARALLEL_THRESHOLD)
            .map(Extents::of)
            .reduce(|| Extents::EMPTY, Extents::union)
    }

    fn bounds(&self) -> Bounds3 {
        Bounds3 {
            min: self.lower.truncate(),
            max: self.upper.truncate(),
        }
    }
}

/// Half the surface area of the box between `lower` and `upper` (the SAH compares ratios of
/// areas).
#[inline(always)]
fn half_area(lower: Vec4, upper: Vec4) -> f32 {
    let e = (upper - lower).truncate();
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// Where binning puts a centre: per axis, bin `⌊(c − lo)·scale⌋` of `bins` (the last one
/// also holding the highest centre); an axis along which the centres do not spread has
/// scale 0, every primitive in its first bin.
#[derive(Clone, Copy)]
struct BinMap {
    lo: Vec4,
    scale: Vec4,
    bins: usize,
}

impl BinMap {
    fn new(e: &Extents, bins: usize) -> BinMap {
        let extent = e.centre_upper - e.centre_lower;
        let scale = Vec4::splat(bins as f32) / extent;
        BinMap {
            lo: e.centre_lower,
            scale: Vec4::select(extent.cmpgt(Vec4::ZERO), scale, Vec4::ZERO),
            bins,
        }
    }

    /// The bins of centre `c` along the three axes.
    #[inline(always)]
    fn bins(&self, c: Vec4) -> [usize; 3] {
        let f = ((c - self.lo) * self.scale).to_array();
        [0, 1, 2].map(|a| (f[a] as usize).min(self.bins - 1))
    }

    /// The bin of centre `c` along `axis`: the same number as `bins` finds (the same
    /// operations on the same lane).
    #[inline(always)]
    fn bin(&self, c: Vec4, axis: usize) -> usize {
        (((c[axis] - self.lo[axis]) * self.scale[axis]) as usize).min(self.bins - 1)
    }
}

/// Per axis and bin the box of the primitives whose centres fall in it, and their counts
/// (primitives in the low 32 bits, those of them that are not triangles in the high ones:
/// one addition counts both).
#[derive(Clone)]
struct Bins {
    lower: [[Vec4; BINS]; 3],
    upper: [[Vec4; BINS]; 3],
    counts: [[u64; BINS]; 3],
}

impl Bins {
    fn new() -> Box<Bins> {
        Box::new(Bins {
            lower: [[Vec4::INFINITY; BINS]; 3],
            upper: [[Vec4::NEG_INFINITY; BINS]; 3],
            counts: [[0; BINS]; 3],
        })
    }

    /// Empties the first `bins` bins of each axis, those `fill` will use.
    fn clear(&mut self, bins: usize) {
        for a in 0..3 {
            self.lower[a][..bins].fill(Vec4::INFINITY);
            self.upper[a][..bins].fill(Vec4::NEG_INFINITY);
            self.counts[a][..bins].fill(0);
        }
    }

    /// Adds `prims` to the bins `map` puts them in (all three axes in one pass).
    fn fill(&mut self, prims: &[BuildPrim], map: &BinMap) {
        for p in prims {
            let count = 1 | (!p.is_triangle() as u64) << 32;
            let bins = map.bins(p.centroid2());
            for (a, &b) in bins.iter().enumerate() {
                self.lower[a][b] = self.lower[a][b].min(p.lower);
                self.upper[a][b] = self.upper[a][b].max(p.upper);
                self.counts[a][b] += count;
            }
        }
    }

    /// Adds the first `bins` bins of `o` to those of `self`.
    fn merge(mut self: Box<Bins>, o: Box<Bins>, bins: usize) -> Box<Bins> {
        for a in 0..3 {
            for b in 0..bins {
                self.lower[a][b] = self.lower[a][b].min(o.lower[a][b]);
                self.upper[a][b] = self.upper[a][b].max(o.upper[a][b]);
                self.counts[a][b] += o.counts[a][b];
            }
        }
        self
    }

    /// The box of bins `range` along `axis`.
    fn union(&self, axis: usize, range: std::ops::Range<usize>) -> (Vec4, Vec4) {
        range.fold((Vec4::INFINITY, Vec4::NEG_INFINITY), |(lo, hi), b| {
            (lo.min(self.lower[axis][b]), hi.max(self.upper[axis][b]))
        })
    }
}

/// What `leaf_cost` makes of a bin count (`Bins::counts`).
fn counted_cost(count: u64) -> f32 {
    let (prims, singles) = (count as u32, (count >> 32) as u32);
    leaf_cost(prims - singles, singles)
}

/// Bins for a node of `n` primitives: fewer for small nodes (as Embree's builders), whose
/// bins would mostly stay empty and whose time goes to clearing and sweeping them.
fn bin_count(n: usize) -> usize {
    (4 + n / 2).min(BINS)
}

/// The cheapest SAH split of the binned primitives: (axis, last bin of the left side, cost
/// relative to one triangle intersection). None when no bin boundary has primitives on both
/// sides (all centres coincide).
fn best_split(bins: &Bins, map: &BinMap, parent_area: f32) -> Option<(usize, usize, f32)> {
    let n = map.bins;
    let parent_area = parent_area.max(f32::MIN_POSITIVE);
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        if map.scale[axis] == 0.0 {
            continue;
        }
        // Sweep from the right (each boundary's right side's area times its cost), then
        // from the left.
        let mut right = [0f32; BINS];
        let (mut lo, mut hi, mut count) = (Vec4::INFINITY, Vec4::NEG_INFINITY, 0u64);
        for b in (1..n).rev() {
            lo = lo.min(bins.lower[axis][b]);
            hi = hi.max(bins.upper[axis][b]);
            count += bins.counts[axis][b];
            right[b] = if count as u32 == 0 {
                f32::NAN
            } else {
                half_area(lo, hi) * counted_cost(count)
            };
        }
        let (mut lo, mut hi, mut count) = (Vec4::INFINITY, Vec4::NEG_INFINITY, 0u64);
        for b in 0..n - 1 {
            lo = lo.min(bins.lower[axis][b]);
            hi = hi.max(bins.upper[axis][b]);
            count += bins.counts[axis][b];
            // An empty side (NaN on the right) is no split.
            if count as u32 == 0 || right[b + 1].is_nan() {
                continue;
            }
            let cost = TRAVERSAL_COST
                + (half_area(lo, hi) * counted_cost(count) + right[b + 1]) / parent_area;
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, b, cost));
            }
        }
    }
    best
}

/// Bins `prims` with `map` into `bins` (cleared here), on every thread when they are many:
/// the top nodes of the tree are otherwise each binned by one thread alone.
fn bin(prims: &[BuildPrim], map: &BinMap, bins: &mut Box<Bins>) {
    if prims.len() > PARALLEL_BINNING {
        *bins = prims
            .par_chunks(PARALLEL_BINNING / 2)
            .map(|part| {
                let mut b = Bins::new();
                b.fill(part, map);
                b
            })
            .reduce_with(|a, b| a.merge(b, map.bins))
            .expect("a node has primitives");
    } else {
        bins.clear(map.bins);
        bins.fill(prims, map);
    }
}

/// Builds the subtree over `prims` (whose boxes and centres `extents` holds), which start at
/// `offset` in the final primitive order; `bins` is working space, cleared for each node
/// rather than made anew.
fn build_node(
    prims: &mut [BuildPrim],
    offset: usize,
    depth: usize,
    extents: &Extents,
    bins: &mut Box<Bins>,
) -> BuildNode {
    let n = prims.len();
    let bounds = extents.bounds();
    let leaf = BuildNode::Leaf {
        bounds,
        first: offset,
        count: n,
    };
    if n <= 1 || depth >= MAX_DEPTH {
        return leaf;
    }
    let map = BinMap::new(extents, bin_count(n));
    bin(prims, &map, bins);
    let (split, left, right) = match best_split(bins, &map, half_area(extents.lower, extents.upper))
    {
        Some((axis, b, cost)) => {
            if n <= MAX_LEAF && cost >= counted_cost(bins.counts[0][..map.bins].iter().sum()) {
                return leaf;
            }
            let (split, left_centres, right_centres) = partition(prims, |c| map.bin(c, axis) <= b);
            debug_assert_eq!(
                split as u64,
                bins.counts[axis][..=b].iter().sum::<u64>() & u64::from(u32::MAX),
                "partition and binning put the primitives apart alike"
            );
            let side = |range, centres: Extents| {
                let (lower, upper) = bins.union(axis, range);
                Extents {
                    lower,
                    upper,
                    ..centres
                }
            };
            (
                split,
                side(0..b + 1, left_centres),
                side(b + 1..map.bins, right_centres),
            )
        }
        // All centres coincide: split by count so that no leaf grows without bound.
        None if n <= MAX_LEAF => return leaf,
        None => {
            let split = n / 2;
            let (l, r) = prims.split_at(split);
            (split, Extents::of(l), Extents::of(r))
        }
    };
    let (left_prims, right_prims) = prims.split_at_mut(split);
    let (l, r) = if n > PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(left_prims, offset, depth + 1, &left, bins),
            || {
                build_node(
                    right_prims,
                    offset + split,
                    depth + 1,
                    &right,
                    &mut Bins::new(),
                )
            },
        )
    } else {
        (
            build_node(left_prims, offset, depth + 1, &left, bins),
            build_node(right_prims, offset + split, depth + 1, &right, bins),
        )
    };
    BuildNode::Interior {
        bounds,
        children: Box::new([l, r]),
    }
}

/// Moves the primitives whose centre `left` takes to the front; returns how many there are,
/// and the boxes of the centres on each side (`Extents`' centre corners; its box corners
/// unset).
fn partition(prims: &mut [BuildPrim], left: impl Fn(Vec4) -> bool) -> (usize, Extents, Extents) {
    let (mut l, mut r) = (Extents::EMPTY, Extents::EMPTY);
    let (mut i, mut j) = (0, prims.len());
    loop {
        while i < j {
            let c = prims[i].centroid2();
            if !left(c) {
                break;
            }
            l.add_centre(c);
            i += 1;
        }
        while i < j {
            let c = prims[j - 1].centroid2();
            if left(c) {
                break;
            }
            r.add_centre(c);
            j -= 1;
        }
        if i == j {
            return (i, l, r);
        }
        // prims[i] goes right, prims[j - 1] left.
        prims.swap(i, j - 1);
        l.add_centre(prims[i].centroid2());
        r.add_centre(prims[j - 1].centroid2());
        i += 1;
        j -= 1;
    }
}

/// The binary tree collapsed into wide nodes, and the leaves' ranges of the build's
/// primitives in the order their items are stored.
struct Collapse<'a> {
    prims: &'a [BuildPrim],
    nodes: &'a mut Vec<Node>,
    /// Each leaf's range of `prims` and its number of items.
    leaves: &'a mut Vec<(std::ops::Range<usize>, usize)>,
    /// Items of the leaves listed so far.
    item_count: usize,
}

impl Collapse<'_> {
    /// Appends the wide nodes of the binary subtree under `node`; returns the index of its
    /// top node. The subtree's top is opened into its two children, then the child of
    /// largest area is opened in turn until `WIDTH` children are held or only leaves are left:
    /// the children most likely to be entered are the ones tested together.
    fn node(&mut self, node: &BuildNode) -> u32 {
        let mut kids: Vec<&BuildNode> = match node {
            BuildNode::Interior { children, .. } => vec![&children[0], &children[1]],
            BuildNode::Leaf { .. } => vec![node],
        };
        while kids.len() < WIDTH {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|(_, k)| matches!(k, BuildNode::Interior { .. }))
                .max_by(|(_, a), (_, b)| a.bounds().area().total_cmp(&b.bounds().area()))
                .map(|(i, _)| i);
            let Some(i) = widest else { break };
            let BuildNode::Interior { children, .. } = kids[i] else {
                unreachable!("only interior nodes are opened")
            };
            kids[i] = &children[0];
            kids.push(&children[1]);
        }
        let index = self.nodes.len();
        self.nodes.push(Node::EMPTY);
        for (slot, kid) in kids.into_iter().enumerate() {
            let (first, count) = match kid {
                BuildNode::Leaf { first, count, .. } => self.leaf(*first..first + count),
                BuildNode::Interior { .. } => (self.node(kid), 0),
            };
            self.nodes[index].set_child(slot, kid.bounds(), first, count);
        }
        index as u32
    }

    /// Lists a leaf; returns where its items will start and how many there are.
    fn leaf(&mut self, range: std::ops::Range<usize>) -> (u32, u32) {
        let first = self.item_count;
        let count = leaf_items(&self.prims[range.clone()]);
        self.leaves.push((range, count));
        self.item_count += count;
        (first as u32, count as u32)
    }
}
