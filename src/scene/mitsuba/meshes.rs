//! The meshes of Mitsuba's shapes in their own space: read from OBJ, PLY (ASCII and binary)
//! and Mitsuba's `serialized` files, or made for `rectangle`, `cube` and `disk`. Texture
//! coordinates are stored as trilux reads them (t = 0 at the image's bottom row, as in OBJ),
//! which for PLY and the built-in shapes is Mitsuba's v turned over.

use std::io::Read;
use std::path::Path;

use crate::geometry::{vec2, vec3, Vec2, Vec3};

/// Triangles with optional per-vertex normals and texture coordinates (each empty or one per
/// position).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub tex_coords: Vec<Vec2>,
    pub indices: Vec<[u32; 3]>,
}

/// Elements a mesh file may declare: what a 24 GiB machine can hold with room to spare. A
/// header asking for more is refused before anything is allocated for it.
const MAX_ELEMENTS: u64 = 200_000_000;

impl Mesh {
    /// Checks that every index points at a vertex and every attribute has one entry a vertex.
    fn checked(self, what: &str) -> Result<Mesh, String> {
        let n = self.positions.len();
        if let Some(bad) = self.indices.iter().flatten().find(|&&k| k as usize >= n) {
            return Err(format!(
                "{what}: a face refers to vertex {bad}, but there are {n} vertices"
            ));
        }
        for (name, len) in [
            ("normals", self.normals.len()),
            ("texture coordinates", self.tex_coords.len()),
        ] {
            if len != 0 && len != n {
                return Err(format!("{what}: {len} {name} for {n} vertices"));
            }
        }
        let in_range = |v: &Vec3| v.to_array().into_iter().all(crate::scene::range::in_range);
        if let Some(p) = self.positions.iter().find(|p| !in_range(p)) {
            return Err(format!(
                "{what}: a vertex at {p}: {}",
                crate::scene::range::RANGE
            ));
        }
        if let Some(n) = self.normals.iter().find(|n| !n.is_finite()) {
            return Err(format!("{what}: a normal is not finite ({n})"));
        }
        Ok(self)
    }
}

/// An OBJ file's faces (triangulated), vertex normals and texture coordinates; its materials
/// are ignored, as Mitsuba ignores them.
pub fn read_obj(path: &Path) -> Result<Mesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut reader = std::io::BufReader::new(file);
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Ok((Vec::new(), Default::default()))
    })
    .map_err(|e| e.to_string())?;
    let mut mesh = Mesh::default();
    let all_uv = models
        .iter()
        .all(|m| m.mesh.texcoords.len() / 2 == m.mesh.positions.len() / 3);
    let all_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| vec3(p[0], p[1], p[2])));
        if all_uv {
            mesh.tex_coords
                .extend(m.texcoords.chunks_exact(2).map(|t| vec2(t[0], t[1])));
        }
        if all_normals {
            mesh.normals
                .extend(m.normals.chunks_exact(3).map(|n| vec3(n[0], n[1], n[2])));
        }
        let count = (m.positions.len() / 3) as u32;
        for t in m.indices.chunks_exact(3) {
            if t.iter().any(|&k| k >= count) {
                return Err(format!(
                    "object `{}`: a face index is out of range",
                    model.name
                ));
            }
            mesh.indices.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    mesh.checked("OBJ")
}

