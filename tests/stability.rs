//! Numerical stability on stiff and extreme cases (issue #7), at sizes fast enough for CI.
//! Each case has an oracle the code under test does not produce: the furnace's Le/(1−ρ), the
//! untransformed render of the same scene, linearity in the emitted radiance, closed forms.
//! STABILITY.md holds the figures for both Accels and the commands behind them.

mod common;

use std::path::Path;

use common::{backends, furnace, own_scenes, square_light, worst_relative_error};
use trilux::accel::{self, AccelOptions};
use trilux::engines::radiosity::solver::{Relaxation, Stop};
use trilux::engines::radiosity::{RadiositySettings, Solution};
use trilux::engines::{self, EngineKind, RenderSettings};
use trilux::film::metrics;
use trilux::film::Film;
use trilux::geometry::{vec3, Vec3};
use trilux::scene::Scene;

fn render(engine: EngineKind, scene: &Scene, kind: accel::AccelKind, s: &RenderSettings) -> Film {
    let accel = accel::build(scene, kind, &AccelOptions::default()).expect("builds");
    engines::render(engine, scene, accel.as_ref(), s)
        .expect("renders")
        .film
}

fn all_finite(film: &Film) -> bool {
    film.pixels.iter().all(|p| p.is_finite())
}

/// The radiosity furnace (384 patches) with plain shooting and with the automatic
/// over-relaxation: the error against 1/(1−ρ) and the shots, for ρ = 0.9, 0.99, 0.999. The
/// automatic one must converge at ρ = 0.999, within 0.5%, where plain shooting hits its cap.
#[test]
fn stiff_radiosity_furnace_converges_with_automatic_over_relaxation() {
    for (kind, rho) in backends()
        .into_iter()
        .flat_map(|k| [0.9f32, 0.99, 0.999].map(|rho| (k, rho)))
    {
        let scene = furnace(rho);
        let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
        let truth = 1.0 / (1.0 - rho);
        for relaxation in [Relaxation::Fixed(1.0), Relaxation::Auto] {
            let settings = RenderSettings {
                num_shadow_samples: 0,
                quiet: true,
                radiosity: RadiositySettings {
                    subdivide: 3,
                    num_form_factor_samples: 16,
                    relaxation,
                    ..Default::default()
                },
                ..RenderSettings::default()
            };
            let solution = Solution::solve(&scene, accel.as_ref(), &settings, |_| {});
            let worst = worst_relative_error(&solution.state.radiance, truth);
            println!(
                "{kind}: ρ = {rho}, {relaxation:?}: {} shots, {:?}, worst patch {:.3}%",
                solution.state.iterations,
                solution.stop,
                100.0 * worst
            );
            assert!(solution.state.radiance.iter().all(|l| l.is_finite()));
            if rho == 0.999 && relaxation == Relaxation::Fixed(1.0) {
                // Plain shooting needs millions of shots here: it stops at the safety cap,
                // and says so (the command prints a warning on Stop::Cap).
                assert_eq!(solution.stop, Stop::Cap);
                continue;
            }
            assert_eq!(solution.stop, Stop::Converged, "ρ = {rho}, {relaxation:?}");
            assert!(worst < 0.005, "ρ = {rho}, {relaxation:?}: {worst}");
        }
    }
}

/// The path tracer's and the photon engine's furnace at ρ = 0.99: Russian roulette keeps the
/// paths finite and the estimates within 1% (paths) and 3% (photons) of 100.
#[test]
fn stiff_path_and_photon_furnace() {
    let rho = 0.99f32;
    let scene = furnace(rho);
    let truth = 1.0 / (1.0 - rho as f64);
    let mean = |f: &Film| f.pixels.iter().map(|p| p.x as f64).sum::<f64>() / f.pixels.len() as f64;
    for kind in backends() {
        let path = render(
            EngineKind::Path,
            &scene,
            kind,
            &RenderSettings {
                width: 8,
                height: 8,
                num_antialias_samples: 4096,
                quiet: true,
                ..RenderSettings::default()
            },
        );
        let mut s = RenderSettings {
            width: 8,
            height: 8,
            num_shadow_samples: 16,
            num_antialias_samples: 4,
            quiet: true,
            ..RenderSettings::default()
        };
        s.photon.num_photons_to_shoot = 400_000;
        s.photon.max_photon_depth = 100_000;
        let photons = render(EngineKind::Photon, &scene, kind, &s);
        let (p, ph) = (mean(&path), mean(&photons));
        println!("{kind}: ρ = 0.99 furnace: path {p:.3}, photons {ph:.3}, truth {truth:.3}");
        assert!((p / truth - 1.0).abs() < 0.01, "{kind}: {p}");
        assert!((ph / truth - 1.0).abs() < 0.03, "{kind}: {ph}");
    }
}

