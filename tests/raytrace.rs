//! The ray tracer against answers it did not produce: the closed-form irradiance of a square
//! light (Lambert's polygon formula, and the tabulated point-to-square form factor), a mirror
//! in front of an emitter, a glass sphere in a white furnace; and the sampling patterns
//! compared by their error.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{backends, square_light};
use trilux::accel::{self, AccelOptions};
use trilux::engines::{raytrace, EngineKind, RenderSettings};
use trilux::film::Film;
use trilux::geometry::Vec3;
use trilux::sampling::LightSampling;
use trilux::scene::Scene;

/// Irradiance at `x` (normal `n`) from a polygon of unit radiance, by Lambert's formula:
/// E = ½ Σ θᵢ (n · γᵢ), γᵢ the unit normal of the plane through x and edge i.
fn polygon_irradiance(x: [f64; 3], n: [f64; 3], polygon: &[[f64; 3]]) -> f64 {
    use common::vec64::{cross, dot, norm, sub};
    let mut sum = 0.0;
    for i in 0..polygon.len() {
        let a = sub(polygon[i], x);
        let b = sub(polygon[(i + 1) % polygon.len()], x);
        let theta = (dot(a, b) / (norm(a) * norm(b))).clamp(-1.0, 1.0).acos();
        let g = cross(a, b);
        sum += theta * dot(n, g) / norm(g);
    }
    0.5 * sum.abs()
}

fn load(text: &str) -> Scene {
    Scene::parse_dialect(Path::new("test.obj"), text).expect("test scene parses")
}

fn render(scene: &Scene, settings: &RenderSettings, kind: trilux::accel::AccelKind) -> Film {
    let accel = accel::build(scene, kind, &AccelOptions::default()).expect("builds");
    raytrace::render(scene, accel.as_ref(), settings).0
}

const LE: f32 = 10.0;
const RHO: f32 = 0.6;

fn quiet(width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        ambient_light: Vec3::ZERO,
        quiet: true,
        ..RenderSettings::default()
    }
}

fn mean(film: &Film) -> f64 {
    film.pixels.iter().map(|c| c.x as f64).sum::<f64>() / film.pixels.len() as f64
}

fn rmse(film: &Film, truth: f64) -> f64 {
    (film
        .pixels
        .iter()
        .map(|c| (c.x as f64 - truth).powi(2))
        .sum::<f64>()
        / film.pixels.len() as f64)
        .sqrt()
}

#[test]
fn square_light_matches_the_closed_form() {
    let square = [
        [-0.5, 1.0, 0.5],
        [-0.5, 1.0, -0.5],
        [0.5, 1.0, -0.5],
        [0.5, 1.0, 0.5],
    ];
    let form_factor = polygon_irradiance([0.0; 3], [0.0, 1.0, 0.0], &square) / PI;
    // The tabulated value's six digits: it is rounded to ±5e-7.
    assert!(
        (form_factor - 0.239456).abs() < 1e-6,
        "Lambert's formula gives F = {form_factor}"
    );
    let truth = RHO as f64 * LE as f64 * form_factor;
    let scene = square_light(LE, RHO);
    for kind in backends() {
        let settings = RenderSettings {
            num_shadow_samples: 1024,
            ..quiet(8, 8)
        };
        let m = mean(&render(&scene, &settings, kind));
        println!(
            "{kind}: {m:.6} against {truth:.6} ({:+.3}%)",
            100.0 * (m / truth - 1.0)
        );
        // Stratified shadow rays: a pixel's error at 16 is 1.2% (the RMSE of
        // `jittered_and_stratified_beat_random_sampling`), falling as N^−0.75 to 0.05% at
        // 1,024 and to 0.007% in the mean of 64 pixels. Measured −0.004%; the bound is seven
        // of those.
        assert!(
            (m / truth - 1.0).abs() < 5e-4,
            "{kind}: {m} against {truth}"
        );
    }
    // Without shadow samples the course's estimator uses the light's centre: A·cos²/r² = 1.
    let settings = RenderSettings {
        num_shadow_samples: 0,
        ..quiet(2, 2)
    };
    let m = mean(&render(&scene, &settings, trilux::accel::AccelKind::Bvh));
    println!(
        "centre estimate {:.2e} off",
        (m - (RHO * LE) as f64 / PI).abs()
    );
    // Measured 1.7e-8: exact but for the f32 rounding of 1.91, whose spacing is 1.2e-7.
    assert!(
        (m - (RHO * LE) as f64 / PI).abs() < 1.2e-7,
        "centre estimate {m}"
    );
}

/// `--light-sampling adaptive` through the ray tracer and each Accel: an unoccluded square
/// light takes four shadow rays and gives Lambert's value to f32 rounding; with a wall
/// hiding the light's part x > 0.13 from the lit point, the estimate is within half the form
/// factor of the column of finest cells the shadow's edge crosses (each such cell is counted
/// half seen), at a number of rays that grows with the edge, not the grid.
#[test]
fn adaptive_light_sampling_is_exact_where_the_corners_agree() {
    let strip = |from: f64, to: f64| {
        polygon_irradiance(
            [0.0; 3],
            [0.0, 1.0, 0.0],
            &[
                [from, 1.0, -0.5],
                [to, 1.0, -0.5],
                [to, 1.0, 0.5],
                [from, 1.0, 0.5],
            ],
        ) / PI
    };
    let scale = (RHO * LE) as f64;
    // A wall at height 0.5 facing down: it hides the light from the origin beyond x = 0.13,
    // and the camera above sees through its back (quads are one-sided).
    let wall = "material\ndiffuse 0 0 0\nm 2\n\
                v 0.065 0.5 10\nv 0.065 0.5 -10\nv 10 0.5 -10\nv 10 0.5 10\nf 9 10 11 12\n";
    let open = square_light(LE, RHO);
    let walled = common::square_light_and(LE, RHO, wall);
    for kind in backends() {
        let run = |scene: &Scene, depth: u32| {
            let settings = RenderSettings {
                num_shadow_samples: 4,
                light_sampling: Some(LightSampling::Adaptive),
                adaptive_depth: depth,
                ..quiet(2, 2)
            };
            let accel = accel::build(scene, kind, &AccelOptions::default()).expect("builds");
            let (film, stats) = raytrace::render(scene, accel.as_ref(), &settings);
            let rays = stats.shadow_rays.load(std::sync::atomic::Ordering::Relaxed) / 4;
            (mean(&film), rays)
        };
        let (m, rays) = run(&open, 3);
        let truth = scale * strip(-0.5, 0.5);
        println!("{kind}: unoccluded {m:.7} against {truth:.7}, {rays} rays");
        assert_eq!(rays, 4, "{kind}");
        // f32 rounding of the contour sum and the shading: measured 1e-7 relative.
        assert!(
            (m / truth - 1.0).abs() < 1e-6,
            "{kind}: {m} against {truth}"
        );
        for depth in 1..=4 {
            let (m, rays) = run(&walled, depth);
            let truth = scale * strip(-0.5, 0.13);
            let width = 1.0 / (1u32 << depth) as f64;
            let column = ((0.13 + 0.5) / width).floor() * width - 0.5;
            let bound = 0.5 * scale * strip(column, column + width);
            println!(
                "{kind}: depth {depth}: {m:.5} against {truth:.5} (bound {bound:.1e}), {rays} rays"
            );
            assert!((m - truth).abs() <= bound * 1.001, "{kind}: depth {depth}");
            let side = (1u64 << depth) + 1;
            assert!(rays <= 4 * side + 2 * depth as u64, "{kind}: {rays} rays");
        }
    }
}

