//! A photon map: photons in a kd-tree (`kdtree::KdTree`) and the k-nearest radiance estimate
//! with a cone filter.

use std::num::NonZero;

use super::kdtree::{KdTree, Neighbour};
use super::trace::{PathKind, Photon};
use crate::geometry::Vec3;
use crate::scene::medium::Medium;
use crate::scene::Color;

/// Cone filter constant k (Jensen): weights 1 − d/(k·r).
const CONE_K: f32 = 1.1;
/// Photons whose surface normal differs more than this (cosine) from the query's are left
/// out: they lie on another surface, e.g. the other side of a thin wall.
pub const NORMAL_COS: f32 = 0.9;

pub struct PhotonMap {
    pub photons: Vec<Photon>,
    tree: KdTree,
}

/// Counters of the lookups of one map.
#[derive(Clone, Copy, Debug, Default)]
pub struct Lookup {
    /// Photons that passed the normal and side checks and were filtered in.
    pub used: usize,
    /// Radius of the estimate.
    pub radius: f32,
}

impl PhotonMap {
    /// The map of `photons`, which it keeps in the tree's leaf order: an estimate's photons
    /// then lie side by side in memory (on the 2M-photon Cornell box map, reading them in
    /// their traced order took more time than finding them).
    pub fn new(mut photons: Vec<Photon>) -> PhotonMap {
        let points: Vec<[f32; 3]> = photons.iter().map(|p| p.position.to_array()).collect();
        let mut tree = KdTree::new(&points);
        drop(points);
        permute(&mut photons, &tree.renumber_in_leaf_order());
        PhotonMap { photons, tree }
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// The `k` nearest photons to `x` within `max_radius` (nearest first: squared distance
    /// and index) and the squared radius of the estimate: the k-th photon's, or the whole
    /// reach when fewer are in it.
    fn nearest(&self, x: Vec3, k: NonZero<usize>, max_radius: f32) -> (Vec<Neighbour>, f32) {
        let found = self
            .tree
            .nearest(x.to_array(), k.get(), max_radius * max_radius);
        let r2 = if found.len() == k.get() {
            found.last().map_or(0.0, |f| f.distance)
        } else {
            max_radius * max_radius
        };
        (found, r2)
    }

    /// Radiance scattered in per unit length at `x` in the fog `medium`, leaving along the
    /// unit direction `towards`, from the `k` nearest volume photons within `max_radius`:
    /// Σ p(ω_p → towards)·Φ_p / (4/3·π·r³) over the k − 1 inside the k-th's sphere (Jensen &
    /// Christensen 1998, made unbiased for a uniform density). The photons are
    /// stored where they scattered with their power times σs over the density of the event,
    /// so their density is σs times the fluence. `first_scatterings`: whether photons
    /// scattered straight from the light (`PathKind::Direct`) count; skipped, they still
    /// take their place among the k, so the estimate is that of the others' density.
    pub fn in_scattered(
        &self,
        (x, towards): (Vec3, Vec3),
        medium: &Medium,
        k: usize,
        max_radius: f32,
        first_scatterings: bool,
    ) -> Color {
        let Some(k) = NonZero::new(k) else {
            return Vec3::ZERO;
        };
        if self.photons.is_empty() {
            return Vec3::ZERO;
        }
        let (found, r2) = self.nearest(x, k, max_radius);
        if r2 <= 0.0 {
            return Vec3::ZERO;
        }
        // The k-th photon lies on the sphere that defines it: counting it too would make the
        // estimate k/(k−1) times the density (of Poisson points); the others, k − 1 over the
        // sphere, are unbiased. With fewer than k in reach, the reach is the sphere and all
        // count.
        let inside = if found.len() == k.get() {
            k.get() - 1
        } else {
            found.len()
        };
        let mut sum = Vec3::ZERO;
        for f in &found[..inside] {
            let p = &self.photons[f.item as usize];
            if first_scatterings || p.kind != PathKind::Direct {
                sum += p.power * medium.phase(p.direction, towards);
            }
        }
        let volume = 4.0 / 3.0 * std::f32::consts::PI * r2 * r2.sqrt();
        sum * volume.recip()
    }

    /// Irradiance over π (the incident radiance averaged over the hemisphere, what a
    /// Lambertian albedo multiplies) at `x` on a surface with unit normal `n` (turned to the
    /// side being lit), from the `k` nearest photons within `max_radius`: the cone-filtered
    /// sum Σ Φ_p·w_p / ((1 − 2/(3k))·π·r²) / π.
    pub fn irradiance_over_pi(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        max_radius: f32,
    ) -> (Color, Lookup) {
        let Some(k) = NonZero::new(k) else {
            return (Vec3::ZERO, Lookup::default());
        };
        if self.photons.is_empty() {
            return (Vec3::ZERO, Lookup::default());
        }
        let (found, r2) = self.nearest(x, k, max_radius);
        if r2 <= 0.0 {
            return (Vec3::ZERO, Lookup::default());
        }
        let r = r2.sqrt();
        let mut sum = Vec3::ZERO;
        let mut used = 0;
        for f in &found {
            let p = &self.photons[f.item as usize];
            if p.normal.dot(n) < NORMAL_COS || p.direction.dot(n) >= 0.0 {
                continue;
            }
            let w = 1.0 - f.distance.sqrt() / (CONE_K * r);
            sum += p.power * w;
            used += 1;
        }
        let norm = (1.0 - 2.0 / (3.0 * CONE_K)) * std::f32::consts::PI * r2;
        (
            sum * (norm * std::f32::consts::PI).recip(),
            Lookup { used, radius: r },
        )
    }
}

/// Reorders `items` in place so that item i becomes the one at `order[i]` (a permutation),
/// following its cycles: no second copy of the photons.
fn permute<T: Copy>(items: &mut [T], order: &[u32]) {
    let mut done = vec![false; items.len()];
    for start in 0..items.len() {
        if done[start] {
            continue;
        }
        let first = items[start];
        let mut i = start;
        loop {
            done[i] = true;
            let from = order[i] as usize;
            if from == start {
                items[i] = first;
                break;
            }
            items[i] = items[from];
            i = from;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// In place, as a second copy would place them: cycles of every length, fixed points.
    #[test]
    fn permute_follows_the_order() {
        let mut rng = crate::sampling::Rng::new(3, 0, 0);
        for n in [0usize, 1, 2, 7, 100] {
            let mut order: Vec<u32> = (0..n as u32).collect();
            for i in (1..n).rev() {
                order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
            }
            let items: Vec<u64> = (0..n as u64).map(|i| i * 10).collect();
            let want: Vec<u64> = order.iter().map(|&i| items[i as usize]).collect();
            let mut got = items.clone();
            permute(&mut got, &order);
            assert_eq!(got, want);
        }
    }
}
