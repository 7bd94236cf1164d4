//! The sky (`sky_color`, `sky_gradient`, `sky_scale`; docs/scene-format.md): radiance from
//! every direction a ray leaves the scene in, which lights the scene. +y is up.

use crate::color::Color;
use crate::geometry::Vec3;

/// A sky: its radiance by direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sky {
    /// The same radiance from every direction (`sky_color r g b`).
    Uniform(Color),
    /// Linear in the direction's height from the horizon's radiance to the zenith's above it
    /// and to the nadir's below (`sky_gradient zenith horizon nadir`).
    Gradient {
        zenith: Color,
        horizon: Color,
        nadir: Color,
    },
}

impl Sky {
    /// The radiance arriving from the unit direction `towards` (a ray going that way sees it).
    pub fn radiance(&self, towards: Vec3) -> Color {
        match *self {
            Sky::Uniform(c) => c,
            Sky::Gradient {
                zenith,
                horizon,
                nadir,
            } => {
                let y = towards.y.clamp(-1.0, 1.0);
                if y >= 0.0 {
                    horizon + (zenith - horizon) * y
                } else {
                    horizon + (nadir - horizon) * -y
                }
            }
        }
    }

    /// Its radiance integrated over the sphere of directions, ∫ L dω: for a uniform sky 4π·L,
    /// for a gradient π·(zenith + 2·horizon + nadir) (each hemisphere's radiance is linear in
    /// the height y, and dω = dy dφ).
    pub fn integral(&self) -> Color {
        match *self {
            Sky::Uniform(c) => c * (4.0 * std::f32::consts::PI),
            Sky::Gradient {
                zenith,
                horizon,
                nadir,
            } => (zenith + horizon * 2.0 + nadir) * std::f32::consts::PI,
        }
    }

    /// The sky with every radiance multiplied by `scale` (`sky_scale`).
    pub fn scaled(self, scale: f32) -> Sky {
        match self {
            Sky::Uniform(c) => Sky::Uniform(c * scale),
            Sky::Gradient {
                zenith,
                horizon,
                nadir,
            } => Sky::Gradient {
                zenith: zenith * scale,
                horizon: horizon * scale,
                nadir: nadir * scale,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    /// `integral` against a midpoint sum over the sphere in (y, φ) (dω = dy dφ).
    #[test]
    fn integral_matches_a_sum_over_the_sphere() {
        let sky = Sky::Gradient {
            zenith: vec3(3.0, 2.0, 1.0),
            horizon: vec3(1.0, 1.0, 1.0),
            nadir: vec3(0.5, 0.0, 0.25),
        };
        let n = 400;
        let mut sum = Color::ZERO;
        for i in 0..n {
            let y = -1.0 + (i as f32 + 0.5) * 2.0 / n as f32;
            let r = (1.0 - y * y).sqrt();
            for j in 0..n {
                let phi = (j as f32 + 0.5) * std::f32::consts::TAU / n as f32;
                sum += sky.radiance(vec3(r * phi.cos(), y, r * phi.sin()));
            }
        }
        let sum = sum * (2.0 / n as f32) * (std::f32::consts::TAU / n as f32);
        let exact = sky.integral();
        for c in 0..3 {
            assert!(
                (sum[c] / exact[c] - 1.0).abs() < 1e-3,
                "{sum} against {exact}"
            );
        }
        let uniform = Sky::Uniform(vec3(1.0, 2.0, 3.0)).integral();
        assert!((uniform - vec3(4.0, 8.0, 12.0) * std::f32::consts::PI).length() < 1e-5);
    }
}
