//! Images read as inputs — textures, height images, skies and environment maps, images to
//! compare — one reader per format, each giving linear RGB. It lies below both `scene` (which
//! reads its textures and skies here) and `film` (which reads back what it wrote), so that
//! neither imports the other. Mitsuba's volume grids (`.vol`) are read here too.
//!
//! Every reader is bounded: PFM by the file's own bytes, the others by `MAX_IMAGE_BYTES` (a
//! hostile header cannot make them allocate without bound). Errors name the file.

use std::path::Path;

use crate::color::{srgb_to_linear, Color};
use crate::geometry::Vec3;

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
    read_image(path, srgb_to_linear)
}

/// Reads an image by its extension: `.pfm` and `.exr` as stored (they hold linear values),
/// any other as 8-bit values mapped through `decode` (see `read_8bit`).
pub fn read_image(path: &Path, decode: fn(f32) -> f32) -> Result<Image, String> {
    let is = |ext: &str| {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case(ext))
    };
    if is("pfm") {
        read_pfm(path)
    } else if is("exr") {
        read_exr(path)
    } else {
        read_8bit(path, decode)
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
    // `decode` of each of the 256 values once, not of every channel of every pixel (a powf
    // each for sRGB: 16% of loading `bsdf_spheres`' sphere grid, its 2048×1571 wood.jpg).
    let decoded: [f32; 256] = std::array::from_fn(|v| decode(v as f32 / 255.0));
    let pixels = img
        .pixels()
        .map(|p| Color {
            x: decoded[p[0] as usize],
            y: decoded[p[1] as usize],
            z: decoded[p[2] as usize],
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
    // The header's size is checked against the file's bytes before anything is allocated.
    let data = 12usize
        .checked_mul(n)
        .and_then(|len| bytes.get(pos..pos.checked_add(len)?))
        .ok_or_else(|| {
            format!(
                "{}: truncated PFM data (a {width}×{height} image needs {} bytes)",
                path.display(),
                12 * n as u128
            )
        })?;
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

/// Mitsuba's binary volume grid (`.vol`), little-endian: the bytes `VOL`, the version byte 3,
/// an `i32` encoding (1: float32, the only one), the `i32` cell counts along x, y and z, the
/// `i32` channel count, the bounding box as six `f32` (min x, y, z, max x, y, z), then the
/// values, channels interleaved, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeGrid {
    /// Cells along x, y and z (each ≥ 1).
    pub size: [usize; 3],
    /// Values a cell: 1 (a density) or 3 (a colour).
    pub channels: usize,
    /// The box the file places the grid in (min, max): where Mitsuba's `use_grid_bbox` puts it.
    pub bbox: (Vec3, Vec3),
    /// The values, channels interleaved, x fastest, then y, then z.
    pub data: Vec<f32>,
}

/// Bytes before a `.vol` file's values.
const VOL_HEADER_BYTES: usize = 48;

/// Reads a `.vol` file; the error names the file and what it expected there.
pub fn read_volume_grid(path: &Path) -> Result<VolumeGrid, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse_volume_grid(&bytes).map_err(|why| format!("{}: {why}", path.display()))
}

/// Decodes the bytes of a `.vol` file: its header checked, and its length against the
/// header's counts before anything is allocated.
fn parse_volume_grid(bytes: &[u8]) -> Result<VolumeGrid, String> {
    if bytes.len() < VOL_HEADER_BYTES {
        return Err(format!(
            "{} bytes: expected a Mitsuba volume grid's {VOL_HEADER_BYTES}-byte header",
            bytes.len()
        ));
    }
    if &bytes[0..3] != b"VOL" {
        return Err("expected a Mitsuba volume grid (starting with \"VOL\")".into());
    }
    if bytes[3] != 3 {
        return Err(format!("version {}: expected version 3", bytes[3]));
    }
    let int = |k: usize| i32::from_le_bytes(bytes[4 + 4 * k..8 + 4 * k].try_into().unwrap());
    let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let encoding = int(0);
    if encoding != 1 {
        return Err(format!("encoding {encoding}: expected 1 (float32)"));
    }
    let count = |k: usize, what: &str| {
        usize::try_from(int(k))
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("{} cells along {what}: expected at least 1", int(k)))
    };
    let size = [count(1, "x")?, count(2, "y")?, count(3, "z")?];
    let channels = int(4);
    if channels != 1 && channels != 3 {
        return Err(format!("{channels} channels: expected 1 or 3"));
    }
    let channels = channels as usize;
    let values = size
        .iter()
        .try_fold(channels, |n, &s| n.checked_mul(s))
        .filter(|n| n.checked_mul(4).is_some())
        .ok_or_else(|| format!("{size:?} cells of {channels} channels: too many"))?;
    let expected = VOL_HEADER_BYTES as u64 + 4 * values as u64;
    if bytes.len() as u64 != expected {
        return Err(format!(
            "{} bytes: expected {expected} for {}×{}×{} cells of {channels} channel(s)",
            bytes.len(),
            size[0],
            size[1],
            size[2]
        ));
    }
    let bbox = (
        Vec3::new(float(24), float(28), float(32)),
        Vec3::new(float(36), float(40), float(44)),
    );
    let data: Vec<f32> = bytes[VOL_HEADER_BYTES..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    if let Some(k) = data.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "value {k} is {}: expected a finite number",
            data[k]
        ));
    }
    Ok(VolumeGrid {
        size,
        channels,
        bbox,
        data,
    })
}