#[test]
fn jittered_and_stratified_beat_random_sampling() {
    let square = [
        [-0.5, 1.0, 0.5],
        [-0.5, 1.0, -0.5],
        [0.5, 1.0, -0.5],
        [0.5, 1.0, 0.5],
    ];
    let truth =
        RHO as f64 * LE as f64 * polygon_irradiance([0.0; 3], [0.0, 1.0, 0.0], &square) / PI;
    let scene = square_light(LE, RHO);
    let error = |pattern: LightSampling, n: u32| {
        let settings = RenderSettings {
            num_shadow_samples: n,
            light_sampling: Some(pattern),
            ..quiet(24, 24)
        };
        rmse(
            &render(&scene, &settings, trilux::accel::AccelKind::Bvh),
            truth,
        )
    };
    let random_16 = error(LightSampling::Random, 16);
    let random_32 = error(LightSampling::Random, 32);
    let random_64 = error(LightSampling::Random, 64);
    let random_256 = error(LightSampling::Random, 256);
    let jittered_16 = error(LightSampling::Jittered, 16);
    let jittered_64 = error(LightSampling::Jittered, 64);
    let stratified_16 = error(LightSampling::Stratified, 16);
    println!(
        "RMSE: random 16 {random_16:.5}, 32 {random_32:.5}, 64 {random_64:.5}, 256 {random_256:.5}; \
         jittered 16 {jittered_16:.5}, 64 {jittered_64:.5}; stratified 16 {stratified_16:.5}"
    );
    assert!(random_64 < random_16, "more random samples, less error");
    assert!(
        jittered_16 < random_32,
        "16 jittered samples beat 32 random ones"
    );
    assert!(
        jittered_64 < random_256,
        "64 jittered samples beat 256 random ones"
    );
    assert!(
        stratified_16 < random_32,
        "16 stratified samples beat 32 random ones"
    );
}

#[test]
fn mirror_shows_its_reflectance_times_the_emitter() {
    let r = 0.7;
    let scene = load(&format!(
        "material\ndiffuse 0 0 0\nreflective {r} {r} {r}\n\
         material\ndiffuse 0 0 0\nemitted {LE} {LE} {LE}\n\
         m 0\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n\
         m 1\nv -5 -5 10\nv -5 5 10\nv 5 5 10\nv 5 -5 10\nf 5 6 7 8\n\
         OrthographicCamera {{\ncamera_position 0 0 5\npoint_of_interest 0 0 0\nup 0 1 0\nsize 1\n}}\n"
    ));
    for kind in backends() {
        let settings = RenderSettings {
            num_bounces: 1,
            ..quiet(8, 8)
        };
        let film = render(&scene, &settings, kind);
        let worst = film
            .pixels
            .iter()
            .map(|p| (p.x - r * LE).abs())
            .fold(0.0, f32::max);
        println!("{kind}: mirror {worst:.2e} off");
        // Measured exactly r·Le; the bound is ten f32 spacings at 7 (4.8e-7 each).
        for p in &film.pixels {
            assert!(
                (p.x - r * LE).abs() < 4.8e-6,
                "{kind}: {p:?}, expected {}",
                r * LE
            );
        }
        // With no bounce the mirror shows nothing (diffuse 0, ambient 0).
        let film = render(&scene, &quiet(4, 4), kind);
        assert!(film.pixels.iter().all(|p| p.x == 0.0));
    }
}

#[test]
fn glass_sphere_in_a_white_furnace_is_invisible() {
    let scene = load(
        "material\ndiffuse 0 0 0\ntransmitted 1 1 1\nior 1.5\n\
         m 0\ns 0 0 0 1\nbackground_color 1 1 1\n\
         OrthographicCamera {\ncamera_position 0 0 5\npoint_of_interest 0 0 0\nup 0 1 0\nsize 1.9\n}\n",
    );
    for kind in backends() {
        let settings = RenderSettings {
            num_bounces: 30,
            ..quiet(32, 32)
        };
        let film = render(&scene, &settings, kind);
        let worst = film
            .pixels
            .iter()
            .map(|p| (p.x - 1.0).abs())
            .fold(0.0f32, f32::max);
        println!("{kind}: largest deviation from the background {worst}");
        // Measured 3.1e-4: the branches pruned below a weight of 1e-4 (`MIN_WEIGHT`) and the
        // light still inside after 30 bounces. The bound is 3.3 times it.
        assert!(
            worst < 1e-3,
            "{kind}: a pixel is {worst} off the white background"
        );
    }
}