/// Every course scene scaled by 1e-4 … 1e4 and moved by 1e2 and 1e3 renders the image of the
/// untransformed scene (relMSE ≤ 1e-3: no acne, no leaks), with both Accels; moved by 1e4 it
/// is measured and printed.
#[test]
fn scenes_do_not_depend_on_units_or_position() {
    let s = RenderSettings {
        width: 32,
        height: 32,
        num_shadow_samples: 4,
        num_antialias_samples: 4,
        num_bounces: 2,
        quiet: true,
        ..RenderSettings::default()
    };
    let held = [
        (1e-4f32, 0.0f32),
        (1e-2, 0.0),
        (1e2, 0.0),
        (1e4, 0.0),
        (1.0, 1e2),
        (1.0, 1e3),
    ];
    // The worst relMSE over the course scenes, per Accel and transform, and which scene.
    let mut worst: Vec<(String, f32, f32, f64, String)> = Vec::new();
    for path in own_scenes() {
        let base = Scene::load(&path).expect("loads");
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        for kind in backends() {
            let reference = render(EngineKind::Raytrace, &base, kind, &s);
            for (scale, offset) in held.iter().copied().chain([(1.0, 1e4)]) {
                let moved = base.transformed(scale, Vec3::splat(offset));
                let film = render(EngineKind::Raytrace, &moved, kind, &s);
                let m = metrics::compare(&film, &reference).expect("same size");
                assert!(all_finite(&film));
                if held.contains(&(scale, offset)) {
                    assert!(
                        m.relmse <= 1e-3,
                        "{name} ({kind}) scale {scale} offset {offset}: {m:?}"
                    );
                }
                let key = (kind.to_string(), scale, offset);
                match worst.iter_mut().find(|w| (w.0.clone(), w.1, w.2) == key) {
                    Some(w) if w.3 >= m.relmse => {}
                    Some(w) => (w.3, w.4) = (m.relmse, name.to_string()),
                    None => worst.push((key.0, scale, offset, m.relmse, name.to_string())),
                }
            }
        }
    }
    for (kind, scale, offset, relmse, name) in &worst {
        println!("{kind}: scale {scale:e}, offset {offset:e}: worst relMSE {relmse:.2e} ({name})");
    }
}

/// Emitted radiance of 1e-30 and 1e30: every engine's image scales with it (relMSE of the image
/// divided by the factor against the image at 1, below 1e-6), and nothing overflows.
#[test]
fn emitted_radiance_from_1e_minus_30_to_1e30_scales_linearly() {
    let dir = common::own_scene_dir();
    let base = Scene::load(&dir.join("cornell_box_diffuse_sphere.obj")).expect("loads");
    let mut s = RenderSettings {
        width: 24,
        height: 24,
        num_shadow_samples: 4,
        num_antialias_samples: 4,
        ambient_light: Vec3::ZERO,
        quiet: true,
        ..RenderSettings::default()
    };
    s.radiosity.subdivide = 1;
    s.photon.num_photons_to_shoot = 50_000;
    for (kind, engine) in backends().into_iter().flat_map(|k| {
        [
            EngineKind::Raytrace,
            EngineKind::Path,
            EngineKind::Radiosity,
            EngineKind::Photon,
        ]
        .map(|e| (k, e))
    }) {
        let reference = render(engine, &base, kind, &s);
        for factor in [1e-30f32, 1e30] {
            let mut scene = base.clone();
            for m in &mut scene.materials {
                m.emitted *= factor;
            }
            // What the camera sees past the walls scales too.
            scene.background *= factor;
            let mut film = render(engine, &scene, kind, &s);
            assert!(all_finite(&film), "{kind}: {engine} × {factor:e}");
            film.pixels.iter_mut().for_each(|p| *p /= factor);
            let m = metrics::compare(&film, &reference).expect("same size");
            println!(
                "{kind}: {engine}, emitted × {factor:e}: relMSE {:.2e}",
                m.relmse
            );
            assert!(m.relmse < 1e-6, "{kind}: {engine} × {factor:e}: {m:?}");
        }
    }
}

