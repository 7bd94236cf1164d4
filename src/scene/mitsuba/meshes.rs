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
/// u, v (or s, t, or texture_u, texture_v), `face` elements with `vertex_indices` (or
/// `vertex_index`) lists, polygons split into fans; other elements and properties are read
/// past. Each element is parsed straight into the few numbers trilux keeps (`PlyVertex`,
/// `PlyFace`): the parser's own element, a map of named properties, cost 1.9 s and 1.4 GB
/// for a 38 MB file of 2M triangles.
pub fn read_ply(path: &Path) -> Result<Mesh, String> {
    use ply_rs_bw::parser::Parser;

    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let length = file.metadata().map_err(|e| e.to_string())?.len();
    let mut reader = ply_rs_bw::parser::Reader::new(std::io::BufReader::new(file));
    let header = Parser::<PlySkipped>::new()
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
    let data =
        |e: ply_rs_bw::parser::ParseError| format!("PLY data (truncated or malformed?): {e}");
    let (mut vertices, mut faces) = (None, Vec::new());
    // The elements in the order the header declares them, as the data holds them.
    for (name, element) in &header.elements {
        match name.as_str() {
            "vertex" => {
                vertices = Some(
                    Parser::<PlyVertex>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(data)?,
                )
            }
            "face" => {
                faces = Parser::<PlyFace>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(data)?
            }
            _ => {
                Parser::<PlySkipped>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(data)?;
            }
        }
    }
    let vertices = vertices.ok_or("PLY: no vertex element")?;
    let mut mesh = Mesh::default();
    let both = |[a, b]: [Option<f32>; 2]| Some((a?, b?));
    for v in &vertices {
        let [Some(x), Some(y), Some(z)] = v.position else {
            return Err("PLY: a vertex without x, y, z".into());
        };
        mesh.positions.push(vec3(x, y, z));
        if let [Some(x), Some(y), Some(z)] = v.normal {
            mesh.normals.push(vec3(x, y, z));
        }
        if let Some((s, t)) = both(v.uv).or(both(v.st)).or(both(v.texture_uv)) {
            // Mitsuba's v runs down the image; trilux's t runs up it.
            mesh.tex_coords.push(vec2(s, 1.0 - t));
        }
    }
    let n = mesh.positions.len() as i64;
    for face in &faces {
        let indices = face
            .indices
            .as_ref()
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

/// The numbers of a PLY vertex trilux reads, as the file gives them (None where it does not).
#[derive(Default)]
struct PlyVertex {
    position: [Option<f32>; 3],
    normal: [Option<f32>; 3],
    /// Texture coordinates by their three usual names: u, v; s, t; texture_u, texture_v.
    uv: [Option<f32>; 2],
    st: [Option<f32>; 2],
    texture_uv: [Option<f32>; 2],
}

impl ply_rs_bw::ply::PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex::default()
    }

    fn set_property(
        &mut self,
        name: &str,
        property: ply_rs_bw::ply::Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::{Property, PropertyAccessResult};
        let value = match property {
            Property::Char(v) => v as f32,
            Property::UChar(v) => v as f32,
            Property::Short(v) => v as f32,
            Property::UShort(v) => v as f32,
            Property::Int(v) => v as f32,
            Property::UInt(v) => v as f32,
            Property::Float(v) => v,
            Property::Double(v) => v as f32,
            _ => return PropertyAccessResult::Ignored,
        };
        let slot = match name {
            "x" => &mut self.position[0],
            "y" => &mut self.position[1],
            "z" => &mut self.position[2],
            "nx" => &mut self.normal[0],
            "ny" => &mut self.normal[1],
            "nz" => &mut self.normal[2],
            "u" => &mut self.uv[0],
            "v" => &mut self.uv[1],
            "s" => &mut self.st[0],
            "t" => &mut self.st[1],
            "texture_u" => &mut self.texture_uv[0],
            "texture_v" => &mut self.texture_uv[1],
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = Some(value);
        PropertyAccessResult::Set
    }
}

/// A PLY face: its vertex indices, from its `vertex_indices` (or `vertex_index`) list.
struct PlyFace {
    indices: Option<Vec<i64>>,
}

impl ply_rs_bw::ply::PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace { indices: None }
    }

    fn set_property(
        &mut self,
        name: &str,
        property: ply_rs_bw::ply::Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::{Property, PropertyAccessResult};
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        fn widen<T: Copy + Into<i64>>(v: &[T]) -> Vec<i64> {
            v.iter().map(|&k| k.into()).collect()
        }
        self.indices = Some(match &property {
            Property::ListChar(v) => widen(v),
            Property::ListUChar(v) => widen(v),
            Property::ListShort(v) => widen(v),
            Property::ListUShort(v) => widen(v),
            Property::ListInt(v) => widen(v),
            Property::ListUInt(v) => widen(v),
            _ => return PropertyAccessResult::Ignored,
        });
        PropertyAccessResult::Set
    }
}

