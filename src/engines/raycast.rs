//! The MATERIALS view: each pixel shows the first surface its ray meets, as emitted radiance
//! plus albedo (texture looked up), or the background. It exercises scene loading, cameras,
//! textures and closest-hit queries of every backend.

use crate::accel::Accel;
use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;

use super::engine::{Budget, Engine, EngineKind, RenderSettings, Rendered};
use crate::film::Film;
use crate::geometry::Ray;
use crate::render::RenderStats;
use crate::scene::{Camera, Scene};

/// Renders the MATERIALS view; camera rays of each row go to the Accel as one batch.
pub fn render(scene: &Scene, accel: &dyn Accel, settings: &RenderSettings) -> Film {
    let (w, h) = (settings.width, settings.height);
    let view = scene.camera().view();
    let mut film = Film::new(w, h);
    let bar = crate::progress::bar(h as u64, "raycast", settings.quiet);
    film.pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(row, out)| {
            let j = h - 1 - row as u32;
            let rays: Vec<Ray> = (0..w)
                .map(|i| {
                    let (x, y) = Camera::screen_point(i, j, 0.5, 0.5, w, h);
                    view.ray(x, y)
                })
                .collect();
            let mut hits = vec![None; rays.len()];
            accel.intersect_batch(&rays, &mut hits);
            for ((pixel, ray), hit) in out.iter_mut().zip(&rays).zip(&hits) {
                *pixel = match hit {
                    Some(h) => {
                        let s = scene.surface(ray, h);
                        scene.materials[s.material as usize].emitted + scene.albedo(&s)
                    }
                    None => scene.background,
                };
            }
            bar.inc(1);
        });
    bar.finish_and_clear();
    film
}

/// The MATERIALS view (`--engine raycast`).
pub struct RaycastEngine;

impl Engine for RaycastEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Raycast
    }

    /// One ray through each pixel's centre: no samples to split.
    fn samples_pixels(&self, _settings: &RenderSettings) -> bool {
        false
    }

    fn unread_flags(&self) -> &'static [&'static str] {
        &[
            "num_bounces",
            "num_shadow_samples",
            "ambient_light",
            "light_sampling",
            "indirect",
            "num_antialias_samples",
            "aperture",
            "focus_distance",
        ]
    }

    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        let film = render(scene, accel, settings);
        let stats = RenderStats::default();
        stats
            .camera_rays
            .store(settings.width as u64 * settings.height as u64, Relaxed);
        Ok(Rendered::plain(film, stats))
    }

    /// One camera ray per pixel sample, doubling (the view has no other noise: its curve
    /// measures antialiasing alone).
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget> {
        Budget::samples_per_pixel(level, 10, base)
    }

    fn colour(&self) -> (u8, u8, u8) {
        (31, 119, 180)
    }
}
