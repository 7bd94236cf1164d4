//! Sphere and ring intersection for the brute-force oracle, in f64 and written apart from
//! `geometry::shape`: the textbook quadratic rather than the stable form, and each surface of
//! the ring solved on its own. With it, the backends' agreement with brute force covers the
//! shapes' own routines, not only the traversal that calls them.

use trilux::geometry::{AnalyticShape, Ray};

use super::vec64::{dot, of as v, V3 as V};

/// The roots of a t² + b t + c = 0, smaller first (none when a = 0 or the discriminant is
/// negative).
fn roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - 4.0 * a * c;
    (a != 0.0 && disc >= 0.0).then(|| {
        let s = disc.sqrt();
        ((-b - s) / (2.0 * a), (-b + s) / (2.0 * a))
    })
}

/// The nearest t in (`ray.t_min`, `t_max`) at which `ray` meets `shape`.
pub fn hit(shape: &AnalyticShape, ray: &Ray, t_max: f32) -> Option<f64> {
    let (o, d) = (v(ray.origin), v(ray.direction));
    let (t_min, t_max) = (ray.t_min as f64, t_max as f64);
    let inside = |t: f64| t > t_min && t < t_max;
    let at = |t: f64| [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t];
    let mut candidates: Vec<f64> = Vec::new();
    match shape {
        AnalyticShape::Sphere(s) => {
            let c = v(s.centre);
            let f = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
            let r = s.radius as f64;
            if let Some((t0, t1)) = roots(dot(d, d), 2.0 * dot(f, d), dot(f, f) - r * r) {
                candidates.extend([t0, t1]);
            }
        }
        AnalyticShape::Ring(ring) => {
            let base = v(ring.base);
            let (y0, y1) = (base[1], base[1] + ring.height as f64);
            let (fx, fz) = (o[0] - base[0], o[2] - base[2]);
            let rho2 = |p: V| (p[0] - base[0]).powi(2) + (p[2] - base[2]).powi(2);
            for radius in [ring.r_in as f64, ring.r_out as f64] {
                let a = d[0] * d[0] + d[2] * d[2];
                let b = 2.0 * (fx * d[0] + fz * d[2]);
                let c = fx * fx + fz * fz - radius * radius;
                if let Some((t0, t1)) = roots(a, b, c) {
                    candidates.extend([t0, t1].into_iter().filter(|&t| {
                        let y = at(t)[1];
                        (y0..=y1).contains(&y)
                    }));
                }
            }
            let (r_in2, r_out2) = ((ring.r_in as f64).powi(2), (ring.r_out as f64).powi(2));
            for y in [y0, y1] {
                if d[1] != 0.0 {
                    let t = (y - o[1]) / d[1];
                    if (r_in2..=r_out2).contains(&rho2(at(t))) {
                        candidates.push(t);
                    }
                }
            }
        }
    }
    candidates
        .into_iter()
        .filter(|&t| inside(t))
        .min_by(f64::total_cmp)
}
