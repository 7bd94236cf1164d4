//! Parts of a split render and their merge (`--crop-window`, `--pixel-samples`, `render
//! merge`). A part is a window of the image and a range of each pixel's samples; it is written
//! as an EXR whose display window is the whole image and whose data window is the part's, with
//! the mean in R, G, B (so that any viewer shows it) and, per pixel, the sum of its finite
//! samples and the sum of their squares (in two f32 channels each, `sum.*` and `sum_lo.*`,
//! `sq.*` and `sq_lo.*`, which hold the f64 sums to about 48 bits) and their number (`count`,
//! u32). Attributes record the sample range, the
//! fingerprint of scene and settings, and whether the render ran to its end.
//!
//! Because every random number is a function of (seed, pixel, sample), a pixel's samples are
//! the same whichever part takes them: tiles merge into the very bytes of the single render
//! (a pixel one part covers whole keeps that part's mean), and sample batches merge as sums
//! divided once, to within f32 rounding of the single render.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, FlatSamples, Image, ImageAttributes, IntegerBounds,
    Layer, LayerAttributes, ReadChannels, ReadLayers, SmallVec, Text, Vec2, WritableImage,
};

use super::Film;
use crate::color::Color;
use crate::output::{write_atomically, OutputError};

/// A rectangle of pixels: columns `x0..x1`, rows `y0..y1` counted from the top.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Window {
    pub y0: u32,
    pub x0: u32,
    pub y1: u32,
    pub x1: u32,
}

impl Window {
    /// Every pixel of a `width` × `height` image.
    pub fn full(width: u32, height: u32) -> Window {
        Window {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// pbrt's crop window: fractions `[x0, x1, y0, y1]` of the image, x from the left and y
    /// from the top, each pixel edge at ⌈side × fraction⌉. The product is taken in f64 less
    /// 1e-6, so that a fraction written as edge / side with 12 digits gives back that edge.
    pub fn from_fractions(f: [f64; 4], width: u32, height: u32) -> Window {
        let edge = |fraction: f64, side: u32| {
            ((side as f64 * fraction - 1e-6).ceil().max(0.0) as u32).min(side)
        };
        Window {
            x0: edge(f[0], width),
            x1: edge(f[1], width),
            y0: edge(f[2], height),
            y1: edge(f[3], height),
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    pub fn pixels(&self) -> usize {
        self.width() as usize * self.height() as usize
    }

    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    /// Whether the pixel in column `x` and row `row` (from the top) lies inside.
    pub fn contains(&self, x: u32, row: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&row)
    }
}

impl std::fmt::Display for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "columns {}..{}, rows {}..{}",
            self.x0, self.x1, self.y0, self.y1
        )
    }
}

/// What a render took at each pixel of its window, row by row: the sum of the finite samples
/// and the sum of their squares (in f64, as the pixel loop sums them), and how many there were.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleSums {
    pub window: Window,
    pub sums: Vec<[f64; 3]>,
    pub squares: Vec<[f64; 3]>,
    pub counts: Vec<u32>,
}

impl SampleSums {
    /// The sums of an image whose every pixel is one sample: its own value, counted once (for
    /// views that take no samples, such as the MATERIALS view).
    pub fn of_pixels(film: &Film, window: Window) -> SampleSums {
        let mut sums = Vec::with_capacity(window.pixels());
        for row in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                sums.push(film.get(x, row).to_array().map(f64::from));
            }
        }
        SampleSums {
            window,
            counts: vec![1; sums.len()],
            squares: sums.iter().map(|s| s.map(|v| v * v)).collect(),
            sums,
        }
    }

    /// The variance of each pixel's samples (the unbiased estimate, n − 1 in the denominator;
    /// 0 where a pixel has fewer than two samples), as a `width` × `height` image that is
    /// black outside the window. The variance of a pixel's mean is this over its count.
    pub fn variance(&self, width: u32, height: u32) -> Film {
        let mut film = Film::new(width, height);
        let w = self.window.width().max(1) as usize;
        for (k, ((sum, squares), &n)) in self
            .sums
            .iter()
            .zip(&self.squares)
            .zip(&self.counts)
            .enumerate()
        {
            let (x, row) = (
                self.window.x0 as usize + k % w,
                self.window.y0 as usize + k / w,
            );
            let n = n as f64;
            // Σx² − (Σx)²/n cancels to rounding where the samples agree; it is never below 0.
            let v = |c: usize| {
                if n < 2.0 {
                    0.0
                } else {
                    ((squares[c] - sum[c] * sum[c] / n).max(0.0) / (n - 1.0)) as f32
                }
            };
            film.pixels[row * width as usize + x] = Color::new(v(0), v(1), v(2));
        }
        film
    }
}

