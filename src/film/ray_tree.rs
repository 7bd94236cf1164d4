//! Output of a ray tree (`--ray-tree X Y`): the rays drawn over the image (eye rays white,
//! reflected and refracted rays red, shadow rays green), and the same segments as OBJ lines.

use std::io::Write;
use std::path::Path;

use super::{write_atomically, Film, FilmError};
use crate::engines::raytrace::{Segment, SegmentKind};
use crate::geometry::vec3;
use crate::scene::{Camera, Color};

fn colour(kind: SegmentKind) -> Color {
    match kind {
        SegmentKind::Eye => vec3(1.0, 1.0, 1.0),
        SegmentKind::Specular => vec3(1.0, 0.0, 0.0),
        SegmentKind::Shadow => vec3(0.0, 1.0, 0.0),
    }
}

/// Draws the segments, projected through the camera, over a copy of the film.
pub fn overlay(film: &Film, camera: &Camera, segments: &[Segment]) -> Film {
    let mut out = film.clone();
    let (w, h) = (film.width as f32, film.height as f32);
    let m = w.max(h);
    // Inverse of Camera::screen_point: screen (x, y) to pixel coordinates, row 0 at the top.
    let to_pixel = |(x, y): (f32, f32)| ((x - 0.5) * m + w / 2.0, h - ((y - 0.5) * m + h / 2.0));
    for s in segments {
        // Clip the segment to the part in front of the camera by sampling along it.
        let steps = 2048;
        for k in 0..=steps {
            let p = s.from + (s.to - s.from) * (k as f32 / steps as f32);
            let Some(screen) = camera.project(p) else {
                continue;
            };
            let (px, py) = to_pixel(screen);
            if px >= 0.0 && py >= 0.0 && px < w && py < h {
                let idx = py as usize * film.width as usize + px as usize;
                out.pixels[idx] = colour(s.kind);
            }
        }
    }
    out
}

/// Writes the segments as an OBJ file of line elements, one object per kind.
pub fn write_obj(segments: &[Segment], path: &Path) -> Result<(), FilmError> {
    write_atomically(path, |w| {
        let io = |source| FilmError::Io {
            path: path.to_path_buf(),
            source,
        };
        writeln!(w, "# trilux ray tree: {} segments", segments.len()).map_err(io)?;
        for (k, s) in segments.iter().enumerate() {
            writeln!(w, "o {:?}_{k}", s.kind).map_err(io)?;
            writeln!(w, "v {} {} {}", s.from.x, s.from.y, s.from.z).map_err(io)?;
            writeln!(w, "v {} {} {}", s.to.x, s.to.y, s.to.z).map_err(io)?;
            writeln!(w, "l {} {}", 2 * k + 1, 2 * k + 2).map_err(io)?;
        }
        Ok(())
    })
}
