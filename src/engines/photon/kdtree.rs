//! A kd-tree for the photon maps' and the irradiance cache's k-nearest queries (issue #16).
//!
//! kiddo's `ImmutableKdTree`, which they used before, splits the axes in turn; photons lie on
//! surfaces, and on an axis-aligned wall every photon shares one coordinate, so a third of its
//! levels split nothing there. This tree splits each node at the median of its points along
//! the axis where they spread most, down to leaves of at most `LEAF_SIZE` points, built by two
//! threads, and searches best-first (the nearest unopened cell next). A query is bound by
//! memory: on the Cornell box's photon map it opens about 13 leaves and reads some 250 points
//! for k = 50 (photons lie on surfaces, where a ball meets about 3×3 cells). What made it
//! fast, one change at a time (one thread, k = 50; BENCHMARKS.md, session 20):
//! - a leaf's points stored together with their indices, 16 bytes each side by side (one
//!   array per axis and one of indices were four places apart: 8.2 → 5.2 µs on the 10M-photon
//!   map);
//! - the candidates' heap ordered by one u64 (squared distance's bits, then index) instead of
//!   a pair of floats (5.2 → 4.0 µs on 500k points on a box's walls);
//! - best-first rather than depth-first search (8.8 → 8.2 µs);
//! - leaves of 32 points rather than 16 (4.5–7.4 → 4.4–5.6 µs, noisy; 8 was slower);
//! - the points moved, not indices, while building (7.5 s → 0.95 s with the two threads).
//!
//! A query returns the k points nearest to it within a radius, ordered by (squared distance,
//! index): ties are broken by the point's index, so the answer is one set whatever the tree's
//! shape or the order in which it was searched — as a brute-force search gives it (tested).

/// Points per leaf at most.
const LEAF_SIZE: usize = 32;
/// Marks a leaf in `Node::axis`.
const LEAF: u32 = 3;
/// Cells are pruned by their incremental distance times this: a bound rounded up by an ulp
/// must not prune a point that ties with the k-th.
const SLACK: f32 = 1.0 - 1e-6;
/// Room for the cells a query has still to open, reserved up front (more are taken if
/// needed).
const PENDING: usize = 64;

/// A node: an inner node splits its points at `split` along `axis` (its left child is the
/// next node, its right child `right_or_start`); a leaf holds points `right_or_start..end`.
#[derive(Clone, Copy, Debug)]
struct Node {
    split: f32,
    axis: u32,
    right_or_start: u32,
    end: u32,
}

/// A cell a query has still to open, ordered nearest first (`BinaryHeap` pops its largest).
#[derive(Clone, Copy, Debug)]
struct Pending {
    bound: f32,
    node: u32,
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
            .then(other.node.cmp(&self.node))
    }
}

/// A point found by a query: its squared distance to the query and its index in the slice the
/// tree was built from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub distance: f32,
    pub item: u32,
}

pub struct KdTree {
    nodes: Vec<Node>,
    /// The points in leaf order, each with its index in the slice the tree was built from:
    /// a leaf's are 16 bytes apiece, side by side, all a query reads of it.
    points: Vec<([f32; 3], u32)>,
}

