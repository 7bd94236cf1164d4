//! The lights that are not patches as radiosity's light: the sky, and the lights without area
//! (Mitsuba's point, spot and directional lights). Each patch gathers what it receives of them
//! before the solve, through occlusion rays in the Accel, and reflects it as if it emitted it;
//! the solvers then carry that light on between the patches like any emitter's.
//!
//! - The sky: points stratified over the patch, each with a direction stratified in the
//!   cosine about its normal (by the map's importance for a `sky_texture`).
//! - A light without area: points stratified over the patch, each with the one direction to
//!   the light. Their mean is the patch's mean irradiance, which falls off across the patch
//!   with the distance and the angle, and which a shadow's edge may cut.
//!
//! A patch shows one value, so before the patches are made the mesh is split where a light
//! without area lights a face unevenly (`split_where_unevenly_lit`): along its shadows' edges,
//! a spot's rim, and near it, where its light falls off fast. Without that, the lamp's pool of
//! light on a floor of one patch was spread over the whole floor. The sky's light varies
//! slowly, and the solvers' own refinement follows the light between patches.

use rayon::prelude::*;

use super::mesh::QuadMesh;
use super::patch::{on_primitive, on_surface, Patch};
use crate::accel::Accel;
use crate::engines::scattering::delta_arrival_at;
use crate::geometry::{Ray, Vec3};
use crate::sampling::{orthonormal_basis, Pattern, Rng, Strata};
use crate::scene::sky::Sky;
use crate::scene::{Color, Scene};

/// Rays each patch sends towards the sky (point and direction stratified together).
pub const SKY_RAYS_PER_PATCH: u32 = 64;

/// Points of each patch from which each light without area is seen, one shadow ray each
/// (jittered). Under a point light 1.5 above a corner of a 2×2 floor, split as
/// `split_where_unevenly_lit` splits it, every patch is within 0.73% of its exact mean
/// with 64, 2.0% with 16 (tests/radiosity.rs).
pub const POINTS_PER_PATCH_FOR_LIGHTS_WITHOUT_AREA: u32 = 64;

/// Whether the scene has light for `reflected` to gather: a sky outside a fog (which is
/// infinite and hides it) or a light without area (refused in a fog: see `render`'s
/// `refuse_unrendered_media`).
pub fn any(scene: &Scene) -> bool {
    sky(scene).is_some() || !scene.delta_lights.is_empty()
}

fn sky(scene: &Scene) -> Option<&Sky> {
    scene.sky.as_ref().filter(|_| scene.fog.is_none())
}

/// The radiance each patch reflects of the lights that are not patches: albedo × the sky's
/// radiance averaged over the patch and the cosine-weighted hemisphere of its front side,
/// where an occlusion ray leaves the scene, plus albedo/π × the irradiance of the lights
/// without area averaged over the patch, where a shadow ray reaches them. Also returns the
/// rays cast. Exact for a uniform sky nothing hides.
pub fn reflected(
    scene: &Scene,
    accel: &dyn Accel,
    patches: &[Patch],
    seed: u64,
) -> (Vec<Color>, u64) {
    let reflected = patches
        .par_iter()
        .enumerate()
        .map(|(k, p)| {
            if p.area <= 0.0 || p.albedo.max_element() <= 0.0 {
                return (Color::ZERO, 0);
            }
            let (mut rays, mut weights) = (Vec::new(), Vec::new());
            let sky_rays = match sky(scene) {
                Some(sky) => rays_to_sky(scene, sky, p, (k, seed), (&mut rays, &mut weights)),
                None => 0,
            };
            rays_to_lights_without_area(scene, p, (k, seed), (&mut rays, &mut weights));
            let mut blocked = vec![false; rays.len()];
            accel.occluded_batch(&rays, &mut blocked);
            let seen = |range: std::ops::Range<usize>| -> Vec3 {
                (blocked[range.clone()].iter().zip(&weights[range]))
                    .filter(|(&b, _)| !b)
                    .map(|(_, &w)| w)
                    .sum()
            };
            let from_sky = p.albedo * seen(0..sky_rays) / SKY_RAYS_PER_PATCH as f32;
            let from_lights = p.albedo * seen(sky_rays..rays.len());
            (from_sky + from_lights, rays.len() as u64)
        })
        .collect::<Vec<_>>();
    let rays = reflected.iter().map(|r| r.1).sum();
    (reflected.into_iter().map(|r| r.0).collect(), rays)
}

/// Adds patch `p`'s rays towards the sky, each with the radiance it brings if unblocked ×
/// its weight, (cos/π)/density (1 for the cosine's directions); returns how many.
fn rays_to_sky(
    scene: &Scene,
    sky: &Sky,
    p: &Patch,
    (k, seed): (usize, u64),
    (rays, weights): (&mut Vec<Ray>, &mut Vec<Color>),
) -> usize {
    let strata = Strata::new(Pattern::Jittered, SKY_RAYS_PER_PATCH);
    let mut rng = Rng::new(seed ^ 0x5c1e_5c1e, k as u64, 0);
    // The directions' strata are shuffled against the points' so that point and direction
    // are independent.
    let shift = (rng.next_u64() % SKY_RAYS_PER_PATCH as u64) as u32;
    let (t, b) = orthonormal_basis(p.normal);
    let start = rays.len();
    for i in 0..SKY_RAYS_PER_PATCH {
        let (s, q) = strata.sample(i, &mut rng);
        let (u, v) = strata.sample((i + shift) % SKY_RAYS_PER_PATCH, &mut rng);
        let (dir, weight) = match sky.map() {
            // A map by its importance (a bright sun would rarely be met by the cosine's
            // directions).
            Some(map) => match map.sample_above(p.normal, u, v) {
                Some(sample) => sample,
                None => continue,
            },
            None => {
                // Cosine-weighted: uniform on the disk, lifted. By radius and angle, not by
                // `sky_lighting_sample`'s concentric disk: u's strata are then bands of
                // elevation, where a sky's gradient lies. The concentric map put the floor
                // under `tests/media.rs`' gradient sky 1.4% high with the 64 rays, this one 0.4%.
                let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
                let dir = t * (r * phi.cos())
                    + b * (r * phi.sin())
                    + p.normal * (1.0 - u).max(0.0).sqrt();
                (dir, 1.0)
            }
        };
        let origin = on_primitive(scene, p, p.point(s, q), dir);
        rays.push(Ray::new(origin, dir));
        weights.push(sky.radiance(dir.normalize_or_zero()) * weight);
    }
    rays.len() - start
}

