//! Camera moves by mouse, as in the course's viewer: a left drag orbits the camera around its
//! point of interest (turntable about the up direction, then tilt), a right drag or the
//! wheel dollies towards or away from that point, a middle drag pans camera and point
//! together so that the scene follows the pointer.

use glam::Quat;

use crate::geometry::Vec3;
use crate::scene::{Camera, Projection};

/// Radians of orbit per pixel of drag: a drag across a 256-pixel window turns half a turn.
const ORBIT_PER_PIXEL: f32 = std::f32::consts::PI / 256.0;
/// The closest the line of sight comes to the up direction, in radians: the frame stays
/// defined (the camera never looks straight along `up`).
const POLE_MARGIN: f32 = 0.02;
/// Dolly factor per pixel of right drag (down moves away), and per wheel step.
const DOLLY_PER_PIXEL: f32 = 0.005;
const DOLLY_PER_STEP: f32 = 0.1;
/// The nearest the camera gets to its point of interest, as a share of where it started.
const NEAREST: f32 = 1e-3;

/// Turns the camera around its point of interest by a drag of (dx, dy) pixels (x right, y
/// down): horizontal drags about the up direction, vertical ones about the screen's
/// horizontal, stopping short of the poles.
pub fn orbit(camera: &Camera, (dx, dy): (f32, f32)) -> Camera {
    let up = camera.up.normalize_or_zero();
    let offset = camera.position - camera.point_of_interest;
    let yaw = Quat::from_axis_angle(up, -dx * ORBIT_PER_PIXEL);
    let offset = yaw * offset;
    // The elevation of the offset above the plane normal to `up`, tilted by the drag and
    // kept off the poles.
    let r = offset.length();
    let elevation = (offset.dot(up) / r).clamp(-1.0, 1.0).asin();
    let limit = std::f32::consts::FRAC_PI_2 - POLE_MARGIN;
    let tilted = (elevation + dy * ORBIT_PER_PIXEL).clamp(-limit, limit);
    let horizontal = up.cross(offset).normalize_or_zero();
    let offset = if horizontal == Vec3::ZERO {
        offset
    } else {
        Quat::from_axis_angle(horizontal, elevation - tilted) * offset
    };
    Camera {
        position: camera.point_of_interest + offset,
        ..*camera
    }
}

/// Moves the camera along its line of sight: `steps` > 0 nearer, < 0 farther (a wheel step
/// is 1; a right drag of d pixels down is −d·DOLLY_PER_PIXEL/DOLLY_PER_STEP steps).
pub fn dolly(camera: &Camera, steps: f32, start_distance: f32) -> Camera {
    let offset = camera.position - camera.point_of_interest;
    let distance =
        (offset.length() * (-steps * DOLLY_PER_STEP).exp()).max(NEAREST * start_distance);
    Camera {
        position: camera.point_of_interest + offset.normalize_or_zero() * distance,
        ..*camera
    }
}

/// Dolly steps of a right drag of `dy` pixels (down: away).
pub fn dolly_steps_of_drag(dy: f32) -> f32 {
    -dy * DOLLY_PER_PIXEL / DOLLY_PER_STEP
}

/// Moves camera and point of interest together by a drag of (dx, dy) pixels in an image
/// `height` pixels high, so that a point at the depth of the point of interest stays under
/// the pointer.
pub fn pan(camera: &Camera, (dx, dy): (f32, f32), (width, height): (u32, u32)) -> Camera {
    let forward = (camera.point_of_interest - camera.position).normalize_or_zero();
    let horizontal = forward.cross(camera.up).normalize_or_zero();
    let screen_up = horizontal.cross(forward);
    let screen_side = match camera.projection {
        Projection::Perspective { angle } => 2.0 * (angle * 0.5).tan() * camera.focus_distance(),
        Projection::Orthographic { size } => size,
    };
    // The screen side spans the larger image side (Camera::screen_point).
    let per_pixel = screen_side / width.max(height) as f32;
    let shift = (-dx * horizontal + dy * screen_up) * per_pixel;
    Camera {
        position: camera.position + shift,
        point_of_interest: camera.point_of_interest + shift,
        ..*camera
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    fn camera() -> Camera {
        Camera {
            position: vec3(0.0, 1.0, 5.0),
            point_of_interest: vec3(0.0, 1.0, 0.0),
            up: vec3(0.0, 1.0, 0.0),
            projection: Projection::Perspective {
                angle: 40f32.to_radians(),
            },
        }
    }

    #[test]
    fn a_horizontal_drag_of_half_a_window_turns_a_quarter_about_up() {
        let c = orbit(&camera(), (128.0, 0.0));
        // Dragging right moves the camera to the left of where it was (seen from above: −x).
        assert!((c.position - vec3(-5.0, 1.0, 0.0)).length() < 1e-4, "{c:?}");
        assert_eq!(c.point_of_interest, camera().point_of_interest);
    }

    #[test]
    fn orbiting_keeps_the_distance_and_stops_short_of_the_pole() {
        let c = orbit(&camera(), (30.0, 10_000.0));
        let offset = c.position - c.point_of_interest;
        assert!((offset.length() - 5.0).abs() < 1e-4);
        let from_up = offset.normalize().dot(vec3(0.0, 1.0, 0.0)).acos();
        assert!((from_up - POLE_MARGIN).abs() < 1e-3, "{from_up}");
        let forward = (c.point_of_interest - c.position).normalize();
        assert!(forward.cross(c.up).length() > 0.01);
    }

    #[test]
    fn a_wheel_step_forward_and_one_back_return_the_camera() {
        let c = dolly(&dolly(&camera(), 1.0, 5.0), -1.0, 5.0);
        assert!((c.position - camera().position).length() < 1e-5);
        assert!(dolly(&camera(), 1.0, 5.0).focus_distance() < 5.0);
        assert!(dolly(&camera(), 1e6, 5.0).focus_distance() >= NEAREST * 5.0 * 0.999);
    }

    #[test]
    fn panning_keeps_the_point_of_interest_under_the_pointer() {
        // A drag of the whole image width moves the scene by the screen's width at the
        // point of interest's depth: 2·tan(20°)·5.
        let c = pan(&camera(), (256.0, 0.0), (256, 256));
        let moved = c.point_of_interest - camera().point_of_interest;
        let expected = 2.0 * 20f32.to_radians().tan() * 5.0;
        assert!((moved.x + expected).abs() < 1e-4, "{moved:?}");
        assert_eq!(
            c.position - c.point_of_interest,
            camera().position - camera().point_of_interest
        );
    }
}
