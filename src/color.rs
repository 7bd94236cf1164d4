//! Colour: linear RGB in f32 (radiance, albedo, pixel values) and the sRGB transfer function
//! used where images and textures meet 8-bit files. Everything above geometry takes its colour
//! type from here.

use crate::geometry::Vec3;

/// Linear RGB radiance or reflectance.
pub type Color = Vec3;

/// The sRGB transfer function, decoding.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer function, encoding.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The Rec. 709 luminance of a linear RGB colour, with Mitsuba's coefficients (its
/// `luminance`): what a colour texture gives where one number is asked of it.
pub fn luminance(c: Vec3) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}
