//! Instancing (Mitsuba's `shapegroup` and `instance`): a group's triangles are stored once, in
//! the group's own space, and each instance is a transform that places them in the world.
//!
//! A hit on an instanced triangle is `PrimKind::Instanced` with one index over all instances'
//! triangles: instance `k`'s triangle `j` of its group is `instances[k].first + j`, so that
//! `PrimRef` stays two words and both backends order such hits (the tie rule of equally near
//! hits) as they would the same triangles flattened in instance order.
//!
//! Both backends test an instanced triangle in its group's space, on the ray that
//! `Instance::ray_to_group` makes: the same function for both, so that they agree on t, u and
//! v bit for bit. The direction is transformed without normalizing, so a point at t along the
//! group-space ray is the world point at the same t: t needs no conversion. Everything a hit
//! then needs in the world (its point, normals, tangents) is computed from the triangle's
//! world vertices (`Instancing::world_vertices`), placed as the scene reader would have placed
//! them flattened, so shading agrees with the flattened scene to float precision.

use glam::{DMat3, DMat4, DVec3, Mat4};

use super::TriangleMesh;
use crate::geometry::{Bounds3, Ray, Vec3};

/// One group's triangles, in the group's own space.
#[derive(Clone, Debug, Default)]
pub struct Group {
    pub mesh: TriangleMesh,
    /// The box of the mesh's vertices, in the group's space.
    pub bounds: Bounds3,
}

/// One placement of a group.
#[derive(Clone, Debug)]
pub struct Instance {
    /// Index into `Instancing::groups`.
    pub group: u32,
    /// The `PrimKind::Instanced` index of the instance's first triangle (see the module).
    pub first: u32,
    /// From the group's space to the world (Mitsuba's `to_world`), in f64 as the reader
    /// composes transforms.
    pub to_world: DMat4,
    /// `to_world`'s inverse, in f32: what rays are taken into the group's space by.
    pub to_group: Mat4,
    /// The inverse transpose of `to_world`'s linear part: what takes normals to the world.
    pub normal_matrix: DMat3,
}

impl Instance {
    /// The ray in the group's space, over the same range of t: origin and direction
    /// transformed by `to_group`, the direction not normalized (a point at t along it is the
    /// point at t along `ray`). Both backends test instanced triangles on this ray.
    #[inline]
    pub fn ray_to_group(&self, ray: &Ray) -> Ray {
        Ray {
            origin: self.to_group.transform_point3(ray.origin),
            t_min: ray.t_min,
            direction: self.to_group.transform_vector3(ray.direction),
            t_max: ray.t_max,
        }
    }

    /// A point of the group placed in the world, as the scene reader places a shape's vertex.
    #[inline]
    pub fn place(&self, p: Vec3) -> Vec3 {
        self.to_world.transform_point3(p.as_dvec3()).as_vec3()
    }

    /// A normal of the group turned into the world, unit length (zero where it is zero).
    #[inline]
    pub fn turn(&self, n: Vec3) -> Vec3 {
        (self.normal_matrix * n.as_dvec3())
            .normalize_or_zero()
            .as_vec3()
    }

    /// The box of a box `b` of the group (not empty) with its corners placed: for an instance
    /// that only scales, mirrors and moves its group, the box of `b`'s points placed, to the
    /// bit (each coordinate placed depends on that coordinate alone); for one that turns it,
    /// a box around them.
    pub fn place_box(&self, b: Bounds3) -> Bounds3 {
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let corners: Vec<Vec3> = (0..8)
            .map(|k| {
                let pick = |bit: usize, a: f64, b: f64| if k >> bit & 1 == 0 { a } else { b };
                let corner = DVec3::new(
                    pick(0, lo.x, hi.x),
                    pick(1, lo.y, hi.y),
                    pick(2, lo.z, hi.z),
                );
                self.to_world.transform_point3(corner).as_vec3()
            })
            .collect();
        Bounds3::from_points(&corners)
    }

