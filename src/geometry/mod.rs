//! Geometry shared by every part of trilux: vectors, rays, boxes and the exact intersection
//! routines of the four primitive kinds.

mod bounds;
mod ray;
mod shapes;
mod vec;

pub use bounds::Bounds3;
pub use ray::{offset_ray_origin, point_error, shadow_ray, spawn_ray, Ray};
pub use shapes::{
    faces_ray, intersect_quad, intersect_quad_sheared, intersect_triangle,
    intersect_triangle_sheared, quad_normal, RayShear, RingPart, RingShape, SphereShape,
};
pub use vec::{vec2, vec3, Vec2, Vec3};