/// Albedo exactly 0 and exactly 1 under the square light: the floor shows ρ·Le·F (F =
/// 0.239456) for the ray tracer and the path tracer.
#[test]
fn albedo_zero_and_one_under_a_square_light() {
    let le = 10.0f32;
    for rho in [0.0f32, 1.0] {
        let scene = square_light(le, rho);
        let truth = (rho * le) as f64 * 0.239456;
        for engine in [EngineKind::Raytrace, EngineKind::Path] {
            let s = RenderSettings {
                width: 4,
                height: 4,
                num_shadow_samples: 256,
                num_antialias_samples: if engine == EngineKind::Path { 2048 } else { 4 },
                ambient_light: Vec3::ZERO,
                quiet: true,
                ..RenderSettings::default()
            };
            for kind in backends() {
                let film = render(engine, &scene, kind, &s);
                let mean =
                    film.pixels.iter().map(|p| p.x as f64).sum::<f64>() / film.pixels.len() as f64;
                println!("{kind}: ρ = {rho}, {engine}: {mean:.5} against {truth:.5}");
                assert!(
                    (mean - truth).abs() <= 0.01 * truth.max(1e-9),
                    "{kind}: {engine} ρ = {rho}: {mean}"
                );
            }
        }
    }
}

/// Geometry extremes: spheres of radius 1e-4 and 1e4 and a ring whose wall is 1e-4 of its
/// radius thick are hit where the closed form says, by both Accels; a ray through the middle of
/// the ring passes.
#[test]
fn tiny_and_huge_spheres_and_a_paper_thin_ring() {
    for r in [1e-4f32, 1e4] {
        let text =
            format!("material\ndiffuse 0.5 0.5 0.5\nm 0\ns 0 0 0 {r}\nbackground_color 0 0 0\n");
        let scene = Scene::parse_dialect(Path::new("sphere.obj"), &text).expect("parses");
        for kind in backends() {
            let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
            for (origin, dir) in [
                (vec3(0.0, 0.0, 10.0 * r), vec3(0.0, 0.0, -1.0)),
                (vec3(3.0 * r, 0.3 * r, 0.2 * r), vec3(-1.0, 0.0, 0.0)),
            ] {
                let hit = trilux::accel::closest_surface(
                    accel.as_ref(),
                    &scene,
                    &trilux::geometry::Ray::new(origin, dir),
                )
                .expect("hits");
                let off = (hit.point.length() / r - 1.0).abs();
                assert!(
                    off < 1e-4,
                    "radius {r} ({kind}): {:?} off by {off}",
                    hit.point
                );
            }
        }
    }
    let (r_out, h) = (1.0f32, 0.5f32);
    let r_in = r_out * (1.0 - 1e-4);
    let text = format!(
        "material\ndiffuse 0.5 0.5 0.5\nm 0\nr 0 0 0 {h} {r_in} {r_out}\nbackground_color 0 0 0\n"
    );
    let scene = Scene::parse_dialect(Path::new("ring.obj"), &text).expect("parses");
    for kind in backends() {
        let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
        let down = vec3(0.0, -1.0, 0.0);
        let on_cap = vec3(0.5 * (r_in + r_out), 2.0, 0.0);
        let hit = trilux::accel::closest_surface(
            accel.as_ref(),
            &scene,
            &trilux::geometry::Ray::new(on_cap, down),
        )
        .expect("the top annulus, 1e-4 wide, is hit");
        assert!((hit.point.y - h).abs() < 1e-5, "{kind}: {:?}", hit.point);
        let through = trilux::accel::closest_surface(
            accel.as_ref(),
            &scene,
            &trilux::geometry::Ray::new(vec3(0.0, 2.0, 0.0), down),
        );
        assert!(through.is_none(), "{kind}: the hole is open");
        let side = trilux::accel::closest_surface(
            accel.as_ref(),
            &scene,
            &trilux::geometry::Ray::new(vec3(3.0, 0.25, 0.0), vec3(-1.0, 0.0, 0.0)),
        )
        .expect("the outer wall");
        assert!(
            (side.point.x - r_out).abs() < 1e-5,
            "{kind}: {:?}",
            side.point
        );
    }
}

