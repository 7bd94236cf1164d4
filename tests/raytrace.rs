//! The ray tracer against answers it did not produce: the closed-form irradiance of a square
//! light (Lambert's polygon formula, and the tabulated point-to-square form factor), a mirror
//! in front of an emitter, a glass sphere in a white furnace; and the sampling patterns
//! compared by their error.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{backends, square_light};
use trilux::accel::{self, AccelOptions};
use trilux::engines::{raytrace, RenderSettings};
use trilux::film::Film;
use trilux::geometry::Vec3;
use trilux::sampling::Pattern;
use trilux::scene::Scene;

/// Irradiance at `x` (normal `n`) from a polygon of unit radiance, by Lambert's formula:
/// E = ½ Σ θᵢ (n · γᵢ), γᵢ the unit normal of the plane through x and edge i.
fn polygon_irradiance(x: [f64; 3], n: [f64; 3], polygon: &[[f64; 3]]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f64; 3]| dot(a, a).sqrt();
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
        assert!(
            (m / truth - 1.0).abs() < 0.01,
            "{kind}: {m} against {truth}"
        );
    }
    // Without shadow samples the course's estimator uses the light's centre: A·cos²/r² = 1.
    let settings = RenderSettings {
        num_shadow_samples: 0,
        ..quiet(2, 2)
    };
    let m = mean(&render(&scene, &settings, trilux::accel::AccelKind::Bvh));
    assert!(
        (m - (RHO * LE) as f64 / PI).abs() < 1e-4,
        "centre estimate {m}"
    );
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
    let error = |pattern: Pattern, n: u32| {
        let settings = RenderSettings {
            num_shadow_samples: n,
            light_sampling: pattern,
            ..quiet(24, 24)
        };
        rmse(
            &render(&scene, &settings, trilux::accel::AccelKind::Bvh),
            truth,
        )
    };
    let random_16 = error(Pattern::Random, 16);
    let random_32 = error(Pattern::Random, 32);
    let random_64 = error(Pattern::Random, 64);
    let random_256 = error(Pattern::Random, 256);
    let jittered_16 = error(Pattern::Jittered, 16);
    let jittered_64 = error(Pattern::Jittered, 64);
    let stratified_16 = error(Pattern::Stratified, 16);
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
        for p in &film.pixels {
            assert!(
                (p.x - r * LE).abs() < 1e-4,
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
        assert!(
            worst < 0.01,
            "{kind}: a pixel is {worst} off the white background"
        );
    }
}

#[test]
fn same_image_for_both_backends_and_any_thread_count() {
    let Some(course) = common::course_dir() else {
        return;
    };
    let scene = Scene::load(&course.join("textured_plane_reflective_sphere.obj")).expect("loads");
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

/// Depth of field: with a lens, the edge of a quad on the plane in focus stays sharp and the
/// edge of one off that plane is spread over many pixels.
#[test]
fn depth_of_field_blurs_only_what_is_out_of_focus() {
    // A white emitting quad's right edge at x = 0, seen head-on from z = 10.
    let scene_at = |z: f32| {
        load(&format!(
            "material\ndiffuse 0 0 0\nemitted 1 1 1\nm 0\n\
             v -5 -5 {z}\nv 0 -5 {z}\nv 0 5 {z}\nv -5 5 {z}\nf 1 2 3 4\n\
             background_color 0 0 0\n\
             PerspectiveCamera {{\ncamera_position 0 0 10\npoint_of_interest 0 0 0\nup 0 1 0\nangle 0.2\n}}\n"
        ))
    };
    // Pixels of the middle row that are neither black nor white: the width of the edge.
    let edge_width = |z: f32| {
        let scene = scene_at(z);
        let settings = RenderSettings {
            num_antialias_samples: 64,
            aperture: 0.2,
            focus_distance: Some(10.0),
            ..quiet(64, 64)
        };
        let film = render(&scene, &settings, trilux::accel::AccelKind::Bvh);
        (0..64)
            .filter(|&i| (0.05..0.95).contains(&film.get(i, 32).x))
            .count()
    };
    let in_focus = edge_width(0.0);
    let out_of_focus = edge_width(5.0);
    println!("edge width: in focus {in_focus} px, out of focus {out_of_focus} px");
    assert!(
        in_focus <= 2,
        "the edge on the focus plane is sharp ({in_focus} px)"
    );
    assert!(
        out_of_focus >= 6,
        "the edge off the focus plane is blurred ({out_of_focus} px)"
    );
}
