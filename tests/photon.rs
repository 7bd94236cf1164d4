//! The photon engine against closed forms: the furnace (a closed cube of albedo ρ whose walls
//! all emit Le = 1 has radiance 1/(1−ρ) everywhere; direct light is ray traced, the rest comes
//! from the global map), the caustic of a mirror ring, the course command lines, and identical
//! images from both Accels.

mod common;

use common::{backends, furnace};
use trilux::accel::{self, AccelOptions};
use trilux::engines::compose::render_photons;
use trilux::engines::photon::{PathKind, PhotonMaps, PhotonSettings};
use trilux::engines::RenderSettings;
use trilux::scene::Scene;

fn settings(photons: u64) -> RenderSettings {
    RenderSettings {
        width: 24,
        height: 24,
        num_shadow_samples: 16,
        num_antialias_samples: 4,
        photon: PhotonSettings {
            num_photons_to_shoot: Some(photons),
            num_photons_to_collect: 100,
            ..Default::default()
        },
        quiet: true,
        ..RenderSettings::default()
    }
}

#[test]
fn furnace_radiance_is_le_over_one_minus_rho() {
    for rho in [0.5f32, 0.9] {
        let scene = furnace(rho);
        let truth = 1.0 / (1.0 - rho as f64);
        for gather in [false, true] {
            let accel =
                accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
            let mut s = settings(400_000);
            s.photon.gather_indirect = gather;
            s.photon.final_gather_rays = 64;
            // Russian roulette alone ends the paths; a depth limit of 10 would lose
            // ρ¹¹/(1−ρ) = 3.1 of the 10 at ρ = 0.9 (measured: −29%).
            s.photon.max_photon_depth = 100_000;
            let (rendered, maps) = render_photons(&scene, accel.as_ref(), &s).expect("renders");
            let film = rendered.film;
            let mean: f64 =
                film.pixels.iter().map(|p| p.x as f64).sum::<f64>() / film.pixels.len() as f64;
            println!(
                "ρ = {rho}, gather {gather}: mean {mean:.4} (exact {truth:.4}, {:+.2}%), global map {} photons, {} cut by the depth limit",
                100.0 * (mean / truth - 1.0),
                maps.global.len(),
                maps.truncated
            );
            assert_eq!(maps.truncated, 0);
            // Measured −0.98% and −0.93% at ρ = 0.5, −0.77% and −0.44% at ρ = 0.9 (direct
            // lookup, final gathering): the density estimate's bias where the k nearest
            // photons reach round the cube's edges. The bound is three times the worst.
            assert!(
                (mean / truth - 1.0).abs() < 0.03,
                "ρ = {rho}, gather {gather}: {mean} vs {truth}"
            );
        }
    }
}

/// The light that the ring's mirror interior reflects onto the floor is stored as caustic
/// photons, inside the ring's footprint.
#[test]
fn mirror_ring_focuses_a_caustic_inside_itself() {
    let dir = common::own_scene_dir();
    let scene = Scene::load(&dir.join("reflective_ring.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let maps = PhotonMaps::build(&scene, accel.as_ref(), &settings(200_000));
    let trilux::geometry::AnalyticShape::Ring(ring) = scene.shapes[0].shape else {
        panic!("reflective_ring.obj's one shape is a ring");
    };
    assert!(
        maps.caustic.len() > 1000,
        "{} caustic photons",
        maps.caustic.len()
    );
    let on_floor_inside = maps
        .caustic
        .photons
        .iter()
        .filter(|p| {
            let (x, z) = (p.position.x - ring.base.x, p.position.z - ring.base.z);
            p.kind == PathKind::Caustic
                && p.position.y < ring.base.y
                && (x * x + z * z).sqrt() < ring.r_in
        })
        .count();
    println!(
        "{on_floor_inside} of {} caustic photons on the floor inside the ring",
        maps.caustic.len()
    );
    // Measured 72.7% (the rest reflect off the ring's outside or its rim onto the floor
    // around it). A bound on where the caustic map's photons go, not on how much light they
    // carry, which `ring_caustic_stands_out_as_in_the_path_tracer` checks against the path
    // tracer: "most of them inside" is the claim, so the bound is a half, not a spread.
    assert!(on_floor_inside * 2 > maps.caustic.len());
}

#[cfg_attr(
    not(feature = "embree"),
    ignore = "compares Embree with the BVH: needs the embree feature"
)]
#[test]
fn both_accels_give_identical_photon_images() {
    let dir = common::own_scene_dir();
    for (file, gather) in [
        ("cornell_box_diffuse_sphere.obj", true),
        ("reflective_ring.obj", false),
    ] {
        let scene = Scene::load(&dir.join(file)).expect("loads");
        let mut s = settings(50_000);
        s.photon.gather_indirect = gather;
        s.photon.final_gather_rays = 32;
        s.num_bounces = 2;
        let images: Vec<Vec<f32>> = backends()
            .into_iter()
            .map(|kind| {
                let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
                let film = render_photons(&scene, accel.as_ref(), &s)
                    .expect("renders")
                    .0
                    .film;
                film.pixels.iter().flat_map(|p| p.to_array()).collect()
            })
            .collect();
        assert_eq!(images[0], images[1], "{file}");
    }
}