/// A PLY file (ASCII or binary): `vertex` elements with x, y, z and optionally nx, ny, nz and
/// u, v (or s, t), `face` elements with `vertex_indices` (or `vertex_index`) lists, polygons
/// split into fans.
pub fn read_ply(path: &Path) -> Result<Mesh, String> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};

    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let length = file.metadata().map_err(|e| e.to_string())?.len();
    let mut reader = ply_rs_bw::parser::Reader::new(std::io::BufReader::new(file));
    let parser = Parser::<DefaultElement>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("PLY header: {e}"))?;
    // Every element takes at least a byte (binary) or two (ASCII): a count beyond the file's
    // length is a corrupt or hostile header, refused before the parser allocates for it.
    for element in header.elements.values() {
        if element.count as u64 > length.min(MAX_ELEMENTS) {
            return Err(format!(
                "PLY header: {} {} elements in a file of {length} bytes",
                element.count, element.name
            ));
        }
    }
    let payload = parser
        .read_payload(&mut reader, &header)
        .map_err(|e| format!("PLY data (truncated or malformed?): {e}"))?;
    let scalar = |p: &Property| -> Option<f32> {
        Some(match *p {
            Property::Char(v) => v as f32,
            Property::UChar(v) => v as f32,
            Property::Short(v) => v as f32,
            Property::UShort(v) => v as f32,
            Property::Int(v) => v as f32,
            Property::UInt(v) => v as f32,
            Property::Float(v) => v,
            Property::Double(v) => v as f32,
            _ => return None,
        })
    };
    let list = |p: &Property| -> Option<Vec<i64>> {
        Some(match p {
            Property::ListChar(v) => v.iter().map(|&k| k as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|&k| k as i64).collect(),
            Property::ListShort(v) => v.iter().map(|&k| k as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|&k| k as i64).collect(),
            Property::ListInt(v) => v.iter().map(|&k| k as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|&k| k as i64).collect(),
            _ => return None,
        })
    };
    let vertices = payload.get("vertex").ok_or("PLY: no vertex element")?;
    let mut mesh = Mesh::default();
    let get3 = |v: &DefaultElement, names: [&str; 3]| -> Option<Vec3> {
        let c = names.map(|n| v.get(n).and_then(scalar));
        Some(vec3(c[0]?, c[1]?, c[2]?))
    };
    for v in vertices {
        mesh.positions
            .push(get3(v, ["x", "y", "z"]).ok_or("PLY: a vertex without x, y, z")?);
        if let Some(n) = get3(v, ["nx", "ny", "nz"]) {
            mesh.normals.push(n);
        }
        let uv = |a: &str, b: &str| Some((v.get(a).and_then(scalar)?, v.get(b).and_then(scalar)?));
        if let Some((s, t)) = uv("u", "v")
            .or_else(|| uv("s", "t"))
            .or_else(|| uv("texture_u", "texture_v"))
        {
            // Mitsuba's v runs down the image; trilux's t runs up it.
            mesh.tex_coords.push(vec2(s, 1.0 - t));
        }
    }
    let n = mesh.positions.len() as i64;
    for face in payload.get("face").map(Vec::as_slice).unwrap_or_default() {
        let indices = face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
            .and_then(list)
            .ok_or("PLY: a face without a vertex_indices list")?;
        if let Some(bad) = indices.iter().find(|&&k| k < 0 || k >= n) {
            return Err(format!(
                "PLY: a face refers to vertex {bad}, but there are {n} vertices"
            ));
        }
        for k in 1..indices.len().saturating_sub(1) {
            mesh.indices
                .push([indices[0], indices[k], indices[k + 1]].map(|i| i as u32));
        }
    }
    mesh.checked("PLY")
}

/// Mitsuba's `serialized` format: a little-endian file of zlib-compressed meshes, the one at
/// `shape_index` read (a table of the meshes' offsets closes the file).
pub fn read_serialized(path: &Path, shape_index: u32) -> Result<Mesh, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
    };
    let u64_at = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?))
    };
    let short = || "serialized: the file is truncated".to_string();
    let (format, version) = (
        u16::from_le_bytes(
            bytes
                .get(0..2)
                .ok_or_else(short)?
                .try_into()
                .unwrap_or_default(),
        ),
        u16::from_le_bytes(
            bytes
                .get(2..4)
                .ok_or_else(short)?
                .try_into()
                .unwrap_or_default(),
        ),
    );
    if format != 0x041C {
        return Err(format!(
            "serialized: not a Mitsuba mesh file (format {format:#06x})"
        ));
    }
    // The table at the end: offsets of the meshes (u64 from version 4), then their count.
    let count = u32_at(bytes.len().checked_sub(4).ok_or_else(short)?).ok_or_else(short)?;
    if shape_index >= count {
        return Err(format!(
            "serialized: shape_index {shape_index}, but the file holds {count} meshes"
        ));
    }
    let offset = if version >= 4 {
        let table = bytes
            .len()
            .checked_sub(4 + 8 * count as usize)
            .ok_or_else(short)?;
        u64_at(table + 8 * shape_index as usize).ok_or_else(short)? as usize
    } else {
        let table = bytes
            .len()
            .checked_sub(4 + 4 * count as usize)
            .ok_or_else(short)?;
        u32_at(table + 4 * shape_index as usize).ok_or_else(short)? as usize
    };
    let compressed = bytes.get(offset + 4..).ok_or_else(short)?;
    let mut data = Vec::new();
    flate2::read::ZlibDecoder::new(compressed)
        .take(16 << 30)
        .read_to_end(&mut data)
        .map_err(|e| format!("serialized: {e}"))?;
    decode_serialized(&data, version)
}

