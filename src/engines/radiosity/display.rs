//! The solved mesh seen from the camera: each camera ray's hit finds its patch, which shows
//! the value of the chosen visualization mode — flat, or bilinear between corner values with
//! `-interpolate` — with patch outlines drawn over the image for `--wireframe`.

use rayon::prelude::*;

use super::settings::Display;
use super::solver::{Element, FormFactorSampler};
use super::{PatchField, Solution};
use crate::accel::Accel;
use crate::engines::engine::RenderSettings;
use crate::engines::radiosity::mesh::NONE;
use crate::film::Film;
use crate::geometry::{Ray, Vec3};
use crate::render::{render_keeping_samples, render_pixels, RenderStats, SampleGrid};
use crate::scene::{Camera, Color, Scene, SurfaceHit};

const WIRE: Color = Vec3::ZERO;
const SOURCE_OUTLINE: Color = Vec3 {
    x: 1.0,
    y: 0.0,
    z: 0.0,
};

/// At most this many camera samples are kept (`SeenMesh`, 32 bytes each, 64 MiB in all): a
/// 1024×1024 image at 2 samples a pixel.
const MAX_KEPT_SAMPLES: usize = 1 << 21;

/// What the camera samples of an image saw of a solution's mesh. The viewer keeps it between
/// images of one solve from one camera: each shot more draws the image again from it
/// (`Samples::Kept`) without a camera ray.
pub struct SeenMesh(SampleGrid<Seen>);

