//! The radiosity mesh: a half-edge quad mesh over the scene's surfaces. Quads come from the
//! scene's quads as they are, spheres and rings are rasterized into quads, triangles enter as
//! quads with two coincident corners. Every face remembers the primitive it lies on and the
//! rectangle of that primitive's parameter space it covers, so a ray hit on the primitive
//! finds its face by descending the subdivision tree. Splitting a face keeps it as the parent
//! of its four children; the leaves are the patches.

use std::collections::HashMap;

use crate::geometry::{quad_normal, Shape, Tessellation, Vec3};
use crate::scene::{PrimKind, PrimRef, Scene};

/// No half-edge (a border edge has no twin).
pub const NONE: u32 = u32::MAX;

/// The part of a quad or triangle that is its back side: with `--two-sided` every polygon
/// gets a back-facing face of its own (RenderPark's `sides 2`), so that each side gathers and
/// shows its own light. Its vertices are welded apart from the front's, so the two sides are
/// never neighbours across an edge or a corner.
pub const BACK: u32 = 1;

/// A directed edge of one face: from `vertex` to the next half-edge's vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HalfEdge {
    pub vertex: u32,
    pub face: u32,
    pub next: u32,
    /// The opposite half-edge of the neighbouring face, or `NONE` on a border (or across a
    /// T-junction left by adaptive subdivision).
    pub twin: u32,
}

/// A quad face: its first half-edge (the others follow through `next`), where it lies in its
/// primitive's parameter space, and its place in the subdivision tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face {
    pub half_edge: u32,
    pub material: u32,
    pub prim: PrimRef,
    /// The part of an analytic shape the face lies on (see `Shape`); on polygons 0 for the
    /// front and `BACK` for the back side.
    pub part: u32,
    /// (u0, v0, u1, v1): the rectangle of the primitive's parameters the face covers; its
    /// corners in half-edge order are (u0,v0), (u1,v0), (u1,v1), (u0,v1).
    pub param: [f32; 4],
    pub parent: u32,
    /// The first of four consecutive child faces, or `NONE` for a leaf.
    pub children: u32,
    pub level: u32,
}

#[derive(Clone, Debug, Default)]
pub struct QuadMesh {
    pub vertices: Vec<Vec3>,
    pub half_edges: Vec<HalfEdge>,
    pub faces: Vec<Face>,
    /// The faces that are not split, in creation order: the patches.
    pub leaves: Vec<u32>,
    /// For each primitive, its top-level faces: quads and triangles have one (two with their
    /// back), spheres H×V (row by row from the bottom), rings 4×N (outer, inner, bottom, top).
    roots: HashMap<PrimRef, Roots>,
    /// Vertex positions seen so far (bit patterns, and 1 on back sides), so equal positions
    /// on the same side share one vertex.
    welded: HashMap<[u32; 4], u32>,
    /// Midpoints already made, keyed by their edge's two vertices (smaller first).
    midpoints: HashMap<(u32, u32), u32>,
}

/// The top-level faces of one primitive: `count` consecutive faces from `first`, a grid of
/// `cols` × `rows` cells of the parameter space of each of its parts, part after part.
#[derive(Clone, Copy, Debug)]
struct Roots {
    first: u32,
    count: u32,
    cols: u32,
    rows: u32,
}

