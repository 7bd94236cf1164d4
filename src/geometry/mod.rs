//! Geometry shared by every part of trilux: vectors, rays, boxes and the exact intersection
//! routines of polygons, the point-to-polygon form factor, and the analytic shapes.

mod bounds;
pub mod form_factor;
mod polygon;
mod ray;
mod shape;

pub use bounds::Bounds3;
/// Points, directions, normals and linear RGB are glam's `Vec3` (`#[repr(C)]`, three `f32`s:
/// the Embree shim reads rays of them directly); texture coordinates are glam's `Vec2`.
/// `cargo bench --bench vec` measures a hand-written `Vec3` against it: the same speed.
pub use glam::{vec2, vec3, Vec2, Vec3};
pub(crate) use polygon::{
    edge_function_zero, edge_functions_disagree, sheared_edge_functions, sheared_triangle_solve,
};
pub use polygon::{
    faces_ray, intersect_quad, intersect_quad_sheared, intersect_triangle,
    intersect_triangle_sheared, quad_normal, quad_off_plane, triangle_normal, RayShear,
};
pub use ray::{offset_ray_origin, point_error, shadow_ray, spawn_ray, Ray};
pub use shape::{AnalyticShape, RingPart, RingShape, Shape, SphereShape, Tessellation};
