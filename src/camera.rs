//! Cameras of the course dialect: perspective and orthographic, with the course's mapping of
//! pixels to a square screen. Every scene format gives one and the film projects through it
//! (ray trees, wireframes), so it lies below both `scene` and `film`.

use crate::geometry::{vec3, Bounds3, Ray, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// `angle`: the full field of view in radians across the larger image dimension.
    Perspective { angle: f32 },
    /// `size`: the side of the square screen in scene units.
    Orthographic { size: f32 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub point_of_interest: Vec3,
    pub up: Vec3,
    pub projection: Projection,
}

impl Camera {
    /// The camera used when a scene has none: outside the scene's box on +z, looking at its
    /// centre, 20° field of view (scene-format.md).
    pub fn default_for(bounds: &Bounds3) -> Camera {
        let centre = if bounds.is_empty() {
            Vec3::ZERO
        } else {
            bounds.centre()
        };
        let extent = bounds.extent().max_element().max(1e-6);
        Camera {
            position: centre + vec3(0.0, 0.0, 4.0 * extent),
            point_of_interest: centre,
            up: vec3(0.0, 1.0, 0.0),
            projection: Projection::Perspective {
                angle: 20f32.to_radians(),
            },
        }
    }

    /// The camera's frame and screen worked out once, for generating many rays.
    pub fn view(&self) -> View {
        let forward = (self.point_of_interest - self.position).normalize_or_zero();
        let horizontal = forward.cross(self.up).normalize_or_zero();
        let up = horizontal.cross(forward);
        let (perspective, side) = match self.projection {
            Projection::Perspective { angle } => (true, 2.0 * (angle * 0.5).tan()),
            Projection::Orthographic { size } => (false, size),
        };
        View {
            position: self.position,
            forward,
            horizontal,
            up,
            perspective,
            side,
        }
    }

    /// The ray through screen point (x, y) in \[0,1\]², (0,0) bottom left. For many rays,
    /// `view()` once and `View::ray`.
    pub fn generate_ray(&self, x: f32, y: f32) -> Ray {
        self.view().ray(x, y)
    }

    /// Distance from the camera to its point of interest: the default focus distance.
    pub fn focus_distance(&self) -> f32 {
        (self.point_of_interest - self.position).length()
    }

    /// Screen coordinates of pixel (i, j) of a W×H image, j counted from the bottom; `(dx, dy)`
    /// is the position inside the pixel, (0.5, 0.5) at its centre.
    pub fn screen_point(i: u32, j: u32, dx: f32, dy: f32, width: u32, height: u32) -> (f32, f32) {
        let m = width.max(height) as f32;
        let x = (i as f32 + dx - width as f32 / 2.0) / m + 0.5;
        let y = (j as f32 + dy - height as f32 / 2.0) / m + 0.5;
        (x, y)
    }

    /// Projects a world point to screen coordinates in \[0,1\]² (None when behind the camera).
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        self.view().project(p)
    }
}

/// A camera's orthonormal frame and screen size, computed once per image rather than per ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    position: Vec3,
    forward: Vec3,
    horizontal: Vec3,
    up: Vec3,
    perspective: bool,
    /// The screen's side: at distance 1 in front of a perspective camera (2·tan(angle/2)),
    /// in scene units for an orthographic one.
    side: f32,
}

impl View {
    /// Whether every ray it makes is finite: its position, frame and screen are. Checked once
    /// an image, where the rays are made (a camera of values in range always is).
    pub fn is_finite(&self) -> bool {
        self.position.is_finite()
            && self.forward.is_finite()
            && self.horizontal.is_finite()
            && self.up.is_finite()
            && self.side.is_finite()
    }

    /// The ray through screen point (x, y) in \[0,1\]², (0,0) bottom left.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let (h, v) = ((x - 0.5) * self.side, (y - 0.5) * self.side);
        if self.perspective {
            let dir = self.forward + self.horizontal * h + self.up * v;
            Ray::new(self.position, dir.normalize_or_zero())
        } else {
            Ray::new(
                self.position + self.horizontal * h + self.up * v,
                self.forward,
            )
        }
    }

    /// The ray through screen point (x, y) of a thin lens: `aperture` is the lens radius,
    /// `focus_distance` the distance (along the view direction) of the plane in focus, and
    /// (lens_u, lens_v) in [0,1)² picks the point on the lens. Aperture 0 is the pinhole.
    #[inline]
    pub fn lens_ray(
        &self,
        (x, y): (f32, f32),
        aperture: f32,
        focus_distance: f32,
        (lens_u, lens_v): (f32, f32),
    ) -> Ray {
        let ray = self.ray(x, y);
        if aperture <= 0.0 {
            return ray;
        }
        let along = ray.direction.dot(self.forward);
        if along <= 0.0 {
            return ray;
        }
        let focus = ray.at(focus_distance / along);
        let (dx, dy) = crate::sampling::sample_disk(lens_u, lens_v);
        let origin = ray.origin + self.horizontal * (dx * aperture) + self.up * (dy * aperture);
        Ray::new(origin, (focus - origin).normalize_or_zero())
    }

    /// Projects a world point to screen coordinates in \[0,1\]² (None when behind the camera).
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let d = p - self.position;
        if !self.perspective {
            return Some((
                d.dot(self.horizontal) / self.side + 0.5,
                d.dot(self.up) / self.side + 0.5,
            ));
        }
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        Some((
            d.dot(self.horizontal) / z / self.side + 0.5,
            d.dot(self.up) / z / self.side + 0.5,
        ))
    }
}
