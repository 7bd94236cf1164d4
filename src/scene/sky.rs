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
