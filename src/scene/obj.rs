//! Standard Wavefront OBJ + MTL through `tobj`: triangles (polygons are triangulated), albedo
//! from `Kd`, emission from `Ke`, mirror from `Ks` with `illum 3/5`, transmission from `Tf`
//! (or `d` < 1) with `Ni` as the index of refraction.

use std::path::Path;

use super::error::SceneError;
use super::{Material, Scene, TriangleMesh};
use crate::geometry::{vec2, vec3, Vec3};

const DEFAULT_ALBEDO: f32 = 0.8;

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    check_values(path)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &options).map_err(|e| SceneError::Obj {
        file: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut warnings = Vec::new();
    let mtl = materials.unwrap_or_else(|e| {
        warnings.push(format!("{}: materials not loaded: {e}", path.display()));
        Vec::new()
    });
    let mut scene = Scene {
        path: path.to_path_buf(),
        background: Vec3::ZERO,
        warnings,
        ..Scene::default()
    };
    scene.materials = mtl.iter().map(convert_material).collect();
    // Faces without a material get a grey default, appended last.
    let default_material = scene.materials.len() as u32;
    scene.materials.push(Material {
        diffuse: Vec3::splat(DEFAULT_ALBEDO),
        ..Material::default()
    });

    let mut mesh = TriangleMesh::default();
    let all_have_uv = models
        .iter()
        .all(|m| m.mesh.texcoords.len() / 2 == m.mesh.positions.len() / 3);
    let all_have_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| vec3(p[0], p[1], p[2])));
        if all_have_uv {
            mesh.tex_coords
                .extend(m.texcoords.chunks_exact(2).map(|t| vec2(t[0], t[1])));
        }
        if all_have_normals {
            mesh.normals
                .extend(m.normals.chunks_exact(3).map(|n| vec3(n[0], n[1], n[2])));
        }
        let material = m
            .material_id
            .filter(|&k| k < mtl.len())
            .map_or(default_material, |k| k as u32);
        for tri in m.indices.chunks_exact(3) {
            if tri.iter().any(|&k| k as usize >= count) {
                return Err(SceneError::Obj {
                    file: path.to_path_buf(),
                    message: format!("object `{}`: face index out of range", model.name),
                });
            }
            mesh.indices
                .push([base + tri[0], base + tri[1], base + tri[2]]);
            mesh.materials.push(material);
        }
    }
    scene.triangles = mesh;
    Ok(scene)
}

/// The numbers of the file's vertex lines (`v`, `vn`, `vt`) checked against the range of scene
/// values, each refused with its line and column: `tobj` takes `nan`, `inf` and 1e38 as
/// numbers and does not say where a value came from.
fn check_values(path: &Path) -> Result<(), SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split('#').next().unwrap_or("").split_whitespace();
        if !matches!(words.next(), Some("v" | "vn" | "vt")) {
            continue;
        }
        for word in words {
            let Ok(x) = word.parse::<f32>() else {
                continue; // tobj says what it cannot read
            };
            if !super::range::in_range(x) {
                let column = word.as_ptr() as usize - line.as_ptr() as usize + 1;
                return Err(SceneError::Invalid {
                    file: path.to_path_buf(),
                    line: n as u32 + 1,
                    column: column as u32,
                    message: format!("`{word}` is out of range: {}", super::range::RANGE),
                });
            }
        }
    }
    Ok(())
}

fn rgb(v: Option<[f32; 3]>) -> Vec3 {
    v.map_or(Vec3::ZERO, |c| vec3(c[0], c[1], c[2]))
}

fn param(m: &tobj::Material, key: &str) -> Option<Vec3> {
    let values: Vec<f32> = m
        .unknown_param
        .get(key)?
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    match values[..] {
        [x] => Some(Vec3::splat(x)),
        [x, y, z, ..] => Some(vec3(x, y, z)),
        _ => None,
    }
}

fn convert_material(m: &tobj::Material) -> Material {
    let illum = m.illumination_model.unwrap_or(2);
    let mirror = matches!(illum, 3 | 5 | 7);
    let ior = m.optical_density.filter(|n| *n > 0.0).unwrap_or(1.5);
    let transmitted = param(m, "Tf")
        .filter(|_| matches!(illum, 4 | 6 | 7 | 9))
        .or_else(|| {
            m.dissolve
                .filter(|d| *d < 1.0)
                .map(|d| Vec3::splat(1.0 - d))
        })
        .unwrap_or(Vec3::ZERO);
    Material {
        diffuse: rgb(m.diffuse),
        texture_file: m.diffuse_texture.as_ref().map(Into::into),
        reflective: if mirror { rgb(m.specular) } else { Vec3::ZERO },
        emitted: rgb(m.emissive),
        transmitted,
        ior,
        ..Material::default()
    }
}