#[test]
fn same_image_for_both_backends_and_any_thread_count() {
    let scenes = common::own_scene_dir();
    let scene = Scene::load(&scenes.join("textured_plane_reflective_sphere.obj")).expect("loads");
    let settings = RenderSettings {
        num_bounces: 1,
        num_shadow_samples: 4,
        num_antialias_samples: 4,
        seed: 3,
        ..quiet(48, 48)
    };
    let mut images = Vec::new();
    for kind in backends() {
        for threads in [1, 2] {
            let pool = trilux::parallel::thread_pool(threads).expect("pool");
            images.push(pool.install(|| render(&scene, &settings, kind)));
        }
    }
    assert!(
        images.windows(2).all(|w| w[0] == w[1]),
        "images differ between backends or thread counts"
    );
}

/// Depth of field against the thin lens: a white emitting half-plane's edge at x = 0, seen
/// head-on from z = 10 through a lens of radius A = 0.2 focused at 10. On the plane in focus
/// the edge stays sharp. At z = 5, a pixel whose ray meets the focus plane at x_f sees the
/// half-plane through the part of the lens with x_lens < −x_f (the chord from the lens point
/// to the focus point crosses z = 5 halfway), so its value is the fraction of the lens disk
/// left of −x_f: F(u) = 1/2 + (u √(1 − u²) + asin u)/π at u = −x_f/A, averaged over the pixel
/// (a blur 12.8 px across in a 64 px image). Each column (its 64 rows alike, 64 samples each)
/// is held to that within four standard errors of its rows' own spread, plus 1e-3 for the
/// quadrature of the pixel average. A lens 40% too small fails by up to 0.3.
#[test]
fn depth_of_field_matches_the_thin_lens() {
    const SIZE: u32 = 64;
    const APERTURE: f64 = 0.2;
    let scene_at = |z: f32| {
        load(&format!(
            "material\ndiffuse 0 0 0\nemitted 1 1 1\nm 0\n\
             v -50 -50 {z}\nv 0 -50 {z}\nv 0 50 {z}\nv -50 50 {z}\nf 1 2 3 4\n\
             background_color 0 0 0\n\
             PerspectiveCamera {{\ncamera_position 0 0 10\npoint_of_interest 0 0 0\nup 0 1 0\nangle 0.2\n}}\n"
        ))
    };
    let settings = RenderSettings {
        num_antialias_samples: 64,
        aperture: APERTURE as f32,
        focus_distance: Some(10.0),
        ..quiet(SIZE, SIZE)
    };
    // The focus plane's width the image spans: 2 · 10 · tan(angle / 2).
    let span = 20.0 * (0.1f64).tan();
    let lens_fraction_left_of = |u: f64| {
        let u = u.clamp(-1.0, 1.0);
        0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / PI
    };
    let expected = |i: u32| -> f64 {
        const STEPS: u32 = 1000;
        (0..STEPS)
            .map(|k| {
                let x = (i as f64 + (k as f64 + 0.5) / STEPS as f64) / SIZE as f64 - 0.5;
                lens_fraction_left_of(-x * span / APERTURE)
            })
            .sum::<f64>()
            / STEPS as f64
    };
    let columns = |z: f32| -> Vec<(f64, f64)> {
        let film = render(&scene_at(z), &settings, trilux::accel::AccelKind::Bvh);
        (0..SIZE)
            .map(|i| {
                let rows: Vec<f64> = (0..SIZE).map(|j| film.get(i, j).x as f64).collect();
                let mean = rows.iter().sum::<f64>() / rows.len() as f64;
                let var =
                    rows.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (rows.len() - 1) as f64;
                (mean, (var / rows.len() as f64).sqrt())
            })
            .collect()
    };
    // In focus: every lens ray of a pixel meets the plane where the pinhole ray does.
    let sharp = columns(0.0);
    println!(
        "in focus: worst column {:.2e} off",
        sharp
            .iter()
            .enumerate()
            .map(|(i, &(m, _))| (m - if i < SIZE as usize / 2 { 1.0 } else { 0.0 }).abs())
            .fold(0.0, f64::max)
    );
    for (i, &(mean, _)) in sharp.iter().enumerate() {
        let truth = if i < SIZE as usize / 2 { 1.0 } else { 0.0 };
        // Measured exactly 0 or 1: every lens ray lands on the same side of the edge.
        assert!(
            (mean - truth).abs() < 1e-9,
            "in focus, column {i}: {mean} where the edge is sharp"
        );
    }
    let blurred = columns(5.0);
    let mut worst = 0.0f64;
    for (i, &(mean, standard_error)) in blurred.iter().enumerate() {
        let truth = expected(i as u32);
        let off = (mean - truth).abs();
        worst = worst.max(off / (4.0 * standard_error + 1e-3));
        assert!(
            off <= 4.0 * standard_error + 1e-3,
            "out of focus, column {i}: {mean:.4} ± {standard_error:.4} against the thin lens's {truth:.4}"
        );
    }
    println!("out of focus: worst column at {worst:.2} of its bound");
}

