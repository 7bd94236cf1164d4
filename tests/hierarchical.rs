//! The hierarchical radiosity solver against what it did not produce: the furnace (a closed
//! cube of albedo ρ emitting radiance 1 reaches 1/(1 − ρ) everywhere) and the progressive
//! solver on the course's Cornell box.

mod common;

use common::references::{
    hierarchical, patch_means, path_traced_patches, per_input_patch_difference, printed_difference,
    solve,
};
use common::{backends, furnace, own_scene, worst_relative_error};
use trilux::accel::{self, AccelOptions};
use trilux::engines::radiosity::mesh::NONE;
use trilux::engines::radiosity::{RadiositySettings, Solution, SolverKind};
use trilux::engines::scattering::diffuse_sample;
use trilux::geometry::{Ray, Vec3};
use trilux::scene::Scene;

/// Every input patch of the closed cube within 0.01% of 1/(1 − ρ) for ρ = 0.5, 0.9, 0.99: the
/// links neither lose nor create light, whether linking starts from every pair of patches or
/// from the root cluster linked to itself (so that cluster links carry the first bounces).
/// Measured worst: 0.0011% (ρ = 0.99, the sweeps' stopping rule); the bound is nine times
/// that. (Without the solver's leaf scales, leaves near the cube's edges summed their form
/// factors to between 0.91 and 1.5, and ρ = 0.9 gave 2.3%.)
#[test]
fn furnace_through_the_hierarchy() {
    for cluster_above in [RadiositySettings::default().cluster_above, 0] {
        for rho in [0.5f32, 0.9, 0.99] {
            let scene = furnace(rho);
            let mut settings = hierarchical(1);
            // Coarser than the default: refining by B·F·A splits ever more as B grows
            // towards 1/(1 − ρ), which the furnace does not need and the test's time would
            // not bear.
            settings.radiosity.link_error = 1e-3;
            settings.radiosity.cluster_above = cluster_above;
            let solution = solve(&scene, &settings);
            let truth = 1.0 / (1.0 - rho);
            let worst = worst_relative_error(&solution.state.radiance, truth);
            println!(
                "ρ = {rho}, clusters above {cluster_above} patches: {}, stop {:?}, worst error {:.4}%",
                solution.solver_report,
                solution.stop,
                100.0 * worst
            );
            assert!(worst < 1e-4, "ρ = {rho}: worst error {worst}");
        }
    }
}

