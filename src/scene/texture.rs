//! Image textures: decoded once to linear albedo, looked up bilinearly with wrap-around.

use std::path::Path;

use crate::color::srgb_to_linear;

use crate::geometry::{Vec2, Vec3};

/// The largest texture trilux decodes, in bytes of decoded pixels: a bad header cannot make
/// it allocate without bound.
pub const MAX_TEXTURE_BYTES: u64 = 1 << 30;

#[derive(Clone, Debug)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// Linear RGB, row 0 at the top of the image.
    pub texels: Vec<Vec3>,
}

impl Texture {
    /// Reads PPM (P3/P6) or PNG; 8-bit values are sRGB-encoded and converted to linear.
    pub fn load(path: &Path) -> Result<Texture, String> {
        Self::load_with(path, srgb_to_linear)
    }

    /// Reads a height image (`bump_file`): 8-bit values v are heights v/255, not colours.
    pub fn load_heights(path: &Path) -> Result<Texture, String> {
        Self::load_with(path, |v| v)
    }

    /// Reads an image, mapping each channel's value in [0, 1] through `decode`.
    fn load_with(path: &Path, decode: fn(f32) -> f32) -> Result<Texture, String> {
        let mut reader = image::ImageReader::open(path)
            .map_err(|e| e.to_string())?
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_TEXTURE_BYTES);
        reader.limits(limits);
        let img = reader.decode().map_err(|e| e.to_string())?.to_rgb8();
        let (width, height) = img.dimensions();
        let texels = img
            .pixels()
            .map(|p| Vec3 {
                x: decode(p[0] as f32 / 255.0),
                y: decode(p[1] as f32 / 255.0),
                z: decode(p[2] as f32 / 255.0),
            })
            .collect();
        Ok(Texture {
            width,
            height,
            texels,
        })
    }

    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = x.rem_euclid(w) as usize;
        let y = y.rem_euclid(h) as usize;
        self.texels[y * self.width as usize + x]
    }

    /// Bilinear lookup with repeat; `t = 0` is the bottom row of the image, as in OBJ.
    pub fn lookup(&self, st: Vec2) -> Vec3 {
        if self.texels.is_empty() {
            return Vec3::ZERO;
        }
        let x = st.x * self.width as f32 - 0.5;
        let y = (1.0 - st.y) * self.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return self.texel(0, 0);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (ix, iy) = (x0 as i64, y0 as i64);
        let top = self.texel(ix, iy) * (1.0 - fx) + self.texel(ix + 1, iy) * fx;
        let bottom = self.texel(ix, iy + 1) * (1.0 - fx) + self.texel(ix + 1, iy + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}
