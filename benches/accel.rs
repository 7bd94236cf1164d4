//! Criterion benchmarks of the Accel backends: closest-hit and occlusion queries, single and
//! batched, on incoherent rays over a generated terrain, and the build of each backend.
//! `render bench-accel` gives the full table (camera rays, threads, the C baseline).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

use trilux::accel::{self, AccelKind, AccelOptions};
use trilux::bench::{incoherent_rays, occlusion_rays, trace, Mode, Query};
use trilux::generate::terrain;

const TRIANGLES: usize = 200_000;
const RAYS: usize = 100_000;

fn backends() -> Vec<AccelKind> {
    let mut kinds = vec![AccelKind::Bvh];
    if cfg!(feature = "embree") {
        kinds.insert(0, AccelKind::Embree);
    }
    kinds
}

fn queries(c: &mut Criterion) {
    trilux::parallel::worker_start();
    let scene = terrain(TRIANGLES);
    let rays = incoherent_rays(&scene, RAYS, 1);
    let shadow = occlusion_rays(&scene, &rays, 2);
    let mut group = c.benchmark_group("terrain_incoherent");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.sample_size(10);
    for kind in backends() {
        let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("build");
        for (query, name, set) in [
            (Query::Closest, "closest", &rays),
            (Query::Occluded, "occluded", &shadow),
        ] {
            for (mode, mname) in [(Mode::Single, "single"), (Mode::Batched, "batched")] {
                group.bench_with_input(
                    BenchmarkId::new(format!("{kind}/{name}/{mname}"), RAYS),
                    set,
                    |b, set| b.iter(|| trace(accel.as_ref(), set, query, mode, false)),
                );
            }
        }
    }
    group.finish();
}

fn builds(c: &mut Criterion) {
    let scene = terrain(TRIANGLES);
    let mut group = c.benchmark_group("terrain_build");
    group.sample_size(10);
    for kind in backends() {
        group.bench_function(kind.to_string(), |b| {
            b.iter(|| accel::build(&scene, kind, &AccelOptions::default()).expect("build"))
        });
    }
    group.finish();
}

criterion_group!(benches, queries, builds);
criterion_main!(benches);
