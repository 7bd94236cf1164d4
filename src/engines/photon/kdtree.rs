//! A kd-tree for the photon maps' and the irradiance cache's k-nearest queries.
//!
//! kiddo's `ImmutableKdTree`, which they used before, splits the axes in turn; photons lie on
//! surfaces, and on an axis-aligned wall every photon shares one coordinate, so a third of its
//! levels split nothing there. This tree splits each node at the median of its points along
//! the axis where they spread most, down to leaves of at most `LEAF_SIZE` points, built by two
//! threads, and searches best-first (the nearest unopened cell next). A query is bound by
//! memory: on the 2M-photon Cornell box map it opens about 9 leaves and reads some 180 points
//! for k = 50 (photons lie on surfaces, where a ball meets about 3×3 cells). What made it
//! fast, one change at a time (one thread, k = 50; `cargo bench --bench photon`):
//! - a leaf's points stored together (one array per axis and one of indices were four
//!   places apart: 8.2 → 5.2 µs on the 10M-photon map);
//! - the candidates ordered by one u64 (squared distance's bits, then index) instead of a
//!   pair of floats (5.2 → 4.0 µs on 500k points on a box's walls);
//! - best-first rather than depth-first search (8.8 → 8.2 µs);
//! - leaves of 32 points rather than 16 (4.5–7.4 → 4.4–5.6 µs, noisy; 8 was slower);
//! - the points moved, not indices, while building (7.5 s → 0.95 s with the two threads);
//! - together 0.78× the time of the above in interleaved rounds: nodes of 8
//!   bytes with no leaves stored (ranges follow from the median split); a leaf's coordinates
//!   as runs of x, y and z, 12 bytes a point, the indices apart (the photon maps renumber
//!   their photons in leaf order and need none); the k best kept sorted, a nearer one
//!   inserted by a binary search, instead of a binary heap (about 33 insertions a query);
//!   the points within reach marked as bits before they are offered.
//!
//! A query returns the k points nearest to it within a radius, ordered by (squared distance,
//! index): ties are broken by the point's index, so the answer is one set whatever the tree's
//! shape or the order in which it was searched — as a brute-force search gives it (tested).

/// Points per leaf at most.
const LEAF_SIZE: usize = 32;
/// Marks, as a node's axis, a cell whose points all coincide: a leaf, however many they are
/// (no split could part them).
const COINCIDENT: u32 = 3;
/// Cells are pruned by their incremental distance times this: a bound rounded up by an ulp
/// must not prune a point that ties with the k-th.
const SLACK: f32 = 1.0 - 1e-6;
/// Room for the cells a query has still to open, reserved up front (more are taken if
/// needed).
const PENDING: usize = 64;

/// An inner node. Its cell's points are a range of the leaf order; it splits them at the
/// median, the first half (rounded down) to its left child, which is the next node, and the
/// rest to its right child, node `packed >> 2`; `split` separates them along axis
/// `packed & 3`. The ranges follow from the root's, so no node stores one, and leaves (cells
/// of at most `LEAF_SIZE` points) are not stored at all: 8 bytes an inner node, a quarter of
/// what nodes with their ranges and stored leaves took.
#[derive(Clone, Copy, Debug)]
struct Node {
    split: f32,
    packed: u32,
}

/// A cell a query has still to open, ordered nearest first (`BinaryHeap` pops its largest):
/// its points `start..end` of the leaf order and its node (meaningful if it is not a leaf).
#[derive(Clone, Copy, Debug)]
struct Pending {
    bound: f32,
    node: u32,
    start: u32,
    end: u32,
    offset: [f32; 3],
}

impl PartialEq for Pending {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == std::cmp::Ordering::Equal
    }
}

impl Eq for Pending {}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Pending {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        other
            .bound
            .total_cmp(&self.bound)
            .then(other.start.cmp(&self.start))
            .then(other.end.cmp(&self.end))
    }
}

/// A point found by a query: its squared distance to the query and its index in the slice the
/// tree was built from (or its position in the leaf order, once renumbered).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub distance: f32,
    pub item: u32,
}

pub struct KdTree {
    nodes: Vec<Node>,
    /// The points' coordinates in leaf order, a leaf's as three runs (its x's, its y's, its
    /// z's) so that their distances are computed four or eight at a time: 12 bytes a point,
    /// all a query reads of a leaf.
    coords: Vec<f32>,
    /// The index in the slice the tree was built from of each point in leaf order, read
    /// only for the points offered to a query; `None` once renumbered (a point's index is then
    /// its position).
    order: Option<Vec<u32>>,
}