/// Where the light of `scenes/glass_sphere_caustic.obj` lands on the floor after passing its
/// glass sphere, from an oracle written apart from the photon tracer: f64, every Fresnel
/// branch followed with its weight instead of one chosen at random. The light (Le = 60, a
/// 0.5 × 0.5 square at y = 4 facing down) sends `samples` rays uniformly into the cone that
/// the sphere (centre (0, 1.2, 0), radius 0.8, n = 1.5) subtends; each glass hit keeps 0.95
/// of the power (`transmitted 0.95`, the rest absorbed). Returns the floor points (x, z)
/// within 1.5 of the point below the sphere with the flux (W) that reaches each, and the flux
/// landing anywhere on the floor more than 2 away from it.
fn glass_sphere_floor_oracle(samples: u64, seed: u64) -> (Vec<(f64, f64, f64)>, f64) {
    use common::vec64::{add, dot, norm, scale, sub, V3};
    let (le, side, light_y) = (60.0, 0.5, 4.0);
    let (centre, radius, ior, kept): (V3, f64, f64, f64) = ([0.0, 1.2, 0.0], 0.8, 1.5, 0.95);
    let mut rng = trilux::sampling::Rng::new(seed, 0, 0);
    let mut uniform = move || rng.next_f32() as f64;
    let fresnel = common::fresnel;
    let (mut near, mut far) = (Vec::new(), 0.0);
    let mut land = |o: V3, d: V3, w: f64| {
        if d[1] < 0.0 {
            let p = add(o, scale(d, -o[1] / d[1]));
            if p[0].abs() <= 4.0 && p[2].abs() <= 4.0 {
                let r = p[0].hypot(p[2]);
                if r < 1.5 {
                    near.push((p[0], p[2], w));
                } else if r > 2.0 {
                    far += w;
                }
            }
        }
    };
    for _ in 0..samples {
        let o = [side * (uniform() - 0.5), light_y, side * (uniform() - 0.5)];
        let to = sub(centre, o);
        let dist = norm(to);
        let axis = scale(to, 1.0 / dist);
        let cos_max = (1.0 - (radius / dist).powi(2)).sqrt();
        let cos_t = 1.0 - uniform() * (1.0 - cos_max);
        let sin_t = (1.0 - cos_t * cos_t).sqrt();
        let phi = std::f64::consts::TAU * uniform();
        // Any basis about the axis: one from the axis and x.
        let t1 = {
            let c = [0.0, axis[2], -axis[1]];
            scale(c, 1.0 / norm(c))
        };
        let t2 = common::vec64::cross(axis, t1);
        let mut d = add(
            scale(axis, cos_t),
            add(scale(t1, sin_t * phi.cos()), scale(t2, sin_t * phi.sin())),
        );
        d = scale(d, 1.0 / norm(d));
        // Flux per sample: Le·A·cosθ·Ω / N, θ from the light's normal (0, −1, 0).
        let solid_angle = std::f64::consts::TAU * (1.0 - cos_max);
        let mut w = le * side * side * (-d[1]) * solid_angle / samples as f64;
        let (mut o, mut inside) = (o, false);
        while w > 1e-12 {
            let f = sub(o, centre);
            let (b, c) = (dot(f, d), dot(f, f) - radius * radius);
            let disc = b * b - c;
            if disc < 0.0 {
                break;
            }
            let t = if inside {
                -b + disc.sqrt()
            } else {
                -b - disc.sqrt()
            };
            if t <= 0.0 {
                break;
            }
            let x = add(o, scale(d, t));
            let outward = scale(sub(x, centre), 1.0 / radius);
            let n = if inside {
                scale(outward, -1.0)
            } else {
                outward
            };
            let (eta_i, eta_t) = if inside { (ior, 1.0) } else { (1.0, ior) };
            let cos_i = -dot(d, n);
            let reflectance = fresnel(cos_i, eta_i, eta_t);
            w *= kept;
            let reflected = add(d, scale(n, 2.0 * cos_i));
            let eta = eta_i / eta_t;
            let cos_out = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).max(0.0).sqrt();
            let refracted = add(scale(d, eta), scale(n, eta * cos_i - cos_out));
            // Outside, the reflected branch leaves and the refracted one goes in; inside, the
            // refracted branch leaves and the reflected one stays.
            let (leaving, staying, w_leaving, w_staying) = if inside {
                (
                    refracted,
                    reflected,
                    w * (1.0 - reflectance),
                    w * reflectance,
                )
            } else {
                (
                    reflected,
                    refracted,
                    w * reflectance,
                    w * (1.0 - reflectance),
                )
            };
            if w_leaving > 0.0 {
                land(x, scale(leaving, 1.0 / norm(leaving)), w_leaving);
            }
            (o, d, w, inside) = (x, scale(staying, 1.0 / norm(staying)), w_staying, true);
        }
    }
    (near, far)
}

