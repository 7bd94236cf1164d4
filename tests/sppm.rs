//! Stochastic progressive photon mapping (`--engine sppm`): the furnace (a closed
//! box of albedo ρ emitting 1 has radiance 1/(1−ρ) everywhere), convergence to the path
//! tracer's image as passes grow, and a tile equal to the same pixels of the whole image.

mod common;

use trilux::accel::{self, AccelOptions};
use trilux::engines::{self, EngineKind, RenderSettings};
use trilux::film::part::Window;
use trilux::film::{metrics, Film};
use trilux::geometry::Vec3;
use trilux::scene::Scene;

fn render(engine: EngineKind, scene: &Scene, s: &RenderSettings) -> Film {
    let accel =
        accel::build(scene, common::backends()[0], &AccelOptions::default()).expect("builds");
    engines::render(engine, scene, accel.as_ref(), s)
        .expect("renders")
        .film
}

fn sppm(width: u32, passes: u32, photons: u64) -> RenderSettings {
    let mut s = RenderSettings {
        width,
        height: width,
        num_antialias_samples: passes,
        quiet: true,
        ..RenderSettings::default()
    };
    s.photon.sppm_photons = Some(photons);
    s
}

/// The furnace at ρ = 0.5 and 0.9 (16×16 pixels, 32 passes of 100,000 photons): the image's
/// mean within 1% of 1/(1−ρ) (measured within 0.34% over seeds 0–3), and
/// no pixel 12% off (measured at most 8.1%: the noise of 32 passes, where a photon lost or
/// doubled at the walls' edges would show as a band).
#[test]
fn sppm_furnace_has_radiance_le_over_one_minus_rho() {
    for rho in [0.5f32, 0.9] {
        let film = render(
            EngineKind::Sppm,
            &common::furnace(rho),
            &sppm(16, 32, 100_000),
        );
        let truth = 1.0 / (1.0 - rho);
        let mean = film.pixels.iter().map(|p| p.x as f64).sum::<f64>() / 256.0;
        let worst = common::worst_relative_error(&film.pixels, truth);
        println!("ρ = {rho}: mean {mean:.4} against {truth:.4}, worst pixel {worst:.2e}");
        assert!(
            (mean / truth as f64 - 1.0).abs() < 0.01,
            "ρ = {rho}: mean {mean}"
        );
        assert!(worst < 0.12, "ρ = {rho}: worst pixel {worst}");
    }
}

/// On the Cornell box with the diffuse sphere (24×24), against the path tracer at 16,384
/// paths a pixel: SPPM's relMSE falls as passes double from 8 to 256, with a fitted slope
/// steeper than −0.5, where a photon map of fixed radius levels off at its bias.
#[test]
fn sppm_converges_to_the_path_tracer() {
    let scene = common::own_scene("cornell_box_diffuse_sphere.obj");
    let reference = render(
        EngineKind::Path,
        &scene,
        &RenderSettings {
            width: 24,
            height: 24,
            num_antialias_samples: 16_384,
            quiet: true,
            ..RenderSettings::default()
        },
    );
    let passes = [8u32, 16, 32, 64, 128, 256];
    let errors: Vec<f64> = passes
        .iter()
        .map(|&n| {
            let film = render(EngineKind::Sppm, &scene, &sppm(24, n, 4096));
            let m = metrics::compare(&film, &reference).expect("same size");
            println!("{n} passes: relMSE {:.3e}", m.relmse);
            m.relmse
        })
        .collect();
    let slope = common::log_log_slope(&passes[2..], &errors[2..]);
    println!("slope over the last decade: {slope:.2}");
    assert!(slope < -0.5, "relMSE falls as passes^{slope:.2}");
    assert!(errors[5] < errors[0] / 4.0, "{errors:?}");
}

/// A window of the image is the same pixels as the whole render (each pixel's radius and
/// flux depend on its own samples and the photons alone), so SPPM farms out by tiles.
#[test]
fn an_sppm_tile_is_the_same_pixels_as_the_whole_image() {
    let scene = common::own_scene("cornell_box_reflective_sphere.obj");
    let whole = render(EngineKind::Sppm, &scene, &sppm(32, 4, 20_000));
    let window = Window {
        x0: 5,
        y0: 9,
        x1: 21,
        y1: 30,
    };
    let tile = render(
        EngineKind::Sppm,
        &scene,
        &RenderSettings {
            window: Some(window),
            ..sppm(32, 4, 20_000)
        },
    );
    for row in 0..32 {
        for x in 0..32 {
            let expected = if window.contains(x, row) {
                whole.get(x, row)
            } else {
                Vec3::ZERO
            };
            assert_eq!(tile.get(x, row), expected, "({x}, {row})");
        }
    }
}