/// A closed corridor 1 × 1 × `length` in MGF, every face of albedo ρ (`rd`) emitting radiance
/// 1 (`ed` 183.07 π), its four long walls split into unit squares: far enough apart for
/// clusters at its ends to be linked as clusters.
fn furnace_corridor_mgf(rho: f32, length: usize) -> Scene {
    let mut text = format!("m wall =\n c\n  cxy 0.333333 0.333333\n rd {rho}\n ed 575.13\n");
    let mut count = 0;
    // A face from four corners, wound so that its normal points along `inward`.
    let mut face = |corners: [[f32; 3]; 4], inward: [f32; 3]| {
        let [a, b, c, _] = corners.map(trilux::geometry::Vec3::from_array);
        let mut corners = corners.to_vec();
        if (b - a).cross(c - b).dot(inward.into()) < 0.0 {
            corners.reverse();
        }
        let mut names = Vec::new();
        for [x, y, z] in corners {
            count += 1;
            text += &format!("v c{count} =\n p {x} {y} {z}\n");
            names.push(format!("c{count}"));
        }
        text += &format!("f {}\n", names.join(" "));
    };
    for i in 0..length {
        let (x0, x1) = (i as f32, i as f32 + 1.0);
        face(
            [[x0, 0., 0.], [x1, 0., 0.], [x1, 1., 0.], [x0, 1., 0.]],
            [0., 0., 1.],
        );
        face(
            [[x0, 0., 1.], [x1, 0., 1.], [x1, 1., 1.], [x0, 1., 1.]],
            [0., 0., -1.],
        );
        face(
            [[x0, 0., 0.], [x1, 0., 0.], [x1, 0., 1.], [x0, 0., 1.]],
            [0., 1., 0.],
        );
        face(
            [[x0, 1., 0.], [x1, 1., 0.], [x1, 1., 1.], [x0, 1., 1.]],
            [0., -1., 0.],
        );
    }
    let l = length as f32;
    face(
        [[0., 0., 0.], [0., 1., 0.], [0., 1., 1.], [0., 0., 1.]],
        [1., 0., 0.],
    );
    face(
        [[l, 0., 0.], [l, 1., 0.], [l, 1., 1.], [l, 0., 1.]],
        [-1., 0., 0.],
    );
    let dir = std::env::temp_dir().join(format!("trilux-furnace-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("corridor-{rho}.mgf"));
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).expect("the corridor loads");
    std::fs::remove_file(&path).ok();
    scene
}

/// The MGF corridor furnace from the root cluster: links with a cluster at an end carry part
/// of the light (asserted), and still every patch is within 0.5% of Le/(1 − ρ), per channel.
/// Measured worst: 0.045%, 0.10% and 0.059% for ρ = 0.5, 0.9, 0.99 (a cluster link spreads
/// its light by the cluster's mean, not per patch; 0.19%, 0.17%, 0.085% when the bound was
/// set); the bound is 5 times the worst.
#[test]
fn furnace_through_the_clusters() {
    for rho in [0.5f32, 0.9, 0.99] {
        let scene = furnace_corridor_mgf(rho, 12);
        let mut settings = hierarchical(0);
        settings.radiosity.link_error = 1e-3;
        settings.radiosity.cluster_above = 0;
        let solution = solve(&scene, &settings);
        let mut worst = 0.0f32;
        for (p, b) in solution.patches.iter().zip(&solution.state.radiance) {
            let truth = p.emitted / (trilux::geometry::Vec3::ONE - p.albedo);
            worst = worst.max(((*b - truth) / truth).abs().max_element());
        }
        let report = &solution.solver_report;
        println!("ρ = {rho}: {report}, worst error {:.4}%", 100.0 * worst);
        let clustered: usize = report
            .split(" links (")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|n| n.parse().ok())
            .expect("the report counts the links with a cluster at an end");
        assert!(clustered > 0, "no cluster link survived: {report}");
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
    let (l1, power_error) = printed_difference(&reference, &solution);
    // Bounds 2% and 1%; measured 1.72% and +0.54% (the reference takes one point
    // per form factor, so part of the difference is its own).
    assert!(l1 < 0.02, "relative L1 {l1}");
    assert!(power_error.abs() < 0.01, "reflected power {power_error}");
}

/// The Cornell box as MGF (scenes/cornell_box.mgf: 16 input patches), solved hierarchically
/// from every pair of patches and from the root cluster, against two references it did not
/// produce: the path tracer averaged per input patch (65,536 paths a patch), and the
/// progressive solver on the mesh subdivided four times (4,096 patches) converged to 1e-5,
/// averaged per input patch. The references agree with each other first.
#[test]
fn cornell_box_mgf_agrees_with_path_traced_and_fine_progressive_references() {
    let scene = own_scene("cornell_box.mgf");
    let mut progressive = hierarchical(4);
    progressive.radiosity.solver = SolverKind::Progressive;
    progressive.radiosity.tolerance = 1e-5;
    progressive.num_shadow_samples = 1;
    let fine = solve(&scene, &progressive);
    let mut traced = solve(&scene, &hierarchical(0));
    traced.state.radiance =
        path_traced_patches(&scene, &traced, &vec![1 << 16; traced.patches.len()], 7);
    let (l1, power_error) = per_input_patch_difference(&fine, &traced);
    println!(
        "path tracer against the fine progressive: relative L1 {:.3}%, reflected power {:+.3}%",
        100.0 * l1,
        100.0 * power_error
    );
    // Measured 0.30% / -0.05% (0.51% / +0.32% while the form factor's clip dropped
    // crossings); the bounds are twice the earlier figures (the path tracer's own noise per
    // patch is about 0.1–1%).
    assert!(l1 < 0.01, "references disagree: relative L1 {l1}");
    assert!(
        power_error.abs() < 0.0065,
        "references disagree: power {power_error}"
    );
    for cluster_above in [RadiositySettings::default().cluster_above, 0] {
        let mut hier = hierarchical(0);
        hier.num_shadow_samples = 1;
        hier.radiosity.cluster_above = cluster_above;
        let solution = solve(&scene, &hier);
        for (name, reference) in [("path tracer", &traced), ("fine progressive", &fine)] {
            let (l1, power_error) = per_input_patch_difference(reference, &solution);
            println!(
                "clusters above {cluster_above} patches: {}: against the {name}: relative L1 \
                 {:.3}%, reflected power {:+.3}%",
                solution.solver_report,
                100.0 * l1,
                100.0 * power_error
            );
            // Measured (pairs, root cluster): against the path tracer 0.91% / +0.14% and
            // 0.92% / +0.13%, against the fine progressive 1.02% / +0.09% and 1.04% / +0.08%
            // (0.90%, 0.92%, 1.01%, 1.03% while each link's visibility multiplied its mean
            // form factor and every leaf was taken at its centre). The L1 bound is the worst of those and two fifths (the references are 0.30%
            // apart), the power bound 1%. Two faults these bounds catch: a link none of whose
            // four point pairs saw its source dropped instead of refined (-2.0% power), and a
            // form factor's clip losing crossings or leaf scales not weighted by the light each
            // link carries (1.54% L1).
            assert!(l1 < 0.015, "{name}: relative L1 {l1}");
            assert!(
                power_error.abs() < 0.01,
                "{name}: reflected power {power_error}"
            );
        }
    }
}

/// The light straight from the lamp, through the clusters: the Cornell MGF's patches split
/// 8×8 (1,024) with every albedo a thousandth, so that each patch shows the light that
/// reaches it straight from the lamp, solved from the root cluster, against the path tracer
/// averaged per patch (1,024 paths each).
#[test]
fn direct_light_through_the_clusters_matches_the_rays() {
    let mut scene = own_scene("cornell_box.mgf");
    for m in &mut scene.materials {
        m.diffuse *= 1e-3;
    }
    let mut settings = hierarchical(3);
    settings.num_shadow_samples = 1;
    settings.radiosity.cluster_above = 0;
    let solution = solve(&scene, &settings);
    let mut traced = solution.clone();
    traced.state.radiance =
        path_traced_patches(&scene, &solution, &vec![1 << 10; solution.patches.len()], 7);
    let (l1, power_error) = printed_difference(&traced, &solution);
    // Measured 2.71% / -1.99% (3.00% / -2.34% while a cluster's points were drawn among all
    // its patches until one faced the other end); 11.0% / -10.9% while a cluster holding
    // the lamp sent its light as one and clusters sent their patches' mean whichever way
    // they faced. The bounds are the measured figures and a half.
    assert!(l1 < 0.045, "relative L1 {l1}");
    assert!(power_error.abs() < 0.035, "reflected power {power_error}");
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

/// The leaf elements a hierarchical solution shows and exports: the leaf `leaf_at` finds
/// for a patch's point (s, t) holds that very point at the parameters it returns; each
/// patch's radiance is the area mean of its leaves'; the PLY export writes one face per
/// leaf.
#[test]
fn leaf_elements_tile_their_patches() {
    let scene = own_scene("cornell_box.mgf");
    let mut settings = hierarchical(0);
    settings.num_shadow_samples = 1;
    let solution = solve(&scene, &settings);
    let elements = &solution.state.elements;
    assert!(
        elements.len() > 10 * solution.patches.len(),
        "the patches were split"
    );
    let bilinear = |c: &[Vec3; 4], s: f32, t: f32| {
        (c[0] * (1.0 - s) + c[1] * s) * (1.0 - t) + (c[3] * (1.0 - s) + c[2] * s) * t
    };
    let mut leaves = 0;
    for (k, p) in solution.patches.iter().enumerate() {
        for i in 0..50 {
            let (s, t) = ((i % 7) as f32 / 6.5 + 0.01, (i / 7) as f32 / 7.5 + 0.02);
            let (e, u, v) = solution.state.leaf_at(k, s, t);
            assert_eq!(elements[e].children, NONE, "a leaf");
            let (want, got) = (
                bilinear(&p.corners, s, t),
                bilinear(&elements[e].corners, u, v),
            );
            assert!(
                (want - got).length() < 1e-5,
                "patch {k} at ({s}, {t}): {want} vs {got}"
            );
        }
        // Area mean of the leaves below patch k.
        let (mut sum, mut area) = (Vec3::ZERO, 0.0f32);
        let mut stack = vec![k];
        while let Some(e) = stack.pop() {
            let el = &elements[e];
            if el.children == NONE {
                let c = el.corners;
                let a = 0.5 * (c[2] - c[0]).cross(c[3] - c[1]).length();
                sum += el.radiance * a;
                area += a;
                leaves += 1;
            } else {
                stack.extend((0..4).map(|q| el.children as usize + q));
            }
        }
        let mean = sum / area;
        let b = solution.state.radiance[k];
        assert!(
            (mean - b).abs().max_element() <= 1e-4 * b.max_element().max(1e-3),
            "patch {k}: leaves' mean {mean} vs {b}"
        );
    }
    let path = std::env::temp_dir().join(format!("trilux-leaves-{}.ply", std::process::id()));
    solution.write_ply(&path).expect("writes");
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).ok();
    let header = String::from_utf8_lossy(&bytes[..400.min(bytes.len())]).to_string();
    assert!(
        header.contains(&format!("element face {leaves}\n")),
        "{header}"
    );
}

/// A memory budget stops the refinement (with a warning) instead of growing past it, and the
/// solution still conserves light: the closed cube's furnace stays exact to f32 rounding.
#[test]
fn a_memory_budget_stops_the_refinement() {
    let scene = furnace(0.5);
    let mut settings = hierarchical(1);
    settings.radiosity.link_error = 1e-3;
    let free = solve(&scene, &settings);
    let budget = 200_000;
    settings.radiosity.memory_budget = budget;
    let capped = solve(&scene, &settings);
    let count = |s: &Solution, name: &str| {
        s.solver_counters
            .iter()
            .find(|(n, _)| *n == name)
            .map(|c| c.1)
            .expect("counted")
    };
    println!(
        "links {} free, {} within {budget} bytes; {:?}",
        count(&free, "links"),
        count(&capped, "links"),
        capped.solver_warning
    );
    assert!(free.solver_warning.is_none());
    assert!(capped.solver_warning.is_some());
    assert!(count(&capped, "link bytes") <= budget);
    assert!(count(&capped, "links") < count(&free, "links"));
    let worst = worst_relative_error(&capped.state.radiance, 2.0);
    println!("capped furnace: worst error {worst:.2e}");
    // Light is conserved however coarse the links: measured 4.8e-7 (four f32 roundings of
    // 2.0); the bound is eight times that.
    assert!(worst < 4e-6, "worst error {worst}");
}

/// The MGF corridor with nothing emitting (its walls' `ed` removed): every patch is dark, and
/// the solver says nothing emits without refining a link or sweeping (its rule splits links
/// whose error passes a fraction of the brightest emitter's power, 0 here: the hospital's
/// 7,632-patch coat rack took 15.5 million links and 28 s for a black image).
#[test]
fn nothing_emitting_is_dark_without_refinement() {
    let lit = furnace_corridor_mgf(0.5, 8);
    let mut scene = lit.clone();
    for m in &mut scene.materials {
        m.emitted = Vec3::ZERO;
    }
    let solution = solve(&scene, &hierarchical(1));
    assert_eq!(
        solution.stop,
        trilux::engines::radiosity::solver::Stop::NoLight
    );
    assert!(solution.state.radiance.iter().all(|c| *c == Vec3::ZERO));
    assert!(
        solution.solver_counters.iter().all(|(_, n)| *n == 0),
        "{:?}",
        solution.solver_counters
    );
}

/// Two rooms sharing one wall, with `--two-sided` (every quad has a patch on each side): the
/// left room is a furnace (every face albedo ρ, emitting 1 from both sides), the right
/// room's other faces are black. The closed forms hold side by side: 1/(1 − ρ) on every
/// side facing into the left room; elsewhere nothing a side sees reflects, so it shows its
/// own emission — 1 on the shared wall's right side and the left room's outsides, 0 on the
/// black faces; and a ray finds the side it looks at. (With one patch for both sides, the
/// wall's right side showed the left's 1/(1 − ρ).)
#[test]
fn two_sided_walls_have_a_patch_on_each_side() {
    let rho = 0.5f32;
    let text = format!(
        "material\ndiffuse {rho} {rho} {rho}\nemitted 1 1 1\nmaterial\ndiffuse 0 0 0\n\
         v -1 -1 -1\nv 1 -1 -1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\n\
         v 3 -1 -1\nv 3 1 -1\nv 3 -1 1\nv 3 1 1\n\
         m 0\nf 5 7 8 6\nf 1 2 4 3\nf 3 4 8 7\nf 1 5 6 2\nf 1 3 7 5\nf 2 6 8 4\n\
         m 1\nf 9 11 12 10\nf 2 6 11 9\nf 4 10 12 8\nf 2 9 10 4\nf 6 8 12 11\n\
         background_color 0 0 0\n\
         PerspectiveCamera {{\ncamera_position 0 0 0\npoint_of_interest 1 0 0\nup 0 1 0\nangle 1\n}}\n"
    );
    let mut scene = Scene::parse_dialect(std::path::Path::new("rooms.obj"), &text).unwrap();
    scene.two_sided_quads = true;
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let furnace = 1.0 / (1.0 - rho);
    for solver in [SolverKind::Progressive, SolverKind::Hierarchical] {
        let mut settings = hierarchical(1);
        settings.radiosity.solver = solver;
        settings.radiosity.link_error = 1e-3;
        settings.num_shadow_samples = 1;
        let solution = Solution::solve(&scene, accel.as_ref(), &settings, |_| {});
        // 11 quads with their backs, each split in four.
        assert_eq!(solution.patches.len(), 4 * 22, "{solver}");
        let (mut wall_backs, mut worst) = (0, 0.0f32);
        for (p, l) in solution.patches.iter().zip(&solution.state.radiance) {
            let ahead = p.centre + p.normal * 0.01;
            let inside = ahead.y.abs() < 1.0 && ahead.z.abs() < 1.0;
            let truth = if inside && ahead.x.abs() < 1.0 {
                furnace
            } else {
                wall_backs += (inside && p.centre.x == 1.0) as usize;
                p.emitted.x
            };
            let error = (l.max_element() - truth)
                .abs()
                .max((l.min_element() - truth).abs());
            worst = worst.max(error / truth.max(1.0));
            // Measured worst 9.5e-7 (progressive) and 3.0e-7 (hierarchical), f32 rounding
            // of sums of exact terms: nothing a side sees is wrong, so nothing drifts. The
            // bound is ten times the worst.
            assert!(
                error <= 1e-5 * truth.max(1.0),
                "{solver}: patch at {:?} facing {:?} has {l:?}, not {truth}",
                p.centre,
                p.normal
            );
        }
        println!("{solver}: worst patch {worst:.2e}");
        assert_eq!(wall_backs, 4, "{solver}");
        let field = solution.field(solution.display_radiance(), false);
        for (from, dir, truth) in [(-0.5f32, 1.0f32, furnace), (2.5, -1.0, 1.0)] {
            let ray = Ray::new(Vec3::new(from, 0.1, 0.2), Vec3::new(dir, 0.0, 0.0));
            let hit = accel::closest_surface(accel.as_ref(), &scene, &ray).expect("the wall");
            let seen = solution
                .sample(&scene, &hit, -ray.direction, &field)
                .unwrap();
            assert!(
                (seen.x - truth).abs() < 1e-5 * truth,
                "{solver}: looking along x = {dir} at the wall shows {seen:?}, not {truth}"
            );
        }
    }
}

/// The analytic form factors between unit squares, through the hierarchy: a square
/// emitting radiance 1 (albedo 0) and a receiving square of albedo ρ = 0.5, nothing else, so
/// the receiver's radiance is exactly ρ·F. Linked as one pair of patches and refined by the
/// oracle, the receiver's area mean over its leaves gives F within 1%.
#[test]
fn one_refined_link_reproduces_analytic_form_factors() {
    let pair = |source: &str, receiver: &str| {
        let text = format!(
            "material\ndiffuse 0 0 0\nemitted 1 1 1\nmaterial\ndiffuse 0.5 0.5 0.5\n\
             v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
             v 0 0 0.5\nv 1 0 0.5\nv 1 1 0.5\nv 0 1 0.5\nv 0 0 2\nv 1 0 2\nv 1 1 2\nv 0 1 2\n\
             v 1 0 1\nv 0 0 1\n\
             m 0\n{source}\nm 1\n{receiver}\n"
        );
        Scene::parse_dialect(std::path::Path::new("pair.obj"), &text).unwrap()
    };
    // Form factors from Howell's catalogue (as in tests/radiosity.rs).
    let cases = [
        ("opposed d=1", pair("f 1 2 3 4", "f 5 8 7 6"), 0.199825),
        ("opposed d=0.5", pair("f 1 2 3 4", "f 9 12 11 10"), 0.415253),
        ("opposed d=2", pair("f 1 2 3 4", "f 13 16 15 14"), 0.068590),
        ("perpendicular", pair("f 1 2 3 4", "f 1 18 17 2"), 0.200044),
    ];
    for (name, scene, truth) in cases {
        let mut settings = hierarchical(0);
        settings.num_shadow_samples = 1;
        let solution = solve(&scene, &settings);
        let f = solution.state.radiance[1].x as f64 / 0.5;
        println!(
            "{name}: {}: F = {f:.6} (exact {truth})",
            solution.solver_report
        );
        // 1% (the link error refines until the oracle's estimate is within it);
        // measured +0.24%, +0.42%, +0.40% and −0.05% in the order above.
        assert!((f / truth - 1.0).abs() < 0.01, "{name}: {f} vs {truth}");
    }
}

/// The Cornell MGF made a measure of form factors: every face white of albedo 0.001, the
/// faces `lit` picks emitting radiance 1 (`ed` 575.13, as mgf.md converts), the others none,
/// and only the faces `kept` picks. A patch's radiance less its own emission, over 0.001, is
/// then what its form factors (visibility included) to the lit faces sum to, up to 0.1%.
fn cornell_mgf_lit(lit: impl Fn(usize) -> bool, kept: impl Fn(usize) -> bool) -> String {
    let text = std::fs::read_to_string(common::own_scene_dir().join("cornell_box.mgf")).unwrap();
    let mut out = String::new();
    for (name, ed) in [("dark", ""), ("lit", "\n ed 575.13")] {
        out += &format!("m {name} =\n c\n  cxy 0.333333 0.333333\n rd 0.001{ed}\n");
    }
    let mut face = 0;
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let t = line.trim_start();
        if t.starts_with("m ") {
            // The scene's own materials, defined (with their indented lines) or used.
            while lines.peek().is_some_and(|l| l.starts_with(' ')) {
                lines.next();
            }
            continue;
        }
        if t.starts_with("f ") {
            face += 1;
            if !kept(face - 1) {
                continue;
            }
            out += if lit(face - 1) { "m lit\n" } else { "m dark\n" };
        }
        out += line;
        out += "\n";
    }
    out
}