/// Snell's law, total internal reflection and the Fresnel reflectance, through a glass prism
/// of right-isosceles section, the rays of an orthographic camera entering its first leg face
/// head-on and meeting its hypotenuse face at 45°. Beyond the second leg (where what the
/// hypotenuse reflects leaves) a red emitter; below, far off (50 units), a green strip that
/// only the direction Snell's law gives through the hypotenuse reaches (21.8° off the
/// incoming ray for n = 1.3; 0° unbent, 12° with the indices swapped). Inside, the light
/// cycles between the four directions with gain R45² R0² per turn, so with
/// R0 = ((n − 1)/(n + 1))² (normal incidence) and R45 the Fresnel reflectance at 45° from
/// glass to air, computed here in f64:
/// red = (1 − R0)² R45 / (1 − R45² R0²), green = (1 − R0)(1 − R45) / (1 − R45² R0²).
/// For n = 1.5 the critical angle is 41.8° < 45°: R45 = 1, green 0 and red (1 − R0)/(1 + R0).
/// For n = 1.3 it is 50.3°: the hypotenuse lets 1 − R45 = 0.79 through.
#[test]
fn a_glass_prism_refracts_by_snells_law_and_reflects_totally_past_the_critical_angle() {
    let fresnel = common::fresnel;
    for n in [1.5f64, 1.3] {
        let mut scene = load(&format!(
            "material\ndiffuse 0 0 0\ntransmitted 1 1 1\nior {n}\n\
             material\ndiffuse 0 0 0\nemitted 1 0 0\n\
             material\ndiffuse 0 0 0\nemitted 0 1 0\n\
             v -1 -2 0\nv 1 -2 0\nv 1 2 0\nv -1 2 0\n\
             v 1 -2 -2\nv 1 2 -2\n\
             v 5 -10 2\nv 5 10 2\nv 5 10 -4\nv 5 -10 -4\n\
             v 15 -10 -50\nv 25 -10 -50\nv 25 10 -50\nv 15 10 -50\n\
             m 0\nf 1 2 3 4\nf 2 5 6 3\nf 1 4 6 5\n\
             m 1\nf 7 8 9 10\n\
             m 2\nf 11 12 13 14\n\
             background_color 0 0 0\n\
             OrthographicCamera {{\ncamera_position 0 0 5\npoint_of_interest 0 0 0\nup 0 1 0\nsize 1\n}}\n"
        ));
        // The prism is a closed solid of quads, which the course dialect makes one-sided.
        scene.two_sided_quads = true;
        let r0 = ((n - 1.0) / (n + 1.0)).powi(2);
        let r45 = fresnel(0.5f64.sqrt(), n, 1.0);
        let turn = 1.0 - r45 * r45 * r0 * r0;
        let red = (1.0 - r0).powi(2) * r45 / turn;
        let green = (1.0 - r0) * (1.0 - r45) / turn;
        for kind in backends() {
            let settings = RenderSettings {
                num_bounces: 30,
                ..quiet(16, 16)
            };
            let film = render(&scene, &settings, kind);
            println!(
                "n = {n}, {kind}: pixel {:?}, expected red {red:.6} green {green:.6}",
                film.get(8, 8)
            );
            // f32 arithmetic through a dozen interfaces (measured: 2.3e-6 off in either
            // channel).
            for p in &film.pixels {
                assert!(
                    (p.x as f64 - red).abs() < 1e-5 && (p.y as f64 - green).abs() < 1e-5,
                    "n = {n}, {kind}: {p:?} where red {red} and green {green}"
                );
            }
        }
    }
}

/// An OBJ scene (through its MTL, as a user writes one) of one triangle light of radiance
/// `le` and a floor of albedo `rho` 100 units wide at y = 0, on a black background.
fn triangle_light_over_a_floor(name: &str, triangle: [[f64; 3]; 3], le: f64, rho: f64) -> Scene {
    let dir = common::temp_dir(name);
    std::fs::write(
        dir.join("tri.mtl"),
        format!("newmtl light\nKd 0 0 0\nKe {le} {le} {le}\nnewmtl floor\nKd {rho} {rho} {rho}\n"),
    )
    .unwrap();
    let v = |p: [f64; 3]| format!("v {} {} {}\n", p[0], p[1], p[2]);
    std::fs::write(
        dir.join("tri.obj"),
        format!(
            "mtllib tri.mtl\n{}{}{}v -50 0 -50\nv -50 0 50\nv 50 0 50\nv 50 0 -50\n\
             usemtl light\nf 1 2 3\nusemtl floor\nf 4 5 6\nf 4 6 7\n",
            v(triangle[0]),
            v(triangle[1]),
            v(triangle[2])
        ),
    )
    .unwrap();
    let mut scene = Scene::load(&dir.join("tri.obj")).expect("the OBJ loads");
    std::fs::remove_dir_all(&dir).ok();
    scene.background = Vec3::ZERO;
    scene
}

/// Lights that are not quads, against closed forms, in the ray tracer and the path tracer.
/// A sphere of radius R and radiance Le whose centre is at distance d, at angle θ from a
/// surface's normal, and wholly above its horizon, gives irradiance π Le (R/d)² cos θ: a
/// white floor of albedo ρ seen at (1.5, 0, 0) under a sphere at (0, 2, 0), R = 0.5, has
/// radiance ρ Le (R/d)² cos θ = ρ Le · 0.04 · 0.8. A triangle of an OBJ file with an MTL
/// `Ke` gives what Lambert's polygon formula gives (`polygon_irradiance`, above). Both
/// within 1% (the square light's tolerance; measured: the ray tracer at 1,024 shadow samples
/// −0.00% and +0.06%, the path tracer at 4,096 paths a pixel over 4×4 pixels +0.01% and
/// +0.20%: the sphere sampled by its cone, the triangle by area; by area the sphere was
/// +0.05% and +0.42%).
#[test]
fn sphere_and_triangle_lights_give_the_closed_form_irradiance() {
    const RHO_FLOOR: f64 = 0.5;
    const LE_LIGHT: f64 = 4.0;
    let camera_at = |x: f32| trilux::scene::Camera {
        position: trilux::geometry::vec3(x, 5.0, 0.0),
        point_of_interest: trilux::geometry::vec3(x, 0.0, 0.0),
        up: trilux::geometry::vec3(0.0, 0.0, -1.0),
        projection: trilux::scene::Projection::Orthographic { size: 1e-4 },
    };
    let sphere = load(&format!(
        "material\ndiffuse 0 0 0\nemitted {LE_LIGHT} {LE_LIGHT} {LE_LIGHT}\n\
         material\ndiffuse {RHO_FLOOR} {RHO_FLOOR} {RHO_FLOOR}\n\
         m 0\ns 0 2 0 0.5\n\
         m 1\nv -50 0 -50\nv -50 0 50\nv 50 0 50\nv 50 0 -50\nf 1 2 3 4\n\
         background_color 0 0 0\n\
         OrthographicCamera {{\ncamera_position 1.5 5 0\npoint_of_interest 1.5 0 0\nup 0 0 -1\nsize 0.0001\n}}\n"
    ));
    let sphere_truth = RHO_FLOOR * LE_LIGHT * (0.5f64 / 2.5).powi(2) * 0.8;
    // The triangle faces down (its vertices counter-clockwise seen from below); the floor
    // is seen at (1.5, 0, 0), beside it, where the camera's ray does not meet it first.
    let triangle = [[-1.0, 1.0, -0.5], [1.0, 1.0, -0.5], [0.0, 1.0, 1.0]];
    let mut tri = triangle_light_over_a_floor("triangle-light", triangle, LE_LIGHT, RHO_FLOOR);
    tri.camera = Some(camera_at(1.5));
    let tri_truth =
        RHO_FLOOR * LE_LIGHT * polygon_irradiance([1.5, 0.0, 0.0], [0.0, 1.0, 0.0], &triangle) / PI;
    for (name, scene, truth) in [
        ("sphere", &sphere, sphere_truth),
        ("triangle", &tri, tri_truth),
    ] {
        for engine in [
            trilux::engines::EngineKind::Raytrace,
            trilux::engines::EngineKind::Path,
        ] {
            let settings = RenderSettings {
                num_shadow_samples: 1024,
                num_antialias_samples: if engine == trilux::engines::EngineKind::Path {
                    4096
                } else {
                    1
                },
                ..quiet(4, 4)
            };
            for kind in backends() {
                let accel = accel::build(scene, kind, &AccelOptions::default()).expect("builds");
                let film = trilux::engines::render(engine, scene, accel.as_ref(), &settings)
                    .expect("renders")
                    .film;
                let m = mean(&film);
                println!(
                    "{name} light, {engine}, {kind}: {m:.5} against {truth:.5} ({:+.2}%)",
                    100.0 * (m / truth - 1.0)
                );
                // Measured −0.00% and +0.06% (ray tracer, 1,024 shadow rays), +0.01% and
                // +0.20% (path tracer, 4,096 paths a pixel, the triangle's the noisier, sampled
                // by area): the bound is eight and 2.5 times the worst of each. (The path
                // tracer's was 1% while it sampled the sphere by area: +0.42%.)
                let bound = 5e-3;
                assert!(
                    (m / truth - 1.0).abs() < bound,
                    "{name}, {engine}, {kind}: {m} against {truth}"
                );
            }
        }
    }
}

