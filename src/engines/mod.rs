//! The lighting engines. Each takes the scene, an `Accel` and the settings and fills a `Film`:
//! `raycast` (the course's MATERIALS view), `raytrace`, `radiosity`, `photon` (with `sppm`,
//! stochastic progressive photon mapping) and the reference `path` tracer, each implementing `Engine` (`engine.rs`). The pure engines know
//! no other engine; `compose` wires the two that combine them (the ray tracer with its
//! `--indirect` light, the photon engine). `engine()` is the one registration point.

pub mod compose;
pub mod engine;
pub mod path;
pub mod photon;
pub mod radiosity;
pub mod raycast;
pub mod raytrace;
pub mod scattering;

pub use engine::{Budget, Engine, EngineKind, EnginePlan, IndirectKind, RenderSettings, Rendered};

use crate::accel::Accel;
use crate::scene::Scene;

/// The engine of a kind: the one registration point of the engines.
pub fn engine(kind: EngineKind) -> &'static dyn Engine {
    match kind {
        EngineKind::Raycast => &raycast::RaycastEngine,
        EngineKind::Raytrace => &compose::RayTraceEngine,
        EngineKind::Radiosity => &radiosity::RadiosityEngine,
        EngineKind::Photon => &compose::PhotonEngine,
        EngineKind::Path => &path::PathEngine,
        EngineKind::Sppm => &photon::sppm::SppmEngine,
    }
}

/// Every engine, in the order `--engine` lists them.
pub fn all() -> impl Iterator<Item = &'static dyn Engine> {
    <EngineKind as clap::ValueEnum>::value_variants()
        .iter()
        .map(|&k| engine(k))
}

/// Renders the scene with the engine of `kind`.
pub fn render(
    kind: EngineKind,
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<Rendered, String> {
    check_camera(scene)?;
    engine(kind).render(scene, accel, settings)
}

/// Where the rays are made: a camera whose rays would hold inf or NaN is an error, not a
/// render of misses (the scene's range check makes none; this is the backstop).
pub fn check_camera(scene: &Scene) -> Result<(), String> {
    let camera = scene.camera();
    if camera.view().is_finite() {
        return Ok(());
    }
    Err(format!(
        "{}: the camera (at {}, looking at {}) makes rays of inf or NaN",
        scene.path.display(),
        camera.position,
        camera.point_of_interest
    ))
}
