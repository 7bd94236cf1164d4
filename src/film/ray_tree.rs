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
    super::draw_lines(
        &mut out,
        camera,
        segments.iter().map(|s| (s.from, s.to, colour(s.kind))),
    );
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