impl QuadMesh {
    /// The mesh of every primitive of the scene; polygons lit behind (`Scene::lit_behind`:
    /// `--two-sided`, a Mitsuba `twosided` BSDF) have a back.
    pub fn from_scene(scene: &Scene, raster: Tessellation) -> QuadMesh {
        let mut mesh = QuadMesh::default();
        let polygons = scene
            .quads
            .iter()
            .enumerate()
            .map(|(i, q)| (PrimKind::Quad, i, q.material, q.vertices));
        let triangles = (0..scene.triangles.len()).map(|i| {
            let [a, b, c] = scene.triangles.vertices(i);
            (
                PrimKind::Triangle,
                i,
                scene.triangles.materials[i],
                [a, b, c, c],
            )
        });
        // Instanced triangles each a patch of their own, in the world: each instance is lit
        // differently.
        let instanced = (0..scene.instancing.triangle_count()).map(|i| {
            let [a, b, c] = scene.instanced_vertices(i as u32);
            (
                PrimKind::Instanced,
                i,
                scene.instancing.material(i as u32),
                [a, b, c, c],
            )
        });
        for (kind, i, material, corners) in polygons.chain(triangles).chain(instanced) {
            let prim = PrimRef {
                kind,
                index: i as u32,
            };
            mesh.add_root(prim, material, 0, corners, [0.0, 0.0, 1.0, 1.0], (1, 1));
            if scene.lit_behind(material) {
                // The same parameters seen from behind: u runs the other way.
                let [c0, c1, c2, c3] = corners;
                let back = [c1, c0, c3, c2];
                mesh.add_root(prim, material, BACK, back, [1.0, 0.0, 0.0, 1.0], (1, 1));
            }
        }
        for (i, s) in scene.shapes.iter().enumerate() {
            let prim = PrimRef {
                kind: PrimKind::Shape,
                index: i as u32,
            };
            let shape = s.shape;
            let (cols, rows) = shape.grid(&raster);
            for part in 0..shape.part_count() {
                for row in 0..rows {
                    for col in 0..cols {
                        let point = |pu, pv| shape.point_at(part, pu, pv);
                        let outward = |p| shape.normal_at(p, part);
                        let (param, corners) = oriented(cell(col, row, cols, rows), point, outward);
                        mesh.add_root(prim, s.material, part, corners, param, (cols, rows));
                    }
                }
            }
        }
        mesh.leaves = (0..mesh.faces.len() as u32).collect();
        mesh.link_twins();
        mesh
    }

    /// Adds a top-level face, turned so that its normal points out of the primitive's front.
    fn add_root(
        &mut self,
        prim: PrimRef,
        material: u32,
        part: u32,
        corners: [Vec3; 4],
        param: [f32; 4],
        grid: (u32, u32),
    ) {
        let face = self.faces.len() as u32;
        let (cols, rows) = grid;
        self.roots
            .entry(prim)
            .or_insert(Roots {
                first: face,
                count: 0,
                cols,
                rows,
            })
            .count += 1;
        let back = is_back(prim, part);
        let ids = corners.map(|p| self.weld(p, back));
        self.push_face_ids(prim, material, part, ids, param, NONE, 0);
    }

    #[allow(clippy::too_many_arguments)]
    fn push_face_ids(
        &mut self,
        prim: PrimRef,
        material: u32,
        part: u32,
        ids: [u32; 4],
        param: [f32; 4],
        parent: u32,
        level: u32,
    ) -> u32 {
        let face = self.faces.len() as u32;
        let first = self.half_edges.len() as u32;
        for (k, &vertex) in ids.iter().enumerate() {
            self.half_edges.push(HalfEdge {
                vertex,
                face,
                next: first + (k as u32 + 1) % 4,
                twin: NONE,
            });
        }
        self.faces.push(Face {
            half_edge: first,
            material,
            prim,
            part,
            param,
            parent,
            children: NONE,
            level,
        });
        face
    }

