//! Diffuse indirect light as the ray tracer consumes it: whatever can say how much light
//! arrives at a surface point besides the direct light of the emitters. The constant ambient
//! term is here; the radiosity solution and the photon maps implement the same trait in their
//! own engines, so the ray tracer imports neither.

use crate::accel::Accel;
use crate::color::Color;
use crate::geometry::{Ray, Vec3};
use crate::sampling::Rng;
use crate::scene::medium::Medium;
use crate::scene::{Scene, SurfaceHit};

/// A source of diffuse indirect light for the ray tracer.
pub trait IndirectLight: Sync {
    /// Incident radiance averaged over the hemisphere at `s` (unit normal `n` on the lit
    /// side, in `medium`: the fog, an object's interior medium or none), `depth` specular
    /// bounces from the camera: what the surface's albedo multiplies besides the direct light.
    fn incident(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        s: &SurfaceHit,
        n_medium: (Vec3, Option<&Medium>),
        depth: u32,
        rng: &mut Rng,
    ) -> Color;

    /// Radiance `medium` scatters into `ray` over the first `length` of distance (∞:
    /// the ray leaves the scene) besides the single scattering of the lights, which the ray
    /// tracer computes itself: light that has scattered or bounced before. None by default.
    fn in_scattered(&self, _medium: &Medium, _ray: &Ray, _length: f32, _rng: &mut Rng) -> Color {
        Color::ZERO
    }
}

/// A constant incident radiance everywhere (`-ambient_light`, the course's stand-in).
pub struct Ambient(pub Color);

impl IndirectLight for Ambient {
    fn incident(
        &self,
        _: &Scene,
        _: &dyn Accel,
        _: &SurfaceHit,
        _: (Vec3, Option<&Medium>),
        _: u32,
        _: &mut Rng,
    ) -> Color {
        self.0
    }

    /// The constant radiance scattered in, in closed form: (σs/σt)·(1 − transmittance)·L.
    fn in_scattered(&self, medium: &Medium, _: &Ray, length: f32, _: &mut Rng) -> Color {
        medium.albedo() * (Color::ONE - medium.transmittance(length)) * self.0
    }
}
