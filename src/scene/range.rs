//! The range of scene values: every coordinate, radius, transform entry, camera value and
//! medium coefficient a reader accepts is finite and at most `MAX_COORDINATE` in magnitude
//! (docs/scene-format.md, "Range of values", says why this bound). Every reader checks the
//! values it reads here, so that its error names the file and line; `check_scene` checks the
//! scene a reader made, as a backstop for what a reader derives (a transformed vertex, a
//! default camera).

use std::path::Path;

use super::{Camera, Projection, Scene, SceneError};
use crate::geometry::{Shape, Vec3};

/// The largest magnitude of a scene value. With every coordinate within ±1e8, a scene's
/// diameter is at most 4e8 (a sphere of radius 1e8 at 1e8), and the largest product the
/// watertight ray–triangle tests form (the fourth power of a length, in a normal's squared
/// length, 2.6e34) stays below f32's largest value, 3.4e38, by four orders of magnitude.
pub const MAX_COORDINATE: f32 = 1e8;

/// The range as the errors state it.
pub const RANGE: &str = "scene values must be finite and within ±1e8 (docs/scene-format.md)";

/// Whether one scene value is in range: finite and at most `MAX_COORDINATE` in magnitude.
pub fn in_range(value: f32) -> bool {
    value.abs() <= MAX_COORDINATE
}

/// One scene value (a radius, a scale, a coefficient) checked: the error says what it is
/// (`what`), its value and the range.
pub fn check_value(value: f32, what: &str) -> Result<(), String> {
    if in_range(value) {
        Ok(())
    } else {
        Err(format!("{what} {value} is out of range: {RANGE}"))
    }
}

/// A point or vector checked, every coordinate in range: the error says what it is (`what`,
/// written out only then: a mesh's millions of vertices are checked with `format_args!`),
/// its value and the range.
pub fn check_coordinate(value: Vec3, what: impl std::fmt::Display) -> Result<(), String> {
    if value.to_array().into_iter().all(in_range) {
        Ok(())
    } else {
        Err(format!(
            "{what} {} {} {} is out of range: {RANGE}",
            value.x, value.y, value.z
        ))
    }
}

/// A camera checked: position and point of interest in range and apart, an up vector in range
/// and not along the view, a finite field of view in (0, π) or a screen size in range and > 0.
pub fn check_camera(camera: &Camera) -> Result<(), String> {
    check_coordinate(camera.position, "camera position")?;
    check_coordinate(camera.point_of_interest, "camera point of interest")?;
    check_coordinate(camera.up, "camera up vector")?;
    let view = camera.point_of_interest - camera.position;
    if view.length_squared() == 0.0 || view.cross(camera.up).length_squared() == 0.0 {
        return Err("the camera looks at its own position or along its up vector".into());
    }
    match camera.projection {
        Projection::Perspective { angle } if !(angle > 0.0 && angle < std::f32::consts::PI) => Err(
            format!("the camera's angle must be in (0, π), found {angle}"),
        ),
        Projection::Orthographic { size } if !(size > 0.0 && in_range(size)) => Err(format!(
            "the camera's size must be > 0, found {size}; {RANGE}"
        )),
        _ => Ok(()),
    }
}

/// The scene a reader made, checked whole: every vertex, shape, medium and the camera (the
/// file's, or the default one made from the bounds). Readers check the values they read with
/// the file's line; this names the file and the element, for what a reader derived.
pub fn check_scene(scene: &Scene) -> Result<(), SceneError> {
    let fail = |message: String| SceneError::Obj {
        file: scene.path.clone(),
        message,
    };
    for (i, q) in scene.quads.iter().enumerate() {
        for v in q.vertices {
            check_coordinate(v, format_args!("a vertex of quad {i}")).map_err(fail)?;
        }
    }
    for (i, p) in scene.triangles.positions.iter().enumerate() {
        check_coordinate(*p, format_args!("triangle vertex {i}")).map_err(fail)?;
    }
    for (i, n) in scene.triangles.normals.iter().enumerate() {
        if !n.is_finite() {
            return Err(fail(format!(
                "the normal of triangle vertex {i} is not finite: {RANGE}"
            )));
        }
    }
    for (k, g) in scene.instancing.groups.iter().enumerate() {
        for (i, p) in g.mesh.positions.iter().enumerate() {
            check_coordinate(*p, format_args!("vertex {i} of shapegroup {k}")).map_err(fail)?;
        }
    }
    for (k, i) in scene.instancing.instances.iter().enumerate() {
        let b = i.world_bounds(scene.instancing.group_of(i));
        if !b.is_empty() {
            for corner in [b.min, b.max] {
                check_coordinate(corner, format_args!("the box of instance {k}")).map_err(fail)?;
            }
        }
    }
    for (i, s) in scene.shapes.iter().enumerate() {
        // A shape's centre and size each within the range: its extent within twice that.
        let m = s.shape.magnitude();
        if m.is_nan() || m > 2.0 * MAX_COORDINATE {
            return Err(fail(format!(
                "shape {i} ({}) reaches {m} from the origin: its centre and size are scene values, and {RANGE}",
                s.shape.name()
            )));
        }
    }
    for (k, m) in scene.media.iter().enumerate() {
        let majorant = m.heterogeneous.as_ref().map_or(0.0, |h| h.majorant());
        check_coordinate(m.sigma_a, "sigma_a")
            .and_then(|_| check_coordinate(m.sigma_s, "sigma_s"))
            .and_then(|_| check_coordinate(Vec3::splat(majorant), "the largest sigma_t"))
            .map_err(|e| scene_line(&scene.path, m.line, format!("medium {k}: {e}")))?;
    }
    for (k, m) in scene.materials.iter().enumerate() {
        let values = [m.diffuse, m.reflective, m.emitted, m.transmitted];
        if !values.iter().all(|c| c.is_finite()) || !m.ior.is_finite() || !m.roughness.is_finite() {
            return Err(scene_line(
                &scene.path,
                m.line,
                format!("material {k}: a value is not finite: {RANGE}"),
            ));
        }
    }
    check_camera(&scene.camera()).map_err(fail)
}

/// An error at `line` of `file` (the whole file when the line is not known, 0).
fn scene_line(file: &Path, line: u32, message: String) -> SceneError {
    if line == 0 {
        return SceneError::Obj {
            file: file.to_path_buf(),
            message,
        };
    }
    SceneError::Invalid {
        file: file.to_path_buf(),
        line,
        column: 1,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    #[test]
    fn values_beyond_the_range_or_not_finite_are_refused() {
        assert!(check_value(1e8, "a radius").is_ok());
        assert!(check_value(-1e8, "a radius").is_ok());
        for v in [1.1e8, -1e38, f32::INFINITY, f32::NAN, 2f32.powi(64)] {
            let e = check_value(v, "a radius").expect_err("refused");
            assert!(e.contains("a radius") && e.contains("±1e8"), "{e}");
        }
        assert!(check_coordinate(vec3(0.0, 1e4, -3e7), "a vertex").is_ok());
        assert!(check_coordinate(vec3(0.0, f32::NAN, 0.0), "a vertex").is_err());
    }
}