/// A PLY element trilux does not use, read past.
struct PlySkipped;

impl ply_rs_bw::ply::PropertyAccess for PlySkipped {
    fn new() -> Self {
        PlySkipped
    }
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

    /// The same mesh written as ASCII and as big-endian binary PLY, with properties and an
    /// element trilux does not read (a double, a colour, an `edge` element before the faces),
    /// a quad split into a fan, normals and (u, v) as Mitsuba's: both read to the same
    /// positions, normals, texture coordinates (v flipped) and triangles.
    #[test]
    fn ascii_and_binary_ply_read_alike() {
        let vertices: [([f32; 3], [f32; 3], [f32; 2]); 4] = [
            ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0]),
            ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0]),
            ([1.0, 2.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0]),
            ([0.0, 2.0, 0.5], [0.0, 0.6, 0.8], [0.0, 0.25]),
        ];
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\ncomment written by a test\nelement vertex 4\n\
                 property float x\nproperty float y\nproperty float z\nproperty double quality\n\
                 property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n\
                 property float u\nproperty float v\nelement edge 1\nproperty int vertex1\n\
                 property int vertex2\nelement face 2\nproperty list uchar int vertex_indices\n\
                 end_header\n"
            )
        };
        let mut ascii = header("ascii");
        for (p, n, uv) in vertices {
            ascii += &format!(
                "{} {} {} 0.5 {} {} {} 255 {} {}\n",
                p[0], p[1], p[2], n[0], n[1], n[2], uv[0], uv[1]
            );
        }
        ascii += "0 2\n4 0 1 2 3\n3 0 2 3\n";
        let mut binary = header("binary_big_endian").into_bytes();
        for (p, n, uv) in vertices {
            p.iter().for_each(|x| binary.extend(x.to_be_bytes()));
            binary.extend(0.5f64.to_be_bytes());
            n.iter().for_each(|x| binary.extend(x.to_be_bytes()));
            binary.push(255);
            uv.iter().for_each(|x| binary.extend(x.to_be_bytes()));
        }
        [0i32, 2]
            .iter()
            .for_each(|k| binary.extend(k.to_be_bytes()));
        for face in [&[0i32, 1, 2, 3][..], &[0, 2, 3]] {
            binary.push(face.len() as u8);
            face.iter().for_each(|k| binary.extend(k.to_be_bytes()));
        }
        let dir = std::env::temp_dir().join(format!("trilux-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        let read = |name: &str, bytes: &[u8]| {
            let path = dir.join(name);
            std::fs::write(&path, bytes).expect("written");
            read_ply(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        let (a, b) = (read("a.ply", ascii.as_bytes()), read("b.ply", &binary));
        std::fs::remove_dir_all(&dir).ok();
        for mesh in [&a, &b] {
            assert_eq!(mesh.positions, vertices.map(|v| Vec3::from(v.0)).to_vec());
            assert_eq!(mesh.normals, vertices.map(|v| Vec3::from(v.1)).to_vec());
            assert_eq!(
                mesh.tex_coords,
                vertices.map(|v| vec2(v.2[0], 1.0 - v.2[1])).to_vec()
            );
            assert_eq!(mesh.indices, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        }
    }

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
