//! glam's `Vec3` (what trilux uses) against its 16-byte-aligned `Vec3A` on the kind of loop
//! the engines spend their time in: ray–triangle tests (Möller–Trumbore) and the area-light
//! geometric term of the ray tracer's shadow loop. The same source is instantiated for each
//! type by a macro, so the comparison is of the types alone. A hand-written `Vec3` as a third
//! arm ran at the same speed as glam's `Vec3`, which is why trilux uses glam's.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};

const N: usize = 4096;

/// Hash-based uniform numbers in [0, 1): the same inputs for every type.
fn u(i: u64) -> f32 {
    let mut x = i.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x2545_f491_4f6c_dd1d;
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

macro_rules! kernels {
    ($name:ident, $v:ty, $new:expr) => {
        mod $name {
            type V = $v;
            fn v(x: f32, y: f32, z: f32) -> V {
                $new(x, y, z)
            }

            pub struct Data {
                origins: Vec<V>,
                dirs: Vec<V>,
                tris: Vec<[V; 3]>,
                normals: Vec<V>,
            }

            pub fn data() -> Data {
                let r = |k: usize, c: u64| super::u((k as u64) * 16 + c) * 2.0 - 1.0;
                Data {
                    origins: (0..super::N)
                        .map(|k| v(r(k, 0), r(k, 1), r(k, 2) - 3.0))
                        .collect(),
                    dirs: (0..super::N)
                        .map(|k| v(r(k, 3) * 0.3, r(k, 4) * 0.3, 1.0))
                        .collect(),
                    tris: (0..super::N)
                        .map(|k| {
                            [
                                v(r(k, 5), r(k, 6), 0.0),
                                v(r(k, 7) + 1.0, r(k, 8), 0.1),
                                v(r(k, 9), r(k, 10) + 1.0, -0.1),
                            ]
                        })
                        .collect(),
                    normals: (0..super::N).map(|k| v(r(k, 11), r(k, 12), 1.0)).collect(),
                }
            }

            /// Möller–Trumbore: hits of every ray against its triangle.
            pub fn triangles(d: &Data) -> f32 {
                let mut sum = 0.0;
                for k in 0..d.origins.len() {
                    let (o, dir, [a, b, c]) = (d.origins[k], d.dirs[k], d.tris[k]);
                    let (e1, e2) = (b - a, c - a);
                    let p = dir.cross(e2);
                    let det = e1.dot(p);
                    if det.abs() < 1e-12 {
                        continue;
                    }
                    let inv = 1.0 / det;
                    let s = o - a;
                    let bu = s.dot(p) * inv;
                    let q = s.cross(e1);
                    let bv = dir.dot(q) * inv;
                    if bu >= 0.0 && bv >= 0.0 && bu + bv <= 1.0 {
                        sum += e2.dot(q) * inv;
                    }
                }
                sum
            }

            /// cos θ · cos θ' / r² between points and points on a light, as the shadow loop.
            pub fn geometric_terms(d: &Data) -> f32 {
                let mut sum = 0.0;
                for k in 0..d.origins.len() {
                    let (x, n) = (d.origins[k], d.normals[k] * (1.0 / d.normals[k].length()));
                    let p = d.tris[k][0] + v(0.0, 0.0, 4.0);
                    let w = p - x;
                    let r2 = w.dot(w);
                    let along_surface = n.dot(w);
                    let along_light = -(v(0.0, 0.0, -1.0)).dot(w);
                    if along_surface > 0.0 && along_light > 0.0 {
                        sum += along_surface * along_light / (r2 * r2);
                    }
                }
                sum
            }
        }
    };
}

kernels!(glam3, glam::Vec3, glam::Vec3::new);
kernels!(glam3a, glam::Vec3A, glam::Vec3A::new);

fn compare(c: &mut Criterion) {
    let mut g = c.benchmark_group("vec3");
    g.throughput(Throughput::Elements(N as u64));
    let (a, b) = (glam3::data(), glam3a::data());
    // The two agree on the answer (the inputs are the same numbers).
    let (x, y) = (glam3::triangles(&a), glam3a::triangles(&b));
    assert!((x - y).abs() <= 1e-3 * x.abs().max(1.0));
    g.bench_function("triangles/glam Vec3", |bch| {
        bch.iter(|| glam3::triangles(std::hint::black_box(&a)))
    });
    g.bench_function("triangles/glam Vec3A", |bch| {
        bch.iter(|| glam3a::triangles(std::hint::black_box(&b)))
    });
    g.bench_function("geometric/glam Vec3", |bch| {
        bch.iter(|| glam3::geometric_terms(std::hint::black_box(&a)))
    });
    g.bench_function("geometric/glam Vec3A", |bch| {
        bch.iter(|| glam3a::geometric_terms(std::hint::black_box(&b)))
    });
    g.finish();
}

criterion_group!(benches, compare);
criterion_main!(benches);
