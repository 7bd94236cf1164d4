//! The solved mesh seen from the camera: each camera ray's hit finds its patch, which shows
//! the value of the chosen visualization mode — flat, or bilinear between corner values with
//! `-interpolate` — with patch outlines drawn over the image for `--wireframe`.

use rayon::prelude::*;

use super::settings::Display;
use super::solver::{Element, FormFactorSampler};
use super::Solution;
use crate::accel::Accel;
use crate::engines::engine::RenderSettings;
use crate::engines::radiosity::mesh::NONE;
use crate::film::Film;
use crate::geometry::Vec3;
use crate::render::{render_pixels, RenderStats};
use crate::scene::{Camera, Color, Scene};

const WIRE: Color = Vec3::ZERO;
const SOURCE_OUTLINE: Color = Vec3 {
    x: 1.0,
    y: 0.0,
    z: 0.0,
};

/// Renders a solution in the mode `settings.radiosity.display`.
pub fn render_solution(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    solution: &Solution,
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
    // A hierarchical solution shows its leaf elements (flat; -interpolate smooths the
    // patches' means instead) in the views it has per element.
    let per_element: Option<fn(&Element, Color, Color) -> Color> = match r.display {
        Display::Radiance => Some(|e, albedo, ambient| e.radiance + albedo * ambient),
        Display::Absorbed => Some(|e, albedo, _| (Vec3::ONE - albedo) * e.incident),
        _ => None,
    };
    let elements = &solution.state.elements;
    let field = match per_element {
        Some(value) if !elements.is_empty() && !r.interpolate => solution.element_field(
            elements
                .iter()
                .map(|e| value(e, patches[e.patch as usize].albedo, solution.ambient))
                .collect(),
        ),
        _ => solution.field(values, r.interpolate),
    };
    let (mut film, stats) = render_pixels(
        scene,
        accel,
        &settings.image(),
        "display",
        |ray, hit, _rng, _id, _counts| {
            // Through a fog, what the camera sees is attenuated over the ray's length (and
            // nothing beyond the scene gets through); the light the fog scatters in is the
            // other engines' (`--plan` says so).
            let fog = scene.fog.map(|k| &scene.media[k]);
            let Some(s) = hit else {
                if fog.is_some() {
                    return Vec3::ZERO;
                }
                return scene.sky_or_background(ray.direction);
            };
            let seen = solution
                .sample(scene, &s, -ray.direction, &field)
                .unwrap_or(Vec3::ZERO);
            match fog {
                Some(m) => seen * m.transmittance(s.t * ray.direction.length()),
                None => seen,
            }
        },
    );
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
