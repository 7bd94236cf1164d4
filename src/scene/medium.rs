//! Participating media (`medium` blocks, `fog K`, Mitsuba's `homogeneous` and
//! `heterogeneous`; docs/scene-format.md): the coefficients, the transmittance along a
//! segment, free-flight distances (sampled by a hero channel in a homogeneous medium, by
//! delta tracking in a heterogeneous one, whose transmittance ratio tracking estimates), and
//! the Henyey–Greenstein phase function.

use crate::color::Color;
use crate::geometry::{Bounds3, Vec3};
use crate::sampling::{orthonormal_basis, PathSamples};

use super::volume_grid::GridVolume;

/// A medium. Coefficients are per scene unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Absorption coefficient σa (`sigma_a`, default 0); 0 in a heterogeneous medium.
    pub sigma_a: Color,
    /// Scattering coefficient σs (`sigma_s`, default 0); 0 in a heterogeneous medium.
    pub sigma_s: Color,
    /// Henyey–Greenstein asymmetry in (−1, 1) (`g`, default 0: isotropic).
    pub g: f32,
    /// The coefficients of a heterogeneous medium, which vary through space (default None:
    /// the medium is homogeneous, of `sigma_a` and `sigma_s`).
    pub heterogeneous: Option<Box<Heterogeneous>>,
    /// Line of the file where the block starts.
    pub line: u32,
}

impl Default for Medium {
    fn default() -> Self {
        Medium {
            sigma_a: Color::ZERO,
            sigma_s: Color::ZERO,
            g: 0.0,
            heterogeneous: None,
            line: 0,
        }
    }
}

/// Mitsuba's `heterogeneous` medium: σt = `scale` × a grid, σs = σt × the albedo (a colour or
/// a grid). Outside the σt grid's box nothing interacts (Mitsuba samples only within it);
/// inside, the grid is clamped to its outer cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Heterogeneous {
    /// The grid of σt before `scale` (`sigma_t`).
    pub sigma_t: GridVolume,
    /// What the σt grid is multiplied by (`scale`, default 1).
    pub scale: f32,
    /// The single-scattering albedo σs/σt (`albedo`, default 0.75).
    pub albedo: Albedo,
}

/// A heterogeneous medium's albedo: one colour, or a grid of them.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    Constant(Color),
    Grid(GridVolume),
}

impl Heterogeneous {
    /// The bound on σt that delta and ratio tracking sample against: `scale` × the grid's
    /// largest value, in every channel (Mitsuba's majorant).
    pub fn majorant(&self) -> f32 {
        self.scale * self.sigma_t.grid.max()
    }

    /// Where the medium interacts: the σt grid's box in the world.
    pub fn bounds(&self) -> Bounds3 {
        self.sigma_t.bounds()
    }

    /// σt at the world point `x` (within `bounds`).
    pub fn sigma_t(&self, x: Vec3) -> Color {
        self.sigma_t.eval(x) * self.scale
    }

    /// The albedo at the world point `x`.
    pub fn albedo(&self, x: Vec3) -> Color {
        match &self.albedo {
            Albedo::Constant(c) => *c,
            Albedo::Grid(g) => g.eval(x),
        }
    }

    /// The same medium in a world scaled by `scale` about the origin and moved by `offset`:
    /// the grids follow, and σt keeps its optical depths.
    pub fn transformed(&self, scale: f32, offset: Vec3) -> Heterogeneous {
        Heterogeneous {
            sigma_t: self.sigma_t.transformed(scale, offset),
            scale: self.scale / scale,
            albedo: match &self.albedo {
                Albedo::Constant(c) => Albedo::Constant(*c),
                Albedo::Grid(g) => Albedo::Grid(g.transformed(scale, offset)),
            },
        }
    }

    /// The part of the segment from `origin` along the unit `direction`, `length` long,
    /// inside `bounds`, and the majorant; None where nothing can interact on it.
    fn span(&self, origin: Vec3, direction: Vec3, length: f32) -> Option<(f32, f32, f32)> {
        let majorant = self.majorant();
        if majorant <= 0.0 {
            return None;
        }
        let (near, far) = self.bounds().clip(origin, direction, length)?;
        Some((near, far, majorant))
    }