/// trilux's glass-sphere scene: the caustic the sphere focuses onto the floor below it,
/// against the f64 oracle above. The photons' flux into a disk below the sphere, and the
/// photon map's cone-filtered estimate there (at the radius its 2,000 nearest photons span,
/// the oracle's landing points filtered by the same cone), each agree with the oracle; the
/// caustic map holds as much far from the sphere as the oracle says reaches there (grazing
/// reflections off its rim).
///
/// Bounds from the spread over photon seeds 0–8 (oracle seeds 1 and 10–17, whose own spread
/// is 0.08% in the disk and 0.2% far away): the disk's flux is off by +0.1% on average with a
/// standard deviation of 1.0% (about 24,000 photons land in it), the estimate from the 2,000
/// nearest photons by +2.3% ± 3.4%, the far floor's flux by −1.5% ± 1.6% (the f32 tracer
/// loses a sliver of the grazing rays at the cone's rim). Each bound is the mean's offset
/// plus four standard deviations. Leaving out the glass's 0.95 per hit moves the disk by
/// +11%; the estimator without its cone normalisation is 2.5× off.
#[test]
fn glass_sphere_caustic_matches_an_independent_oracle() {
    let scene = common::own_scene("glass_sphere_caustic.obj");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let maps = PhotonMaps::build(&scene, accel.as_ref(), &settings(300_000));
    let (oracle, oracle_far) = glass_sphere_floor_oracle(4_000_000, 1);
    let up = trilux::geometry::vec3(0.0, 1.0, 0.0);
    let below = trilux::geometry::vec3(0.0, 0.0, 0.0);
    let disk = 0.1f64;
    let on_floor: Vec<_> = maps
        .caustic
        .photons
        .iter()
        .filter(|p| p.position.y.abs() < 1e-4)
        .collect();
    let in_disk: Vec<_> = on_floor
        .iter()
        .filter(|p| (p.position.x as f64).hypot(p.position.z as f64) < disk)
        .collect();
    let photon_disk: f64 = in_disk.iter().map(|p| p.power.x as f64).sum();
    let oracle_disk: f64 = oracle
        .iter()
        .filter(|&&(x, z, _)| x.hypot(z) < disk)
        .map(|&(_, _, w)| w)
        .sum();
    let (estimate, lookup) = maps
        .caustic
        .irradiance_over_pi(below, up, 2000, maps.max_radius);
    let r = lookup.radius as f64;
    // The map's estimator Σ Φ·(1 − d/(1.1 r)) / ((1 − 2/3.3)·π r²) / π, over the oracle's points.
    let oracle_estimate = oracle
        .iter()
        .filter(|&&(x, z, _)| x.hypot(z) < r)
        .map(|&(x, z, w)| w * (1.0 - x.hypot(z) / (1.1 * r)))
        .sum::<f64>()
        / ((1.0 - 2.0 / 3.3) * std::f64::consts::PI * r * r * std::f64::consts::PI);
    let photon_far: f64 = on_floor
        .iter()
        .filter(|p| (p.position.x as f64).hypot(p.position.z as f64) > 2.0)
        .map(|p| p.power.x as f64)
        .sum();
    println!(
        "flux into the disk r = {disk}: photons {photon_disk:.5} W ({} photons), oracle {oracle_disk:.5} W ({:+.2}%); estimate at r = {r:.4}: {:.4} against the oracle's {oracle_estimate:.4} ({:+.2}%); floor beyond 2: photons {photon_far:.5} W, oracle {oracle_far:.5} W",
        in_disk.len(),
        100.0 * (photon_disk / oracle_disk - 1.0),
        estimate.x,
        100.0 * (estimate.x as f64 / oracle_estimate - 1.0)
    );
    assert!((photon_disk / oracle_disk - 1.0).abs() < 0.045);
    assert!((estimate.x as f64 / oracle_estimate - 1.0).abs() < 0.16);
    assert!((photon_far / oracle_far - 1.0).abs() < 0.08);
}

