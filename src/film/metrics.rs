//! Image comparison (`render compare`): error metrics of an image against a reference, and a
//! heat map of where they differ. Images are compared as linear radiance.

use std::path::Path;

use super::{Film, ImageFormat};
use crate::color::Color;

/// The ε of relMSE: keeps dark reference pixels from dominating.
pub const RELMSE_EPSILON: f64 = 1e-2;

/// Error of an image against a reference, over every pixel and channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Root mean square error.
    pub rmse: f64,
    /// Mean of (a − b)² / (b² + ε), ε = 1e-2.
    pub relmse: f64,
    /// Mean of |a − b| / (|b| + ε), ε = 1e-2.
    pub mape: f64,
    /// Largest absolute difference.
    pub max_error: f64,
}

/// Reads an image as linear radiance: PFM and EXR as stored, PNG and JPEG decoded from sRGB.
pub fn read_image(path: &Path) -> Result<Film, String> {
    if ImageFormat::from_path(path).is_none() {
        return Err(format!(
            "{}: unknown image format (use .png, .jpg, .exr or .pfm)",
            path.display()
        ));
    }
    crate::image_io::read_radiance(path).map(Film::from)
}

/// The metrics of `image` against `reference`; the two must have the same size.
pub fn compare(image: &Film, reference: &Film) -> Result<Metrics, String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "the images differ in size: {}×{} against {}×{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    let (mut se, mut rel, mut ape, mut max) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut n = 0usize;
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        for (a, b) in a.to_array().into_iter().zip(b.to_array()) {
            let (a, b) = (a as f64, b as f64);
            let d = a - b;
            se += d * d;
            rel += d * d / (b * b + RELMSE_EPSILON);
            ape += d.abs() / (b.abs() + RELMSE_EPSILON);
            max = max.max(d.abs());
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    Ok(Metrics {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
        mape: ape / n,
        max_error: max,
    })
}

/// A heat map of the per-pixel error (mean absolute difference over the channels), black for
/// none through red and yellow to white for the largest.
pub fn heatmap(image: &Film, reference: &Film) -> Film {
    let errors: Vec<f32> = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| (*a - *b).abs().to_array().iter().sum::<f32>() / 3.0)
        .collect();
    let max = errors
        .iter()
        .copied()
        .fold(0.0f32, f32::max)
        .max(f32::MIN_POSITIVE);
    let pixels = errors
        .iter()
        .map(|&e| {
            let x = (e / max).clamp(0.0, 1.0) * 3.0;
            Color {
                x: x.min(1.0),
                y: (x - 1.0).clamp(0.0, 1.0),
                z: (x - 2.0).clamp(0.0, 1.0),
            }
        })
        .collect();
    Film {
        width: image.width,
        height: image.height,
        pixels,
        samples: None,
    }
}
