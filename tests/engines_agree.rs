//! All engines converge to the same image on the same diffuse scene: on the course's Cornell
//! box with a diffuse sphere, the converged radiosity (fine mesh, interpolated), the
//! photon-mapped and the path-traced images agree over the large flat regions (back wall,
//! floor, ceiling) to within 5% mean relative difference — none of them produced the others.

mod common;

use common::backends;
use trilux::accel::{self, closest_surface, Accel, AccelOptions};
use trilux::engines::photon::PhotonSettings;
use trilux::engines::radiosity::{RadiositySettings, SolverKind};
use trilux::engines::{compose, path, radiosity, raytrace, RenderSettings};
use trilux::film::Film;
use trilux::scene::{Camera, PrimKind, PrimRef, Scene};

const SIZE: u32 = 40;

/// For each named quad of the scene, the pixels whose centre ray and whose eight neighbours'
/// all hit that quad (flat, away from edges and the sphere).
fn regions(
    scene: &Scene,
    accel: &dyn Accel,
    quads: &[(&'static str, usize)],
) -> Vec<(&'static str, Vec<usize>)> {
    let named: Vec<_> = quads
        .iter()
        .map(|&(name, q)| (name, quad(q as u32)))
        .collect();
    regions_of(scene, accel, &named)
}

/// For each named primitive, the pixels whose centre ray and whose eight neighbours' all hit
/// it first.
fn regions_of(
    scene: &Scene,
    accel: &dyn Accel,
    prims: &[(&'static str, PrimRef)],
) -> Vec<(&'static str, Vec<usize>)> {
    let camera = scene.camera();
    let hit = |i: i64, j: i64| -> Option<PrimRef> {
        if i < 0 || j < 0 || i >= SIZE as i64 || j >= SIZE as i64 {
            return None;
        }
        let (x, y) = Camera::screen_point(i as u32, j as u32, 0.5, 0.5, SIZE, SIZE);
        closest_surface(accel, scene, &camera.generate_ray(x, y)).map(|s| s.prim)
    };
    prims
        .iter()
        .map(|&(name, q)| {
            let mut pixels = Vec::new();
            for j in 0..SIZE as i64 {
                for i in 0..SIZE as i64 {
                    let all = (-1..=1).all(|dj| (-1..=1).all(|di| hit(i + di, j + dj) == Some(q)));
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

/// The settings every render here starts from: `SIZE`², quiet.
fn base_settings() -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        quiet: true,
        ..RenderSettings::default()
    }
}

/// The photon engine's settings of the agreement tests: 16 samples a pixel, `shadow` rays a
/// light, `photons` photons shot.
fn photon_settings(shadow: u32, photons: u64) -> RenderSettings {
    let mut settings = RenderSettings {
        num_shadow_samples: shadow,
        num_antialias_samples: 16,
        ..base_settings()
    };
    settings.photon.num_photons_to_shoot = Some(photons);
    settings
}

/// The path tracer's image at `spp` paths a pixel: the reference.
fn path_traced(scene: &Scene, accel: &dyn Accel, spp: u32) -> Film {
    let clock = std::time::Instant::now();
    let film = path::render(
        scene,
        accel,
        &RenderSettings {
            num_antialias_samples: spp,
            ..base_settings()
        },
    )
    .0;
    println!("path: {:.1} s", clock.elapsed().as_secs_f64());
    film
}

/// The sum of the pixels' three channels over `pixels`.
fn region_sum(film: &Film, pixels: &[usize]) -> f64 {
    pixels
        .iter()
        .map(|&k| {
            let p = film.pixels[k];
            p.x as f64 + p.y as f64 + p.z as f64
        })
        .sum()
}

/// Renders `file` of `scenes/` with the path tracer (`path_spp`) and the photon engine (each
/// of `photons`' settings over the base settings) and asserts that over each of `prims`'
/// regions each photon image's mean is within `bound` of the path tracer's.
fn photon_agrees_with_path_on_region_means(
    file: &str,
    path_spp: u32,
    photons: &[(&str, RenderSettings)],
    prims: &[(&'static str, PrimRef)],
    bound: f64,
) {
    let scene = Scene::load(&common::own_scene_dir().join(file)).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let reference = path_traced(&scene, accel.as_ref(), path_spp);
    let regions = regions_of(&scene, accel.as_ref(), prims);
    for (what, settings) in photons {
        let clock = std::time::Instant::now();
        let image = compose::render_photons(&scene, accel.as_ref(), settings)
            .expect("renders")
            .0
            .film;
        println!("{what}: {:.1} s", clock.elapsed().as_secs_f64());
        for (name, pixels) in &regions {
            assert!(pixels.len() > 20, "{name}: {} pixels", pixels.len());
            let means = region_sum(&image, pixels) / region_sum(&reference, pixels) - 1.0;
            println!(
                "{name} ({} pixels): {what} vs path: means {:+.2}%, per pixel {:.2}%",
                pixels.len(),
                100.0 * means,
                100.0 * mean_relative_difference(&image, &reference, pixels)
            );
            assert!(means.abs() < bound, "{name}: {what} differs by {means}");
        }
    }
}

/// `settings` with final gathering (`-gather_indirect`).
fn gathering(mut settings: RenderSettings) -> RenderSettings {
    settings.photon.gather_indirect = true;
    settings
}

/// Quad `index` of the scene.
fn quad(index: u32) -> PrimRef {
    PrimRef {
        kind: PrimKind::Quad,
        index,
    }
}

#[test]
fn radiosity_photon_and_path_images_agree_on_flat_regions() {
    let dir = common::own_scene_dir();
    let scene = Scene::load(&dir.join("cornell_box_diffuse_sphere.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let base = base_settings();
    let reference = path_traced(&scene, accel.as_ref(), 2048);
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
                num_photons_to_shoot: Some(500_000),
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
    // records in a first pass), radiosity 2.3–3.6% (progressive) and 2.7–4.5% (hierarchical),
    // the floor's the largest (21 pixels); the path tracer's own noise is part of each figure. The bound is 1.1 times the worst: a regression guard at the edge of
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

/// The fog Cornell box (an open-fronted box in a scattering fog, `scenes/cornell_box_fog.obj`):
/// the photon engine (the ray tracer's direct light and single scattering, the surface and
/// volume photon maps for the rest), without and with final gathering (whose gather rays take
/// the transmittance to what they hit and the volume map's light scattered into them),
/// against the path tracer over the back wall, the ceiling and the floor. The ray tracer alone
/// has no multiple scattering nor indirect light; `the_ray_tracer_agrees_with_single_scattering_paths_in_fog`
/// compares it with the paths it does compute.
///
/// Compared by the regions' means, within 3%: measured −0.29%, −0.39%, −1.24% without final
/// gathering, −0.46%, −0.08%, −1.36% with it (gather rays blind to the fog made the back wall
/// 5.8% dark). The per-pixel mean relative difference comes out at 3.8–4.7%
/// here, but it measures the path tracer's noise in fog: two path-traced renders at 4,096
/// paths a pixel (seeds 0 and 3) differ by 5.5% per pixel over the same regions, two photon
/// renders by 1.6%.
///
/// (Before the scene's walls had black outsides, the photon engine was 3–9% below: shadow
/// rays from the fog outside the box passed through the one-sided walls' backs to the light,
/// lighting fog no photon can reach; with `--two-sided` the two agreed within 1.4%.)
#[test]
fn photon_and_path_images_agree_on_flat_regions_in_fog() {
    let photon = photon_settings(64, 1_000_000);
    photon_agrees_with_path_on_region_means(
        "cornell_box_fog.obj",
        4096,
        &[
            ("photon", photon.clone()),
            ("photon with final gathering", gathering(photon)),
        ],
        &[
            ("back wall", quad(1)),
            ("ceiling", quad(2)),
            ("floor", quad(3)),
        ],
        0.03,
    );
}

/// The ray tracer in the fog Cornell box computes the paths of one scattering: direct light at
/// the surfaces (attenuated through the fog) and the lights' single scattering along camera
/// rays. The path tracer cut after one scattering (`--max-depth 1`) computes the same paths
/// by other means (free flights, one light sample and one BSDF or phase sample weighed by MIS,
/// where the ray tracer samples the lights by solid angle and the distance equiangularly),
/// so the two agree over the back wall, the ceiling and the floor by the regions' means
/// within 3%: measured +0.12%, −0.60%, −0.12% (per pixel 1.8%, 3.3%, 1.4%). The paths of more
/// scatterings are what the ray tracer leaves to the photon engine's maps: against the uncut
/// path tracer the ray tracer's back wall is 68% darker.
#[test]
fn the_ray_tracer_agrees_with_single_scattering_paths_in_fog() {
    let scene = Scene::load(&common::own_scene_dir().join("cornell_box_fog.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let clock = std::time::Instant::now();
    let paths = path::render(
        &scene,
        accel.as_ref(),
        &RenderSettings {
            num_antialias_samples: 4096,
            max_depth: Some(1),
            ..base_settings()
        },
    )
    .0;
    println!(
        "path, one scattering: {:.1} s",
        clock.elapsed().as_secs_f64()
    );
    let clock = std::time::Instant::now();
    let traced = raytrace::render(
        &scene,
        accel.as_ref(),
        &RenderSettings {
            num_shadow_samples: 16,
            num_antialias_samples: 64,
            ambient_light: trilux::geometry::Vec3::ZERO,
            ..base_settings()
        },
    )
    .0;
    println!("ray tracer: {:.1} s", clock.elapsed().as_secs_f64());
    let prims = [
        ("back wall", quad(1)),
        ("ceiling", quad(2)),
        ("floor", quad(3)),
    ];
    for (name, pixels) in &regions_of(&scene, accel.as_ref(), &prims) {
        assert!(pixels.len() > 20, "{name}: {} pixels", pixels.len());
        let means = region_sum(&traced, pixels) / region_sum(&paths, pixels) - 1.0;
        println!(
            "{name} ({} pixels): ray tracer vs one-scattering paths: means {:+.2}%, per pixel {:.2}%",
            pixels.len(),
            100.0 * means,
            100.0 * mean_relative_difference(&traced, &paths, pixels)
        );
        assert!(
            means.abs() < 0.03,
            "{name}: the ray tracer differs by {means}"
        );
    }
}

/// The glass sphere filled with a scattering medium (`scenes/glass_sphere_medium.obj`,
/// `interior_medium`): the photon engine against the path tracer over the sphere, the back
/// wall and the floor, by the regions' means within 3%: measured −1.11%, +0.09%, −0.17% (per
/// pixel 4.7%, 2.4%, 3.6%, the path tracer's noise mostly). Inside the glass the photon maps
/// store power/n² (the ray tracer carries radiance through refraction without the n²
/// factors); without that the sphere came out 2.0× the path tracer's.
#[test]
fn photon_and_path_images_agree_through_a_glass_sphere_filled_with_a_medium() {
    let photon = RenderSettings {
        num_bounces: 6,
        ..photon_settings(16, 1_000_000)
    };
    let sphere = PrimRef {
        kind: PrimKind::Shape,
        index: 0,
    };
    photon_agrees_with_path_on_region_means(
        "glass_sphere_medium.obj",
        2048,
        &[("photon", photon)],
        &[
            ("sphere", sphere),
            ("back wall", quad(1)),
            ("floor", quad(4)),
        ],
        0.03,
    );
}

/// The procedural-texture scene (`scenes/procedural_textures.obj`): textures and bump maps
/// are looked up the same way by every engine, so the photon engine, without and with final
/// gathering (whose gather rays' hits look photons up by the geometric normal too), and the
/// path tracer (1,024 paths a pixel) agree over the checker floor, the crackle-bumped wall,
/// the panel bumped by a height image, by the regions' means within 3% (measured −0.25%,
/// −0.50%, −0.15%, per pixel 5.0%, 2.4%, 2.6%; with final gathering −0.18%, +0.73%, +1.30%).
/// The spheres cover too few pixels at this size to be compared on their own. Before photons
/// were stored and looked up by the geometric normal, the bumped normals of neighbouring
/// points kept each other's photons out (the normal check), and the panel came out 4.3% dark.
#[test]
fn photon_and_path_images_agree_on_procedural_textures_and_bumps() {
    let photon = photon_settings(16, 200_000);
    photon_agrees_with_path_on_region_means(
        "procedural_textures.obj",
        1024,
        &[
            ("photon", photon.clone()),
            ("photon with final gathering", gathering(photon)),
        ],
        &[("floor", quad(1)), ("wall", quad(2)), ("panel", quad(3))],
        0.03,
    );
}