/// Huge requests are refused before anything is allocated, with the estimate in the message.
#[test]
fn huge_requests_are_refused_with_a_clear_message() {
    let scene = common::own_scene_dir().join("cornell_box_diffuse_sphere.obj");
    let scene = scene.to_string_lossy().into_owned();
    // The largest image -size accepts (65536², 48 GiB of film) against an explicit limit, so
    // that the case does not depend on the host's memory.
    let cases: [&[&str]; 3] = [
        &["-num_photons_to_shoot", "1000000000"],
        &["--engine", "radiosity", "--subdivide", "12"],
        &["-size", "65536", "65536", "--max-memory", "8G"],
    ];
    let never = std::env::temp_dir().join("trilux-never-written.png");
    for extra in cases {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
            .args(["-input", &scene, "--quiet", "-o"])
            .arg(&never)
            .args(extra)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        println!("{extra:?}: {}", stderr.trim());
        assert!(!out.status.success(), "{extra:?}");
        assert!(
            stderr.contains("would need about") && stderr.contains("--max-memory"),
            "{extra:?}: {stderr}"
        );
        assert!(
            !never.exists(),
            "{extra:?}: refused, yet an image was written"
        );
    }
    // A small limit refuses an ordinary render too, and names it.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
        .args(["-input", &scene, "--max-memory", "1K", "--quiet", "-o"])
        .arg(std::env::temp_dir().join("trilux-never.png"))
        .output()
        .expect("runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-memory 1.000 KiB"));
}

/// Ctrl-C during a long render writes the image so far (a complete, readable file) and exits
/// non-zero.
#[test]
fn interrupted_render_writes_the_image_so_far() {
    let scene = common::own_scene_dir().join("cornell_box_diffuse_sphere.obj");
    let dir = std::env::temp_dir().join(format!("trilux-sigint-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let output = dir.join("partial.png");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
        .arg("-input")
        .arg(&scene)
        .args([
            "--engine",
            "path",
            "-size",
            "256",
            "256",
            "-num_antialias_samples",
            "2000",
            "--quiet",
            "-o",
        ])
        .arg(&output)
        .spawn()
        .expect("starts");
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(killed.success());
    let status = child.wait().expect("ends");
    assert!(!status.success(), "exit status {status}");
    let image = image::open(&output).expect("the partial image is a readable PNG");
    assert_eq!((image.width(), image.height()), (256, 256));
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .expect("lists")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Samples that overflow (emitted radiance near f32's largest, 3e38) never reach the image:
/// each is counted, left out, and the render's statistics report them.
#[test]
fn non_finite_samples_are_counted_and_left_out() {
    let dir = common::own_scene_dir();
    let mut scene = Scene::load(&dir.join("cornell_box_diffuse_sphere.obj")).expect("loads");
    for m in scene
        .materials
        .iter_mut()
        .filter(|m| m.emitted.max_element() > 0.0)
    {
        m.emitted = Vec3::splat(3e38);
    }
    let s = RenderSettings {
        width: 16,
        height: 16,
        num_shadow_samples: 4,
        num_antialias_samples: 4,
        quiet: true,
        ..RenderSettings::default()
    };
    for kind in backends() {
        let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
        for engine in [EngineKind::Raytrace, EngineKind::Path] {
            let r = engines::render(engine, &scene, accel.as_ref(), &s).expect("renders");
            let counted = r
                .stats
                .non_finite_samples
                .load(std::sync::atomic::Ordering::Relaxed);
            println!("{kind}: {engine}: {counted} non-finite samples left out");
            assert!(all_finite(&r.film), "{kind}: {engine}");
            assert!(counted > 0, "{kind}: {engine}");
        }
    }
}