/// Adds patch `p`'s shadow rays towards each light without area, each with the irradiance
/// it brings if unblocked / π, divided by the points.
fn rays_to_lights_without_area(
    scene: &Scene,
    p: &Patch,
    (k, seed): (usize, u64),
    (rays, weights): (&mut Vec<Ray>, &mut Vec<Color>),
) {
    if scene.delta_lights.is_empty() {
        return;
    }
    let points = POINTS_PER_PATCH_FOR_LIGHTS_WITHOUT_AREA;
    let strata = Strata::new(Pattern::Jittered, points);
    let mut rng = Rng::new(seed ^ 0xde17_a1a1, k as u64, 0);
    for i in 0..points {
        let (s, q) = strata.sample(i, &mut rng);
        let origin = on_primitive(scene, p, p.point(s, q), p.normal);
        for light in &scene.delta_lights {
            if let Some(a) = delta_arrival_at(scene, light, (origin, p.normal), origin) {
                rays.push(a.ray);
                weights.push(a.irradiance * (a.value(None) / points as f32));
            }
        }
    }
}

/// Rounds of `split_where_unevenly_lit`: a face becomes at most 4^6 = 4,096 patches, where a
/// shadow's edge crosses it.
pub const UNEVEN_LIGHT_ROUNDS: u32 = 6;

/// A face is lit unevenly where the lights without area give its corners and its centre
/// irradiances that range over more than this share of the largest of them, and over more
/// than `UNEVEN_LIGHT_FLOOR` of the largest anywhere in the scene.
const UNEVEN_LIGHT_SHARE: f32 = 0.2;
const UNEVEN_LIGHT_FLOOR: f32 = 0.01;

/// Splits the mesh's leaves in four where the lights without area light them unevenly, up to
/// `UNEVEN_LIGHT_ROUNDS` times; returns the faces split in each round (for a saved solution
/// to split them again).
pub fn split_where_unevenly_lit(
    scene: &Scene,
    accel: &dyn Accel,
    mesh: &mut QuadMesh,
) -> Vec<Vec<u32>> {
    let mut rounds = Vec::new();
    if scene.delta_lights.is_empty() {
        return rounds;
    }
    let mut largest = 0.0f32;
    // The leaves to look at: all of them, then only the children of those just split. A leaf
    // left whole keeps its range, and `largest` only grows, so it would stay whole.
    let mut new_leaves = mesh.leaves.clone();
    for _ in 0..UNEVEN_LIGHT_ROUNDS {
        let ranges: Vec<(f32, f32)> = new_leaves
            .par_iter()
            .map(|&face| irradiance_range(scene, accel, mesh, face))
            .collect();
        largest = ranges.iter().map(|r| r.1).fold(largest, f32::max);
        let split: Vec<u32> = (new_leaves.iter().zip(&ranges))
            .filter(|(_, &(low, high))| {
                high - low > UNEVEN_LIGHT_SHARE * high && high - low > UNEVEN_LIGHT_FLOOR * largest
            })
            .map(|(&face, _)| face)
            .collect();
        if split.is_empty() {
            break;
        }
        mesh.split_many(&split);
        new_leaves = (split.iter())
            .flat_map(|&f| {
                let first = mesh.faces[f as usize].children;
                first..first + 4
            })
            .collect();
        rounds.push(split);
    }
    rounds
}

/// The least and the largest luminance of the irradiance the lights without area give the
/// corners and the centre of a mesh face, seen from its front (the corners drawn in by a
/// thousandth towards the centre, so that a corner is not taken for its neighbour's).
fn irradiance_range(scene: &Scene, accel: &dyn Accel, mesh: &QuadMesh, face: u32) -> (f32, f32) {
    let f = &mesh.faces[face as usize];
    let corners = mesh.face_vertices(face);
    let (_, normal) = mesh.area_normal(face);
    let centre = corners.iter().copied().sum::<Vec3>() * 0.25;
    let points = corners
        .map(|c| c + (centre - c) * 1e-3)
        .into_iter()
        .chain([centre]);
    let (mut low, mut high) = (f32::INFINITY, 0.0f32);
    for x in points {
        let origin = on_surface(scene, (f.prim, f.part, normal), x, normal);
        let irradiance: f32 = (scene.delta_lights.iter())
            .filter_map(|light| delta_arrival_at(scene, light, (origin, normal), origin))
            .filter(|a| !accel.occluded(&a.ray))
            .map(|a| crate::color::luminance(a.irradiance) * a.cos)
            .sum();
        low = low.min(irradiance);
        high = high.max(irradiance);
    }
    (low, high)
}
