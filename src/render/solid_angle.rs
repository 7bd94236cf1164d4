//! Points on a rectangular light distributed uniformly in the solid angle it subtends from a
//! shading point (Ureña, Fajardo & King, "An Area-Preserving Parametrization for Spherical
//! Rectangles", EGSR 2013). Area sampling weighs each point by cosθ'/r², which grows without
//! bound as the shading point nears the light (the walls' edges where they touch the Cornell
//! box's light); by solid angle every point carries the same weight, the solid angle Ω, and
//! what is left to vary is the receiver's cosine.
//!
//! Worked in f64: Ω is the sum of four angles less 2π, which cancels to nothing in f32 for a
//! light far away (a unit square 1e3 away subtends 1e-6 sr, below f32's rounding of 2π).
//! Lights subtending less than `MIN_SOLID_ANGLE` are sampled by area instead, where the
//! area estimator's weights are nearly constant anyway.

use crate::geometry::Vec3;
use glam::DVec3;

/// Below this solid angle (steradians) a light is sampled by area: it is then small beside
/// its distance (a unit square 100 away), its cosθ'/r² varies by about a percent over it and
/// stays bounded, so area sampling is about as good, and cheaper.
pub const MIN_SOLID_ANGLE: f64 = 1e-4;

/// A rectangle seen from a point: the frame and the constants its samples are made from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphericalRectangle {
    /// The shading point.
    origin: DVec3,
    /// The rectangle's frame: `x` and `y` along its edges, `z` its normal turned away from
    /// the shading point.
    x: DVec3,
    y: DVec3,
    z: DVec3,
    /// The rectangle in that frame, relative to `origin`: [x0, x1] × [y0, y1] at depth z0 < 0.
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    /// The z components of the normals of the planes through the origin and the edges at
    /// y0 and at y1.
    b0: f64,
    b1: f64,
    /// 2π less the spherical rectangle's angles at the edge x0.
    k: f64,
    solid_angle: f64,
}

impl SphericalRectangle {
    /// The rectangle with corner `corner` and perpendicular edges `edge_u`, `edge_v`, seen from
    /// `origin`; None when `origin` lies in its plane (it subtends nothing) or it has no area.
    pub fn new(origin: Vec3, corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> Option<Self> {
        let (origin, corner) = (origin.as_dvec3(), corner.as_dvec3());
        let (eu, ev) = (edge_u.as_dvec3(), edge_v.as_dvec3());
        let (lu, lv) = (eu.length(), ev.length());
        if lu <= 0.0 || lv <= 0.0 {
            return None;
        }
        let (x, y) = (eu / lu, ev / lv);
        let mut z = x.cross(y);
        let d = corner - origin;
        let mut z0 = d.dot(z);
        if z0 == 0.0 || !z0.is_finite() {
            return None;
        }
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        let (x0, y0) = (d.dot(x), d.dot(y));
        let (x1, y1) = (x0 + lu, y0 + lv);
        let v00 = DVec3::new(x0, y0, z0);
        let v01 = DVec3::new(x0, y1, z0);
        let v10 = DVec3::new(x1, y0, z0);
        let v11 = DVec3::new(x1, y1, z0);
        let n0 = v00.cross(v10).normalize();
        let n1 = v10.cross(v11).normalize();
        let n2 = v11.cross(v01).normalize();
        let n3 = v01.cross(v00).normalize();
        let angle = |a: DVec3, b: DVec3| (-a.dot(b)).clamp(-1.0, 1.0).acos();
        let (g0, g1, g2, g3) = (angle(n0, n1), angle(n1, n2), angle(n2, n3), angle(n3, n0));
        let k = std::f64::consts::TAU - g2 - g3;
        let solid_angle = g0 + g1 - k;
        (solid_angle.is_finite() && solid_angle > 0.0).then_some(SphericalRectangle {
            origin,
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: n0.z,
            b1: n2.z,
            k,
            solid_angle,
        })
    }

    /// The solid angle the rectangle subtends (steradians).
    pub fn solid_angle(&self) -> f64 {
        self.solid_angle
    }

    /// The point of the rectangle at (u, v) in [0,1)²: uniform in solid angle for uniform
    /// (u, v), and stratified where (u, v) are.
    pub fn sample(&self, u: f32, v: f32) -> Vec3 {
        let (u, v) = (u as f64, v as f64);
        // The x coordinate: the azimuth that encloses a share u of the solid angle.
        let au = u * self.solid_angle + self.k;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let cu = (fu.signum() / (fu * fu + self.b0 * self.b0).sqrt()).clamp(-1.0, 1.0);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x0, self.x1);
        // The y coordinate: uniform in the sine of the elevation along that line.
        let d = xu.hypot(self.z0);
        let h0 = self.y0 / d.hypot(self.y0);
        let h1 = self.y1 / d.hypot(self.y1);
        let hv = h0 + v * (h1 - h0);
        let yv = if hv * hv < 1.0 - 1e-12 {
            (hv * d / (1.0 - hv * hv).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        (self.origin + self.x * xu + self.y * yv + self.z * self.z0).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    /// The solid angle of a unit square seen from height h above its centre: four times
    /// that of a ½ × ½ rectangle seen from above its corner, asin(a·b / √((a² + h²)(b² + h²))).
    fn square_from_above(h: f64) -> f64 {
        let a = 0.5f64;
        4.0 * (a * a / ((a * a + h * h) * (a * a + h * h)).sqrt()).asin()
    }

    #[test]
    fn solid_angle_matches_the_closed_form_from_near_and_far() {
        for h in [1e-3f32, 1e-2, 0.1, 1.0, 10.0, 100.0, 1e3] {
            let r = SphericalRectangle::new(
                vec3(0.0, 0.0, h),
                vec3(-0.5, -0.5, 0.0),
                vec3(1.0, 0.0, 0.0),
                vec3(0.0, 1.0, 0.0),
            )
            .expect("subtends something");
            let truth = square_from_above(h as f64);
            assert!(
                (r.solid_angle() / truth - 1.0).abs() < 1e-9,
                "h {h}: {} against {truth}",
                r.solid_angle()
            );
        }
    }
}
