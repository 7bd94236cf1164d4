//! The MATERIALS view: each pixel shows the first surface its ray meets, as emitted radiance
//! plus albedo (texture looked up), or the background. It exercises scene loading, cameras,
//! textures and closest-hit queries of every backend.

use rayon::prelude::*;

use crate::accel::Accel;
use crate::engines::RenderSettings;
use crate::film::Film;
use crate::geometry::Ray;
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