impl KdTree {
    /// The tree of `points` (any number, duplicates included), built in parallel.
    pub fn new(points: &[[f32; 3]]) -> KdTree {
        let mut entries: Vec<([f32; 3], u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (*p, i as u32))
            .collect();
        let mut coords = vec![0.0; 3 * entries.len()];
        let nodes = build(&mut entries, &mut coords);
        KdTree {
            nodes,
            coords,
            order: Some(entries.into_iter().map(|(_, i)| i).collect()),
        }
    }

    pub fn len(&self) -> usize {
        self.coords.len() / 3
    }

    /// Renumbers the points in leaf order (queries then answer positions in it) and returns
    /// the old number of each: a caller that stores its records in that order reads a
    /// query's answer from adjacent memory.
    pub fn renumber_in_leaf_order(&mut self) -> Vec<u32> {
        self.order
            .take()
            .unwrap_or_else(|| (0..self.len() as u32).collect())
    }

    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// The `k` points nearest to `query` whose squared distance is at most `max_distance2`,
    /// nearest first (ties by index).
    pub fn nearest(&self, query: [f32; 3], k: usize, max_distance2: f32) -> Vec<Neighbour> {
        if k == 0 || self.is_empty() {
            return Vec::new();
        }
        let mut heap = Farthest::with_capacity(k);
        // Cells still to visit, nearest first (best-first search: only cells nearer than the
        // k-th point found are opened), each with the query's offset from it along each axis
        // (0 inside) and the squared distance that makes, a lower bound of its points' (the
        // incremental distance of Arya & Mount).
        let mut pending = std::collections::BinaryHeap::with_capacity(PENDING);
        pending.push(Pending {
            bound: 0.0,
            node: 0,
            start: 0,
            end: self.len() as u32,
            offset: [0.0; 3],
        });
        let reach = |heap: &Farthest| heap.reach(max_distance2);
        while let Some(Pending {
            bound,
            mut node,
            mut start,
            mut end,
            offset,
        }) = pending.pop()
        {
            if bound * SLACK > reach(&heap) {
                break;
            }
            loop {
                if (end - start) as usize <= LEAF_SIZE {
                    self.search_leaf(query, start, end, max_distance2, &mut heap);
                    break;
                }
                let n = self.nodes[node as usize];
                let axis = n.packed & 3;
                if axis == COINCIDENT {
                    self.search_leaf(query, start, end, max_distance2, &mut heap);
                    break;
                }
                let axis = axis as usize;
                let middle = start + (end - start) / 2;
                let left = (node + 1, start, middle);
                let right = (n.packed >> 2, middle, end);
                let diff = query[axis] - n.split;
                let (near, far) = if diff < 0.0 {
                    (left, right)
                } else {
                    (right, left)
                };
                let mut far_offset = offset;
                far_offset[axis] = diff;
                let far_bound = bound - offset[axis] * offset[axis] + diff * diff;
                if far_bound * SLACK <= reach(&heap) {
                    pending.push(Pending {
                        bound: far_bound,
                        node: far.0,
                        start: far.1,
                        end: far.2,
                        offset: far_offset,
                    });
                }
                (node, start, end) = near;
            }
        }
        heap.into_sorted()
    }

    /// Offers the points `start..end` of the leaf order (one leaf) to `heap`, `LEAF_SIZE` at a
    /// time (a leaf of coincident points can hold more).
    fn search_leaf(
        &self,
        query: [f32; 3],
        start: u32,
        end: u32,
        max_distance2: f32,
        heap: &mut Farthest,
    ) {
        let (start, count) = (start as usize, (end - start) as usize);
        let (xs, rest) = self.coords[3 * start..3 * (start + count)].split_at(count);
        let (ys, zs) = rest.split_at(count);
        let order = self.order.as_deref();
        for first in (0..count).step_by(LEAF_SIZE) {
            let chunk = first..(first + LEAF_SIZE).min(count);
            let mut distances = [0.0f32; LEAF_SIZE];
            // Squared distances of the whole chunk first (vectorised), then the offers.
            for (((d, x), y), z) in distances
                .iter_mut()
                .zip(&xs[chunk.clone()])
                .zip(&ys[chunk.clone()])
                .zip(&zs[chunk.clone()])
            {
                let (dx, dy, dz) = (x - query[0], y - query[1], z - query[2]);
                *d = dx * dx + dy * dy + dz * dz;
            }
            // Which are within the reach as it stands (it only shrinks as they are offered),
            // as bits: the offers then follow no branch a point's distance decides.
            let reach = heap.reach(max_distance2);
            let mut within = 0u32;
            for (i, &distance) in distances[..chunk.len()].iter().enumerate() {
                within |= ((distance <= reach) as u32) << i;
            }
            while within != 0 {
                let i = within.trailing_zeros() as usize;
                within &= within - 1;
                let position = start + first + i;
                let item = order.map_or(position as u32, |o| o[position]);
                heap.offer(key(distances[i], item));
            }
        }
    }
}

