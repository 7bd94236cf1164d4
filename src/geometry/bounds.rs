//! Axis-aligned bounding boxes.

use super::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Bounds3 {
    fn default() -> Self {
        Bounds3::EMPTY
    }
}

impl Bounds3 {
    /// The box that contains nothing; the identity of `union`.
    pub const EMPTY: Bounds3 = Bounds3 {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn from_points(points: &[Vec3]) -> Bounds3 {
        points.iter().fold(Bounds3::EMPTY, |b, &p| b.union_point(p))
    }
    #[inline]
    pub fn union(self, o: Bounds3) -> Bounds3 {
        Bounds3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    #[inline]
    pub fn union_point(self, p: Vec3) -> Bounds3 {
        Bounds3 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    #[inline]
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }
    #[inline]
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    /// Whether `p` lies in the box (boundary included).
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
    /// The part of the ray `origin + t·direction`, 0 ≤ t ≤ `t_max`, inside the box, as its
    /// (entry, exit) parameters; None if it misses the box.
    pub fn clip(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let (mut near, mut far) = (0.0f32, t_max);
        for axis in 0..3 {
            let inv = direction[axis].recip();
            let a = (self.min[axis] - origin[axis]) * inv;
            let b = (self.max[axis] - origin[axis]) * inv;
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            // NaN (0·∞ on a slab's plane) leaves the interval as it was.
            near = if a > near { a } else { near };
            far = if b < far { b } else { far };
        }
        (near <= far && !self.is_empty()).then_some((near, far))
    }
    /// Surface area; 0 for an empty box.
    #[inline]
    pub fn area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    #[test]
    fn clip_keeps_the_part_inside() {
        let b = Bounds3 {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let (near, far) = b
            .clip(vec3(-1.0, 0.5, 0.5), vec3(1.0, 0.0, 0.0), 10.0)
            .unwrap();
        assert_eq!((near, far), (1.0, 2.0));
        // Starting inside, stopping inside.
        let (near, far) = b
            .clip(vec3(0.5, 0.5, 0.5), vec3(0.0, 1.0, 0.0), 0.25)
            .unwrap();
        assert_eq!((near, far), (0.0, 0.25));
        assert!(b
            .clip(vec3(-1.0, 2.0, 0.5), vec3(1.0, 0.0, 0.0), 10.0)
            .is_none());
        assert!(b
            .clip(vec3(-1.0, 0.5, 0.5), vec3(-1.0, 0.0, 0.0), 10.0)
            .is_none());
        assert!(Bounds3::EMPTY
            .clip(Vec3::ZERO, vec3(1.0, 0.0, 0.0), 1.0)
            .is_none());
    }
}