/// The floor of `scene` seen straight down at (1.5, 0, 0), beside a `light` polygon of
/// radiance `le` that faces away from the floor (albedo `rho`), by each engine and way of
/// sampling in `ways`, with both Accels: black one-sided; with `--two-sided` what Lambert's
/// polygon formula says, within 0.5% (the tolerance of
/// `sphere_and_triangle_lights_give_the_closed_form_irradiance`). The photon engine is held
/// to the closed form only one-sided, where the answer is exactly 0: its density estimate is
/// not held to it.
fn assert_light_lights_only_its_front(
    mut scene: Scene,
    light: &[[f64; 3]],
    (le, rho): (f64, f64),
    ways: &[(EngineKind, Option<LightSampling>)],
) {
    scene.camera = Some(trilux::scene::Camera {
        position: trilux::geometry::vec3(1.5, 5.0, 0.0),
        point_of_interest: trilux::geometry::vec3(1.5, 0.0, 0.0),
        up: trilux::geometry::vec3(0.0, 0.0, -1.0),
        projection: trilux::scene::Projection::Orthographic { size: 1e-4 },
    });
    let truth = rho * le * polygon_irradiance([1.5, 0.0, 0.0], [0.0, 1.0, 0.0], light) / PI;
    for two_sided in [false, true] {
        scene.two_sided_quads = two_sided;
        for &(engine, light_sampling) in ways {
            if two_sided && engine == EngineKind::Photon {
                continue;
            }
            let settings = RenderSettings {
                num_shadow_samples: 1024,
                num_antialias_samples: if engine == EngineKind::Path { 4096 } else { 1 },
                light_sampling,
                ..quiet(4, 4)
            };
            for kind in backends() {
                let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
                let film = trilux::engines::render(engine, &scene, accel.as_ref(), &settings)
                    .expect("renders")
                    .film;
                let m = mean(&film);
                let how = format!("{engine} ({light_sampling:?}), {kind}");
                if two_sided {
                    assert!(
                        (m / truth - 1.0).abs() < 5e-3,
                        "two-sided, {how}: {m} against {truth}"
                    );
                } else {
                    assert_eq!(m, 0.0, "one-sided, {how}: the floor behind the light");
                }
            }
        }
    }
}

/// A triangle light lights the side it faces (the side its vertices run counter-clockwise
/// round), as it is seen and as radiosity's patches emit; with `--two-sided`, both sides
/// (`assert_light_lights_only_its_front`), in the ray tracer, the path tracer and the photon
/// engine.
#[test]
fn a_triangle_light_lights_the_side_it_faces() {
    const LE_LIGHT: f64 = 4.0;
    const RHO_FLOOR: f64 = 0.5;
    // Counter-clockwise seen from above: it faces up, away from the floor at y = 0.
    let triangle = [[-1.0, 1.0, -0.5], [0.0, 1.0, 1.0], [1.0, 1.0, -0.5]];
    let scene = triangle_light_over_a_floor("triangle-light-side", triangle, LE_LIGHT, RHO_FLOOR);
    let ways = [EngineKind::Raytrace, EngineKind::Path, EngineKind::Photon].map(|e| (e, None));
    assert_light_lights_only_its_front(scene, &triangle, (LE_LIGHT, RHO_FLOOR), &ways);
}