/// Where the camera samples of a solution's image come from.
pub enum Samples<'a> {
    /// Traced.
    Traced,
    /// Traced, and what they saw of the mesh put in `keep` (None where it is not kept: see
    /// `render::render_keeping_samples`, or more than `MAX_KEPT_SAMPLES` samples).
    Keep(&'a mut Option<SeenMesh>),
    /// What the image's samples saw, kept from an image of the same scene, camera, image
    /// settings and mesh: drawn with no camera ray, the same pixels bit for bit.
    Kept(&'a SeenMesh),
}

/// Renders a solution in the mode `settings.radiosity.display`, its camera samples from
/// `samples`.
pub fn render_solution(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    solution: &Solution,
    samples: Samples,
) -> (Film, RenderStats) {
    let image = settings.image();
    let look = |ray: &Ray, hit| Seen::of(scene, solution, ray, hit);
    draw(scene, accel, settings, solution, |field| match samples {
        Samples::Kept(seen) => seen.0.film(|s| s.radiance(solution, field)),
        Samples::Keep(keep)
            if image.width as usize
                * image.height as usize
                * image.num_antialias_samples as usize
                <= MAX_KEPT_SAMPLES =>
        {
            let (film, stats, grid) =
                render_keeping_samples(scene, accel, &image, "display", look, |s| {
                    s.radiance(solution, field)
                });
            *keep = grid.map(SeenMesh);
            (film, stats)
        }
        samples => {
            if let Samples::Keep(keep) = samples {
                *keep = None;
            }
            render_pixels(scene, accel, &image, "display", |ray, hit, _, _, _| {
                look(ray, hit).radiance(solution, field)
            })
        }
    })
}

/// What one camera sample sees.
#[derive(Clone, Copy, Debug)]
enum Seen {
    /// No surface: the sky or the background (black through a fog, whose light is the other
    /// engines').
    Beyond(Color),
    /// A surface: its patch and the point's parameters on it (None where no patch lies, e.g.
    /// a triangle of a scene whose mesh left it out), and the fog's transmittance along the
    /// ray.
    Surface {
        at: Option<(u32, f32, f32)>,
        through: Option<Color>,
    },
}

impl Seen {
    fn of(scene: &Scene, solution: &Solution, ray: &Ray, hit: Option<SurfaceHit>) -> Seen {
        // Through a fog, what the camera sees is attenuated over the ray's length (and
        // nothing beyond the scene gets through); the light the fog scatters in is the
        // other engines' (`--plan` says so).
        let fog = scene.fog.map(|k| &scene.media[k]);
        let Some(s) = hit else {
            return Seen::Beyond(match fog {
                Some(_) => Vec3::ZERO,
                None => scene.sky_or_background(ray.direction),
            });
        };
        Seen::Surface {
            at: solution
                .locate(scene, &s, -ray.direction)
                .map(|(k, u, v)| (k as u32, u, v)),
            through: fog.map(|m| m.transmittance(s.t * ray.direction.length())),
        }
    }

    /// The radiance `field` shows along the sample's ray.
    fn radiance(&self, solution: &Solution, field: &PatchField) -> Color {
        match *self {
            Seen::Beyond(background) => background,
            Seen::Surface { at, through } => {
                let seen = at.map_or(Vec3::ZERO, |(k, u, v)| {
                    solution.value_at(field, (k as usize, u, v))
                });
                match through {
                    Some(t) => seen * t,
                    None => seen,
                }
            }
        }
    }
}

/// The image of a solution in the mode `settings.radiosity.display`: the values the mode
/// shows over the patches, `pixels` drawing them, then the outlines over the pixels.
fn draw(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    solution: &Solution,
    pixels: impl FnOnce(&PatchField) -> (Film, RenderStats),
) -> (Film, RenderStats) {
    let r = &settings.radiosity;
    let patches = &solution.patches;
    let source = form_factor_source(solution, r.ff_source);
    let values: Vec<Color> = match settings.radiosity.display {
        Display::Radiance => solution.display_radiance(),
        Display::Materials => patches.iter().map(|p| p.albedo).collect(),
        Display::Lights => patches.iter().map(|p| p.emitted).collect(),
        Display::Undistributed => solution.state.undistributed.clone(),
        Display::Absorbed => patches
            .iter()
            .zip(&solution.state.incident)
            .map(|(p, e)| (Vec3::ONE - p.albedo) * (*e))
            .collect(),
        Display::FormFactors => form_factor_greys(scene, accel, settings, solution, source),
    };
    // A hierarchical solution shows its leaf elements (flat, or smoothed between them with
    // -interpolate) in the views it has per element.
    let per_element: Option<fn(&Element, Color, Color) -> Color> = match r.display {
        Display::Radiance => Some(|e, albedo, ambient| e.radiance + albedo * ambient),
        Display::Absorbed => Some(|e, albedo, _| (Vec3::ONE - albedo) * e.incident),
        _ => None,
    };
    let elements = &solution.state.elements;
    let field = match per_element {
        Some(value) if !elements.is_empty() => solution.element_field(
            elements
                .iter()
                .map(|e| value(e, patches[e.patch as usize].albedo, solution.ambient))
                .collect(),
            &values,
            r.interpolate,
        ),
        _ => solution.field(values, r.interpolate),
    };
    let (mut film, stats) = pixels(&field);
    let outline_source = settings.radiosity.display == Display::FormFactors;
    if r.wireframe || outline_source {
        let ids = patch_ids(scene, accel, settings, solution);
        let (w, h) = (settings.width as usize, settings.height as usize);
        let id = |x: usize, y: usize| ids[y * w + x];
        for y in 0..h {
            for x in 0..w {
                let here = id(x, y);
                let neighbours = [
                    (x + 1 < w).then(|| id(x + 1, y)),
                    (y + 1 < h).then(|| id(x, y + 1)),
                    (x > 0).then(|| id(x - 1, y)),
                    (y > 0).then(|| id(x, y - 1)),
                ];
                let border = neighbours.iter().flatten().any(|n| n.0 != here.0);
                if outline_source && here.0 == source as u32 && border {
                    film.pixels[y * w + x] = SOURCE_OUTLINE;
                } else if r.wireframe
                    && here.1 != NONE
                    && neighbours[..2].iter().flatten().any(|n| n.1 != here.1)
                {
                    film.pixels[y * w + x] = WIRE;
                }
            }
        }
    }
    (film, stats)
}

/// The patch `--ff-source` names, or the one with the most undistributed power (the next to
/// shoot), or the brightest emitter when everything has been shot.
fn form_factor_source(solution: &Solution, asked: Option<u32>) -> usize {
    let patches = &solution.patches;
    if let Some(k) = asked {
        return (k as usize).min(patches.len().saturating_sub(1));
    }
    let power = |c: Color, a: f32| (c.x + c.y + c.z) * a;
    let best = |values: &[Color]| {
        (0..patches.len()).max_by(|&a, &b| {
            power(values[a], patches[a].area).total_cmp(&power(values[b], patches[b].area))
        })
    };
    let unshot = &solution.state.undistributed;
    let emitted: Vec<Color> = patches.iter().map(|p| p.emitted).collect();
    if unshot.iter().any(|u| u.max_element() > 0.0) {
        best(unshot).unwrap_or(0)
    } else {
        best(&emitted).unwrap_or(0)
    }
}

/// Grey levels F_source→j / max_j F_source→j.
fn form_factor_greys(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    solution: &Solution,
    source: usize,
) -> Vec<Color> {
    let patches = &solution.patches;
    if patches.is_empty() {
        return Vec::new();
    }
    let sampler = FormFactorSampler::new(
        scene,
        accel,
        patches,
        settings.radiosity.num_form_factor_samples.max(1),
        solution.visibility,
        settings.seed,
        None,
    );
    // The row holds F_j→source; reciprocity turns it into F_source→j.
    let a_source = patches[source].area.max(f32::MIN_POSITIVE);
    let from_source: Vec<f32> = sampler
        .row(source)
        .iter()
        .zip(patches)
        .map(|(f, p)| f * p.area / a_source)
        .collect();
    let max = from_source.iter().copied().fold(0.0f32, f32::max);
    from_source
        .iter()
        .map(|&f| Vec3::splat(if max > 0.0 { f / max } else { 0.0 }))
        .collect()
}

/// The patch and the cell (`Solution::cell_at`) seen at each pixel centre (`NONE` for the
/// background), rows from the top.
fn patch_ids(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    solution: &Solution,
) -> Vec<(u32, u32)> {
    let (w, h) = (settings.width, settings.height);
    let view = scene.camera().view();
    let mut ids = vec![(NONE, NONE); w as usize * h as usize];
    ids.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(row, out)| {
            let j = h - 1 - row as u32;
            for (i, id) in out.iter_mut().enumerate() {
                let (x, y) = Camera::screen_point(i as u32, j, 0.5, 0.5, w, h);
                let ray = view.ray(x, y);
                if let Some(s) = crate::accel::closest_surface(accel, scene, &ray) {
                    if let Some(cell) = solution.cell_at(scene, &s, -ray.direction) {
                        *id = cell;
                    }
                }
            }
        });
    ids
}