    fn weld(&mut self, p: Vec3, back: bool) -> u32 {
        // +0.0 and −0.0 are the same position.
        let [x, y, z] = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f32::to_bits);
        let key = [x, y, z, back as u32];
        let next = self.vertices.len() as u32;
        let id = *self.welded.entry(key).or_insert(next);
        if id == next {
            self.vertices.push(p);
        }
        id
    }

    /// The four vertex indices of a face, in half-edge order.
    pub fn face_vertex_ids(&self, face: u32) -> [u32; 4] {
        let first = self.faces[face as usize].half_edge;
        [0, 1, 2, 3].map(|k| self.half_edges[(first + k) as usize].vertex)
    }

    /// The four corners of a face, counter-clockwise around its normal.
    pub fn face_vertices(&self, face: u32) -> [Vec3; 4] {
        self.face_vertex_ids(face)
            .map(|v| self.vertices[v as usize])
    }

    /// Splits a leaf into four at its edge midpoints and its centre; the face stays as their
    /// parent. The children cover the four quarters of its parameter rectangle, in the order
    /// (u0 side, v0 side), (u1, v0), (u1, v1), (u0, v1). The leaf list is refreshed by the
    /// callers, once per round of splits.
    fn split(&mut self, face: u32) {
        let f = self.faces[face as usize];
        if f.children != NONE {
            return;
        }
        let c = self.face_vertex_ids(face);
        let back = is_back(f.prim, f.part);
        let m = [0, 1, 2, 3].map(|k| self.midpoint(c[k], c[(k + 1) % 4], back));
        let centre = self.weld(
            (self.vertices[c[0] as usize]
                + self.vertices[c[1] as usize]
                + self.vertices[c[2] as usize]
                + self.vertices[c[3] as usize])
                * 0.25,
            back,
        );
        let [u0, v0, u1, v1] = f.param;
        let (um, vm) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
        let children = [
            ([c[0], m[0], centre, m[3]], [u0, v0, um, vm]),
            ([m[0], c[1], m[1], centre], [um, v0, u1, vm]),
            ([centre, m[1], c[2], m[2]], [um, vm, u1, v1]),
            ([m[3], centre, m[2], c[3]], [u0, vm, um, v1]),
        ];
        let first = self.faces.len() as u32;
        for (ids, param) in children {
            self.push_face_ids(f.prim, f.material, f.part, ids, param, face, f.level + 1);
        }
        self.faces[face as usize].children = first;
    }

    fn midpoint(&mut self, a: u32, b: u32, back: bool) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&m) = self.midpoints.get(&key) {
            return m;
        }
        let p = (self.vertices[a as usize] + self.vertices[b as usize]) * 0.5;
        let m = self.weld(p, back);
        self.midpoints.insert(key, m);
        m
    }

    /// Splits every leaf `times` times over.
    pub fn subdivide(&mut self, times: u32) {
        for _ in 0..times {
            let leaves = self.leaves.clone();
            self.split_many(&leaves);
        }
    }

    /// Splits the given leaves, then refreshes the leaf list and the twins once.
    pub fn split_many(&mut self, faces: &[u32]) {
        for &f in faces {
            self.split(f);
        }
        self.leaves = (0..self.faces.len() as u32)
            .filter(|&f| self.faces[f as usize].children == NONE)
            .collect();
        self.link_twins();
    }

    /// Links each leaf half-edge with the leaf half-edge running the other way between the
    /// same two vertices.
    pub fn link_twins(&mut self) {
        let mut by_edge: HashMap<(u32, u32), u32> = HashMap::new();
        for &f in &self.leaves {
            let first = self.faces[f as usize].half_edge;
            for k in 0..4 {
                let h = first + k;
                let from = self.half_edges[h as usize].vertex;
                let to = self.half_edges[self.half_edges[h as usize].next as usize].vertex;
                self.half_edges[h as usize].twin = NONE;
                if from != to {
                    by_edge.insert((from, to), h);
                }
            }
        }
        for (&(from, to), &h) in &by_edge {
            if let Some(&t) = by_edge.get(&(to, from)) {
                self.half_edges[h as usize].twin = t;
            }
        }
    }

    /// The leaves that share an edge with `face` (through twins).
    pub fn edge_neighbours(&self, face: u32) -> impl Iterator<Item = u32> + '_ {
        let first = self.faces[face as usize].half_edge;
        (0..4).filter_map(move |k| {
            let t = self.half_edges[(first + k) as usize].twin;
            (t != NONE).then(|| self.half_edges[t as usize].face)
        })
    }

    /// For each vertex, the leaves that have it as a corner.
    pub fn vertex_leaves(&self) -> Vec<Vec<u32>> {
        let mut around = vec![Vec::new(); self.vertices.len()];
        for &f in &self.leaves {
            let ids = self.face_vertex_ids(f);
            for (k, &v) in ids.iter().enumerate() {
                if !ids[..k].contains(&v) {
                    around[v as usize].push(f);
                }
            }
        }
        around
    }

    /// The leaf under parameters (u, v) of a primitive's part, with the point's parameters
    /// within that leaf in \[0,1\]².
    pub fn locate(&self, prim: PrimRef, part: u32, u: f32, v: f32) -> Option<(u32, f32, f32)> {
        let &Roots {
            first,
            count,
            cols,
            rows,
        } = self.roots.get(&prim)?;
        let col = ((u * cols as f32) as u32).min(cols - 1);
        let row = part * rows + ((v * rows as f32) as u32).min(rows - 1);
        let root = first + row * cols + col;
        if root >= first + count {
            return None;
        }
        let mut face = root;
        loop {
            let f = &self.faces[face as usize];
            let [u0, v0, u1, v1] = f.param;
            if f.children == NONE {
                let s = ((u - u0) / (u1 - u0)).clamp(0.0, 1.0);
                let t = ((v - v0) / (v1 - v0)).clamp(0.0, 1.0);
                return Some((face, s, t));
            }
            let (um, vm) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
            // A rectangle may run from high to low parameters (see `oriented`).
            let quarter = match ((u - um) * (u1 - u0) >= 0.0, (v - vm) * (v1 - v0) >= 0.0) {
                (false, false) => 0,
                (true, false) => 1,
                (true, true) => 2,
                (false, true) => 3,
            };
            face = f.children + quarter;
        }
    }

    /// Area and unit normal of a leaf.
    pub fn area_normal(&self, face: u32) -> (f32, Vec3) {
        let n = quad_normal(&self.face_vertices(face));
        let len = n.length();
        let unit = if len > 0.0 {
            n * len.recip()
        } else {
            Vec3::ZERO
        };
        (0.5 * len, unit)
    }
}

