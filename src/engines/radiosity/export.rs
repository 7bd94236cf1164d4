//! `--export-radiosity FILE.ply`: the solution's patches (the leaf elements) as a binary
//! little-endian PLY mesh whose vertex colours are each patch's radiosity — its outgoing
//! radiance, linear float, not tone-mapped — so that a solution can be looked at in any mesh
//! viewer and compared number by number. Every patch has its own four corners (a triangle
//! patch, whose last two corners coincide, is written as a triangle), so a colour is the
//! patch's own value, never an average.

use std::io::Write;
use std::path::Path;

use super::Solution;
use crate::output::{write_atomically, OutputError};

impl Solution {
    /// Writes the PLY file (atomically).
    pub fn write_ply(&self, path: &Path) -> Result<(), OutputError> {
        let faces: Vec<(usize, usize)> = self
            .patches
            .iter()
            .enumerate()
            .map(|(k, p)| (k, if p.corners[2] == p.corners[3] { 3 } else { 4 }))
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
                let p = &self.patches[k];
                let l = self.state.radiance[k];
                for c in &p.corners[..n] {
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