/// Subtrees of more points than this are built by two threads (rayon's `join`).
const PARALLEL_BUILD: usize = 1 << 16;

/// The inner nodes of the subtree of `entries` (points with their indices), in depth-first
/// order with child indices counted from its root; `entries` end in leaf order and `coords`
/// (three per entry) receive their coordinates, a leaf's as runs of x, y and z. The entries
/// themselves are moved, so that each level reads them in order.
fn build(entries: &mut [([f32; 3], u32)], coords: &mut [f32]) -> Vec<Node> {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for (p, _) in entries.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let extent = [0, 1, 2].map(|a| hi[a] - lo[a]);
    let axis = (0..3)
        .max_by(|&a, &b| extent[a].total_cmp(&extent[b]).then(b.cmp(&a)))
        .unwrap_or(0);
    // A leaf when few points are left, or when they all coincide (a node could not part
    // them; a query then takes them all in one loop).
    if entries.len() <= LEAF_SIZE || extent[axis] <= 0.0 {
        let count = entries.len();
        for (i, (p, _)) in entries.iter().enumerate() {
            for (a, &c) in p.iter().enumerate() {
                coords[a * count + i] = c;
            }
        }
        return if count <= LEAF_SIZE {
            Vec::new()
        } else {
            vec![Node {
                split: 0.0,
                packed: COINCIDENT,
            }]
        };
    }
    let middle = entries.len() / 2;
    entries.select_nth_unstable_by(middle, |a, b| {
        a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1))
    });
    let split = entries[middle].0[axis];
    let (left, right) = entries.split_at_mut(middle);
    let (left_coords, right_coords) = coords.split_at_mut(3 * middle);
    let (left, right) = if left.len() + right.len() > PARALLEL_BUILD {
        rayon::join(|| build(left, left_coords), || build(right, right_coords))
    } else {
        (build(left, left_coords), build(right, right_coords))
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node {
        split,
        packed: axis as u32 | (1 + left.len() as u32) << 2,
    });
    append(&mut nodes, left);
    append(&mut nodes, right);
    nodes
}

/// Appends `subtree`, whose inner nodes count their right children from its root.
fn append(nodes: &mut Vec<Node>, subtree: Vec<Node>) {
    let offset = nodes.len() as u32;
    nodes.extend(subtree.into_iter().map(|mut n| {
        if n.packed & 3 != COINCIDENT {
            n.packed += offset << 2;
        }
        n
    }));
}

/// The k best neighbours found so far, as keys (squared distance, index) packed in a u64 — a
/// distance's bits above the index, which orders as the pair does since squared distances are
/// not negative: one integer comparison where the pair took two float ones. The first k are
/// taken as they come and then sorted; after that the keys stay sorted, a nearer point
/// inserted at its place (a branch-free binary search and one move of the farther keys) and
/// the farthest dropped. On the 2M-photon Cornell box map a k = 50 query makes about 33 such
/// insertions, which a binary heap's sift-downs, a mispredicted branch a level, made slower.
struct Farthest {
    keys: Vec<u64>,
    capacity: usize,
}

/// The heap key of a neighbour.
fn key(distance: f32, item: u32) -> u64 {
    (distance.to_bits() as u64) << 32 | item as u64
}

impl Farthest {
    fn with_capacity(capacity: usize) -> Farthest {
        Farthest {
            keys: Vec::with_capacity(capacity),
            capacity,
        }
    }

    /// The squared distance a point must not exceed to be offered: the farthest of k found,
    /// `max_distance2` before k are.
    fn reach(&self, max_distance2: f32) -> f32 {
        if self.keys.len() == self.capacity {
            f32::from_bits((self.keys[self.capacity - 1] >> 32) as u32)
        } else {
            max_distance2
        }
    }

