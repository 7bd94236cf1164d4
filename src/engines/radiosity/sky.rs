//! The sky as radiosity's light: each patch gathers the sky it sees before the solve — points
//! stratified over the patch, each with a direction stratified in the cosine about its normal
//! (by the map's importance for a `sky_texture`) and an occlusion ray through the Accel — and
//! reflects it as if it emitted it. The solvers then carry that light on between the patches
//! like any emitter's.

use rayon::prelude::*;

use super::patch::{on_primitive, Patch};
use crate::accel::Accel;
use crate::geometry::{Ray, Vec3};
use crate::sampling::{orthonormal_basis, Pattern, Rng, Strata};
use crate::scene::sky::Sky;
use crate::scene::{Color, Scene};

/// Rays each patch sends towards the sky (point and direction stratified together).
pub const SKY_RAYS_PER_PATCH: u32 = 64;

/// The radiance each patch reflects of the sky it sees: albedo × the sky's radiance averaged
/// over the patch and the cosine-weighted hemisphere of its front side, where an occlusion ray
/// leaves the scene. Also returns the rays cast. Exact for a uniform sky nothing hides.
pub fn reflected(
    scene: &Scene,
    accel: &dyn Accel,
    sky: &Sky,
    patches: &[Patch],
    seed: u64,
) -> (Vec<Color>, u64) {
    let strata = Strata::new(Pattern::Jittered, SKY_RAYS_PER_PATCH);
    let reflected = patches
        .par_iter()
        .enumerate()
        .map(|(k, p)| {
            if p.area <= 0.0 || p.albedo.max_element() <= 0.0 {
                return (Color::ZERO, 0);
            }
            let mut rng = Rng::new(seed ^ 0x5c1e_5c1e, k as u64, 0);
            // The directions' strata are shuffled against the points' so that point and
            // direction are independent.
            let shift = (rng.next_u64() % SKY_RAYS_PER_PATCH as u64) as u32;
            let (t, b) = orthonormal_basis(p.normal);
            let mut rays = Vec::with_capacity(SKY_RAYS_PER_PATCH as usize);
            // Each ray's weight: 1 for the cosine's directions, (cos/π)/density for a map's.
            let mut weights = Vec::with_capacity(SKY_RAYS_PER_PATCH as usize);
            for i in 0..SKY_RAYS_PER_PATCH {
                let (s, q) = strata.sample(i, &mut rng);
                let (u, v) = strata.sample((i + shift) % SKY_RAYS_PER_PATCH, &mut rng);
                let (dir, weight) = match sky.map() {
                    // A map by its importance (a bright sun would rarely be met by the
                    // cosine's directions).
                    Some(map) => match map.sample_above(p.normal, u, v) {
                        Some(sample) => sample,
                        None => continue,
                    },
                    None => {
                        // Cosine-weighted: uniform on the disk, lifted.
                        let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
                        let dir = t * (r * phi.cos())
                            + b * (r * phi.sin())
                            + p.normal * (1.0 - u).max(0.0).sqrt();
                        (dir, 1.0)
                    }
                };
                let origin = on_primitive(scene, p, p.point(s, q), dir);
                rays.push(Ray::new(origin, dir));
                weights.push(weight);
            }
            let mut blocked = vec![false; rays.len()];
            accel.occluded_batch(&rays, &mut blocked);
            let seen: Vec3 = rays
                .iter()
                .zip(&blocked)
                .zip(&weights)
                .filter(|((_, &b), _)| !b)
                .map(|((ray, _), &w)| sky.radiance(ray.direction.normalize_or_zero()) * w)
                .sum();
            (
                p.albedo * seen / SKY_RAYS_PER_PATCH as f32,
                rays.len() as u64,
            )
        })
        .collect::<Vec<_>>();
    let rays = reflected.iter().map(|r| r.1).sum();
    (reflected.into_iter().map(|r| r.0).collect(), rays)
}