/// Which part of which render a part is: recorded in its file, checked by the merge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartInfo {
    /// The whole image.
    pub width: u32,
    pub height: u32,
    /// Samples `samples.0 ≤ s < samples.1` of each pixel, of `spp`.
    pub samples: (u32, u32),
    pub spp: u32,
    /// Hash of the scene and of every setting that changes a pixel (not the window, the
    /// sample range, the thread count or the output).
    pub fingerprint: u64,
    /// False when the render was interrupted: pixels it did not reach hold no samples.
    pub complete: bool,
}

/// A part read back: what it is, its window, and per pixel of the window the mean and the
/// sums.
pub struct Part {
    pub info: PartInfo,
    pub means: Vec<Color>,
    pub sums: SampleSums,
}

const FINGERPRINT: &str = "trilux.fingerprint";
const SAMPLES: &str = "trilux.samples";
const COMPLETE: &str = "trilux.complete";

/// Writes a part: the film's pixels inside the window and the sums, as EXR (atomically).
pub fn write(
    path: &Path,
    film: &Film,
    sums: &SampleSums,
    info: &PartInfo,
) -> Result<(), OutputError> {
    let window = sums.window;
    let mut means = [Vec::new(), Vec::new(), Vec::new()];
    for row in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            for (m, v) in means.iter_mut().zip(film.get(x, row).to_array()) {
                m.push(v);
            }
        }
    }
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (name, mean) in ["R", "G", "B"].iter().zip(means) {
        channels.push(AnyChannel::new(*name, FlatSamples::F32(mean)));
    }
    for (prefix, values) in [("sum", &sums.sums), ("sq", &sums.squares)] {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            // The f64 sum as a sum of two f32: the nearest f32, then the nearest f32 to what
            // is left.
            let hi: Vec<f32> = values.iter().map(|s| s[c] as f32).collect();
            let lo: Vec<f32> = values
                .iter()
                .zip(&hi)
                .map(|(s, &h)| (s[c] - h as f64) as f32)
                .collect();
            channels.push(AnyChannel::new(
                format!("{prefix}.{name}").as_str(),
                FlatSamples::F32(hi),
            ));
            channels.push(AnyChannel::new(
                format!("{prefix}_lo.{name}").as_str(),
                FlatSamples::F32(lo),
            ));
        }
    }
    channels.push(AnyChannel::new(
        "count",
        FlatSamples::U32(sums.counts.clone()),
    ));
    let mut attributes = LayerAttributes {
        layer_position: Vec2(window.x0 as i32, window.y0 as i32),
        ..Default::default()
    };
    let other = &mut attributes.other;
    other.insert(
        Text::from(FINGERPRINT),
        AttributeValue::Text(Text::from(format!("{:016x}", info.fingerprint).as_str())),
    );
    other.insert(
        Text::from(SAMPLES),
        AttributeValue::Text(Text::from(
            format!("{} {} {}", info.samples.0, info.samples.1, info.spp).as_str(),
        )),
    );
    other.insert(
        Text::from(COMPLETE),
        AttributeValue::I32(info.complete as i32),
    );
    let layer = Layer::new(
        (window.width() as usize, window.height() as usize),
        attributes,
        exr::prelude::Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    let image_attributes = ImageAttributes::new(IntegerBounds::new(
        (0, 0),
        (info.width as usize, info.height as usize),
    ));
    let image = Image::new(image_attributes, layer);
    write_atomically(path, |w| {
        image
            .write()
            .to_buffered(w)
            .map_err(OutputError::encode(path))
    })
}