    fn offer(&mut self, key: u64) {
        let keys = &mut self.keys;
        if keys.len() < self.capacity {
            keys.push(key);
            if keys.len() == self.capacity {
                keys.sort_unstable();
            }
            return;
        }
        let last = self.capacity - 1;
        if key >= keys[last] {
            return;
        }
        let place = keys[..last].partition_point(|&k| k < key);
        keys.copy_within(place..last, place + 1);
        keys[place] = key;
    }

    fn into_sorted(mut self) -> Vec<Neighbour> {
        if self.keys.len() < self.capacity {
            self.keys.sort_unstable();
        }
        self.keys
            .into_iter()
            .map(|k| Neighbour {
                distance: f32::from_bits((k >> 32) as u32),
                item: k as u32,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The k nearest within the radius by brute force, in the same order.
    fn brute_force(points: &[[f32; 3]], q: [f32; 3], k: usize, max2: f32) -> Vec<Neighbour> {
        let mut all: Vec<Neighbour> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
                Neighbour {
                    distance: dx * dx + dy * dy + dz * dz,
                    item: i as u32,
                }
            })
            .filter(|n| n.distance <= max2)
            .collect();
        all.sort_unstable_by(|a, b| a.distance.total_cmp(&b.distance).then(a.item.cmp(&b.item)));
        all.truncate(k);
        all
    }

    /// Points like a photon map's: on two axis-aligned walls (one coordinate shared by all),
    /// in a volume, and a pile of duplicates; queries on and off them, with and without a
    /// radius, k from 1 to beyond the number of points.
    #[test]
    fn queries_match_brute_force() {
        let mut rng = Rng::new(7, 0, 0);
        let mut r = || rng.next_f32();
        let mut points = Vec::new();
        // Over `PARALLEL_BUILD` points, so that subtrees are built by both threads.
        for _ in 0..25_000 {
            points.push([r() * 2.0 - 1.0, -1.0, r() * 2.0 - 1.0]);
            points.push([r() * 2.0 - 1.0, r() * 2.0 - 1.0, -1.0]);
            points.push([r(), r(), r()]);
        }
        points.extend(std::iter::repeat_n([0.25f32, -1.0, 0.5], 100));
        // Points on a grid share coordinates and distances: ties broken by index.
        for i in 0..20 {
            for j in 0..20 {
                points.push([i as f32 * 0.1, 0.5, j as f32 * 0.1]);
            }
        }
        let tree = KdTree::new(&points);
        assert_eq!(tree.len(), points.len());
        // Renumbered, the points are named by their position in leaf order.
        let mut renumbered = KdTree::new(&points);
        let order = renumbered.renumber_in_leaf_order();
        let in_leaf_order: Vec<[f32; 3]> = order.iter().map(|&i| points[i as usize]).collect();
        for q in 0..300 {
            let query = match q % 4 {
                0 => [r() * 2.0 - 1.0, -1.0, r() * 2.0 - 1.0],
                1 => [0.25, -1.0, 0.5],
                2 => [(q % 20) as f32 * 0.1 + 0.05, 0.5, 0.3],
                _ => [r() * 3.0 - 1.5, r() * 3.0 - 1.5, r() * 3.0 - 1.5],
            };
            for (k, max2) in [
                (1, f32::INFINITY),
                (50, 0.01),
                (50, f32::INFINITY),
                (120, 0.04),
            ] {
                assert_eq!(
                    tree.nearest(query, k, max2),
                    brute_force(&points, query, k, max2),
                    "query {query:?}, k {k}, radius² {max2}"
                );
                assert_eq!(
                    renumbered.nearest(query, k, max2),
                    brute_force(&in_leaf_order, query, k, max2),
                    "renumbered: query {query:?}, k {k}, radius² {max2}"
                );
            }
        }
        let all = tree.nearest([0.0; 3], points.len() + 5, f32::INFINITY);
        assert_eq!(all.len(), points.len());
    }

    #[test]
    fn empty_and_single() {
        assert!(KdTree::new(&[]).nearest([0.0; 3], 5, 1.0).is_empty());
        let one = KdTree::new(&[[1.0, 2.0, 3.0]]);
        assert_eq!(one.nearest([1.0, 2.0, 3.0], 5, 0.0).len(), 1);
        assert!(one.nearest([0.0; 3], 5, 1.0).is_empty());
        assert!(one.nearest([1.0, 2.0, 3.0], 0, 1.0).is_empty());
    }
}