/// Solves an MGF text hierarchically (four point pairs, one shadow sample) and measures,
/// per patch, the fraction of `rays` cosine-distributed rays from stratified points of it
/// whose first hit `counts` (the hit's primitive index).
fn solve_and_cast(
    text: &str,
    name: &str,
    rays: u32,
    counts: impl Fn(u32) -> bool + Sync,
) -> (Solution, Vec<f64>) {
    let dir = std::env::temp_dir().join(format!("trilux-form-factors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.mgf"));
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).expect("the variant loads");
    std::fs::remove_file(&path).ok();
    let mut settings = hierarchical(0);
    settings.num_shadow_samples = 1;
    let solution = solve(&scene, &settings);
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).unwrap();
    let fractions = patch_means(
        &solution,
        &vec![rays; solution.patches.len()],
        3,
        |p, x, rng| {
            let (dir, _) = diffuse_sample(p.normal, rng.next_f32(), rng.next_f32());
            let ray = Ray::new(x + p.normal * 1e-5, dir);
            let hit = accel::closest_surface(accel.as_ref(), &scene, &ray);
            Vec3::splat(hit.is_some_and(|h| counts(h.prim.index)) as u32 as f32)
        },
    );
    (solution, fractions.iter().map(|f| f.x as f64).collect())
}