/// A quad light, as the course's dialect writes one, does the same
/// (`assert_light_lights_only_its_front`), in each of the ray tracer's ways of sampling a
/// rectangle (by solid angle, the default; by area; adaptive, by the corners' form factors),
/// the path tracer and the photon engine.
#[test]
fn a_quad_light_lights_the_side_it_faces() {
    const LE_LIGHT: f64 = 4.0;
    const RHO_FLOOR: f64 = 0.5;
    // Counter-clockwise seen from above: it faces up, away from the floor at y = 0.
    let square = [
        [-0.5, 1.0, 0.5],
        [0.5, 1.0, 0.5],
        [0.5, 1.0, -0.5],
        [-0.5, 1.0, -0.5],
    ];
    let v = |p: [f64; 3]| format!("v {} {} {}\n", p[0], p[1], p[2]);
    let text = format!(
        "material\ndiffuse 0 0 0\nemitted {LE_LIGHT} {LE_LIGHT} {LE_LIGHT}\n\
         material\ndiffuse {RHO_FLOOR} {RHO_FLOOR} {RHO_FLOOR}\n\
         background_color 0 0 0\n\
         m 0\n{}f 1 2 3 4\n\
         m 1\nv -50 0 -50\nv -50 0 50\nv 50 0 50\nv 50 0 -50\nf 5 6 7 8\n",
        square.map(v).concat()
    );
    let scene = Scene::parse_dialect(Path::new("quad-light.obj"), &text).expect("parses");
    assert_eq!(scene.quads.len(), 2, "the light and the floor are quads");
    let ways = [
        (EngineKind::Raytrace, None),
        (EngineKind::Raytrace, Some(LightSampling::Random)),
        (EngineKind::Raytrace, Some(LightSampling::Adaptive)),
        (EngineKind::Path, None),
        (EngineKind::Photon, None),
    ];
    assert_light_lights_only_its_front(scene, &square, (LE_LIGHT, RHO_FLOOR), &ways);
}

/// Glossy reflection against the Phong lobe's closed form: a floor mirror of roughness a
/// reflects about its mirror direction into cosⁿ (n = 2/a² − 2), whose share within α of
/// its axis is 1 − cos^(n+1) α. Seen head-on, it reflects a far emitting sphere straight
/// above, of angular radius α, with that share of the sphere's radiance; a = 0.2 (n = 48)
/// and α chosen where the share is ½. With n = 1/a² − 2 (a lobe twice as wide) the share
/// would be 0.29; a perfect mirror (a = 0) reflects all of it.
///
/// Three estimators: the ray tracer's lobe alone (one shadow ray, the course's mode), the ray
/// tracer with 16 shadow rays, which samples the sphere from the glossy point too and weighs
/// both by multiple importance sampling, and the path tracer (one light sample and one lobe
/// sample, weighed likewise). Held within four standard errors of the lobe alone's binomial
/// spread (16 × 1,024 samples: σ = 0.8% of the value); the weighed estimators must be
/// closer, within one σ (their spread is far smaller: a light sample of a sphere seen
/// within the lobe's core weighs nearly the same every time).
#[test]
fn glossy_reflection_spreads_as_its_phong_lobe() {
    const LE_SPHERE: f64 = 2.0;
    let exponent = 2.0 / (0.2f64 * 0.2) - 2.0;
    let cos_alpha = 0.5f64.powf(1.0 / (exponent + 1.0));
    let radius = 100.0 * (1.0 - cos_alpha * cos_alpha).sqrt();
    for (roughness, share) in [(0.2f64, 0.5f64), (0.0, 1.0)] {
        let scene = load(&format!(
            "material\ndiffuse 0 0 0\nemitted {LE_SPHERE} {LE_SPHERE} {LE_SPHERE}\n\
             material\ndiffuse 0 0 0\nreflective 1 1 1\nroughness {roughness}\n\
             m 0\ns 0 100 0 {radius}\n\
             m 1\nv -50 0 -50\nv -50 0 50\nv 50 0 50\nv 50 0 -50\nf 1 2 3 4\n\
             background_color 0 0 0\n\
             OrthographicCamera {{\ncamera_position 0 1 0\npoint_of_interest 0 0 0\nup 0 0 -1\nsize 0.0001\n}}\n"
        ));
        let truth = LE_SPHERE * share;
        let samples = 16.0 * 1024.0;
        let sigma = LE_SPHERE * (share * (1.0 - share) / samples).sqrt();
        for kind in backends() {
            let mut spreads = Vec::new();
            for (estimator, shadow_rays, bound) in [
                ("raytrace, lobe alone", 1, 4.0),
                ("raytrace, lobe and lights", 16, 1.0),
                ("path", 1, 1.0),
            ] {
                let settings = RenderSettings {
                    num_antialias_samples: 1024,
                    num_bounces: 1,
                    num_shadow_samples: shadow_rays,
                    ..quiet(4, 4)
                };
                let film = if estimator == "path" {
                    let accel = accel::build(&scene, kind, &AccelOptions::default()).unwrap();
                    trilux::engines::path::render(&scene, accel.as_ref(), &settings).0
                } else {
                    render(&scene, &settings, kind)
                };
                let m = mean(&film);
                // The spread of the 16 pixels, each a mean of 1,024 samples of the same point.
                let spread = (film
                    .pixels
                    .iter()
                    .map(|c| (c.x as f64 - m).powi(2))
                    .sum::<f64>()
                    / 15.0)
                    .sqrt();
                println!(
                    "roughness {roughness}, {kind}, {estimator}: {m:.5} against {truth:.5} \
                     ({:+.2}σ), pixels spread {spread:.2e}",
                    (m - truth) / sigma.max(1e-30)
                );
                spreads.push(spread);
                assert!(
                    (m - truth).abs() <= bound * sigma + 1e-5 * truth,
                    "roughness {roughness}, {kind}, {estimator}: {m} against {truth}"
                );
            }
            if roughness > 0.0 {
                // Measured: the lobe alone's pixels spread 2.9e-2 (its binomial σ per pixel
                // is 3.1e-2), the weighed estimators' 8.5e-3 (ray tracer) and 8.6e-3 (path).
                assert!(
                    spreads[1] < 0.5 * spreads[0] && spreads[2] < 0.5 * spreads[0],
                    "{kind}: spreads {spreads:?}"
                );
            }
        }
    }
}