/// Whether a face of this primitive's part is the back side of a polygon.
pub fn is_back(prim: PrimRef, part: u32) -> bool {
    prim.kind != PrimKind::Shape && part == BACK
}

/// The parameter rectangle of cell (col, row) of a cols × rows grid over \[0,1\]².
fn cell(col: u32, row: u32, cols: u32, rows: u32) -> [f32; 4] {
    [
        col as f32 / cols as f32,
        row as f32 / rows as f32,
        (col + 1) as f32 / cols as f32,
        (row + 1) as f32 / rows as f32,
    ]
}

fn param_corners([u0, v0, u1, v1]: [f32; 4]) -> [(f32, f32); 4] {
    [(u0, v0), (u1, v0), (u1, v1), (u0, v1)]
}

/// The corners of a rasterized cell, counter-clockwise around the surface's outward normal
/// (`outward` at a point): when the cell's (u, v) corners run the other way, its rectangle is
/// reversed in u so that its corners, children and parameters all follow the outward order.
fn oriented(
    param: [f32; 4],
    point: impl Fn(f32, f32) -> Vec3,
    outward: impl Fn(Vec3) -> Vec3,
) -> ([f32; 4], [Vec3; 4]) {
    let corners = param_corners(param).map(|(u, v)| point(u, v));
    let [u0, v0, u1, v1] = param;
    let middle = point(0.5 * (u0 + u1), 0.5 * (v0 + v1));
    if quad_normal(&corners).dot(outward(middle)) >= 0.0 {
        return (param, corners);
    }
    let reversed = [u1, v0, u0, v1];
    (reversed, param_corners(reversed).map(|(u, v)| point(u, v)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;
    use crate::scene::{Material, Quad, ShapePrim};

    fn cube() -> Scene {
        let v = |x: f32, y: f32, z: f32| vec3(x, y, z);
        let faces = [
            [
                v(-1., -1., 1.),
                v(-1., 1., 1.),
                v(1., 1., 1.),
                v(1., -1., 1.),
            ],
            [
                v(-1., -1., -1.),
                v(1., -1., -1.),
                v(1., 1., -1.),
                v(-1., 1., -1.),
            ],
            [
                v(-1., 1., -1.),
                v(1., 1., -1.),
                v(1., 1., 1.),
                v(-1., 1., 1.),
            ],
            [
                v(-1., -1., -1.),
                v(-1., -1., 1.),
                v(1., -1., 1.),
                v(1., -1., -1.),
            ],
            [
                v(-1., -1., -1.),
                v(-1., 1., -1.),
                v(-1., 1., 1.),
                v(-1., -1., 1.),
            ],
            [
                v(1., -1., -1.),
                v(1., -1., 1.),
                v(1., 1., 1.),
                v(1., 1., -1.),
            ],
        ];
        Scene {
            materials: vec![Material::default()],
            quads: faces.iter().map(|f| Quad::new(*f, None, 0)).collect(),
            ..Default::default()
        }
    }

    fn raster() -> Tessellation {
        Tessellation {
            sphere: (8, 6),
            ring: 12,
        }
    }

    #[test]
    fn closed_cube_has_a_twin_for_every_half_edge_after_subdivision() {
        let mut mesh = QuadMesh::from_scene(&cube(), raster());
        for level in 0..3 {
            assert_eq!(mesh.leaves.len(), 6 << (2 * level));
            for &f in &mesh.leaves {
                let first = mesh.faces[f as usize].half_edge;
                for k in 0..4 {
                    let h = mesh.half_edges[(first + k) as usize];
                    assert_ne!(h.twin, NONE);
                    let t = mesh.half_edges[h.twin as usize];
                    assert_eq!(t.twin, first + k);
                    assert_eq!(t.vertex, mesh.half_edges[h.next as usize].vertex);
                }
            }
            mesh.subdivide(1);
        }
        // Parents are kept: 6 + 24 + 96 + 384 faces.
        assert_eq!(mesh.faces.len(), 6 + 24 + 96 + 384);
        let total: f32 = mesh.leaves.iter().map(|&f| mesh.area_normal(f).0).sum();
        // Measured exactly 24; the bound is ten f32 spacings at 24.
        assert!((total - 24.0).abs() < 2e-5);
    }

    #[test]
    fn rasterized_sphere_and_ring_faces_point_outwards_and_are_found_again() {
        let sphere = crate::geometry::SphereShape {
            centre: vec3(1.0, 2.0, 3.0),
            radius: 0.5,
        };
        let ring = crate::geometry::RingShape {
            base: vec3(0.0, 0.0, 0.0),
            height: 0.3,
            r_in: 0.8,
            r_out: 1.0,
        };
        let scene = Scene {
            materials: vec![Material::default()],
            shapes: vec![
                ShapePrim {
                    shape: sphere.into(),
                    material: 0,
                },
                ShapePrim {
                    shape: ring.into(),
                    material: 0,
                },
            ],
            ..Default::default()
        };
        let mut mesh = QuadMesh::from_scene(&scene, raster());
        assert_eq!(mesh.leaves.len(), 8 * 6 + 4 * 12);
        mesh.subdivide(1);
        for &f in &mesh.leaves.clone() {
            let face = mesh.faces[f as usize];
            let (area, n) = mesh.area_normal(f);
            let c = mesh.face_vertices(f).iter().fold(Vec3::ZERO, |a, &b| a + b) * 0.25;
            let outward = scene.shapes[face.prim.index as usize]
                .shape
                .normal_at(c, face.part);
            assert!(
                area == 0.0 || n.dot(outward) > 0.0,
                "face {f} faces inwards"
            );
            let [u0, v0, u1, v1] = face.param;
            let (u, v) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
            let (found, s, t) = mesh.locate(face.prim, face.part, u, v).unwrap();
            assert_eq!(found, f);
            // Measured at most 7.2e-7 (Newton's iterations stop near f32's rounding); the
            // bound is ten times that.
            assert!((s - 0.5).abs() < 7e-6 && (t - 0.5).abs() < 7e-6);
        }
    }
}