/// Mean of a film's pixels over those selected, per channel.
fn mean_over(film: &trilux::film::Film, pixels: &[usize]) -> trilux::geometry::Vec3 {
    let sum = pixels
        .iter()
        .fold(trilux::geometry::Vec3::ZERO, |a, &k| a + film.pixels[k]);
    sum / pixels.len().max(1) as f32
}

/// For each pixel (film order, rows from the top), the floor point its centre ray hits.
fn floor_points(
    scene: &Scene,
    accel: &dyn trilux::accel::Accel,
    w: u32,
    h: u32,
    floor_y: f32,
) -> Vec<Option<trilux::geometry::Vec3>> {
    let camera = scene.camera();
    let mut out = vec![None; (w * h) as usize];
    for j in 0..h {
        for i in 0..w {
            let (x, y) = trilux::scene::Camera::screen_point(i, j, 0.5, 0.5, w, h);
            let hit = trilux::accel::closest_surface(accel, scene, &camera.generate_ray(x, y));
            if let Some(s) = hit.filter(|s| (s.point.y - floor_y).abs() < 1e-3) {
                out[((h - 1 - j) * w + i) as usize] = Some(s.point);
            }
        }
    }
    out
}

/// Every photon stored on a diffuse surface, first hits included, carries in all the emitted
/// power times 1/(1−ρ) in the furnace: each unit of light is stored once per bounce.
#[test]
fn stored_power_is_emitted_power_over_one_minus_rho() {
    let scene = furnace(0.5);
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let mut s = settings(400_000);
    s.photon.gather_indirect = true; // the global map then keeps every photon
    s.photon.max_photon_depth = 100_000;
    let maps = PhotonMaps::build(&scene, accel.as_ref(), &s);
    let stored: f64 = maps.global.photons.iter().map(|p| p.power.x as f64).sum();
    let emitted = std::f64::consts::PI * 24.0; // π·Le·A over the six faces of side 2
    let expected = emitted / (1.0 - 0.5);
    println!(
        "stored {stored:.3}, expected {expected:.3} ({:+.3}%)",
        100.0 * (stored / expected - 1.0)
    );
    // Roulette at ρ = 0.5 stores a photon a geometric number of times (mean 2, variance 2),
    // so the total's relative standard deviation is √(2/N)/2 = 0.11% at N = 400,000.
    // Measured +0.11%; the bound is four standard deviations.
    assert!((stored / expected - 1.0).abs() < 4.5e-3);
}