/// The Cornell MGF with every face lit: (B − 1)/0.001 is each patch's coverage, the sum of
/// its form factors, against the fraction of cosine rays from the patch that hit anything
/// (2^16 a patch), which is what coverage is.
/// Without the blocks every patch is within 1% (measured: worst 0.52%; the progressive
/// solver on the mesh as given is 1.9% under on the floor). With them the room's six faces
/// are within 1% too (measured: worst 0.29%), and the blocks' faces within 1.5%
/// (measured: worst 1.20%, the short block's side facing the tall one). This test found two
/// bugs: links whose four point pairs all missed their source were dropped instead of
/// refined (the floor −8.5%, falling with refinement), and the form factor's clip dropped
/// about half the crossings of polygons straddling the receiver's plane (the blocks' faces,
/// which see the floor run on under the other block, up to 10.1% short).
#[test]
fn form_factor_sums_match_the_coverage_rays_measure() {
    // Faces 6–15 are the blocks.
    for (name, faces, bound) in [("empty", 6, 0.01f64), ("blocks", 16, 0.015)] {
        let text = cornell_mgf_lit(|_| true, |f| f < faces);
        let (solution, hit_fractions) = solve_and_cast(&text, name, 1 << 16, |_| true);
        let (mut worst, mut worst_room) = (0.0f64, 0.0f64);
        for (k, &truth) in hit_fractions.iter().enumerate() {
            let coverage = (solution.state.radiance[k].x as f64 - 1.0) / 0.001;
            println!("{name}: patch {k}: coverage {coverage:.4}, rays {truth:.4}");
            let error = (coverage / truth - 1.0).abs();
            worst = worst.max(error);
            // The first six faces are the room's walls and its light.
            if k < 6 {
                worst_room = worst_room.max(error);
            }
        }
        println!(
            "{name}: worst {:.2}%, of the room's faces {:.2}%",
            100.0 * worst,
            100.0 * worst_room
        );
        assert!(
            worst_room < 0.01,
            "{name}: the room's faces {worst_room} off"
        );
        assert!(
            worst < bound,
            "{name}: form factors sum {worst} off the coverage"
        );
    }
}