/// Texture lookup against a lookup written here: a 2×2 PPM (one texel at sRGB 128, the
/// others 0 or 255) on a square whose `vt` run from 0 to 2 (so the image repeats twice each
/// way), seen head-on, lit by `-ambient_light 1 1 1` alone, so each pixel is the albedo at
/// its centre: the texels decoded from sRGB (IEC 61966-2-1) and interpolated bilinearly
/// between texel centres with wrap-around, t = 0 at the image's bottom row. To f32 rounding.
#[test]
fn texture_lookup_is_bilinear_wrapping_and_linear() {
    let dir = common::temp_dir("texture");
    let texels = [[[128u8, 0, 0], [0, 255, 0]], [[0, 0, 255], [255, 255, 255]]];
    let ppm: String = texels
        .iter()
        .flatten()
        .map(|c| format!("{} {} {}\n", c[0], c[1], c[2]))
        .collect();
    std::fs::write(dir.join("tex.ppm"), format!("P3\n2 2\n255\n{ppm}")).unwrap();
    std::fs::write(
        dir.join("plane.obj"),
        "material\ntexture_file tex.ppm\nm 0\n\
         v -1 -1 0\nvt 0 0\nv 1 -1 0\nvt 2 0\nv 1 1 0\nvt 2 2\nv -1 1 0\nvt 0 2\nf 1 2 3 4\n\
         background_color 0 0 0\n\
         OrthographicCamera {\ncamera_position 0 0 5\npoint_of_interest 0 0 0\nup 0 1 0\nsize 2\n}\n",
    )
    .unwrap();
    let scene = Scene::load(&dir.join("plane.obj")).expect("loads");
    std::fs::remove_dir_all(&dir).ok();
    let linear = |c: u8| {
        let c = c as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let texel = |x: i64, y: i64, k: usize| {
        linear(texels[y.rem_euclid(2) as usize][x.rem_euclid(2) as usize][k])
    };
    let lookup = |s: f64, t: f64, k: usize| {
        let (x, y) = (s * 2.0 - 0.5, (1.0 - t) * 2.0 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (ix, iy) = (x0 as i64, y0 as i64);
        let top = texel(ix, iy, k) * (1.0 - fx) + texel(ix + 1, iy, k) * fx;
        let bottom = texel(ix, iy + 1, k) * (1.0 - fx) + texel(ix + 1, iy + 1, k) * fx;
        top * (1.0 - fy) + bottom * fy
    };
    const SIZE: u32 = 40;
    let settings = RenderSettings {
        ambient_light: Vec3::ONE,
        ..quiet(SIZE, SIZE)
    };
    for kind in backends() {
        let film = render(&scene, &settings, kind);
        let mut worst = 0.0f64;
        for row in 0..SIZE {
            for i in 0..SIZE {
                let j = SIZE - 1 - row;
                // The pixel centre on the square, and its (s, t) = (x + 1, y + 1).
                let x = ((i as f64 + 0.5) / SIZE as f64 - 0.5) * 2.0;
                let y = ((j as f64 + 0.5) / SIZE as f64 - 0.5) * 2.0;
                let got = film.get(i, row);
                for (k, value) in [got.x, got.y, got.z].into_iter().enumerate() {
                    worst = worst.max((value as f64 - lookup(x + 1.0, y + 1.0, k)).abs());
                }
            }
        }
        println!("{kind}: largest difference from the lookup {worst:.2e}");
        // Measured: 5.7e-7.
        assert!(worst < 4e-6, "{kind}: a pixel is {worst} off the lookup");
    }
}

/// The part of `polygon` above the plane through `x` with normal `n` (Sutherland–Hodgman
/// against one plane): what Lambert's formula may be given, since it counts the part of a
/// polygon below the horizon with a negative sign.
fn clip_above(x: [f64; 3], n: [f64; 3], polygon: &[[f64; 3]]) -> Vec<[f64; 3]> {
    use common::vec64::{add, dot, scale, sub};
    let height = |p: [f64; 3]| dot(sub(p, x), n);
    let mut out = Vec::new();
    for i in 0..polygon.len() {
        let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
        let (ha, hb) = (height(a), height(b));
        if ha > 0.0 {
            out.push(a);
        }
        if (ha > 0.0) != (hb > 0.0) {
            out.push(add(a, scale(sub(b, a), ha / (ha - hb))));
        }
    }
    out
}

/// The rectangle sampler (`render::solid_angle`) against Lambert's contour formula: the
/// form factor from a point to a unit square estimated from the weights of multi-jittered
/// samples (uniform in solid angle across, by the receiver's cosine along), for points 1e-3
/// to 1e3 from the square, above its centre, just past an edge and tilted towards it, and
/// above its inside with the square crossing the receiver's horizon. The densities it
/// reports integrate to one over the square's solid angle. A point in the square's plane
/// sees nothing.
#[test]
fn solid_angle_sampling_matches_lamberts_formula() {
    use common::vec64::{norm, of, scale};
    use trilux::render::solid_angle::SphericalRectangle;
    use trilux::sampling::{Pattern, Rng, Strata};
    let corner = trilux::geometry::vec3(-0.5, -0.5, 0.0);
    let (eu, ev) = (
        trilux::geometry::vec3(1.0, 0.0, 0.0),
        trilux::geometry::vec3(0.0, 1.0, 0.0),
    );
    let square = [
        [-0.5, -0.5, 0.0],
        [0.5, -0.5, 0.0],
        [0.5, 0.5, 0.0],
        [-0.5, 0.5, 0.0],
    ];
    let unit = |v: [f64; 3]| scale(v, 1.0 / norm(v));
    // (x, y, normal) at each height h above the square's plane.
    let places: [(f32, f32, [f64; 3]); 4] = [
        (0.0, 0.0, [0.0, 0.0, -1.0]),
        (0.501, 0.0, [0.0, 0.0, -1.0]),
        (0.501, 0.2, unit([-1.0, 0.0, -1.0])),
        (0.3, 0.4, unit([0.3, 0.2, -1.0])),
    ];
    let vec = |v: [f64; 3]| trilux::geometry::vec3(v[0] as f32, v[1] as f32, v[2] as f32);
    // The worst relative error at [64, 4,096] samples, and of the densities' integral.
    let mut worst = [(0.0f64, 0.0f32, 0.0f32, 0.0f32); 2];
    let mut worst_density = 0.0f64;
    for h in [1e-3f32, 1e-2, 0.1, 1.0, 10.0, 100.0, 1e3] {
        for (p, &(px, py, n)) in places.iter().enumerate() {
            let x = trilux::geometry::vec3(px, py, h);
            let truth =
                polygon_irradiance(of(x), n, &clip_above(of(x), n, &square)) / std::f64::consts::PI;
            let rect = SphericalRectangle::new(x, corner, eu, ev).expect("subtends something");
            for (k, count) in [64u32, 4096].into_iter().enumerate() {
                let strata = Strata::new(Pattern::MultiJittered, count);
                let mut rng = Rng::new(3, k as u64, p as u64);
                let sum: f64 = strata
                    .samples(&mut rng)
                    .filter_map(|(u, v)| rect.sample_cosine(vec(n), u, v))
                    .map(|s| s.weight)
                    .sum();
                let off = (sum / count as f64 / truth - 1.0).abs();
                if off > worst[k].0 {
                    worst[k] = (off, h, px, py);
                }
            }
            // ∫ pdf dω over the part above the horizon, by uniform solid angle: Ω · mean pdf;
            // for the place whose horizon cuts the square, the share of Ω above it is not
            // known in closed form, so only the others are checked.
            if p < 3 {
                let strata = Strata::new(Pattern::MultiJittered, 4096);
                let mut rng = Rng::new(5, p as u64, 0);
                let mean: f64 = strata
                    .samples(&mut rng)
                    .map(|(u, v)| rect.pdf_cosine(vec(n), rect.sample(u, v)))
                    .sum::<f64>()
                    / 4096.0;
                worst_density = worst_density.max((mean * rect.solid_angle() - 1.0).abs());
            }
        }
    }
    for (k, samples) in [64, 4096].into_iter().enumerate() {
        let (off, h, px, py) = worst[k];
        println!("{samples} samples: worst {off:.2e} (h {h}, at ({px}, {py}))");
    }
    println!("densities integrate to 1 within {worst_density:.2e}");
    // The bound: 0.5% at 64 samples from 1e-3 to 1e3. (Uniform in solid angle with 8 × 8
    // jittered points was 1.4% off at h = 1e-3 above the centre.)
    assert!(worst[0].0 < 5e-3, "{:?}", worst[0]);
    assert!(worst[1].0 < 1e-3, "{:?}", worst[1]);
    assert!(worst_density < 1e-2, "{worst_density}");
    let in_plane = SphericalRectangle::new(trilux::geometry::vec3(0.6, 0.0, 0.0), corner, eu, ev);
    assert!(in_plane.is_none(), "a point in the plane sees nothing");
}

/// Direct light on the Cornell box with the diffuse sphere (256 × 256, 4 camera samples, no
/// ambient term), sampled by solid angle, against the same camera rays with 256 shadow rays
/// a light: at 16 shadow rays no pixel is more than 3× its converged value (by area, the
/// walls' edges where they touch the light are up to 15× too bright), the relMSE of
/// independent points in the solid-angle parametrisation (`solid-angle-random`) falls as 1/N
/// within 0.15 of the exponent (a heavy tail would make it shallower), and that of the
/// default, multi-jittered points at least as fast.
#[test]
fn direct_light_by_solid_angle_has_no_fireflies() {
    use trilux::film::metrics;
    let scene = common::own_scene("cornell_box_diffuse_sphere.obj");
    let accel =
        accel::build(&scene, common::backends()[0], &AccelOptions::default()).expect("builds");
    let direct = |n: u32, sampling: LightSampling| {
        let settings = RenderSettings {
            num_shadow_samples: n,
            num_antialias_samples: 4,
            ambient_light: Vec3::ZERO,
            light_sampling: Some(sampling),
            ..quiet(256, 256)
        };
        raytrace::render(&scene, accel.as_ref(), &settings).0
    };
    let reference = direct(256, LightSampling::SolidAngle);
    let luminance = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let mean =
        reference.pixels.iter().map(|&c| luminance(c)).sum::<f32>() / reference.pixels.len() as f32;
    // The largest ratio of a pixel to its converged value (pixels in shadow against a
    // thousandth of the mean).
    let brightest = |film: &Film| {
        film.pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(&p, &r)| luminance(p) / luminance(r).max(1e-3 * mean))
            .fold(0.0f32, f32::max)
    };
    let by_area = brightest(&direct(16, LightSampling::Jittered));
    let counts = [4u32, 16, 64];
    let independent: Vec<f64> = counts
        .iter()
        .map(|&n| {
            let film = direct(n, LightSampling::SolidAngleRandom);
            metrics::compare(&film, &reference)
                .expect("same size")
                .relmse
        })
        .collect();
    let independent_slope = common::log_log_slope(&counts, &independent);
    let listed: Vec<String> = independent.iter().map(|e| format!("{e:.3e}")).collect();
    println!(
        "independent points: relMSE {}, falling as N^{independent_slope:.2}",
        listed.join(", ")
    );
    assert!(
        (independent_slope + 1.0).abs() < 0.15,
        "independent points' relMSE falls as N^{independent_slope:.2}, not 1/N"
    );
    let mut errors = Vec::new();
    for n in counts {
        let film = direct(n, LightSampling::SolidAngle);
        let m = metrics::compare(&film, &reference).expect("same size");
        println!(
            "{n} shadow rays: relMSE {:.3e}, brightest pixel {:.2}× its converged value",
            m.relmse,
            brightest(&film)
        );
        if n == 16 {
            // Measured 1.74× (by area 14.6×): the bound is 3×.
            assert!(
                brightest(&film) < 3.0,
                "a pixel {}× too bright",
                brightest(&film)
            );
        }
        errors.push(m.relmse);
    }
    let slope = common::log_log_slope(&counts, &errors);
    println!(
        "by area at 16: brightest pixel {by_area:.1}×; solid angle's relMSE falls as N^{slope:.2}"
    );
    // Independent samples give −1; the jittered strata of the solid-angle parametrisation
    // do better (measured −1.6). Heavy tails would make it shallower than −1 (by area it is
    // −0.74 from 4 to 64): the bound is −0.85.
    assert!(slope < -0.85, "relMSE falls as N^{slope:.2}");
}