    /// Delta tracking (Woodcock): tentative collisions at the majorant's rate; at each, a
    /// real one with probability σt/majorant, else a null one that goes on. Each collision
    /// takes two numbers of `samples`. Where σt differs between channels, the choice is made
    /// with the channels mixed by the path's `throughput` (the null probability the mix of
    /// theirs) and each channel weighed by its own over it, so the estimate is unbiased in
    /// every channel (spectral tracking; Mitsuba mixes the channels equally); with σt grey
    /// the weights are 1 at null collisions and the albedo where the path scatters.
    fn sample_flight(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_surface: f32,
        throughput: Color,
        samples: &mut PathSamples,
    ) -> Flight {
        let Some((near, far, majorant)) = self.span(origin, direction, t_surface) else {
            return Flight::Passed { weight: Color::ONE };
        };
        let mut weight = Color::ONE;
        let mut t = near;
        loop {
            let (u, v) = samples.next_2d();
            t -= (1.0 - u).ln() / majorant;
            if t >= far {
                return Flight::Passed { weight };
            }
            let x = origin + direction * t;
            let sigma_t = self.sigma_t(x);
            let sigma_n = (Color::splat(majorant) - sigma_t).max(Color::ZERO);
            let carried = throughput * weight;
            let total = carried.x + carried.y + carried.z;
            let share = if total > 0.0 && total.is_finite() {
                carried / total
            } else {
                Color::splat(1.0 / 3.0)
            };
            let null = share.dot(sigma_n) / majorant;
            if v < null {
                weight *= sigma_n / (majorant * null);
            } else {
                let real = 1.0 - null;
                return Flight::Scattered {
                    t,
                    weight: weight * sigma_t * self.albedo(x) / (majorant * real),
                };
            }
        }
    }

    /// Ratio tracking: the product of (1 − σt/majorant) over tentative collisions at the
    /// majorant's rate, whose mean is the transmittance exp(−∫σt) per channel. Each
    /// collision takes one number of `samples`.
    fn transmittance(
        &self,
        origin: Vec3,
        direction: Vec3,
        length: f32,
        samples: &mut PathSamples,
    ) -> Color {
        let Some((near, far, majorant)) = self.span(origin, direction, length) else {
            return Color::ONE;
        };
        let mut transmittance = Color::ONE;
        let mut t = near;
        loop {
            t -= (1.0 - samples.next_1d()).ln() / majorant;
            if t >= far {
                return transmittance;
            }
            let sigma_t = self.sigma_t(origin + direction * t);
            transmittance *= (Color::ONE - sigma_t / majorant).max(Color::ZERO);
            if transmittance.max_element() <= 0.0 {
                return Color::ZERO;
            }
        }
    }
}

/// Where a free flight ended: scattered in the medium at distance `t`, or at the surface the
/// ray was going to meet (or out of the scene); `weight` is what the path's throughput is
/// multiplied by (transmittance, and σs there, over the density of the event).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight {
    Scattered { t: f32, weight: Color },
    Passed { weight: Color },
}

impl Medium {
    /// The extinction coefficient σt = σa + σs.
    pub fn sigma_t(&self) -> Color {
        self.sigma_a + self.sigma_s
    }

    /// The single-scattering albedo σs/σt per channel (0 where σt is 0).
    pub fn albedo(&self) -> Color {
        let sigma_t = self.sigma_t();
        let ratio = |s: f32, t: f32| if t > 0.0 { s / t } else { 0.0 };
        Color::new(
            ratio(self.sigma_s.x, sigma_t.x),
            ratio(self.sigma_s.y, sigma_t.y),
            ratio(self.sigma_s.z, sigma_t.z),
        )
    }

    /// The fraction of light that crosses `distance` of the medium: exp(−σt·d) per channel.
    pub fn transmittance(&self, distance: f32) -> Color {
        let sigma_t = self.sigma_t();
        let t = sigma_t * distance;
        // exp of −∞·0 is NaN: a channel with σt = 0 transmits everything, however far.
        Color::new(
            transmit(t.x, sigma_t.x),
            transmit(t.y, sigma_t.y),
            transmit(t.z, sigma_t.z),
        )
    }