/// The Cornell MGF lit one face at a time (16 solves): (B_k − [k lit])/0.001 is patch k's
/// form factor to the lit face, against the fraction of 2^16 cosine rays from patch k whose
/// first hit is that face. Per receiver, the sum over the sources of |solved − rays| over
/// its coverage by rays. Measured: worst 2.05% (the green wall; the rays' own noise is
/// about 0.5–1% of a receiver's coverage). Asserted at 3%. With one ratio for every link
/// in the leaf scales (unweighted by what each carries) the worst is 10.1%: a coarse link
/// carrying nothing (the floor's, while only the back wall is lit) rescaled the fine links
/// that carry the light by its own ratio (the short block's back face got 0.20 of the back
/// wall where the rays say 0.29).
#[test]
fn form_factors_per_source_match_the_rays() {
    let n = 16;
    let mut solved = vec![vec![0.0f64; n]; n];
    let mut traced = vec![vec![0.0f64; n]; n];
    for j in 0..n {
        let text = cornell_mgf_lit(|f| f == j, |_| true);
        let (solution, fractions) = solve_and_cast(&text, &format!("lit-{j}"), 1 << 16, |prim| {
            prim as usize == j
        });
        for k in 0..n {
            let own = if k == j { 1.0 } else { 0.0 };
            solved[k][j] = (solution.state.radiance[k].x as f64 - own) / 0.001;
            traced[k][j] = fractions[k];
        }
    }
    let mut worst = (0.0f64, 0);
    for k in 0..n {
        let off: f64 = (0..n)
            .filter(|&j| j != k)
            .map(|j| (solved[k][j] - traced[k][j]).abs())
            .sum();
        let coverage: f64 = traced[k].iter().sum();
        println!(
            "receiver {k}: off by {:.2}% of its coverage {coverage:.4}",
            100.0 * off / coverage
        );
        if off / coverage > worst.0 {
            worst = (off / coverage, k);
        }
    }
    println!("worst: receiver {}, {:.2}%", worst.1, 100.0 * worst.0);
    assert!(worst.0 < 0.03, "receiver {} off by {}", worst.1, worst.0);
}
