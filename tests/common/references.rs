//! What the radiosity tests measure solutions with: the hierarchical solver's settings, a
//! solve, the per-input-patch difference between two solutions, and path-traced references
//! per patch (the path tracer shares no code with the radiosity solvers after the hit).

use std::collections::HashMap;

use trilux::accel::{self, AccelOptions};
use trilux::engines::path::PathTracer;
use trilux::engines::radiosity::patch::Patch;
use trilux::engines::radiosity::{RadiositySettings, Solution, SolverKind};
use trilux::engines::RenderSettings;
use trilux::geometry::{Ray, Vec3};
use trilux::sampling::{PathSamples, Pattern, Rng, Strata};
use trilux::scene::Scene;

use super::backends;

/// The hierarchical solver to a tolerance of 1e-6, the input patches subdivided `subdivide`
/// times, every other setting the default.
pub fn hierarchical(subdivide: u32) -> RenderSettings {
    RenderSettings {
        radiosity: RadiositySettings {
            subdivide,
            solver: SolverKind::Hierarchical,
            tolerance: 1e-6,
            ..Default::default()
        },
        ..RenderSettings::default()
    }
}

pub fn solve(scene: &Scene, settings: &RenderSettings) -> Solution {
    let accel = accel::build(scene, backends()[0], &AccelOptions::default()).expect("builds");
    Solution::solve(scene, accel.as_ref(), settings, |_| {})
}

/// Area-weighted relative L1 difference of the reflected radiance (radiance − emitted,
/// channels summed) per patch of `solution` against `reference`, whose mesh may be finer (the
/// same mesh subdivided further: its patches are averaged over the patch of `solution` they
/// descend from), and the relative difference of the reflected power.
pub fn per_input_patch_difference(reference: &Solution, solution: &Solution) -> (f64, f64) {
    per_input_patch_difference_over(reference, solution, &vec![true; solution.patches.len()])
}

/// `per_input_patch_difference`, printed after the solver's report.
pub fn printed_difference(reference: &Solution, solution: &Solution) -> (f64, f64) {
    let (l1, power_error) = per_input_patch_difference(reference, solution);
    println!(
        "{}: relative L1 {:.3}%, reflected power {:+.3}%",
        solution.solver_report,
        100.0 * l1,
        100.0 * power_error
    );
    (l1, power_error)
}

/// `per_input_patch_difference` over the patches of `solution` that `counted` marks.
pub fn per_input_patch_difference_over(
    reference: &Solution,
    solution: &Solution,
    counted: &[bool],
) -> (f64, f64) {
    let patch_of_face: HashMap<u32, usize> = solution
        .patches
        .iter()
        .enumerate()
        .map(|(k, p)| (p.face, k))
        .collect();
    // Per patch of `solution`: the reference's area and reflected power over it.
    let mut reflected = vec![(0.0f64, 0.0f64); solution.patches.len()];
    for (p, b) in reference.patches.iter().zip(&reference.state.radiance) {
        let mut face = p.face;
        while !patch_of_face.contains_key(&face) {
            face = reference.mesh.faces[face as usize].parent;
        }
        let entry = &mut reflected[patch_of_face[&face]];
        entry.0 += p.area as f64;
        entry.1 += p.area as f64 * (*b - p.emitted).element_sum() as f64;
    }
    let (mut diff, mut sum, mut power_ref, mut power) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (((p, b), &(area, a)), _) in solution
        .patches
        .iter()
        .zip(&solution.state.radiance)
        .zip(&reflected)
        .zip(counted)
        .filter(|(_, &counted)| counted)
    {
        assert!(area > 0.0, "every patch is covered by the reference");
        let b = (*b - p.emitted).element_sum() as f64 * p.area as f64;
        diff += (a - b).abs();
        sum += a.abs();
        power_ref += a;
        power += b;
    }
    (diff / sum, power / power_ref - 1.0)
}

