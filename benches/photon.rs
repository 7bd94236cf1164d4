//! Criterion benchmarks of the photon maps: k-nearest density estimates (k = 50 and 500) on the
//! course's Cornell box with the diffuse sphere, 500k photons, at points spread over the floor
//! and back wall, and the build of the kd-trees.

use std::path::Path;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

use trilux::accel::{self, AccelKind, AccelOptions};
use trilux::engines::photon::{PhotonMap, PhotonMaps, PhotonSettings};
use trilux::engines::RenderSettings;
use trilux::geometry::{vec3, Vec3};
use trilux::scene::Scene;

const QUERIES: usize = 1000;

fn lookups(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box_diffuse_sphere.obj");
    let scene = Scene::load(&path).expect("scene loads");
    let accel = accel::build(&scene, AccelKind::Bvh, &AccelOptions::default()).expect("builds");
    let settings = RenderSettings {
        photon: PhotonSettings {
            num_photons_to_shoot: 500_000,
            gather_indirect: true,
            ..Default::default()
        },
        quiet: true,
        ..RenderSettings::default()
    };
    let maps = PhotonMaps::build(&scene, accel.as_ref(), &settings);
    // Points on a grid over the floor (y = −1, normal up) and the back wall (z = −1).
    let points: Vec<(Vec3, Vec3)> = (0..QUERIES)
        .map(|k| {
            let (u, v) = (
                (k % 25) as f32 / 25.0 * 1.8 - 0.9,
                (k / 25 % 20) as f32 / 20.0 * 1.8 - 0.9,
            );
            if k % 2 == 0 {
                (vec3(u, -1.0, v), vec3(0.0, 1.0, 0.0))
            } else {
                (vec3(u, v, -1.0), vec3(0.0, 0.0, 1.0))
            }
        })
        .collect();
    let mut group = c.benchmark_group("photon_lookup");
    group.throughput(Throughput::Elements(QUERIES as u64));
    group.sample_size(10);
    for k in [50usize, 500] {
        group.bench_with_input(BenchmarkId::new("k_nearest", k), &k, |b, &k| {
            b.iter(|| {
                points
                    .iter()
                    .map(|&(x, n)| maps.global.irradiance_over_pi(x, n, k, maps.max_radius).0.x)
                    .sum::<f32>()
            })
        });
    }
    group.finish();
    let photons = maps.global.photons.clone();
    let mut group = c.benchmark_group("photon_build");
    group.throughput(Throughput::Elements(photons.len() as u64));
    group.sample_size(10);
    group.bench_function("kd_tree", |b| {
        b.iter(|| PhotonMap::new(photons.clone()).len())
    });
    group.finish();
}

criterion_group!(benches, lookups);
criterion_main!(benches);