/// One decompressed mesh of a `serialized` file.
fn decode_serialized(data: &[u8], version: u16) -> Result<Mesh, String> {
    const HAS_NORMALS: u32 = 0x0001;
    const HAS_TEX_COORDS: u32 = 0x0002;
    const HAS_COLORS: u32 = 0x0008;
    const DOUBLE: u32 = 0x2000;
    let mut at = 0usize;
    let short = || "serialized: a mesh is truncated".to_string();
    let mut take = |n: usize| -> Result<&[u8], String> {
        let s = data.get(at..at + n).ok_or_else(short)?;
        at += n;
        Ok(s)
    };
    let flags = u32::from_le_bytes(take(4)?.try_into().unwrap_or_default());
    if version >= 4 {
        // The mesh's name, a NUL-terminated string.
        while take(1)?[0] != 0 {}
    }
    let vertices = u64::from_le_bytes(take(8)?.try_into().unwrap_or_default());
    let triangles = u64::from_le_bytes(take(8)?.try_into().unwrap_or_default());
    if vertices > MAX_ELEMENTS || triangles > MAX_ELEMENTS {
        return Err(format!(
            "serialized: {vertices} vertices and {triangles} triangles: more than a mesh may have"
        ));
    }
    let (vertices, triangles) = (vertices as usize, triangles as usize);
    let double = flags & DOUBLE != 0;
    let mut floats = |n: usize| -> Result<Vec<f32>, String> {
        let width = if double { 8 } else { 4 };
        let raw = take(n * width)?;
        Ok(raw
            .chunks_exact(width)
            .map(|c| {
                if double {
                    f64::from_le_bytes(c.try_into().unwrap_or_default()) as f32
                } else {
                    f32::from_le_bytes(c.try_into().unwrap_or_default())
                }
            })
            .collect())
    };
    let to_vec3 =
        |v: Vec<f32>| -> Vec<Vec3> { v.chunks_exact(3).map(|c| vec3(c[0], c[1], c[2])).collect() };
    let mut mesh = Mesh {
        positions: to_vec3(floats(3 * vertices)?),
        ..Mesh::default()
    };
    if flags & HAS_NORMALS != 0 {
        mesh.normals = to_vec3(floats(3 * vertices)?);
    }
    if flags & HAS_TEX_COORDS != 0 {
        mesh.tex_coords = floats(2 * vertices)?
            .chunks_exact(2)
            .map(|c| vec2(c[0], 1.0 - c[1]))
            .collect();
    }
    if flags & HAS_COLORS != 0 {
        floats(3 * vertices)?;
    }
    let wide = vertices > u32::MAX as usize;
    let raw = take(3 * triangles * if wide { 8 } else { 4 })?;
    let index: Vec<u32> = if wide {
        raw.chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default()) as u32)
            .collect()
    } else {
        raw.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect()
    };
    mesh.indices = index.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    mesh.checked("serialized")
}

/// Mitsuba's `rectangle`: [-1, 1]² in the z = 0 plane, facing +z.
pub fn rectangle() -> Mesh {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    Mesh {
        positions: corners.iter().map(|&(x, y)| vec3(x, y, 0.0)).collect(),
        normals: vec![Vec3::Z; 4],
        tex_coords: corners
            .iter()
            .map(|&(x, y)| vec2(0.5 * (x + 1.0), 1.0 - 0.5 * (y + 1.0)))
            .collect(),
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Mitsuba's `cube`: [-1, 1]³, each face with its own vertices and outward normal.
pub fn cube() -> Mesh {
    let mut mesh = Mesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // Two axes across the face, ordered so that their cross product is n.
            let (mut a, mut b) = (Vec3::ZERO, Vec3::ZERO);
            a[(axis + 1) % 3] = 1.0;
            b[(axis + 2) % 3] = sign;
            let base = mesh.positions.len() as u32;
            for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push(n + a * s + b * t);
                mesh.normals.push(n);
                mesh.tex_coords.push(vec2(0.5 * (s + 1.0), 0.5 * (t + 1.0)));
            }
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.indices.push([base, base + 2, base + 3]);
        }
    }
    mesh
}

/// Mitsuba's `disk`: the unit disk in the z = 0 plane facing +z, as a fan of `segments`
/// triangles (fine enough that its area is within 0.1% of π at 128).
pub fn disk(segments: u32) -> Mesh {
    let mut mesh = Mesh {
        positions: vec![Vec3::ZERO],
        normals: vec![Vec3::Z],
        tex_coords: vec![vec2(0.0, 1.0)],
        indices: Vec::new(),
    };
    for k in 0..segments {
        let phi = std::f32::consts::TAU * k as f32 / segments as f32;
        mesh.positions.push(vec3(phi.cos(), phi.sin(), 0.0));
        mesh.normals.push(Vec3::Z);
        mesh.tex_coords
            .push(vec2(1.0, 1.0 - k as f32 / segments as f32));
        mesh.indices.push([0, 1 + k, 1 + (k + 1) % segments]);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_shapes_face_outward_and_have_their_area() {
        let area = |m: &Mesh| -> f32 {
            m.indices
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|k| m.positions[k as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum()
        };
        let facing_out = |m: &Mesh| {
            m.indices.iter().all(|t| {
                let [a, b, c] = t.map(|k| m.positions[k as usize]);
                (b - a).cross(c - a).dot(m.normals[t[0] as usize]) > 0.0
            })
        };
        assert!((area(&rectangle()) - 4.0).abs() < 1e-5);
        assert!((area(&cube()) - 24.0).abs() < 1e-4);
        assert!((area(&disk(128)) / std::f32::consts::PI - 1.0).abs() < 1e-3);
        assert!(facing_out(&rectangle()) && facing_out(&cube()) && facing_out(&disk(16)));
    }
}
