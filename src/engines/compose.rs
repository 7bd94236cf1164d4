//! The engines made of others: the ray tracer with its `--indirect` light (the ambient term
//! or a radiosity solution), and the photon engine (the ray tracer with photon maps as its
//! indirect light). The pure engines know no other engine; this module wires them through
//! the ray tracer's `IndirectLight` interface.

use std::sync::atomic::Ordering::Relaxed;

use super::engine::PrePass;
use super::radiosity::{self, RadiosityIndirect};
use super::{photon, raytrace};
use super::{Budget, Engine, EngineKind, EnginePlan, IndirectKind, RenderSettings, Rendered};
use crate::accel::Accel;
use crate::render::RenderStats;
use crate::scene::Scene;

/// The ray tracer (`--engine raytrace`, the default), its indirect light the ambient term or
/// (`--indirect radiosity`) a radiosity solution solved first.
pub struct RayTraceEngine;

impl Engine for RayTraceEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Raytrace
    }

    fn structures(&self) -> &'static [&'static str] {
        &["radiosity mesh"]
    }

    fn plan(&self, scene: &Scene, settings: &RenderSettings) -> EnginePlan {
        match settings.indirect {
            IndirectKind::Ambient => EnginePlan::default(),
            IndirectKind::Radiosity => radiosity::mesh_plan(scene, settings),
        }
    }

    fn pre_pass(&self, settings: &RenderSettings) -> Option<PrePass> {
        (settings.indirect == IndirectKind::Radiosity).then(|| radiosity::pre_pass(settings))
    }

    fn run_pre_pass(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Vec<String>, String> {
        radiosity::run_pre_pass(scene, accel, settings)
    }

    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        Ok(match settings.indirect {
            IndirectKind::Ambient => {
                let (film, stats) = raytrace::render(scene, accel, settings);
                Rendered::plain(film, stats)
            }
            IndirectKind::Radiosity => {
                let solution = radiosity::solve_with_progress(scene, accel, settings)?;
                let indirect = RadiosityIndirect::new(&solution, settings.radiosity.interpolate);
                let (film, stats) = raytrace::render_with(scene, accel, settings, &indirect);
                stats.form_factor_rays.store(solution.rays, Relaxed);
                solution.rendered(film, stats, settings)?
            }
        })
    }

    /// Soft shadows and the ambient term, samples per pixel doubling. The ambient term is a
    /// guess, so this curve levels off at its bias.
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget> {
        let four_shadow_rays = RenderSettings {
            num_shadow_samples: 4,
            ..base.clone()
        };
        Budget::samples_per_pixel(level, 10, &four_shadow_rays)
    }

    fn colour(&self) -> (u8, u8, u8) {
        (31, 119, 180)
    }
}

/// The photon engine (`--engine photon`): the ray tracer with the photon maps as its diffuse
/// indirect light, or the photons themselves (`--visualize photons|kdtree`).
pub struct PhotonEngine;

impl Engine for PhotonEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Photon
    }

    fn structures(&self) -> &'static [&'static str] {
        &["photon map", "caustic map", "volume photon map"]
    }

    fn unread_flags(&self) -> &'static [&'static str] {
        // The photon maps replace the ambient term.
        &["ambient_light", "indirect"]
    }

    fn plan(&self, scene: &Scene, settings: &RenderSettings) -> EnginePlan {
        photon::plan(scene, settings)
    }

    /// The photons shown as they are (`--visualize photons|kdtree`) are not samples.
    fn samples_pixels(&self, settings: &RenderSettings) -> bool {
        settings.photon.display == photon::Display::Image
    }

    fn pre_pass(&self, settings: &RenderSettings) -> Option<PrePass> {
        Some(photon::pre_pass(settings))
    }

    fn run_pre_pass(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Vec<String>, String> {
        let maps = photon::maps(scene, accel, settings)?;
        Ok(vec![maps.summary()])
    }

    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        render_photons(scene, accel, settings).map(|(rendered, _)| rendered)
    }

    /// Photons and pixel samples double together: with the pixel samples fixed, the error
    /// of edges and shadows would hide what more photons buy.
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget> {
        if level > 10 {
            return None;
        }
        let doubling = 1u64 << level;
        let photons = 25_000 * doubling;
        let mut s = base.clone();
        s.num_shadow_samples = 16;
        s.num_antialias_samples = doubling.min(256) as u32;
        s.photon.num_photons_to_shoot = Some(photons);
        Some(Budget {
            counts: "photons",
            value: photons,
            settings: s,
        })
    }

    fn colour(&self) -> (u8, u8, u8) {
        (214, 39, 40)
    }
}

/// Renders with the photon engine: the maps (traced or loaded), then the ray tracer with them
/// as its indirect light (or a display of the photons). Returns the maps too.
pub fn render_photons(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<(Rendered, photon::PhotonMaps), String> {
    let maps = photon::maps(scene, accel, settings)?;
    Ok((render_with_maps(scene, accel, settings, &maps), maps))
}

/// The photon engine's image with `maps` traced before (the viewer keeps them while the
/// camera moves): the ray tracer with them as its indirect light, or a display of the
/// photons.
pub fn render_with_maps(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    maps: &photon::PhotonMaps,
) -> Rendered {
    let warnings = maps
        .truncation_warning(settings.photon.max_photon_depth)
        .into_iter()
        .collect();
    if let Some(film) = photon::display(scene, maps, settings) {
        let stats = RenderStats::default();
        stats.photon_rays.store(maps.rays, Relaxed);
        return Rendered {
            summary: vec![maps.summary()],
            warnings,
            ..Rendered::plain(film, stats)
        };
    }
    let cache = settings
        .photon
        .gather_indirect
        .then(|| photon::IrradianceCache::build(scene, accel, settings, maps));
    let indirect = photon::PhotonIndirect {
        maps,
        cache: cache.as_ref(),
    };
    let (film, stats) = raytrace::render_with(scene, accel, settings, &indirect);
    stats.photon_rays.store(maps.rays, Relaxed);
    let mut summary = Vec::new();
    if let Some(c) = &cache {
        stats
            .secondary_rays
            .fetch_add(c.rays.load(Relaxed), Relaxed);
        summary.push(c.summary());
    }
    summary.push(maps.summary());
    Rendered {
        summary,
        warnings,
        ..Rendered::plain(film, stats)
    }
}