/// Reads a part written by `write`.
pub fn read(path: &Path) -> Result<Part, String> {
    let here = |what: &str| format!("{}: {what}", path.display());
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| here(&format!("cannot read the part: {e}")))?;
    let not_a_part = || {
        here("not a part of a split render (no trilux.samples attribute: written by render --crop-window or --pixel-samples?)")
    };
    let layer = &image.layer_data;
    let text = |key: &str| match layer.attributes.other.get(&Text::from(key)) {
        Some(AttributeValue::Text(t)) => Some(t.to_string()),
        _ => None,
    };
    let samples: Vec<u32> = text(SAMPLES)
        .ok_or_else(not_a_part)?
        .split_whitespace()
        .map(|v| v.parse().map_err(|_| not_a_part()))
        .collect::<Result<_, _>>()?;
    let [s0, s1, spp] = samples[..] else {
        return Err(not_a_part());
    };
    let fingerprint = text(FINGERPRINT)
        .and_then(|t| u64::from_str_radix(&t, 16).ok())
        .ok_or_else(not_a_part)?;
    let complete = matches!(
        layer.attributes.other.get(&Text::from(COMPLETE)),
        Some(AttributeValue::I32(1))
    );
    let display = image.attributes.display_window;
    let position = layer.attributes.layer_position;
    let size = layer.size;
    let window = Window {
        x0: position.0.max(0) as u32,
        y0: position.1.max(0) as u32,
        x1: (position.0.max(0) as usize + size.0) as u32,
        y1: (position.1.max(0) as usize + size.1) as u32,
    };
    let (width, height) = (display.size.0 as u32, display.size.1 as u32);
    if display.position != Vec2(0, 0) || window.x1 > width || window.y1 > height {
        return Err(here("its data window lies outside its display window"));
    }
    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .map(|c| &c.sample_data)
            .ok_or_else(|| here(&format!("no channel {name}")))
    };
    let f32s = |name: &str| -> Result<Vec<f32>, String> {
        match channel(name)? {
            FlatSamples::F32(v) => Ok(v.clone()),
            _ => Err(here(&format!("channel {name} is not f32"))),
        }
    };
    let counts = match channel("count")? {
        FlatSamples::U32(v) => v.clone(),
        _ => return Err(here("channel count is not u32")),
    };
    let mean = [f32s("R")?, f32s("G")?, f32s("B")?];
    let n = window.pixels();
    let means = (0..n)
        .map(|k| Color::new(mean[0][k], mean[1][k], mean[2][k]))
        .collect();
    // A sum kept as two f32 channels per colour, `PREFIX.R` and `PREFIX_lo.R`, …
    let split_sums = |prefix: &str| -> Result<Vec<[f64; 3]>, String> {
        let mut channels = Vec::with_capacity(3);
        for c in ["R", "G", "B"] {
            channels.push((
                f32s(&format!("{prefix}.{c}"))?,
                f32s(&format!("{prefix}_lo.{c}"))?,
            ));
        }
        Ok((0..n)
            .map(|k| [0, 1, 2].map(|c| channels[c].0[k] as f64 + channels[c].1[k] as f64))
            .collect())
    };
    let sums = split_sums("sum")?;
    let squares = split_sums("sq")?;
    Ok(Part {
        info: PartInfo {
            width,
            height,
            samples: (s0, s1),
            spp,
            fingerprint,
            complete,
        },
        means,
        sums: SampleSums {
            window,
            sums,
            squares,
            counts,
        },
    })
}

