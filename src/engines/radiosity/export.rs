//! `--export-radiosity FILE.ply`: the solution's leaf elements — the patches, or the leaves
//! of the hierarchical solver's quadtrees over them — as a binary little-endian PLY mesh
//! whose vertex colours are each leaf's radiosity — its outgoing radiance, linear float, not
//! tone-mapped — so that a solution can be looked at in any mesh viewer and compared number
//! by number. Every leaf has its own four corners (a triangle, whose last two corners
//! coincide, is written as a triangle), so a colour is the leaf's own value, never an
//! average.

use std::io::Write;
use std::path::Path;

use super::mesh::NONE;
use super::Solution;
use crate::geometry::Vec3;
use crate::output::{write_atomically, OutputError};
use crate::scene::Color;

impl Solution {
    /// Writes the PLY file (atomically).
    pub fn write_ply(&self, path: &Path) -> Result<(), OutputError> {
        // (corners, radiance) of every leaf.
        let leaves: Vec<(&[Vec3; 4], Color)> = if self.state.elements.is_empty() {
            self.patches
                .iter()
                .zip(&self.state.radiance)
                .map(|(p, &l)| (&p.corners, l))
                .collect()
        } else {
            self.state
                .elements
                .iter()
                .filter(|e| e.children == NONE)
                .map(|e| (&e.corners, e.radiance))
                .collect()
        };
        let faces: Vec<(usize, usize)> = leaves
            .iter()
            .enumerate()
            .map(|(k, (c, _))| (k, if c[2] == c[3] { 3 } else { 4 }))
            .collect();
        let vertices: usize = faces.iter().map(|f| f.1).sum();
        write_atomically(path, |w| {
            let io = OutputError::io(path);
            write!(
                w,
                "ply\nformat binary_little_endian 1.0\ncomment trilux radiosity: vertex colours are linear radiance\n\
                 element vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n\
                 property float red\nproperty float green\nproperty float blue\n\
                 element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
                faces.len()
            )
            .map_err(&io)?;
            for &(k, n) in &faces {
                let (corners, l) = leaves[k];
                for c in &corners[..n] {
                    for v in c.to_array().into_iter().chain(l.to_array()) {
                        w.write_all(&v.to_le_bytes()).map_err(&io)?;
                    }
                }
            }
            let mut next = 0u32;
            for &(_, n) in &faces {
                w.write_all(&[n as u8]).map_err(&io)?;
                for _ in 0..n {
                    w.write_all(&next.to_le_bytes()).map_err(&io)?;
                    next += 1;
                }
            }
            Ok(())
        })
    }
}