    /// Samples where a ray that would meet a surface at `t_surface` (∞: none) first
    /// interacts, from two uniform numbers: a channel chosen in proportion to the path's
    /// `throughput` (the hero), a distance exponential in its σt; the density is the mix of
    /// the three channels' by those proportions (single-sample MIS, balance heuristic), so
    /// the estimate is unbiased for coloured media. Choosing by throughput keeps the sum of
    /// the channels' throughputs from growing where the medium only scatters (uniform choice
    /// let one channel's grow by up to 3× a vertex: a heavy tail that left a coloured fog's
    /// furnace 3% low at 262k paths).
    pub fn sample_flight(
        &self,
        t_surface: f32,
        throughput: Color,
        u_channel: f32,
        u_distance: f32,
    ) -> Flight {
        let total = throughput.x + throughput.y + throughput.z;
        let share = if total > 0.0 && total.is_finite() {
            throughput / total
        } else {
            Color::splat(1.0 / 3.0)
        };
        let hero = if u_channel < share.x {
            0
        } else if u_channel < share.x + share.y || share.z <= 0.0 {
            1
        } else {
            2
        };
        let sigma_t = self.sigma_t();
        let t = if sigma_t[hero] > 0.0 {
            -(1.0 - u_distance).ln() / sigma_t[hero]
        } else {
            f32::INFINITY
        };
        if t < t_surface {
            let tr = self.transmittance(t);
            let density = share.dot(sigma_t * tr);
            Flight::Scattered {
                t,
                weight: if density > 0.0 {
                    tr * self.sigma_s / density
                } else {
                    Color::ZERO
                },
            }
        } else {
            let tr = self.transmittance(t_surface);
            let probability = share.dot(tr);
            Flight::Passed {
                weight: if probability > 0.0 {
                    tr / probability
                } else {
                    Color::ZERO
                },
            }
        }
    }

    /// Where a ray from `origin` along the unit `direction`, which would meet a surface at
    /// `t_surface` (∞: none), first interacts, from the path's `samples`: a homogeneous
    /// medium's `sample_flight` from one 2-D draw, a heterogeneous one's delta tracking.
    pub fn free_flight(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_surface: f32,
        throughput: Color,
        samples: &mut PathSamples,
    ) -> Flight {
        match &self.heterogeneous {
            None => {
                let (u, v) = samples.next_2d();
                self.sample_flight(t_surface, throughput, u, v)
            }
            Some(h) => h.sample_flight(origin, direction, t_surface, throughput, samples),
        }
    }

    /// The transmittance of the segment from `origin` along the unit `direction`, `length`
    /// long: exact in a homogeneous medium (drawing nothing), estimated without bias by ratio
    /// tracking from `samples` in a heterogeneous one.
    pub fn transmittance_along(
        &self,
        origin: Vec3,
        direction: Vec3,
        length: f32,
        samples: &mut PathSamples,
    ) -> Color {
        match &self.heterogeneous {
            None => self.transmittance(length),
            Some(h) => h.transmittance(origin, direction, length, samples),
        }
    }

    /// The Henyey–Greenstein phase function for a ray travelling along `from` and leaving
    /// along `to` (unit vectors): its value, which is also its density in solid angle.
    pub fn phase(&self, from: Vec3, to: Vec3) -> f32 {
        henyey_greenstein(self.g, from.dot(to))
    }