impl KdTree {
    /// The tree of `points` (any number, duplicates included), built in parallel.
    pub fn new(points: &[[f32; 3]]) -> KdTree {
        let mut entries: Vec<([f32; 3], u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (*p, i as u32))
            .collect();
        let nodes = if entries.is_empty() {
            Vec::new()
        } else {
            build(&mut entries, 0)
        };
        KdTree {
            nodes,
            points: entries,
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Renumbers the points in leaf order (queries then answer positions in it) and returns
    /// the old number of each: a caller that stores its records in that order reads a
    /// query's answer from adjacent memory.
    pub fn renumber_in_leaf_order(&mut self) -> Vec<u32> {
        self.points
            .iter_mut()
            .enumerate()
            .map(|(i, (_, item))| std::mem::replace(item, i as u32))
            .collect()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The `k` points nearest to `query` whose squared distance is at most `max_distance2`,
    /// nearest first (ties by index).
    pub fn nearest(&self, query: [f32; 3], k: usize, max_distance2: f32) -> Vec<Neighbour> {
        let mut heap = Farthest::with_capacity(k);
        if k == 0 || self.nodes.is_empty() {
            return Vec::new();
        }
        // Cells still to visit, nearest first (best-first search: only cells nearer than the
        // k-th point found are opened), each with the query's offset from it along each axis
        // (0 inside) and the squared distance that makes, a lower bound of its points' (the
        // incremental distance of Arya & Mount).
        let mut pending = std::collections::BinaryHeap::with_capacity(PENDING);
        pending.push(Pending {
            bound: 0.0,
            node: 0,
            offset: [0.0; 3],
        });
        let reach = |heap: &Farthest| heap.reach(max_distance2);
        while let Some(Pending {
            mut node,
            bound,
            offset,
        }) = pending.pop()
        {
            if bound * SLACK > reach(&heap) {
                break;
            }
            loop {
                let n = self.nodes[node as usize];
                if n.axis == LEAF {
                    self.search_leaf(query, n, max_distance2, &mut heap);
                    break;
                }
                let axis = n.axis as usize;
                let diff = query[axis] - n.split;
                let (near, far) = if diff < 0.0 {
                    (node + 1, n.right_or_start)
                } else {
                    (n.right_or_start, node + 1)
                };
                let mut far_offset = offset;
                far_offset[axis] = diff;
                let far_bound = bound - offset[axis] * offset[axis] + diff * diff;
                if far_bound * SLACK <= reach(&heap) {
                    pending.push(Pending {
                        bound: far_bound,
                        node: far,
                        offset: far_offset,
                    });
                }
                node = near;
            }
        }
        heap.into_sorted()
    }

    /// Offers the points of leaf `n` to `heap`, `LEAF_SIZE` at a time (a leaf of coincident
    /// points can hold more).
    fn search_leaf(&self, query: [f32; 3], n: Node, max_distance2: f32, heap: &mut Farthest) {
        let (start, end) = (n.right_or_start as usize, n.end as usize);
        for first in (start..end).step_by(LEAF_SIZE) {
            let range = first..(first + LEAF_SIZE).min(end);
            let mut distances = [0.0f32; LEAF_SIZE];
            // Squared distances of the whole chunk first, then the offers.
            for (d, (p, _)) in distances.iter_mut().zip(&self.points[range.clone()]) {
                let (dx, dy, dz) = (p[0] - query[0], p[1] - query[1], p[2] - query[2]);
                *d = dx * dx + dy * dy + dz * dz;
            }
            for (k, &distance) in distances[..range.len()].iter().enumerate() {
                if distance <= max_distance2 {
                    heap.offer(key(distance, self.points[first + k].1));
                }
            }
        }
    }
}

/// Subtrees of more points than this are built by two threads (rayon's `join`).
const PARALLEL_BUILD: usize = 1 << 16;

/// The subtree of `entries` (points with their indices), whose first is point `start` of the
/// leaf order: its nodes in depth-first order, child indices counted from its root. The
/// entries themselves are moved, so that each level reads them in order.
fn build(entries: &mut [([f32; 3], u32)], start: u32) -> Vec<Node> {
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
        return vec![Node {
            split: 0.0,
            axis: LEAF,
            right_or_start: start,
            end: start + entries.len() as u32,
        }];
    }
    let middle = entries.len() / 2;
    entries.select_nth_unstable_by(middle, |a, b| {
        a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1))
    });
    let split = entries[middle].0[axis];
    let (left, right) = entries.split_at_mut(middle);
    let right_start = start + middle as u32;
    let (left, right) = if left.len() + right.len() > PARALLEL_BUILD {
        rayon::join(|| build(left, start), || build(right, right_start))
    } else {
        (build(left, start), build(right, right_start))
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node {
        split,
        axis: axis as u32,
        right_or_start: 1 + left.len() as u32,
        end: 0,
    });
    append(&mut nodes, left);
    append(&mut nodes, right);
    nodes
}

/// Appends `subtree`, whose inner nodes count their right children from its root.
fn append(nodes: &mut Vec<Node>, subtree: Vec<Node>) {
    let offset = nodes.len() as u32;
    nodes.extend(subtree.into_iter().map(|mut n| {
        if n.axis != LEAF {
            n.right_or_start += offset;
        }
        n
    }));
}

/// The k best neighbours found so far, as a binary max-heap of keys (squared distance, index)
/// packed in a u64 — a distance's bits above the index, which orders as the pair does since
/// squared distances are not negative: one integer comparison where the pair took two float
/// ones (the heap's comparisons were most of a query's time). The root is the key a nearer
/// point replaces.
struct Farthest {
    heap: Vec<u64>,
    capacity: usize,
}

/// The heap key of a neighbour.
fn key(distance: f32, item: u32) -> u64 {
    (distance.to_bits() as u64) << 32 | item as u64
}

impl Farthest {
    fn with_capacity(capacity: usize) -> Farthest {
        Farthest {
            heap: Vec::with_capacity(capacity),
            capacity,
        }
    }

    /// The squared distance a point must not exceed to be offered: the farthest of k found,
    /// `max_distance2` before k are.
    fn reach(&self, max_distance2: f32) -> f32 {
        if self.heap.len() == self.capacity {
            f32::from_bits((self.heap[0] >> 32) as u32)
        } else {
            max_distance2
        }
    }

    fn offer(&mut self, key: u64) {
        let h = &mut self.heap;
        if h.len() < self.capacity {
            // Sift up.
            h.push(key);
            let mut i = h.len() - 1;
            while i > 0 {
                let parent = (i - 1) / 2;
                if h[parent] >= h[i] {
                    break;
                }
                h.swap(parent, i);
                i = parent;
            }
            return;
        }
        if key >= h[0] {
            return;
        }
        // Replace the root and sift down.
        h[0] = key;
        let mut i = 0;
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut largest = i;
            if l < h.len() && h[l] > h[largest] {
                largest = l;
            }
            if r < h.len() && h[r] > h[largest] {
                largest = r;
            }
            if largest == i {
                break;
            }
            h.swap(i, largest);
            i = largest;
        }
    }

    fn into_sorted(mut self) -> Vec<Neighbour> {
        self.heap.sort_unstable();
        self.heap
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
