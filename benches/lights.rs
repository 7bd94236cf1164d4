//! Next-event estimation's point on a rectangular light, as the path tracer, the ray tracer
//! and SPPM make it from a shading point: by solid angle (`SphericalRectangle::new` and
//! `sample_cosine`, the default), the density MIS asks of it (`pdf_cosine`), and by area
//! (`--light-sampling random`) for scale. Shading points are spread over the course's Cornell
//! box's walls, as its paths' vertices are, and the light is its wall at z = 1.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use trilux::geometry::{vec3, Vec3};
use trilux::render::solid_angle::SphericalRectangle;
use trilux::sampling::Rng;

const N: usize = 4096;

/// Shading points on the box's five other walls, each with the wall's inward normal, and a
/// (u, v) for its sample.
fn places() -> Vec<(Vec3, Vec3, f32, f32)> {
    (0..N as u64)
        .map(|k| {
            let mut rng = Rng::new(1, k, 0);
            let (a, b) = (rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0 - 1.0);
            let (point, normal) = match k % 5 {
                0 => (vec3(a, b, -1.0), Vec3::Z),
                1 => (vec3(a, -1.0, b), Vec3::Y),
                2 => (vec3(a, 1.0, b), Vec3::NEG_Y),
                3 => (vec3(-1.0, a, b), Vec3::X),
                _ => (vec3(1.0, a, b), Vec3::NEG_X),
            };
            (point, normal, rng.next_f32(), rng.next_f32())
        })
        .collect()
}

/// The course box's light: the whole wall at z = 1, facing into the box.
const CORNER: Vec3 = vec3(-1.0, -1.0, 1.0);
const EDGE_U: Vec3 = vec3(2.0, 0.0, 0.0);
const EDGE_V: Vec3 = vec3(0.0, 2.0, 0.0);

/// The sum over `places` of what `f` makes of each.
fn total(
    places: &[(Vec3, Vec3, f32, f32)],
    f: impl Fn(Vec3, Vec3, f32, f32) -> Option<f64>,
) -> f64 {
    places
        .iter()
        .filter_map(|&(x, n, u, v)| f(x, n, u, v))
        .sum()
}

fn lights(c: &mut Criterion) {
    let places = places();
    let mut g = c.benchmark_group("rectangle_light");
    g.throughput(Throughput::Elements(N as u64));
    let rectangle = |x: Vec3| SphericalRectangle::new(x, CORNER, EDGE_U, EDGE_V);
    g.bench_function("solid_angle_sample", |b| {
        b.iter(|| {
            total(&places, |x, n, u, v| {
                let s = rectangle(x)?.sample_cosine(n, u, v)?;
                Some(s.weight + s.pdf + s.point.x as f64)
            })
        })
    });
    g.bench_function("solid_angle_pdf", |b| {
        b.iter(|| {
            total(&places, |x, n, u, v| {
                Some(rectangle(x)?.pdf_cosine(n, CORNER + EDGE_U * u + EDGE_V * v))
            })
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
                let cos_light = w.z / r2.sqrt();
                if cos > 0.0 && cos_light > 0.0 {
                    sum += cos * cos_light * 4.0 / (std::f32::consts::PI * r2);
                }
            }
            sum
        })
    });
    g.finish();
}

criterion_group!(benches, lights);
criterion_main!(benches);
