//! Image textures: decoded once to linear albedo, looked up bilinearly with wrap-around.

use std::path::Path;

use crate::color::srgb_to_linear;
use crate::geometry::{Vec2, Vec3};
use crate::image_io::{self, Image};

#[derive(Clone, Debug)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// Linear RGB, row 0 at the top of the image.
    pub texels: Vec<Vec3>,
    /// The affine map from a surface's texture coordinates to the image's, row by row
    /// (Mitsuba's `to_uv`; default: none, the coordinates as they are).
    pub to_uv: Option<[[f32; 3]; 2]>,
    /// The nearest texel rather than the bilinear mean of four (Mitsuba's `filter_type
    /// nearest`, and its `checkerboard`; default false).
    pub nearest: bool,
}

impl From<Image> for Texture {
    /// The image as it is: no `to_uv`, bilinear.
    fn from(image: Image) -> Texture {
        Texture {
            width: image.width,
            height: image.height,
            texels: image.pixels,
            to_uv: None,
            nearest: false,
        }
    }
}

impl Texture {
    /// Reads an 8-bit image (PNG, JPEG, PPM): values are sRGB-encoded and converted to linear.
    pub fn load(path: &Path) -> Result<Texture, String> {
        image_io::read_8bit(path, srgb_to_linear).map(Texture::from)
    }

    /// Reads a height image (`bump_file`): 8-bit values v are heights v/255, not colours.
    pub fn load_heights(path: &Path) -> Result<Texture, String> {
        image_io::read_8bit(path, |v| v).map(Texture::from)
    }

    /// Mitsuba's `checkerboard`: `color0` where u and v (Mitsuba's, whose v runs down the
    /// image) both lie in the lower or both in the upper half of their unit interval,
    /// `color1` elsewhere; `to_uv` as `lookup` takes it.
    pub fn checkerboard(color0: Vec3, color1: Vec3, to_uv: Option<[[f32; 3]; 2]>) -> Texture {
        Texture {
            width: 2,
            height: 2,
            texels: vec![color0, color1, color1, color0],
            to_uv,
            nearest: true,
        }
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
        let st = match &self.to_uv {
            None => st,
            Some([a, b]) => Vec2::new(
                a[0] * st.x + a[1] * st.y + a[2],
                b[0] * st.x + b[1] * st.y + b[2],
            ),
        };
        if self.nearest {
            let x = (st.x * self.width as f32).floor();
            let y = ((1.0 - st.y) * self.height as f32).floor();
            if !x.is_finite() || !y.is_finite() {
                return self.texel(0, 0);
            }
            return self.texel(x as i64, y as i64);
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
