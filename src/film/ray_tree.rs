//! Output of a ray tree (`--ray-tree X Y`): the rays drawn over the image (eye rays white,
//! reflected and refracted rays red, shadow rays green), and the same segments as OBJ lines.

use std::io::Write;
use std::path::Path;

use super::Film;
use crate::camera::Camera;
use crate::color::Color;
use crate::geometry::vec3;
use crate::geometry::Vec3;
use crate::output::{write_atomically, OutputError};

/// What a segment of a ray tree is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentKind {
    /// The camera ray.
    Eye,
    /// A reflected or refracted ray.
    Specular,
    /// A ray towards a point on a light.
    Shadow,
}

/// One ray of a ray tree, from its origin to where it ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub from: Vec3,
    pub to: Vec3,
    pub kind: SegmentKind,
}

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
pub fn write_obj(segments: &[Segment], path: &Path) -> Result<(), OutputError> {
    write_atomically(path, |w| {
        let io = |source| OutputError::Io {
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