    /// A direction sampled from the phase function for a ray travelling along `from`, and
    /// its density (= the phase function's value).
    pub fn sample_phase(&self, from: Vec3, u: f32, v: f32) -> (Vec3, f32) {
        let g = self.g;
        let cos = if g.abs() < 1e-3 {
            1.0 - 2.0 * u
        } else {
            let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
            ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * v;
        let (tx, ty) = orthonormal_basis(from);
        let to = (tx * (sin * phi.cos()) + ty * (sin * phi.sin()) + from * cos).normalize();
        (to, henyey_greenstein(g, cos))
    }
}

fn transmit(optical_depth: f32, sigma_t: f32) -> f32 {
    if sigma_t == 0.0 {
        1.0
    } else {
        (-optical_depth).exp()
    }
}

/// (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2}), θ between the travel directions before and after.
fn henyey_greenstein(g: f32, cos: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * std::f32::consts::PI * denom * denom.max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;
    use crate::image_io::VolumeGrid;
    use crate::sampling::Rng;
    use glam::{DMat4, DVec3};

    fn fog(sigma_a: Color, sigma_s: Color, g: f32) -> Medium {
        Medium {
            sigma_a,
            sigma_s,
            g,
            line: 1,
            ..Medium::default()
        }
    }

    /// The phase function integrates to 1 over the sphere, and its samples are distributed
    /// as it: the mean cosine of the samples is g.
    #[test]
    fn henyey_greenstein_is_normalised_and_sampled_as_itself() {
        for g in [-0.7f32, 0.0, 0.3, 0.9] {
            let m = fog(Color::ZERO, Color::ONE, g);
            // ∫ p dω = 2π ∫ p(cos) dcos, midpoint rule over 200,000 intervals.
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| {
                    let cos = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                    henyey_greenstein(g, cos as f32) as f64
                })
                .sum::<f64>()
                * std::f64::consts::TAU
                * 2.0
                / n as f64;
            assert!((integral - 1.0).abs() < 1e-3, "g {g}: ∫p = {integral}");
            let from = vec3(0.3, -0.5, 0.8).normalize();
            let mut rng = Rng::new(7, 0, 0);
            let samples = 100_000;
            let mut mean_cos = 0.0f64;
            for _ in 0..samples {
                let (to, pdf) = m.sample_phase(from, rng.next_f32(), rng.next_f32());
                assert!((to.length() - 1.0).abs() < 1e-4);
                assert!((pdf - m.phase(from, to)).abs() <= 1e-3 * pdf);
                mean_cos += from.dot(to) as f64;
            }
            mean_cos /= samples as f64;
            // The mean cosine of HG is g; the standard error of 1e5 samples is below 2e-3.
            assert!(
                (mean_cos - g as f64).abs() < 1e-2,
                "g {g}: mean cos {mean_cos}"
            );
        }
    }

    /// The free-flight weights are unbiased: the mean weight of the flights that pass a
    /// surface at distance d is the transmittance exp(−σt·d), per channel, and the flights
    /// that scatter carry σs·∫₀^d exp(−σt·t) dt = σs/σt·(1 − exp(−σt·d)), for a coloured
    /// medium (one channel with no extinction at all).
    #[test]
    fn free_flights_weigh_to_the_closed_form() {
        let m = fog(vec3(0.2, 0.0, 0.0), vec3(0.5, 1.5, 0.0), 0.0);
        let d = 1.3;
        for throughput in [Color::ONE, vec3(0.2, 1.5, 0.3), vec3(0.0, 0.0, 2.0)] {
            let mut rng = Rng::new(3, 0, 0);
            let n = 400_000;
            let (mut passed, mut scattered) = (Color::ZERO, Color::ZERO);
            for _ in 0..n {
                match m.sample_flight(d, throughput, rng.next_f32(), rng.next_f32()) {
                    Flight::Passed { weight } => passed += weight,
                    Flight::Scattered { t, weight } => {
                        assert!(t < d);
                        scattered += weight;
                    }
                }
            }
            let (passed, scattered) = (passed / n as f32, scattered / n as f32);
            let sigma_t = m.sigma_t();
            for c in 0..3 {
                let tr = if sigma_t[c] > 0.0 {
                    (-sigma_t[c] * d).exp()
                } else {
                    1.0
                };
                let s = if sigma_t[c] > 0.0 {
                    m.sigma_s[c] / sigma_t[c] * (1.0 - tr)
                } else {
                    0.0
                };
                // Weights are bounded by 1/share (10 here at most): the standard error at 4e5
                // flights is below 5e-3.
                // A channel the path carries nothing in may be weighed anyhow (it is multiplied
                // by zero).
                if throughput[c] == 0.0 {
                    continue;
                }
                assert!(
                    (passed[c] - tr).abs() < 1e-2,
                    "{throughput}: channel {c}: passed {} against {tr}",
                    passed[c]
                );
                assert!(
                    (scattered[c] - s).abs() < 1e-2,
                    "{throughput}: channel {c}: scattered {} against {s}",
                    scattered[c]
                );
            }
        }
        // Nothing scatters out of a vacuum, and everything passes.
        let vacuum = fog(Color::ZERO, Color::ZERO, 0.0);
        assert_eq!(
            vacuum.sample_flight(f32::INFINITY, Color::ONE, 0.5, 0.5),
            Flight::Passed { weight: Color::ONE }
        );
    }