/// No stored photon is black. On the course's Cornell box a photon the red wall (1, 0, 0) left
/// red carries nothing after the blue wall (0, 0, 1), yet roulette at a pure-coloured wall
/// keeps it with probability 1: were it to go on, it would be stored at every bounce
/// as zeros that took places among each lookup's k nearest (a third of the photon rays at
/// 200,000 photons; the photon image's relMSE against a converged reference is 6.5e-3 with
/// them, and 4.7e-3 without).
#[test]
fn no_stored_photon_is_black() {
    let dir = common::own_scene_dir();
    let scene = Scene::load(&dir.join("cornell_box_diffuse_sphere.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let mut s = settings(100_000);
    s.photon.gather_indirect = true; // the global map then keeps every photon
    let maps = PhotonMaps::build(&scene, accel.as_ref(), &s);
    assert!(maps.global.photons.len() > 100_000);
    let black = maps
        .global
        .photons
        .iter()
        .filter(|p| p.power.max_element() <= 0.0)
        .count();
    assert_eq!(black, 0, "of {} photons", maps.global.photons.len());
}

/// Colour bleeding: the floor by the red wall is redder (R/B) than the floor by the blue
/// wall, and by more than in the ray tracer with its grey ambient light.
#[test]
fn floor_bleeds_the_colour_of_the_nearest_wall() {
    let dir = common::own_scene_dir();
    let scene = Scene::load(&dir.join("cornell_box_diffuse_sphere.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let (w, h) = (48u32, 48u32);
    let floor = floor_points(&scene, accel.as_ref(), w, h, -1.0);
    let near = |red: bool| -> Vec<usize> {
        (0..floor.len())
            .filter(|&k| floor[k].is_some_and(|p| if red { p.x < -0.6 } else { p.x > 0.6 }))
            .collect()
    };
    let (by_red, by_blue) = (near(true), near(false));
    let r_over_b = |film: &trilux::film::Film, pixels: &[usize]| {
        let m = mean_over(film, pixels);
        m.x / m.z
    };
    let mut s = settings(500_000);
    s.width = w;
    s.height = h;
    let photons = render_photons(&scene, accel.as_ref(), &s)
        .expect("renders")
        .0
        .film;
    let traced = trilux::engines::raytrace::render(&scene, accel.as_ref(), &s).0;
    let bleed_photons = r_over_b(&photons, &by_red) / r_over_b(&photons, &by_blue);
    let mut p = s.clone();
    p.num_antialias_samples = 256;
    let path = trilux::engines::path::render(&scene, accel.as_ref(), &p).0;
    let bleed_path = r_over_b(&path, &by_red) / r_over_b(&path, &by_blue);
    let bleed_traced = r_over_b(&traced, &by_red) / r_over_b(&traced, &by_blue);
    println!(
        "R/B by the red wall over R/B by the blue wall: photons {bleed_photons:.3}, ray tracer with ambient {bleed_traced:.3} ({} and {} pixels)",
        by_red.len(),
        by_blue.len()
    );
    println!("the path tracer's, at 256 paths a pixel: {bleed_path:.3}");
    assert!(by_red.len() > 20 && by_blue.len() > 20);
    assert!(bleed_photons > bleed_traced);
    // Measured over seeds 0, 1, 2: the path tracer 3.58, 3.57, 3.74 (spread 2.6% a seed),
    // the photons 3.53, 3.45, 3.43 (the density estimate's blur: 1–8% under). Bound: four
    // standard deviations of the path tracer's (10%), plus 2% for the photons' bias.
    assert!(
        (bleed_photons / bleed_path - 1.0).abs() < 0.12,
        "photons {bleed_photons} against the path tracer's {bleed_path}"
    );
}

/// Both Accels store the same photons, bit for bit, for the same seed.
#[cfg_attr(
    not(feature = "embree"),
    ignore = "compares Embree with the BVH: needs the embree feature"
)]
#[test]
fn both_accels_give_identical_photon_maps() {
    let dir = common::own_scene_dir();
    for file in ["cornell_box_reflective_sphere.obj", "reflective_ring.obj"] {
        let scene = Scene::load(&dir.join(file)).expect("loads");
        let maps: Vec<PhotonMaps> = backends()
            .into_iter()
            .map(|kind| {
                let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
                PhotonMaps::build(&scene, accel.as_ref(), &settings(200_000))
            })
            .collect();
        assert!(!maps[0].global.photons.is_empty() || !maps[0].caustic.photons.is_empty());
        assert_eq!(maps[0].global.photons, maps[1].global.photons, "{file}");
        assert_eq!(maps[0].caustic.photons, maps[1].caustic.photons, "{file}");
    }
}

/// The course's ring caustic, seen from above with the floor's wood texture replaced by a
/// uniform grey (the grain alone makes regions of the floor twice as bright as their
/// surroundings): the brightest small region inside the ring stands out from the floor around
/// it with photons, as much as in the unbiased path tracer's image, and not with photons off.
///
/// Not 3×, as one might expect: the path tracer, which agrees with the photon image within 2% over
/// the whole view, puts this scene's caustic at about 2× its surroundings: the 2×2 light
/// blurs the cusp over about a unit of floor.
///
/// Bounds from seeds 0–9 (photons and path tracer alike): the photons' contrast over the path
/// tracer's is −2.6% ± 4.3% (the brightest-region search picks up each image's noise: 1.93
/// ± 0.05 against 1.98 ± 0.06), the photons' level in the 9 × 9 pixels around the path
/// tracer's brightest region −0.4% ± 2.9% of the path tracer's; each bound is the mean's
/// offset plus four standard deviations. Without photons the contrast is the direct light's
/// own, 1.20 ± 0.003: the bound of 1.25 says "no caustic" (the path tracer's is 1.98), it is
/// not a spread.
#[test]
fn ring_caustic_stands_out_as_in_the_path_tracer() {
    let dir = common::own_scene_dir();
    let mut scene = Scene::load(&dir.join("reflective_ring.obj")).expect("loads");
    for m in scene.materials.iter_mut().filter(|m| m.texture.is_some()) {
        m.texture = None;
        m.diffuse = trilux::geometry::vec3(0.5, 0.5, 0.5);
    }
    let trilux::geometry::AnalyticShape::Ring(ring) = scene.shapes[0].shape else {
        panic!("reflective_ring.obj's one shape is a ring");
    };
    let centre = trilux::geometry::vec3(ring.base.x, -1.0, ring.base.z);
    scene.camera = Some(trilux::scene::Camera {
        position: centre + trilux::geometry::vec3(0.0, 30.0, 0.0),
        point_of_interest: centre,
        up: trilux::geometry::vec3(0.0, 0.0, -1.0),
        projection: trilux::scene::Projection::Orthographic {
            size: 2.0 * ring.r_out,
        },
    });
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    // 11.7 pixels per unit: the region is 5×5 pixels (0.4 units), the floor around it the
    // pixels 5 to 7 pixels from its centre (a frame 0.4 to 0.6 units away).
    let (w, h) = (96u32, 96u32);
    let floor = floor_points(&scene, accel.as_ref(), w, h, -1.0);
    let inside = |k: usize| floor[k].is_some_and(|p| (p - centre).length() < ring.r_in - 0.05);
    let square = |i: usize, j: usize, r: usize| -> Vec<usize> {
        (j - r..=j + r)
            .flat_map(|y| (i - r..=i + r).map(move |x| y * w as usize + x))
            .collect()
    };
    let luminance = |c: trilux::geometry::Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    // The brightest region's contrast with the floor around it, and where it is.
    let contrast = |film: &trilux::film::Film| {
        let mut best = (0.0f32, 0, 0);
        for j in 7..h as usize - 7 {
            for i in 7..w as usize - 7 {
                let outer = square(i, j, 7);
                if !outer.iter().all(|&k| inside(k)) {
                    continue;
                }
                let middle = square(i, j, 4);
                let around: Vec<usize> =
                    outer.into_iter().filter(|k| !middle.contains(k)).collect();
                let region = luminance(mean_over(film, &square(i, j, 2)));
                let c = region / luminance(mean_over(film, &around));
                if c > best.0 {
                    best = (c, i, j);
                }
            }
        }
        best
    };
    let mut s = settings(500_000);
    (s.width, s.height) = (w, h);
    s.num_bounces = 2;
    s.num_shadow_samples = 10;
    let with_photons = render_photons(&scene, accel.as_ref(), &s)
        .expect("renders")
        .0
        .film;
    let without = trilux::engines::raytrace::render(&scene, accel.as_ref(), &s).0;
    s.num_antialias_samples = 1024;
    let reference = trilux::engines::path::render(&scene, accel.as_ref(), &s).0;
    let (on, off, path) = (
        contrast(&with_photons),
        contrast(&without),
        contrast(&reference),
    );
    let caustic = square(path.1, path.2, 4);
    let (photon_level, path_level) = (
        luminance(mean_over(&with_photons, &caustic)),
        luminance(mean_over(&reference, &caustic)),
    );
    println!(
        "brightest region inside the ring over the floor around it: photons {:.2} at ({}, {}), photons off {:.2}, path tracer {:.2} at ({}, {}); the path tracer's region: photons {photon_level:.4}, path {path_level:.4}",
        on.0, on.1, on.2, off.0, path.0, path.1, path.2
    );
    assert!(off.0 < 1.25, "{off:?}");
    assert!((on.0 / path.0 - 1.0).abs() < 0.2, "{on:?} {path:?}");
    assert!((photon_level / path_level - 1.0).abs() < 0.12);
}

/// Final gathering's first pass puts records wherever the pixel centres need them, so the
/// pixels' samples (jittered, up to 0.7 pixel from the centre the pass checked) are almost all
/// interpolated rather than gathered afresh — the fresh gathers are what made final gathering
/// cost 83 s on this scene when the records were laid on a fixed grid.
#[test]
fn final_gathering_interpolates_almost_every_lookup() {
    let scene = Scene::load(&common::own_scene_dir().join("cornell_box_diffuse_sphere.obj"))
        .expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let mut s = settings(50_000);
    s.width = 128;
    s.height = 128;
    s.photon.gather_indirect = true;
    s.photon.final_gather_rays = 64;
    let (rendered, _) = render_photons(&scene, accel.as_ref(), &s).expect("renders");
    let line = rendered
        .summary
        .iter()
        .find(|l| l.starts_with("irradiance cache"))
        .expect("a cache summary");
    let count = |after: &str| -> u64 {
        let rest = &line[line.find(after).expect(after) + after.len()..];
        rest.trim_start()
            .split(|c: char| !c.is_ascii_digit())
            .next()
            .and_then(|n| n.parse().ok())
            .expect("a number")
    };
    let (interpolated, fresh) = (count("interpolated"), count("afresh"));
    println!("{line}");
    // Lookups happen where a camera sample meets a diffuse surface: 66% of them here.
    assert!(interpolated + fresh >= 128 * 128 * 4 / 2, "{line}");
    // Measured 3.2% (2.0% at 256×256 with 128 rays); with the records on a fixed grid of
    // every 4th pixel, as before, 57%.
    assert!(fresh * 10 < interpolated + fresh, "{line}");
}

/// Final gathering against the photon map's own estimate on the glass-sphere caustic scene,
/// which the camera sees partly through the glass: the two differ only in how the diffuse
/// indirect light is estimated, so the images must agree, through the glass too. With final
/// gathering the global map holds every photon; looked up directly behind the glass it
/// counted direct light and caustics twice, and what the camera saw through the sphere came
/// out too bright (relMSE 2.1e-2 against Mitsuba's reference at 256×256; 6.4e-4 since).
#[test]
fn final_gathering_agrees_with_the_map_behind_glass() {
    let scene =
        Scene::load(&common::own_scene_dir().join("glass_sphere_caustic.obj")).expect("loads");
    let accel = accel::build(&scene, backends()[0], &AccelOptions::default()).expect("builds");
    let mut s = settings(200_000);
    s.width = 64;
    s.height = 64;
    s.num_bounces = 6;
    let (direct_lookup, _) = render_photons(&scene, accel.as_ref(), &s).expect("renders");
    s.photon.gather_indirect = true;
    let (gathered, _) = render_photons(&scene, accel.as_ref(), &s).expect("renders");
    let (a, b) = (&gathered.film, &direct_lookup.film);
    // Mean luminance of each band of 16 rows (the sphere spans the middle two).
    for band in 0..4 {
        let mean = |f: &trilux::film::Film| {
            let rows = &f.pixels[band * 16 * 64..(band + 1) * 16 * 64];
            rows.iter().map(|c| (c.x + c.y + c.z) as f64).sum::<f64>() / rows.len() as f64
        };
        let (g, d) = (mean(a), mean(b));
        println!(
            "rows {}..{}: gathered {g:.4}, map {d:.4}",
            band * 16,
            band * 16 + 16
        );
        // Measured within 0.9% in every band; with the double count, rows 16..32 were 15%
        // too bright.
        assert!((g / d - 1.0).abs() < 0.04, "band {band}: {g} against {d}");
    }
}
