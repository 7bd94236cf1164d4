//! All engines converge to the same image on the same diffuse scene: on the course's Cornell
//! box with a diffuse sphere, the converged radiosity (fine mesh, interpolated), the
//! photon-mapped and the path-traced images agree over the large flat regions (back wall,
//! floor, ceiling) to within 5% mean relative difference — none of them produced the others.

mod common;

use common::backends;
use trilux::accel::{self, closest_surface, Accel, AccelOptions};
use trilux::engines::photon::PhotonSettings;
use trilux::engines::radiosity::{RadiositySettings, SolverKind};
use trilux::engines::{compose, path, radiosity, RenderSettings};
use trilux::film::Film;
use trilux::scene::{Camera, PrimKind, Scene};

const SIZE: u32 = 40;

/// For each named quad of the scene, the pixels whose centre ray and whose eight neighbours'
/// all hit that quad (flat, away from edges and the sphere).
fn regions(
    scene: &Scene,
    accel: &dyn Accel,
    quads: &[(&'static str, usize)],
) -> Vec<(&'static str, Vec<usize>)> {
    let camera = scene.camera();
    let hit = |i: i64, j: i64| -> Option<u32> {
        if i < 0 || j < 0 || i >= SIZE as i64 || j >= SIZE as i64 {
            return None;
        }
        let (x, y) = Camera::screen_point(i as u32, j as u32, 0.5, 0.5, SIZE, SIZE);
        let s = closest_surface(accel, scene, &camera.generate_ray(x, y))?;
        (s.prim.kind == PrimKind::Quad).then_some(s.prim.index)
    };
    quads
        .iter()
        .map(|&(name, q)| {
            let mut pixels = Vec::new();
            for j in 0..SIZE as i64 {
                for i in 0..SIZE as i64 {
                    let all =
                        (-1..=1).all(|dj| (-1..=1).all(|di| hit(i + di, j + dj) == Some(q as u32)));
                    if all {
                        // Film rows run from the top.
                        pixels.push(((SIZE as i64 - 1 - j) * SIZE as i64 + i) as usize);
                    }
                }
            }
            (name, pixels)
        })
        .collect()
}

fn mean_relative_difference(a: &Film, b: &Film, pixels: &[usize]) -> f64 {
    pixels
        .iter()
        .map(|&k| {
            let (x, y) = (a.pixels[k], b.pixels[k]);
            let (x, y) = ((x.x + x.y + x.z) as f64, (y.x + y.y + y.z) as f64);
            (x - y).abs() / y.max(1e-6)
        })
        .sum::<f64>()
        / pixels.len() as f64
}

#[test]
fn radiosity_photon_and_path_images_agree_on_flat_regions() {
    let dir = common::own_scene_dir();
    let scene = Scene::load(&dir.join("cornell_box_diffuse_sphere.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let base = RenderSettings {
        width: SIZE,
        height: SIZE,
        quiet: true,
        ..RenderSettings::default()
    };
    let clock = std::time::Instant::now();
    let reference = path::render(
        &scene,
        accel.as_ref(),
        &RenderSettings {
            num_antialias_samples: 2048,
            ..base.clone()
        },
    )
    .0;
    println!("path: {:.1} s", clock.elapsed().as_secs_f64());
    // Both solvers: the mesh has 12,672 patches, so the hierarchical one links clusters.
    let radiosity: Vec<_> = [SolverKind::Progressive, SolverKind::Hierarchical]
        .into_iter()
        .map(|solver| {
            let clock = std::time::Instant::now();
            let film = radiosity::render(
                &scene,
                accel.as_ref(),
                &RenderSettings {
                    num_shadow_samples: 1,
                    num_antialias_samples: 4,
                    radiosity: RadiositySettings {
                        subdivide: 3,
                        sphere_rasterization: (16, 12),
                        interpolate: true,
                        solver,
                        ..Default::default()
                    },
                    ..base.clone()
                },
            )
            .expect("radiosity render")
            .0;
            println!(
                "radiosity ({solver}): {:.1} s",
                clock.elapsed().as_secs_f64()
            );
            (solver, film)
        })
        .collect();
    let clock = std::time::Instant::now();
    let photons = compose::render_photons(
        &scene,
        accel.as_ref(),
        &RenderSettings {
            num_shadow_samples: 64,
            num_antialias_samples: 4,
            photon: PhotonSettings {
                num_photons_to_shoot: 500_000,
                num_photons_to_collect: 200,
                max_photon_depth: 1000,
                gather_indirect: true,
                final_gather_rays: 64,
                ..Default::default()
            },
            ..base.clone()
        },
    )
    .expect("renders")
    .0
    .film;
    println!("photon: {:.1} s", clock.elapsed().as_secs_f64());
    // The quads of the file: 0 light (front), 1 back wall, 2 ceiling, 3 floor.
    let regions = regions(
        &scene,
        accel.as_ref(),
        &[("back wall", 1), ("ceiling", 2), ("floor", 3)],
    );
    // 5% is the figure the mission's "all engines converge to the same image" was first
    // checked at. Measured: photons 1.4–2.4% (1.5–2.8% before final gathering made its
    // records in a first pass), radiosity 2.4–4.1% (progressive) and 2.7–4.7% (hierarchical),
    // the floor's the largest (21 pixels); the path tracer's own noise is part of each figure. The bound is 1.06 times the worst: a regression guard at the edge of
    // what the subdivide-3 radiosity mesh resolves, not a spread.
    for (name, pixels) in &regions {
        assert!(pixels.len() > 20, "{name}: {} pixels", pixels.len());
        let p = mean_relative_difference(&photons, &reference, pixels);
        println!(
            "{name} ({} pixels): photon vs path {:.2}%",
            pixels.len(),
            100.0 * p
        );
        assert!(p < 0.05, "{name}: photons differ by {p}");
        for (solver, film) in &radiosity {
            let r = mean_relative_difference(film, &reference, pixels);
            println!("{name}: radiosity ({solver}) vs path {:.2}%", 100.0 * r);
            assert!(r < 0.05, "{name}: radiosity ({solver}) differs by {r}");
        }
    }
}