    /// A heterogeneous medium of `values` (x fastest, `channels` a cell) on `size` cells,
    /// its unit cube stretched by `to_world` to [−1, 3] × [0, 1] × [0, 1] (x × 4, then − 1),
    /// σt = `scale` × the grid, of albedo `albedo`.
    fn grid_medium(size: [usize; 3], channels: usize, values: &[f32], scale: f32) -> Medium {
        let grid = VolumeGrid {
            size,
            channels,
            bbox: (Vec3::ZERO, Vec3::ONE),
            data: values.to_vec(),
        };
        let to_world = DMat4::from_translation(DVec3::new(-1.0, 0.0, 0.0))
            * DMat4::from_scale(DVec3::new(4.0, 1.0, 1.0));
        Medium {
            heterogeneous: Some(Box::new(Heterogeneous {
                sigma_t: GridVolume::new(grid, to_world, false).expect("invertible"),
                scale,
                albedo: Albedo::Constant(vec3(0.9, 0.5, 0.0)),
            })),
            line: 1,
            ..Medium::default()
        }
    }

    /// Mean over `n` of delta tracking's passed and scattered weights and of ratio tracking's
    /// transmittance, for the segment from `origin` along `direction`, `length` long.
    fn tracked(
        m: &Medium,
        origin: Vec3,
        direction: Vec3,
        length: f32,
        throughput: Color,
        n: u32,
    ) -> (Color, Color, Color) {
        let mut samples = PathSamples::independent(Rng::new(11, 0, 0));
        let (mut passed, mut scattered, mut ratio) = (Color::ZERO, Color::ZERO, Color::ZERO);
        for _ in 0..n {
            match m.free_flight(origin, direction, length, throughput, &mut samples) {
                Flight::Passed { weight } => passed += weight,
                Flight::Scattered { t, weight } => {
                    assert!((0.0..length).contains(&t), "scattered at {t}");
                    scattered += weight;
                }
            }
            ratio += m.transmittance_along(origin, direction, length, &mut samples);
        }
        let n = n as f32;
        (passed / n, scattered / n, ratio / n)
    }