    /// The world box of the instance: its group's box's corners placed, widened by 1e-5 of
    /// its magnitude, because the ray taken into the group's space is rounded there, and a
    /// triangle at the group's edge may be hit by it a little outside the exact box.
    pub fn world_bounds(&self, group: &Group) -> Bounds3 {
        if group.bounds.is_empty() {
            return Bounds3::EMPTY;
        }
        let b = self.place_box(group.bounds);
        let pad = 1e-5 * b.min.abs().max(b.max.abs()).max_element();
        Bounds3 {
            min: b.min - Vec3::splat(pad),
            max: b.max + Vec3::splat(pad),
        }
    }
}

/// The scene's groups and their instances.
#[derive(Clone, Debug, Default)]
pub struct Instancing {
    pub groups: Vec<Group>,
    pub instances: Vec<Instance>,
}

impl Instancing {
    /// Adds a group (its mesh in its own space); returns its index.
    pub fn add_group(&mut self, mesh: TriangleMesh) -> u32 {
        let bounds = Bounds3::from_points(&mesh.positions);
        self.groups.push(Group { mesh, bounds });
        (self.groups.len() - 1) as u32
    }

    /// Places group `group` by `to_world`. An error (for the reader to name the file and line
    /// with) when the transform cannot be inverted, or the instanced triangles would number
    /// more than 2³² (the BVH takes at most 2³⁰ primitives: `AccelError::TooLarge`).
    pub fn add_instance(&mut self, group: u32, to_world: DMat4) -> Result<(), String> {
        let to_group = to_world.inverse();
        if !(to_world.is_finite() && to_group.is_finite() && to_world.determinant() != 0.0) {
            return Err("an instance's to_world must be invertible".into());
        }
        let count = self.groups[group as usize].mesh.len();
        let first = self.triangle_count();
        if first + count > u32::MAX as usize {
            return Err("the instances place more than 2³² triangles".into());
        }
        let linear = DMat3::from_mat4(to_world);
        self.instances.push(Instance {
            group,
            first: first as u32,
            to_world,
            to_group: to_group.as_mat4(),
            normal_matrix: linear.inverse().transpose(),
        });
        Ok(())
    }

    /// How many triangles the instances place (each instance its group's): the range of
    /// `PrimKind::Instanced` indices.
    pub fn triangle_count(&self) -> usize {
        self.instances.last().map_or(0, |i| {
            i.first as usize + self.groups[i.group as usize].mesh.len()
        })
    }

    /// How many triangles the groups store (once each, whatever their instances).
    pub fn stored_triangle_count(&self) -> usize {
        self.groups.iter().map(|g| g.mesh.len()).sum()
    }

    /// The instance an instanced triangle belongs to, and its index in the group's mesh.
    #[inline]
    pub fn locate(&self, index: u32) -> (&Instance, usize) {
        let k = self.instances.partition_point(|i| i.first <= index) - 1;
        let instance = &self.instances[k];
        (instance, (index - instance.first) as usize)
    }

    /// The group an instance places.
    #[inline]
    pub fn group_of(&self, instance: &Instance) -> &Group {
        &self.groups[instance.group as usize]
    }

    /// The world vertices of instanced triangle `index`: what every engine and the surface
    /// take an instanced triangle as.
    #[inline]
    pub fn world_vertices(&self, index: u32) -> [Vec3; 3] {
        let (instance, j) = self.locate(index);
        self.placed(instance, j)
    }

    /// The world vertices of triangle `j` of the group `instance` places.
    #[inline]
    pub fn placed(&self, instance: &Instance, j: usize) -> [Vec3; 3] {
        self.group_of(instance)
            .mesh
            .vertices(j)
            .map(|p| instance.place(p))
    }

    /// The material of instanced triangle `index`.
    #[inline]
    pub fn material(&self, index: u32) -> u32 {
        let (instance, j) = self.locate(index);
        self.group_of(instance).mesh.materials[j]
    }
}
