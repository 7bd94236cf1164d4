//! Patches: the leaves of the radiosity mesh with what the solver needs of each — area,
//! normal, albedo, emission — and points on them, both on the flat patch (for form factors)
//! and on the primitive it approximates (for visibility rays against the original geometry).

use crate::engines::radiosity::mesh::{self, QuadMesh, NONE};
use crate::geometry::{offset_ray_origin, point_error, Shape, Vec3};
use crate::scene::procedural::disc_half_widths;
use crate::scene::{Color, PrimKind, PrimRef, Scene};

#[derive(Clone, Debug)]
pub struct Patch {
    /// The mesh face this patch is.
    pub face: u32,
    pub corners: [Vec3; 4],
    /// Area-weighted centroid (the point a one-sample form factor uses).
    pub centre: Vec3,
    pub normal: Vec3,
    pub area: f32,
    /// Share of the area in the triangle (c0, c1, c2); the rest is in (c0, c2, c3).
    first_share: f32,
    pub albedo: Color,
    pub emitted: Color,
    pub prim: PrimRef,
    /// The part of an analytic shape the patch lies on (see `Shape`); 0 on polygons.
    pub part: u32,
}

impl Patch {
    /// The point of the patch at (s, t) ∈ \[0,1\]², uniform in area.
    pub fn point(&self, s: f32, t: f32) -> Vec3 {
        let c = &self.corners;
        let (a, b, d, s) = if s < self.first_share {
            (c[0], c[1], c[2], s / self.first_share)
        } else {
            (
                c[0],
                c[2],
                c[3],
                (s - self.first_share) / (1.0 - self.first_share),
            )
        };
        let root = s.clamp(0.0, 1.0).sqrt();
        a * (1.0 - root) + b * (root * (1.0 - t)) + d * (root * t)
    }
}

/// The leaves of `mesh` as patches. Albedo is the material's (a texture's colour at the
/// patch centre when it has one, a procedural texture's averaged over the patch).
pub fn patches(scene: &Scene, mesh: &QuadMesh) -> Vec<Patch> {
    mesh.leaves
        .iter()
        .map(|&face| {
            let f = &mesh.faces[face as usize];
            let corners = mesh.face_vertices(face);
            let (area, normal) = mesh.area_normal(face);
            let area0 = 0.5
                * (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .length();
            let area1 = 0.5
                * (corners[2] - corners[0])
                    .cross(corners[3] - corners[0])
                    .length();
            let total = area0 + area1;
            let first_share = if total > 0.0 { area0 / total } else { 0.5 };
            let centroid0 = (corners[0] + corners[1] + corners[2]) * (1.0 / 3.0);
            let centroid1 = (corners[0] + corners[2] + corners[3]) * (1.0 / 3.0);
            let centre = centroid0 * first_share + centroid1 * (1.0 - first_share);
            let m = &scene.materials[f.material as usize];
            let albedo = match m.texture {
                Some(t) => {
                    let [u0, v0, u1, v1] = f.param;
                    let (u, v) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
                    // A triangle's face parameters are (b1 / (1 − b2), b2) of its
                    // barycentrics (see `Solution::locate`).
                    let parameters = match f.prim.kind {
                        PrimKind::Triangle | PrimKind::Instanced => (u * (1.0 - v), v),
                        PrimKind::Quad | PrimKind::Shape => (u, v),
                    };
                    scene.textures[t].lookup(scene.tex_coords_at(f.prim, parameters))
                }
                // A pattern is averaged over the patch (a disc of the patch's area).
                None => match &m.procedural {
                    Some(p) => p.albedo(
                        centre,
                        disc_half_widths(normal, (area / std::f32::consts::PI).sqrt()),
                    ),
                    None => m.diffuse,
                },
            };
            Patch {
                face,
                corners,
                centre,
                normal,
                area,
                first_share,
                albedo,
                // A Mitsuba emitter sends light from its front alone, whatever its BSDF.
                emitted: if mesh::is_back(f.prim, f.part) && !scene.two_sided_quads {
                    Color::ZERO
                } else {
                    m.emitted
                },
                prim: f.prim,
                part: f.part,
            }
        })
        .collect()
}

/// A point of a patch moved onto the surface of the primitive it approximates, with that
/// surface's outward normal there and the ray origin offset off it (towards `side`, the
/// direction the ray will leave in).
pub fn on_primitive(scene: &Scene, patch: &Patch, p: Vec3, side: Vec3) -> Vec3 {
    on_surface(scene, (patch.prim, patch.part, patch.normal), p, side)
}

/// `on_primitive` for a point of a face of primitive `prim`'s `part`, of unit normal
/// `normal` (a mesh face's, before its patch is made).
pub fn on_surface(
    scene: &Scene,
    (prim, part, normal): (PrimRef, u32, Vec3),
    p: Vec3,
    side: Vec3,
) -> Vec3 {
    let i = prim.index as usize;
    let (point, normal, magnitude) = match prim.kind {
        PrimKind::Quad | PrimKind::Triangle | PrimKind::Instanced => {
            (p, normal, p.abs().max_element())
        }
        PrimKind::Shape => {
            let shape = &scene.shapes[i].shape;
            let (q, n) = shape.project(p, part);
            (q, n, shape.magnitude())
        }
    };
    let n = if normal.dot(side) < 0.0 {
        -normal
    } else {
        normal
    };
    offset_ray_origin(point, n, point_error(magnitude))
}

/// For each patch, the earlier patch it coincides with exactly — the same corners, facing the
/// same way — or `NONE`. Such twins are one surface (the hospital of RenderPark's scenes
/// holds 12,388 of them among 25,099 faces: its structure file already has the furniture the
/// main file adds); solved as two, every receiver would see their light twice (the
/// hierarchical solver's sweeps diverged). `Solution::solve` gives the solvers each twin
/// with no area and copies its first copy's light to it.
pub fn twins(patches: &[Patch]) -> Vec<u32> {
    let mut first: std::collections::HashMap<([[u32; 3]; 4], [i8; 3]), u32> =
        std::collections::HashMap::new();
    patches
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut corners = p
                .corners
                .map(|c| (c + Vec3::ZERO).to_array().map(f32::to_bits));
            corners.sort_unstable();
            let facing = p.normal.to_array().map(|x| (x * 100.0).round() as i8);
            *first.entry((corners, facing)).or_insert(i as u32)
        })
        .enumerate()
        .map(|(i, f)| if f == i as u32 { NONE } else { f })
        .collect()
}