    /// Delta tracking and ratio tracking through a grid against closed forms: a grid of one
    /// value is a homogeneous medium (transmittance exp(−σt·d), scattered weight
    /// albedo·(1 − exp(−σt·d))), and so is each channel of a coloured one; a two-cell ramp
    /// (σt 0 up to its first cell's centre, linear to its second's, constant beyond) has the
    /// optical depth of its integral; outside the grid's box nothing interacts.
    #[test]
    fn tracking_through_grids_weighs_to_the_closed_forms() {
        let n = 200_000;
        let close = |what: &str, got: Color, expected: Color| {
            // Weights are at most 1/share (3 for a grey throughput): standard errors below
            // 4e-3 at 2e5 samples.
            assert!(
                (got - expected).abs().max_element() < 1.2e-2,
                "{what}: {got} against {expected}"
            );
        };
        let albedo = vec3(0.9, 0.5, 0.0);
        // One value, 0.5 × scale 1.6 = 0.8 a unit, along x from x = −0.5 for 2.5 units.
        let constant = grid_medium([3, 2, 2], 1, &[0.5; 12], 1.6);
        let (origin, d) = (vec3(-0.5, 0.3, 0.6), 2.5);
        let tr = (-0.8f32 * d).exp();
        let (passed, scattered, ratio) = tracked(&constant, origin, Vec3::X, d, Color::ONE, n);
        close("constant: passed", passed, Color::splat(tr));
        close("constant: scattered", scattered, albedo * (1.0 - tr));
        close("constant: ratio tracking", ratio, Color::splat(tr));
        // The same σt given per channel, and two others: each channel is its own medium.
        let sigma = vec3(0.8, 0.2, 1.5);
        let values: Vec<f32> = (0..8).flat_map(|_| sigma.to_array()).collect();
        let coloured = grid_medium([2, 2, 2], 3, &values, 1.0);
        let tr = Color::new(
            (-sigma.x * d).exp(),
            (-sigma.y * d).exp(),
            (-sigma.z * d).exp(),
        );
        for throughput in [Color::ONE, vec3(0.2, 1.5, 0.3)] {
            let (passed, scattered, ratio) = tracked(&coloured, origin, Vec3::X, d, throughput, n);
            close("coloured: passed", passed, tr);
            close("coloured: scattered", scattered, albedo * (Color::ONE - tr));
            close("coloured: ratio tracking", ratio, tr);
        }
        // The ramp: cells 0 and 2 along x, scaled by 0.5. World x = 4u − 1, the centres at
        // x = 0 and 2: σt is 0 before x = 0, x/2 for 0 ≤ x ≤ 2, 1 beyond. From x = −0.5
        // to x = 2.5 the optical depth is ∫₀² x/2 dx + 0.5·1 = 1 + 0.5 = 1.5; across the
        // slope alone (y, z held) it is x/2 × the length in the box.
        let ramp = grid_medium([2, 1, 1], 1, &[0.0, 2.0], 0.5);
        let d = 3.0;
        let tr = Color::splat((-1.5f32).exp());
        let (passed, scattered, ratio) = tracked(&ramp, origin, Vec3::X, d, Color::ONE, n);
        close("ramp along x: passed", passed, tr);
        close(
            "ramp along x: scattered",
            scattered,
            albedo * (Color::ONE - tr),
        );
        close("ramp along x: ratio tracking", ratio, tr);
        let (passed, _, ratio) = tracked(&ramp, vec3(0.5, -0.5, 0.5), Vec3::Y, 2.0, Color::ONE, n);
        let tr = Color::splat((-0.25f32).exp());
        close("ramp across: passed", passed, tr);
        close("ramp across: ratio tracking", ratio, tr);
        // Outside the box (y > 1) nothing interacts, and no number is drawn.
        let outside = vec3(-0.5, 1.5, 0.5);
        let mut samples = PathSamples::independent(Rng::new(3, 0, 0));
        assert_eq!(
            ramp.free_flight(outside, Vec3::X, 10.0, Color::ONE, &mut samples),
            Flight::Passed { weight: Color::ONE }
        );
        assert_eq!(
            ramp.transmittance_along(outside, Vec3::X, 10.0, &mut samples),
            Color::ONE
        );
        let mut fresh = PathSamples::independent(Rng::new(3, 0, 0));
        assert_eq!(samples.next_1d(), fresh.next_1d());
    }

    /// A scene moved and scaled keeps a heterogeneous medium's optical depths: the same
    /// segment, mapped, has the same transmittance.
    #[test]
    fn a_transformed_grid_keeps_its_optical_depths() {
        let ramp = grid_medium([2, 1, 1], 1, &[0.0, 2.0], 1.5);
        let h = ramp.heterogeneous.as_ref().expect("heterogeneous");
        let (scale, offset) = (2.5, vec3(1.0, -3.0, 7.0));
        let moved = h.transformed(scale, offset);
        for x in [
            vec3(-0.5, 0.5, 0.5),
            vec3(0.7, 0.2, 0.9),
            vec3(1.9, 0.99, 0.01),
        ] {
            let (a, b) = (h.sigma_t(x), moved.sigma_t(x * scale + offset) * scale);
            assert!((a - b).abs().max_element() < 1e-5, "{x}: {a} against {b}");
        }
        let bounds = moved.bounds();
        assert!((bounds.min - (vec3(-1.0, 0.0, 0.0) * scale + offset)).length() < 1e-5);
        assert!((bounds.max - (vec3(3.0, 1.0, 1.0) * scale + offset)).length() < 1e-5);
    }
}