/// Per patch k of `solution`, the mean of `estimate(patch, point, rng)` over `samples[k]`
/// stratified points of it, each with random numbers from (seed, patch, sample).
pub fn patch_means(
    solution: &Solution,
    samples: &[u32],
    seed: u64,
    estimate: impl Fn(&Patch, Vec3, &mut Rng) -> Vec3 + Sync,
) -> Vec<Vec3> {
    use rayon::prelude::*;
    solution
        .patches
        .par_iter()
        .enumerate()
        .map(|(k, p)| {
            let n = samples[k];
            let strata = Strata::new(Pattern::Jittered, n);
            let mut sum = Vec3::ZERO;
            for i in 0..n {
                let mut rng = Rng::new(seed, k as u64, i as u64);
                let (s, t) = strata.sample(i, &mut rng);
                sum += estimate(p, p.point(s, t), &mut rng);
            }
            sum / n as f32
        })
        .collect()
}

/// Per patch of `solution`, the radiance leaving it estimated by the path tracer on the
/// scene's diffuse part (`diffuse_only`): `paths[k]` paths ending at stratified points of
/// patch k, each along the ray that arrives at the point straight onto its front (the
/// surfaces are then diffuse, so any direction would do).
pub fn path_traced_patches(
    scene: &Scene,
    solution: &Solution,
    paths: &[u32],
    seed: u64,
) -> Vec<Vec3> {
    let scene = &diffuse_only(scene);
    let accel = accel::build(scene, backends()[0], &AccelOptions::default()).expect("builds");
    let tracer = PathTracer::new(scene, accel.as_ref());
    let step = arrival_step(scene);
    patch_means(solution, paths, seed, |p, x, rng| {
        // The sample's generator, not used after this: its numbers drive the path.
        tracer.along(
            &arriving(p, x, step),
            &mut PathSamples::independent(rng.clone()),
        )
    })
}

/// `scene` with the specular parts of its materials (mirror and glossy reflection,
/// transmission) taken out. Radiosity models only the diffuse part (mgf.md), so that is what
/// its reference traces: with them, office3's path-traced patches took in its lamp shades'
/// mirror term (`rs 0.1`, seen straight along the normal, towards the bulb) and the light
/// through its window glass (`ts 0.88`): its reflected power came out 3.4% above the diffuse
/// scene's, its lamp shades' insides 26%.
pub fn diffuse_only(scene: &Scene) -> Scene {
    let mut scene = scene.clone();
    for m in &mut scene.materials {
        m.reflective = Vec3::ZERO;
        m.transmitted = Vec3::ZERO;
    }
    scene
}

/// How far in front of a patch `path_traced_patches`' rays start: a ten-thousandth of the
/// scene's diagonal.
pub fn arrival_step(scene: &Scene) -> f32 {
    1e-4 * scene.bounds().extent().length()
}

/// The ray `path_traced_patches` follows to point `x` of patch `p`: from `step` in front of
/// it, straight onto its front.
pub fn arriving(p: &Patch, x: Vec3, step: f32) -> Ray {
    Ray::new(x + p.normal * step, -p.normal)
}

/// Per patch of `solution`, whether the rays `path_traced_patches` sends to it land on it at
/// least half the time: a patch lying under a coplanar one (office3's walls overlap) is not
/// what those rays measure, so the path-traced reference says nothing of it.
pub fn seen_by_the_reference(scene: &Scene, solution: &Solution, paths: &[u32]) -> Vec<bool> {
    let accel = accel::build(scene, backends()[0], &AccelOptions::default()).expect("builds");
    let step = arrival_step(scene);
    let landed = patch_means(solution, paths, 5, |p, x, _| {
        let hit = accel::closest_surface(accel.as_ref(), scene, &arriving(p, x, step));
        Vec3::splat(hit.is_some_and(|h| h.prim == p.prim && h.part == p.part) as u32 as f32)
    });
    landed.iter().map(|l| l.x >= 0.5).collect()
}
