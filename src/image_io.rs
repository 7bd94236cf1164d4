//! Images read as inputs — textures, height images, skies and environment maps, images to
//! compare — one reader per format, each giving linear RGB. It lies below both `scene` (which
//! reads its textures and skies here) and `film` (which reads back what it wrote), so that
//! neither imports the other. A reader of another input file format (a volume grid) belongs
//! here too.
//!
//! Every reader is bounded: PFM by the file's own bytes, the others by `MAX_IMAGE_BYTES` (a
//! hostile header cannot make them allocate without bound). Errors name the file.

use std::path::Path;

use crate::color::{srgb_to_linear, Color};

/// The largest image trilux decodes, in bytes of decoded pixels.
pub const MAX_IMAGE_BYTES: u64 = 1 << 30;

/// A decoded image.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Linear RGB, row-major, row 0 at the top of the image.
    pub pixels: Vec<Color>,
}

/// Reads an image as linear radiance by its extension: `.pfm` and `.exr` as stored, any other
/// (PNG, JPEG, PPM) as 8-bit values decoded from sRGB.
pub fn read_radiance(path: &Path) -> Result<Image, String> {
    let is = |ext: &str| {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case(ext))
    };
    if is("pfm") {
        read_pfm(path)
    } else if is("exr") {
        read_exr(path)
    } else {
        read_8bit(path, srgb_to_linear)
    }
}

/// Reads an image of 8-bit channels (PNG, JPEG, PPM P3/P6: any format the `image` crate
/// recognises by its content), mapping each value v/255 in [0, 1] through `decode`
/// (`srgb_to_linear` for colours, the identity for heights and normal maps).
pub fn read_8bit(path: &Path, decode: fn(f32) -> f32) -> Result<Image, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| at(&e))?
        .with_guessed_format()
        .map_err(|e| at(&e))?;
    reader.limits(limits());
    let img = reader.decode().map_err(|e| at(&e))?.to_rgb8();
    let (width, height) = img.dimensions();
    let pixels = img
        .pixels()
        .map(|p| Color {
            x: decode(p[0] as f32 / 255.0),
            y: decode(p[1] as f32 / 255.0),
            z: decode(p[2] as f32 / 255.0),
        })
        .collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// Reads an OpenEXR image's RGB as stored (linear).
pub fn read_exr(path: &Path) -> Result<Image, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let mut reader = image::ImageReader::open(path).map_err(|e| at(&e))?;
    reader.limits(limits());
    let img = reader.decode().map_err(|e| at(&e))?.to_rgb32f();
    let (width, height) = img.dimensions();
    let pixels = img
        .pixels()
        .map(|p| Color {
            x: p[0],
            y: p[1],
            z: p[2],
        })
        .collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// The `image` crate's limits with `MAX_IMAGE_BYTES` as its allocation bound.
fn limits() -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_IMAGE_BYTES);
    limits
}

/// Reads a colour PFM, little- or big-endian (the film writes little-endian ones).
pub fn read_pfm(path: &Path) -> Result<Image, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err(format!("{}: truncated PFM header", path.display()));
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1;
    let bad = || format!("{}: bad PFM header", path.display());
    if fields[0] != "PF" {
        return Err(bad());
    }
    let width: u32 = fields[1].parse().map_err(|_| bad())?;
    let height: u32 = fields[2].parse().map_err(|_| bad())?;
    let scale: f32 = fields[3].parse().map_err(|_| bad())?;
    let n = width as usize * height as usize;
    let data = bytes
        .get(pos..pos + 12 * n)
        .ok_or_else(|| format!("{}: truncated PFM data", path.display()))?;
    let value = |k: usize| {
        let b = [
            data[4 * k],
            data[4 * k + 1],
            data[4 * k + 2],
            data[4 * k + 3],
        ];
        if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    // PFM stores the bottom row first.
    let mut pixels = vec![Color::ZERO; n];
    for row in 0..height as usize {
        let src_row = height as usize - 1 - row;
        for i in 0..width as usize {
            let k = 3 * (src_row * width as usize + i);
            pixels[row * width as usize + i] = Color {
                x: value(k),
                y: value(k + 1),
                z: value(k + 2),
            };
        }
    }
    Ok(Image {
        width,
        height,
        pixels,
    })
}