/// Merges parts into the whole image: every part must be complete and of the same render
/// (size, samples per pixel, fingerprint), and together they must take every sample of every
/// pixel exactly once. Parts are taken in a fixed order (by first sample, then window) and
/// sums added in f64, so the result does not depend on the order the parts are given in. A
/// pixel one part covers whole keeps that part's mean: tiles give the single render's bytes.
/// The film keeps the merged sums of the whole image (for the variance of each pixel's
/// samples).
pub fn merge(mut parts: Vec<(PathBuf, Part)>) -> Result<Film, String> {
    let Some((first_path, first)) = parts.first() else {
        return Err("no parts to merge".into());
    };
    let reference = first.info;
    for (path, part) in &parts {
        let i = &part.info;
        let differs = |what: String| {
            format!(
                "{}: {what} {} (the parts are of different renders)",
                path.display(),
                first_path.display()
            )
        };
        if !i.complete {
            return Err(format!(
                "{}: the render of this part was interrupted; render it again",
                path.display()
            ));
        }
        if (i.width, i.height) != (reference.width, reference.height) {
            return Err(differs(format!(
                "a {}×{} image, {}×{} in",
                i.width, i.height, reference.width, reference.height
            )));
        }
        if i.spp != reference.spp {
            return Err(differs(format!(
                "{} samples per pixel, {} in",
                i.spp, reference.spp
            )));
        }
        if i.fingerprint != reference.fingerprint {
            return Err(differs(
                "made from another scene, seed or settings (its fingerprint differs) than".into(),
            ));
        }
    }
    parts.sort_by_key(|(_, p)| (p.info.samples, p.sums.window));
    let (w, h, spp) = (reference.width, reference.height, reference.spp);
    let n = w as usize * h as usize;
    // Per pixel: the next sample a part must start at, the running sums, and the one part
    // that covered it whole (if so).
    let mut next = vec![0u32; n];
    let mut sums = vec![[0.0f64; 3]; n];
    let mut squares = vec![[0.0f64; 3]; n];
    let mut counts = vec![0u32; n];
    let mut whole: Vec<Option<Color>> = vec![None; n];
    let mut gaps: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
    for (path, part) in &parts {
        let (s0, s1) = part.info.samples;
        let window = part.sums.window;
        let mut k = 0;
        for row in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                let p = row as usize * w as usize + x as usize;
                if next[p] > s0 {
                    return Err(format!(
                        "{}: samples {s0}..{} of pixel ({x}, {row}) (column, row from the top) are in another part too",
                        path.display(),
                        next[p].min(s1)
                    ));
                }
                if next[p] < s0 {
                    gaps.entry((next[p], s0)).or_default().push(p);
                }
                whole[p] = (s0 == 0 && s1 == spp).then_some(part.means[k]);
                for c in 0..3 {
                    sums[p][c] += part.sums.sums[k][c];
                    squares[p][c] += part.sums.squares[k][c];
                }
                // At most `spp` samples of a pixel, each in one part: a u32 holds them.
                counts[p] += part.sums.counts[k];
                next[p] = s1;
                k += 1;
            }
        }
    }
    for (p, &s) in next.iter().enumerate() {
        if s < spp {
            gaps.entry((s, spp)).or_default().push(p);
        }
    }
    if !gaps.is_empty() {
        let lines: Vec<String> = gaps
            .iter()
            .map(|(&(s0, s1), pixels)| {
                let (mut lo, mut hi) = ((u32::MAX, u32::MAX), (0, 0));
                for &p in pixels {
                    let (x, row) = ((p % w as usize) as u32, (p / w as usize) as u32);
                    lo = (lo.0.min(x), lo.1.min(row));
                    hi = (hi.0.max(x + 1), hi.1.max(row + 1));
                }
                format!(
                    "samples {s0}..{s1} of {} pixels within columns {}..{}, rows {}..{}",
                    pixels.len(),
                    lo.0,
                    hi.0,
                    lo.1,
                    hi.1
                )
            })
            .collect();
        return Err(format!(
            "the parts do not cover the {w}×{h} image at {spp} samples per pixel: missing {}",
            lines.join("; ")
        ));
    }
    let mut film = Film::new(w, h);
    for (p, pixel) in film.pixels.iter_mut().enumerate() {
        *pixel = whole[p].unwrap_or_else(|| {
            let c = counts[p].max(1) as f64;
            Color::new(
                (sums[p][0] / c) as f32,
                (sums[p][1] / c) as f32,
                (sums[p][2] / c) as f32,
            )
        });
    }
    film.samples = Some(SampleSums {
        window: Window::full(w, h),
        sums,
        squares,
        counts,
    });
    Ok(film)
}
