//! The hierarchical radiosity solver against what it did not produce: the furnace (a closed
//! cube of albedo ρ emitting radiance 1 reaches 1/(1 − ρ) everywhere) and the progressive
//! solver on the course's Cornell box.

mod common;

use common::{backends, furnace, own_scene, worst_relative_error};
use trilux::accel::{self, AccelOptions};
use trilux::engines::radiosity::{RadiositySettings, Solution, SolverKind};
use trilux::engines::RenderSettings;
use trilux::scene::Scene;

fn hierarchical(subdivide: u32) -> RenderSettings {
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

fn solve(scene: &Scene, settings: &RenderSettings) -> Solution {
    let accel = accel::build(scene, backends()[0], &AccelOptions::default()).expect("builds");
    Solution::solve(scene, accel.as_ref(), settings, |_| {})
}

/// Every input patch of the closed cube within 0.5% of 1/(1 − ρ) for ρ = 0.5, 0.9, 0.99: the
/// links neither lose nor create light. (Without the solver's leaf scales, leaves near the
/// cube's edges summed their form factors to between 0.91 and 1.5, and ρ = 0.9 gave 2.3%.)
#[test]
fn furnace_through_the_hierarchy() {
    for rho in [0.5f32, 0.9, 0.99] {
        let scene = furnace(rho);
        let mut settings = hierarchical(1);
        // Coarser than the default: refining by B·F·A splits ever more as B grows towards
        // 1/(1 − ρ), which the furnace does not need and the test's time would not bear.
        settings.radiosity.link_error = 1e-3;
        let solution = solve(&scene, &settings);
        let truth = 1.0 / (1.0 - rho);
        let worst = worst_relative_error(&solution.state.radiance, truth);
        println!(
            "ρ = {rho}: {}, {} sweeps, stop {:?}, worst error {:.4}%",
            solution.solver_report,
            solution.state.iterations,
            solution.stop,
            100.0 * worst
        );
        assert!(worst < 5e-3, "ρ = {rho}: worst error {worst}");
    }
}

/// The Cornell box of scenes/ (with the diffuse sphere, so visibility matters): per input
/// patch, the hierarchical solution against the progressive solver's converged one.
#[test]
fn cornell_box_agrees_with_the_progressive_solver() {
    let scene = own_scene("cornell_box_diffuse_sphere.obj");
    let mut progressive = hierarchical(2);
    progressive.radiosity.solver = SolverKind::Progressive;
    progressive.num_shadow_samples = 1;
    let mut hier = hierarchical(2);
    hier.num_shadow_samples = 1;
    let reference = solve(&scene, &progressive);
    let solution = solve(&scene, &hier);
    let (mut diff, mut sum, mut power_ref, mut power) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for ((p, a), b) in reference
        .patches
        .iter()
        .zip(&reference.state.radiance)
        .zip(&solution.state.radiance)
    {
        let (a, b) = (
            (a - p.emitted).element_sum() as f64,
            (b - p.emitted).element_sum() as f64,
        );
        diff += p.area as f64 * (a - b).abs();
        sum += p.area as f64 * a.abs();
        power_ref += p.area as f64 * a;
        power += p.area as f64 * b;
    }
    let (l1, power_error) = (diff / sum, power / power_ref - 1.0);
    println!(
        "{}: relative L1 {:.3}%, reflected power {:+.3}%",
        solution.solver_report,
        100.0 * l1,
        100.0 * power_error
    );
    // Issue #15's aims; measured 1.72% and +0.08% (the reference takes one point per form
    // factor, so part of the difference is its own).
    assert!(l1 < 0.02, "relative L1 {l1}");
    assert!(power_error.abs() < 0.01, "reflected power {power_error}");
}

/// Embree and the BVH answer every visibility ray alike, so the solutions are identical.
#[test]
fn both_accels_give_the_same_hierarchical_solution() {
    let scene = own_scene("cornell_box_diffuse_sphere.obj");
    let mut settings = hierarchical(1);
    settings.num_shadow_samples = 1;
    let solutions: Vec<Vec<_>> = backends()
        .into_iter()
        .map(|kind| {
            let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
            Solution::solve(&scene, accel.as_ref(), &settings, |_| {})
                .state
                .radiance
        })
        .collect();
    for s in &solutions[1..] {
        assert_eq!(s, &solutions[0]);
    }
}
