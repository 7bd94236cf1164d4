//! Next-event estimation's point on a rectangular light, as the path tracer, the ray tracer
//! and SPPM make it from a shading point: by solid angle (`SphericalRectangle::new` and
//! `sample_cosine`, the default), the density MIS asks of it (`pdf_cosine`), and by area
//! (`--light-sampling random`) for scale. Shading points and normals are spread through the
//! course's Cornell box under its ceiling light, as its paths' vertices are.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use trilux::geometry::{vec3, Vec3};
use trilux::render::solid_angle::SphericalRectangle;

const N: usize = 4096;

/// Hash-based uniform numbers in [0, 1).
fn u(i: u64) -> f32 {
    let mut x = i.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x2545_f491_4f6c_dd1d;
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// Shading points in the box below the light, each with a unit normal on the light's side,
/// and a (u, v) for its sample.
fn places() -> Vec<(Vec3, Vec3, f32, f32)> {
    (0..N as u64)
        .map(|k| {
            let r = |c: u64| u(k * 16 + c) * 2.0 - 1.0;
            let point = vec3(r(0), r(1) * 0.99, r(2));
            let mut normal = vec3(r(3), r(4), r(5)).normalize_or(Vec3::Y);
            if normal.y < 0.0 {
                normal.y = -normal.y;
            }
            (point, normal, u(k * 16 + 6), u(k * 16 + 7))
        })
        .collect()
}

/// The course box's light: a 0.5 × 0.5 square in the ceiling (y = 1), facing down.
const CORNER: Vec3 = vec3(-0.25, 1.0, -0.25);
const EDGE_U: Vec3 = vec3(0.5, 0.0, 0.0);
const EDGE_V: Vec3 = vec3(0.0, 0.0, 0.5);

fn lights(c: &mut Criterion) {
    let places = places();
    let mut g = c.benchmark_group("rectangle_light");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("solid_angle_sample", |b| {
        b.iter(|| {
            let mut sum = 0.0f64;
            for &(x, n, u, v) in &places {
                let rect = SphericalRectangle::new(x, CORNER, EDGE_U, EDGE_V);
                if let Some(s) = rect.and_then(|r| r.sample_cosine(n, u, v)) {
                    sum += s.weight + s.pdf + s.point.x as f64;
                }
            }
            sum
        })
    });
    g.bench_function("solid_angle_pdf", |b| {
        b.iter(|| {
            let mut sum = 0.0f64;
            for &(x, n, u, v) in &places {
                let p = CORNER + EDGE_U * u + EDGE_V * v;
                if let Some(r) = SphericalRectangle::new(x, CORNER, EDGE_U, EDGE_V) {
                    sum += r.pdf_cosine(n, p);
                }
            }
            sum
        })
    });
    g.bench_function("area_sample", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(x, n, u, v) in &places {
                let p = CORNER + EDGE_U * u + EDGE_V * v;
                let w = p - x;
                let r2 = w.length_squared();
                let cos = n.dot(w) / r2.sqrt();
                let cos_light = w.y / r2.sqrt();
                if cos > 0.0 && cos_light > 0.0 {
                    sum += cos * cos_light * 0.25 / (std::f32::consts::PI * r2);
                }
            }
            sum
        })
    });
    g.finish();
}

criterion_group!(benches, lights);
criterion_main!(benches);
