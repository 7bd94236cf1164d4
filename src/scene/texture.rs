//! Image textures: decoded once to linear albedo, looked up bilinearly with wrap-around.

use std::path::Path;

use crate::color::{luminance, srgb_to_linear};
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
    /// The mean of its texels: its mean over the surface where the surface's texture
    /// coordinates cover the unit square evenly.
    pub fn mean(&self) -> Vec3 {
        let sum: Vec3 = self.texels.iter().copied().sum();
        sum / self.texels.len().max(1) as f32
    }

    /// Reads a colour image: an 8-bit one (PNG, JPEG, PPM) decoded from sRGB to linear, an
    /// EXR or PFM as stored.
    pub fn load(path: &Path) -> Result<Texture, String> {
        image_io::read_image(path, srgb_to_linear).map(Texture::from)
    }

    /// Reads an image of values that are not colours (`bump_file` heights, Mitsuba's `raw`
    /// bitmaps): 8-bit values v as v/255, an EXR or PFM as stored.
    pub fn load_heights(path: &Path) -> Result<Texture, String> {
        image_io::read_image(path, |v| v).map(Texture::from)
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

    /// A surface's texture coordinates in the image's, through `to_uv`.
    fn mapped(&self, st: Vec2) -> Vec2 {
        match &self.to_uv {
            None => st,
            Some([a, b]) => Vec2::new(
                a[0] * st.x + a[1] * st.y + a[2],
                b[0] * st.x + b[1] * st.y + b[2],
            ),
        }
    }

    /// The gradient of the bilinear lookup's luminance with respect to the surface's texture
    /// coordinates (s, t): what a height map tilts a normal by, as Mitsuba's bitmap
    /// `eval_1_grad` gives it (zero under the nearest filter, flat almost everywhere).
    pub fn gradient(&self, st: Vec2) -> Vec2 {
        if self.nearest || self.texels.is_empty() {
            return Vec2::ZERO;
        }
        let Some((ix, iy, fx, fy)) = self.bilinear_cell(self.mapped(st)) else {
            return Vec2::ZERO;
        };
        let f = |dx, dy| luminance(self.texel(ix + dx, iy + dy));
        let (f00, f10, f01, f11) = (f(0, 0), f(1, 0), f(0, 1), f(1, 1));
        let dfdx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let dfdy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        // Image coordinates against the mapped ones (rows run down, t up), then through
        // `to_uv`'s linear part, transposed.
        let (gx, gy) = (dfdx * self.width as f32, -dfdy * self.height as f32);
        match &self.to_uv {
            None => Vec2::new(gx, gy),
            Some([a, b]) => Vec2::new(a[0] * gx + b[0] * gy, a[1] * gx + b[1] * gy),
        }
    }

    /// The texel whose centre is up and left of the mapped coordinates `st` (rows run down,
    /// t up) and the fractions of the way to the next texel's centre, across and down: the
    /// four texels a bilinear lookup weighs. None for coordinates that are not finite.
    fn bilinear_cell(&self, st: Vec2) -> Option<(i64, i64, f32, f32)> {
        let x = st.x * self.width as f32 - 0.5;
        let y = (1.0 - st.y) * self.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return None;
        }
        let (x0, y0) = (x.floor(), y.floor());
        Some((x0 as i64, y0 as i64, x - x0, y - y0))
    }

    /// Bilinear lookup with repeat; `t = 0` is the bottom row of the image, as in OBJ.
    pub fn lookup(&self, st: Vec2) -> Vec3 {
        if self.texels.is_empty() {
            return Vec3::ZERO;
        }
        let st = self.mapped(st);
        if self.nearest {
            let x = (st.x * self.width as f32).floor();
            let y = ((1.0 - st.y) * self.height as f32).floor();
            if !x.is_finite() || !y.is_finite() {
                return self.texel(0, 0);
            }
            return self.texel(x as i64, y as i64);
        }
        let Some((ix, iy, fx, fy)) = self.bilinear_cell(st) else {
            return self.texel(0, 0);
        };
        let top = self.texel(ix, iy) * (1.0 - fx) + self.texel(ix + 1, iy) * fx;
        let bottom = self.texel(ix, iy + 1) * (1.0 - fx) + self.texel(ix + 1, iy + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Heights that climb by 0.25 a texel to the right and by 0.125 a texel up (rows run
    /// down the image): away from the wrap, the gradient in (s, t) is the climb times the
    /// texels per unit, (0.25·8, 0.125·4); through a `to_uv` that doubles s and shifts, twice
    /// the first.
    /// An EXR texture keeps its linear values, above 1 too; an 8-bit PNG is decoded from
    /// sRGB as a colour and taken as it is as heights.
    #[test]
    fn exr_textures_keep_their_values_and_8_bit_ones_are_decoded() {
        let dir = std::env::temp_dir().join(format!("trilux-texture-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        let values = [[2.5f32, 0.1, 0.0], [0.25, 7.0, 1.0]];
        let exr = image::Rgb32FImage::from_fn(2, 1, |x, _| image::Rgb(values[x as usize]));
        let exr_path = dir.join("hdr.exr");
        exr.save(&exr_path).expect("writes an EXR");
        for texture in [Texture::load(&exr_path), Texture::load_heights(&exr_path)] {
            let texels = texture.expect("reads the EXR").texels;
            assert_eq!(texels, values.map(Vec3::from_array).to_vec());
        }
        let png = image::RgbImage::from_pixel(1, 1, image::Rgb([128, 0, 255]));
        let png_path = dir.join("ldr.png");
        png.save(&png_path).expect("writes a PNG");
        let colour = Texture::load(&png_path).expect("reads the PNG").texels[0];
        assert_eq!(colour, Vec3::new(srgb_to_linear(128.0 / 255.0), 0.0, 1.0));
        let heights = Texture::load_heights(&png_path)
            .expect("reads the PNG")
            .texels[0];
        assert_eq!(heights, Vec3::new(128.0 / 255.0, 0.0, 1.0));
        std::fs::remove_dir_all(&dir).expect("removes the folder");
    }

    #[test]
    fn the_gradient_of_a_ramp_is_its_slope() {
        let (width, height) = (8u32, 4u32);
        let texels = (0..height)
            .flat_map(|y| {
                (0..width).map(move |x| Vec3::splat(0.25 * x as f32 + 0.125 * (3 - y) as f32))
            })
            .collect();
        let mut ramp = Texture {
            width,
            height,
            texels,
            to_uv: None,
            nearest: false,
        };
        let g = ramp.gradient(Vec2::new(0.4, 0.5));
        assert!((g - Vec2::new(2.0, 0.5)).length() < 1e-5, "{g}");
        ramp.to_uv = Some([[2.0, 0.0, -0.3], [0.0, 1.0, 0.0]]);
        let g = ramp.gradient(Vec2::new(0.4, 0.5));
        assert!((g - Vec2::new(4.0, 0.5)).length() < 1e-5, "{g}");
        ramp.nearest = true;
        assert_eq!(ramp.gradient(Vec2::new(0.4, 0.5)), Vec2::ZERO);
    }
}