impl VolumeGrid {
    /// The largest value of any cell and channel (0 for none above it).
    pub fn max(&self) -> f32 {
        self.data.iter().fold(0.0, |m, &v| m.max(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bytes of a `.vol` file of `size` cells of `channels` channels and these values.
    fn vol_file(size: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
        let mut bytes = b"VOL\x03".to_vec();
        for v in [1, size[0], size[1], size[2], channels] {
            bytes.extend(v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(values) {
            bytes.extend(v.to_le_bytes());
        }
        bytes
    }

    /// A PFM whose header promises more pixels than its bytes hold, up to sizes whose byte
    /// count overflows, is refused before anything is allocated; one that holds them is read,
    /// bottom row first.
    #[test]
    fn a_pfm_is_read_only_as_far_as_its_bytes_go() {
        let dir = std::env::temp_dir().join(format!("trilux-pfm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        let path = dir.join("image.pfm");
        let mut good = b"PF\n1 2\n-1\n".to_vec();
        for v in [0.0f32, 0.0, 0.0, 1.5, 2.5, 3.5] {
            good.extend(v.to_le_bytes());
        }
        std::fs::write(&path, &good).expect("writes");
        let image = read_pfm(&path).expect("reads");
        assert_eq!(image.pixels[0], Color::new(1.5, 2.5, 3.5));
        for header in ["PF\n4294967295 4294967295\n-1\n", "PF\n1 3\n-1\n"] {
            let mut bytes = header.as_bytes().to_vec();
            bytes.extend(&good[good.len() - 24..]);
            std::fs::write(&path, &bytes).expect("writes");
            let why = read_pfm(&path).expect_err(header);
            assert!(why.contains("truncated PFM data"), "{why}");
        }
        std::fs::remove_dir_all(&dir).expect("removes the folder");
    }

    #[test]
    fn reads_a_volume_grid_as_the_file_lays_it_out() {
        let values: Vec<f32> = (0..24).map(|v| v as f32).collect();
        let grid = parse_volume_grid(&vol_file([2, 2, 2], 3, &values)).expect("reads");
        assert_eq!(grid.size, [2, 2, 2]);
        assert_eq!(grid.channels, 3);
        assert_eq!(grid.bbox, (Vec3::ZERO, Vec3::ONE));
        assert_eq!(grid.data, values);
        assert_eq!(grid.max(), 23.0);
    }

    #[test]
    fn refuses_bad_volume_grids_saying_what_it_expected() {
        let good = vol_file([2, 2, 1], 1, &[0.0; 4]);
        let cases: [(Vec<u8>, &str); 7] = [
            (
                good[..40].to_vec(),
                "40 bytes: expected a Mitsuba volume grid's 48-byte header",
            ),
            (
                good[..60].to_vec(),
                "60 bytes: expected 64 for 2×2×1 cells of 1 channel(s)",
            ),
            ([&good[..], &[0; 4]].concat(), "68 bytes: expected 64"),
            (
                b"BOL".iter().chain(&good[3..]).copied().collect(),
                "\"VOL\"",
            ),
            (
                vol_file([2, 0, 1], 1, &[]),
                "0 cells along y: expected at least 1",
            ),
            (
                vol_file([1, 1, 1], 2, &[0.0; 2]),
                "2 channels: expected 1 or 3",
            ),
            (vol_file([1, 1, 1], 1, &[f32::NAN]), "value 0 is NaN"),
        ];
        for (bytes, expected) in cases {
            let why = parse_volume_grid(&bytes).expect_err(expected);
            assert!(why.contains(expected), "{why:?} does not say {expected:?}");
        }
        // Counts whose product overflows are refused before anything is allocated.
        let huge = vol_file([i32::MAX, i32::MAX, i32::MAX], 3, &[]);
        assert!(parse_volume_grid(&huge).is_err());
        let missing = Path::new("/nonexistent/grid.vol");
        let why = read_volume_grid(missing).expect_err("no such file");
        assert!(why.starts_with("/nonexistent/grid.vol: "), "{why}");
    }
}
