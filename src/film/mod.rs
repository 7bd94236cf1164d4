//! The film: a linear RGB image in f32, and its output as PNG (sRGB, 8 bit), EXR or PFM
//! (linear float). Files are written atomically: to a temporary file beside the target, then
//! renamed over it, so an interrupted render never leaves a broken image.

pub mod metrics;
pub mod part;
pub mod ray_tree;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::camera::Camera;
use crate::color::{linear_to_srgb, Color};
use crate::image_io::Image;
use crate::output::{write_atomically, OutputError};

#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Row-major, row 0 at the top of the image.
    pub pixels: Vec<Color>,
    /// The sums of the samples behind each pixel of the window a partial render took
    /// (`--crop-window`, `--pixel-samples`): what a part file keeps for an exact merge. None
    /// for a whole render.
    pub samples: Option<part::SampleSums>,
}

/// Quality of `.jpg` output (1–100): high enough that the 8-bit image shows no blocking.
const JPEG_QUALITY: u8 = 95;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Jpeg,
    Exr,
    Pfm,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageFormat::Png),
            "jpg" | "jpeg" => Some(ImageFormat::Jpeg),
            "exr" => Some(ImageFormat::Exr),
            "pfm" => Some(ImageFormat::Pfm),
            _ => None,
        }
    }
}

impl ImageFormat {
    /// The format of an output path, and that its folder exists: checked before a render
    /// starts, so that a typo does not cost the render.
    pub fn check_output(path: &Path) -> Result<ImageFormat, OutputError> {
        let format = ImageFormat::from_path(path).ok_or_else(|| OutputError::UnknownFormat {
            path: path.to_path_buf(),
        })?;
        crate::output::check_folder(path)?;
        Ok(format)
    }
}

impl Film {
    pub fn new(width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            pixels: vec![Color::ZERO; width as usize * height as usize],
            samples: None,
        }
    }

    /// The pixels inside `window`, as an image of the window's size.
    pub fn cropped(&self, window: part::Window) -> Film {
        let mut film = Film::new(window.width(), window.height());
        for (k, row) in (window.y0..window.y1).enumerate() {
            let from = row as usize * self.width as usize;
            let to = k * window.width() as usize;
            film.pixels[to..to + window.width() as usize].copy_from_slice(
                &self.pixels[from + window.x0 as usize..from + window.x1 as usize],
            );
        }
        film
    }

    /// The pixel in column `i` and row `row` counted from the top.
    /// The pixel (index into `pixels`, rows from the top) that a world point projects to
    /// through the camera, if it lands on the film: the inverse of `Camera::screen_point`.
    pub fn pixel_of(&self, camera: &Camera, p: crate::geometry::Vec3) -> Option<usize> {
        let (x, y) = camera.project(p)?;
        let (w, h) = (self.width as f32, self.height as f32);
        let m = w.max(h);
        let (px, py) = ((x - 0.5) * m + w / 2.0, h - ((y - 0.5) * m + h / 2.0));
        (px >= 0.0 && py >= 0.0 && px < w && py < h)
            .then(|| py as usize * self.width as usize + px as usize)
    }

    pub fn get(&self, i: u32, row: u32) -> Color {
        self.pixels[row as usize * self.width as usize + i as usize]
    }

    /// 8-bit sRGB, clamped, row 0 at the top.
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|c| c.to_array())
            .map(|v| {
                let v = if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (linear_to_srgb(v) * 255.0 + 0.5) as u8
            })
            .collect()
    }

    /// Writes the film in the format the extension names.
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let format = ImageFormat::check_output(path)?;
        write_atomically(path, |w| self.encode(format, w, path))
    }

    fn encode(
        &self,
        format: ImageFormat,
        w: &mut BufWriter<File>,
        path: &Path,
    ) -> Result<(), OutputError> {
        match format {
            ImageFormat::Png | ImageFormat::Jpeg => {
                let img = image::RgbImage::from_raw(self.width, self.height, self.to_srgb8())
                    .ok_or_else(|| OutputError::Encode {
                        path: path.to_path_buf(),
                        message: "pixel count does not match the size".into(),
                    })?;
                if format == ImageFormat::Png {
                    img.write_to(w, image::ImageFormat::Png)
                        .map_err(OutputError::encode(path))
                } else {
                    // Quality 95: the 8-bit sRGB image with no visible blocking.
                    image::codecs::jpeg::JpegEncoder::new_with_quality(w, JPEG_QUALITY)
                        .encode_image(&img)
                        .map_err(OutputError::encode(path))
                }
            }
            ImageFormat::Exr => {
                // The `image` crate's encoding (run-length, tiles of 64²) with the tiles in
                // increasing order: left unspecified, as `image` leaves it, the tiles compressed
                // in parallel were written as they finished, so two renders of one image gave
                // different files.
                use exr::prelude::WritableImage;
                let encoding = exr::prelude::Encoding {
                    line_order: exr::prelude::LineOrder::Increasing,
                    ..exr::prelude::Encoding::FAST_LOSSLESS
                };
                let width = self.width as usize;
                let channels = exr::prelude::SpecificChannels::rgb(|p: exr::math::Vec2<usize>| {
                    self.pixels[p.y() * width + p.x()].to_array().into()
                });
                exr::prelude::Image::from_encoded_channels(
                    (width, self.height as usize),
                    encoding,
                    channels,
                )
                .write()
                .to_buffered(w)
                .map_err(OutputError::encode(path))
            }
            ImageFormat::Pfm => {
                // PFM: little-endian (negative scale), rows from the bottom up.
                write!(w, "PF\n{} {}\n-1.0\n", self.width, self.height)
                    .map_err(OutputError::io(path))?;
                for row in (0..self.height).rev() {
                    for i in 0..self.width {
                        for v in self.get(i, row).to_array() {
                            w.write_all(&v.to_le_bytes())
                                .map_err(OutputError::io(path))?;
                        }
                    }
                }
                Ok(())
            }
        }
    }
}

/// Reads a PFM file written by `Film::write` (or any little- or big-endian colour PFM).
pub fn read_pfm(path: &Path) -> Result<Film, String> {
    crate::image_io::read_pfm(path).map(Film::from)
}

impl From<Image> for Film {
    fn from(image: Image) -> Film {
        Film {
            width: image.width,
            height: image.height,
            pixels: image.pixels,
            samples: None,
        }
    }
}

/// Draws 3D line segments, projected through the camera, over the film (one pixel wide;
/// the parts behind the camera are left out).
pub fn draw_lines(
    film: &mut Film,
    camera: &Camera,
    lines: impl Iterator<Item = (crate::geometry::Vec3, crate::geometry::Vec3, Color)>,
) {
    for (from, to, colour) in lines {
        // Clip to the part in front of the camera by sampling along the segment.
        let steps = 2048;
        for k in 0..=steps {
            let p = from + (to - from) * (k as f32 / steps as f32);
            if let Some(idx) = film.pixel_of(camera, p) {
                film.pixels[idx] = colour;
            }
        }
    }
}
