//! Mitsuba 3 scenes (`.xml`): the plugins trilux knows made into a `Scene`, each one that it
//! does not render exactly named in a warning, and every plugin or parameter it does not read
//! named too (file:line:column). docs/scene-format.md lists what is read and how.
//!
//! Mitsuba's conventions, and what they become here:
//! * a sensor's `to_world` (usually a `lookat`) gives the camera: its origin, +z the view
//!   direction, +y up; `fov` along `fov_axis` becomes the course camera's angle across the
//!   larger image side;
//! * the film's size, the sampler's `sample_count` and the integrator's `max_depth` (which
//!   counts the camera's segment: 2 is direct light) are the scene's `RenderHints`, which the
//!   command line's `-size`, `-num_antialias_samples` and `--max-depth` override; so is an
//!   ambient light of 0 (`-ambient_light`): Mitsuba has no such term;
//! * every shape becomes triangles with per-vertex shading normals (a mesh's own, or its
//!   faces' for `face_normals` and meshes without them), except `sphere`, the analytic
//!   sphere; texture coordinates follow trilux's convention (t = 0 at the image's bottom);
//! * colours are linear sRGB; spectra are integrated as Mitsuba's RGB variants integrate them
//!   (`spectrum.rs`).

mod cie;
mod meshes;
mod spectrum;
mod xml;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{DMat4, DVec3, Mat3};

use self::meshes::Mesh;
use self::spectrum::{spectrum_to_rgb, SpectrumUse};
use self::xml::{Plugin, Value};
use super::bsdf::{Bsdf, Microfacet, MicrofacetKind, Plastic, Principled, PrincipledThin};
use super::bsdf_support::{MitsubaBsdf, PluginSupport};
use super::bsdf_texture::{BsdfParameter, TexturedParameter};
use super::medium::{Albedo, Heterogeneous, Medium};
use super::sky::{Sky, SkyMap};
use super::volume_grid::GridVolume;
use super::{
    DeltaKind, DeltaLight, Material, RenderHints, Scene, SceneError, ShadingTilt, ShapePrim,
    Texture, TriangleMesh,
};
use crate::camera::{Camera, Projection};
use crate::color::Color;
use crate::geometry::{SphereShape, Vec2, Vec3};
use crate::image_io::read_volume_grid;

/// Segments around a `disk` or a `cylinder` (their triangles' shading normals are smooth).
const ROUND_SEGMENTS: u32 = 128;

/// Shadow rays a light for the ray tracer and the photon engine on Mitsuba scenes when
/// `-num_shadow_samples` is not given (with it, radiosity's form factors test visibility).
/// The course's 0 casts no shadow: a Mitsuba scene's lights are the only light, and its
/// shadows are the image. 16 is `--time-limit`'s choice too. On a lamp over a cube and a
/// floor (direct light, 16 samples a pixel), the ray tracer's relMSE against the path
/// tracer's converged image: 1.4e-2 with 0 (5% bright), 2.0e-3 with 1 (the centre's hard
/// shadow), 1.7e-4 with 4, 5.7e-5 with 16 (the lowest time × relMSE with 8), 4.5e-5 with 32.
pub const SHADOW_SAMPLES: u32 = 16;

/// Reads a Mitsuba 3 scene; `defines` are the command line's `--define name=value`s.
pub fn load(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
    let root = xml::read(path, defines)?;
    let mut builder = Builder {
        scene: Scene {
            path: path.to_path_buf(),
            smooth_normals: true,
            render_hints: RenderHints {
                ambient_light: Some(Color::ZERO),
                num_shadow_samples: Some(SHADOW_SAMPLES),
                // A rectangle is two triangles: the progressive solver's patch each showed a
                // lamp's floor at a fifth of the path tracer's mean, the hierarchical solver's
                // elements within 1%.
                hierarchical_radiosity: true,
                ..RenderHints::default()
            },
            ..Scene::default()
        },
        materials: HashMap::new(),
        media: HashMap::new(),
        bsdf_textures: Vec::new(),
        bsdf_plugins: Vec::new(),
        mesh_files: HashMap::new(),
        groups: HashMap::new(),
        group_mesh: None,
    };
    for child in &root.children {
        let plugin = &child.plugin;
        match plugin.tag.as_str() {
            "integrator" => builder.integrator(plugin)?,
            "sensor" => builder.sensor(plugin)?,
            "shape" => builder.shape(plugin, DMat4::IDENTITY)?,
            "emitter" => builder.emitter(plugin)?,
            // Made where a shape refers to them; reported below if none does.
            "bsdf" | "texture" | "medium" | "spectrum" => {}
            other => {
                return Err(plugin.at.error(format!(
                    "<{other}> cannot stand in <scene>: expected integrator, sensor, shape, emitter, bsdf, texture or medium"
                )))
            }
        }
    }
    let mut unused = Vec::new();
    root.unused(&mut unused);
    let mut seen = std::collections::HashSet::new();
    unused.retain(|w| seen.insert(w.clone()));
    builder.scene.warnings.extend(unused);
    Ok(builder.scene)
}

struct Builder {
    scene: Scene,
    /// The material made of each BSDF plugin (by its address: a plugin referenced by several
    /// shapes is one material).
    materials: HashMap<*const Plugin, u32>,
    /// The medium made of each medium plugin.
    media: HashMap<*const Plugin, usize>,
    /// The textured parameters of the BSDF being made (`scalar` adds to them; `bsdf` gives
    /// them to its material).
    bsdf_textures: Vec<TexturedParameter>,
    /// The plugins of the BSDF being made, outermost first (`bsdf_alone` adds each;
    /// `shape_material` gives them to the scene's `mitsuba_bsdfs`).
    bsdf_plugins: Vec<PluginSupport>,
    /// Each mesh file read, by its shape type, path and shape index: a file that several
    /// shapes name is read once (Mitsuba's BSDF tests place one 2.8 MB sphere twelve times).
    mesh_files: HashMap<(String, PathBuf, u32), Mesh>,
    /// The group (`Scene::instancing`) made of each shapegroup plugin, made where an instance
    /// first refers to it.
    groups: HashMap<*const Plugin, u32>,
    /// The triangles of the shapegroup being made (in its own space), where `shape` adds a
    /// mesh while one is; None otherwise (meshes go to the scene's triangles).
    group_mesh: Option<TriangleMesh>,
}

impl Builder {
    fn warn(&mut self, at: &xml::Location, message: impl std::fmt::Display) {
        self.scene.warnings.push(format!("{at}: {message}"));
    }

    fn integrator(&mut self, p: &Plugin) -> Result<(), SceneError> {
        p.mark_used();
        match p.kind.as_str() {
            // Mitsuba's `moment` integrator renders what it wraps (and its second moment).
            "moment" => {
                for child in p.children_tagged("integrator") {
                    self.integrator(&child.plugin)?;
                }
            }
            "path" | "volpath" | "volpathmis" | "direct" => {
                let depth = if p.kind == "direct" {
                    2
                } else {
                    p.integer("max_depth", -1)?
                };
                // Mitsuba counts the camera's segment: max_depth 1 shows emitters only, 2
                // direct light; −1 is no limit.
                self.scene.render_hints.max_depth = match depth {
                    -1 => None,
                    d if d >= 1 => Some((d - 1) as u32),
                    d => {
                        return Err(p.at.error(format!(
                            "max_depth {d}: expected -1 (no limit) or at least 1"
                        )))
                    }
                };
                let _ = p.integer("rr_depth", 5)?;
                if p.kind == "direct" {
                    for name in ["emitter_samples", "bsdf_samples", "shading_samples"] {
                        let _ = p.integer(name, 1)?;
                    }
                }
                self.scene.hide_emitters = p.boolean("hide_emitters", false)?;
            }
            other => {
                return Err(p.at.error(format!(
                    "integrator \"{other}\" is not supported: expected path, volpath, volpathmis, direct or moment"
                )))
            }
        }
        Ok(())
    }

    fn sensor(&mut self, p: &Plugin) -> Result<(), SceneError> {
        p.mark_used();
        let to_world = p.transform("to_world")?;
        let _ = p.float("near_clip", 1e-2)?;
        let _ = p.float("far_clip", 1e4)?;
        let mut width = 768u32;
        let mut height = 576u32;
        for film in p.children_tagged("film") {
            let film = &film.plugin;
            film.mark_used();
            width = positive(film, "width", 768)?;
            height = positive(film, "height", 576)?;
            for name in ["pixel_format", "component_format", "file_format"] {
                let _ = film.string(name)?;
            }
            let _ = film.boolean("banner", false)?;
            for filter in film.children_tagged("rfilter") {
                filter.plugin.mark_used();
                if filter.plugin.kind != "box" {
                    self.warn(
                        &filter.plugin.at,
                        format!(
                            "rfilter \"{}\": trilux averages a pixel's samples with equal weights (box)",
                            filter.plugin.kind
                        ),
                    );
                }
            }
        }
        if width.max(height) > super::MAX_IMAGE_SIDE {
            return Err(p.at.error(format!(
                "film {width} × {height}: a side may be at most {}",
                super::MAX_IMAGE_SIDE
            )));
        }
        self.scene.render_hints.size = Some((width, height));
        for sampler in p.children_tagged("sampler") {
            let sampler = &sampler.plugin;
            sampler.mark_used();
            self.scene.render_hints.samples = Some(positive(sampler, "sample_count", 4)?);
            let _ = sampler.integer("seed", 0)?;
        }
        // Mitsuba takes a sensor's medium child, under any name, as the medium it is in.
        if let Some(medium) = p.children_tagged("medium").next() {
            self.scene.camera_medium = Some(self.medium(&medium.plugin)?);
        }
        let origin = to_world.transform_point3(DVec3::ZERO);
        let forward = to_world.transform_vector3(DVec3::Z);
        let up = to_world.transform_vector3(DVec3::Y);
        let left = to_world.transform_vector3(DVec3::X);
        if forward.length_squared() == 0.0 || up.length_squared() == 0.0 {
            return Err(p.at.error("the sensor's to_world is degenerate"));
        }
        if forward.cross(up).dot(left) > 0.0 {
            self.warn(
                &p.at,
                "the sensor's to_world mirrors the image (trilux renders it unmirrored)",
            );
        }
        let aspect = width as f64 / height as f64;
        let projection = match p.kind.as_str() {
            "perspective" | "thinlens" => {
                // Mitsuba's default: a 50 mm lens on 36 × 24 mm film, across its diagonal.
                let (fov, axis) = match p.property("fov") {
                    Some(_) => {
                        let axis = p.string("fov_axis")?.map_or("x", |(a, _)| a).to_string();
                        (p.float("fov", 0.0)?, axis)
                    }
                    None => {
                        let focal = match p.string("focal_length")? {
                            Some((f, at)) => f.trim_end_matches("mm").parse::<f64>().map_err(|_| {
                                at.error(format!("focal_length \"{f}\": expected e.g. 50mm"))
                            })?,
                            None => 50.0,
                        };
                        let diagonal = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
                        (2.0 * (diagonal / (2.0 * focal)).atan().to_degrees(), "diagonal".to_string())
                    }
                };
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(p.at.error(format!("fov {fov}: expected (0, 180) degrees")));
                }
                let t = (fov.to_radians() / 2.0).tan();
                let diagonal = (aspect * aspect + 1.0).sqrt();
                // The half-width's tangent along x.
                let tx = match axis.as_str() {
                    "x" => t,
                    "y" => t * aspect,
                    "diagonal" => t * aspect / diagonal,
                    "smaller" if aspect < 1.0 => t,
                    "smaller" => t * aspect,
                    "larger" if aspect >= 1.0 => t,
                    "larger" => t * aspect,
                    other => {
                        return Err(p.at.error(format!(
                            "fov_axis \"{other}\": expected x, y, diagonal, smaller or larger"
                        )))
                    }
                };
                // The course camera's angle spans the larger side.
                let larger = if aspect >= 1.0 { tx } else { tx / aspect };
                if p.kind == "thinlens" {
                    let radius = p.float("aperture_radius", 0.0)?;
                    let focus = p.float("focus_distance", 0.0)?;
                    self.scene.render_hints.lens = Some((radius as f32, focus as f32));
                }
                Projection::Perspective {
                    angle: (2.0 * larger.atan()) as f32,
                }
            }
            "orthographic" => {
                // Mitsuba's orthographic camera sees [-1, 1]² of its own space, scaled by
                // to_world: the screen's side along x is twice the x axis's length.
                let side_x = 2.0 * left.length();
                let side = if aspect >= 1.0 {
                    side_x
                } else {
                    side_x / aspect
                };
                Projection::Orthographic { size: side as f32 }
            }
            other => {
                return Err(p.at.error(format!(
                    "sensor \"{other}\" is not supported: expected perspective, thinlens or orthographic"
                )))
            }
        };
        let position = origin.as_vec3();
        self.scene.camera = Some(Camera {
            position,
            point_of_interest: position + forward.normalize().as_vec3(),
            up: up.normalize().as_vec3(),
            projection,
        });
        Ok(())
    }

    /// A shape, placed by its `to_world` and then by `outer` (an instance's sphere's, or the
    /// identity); a mesh goes into the group being made, if one is (`group_mesh`).
    fn shape(&mut self, p: &Plugin, outer: DMat4) -> Result<(), SceneError> {
        p.mark_used();
        let to_world = outer * p.transform("to_world")?;
        let in_group = self.group_mesh.is_some();
        match p.kind.as_str() {
            // As Mitsuba: no nesting, and no emitters in a group.
            "shapegroup" | "instance" if in_group => {
                return Err(p.at.error(format!(
                    "a {} cannot stand inside a shapegroup (Mitsuba does not nest instancing)",
                    p.kind
                )))
            }
            // Made where an instance refers to it.
            "shapegroup" if outer == DMat4::IDENTITY => return Ok(()),
            "shapegroup" => return Err(p.at.error("a shapegroup cannot stand inside another")),
            "instance" => return self.instance(p, to_world),
            _ => {}
        }
        if let Some(e) = p.children_tagged("emitter").next().filter(|_| in_group) {
            return Err(e.plugin.at.error(
                "an emitter cannot stand in a shapegroup: Mitsuba does not instance emitters",
            ));
        }
        let flip = p.boolean("flip_normals", false)?;
        let material = self.shape_material(p)?;
        if p.kind == "sphere" {
            let centre = to_world.transform_point3(p.point("center", DVec3::ZERO)?);
            let radius = p.float("radius", 1.0)?;
            let axes =
                [DVec3::X, DVec3::Y, DVec3::Z].map(|a| to_world.transform_vector3(a).length());
            if (axes[0] - axes[1]).abs() > 1e-6 * axes[0]
                || (axes[0] - axes[2]).abs() > 1e-6 * axes[0]
            {
                return Err(p.at.error(
                    "a sphere's to_world must scale all axes alike (trilux's sphere is round)",
                ));
            }
            if flip {
                self.warn(
                    &p.at,
                    "flip_normals on a sphere: trilux's sphere faces outward",
                );
            }
            self.scene.shapes.push(ShapePrim {
                shape: SphereShape {
                    centre: centre.as_vec3(),
                    radius: (radius * axes[0]) as f32,
                }
                .into(),
                material,
            });
            return Ok(());
        }
        let file = |name: &str| -> Result<(PathBuf, &xml::Location), SceneError> {
            p.file(name)?
                .ok_or_else(|| p.at.error(format!("shape \"{}\" needs a filename", p.kind)))
        };
        let mut read = |path: PathBuf, at: &xml::Location, index: u32| {
            let key = (p.kind.clone(), path, index);
            if let Some(mesh) = self.mesh_files.get(&key) {
                return Ok(mesh.clone());
            }
            let path = &key.1;
            let mesh = match p.kind.as_str() {
                "obj" => meshes::read_obj(path),
                "ply" => meshes::read_ply(path),
                _ => meshes::read_serialized(path, index),
            }
            .map_err(|why| at.error(format!("cannot read {}: {why}", path.display())))?;
            self.mesh_files.insert(key, mesh.clone());
            Ok::<_, SceneError>(mesh)
        };
        let mut mesh = match p.kind.as_str() {
            "obj" | "ply" => {
                let (path, at) = file("filename")?;
                read(path, at, 0)?
            }
            "serialized" => {
                let (path, at) = file("filename")?;
                let index = p.integer("shape_index", 0)?;
                let index = u32::try_from(index)
                    .map_err(|_| at.error(format!("shape_index {index}: expected ≥ 0")))?;
                read(path, at, index)?
            }
            "rectangle" => meshes::rectangle(),
            "cube" => meshes::cube(),
            "disk" => meshes::disk(ROUND_SEGMENTS),
            "cylinder" => {
                let p0 = p.point("p0", DVec3::ZERO)?;
                let p1 = p.point("p1", DVec3::Z)?;
                let radius = p.float("radius", 1.0)?;
                cylinder(p0, p1, radius, ROUND_SEGMENTS)
                    .ok_or_else(|| p.at.error("a cylinder needs p0 ≠ p1 and a radius > 0"))?
            }
            other => {
                return Err(p.at.error(format!(
                    "shape \"{other}\" is not supported: expected obj, ply, serialized, rectangle, cube, disk, sphere, cylinder, shapegroup or instance"
                )))
            }
        };
        if p.boolean("face_normals", false)? {
            mesh.normals.clear();
        }
        let into = match &mut self.group_mesh {
            Some(group) => group,
            None => &mut self.scene.triangles,
        };
        add_mesh(into, mesh, to_world, flip, material);
        Ok(())
    }

    /// An instance: its shapegroup's triangles, made once into a group (`Scene::instancing`),
    /// placed by `to_world`. The group's spheres are placed as shapes of their own, one per
    /// instance (an analytic shape is a centre and a radius: nothing to share).
    fn instance(&mut self, p: &Plugin, to_world: DMat4) -> Result<(), SceneError> {
        let group = p
            .children_tagged("shape")
            .find(|c| c.plugin.kind == "shapegroup")
            .map(|c| c.plugin.clone())
            .ok_or_else(|| p.at.error("an instance needs a <ref> to a shapegroup"))?;
        group.mark_used();
        let members = || group.children_tagged("shape").map(|c| c.plugin.clone());
        let index = match self.groups.get(&Rc::as_ptr(&group)) {
            Some(&k) => k,
            None => {
                self.group_mesh = Some(TriangleMesh::default());
                let made = members()
                    .filter(|m| m.kind != "sphere")
                    .try_for_each(|m| self.shape(&m, DMat4::IDENTITY));
                let mesh = self.group_mesh.take().unwrap_or_default();
                made?;
                let k = self.scene.instancing.add_group(mesh);
                self.groups.insert(Rc::as_ptr(&group), k);
                k
            }
        };
        for sphere in members().filter(|m| m.kind == "sphere") {
            if let Some(e) = sphere.children_tagged("emitter").next() {
                return Err(e.plugin.at.error(
                    "an emitter cannot stand in a shapegroup: Mitsuba does not instance emitters",
                ));
            }
            self.shape(&sphere, to_world)?;
        }
        self.scene
            .instancing
            .add_instance(index, to_world)
            .map_err(|why| p.at.error(why))
    }
}

/// Appends a mesh, moved by `to_world`, to `tri` (the scene's triangles, or a group's): every
/// triangle gets shading normals at its vertices (its own face's where the mesh has none).
fn add_mesh(tri: &mut TriangleMesh, mesh: Mesh, to_world: DMat4, flip: bool, material: u32) {
    let normal_matrix = to_world.inverse().transpose();
    let place = |p: Vec3| to_world.transform_point3(p.as_dvec3()).as_vec3();
    let turn = |n: Vec3| {
        let n = normal_matrix
            .transform_vector3(n.as_dvec3())
            .normalize_or_zero()
            .as_vec3();
        if flip {
            -n
        } else {
            n
        }
    };
    // Texture coordinates are one per position or none: meshes without them get (0, 0).
    let before = tri.positions.len();
    if !mesh.tex_coords.is_empty() {
        tri.tex_coords.resize(before, Vec2::ZERO);
    }
    let flat = mesh.normals.is_empty();
    let order = |t: [u32; 3]| if flip { [t[0], t[2], t[1]] } else { t };
    if flat {
        // Each triangle its own vertices, with its face's normal.
        for t in &mesh.indices {
            let t = order(*t);
            let [a, b, c] = t.map(|k| place(mesh.positions[k as usize]));
            let n = (b - a).cross(c - a).normalize_or_zero();
            let base = tri.positions.len() as u32;
            tri.positions.extend([a, b, c]);
            tri.normals.extend([n; 3]);
            if !mesh.tex_coords.is_empty() {
                tri.tex_coords
                    .extend(t.map(|k| mesh.tex_coords[k as usize]));
            }
            tri.indices.push([base, base + 1, base + 2]);
            tri.materials.push(material);
        }
    } else {
        let base = tri.positions.len() as u32;
        tri.positions
            .extend(mesh.positions.iter().map(|&p| place(p)));
        tri.normals.extend(mesh.normals.iter().map(|&n| turn(n)));
        tri.tex_coords.extend(mesh.tex_coords.iter().copied());
        for t in &mesh.indices {
            tri.indices.push(order(*t).map(|k| base + k));
            tri.materials.push(material);
        }
    }
    if !tri.tex_coords.is_empty() {
        tri.tex_coords.resize(tri.positions.len(), Vec2::ZERO);
    }
}

impl Builder {
    /// The material of a shape: its BSDF (Mitsuba's default, diffuse 0.5, without one), with
    /// its area emitter's radiance, and the media inside and outside it.
    fn shape_material(&mut self, p: &Plugin) -> Result<u32, SceneError> {
        let bsdf = p.children_tagged("bsdf").next().map(|c| c.plugin.clone());
        let emitter = p
            .children_tagged("emitter")
            .next()
            .map(|c| c.plugin.clone());
        let interior = p.child_named("interior").cloned();
        let exterior = p.child_named("exterior").cloned();
        let plain = emitter.is_none() && interior.is_none() && exterior.is_none();
        if let (true, Some(b)) = (plain, &bsdf) {
            if let Some(&k) = self.materials.get(&Rc::as_ptr(b)) {
                return Ok(k);
            }
        }
        let mut material = match &bsdf {
            Some(b) => self.bsdf(b)?,
            // One-sided, as an explicit `diffuse` (black from behind).
            None => Material {
                diffuse: Color::splat(0.5),
                bsdf: Some(Bsdf::Diffuse {
                    reflectance: Color::splat(0.5),
                }),
                ..Material::default()
            },
        };
        let plugins = std::mem::take(&mut self.bsdf_plugins);
        if let Some(e) = &emitter {
            e.mark_used();
            if e.kind != "area" {
                return Err(e.at.error(format!(
                    "emitter \"{}\" inside a shape: only \"area\" emitters belong to shapes",
                    e.kind
                )));
            }
            match e.child_named("radiance").cloned() {
                Some(t) => {
                    t.mark_used();
                    if p.kind == "sphere" {
                        return Err(t.at.error(
                            "a textured radiance on a sphere is not supported: give a colour, or a mesh",
                        ));
                    }
                    let k = self.emission_texture(&t)?;
                    material.emitted = self.scene.textures[k].mean();
                    material.emission_texture = Some(k);
                    self.warn(
                        &t.at,
                        format!(
                            "a {} radiance: the engines but the path tracer emit its mean, {}",
                            t.kind, material.emitted
                        ),
                    );
                }
                None => {
                    material.emitted = self.colour(e, "radiance", 1.0, SpectrumUse::Emission)?;
                }
            }
        }
        if let Some(m) = &interior {
            material.interior_medium = Some(self.medium(m)?);
            if material.transmitted == Vec3::ZERO {
                self.warn(
                    &m.at,
                    "a medium inside an opaque shape: light never reaches it",
                );
            }
        }
        if let Some(m) = &exterior {
            material.exterior_medium = Some(self.medium(m)?);
        }
        let k = self.scene.materials.len() as u32;
        self.scene.materials.push(material);
        if let Some(b) = &bsdf {
            self.scene.mitsuba_bsdfs.insert(
                k,
                MitsubaBsdf {
                    id: b.id.clone(),
                    plugins,
                },
            );
        }
        if let (true, Some(b)) = (plain, &bsdf) {
            self.materials.insert(Rc::as_ptr(b), k);
        }
        Ok(k)
    }

    /// A BSDF as a material. Lambertian reflection, smooth dielectrics and `null` are exact;
    /// the others are approximated by the course's lobes, with a warning that says how.
    fn bsdf(&mut self, p: &Plugin) -> Result<Material, SceneError> {
        let mut material = self.bsdf_alone(p)?;
        material
            .bsdf_textures
            .extend(std::mem::take(&mut self.bsdf_textures));
        Ok(material)
    }

    /// `bsdf`, its textured parameters left in `self.bsdf_textures`.
    fn bsdf_alone(&mut self, p: &Plugin) -> Result<Material, SceneError> {
        p.mark_used();
        let inner = |p: &Plugin| p.children_tagged("bsdf").next().map(|c| c.plugin.clone());
        let line = p.at.line;
        let first = self.bsdf_plugins.len();
        // The material, and what the path tracer and the other engines render in the
        // plugin's place (None: the plugin, exactly).
        let (material, path, others) = match p.kind.as_str() {
            "diffuse" => {
                let mut m = Material {
                    line,
                    ..Material::default()
                };
                self.reflectance(p, "reflectance", 0.5, &mut m)?;
                // One-sided, as Mitsuba's: black from behind (the course's diffuse material,
                // which the other engines take, reflects on both sides).
                m.bsdf = Some(Bsdf::Diffuse {
                    reflectance: m.diffuse,
                });
                (m, None, None)
            }
            "twosided" => match inner(p) {
                Some(b) => {
                    let mut m = self.bsdf(&b)?;
                    m.two_sided = true;
                    // Two-sided Lambertian reflection is the course's diffuse material, exact
                    // and the fastest the path tracer has.
                    if matches!(m.bsdf, Some(Bsdf::Diffuse { .. })) {
                        m.bsdf = None;
                    }
                    (m, None, None)
                }
                None => return Err(p.at.error("twosided needs a nested bsdf")),
            },
            "mask" => {
                let mut m = match inner(p) {
                    Some(b) => self.bsdf(&b)?,
                    None => return Err(p.at.error("mask needs a nested bsdf")),
                };
                m.opacity = Some(self.opacity(p)?);
                // The path tracer lets light through where it is transparent.
                (m, None, Some("its nested BSDF, opaque"))
            }
            "normalmap" | "bumpmap" => {
                let mut m = match inner(p) {
                    Some(b) => self.bsdf(&b)?,
                    None => return Err(p.at.error(format!("{} needs a nested bsdf", p.kind))),
                };
                if m.bsdf.is_none() {
                    // The course's two-sided diffuse material as a BSDF, to be tilted.
                    m.bsdf = Some(Bsdf::Diffuse {
                        reflectance: m.diffuse,
                    });
                }
                let t = match p.kind.as_str() {
                    "normalmap" => p.child_named("normalmap").cloned(),
                    _ => p.children_tagged("texture").next().map(|c| c.plugin.clone()),
                }
                .ok_or_else(|| p.at.error(format!("{} needs a texture", p.kind)))?;
                let texture = self.raw_texture(&t)?;
                m.tilt = Some(if p.kind == "normalmap" {
                    ShadingTilt::NormalMap(texture)
                } else {
                    ShadingTilt::BumpMap {
                        heights: texture,
                        scale: p.float("scale", 1.0)? as f32,
                    }
                });
                let _ = p.boolean("flip_invalid_normals", true)?;
                let _ = p.boolean("use_shadowing_function", true)?;
                // The path tracer tilts the shading frame.
                (m, None, Some("its nested BSDF, untilted"))
            }
            "null" => (
                Material {
                    // A boundary that changes nothing: glass of index 1 reflects nothing.
                    transmitted: Color::ONE,
                    ior: 1.0,
                    line,
                    ..Material::default()
                },
                None,
                None,
            ),
            "dielectric" | "roughdielectric" | "thindielectric" => {
                let eta = (self.ior(p, "int_ior", "bk7")? / self.ior(p, "ext_ior", "air")?) as f32;
                let transmittance =
                    self.colour(p, "specular_transmittance", 1.0, SpectrumUse::Bounded)?;
                let reflectance = self.colour(p, "specular_reflectance", 1.0, SpectrumUse::Bounded)?;
                let distribution = self.distribution(p)?;
                let bsdf = match p.kind.as_str() {
                    "thindielectric" => Some(Bsdf::ThinDielectric {
                        eta,
                        reflectance,
                        transmittance,
                    }),
                    "roughdielectric" => Some(Bsdf::Dielectric {
                        eta,
                        reflectance,
                        transmittance,
                        distribution,
                    }),
                    // The course's glass is exact when both factors are one.
                    _ if reflectance == Color::ONE => None,
                    _ => Some(Bsdf::Dielectric {
                        eta,
                        reflectance,
                        transmittance,
                        distribution: None,
                    }),
                };
                let thin = p.kind == "thindielectric";
                let others = match (&bsdf, thin) {
                    (None, _) => None,
                    (Some(_), true) => Some("a boundary light passes straight through"),
                    (Some(_), false) => Some("smooth glass"),
                };
                let m = Material {
                    transmitted: transmittance,
                    // A thin sheet does not bend light: the other engines pass through it.
                    ior: if thin { 1.0 } else { eta },
                    bsdf,
                    line,
                    ..Material::default()
                };
                (m, None, others)
            }
            "conductor" | "roughconductor" => {
                let specular = self.colour(p, "specular_reflectance", 1.0, SpectrumUse::Bounded)?;
                let name = p.string("material")?.map(|(m, at)| (m.to_string(), at.clone()));
                let given = p.property("eta").is_some() || p.property("k").is_some();
                let (eta, k) = if given {
                    (
                        self.colour(p, "eta", 0.0, SpectrumUse::Unbounded)?,
                        self.colour(p, "k", 1.0, SpectrumUse::Unbounded)?,
                    )
                } else {
                    match name {
                        None => (Color::ZERO, Color::ONE),
                        Some((m, _)) if m == "none" => (Color::ZERO, Color::ONE),
                        Some((m, at)) => spectrum::named_conductor(&m).ok_or_else(|| {
                            at.error(format!(
                                "conductor material \"{m}\" is unknown: expected none or one of {}",
                                spectrum::conductor_names()
                            ))
                        })?,
                    }
                };
                let distribution = self.distribution(p)?;
                let m = Material {
                    reflective: specular * conductor_reflectance(eta, k),
                    roughness: distribution.map_or(0.0, |d| {
                        let (u, v) = d.alpha();
                        0.5 * (u + v)
                    }),
                    bsdf: Some(Bsdf::Conductor {
                        eta,
                        k,
                        specular,
                        distribution,
                    }),
                    line,
                    ..Material::default()
                };
                (m, None, Some("a mirror of the Fresnel reflectance at normal incidence, a glossy lobe if rough"))
            }
            "plastic" | "roughplastic" => {
                let eta = (self.ior(p, "int_ior", "polypropylene")? / self.ior(p, "ext_ior", "air")?) as f32;
                let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
                let specular = self.colour(p, "specular_reflectance", 1.0, SpectrumUse::Bounded)?;
                let nonlinear = p.boolean("nonlinear", false)?;
                let distribution = self.distribution(p)?;
                let mut m = Material {
                    reflective: specular * f0,
                    roughness: distribution.map_or(0.0, |d| d.alpha().0),
                    line,
                    ..Material::default()
                };
                self.reflectance(p, "diffuse_reflectance", 0.5, &mut m)?;
                let base = m.diffuse;
                m.diffuse *= 1.0 - f0;
                m.bsdf = Some(Bsdf::Plastic(Plastic::new(base, specular, eta, nonlinear, distribution)));
                if m.texture.is_some() || m.texture_file.is_some() {
                    self.warn(&p.at, format!("{}: a textured diffuse_reflectance is taken at its mean by the path tracer", p.kind));
                }
                (m, None, Some("a Lambertian base under a constant specular layer"))
            }
            "principled" => {
                let mut m = Material {
                    line,
                    ..Material::default()
                };
                self.reflectance(p, "base_color", 0.5, &mut m)?;
                let scalar = |this: &mut Self, name: &str, default: f64| this.scalar(p, name, default);
                let principled = Principled {
                    base_color: m.diffuse,
                    roughness: scalar(self, "roughness", 0.5)?,
                    anisotropic: scalar(self, "anisotropic", 0.0)?,
                    metallic: scalar(self, "metallic", 0.0)?,
                    spec_trans: scalar(self, "spec_trans", 0.0)?,
                    specular: scalar(self, "specular", 0.5)?,
                    eta: match p.property("eta") {
                        Some(_) => Some(p.float("eta", 1.5)? as f32),
                        None => None,
                    },
                    spec_tint: scalar(self, "spec_tint", 0.0)?,
                    sheen: scalar(self, "sheen", 0.0)?,
                    sheen_tint: scalar(self, "sheen_tint", 0.0)?,
                    flatness: scalar(self, "flatness", 0.0)?,
                    clearcoat: scalar(self, "clearcoat", 0.0)?,
                    clearcoat_gloss: scalar(self, "clearcoat_gloss", 0.0)?,
                    ..Principled::default()
                };
                let metallic = principled.metallic;
                m.reflective = m.diffuse * metallic + Color::splat(0.04 * (1.0 - metallic));
                m.diffuse *= 1.0 - metallic;
                m.roughness = principled.roughness * principled.roughness;
                m.bsdf = Some(Bsdf::Principled(principled));
                (m, None, Some("a Lambertian base and a glossy lobe"))
            }
            "principledthin" => {
                let mut m = Material {
                    line,
                    ..Material::default()
                };
                self.reflectance(p, "base_color", 0.5, &mut m)?;
                let scalar = |this: &mut Self, name: &str, default: f64| this.scalar(p, name, default);
                let rate = |name: &str| -> Result<f32, SceneError> { Ok(p.float(name, 1.0)? as f32) };
                let thin = PrincipledThin {
                    base_color: m.diffuse,
                    roughness: scalar(self, "roughness", 0.5)?,
                    anisotropic: scalar(self, "anisotropic", 0.0)?,
                    spec_trans: scalar(self, "spec_trans", 0.0)?,
                    eta: scalar(self, "eta", 1.5)?,
                    spec_tint: scalar(self, "spec_tint", 0.0)?,
                    sheen: scalar(self, "sheen", 0.0)?,
                    sheen_tint: scalar(self, "sheen_tint", 0.0)?,
                    flatness: scalar(self, "flatness", 0.0)?,
                    diff_trans: scalar(self, "diff_trans", 0.0)?,
                    specular_reflectance_sampling_rate: rate("specular_reflectance_sampling_rate")?,
                    specular_transmittance_sampling_rate: rate("specular_transmittance_sampling_rate")?,
                    diffuse_reflectance_sampling_rate: rate("diffuse_reflectance_sampling_rate")?,
                    diffuse_transmittance_sampling_rate: rate("diffuse_transmittance_sampling_rate")?,
                };
                // The other engines see the diffuse part that is reflected.
                m.diffuse *= (1.0 - thin.spec_trans) * (1.0 - thin.diff_trans / 2.0);
                m.bsdf = Some(Bsdf::PrincipledThin(thin));
                (m, None, Some("a Lambertian base"))
            }
            other => {
                return Err(p.at.error(format!(
                    "bsdf \"{other}\" is not supported: expected diffuse, dielectric, roughdielectric, thindielectric, conductor, roughconductor, plastic, roughplastic, principled, principledthin, twosided, mask, bumpmap, normalmap or null"
                )))
            }
        };
        let support = PluginSupport {
            kind: p.kind.clone(),
            at: p.at.to_string(),
            path,
            others,
        };
        // A wrapper's nested BSDF recorded itself first: this plugin goes in front of it.
        self.bsdf_plugins.insert(first, support);
        Ok(material)
    }

    /// A rough BSDF's microfacet distribution (`distribution` beckmann or ggx, `alpha` or
    /// `alpha_u` and `alpha_v`, `sample_visible`; Mitsuba's defaults beckmann, 0.1, true);
    /// None for the smooth kinds.
    fn distribution(&mut self, p: &Plugin) -> Result<Option<Microfacet>, SceneError> {
        if !p.kind.starts_with("rough") {
            return Ok(None);
        }
        let kind = match p.string("distribution")? {
            None => MicrofacetKind::Beckmann,
            Some(("beckmann", _)) => MicrofacetKind::Beckmann,
            Some(("ggx", _)) => MicrofacetKind::Ggx,
            Some((other, at)) => {
                return Err(at.error(format!(
                    "distribution \"{other}\": expected beckmann or ggx"
                )))
            }
        };
        let visible = p.boolean("sample_visible", true)?;
        let anisotropic = p.property("alpha_u").is_some() || p.child_named("alpha_u").is_some();
        let (au, av) = if anisotropic {
            (
                self.scalar(p, "alpha_u", 0.1)?,
                self.scalar(p, "alpha_v", 0.1)?,
            )
        } else {
            let a = self.scalar(p, "alpha", 0.1)?;
            (a, a)
        };
        if !(au > 0.0 && av > 0.0 && au.is_finite() && av.is_finite()) {
            return Err(p
                .at
                .error(format!("alpha {au} {av}: expected finite and > 0")));
        }
        Ok(Some(Microfacet::new(kind, au, av, visible)))
    }

    /// A texture of raw values (a normal or bump map's): a `bitmap` decoded without sRGB's curve
    /// whatever its `raw` says, or a `rawconstant`; pushed to the scene's textures.
    fn raw_texture(&mut self, t: &Plugin) -> Result<usize, SceneError> {
        t.mark_used();
        let texture = match t.kind.as_str() {
            "bitmap" => {
                let (file, at) = t
                    .file("filename")?
                    .ok_or_else(|| t.at.error("bitmap needs a filename"))?;
                if !t.boolean("raw", false)? {
                    self.warn(&t.at, "a normal or bump map is read raw (no sRGB curve)");
                }
                bitmap(t, &file, at, true)?
            }
            "rawconstant" => {
                let v = t.point("value", DVec3::new(0.5, 0.5, 1.0))?.as_vec3();
                Texture::checkerboard(v, v, None)
            }
            other => {
                return Err(t.at.error(format!(
                    "a {other} normal or bump map is not supported: give a bitmap or a rawconstant"
                )))
            }
        };
        self.scene.textures.push(texture);
        Ok(self.scene.textures.len() - 1)
    }

    /// A mask's `opacity` as one of the scene's textures: a constant, or a `bitmap` (its
    /// luminance, decoded from sRGB unless `raw`).
    fn opacity(&mut self, p: &Plugin) -> Result<usize, SceneError> {
        let texture = match p.child_named("opacity").cloned() {
            None => {
                let alpha = p.float("opacity", 0.5)? as f32;
                Texture::checkerboard(Color::splat(alpha), Color::splat(alpha), None)
            }
            Some(t) if t.kind == "bitmap" => {
                t.mark_used();
                let (file, at) = t
                    .file("filename")?
                    .ok_or_else(|| t.at.error("bitmap needs a filename"))?;
                let raw = t.boolean("raw", false)?;
                let mut texture = bitmap(&t, &file, at, raw)?;
                for c in &mut texture.texels {
                    *c = Color::splat(crate::color::luminance(*c));
                }
                texture
            }
            Some(t) => {
                return Err(t.at.error(format!(
                    "a {} opacity is not supported: give a number or a bitmap",
                    t.kind
                )))
            }
        };
        self.scene.textures.push(texture);
        Ok(self.scene.textures.len() - 1)
    }

    /// An area emitter's textured radiance, a `bitmap` (decoded from sRGB unless `raw`) or a
    /// `checkerboard`, added to the scene's textures: its index.
    fn emission_texture(&mut self, t: &Plugin) -> Result<usize, SceneError> {
        let texture = match t.kind.as_str() {
            "bitmap" => {
                let (file, at) = t
                    .file("filename")?
                    .ok_or_else(|| t.at.error("bitmap needs a filename"))?;
                let raw = t.boolean("raw", false)?;
                bitmap(t, &file, at, raw)?
            }
            "checkerboard" => {
                let a = self.colour(t, "color0", 0.4, SpectrumUse::Emission)?;
                let b = self.colour(t, "color1", 0.2, SpectrumUse::Emission)?;
                Texture::checkerboard(a, b, to_uv(t)?)
            }
            other => {
                return Err(t.at.error(format!(
                    "a {other} radiance is not supported: expected a colour, a bitmap or a checkerboard"
                )))
            }
        };
        self.scene.textures.push(texture);
        Ok(self.scene.textures.len() - 1)
    }

    /// A number that may be given as a `float` or as a texture: a `checkerboard`'s is taken
    /// at the mean of its two values, with a warning.
    fn scalar(&mut self, p: &Plugin, name: &str, default: f64) -> Result<f32, SceneError> {
        let Some(t) = p.child_named(name).cloned() else {
            return Ok(p.float(name, default)? as f32);
        };
        t.mark_used();
        if t.kind != "checkerboard" {
            return Err(t.at.error(format!(
                "a {} texture for \"{name}\" is not supported: give a number or a checkerboard",
                t.kind
            )));
        }
        let a = t.float("color0", 0.4)? as f32;
        let b = t.float("color1", 0.2)? as f32;
        let parameter = BsdfParameter::named(name).ok_or_else(|| {
            t.at.error(format!("\"{name}\" cannot be given by a texture"))
        })?;
        self.bsdf_textures.push(TexturedParameter {
            parameter,
            texture: self.scene.textures.len(),
        });
        // Mitsuba's checkerboard gives a number (`eval_1`) on the other squares than a
        // colour (`eval`): `color0` where the two halves differ. Its references are made so.
        self.scene.textures.push(Texture::checkerboard(
            Color::splat(b),
            Color::splat(a),
            to_uv(&t)?,
        ));
        self.warn(
            &t.at,
            format!(
                "a checkerboard for \"{name}\": the engines but the path tracer take its mean, {}",
                0.5 * (a + b)
            ),
        );
        Ok(0.5 * (a + b))
    }

    /// A reflectance given as a colour, or as a `bitmap` texture (read through the scene's
    /// textures), or a `checkerboard` (its mean, with a warning).
    fn reflectance(
        &mut self,
        p: &Plugin,
        name: &str,
        default: f64,
        m: &mut Material,
    ) -> Result<(), SceneError> {
        if let Some(t) = p.child_named(name).cloned() {
            t.mark_used();
            match t.kind.as_str() {
                "bitmap" => {
                    let (file, _) = t
                        .file("filename")?
                        .ok_or_else(|| t.at.error("bitmap needs a filename"))?;
                    m.texture_file = Some(file);
                    m.texture_to_uv = to_uv(&t)?;
                    if let Some((filter, _)) = t.string("filter_type")? {
                        m.texture_nearest = filter == "nearest";
                    }
                    if let Some((wrap, at)) = t.string("wrap_mode")? {
                        if wrap != "repeat" {
                            self.warn(at, format!("wrap_mode \"{wrap}\": trilux repeats textures"));
                        }
                    }
                    let _ = t.string("format")?;
                    if t.boolean("raw", false)? {
                        self.warn(&t.at, "raw: trilux decodes 8-bit textures from sRGB");
                    }
                }
                "checkerboard" => {
                    let a = self.colour(&t, "color0", 0.4, SpectrumUse::Bounded)?;
                    let b = self.colour(&t, "color1", 0.2, SpectrumUse::Bounded)?;
                    m.diffuse = (a + b) * 0.5;
                    m.texture = Some(self.scene.textures.len());
                    self.scene
                        .textures
                        .push(Texture::checkerboard(a, b, to_uv(&t)?));
                }
                other => {
                    return Err(t.at.error(format!(
                        "texture \"{other}\" is not supported: expected bitmap or checkerboard"
                    )))
                }
            }
            return Ok(());
        }
        m.diffuse = self.colour(p, name, default, SpectrumUse::Bounded)?;
        Ok(())
    }

    /// A colour property (`rgb`, `spectrum`, `float`), or `default` grey.
    fn colour(
        &mut self,
        p: &Plugin,
        name: &str,
        default: f64,
        usage: SpectrumUse,
    ) -> Result<Color, SceneError> {
        if let Some(t) = p.child_named(name).cloned() {
            t.mark_used();
            return Err(t.at.error(format!(
                "a {} texture for \"{name}\" is not supported here: give a colour",
                t.kind
            )));
        }
        // A default or a `float` is grey, even for an emitter; a uniform `spectrum` emitter
        // is not (see `spectrum_to_rgb`).
        let Some(prop) = p.property(name) else {
            return Ok(Color::splat(default as f32));
        };
        let c = match &prop.value {
            Value::Rgb(c) => c.as_vec3(),
            Value::Float(v) => Color::splat(*v as f32),
            Value::Spectrum(s) => spectrum_to_rgb(s, usage),
            other => {
                return Err(prop.at.error(format!(
                    "\"{name}\" is a {other:?}: expected rgb, spectrum or float"
                )))
            }
        };
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(prop
                .at
                .error(format!("\"{name}\" must be finite and ≥ 0, found {c}")));
        }
        Ok(c)
    }

    /// An index of refraction given as a number or a name.
    fn ior(&mut self, p: &Plugin, name: &str, default: &str) -> Result<f64, SceneError> {
        let Some(prop) = p.property(name) else {
            return Ok(spectrum::named_ior(default).unwrap_or(1.0) as f64);
        };
        let ior = match &prop.value {
            Value::Float(v) => *v,
            Value::String(s) => spectrum::named_ior(s).ok_or_else(|| {
                prop.at.error(format!(
                    "\"{s}\" is not a known index of refraction: expected a number or one of {}",
                    spectrum::ior_names()
                ))
            })? as f64,
            other => {
                return Err(prop.at.error(format!(
                    "\"{name}\" is a {other:?}: expected a number or a name"
                )))
            }
        };
        if ior.is_nan() || ior <= 0.0 {
            return Err(prop.at.error(format!("\"{name}\" {ior}: expected > 0")));
        }
        Ok(ior)
    }

    /// A medium plugin as a medium of the scene.
    fn medium(&mut self, p: &Rc<Plugin>) -> Result<usize, SceneError> {
        if let Some(&k) = self.media.get(&Rc::as_ptr(p)) {
            return Ok(k);
        }
        p.mark_used();
        let heterogeneous = match p.kind.as_str() {
            "homogeneous" => false,
            "heterogeneous" => true,
            other => {
                return Err(p.at.error(format!(
                    "medium \"{other}\" is not supported: expected homogeneous or heterogeneous"
                )))
            }
        };
        let scale = p.float("scale", 1.0)? as f32;
        let _ = p.boolean("sample_emitters", true)?;
        let mut g = 0.0;
        for phase in p.children_tagged("phase") {
            let phase = &phase.plugin;
            phase.mark_used();
            match phase.kind.as_str() {
                "isotropic" => {}
                "hg" => g = phase.float("g", 0.8)? as f32,
                other => {
                    return Err(phase.at.error(format!(
                        "phase \"{other}\" is not supported: expected isotropic or hg"
                    )))
                }
            }
        }
        let medium = if heterogeneous {
            Medium {
                g,
                heterogeneous: Some(Box::new(self.heterogeneous(p, scale)?)),
                line: p.at.line,
                ..Medium::default()
            }
        } else {
            let sigma_t = self.colour(p, "sigma_t", 1.0, SpectrumUse::Unbounded)? * scale;
            let albedo = self.colour(p, "albedo", 0.75, SpectrumUse::Bounded)?;
            Medium {
                sigma_a: sigma_t * (Color::ONE - albedo),
                sigma_s: sigma_t * albedo,
                g,
                heterogeneous: None,
                line: p.at.line,
            }
        };
        let k = self.scene.media.len();
        self.scene.media.push(medium);
        self.media.insert(Rc::as_ptr(p), k);
        Ok(k)
    }

    /// A `heterogeneous` medium's coefficients: `sigma_t` a grid (times `scale`), `albedo` a
    /// grid or a colour.
    fn heterogeneous(&mut self, p: &Plugin, scale: f32) -> Result<Heterogeneous, SceneError> {
        let Some(sigma_t) = p.child_named("sigma_t").cloned() else {
            let at = p.property("sigma_t").map_or(&p.at, |given| &given.at);
            return Err(at.error(
                "a heterogeneous medium needs its \"sigma_t\" as a gridvolume (a <volume> of type gridvolume)",
            ));
        };
        let sigma_t = grid_volume(&sigma_t)?;
        let albedo = match p.child_named("albedo").cloned() {
            Some(v) => {
                let grid = grid_volume(&v)?;
                if grid.grid.data.iter().any(|&a| a > 1.0) {
                    return Err(v
                        .at
                        .error("an albedo grid above 1: expected values in [0, 1]"));
                }
                Albedo::Grid(grid)
            }
            None => Albedo::Constant(self.colour(p, "albedo", 0.75, SpectrumUse::Bounded)?),
        };
        let medium = Heterogeneous {
            sigma_t,
            scale,
            albedo,
        };
        if !(scale >= 0.0 && medium.majorant().is_finite()) {
            return Err(p.at.error(format!(
                "scale {scale}: expected ≥ 0, with the largest σt (scale × the grid's largest value) finite"
            )));
        }
        Ok(medium)
    }

    fn emitter(&mut self, p: &Plugin) -> Result<(), SceneError> {
        p.mark_used();
        let sky = match p.kind.as_str() {
            "constant" => Sky::Uniform(self.colour(p, "radiance", 1.0, SpectrumUse::Emission)?),
            "envmap" => {
                let (file, _) = p
                    .file("filename")?
                    .ok_or_else(|| p.at.error("envmap needs a filename"))?;
                let mut map = SkyMap::named(file, p.at.line);
                map.scale = p.float("scale", 1.0)? as f32;
                let to_world = p.transform("to_world")?;
                let rotation = Mat3::from_mat4(to_world.as_mat4());
                map.mitsuba_frame = Some(rotation.transpose());
                Sky::Map(std::sync::Arc::new(map))
            }
            "point" | "spot" | "directional" => {
                let light = self.delta_light(p)?;
                self.scene.delta_lights.push(light);
                return Ok(());
            }
            other => {
                return Err(p.at.error(format!(
                    "emitter \"{other}\" is not supported: expected constant, envmap, point, spot, directional (and, inside shapes, area)"
                )))
            }
        };
        if self.scene.sky.is_some() {
            self.warn(
                &p.at,
                "a second environment emitter: only the first lights the scene",
            );
            return Ok(());
        }
        self.scene.sky = Some(sky);
        Ok(())
    }
}

impl Builder {
    /// A `point`, `spot` or `directional` emitter.
    fn delta_light(&mut self, p: &Plugin) -> Result<DeltaLight, SceneError> {
        let to_world = p.transform("to_world")?;
        let unit = |v: DVec3, what: &str| {
            v.try_normalize()
                .map(|v| v.as_vec3())
                .ok_or_else(|| p.at.error(format!("the {what} is zero")))
        };
        let kind = match p.kind.as_str() {
            "point" => DeltaKind::Point {
                position: match p.property("position") {
                    Some(_) => p.point("position", DVec3::ZERO)?,
                    None => to_world.transform_point3(DVec3::ZERO),
                }
                .as_vec3(),
            },
            "spot" => {
                let cutoff = p.float("cutoff_angle", 20.0)?;
                let beam = p.float("beam_width", cutoff * 0.75)?;
                if !(0.0 < beam && beam <= cutoff && cutoff < 180.0) {
                    return Err(p.at.error(format!(
                        "beam_width {beam}, cutoff_angle {cutoff}: expected 0 < beam_width ≤ cutoff_angle < 180"
                    )));
                }
                let projects = match p.child_named("texture").cloned() {
                    None => None,
                    Some(t) if t.kind == "bitmap" => {
                        t.mark_used();
                        let (file, at) = t
                            .file("filename")?
                            .ok_or_else(|| t.at.error("bitmap needs a filename"))?;
                        let raw = t.boolean("raw", false)?;
                        self.scene.textures.push(bitmap(&t, &file, at, raw)?);
                        let linear = Mat3::from_mat4(to_world.as_mat4());
                        if linear.determinant() == 0.0 {
                            return Err(p.at.error("the spot's to_world is singular"));
                        }
                        Some((self.scene.textures.len() - 1, linear.inverse()))
                    }
                    Some(t) => {
                        return Err(t.at.error(format!(
                            "a spot's texture \"{}\" is not supported: expected bitmap",
                            t.kind
                        )))
                    }
                };
                DeltaKind::Spot {
                    position: to_world.transform_point3(DVec3::ZERO).as_vec3(),
                    axis: unit(to_world.transform_vector3(DVec3::Z), "spot's axis")?,
                    beam: beam.to_radians() as f32,
                    cutoff: cutoff.to_radians() as f32,
                    projects,
                }
            }
            _ => DeltaKind::Directional {
                direction: unit(
                    match p.property("direction") {
                        Some(_) => p.point("direction", DVec3::Z)?,
                        None => to_world.transform_vector3(DVec3::Z),
                    },
                    "direction",
                )?,
            },
        };
        let name = if p.kind == "directional" {
            "irradiance"
        } else {
            "intensity"
        };
        let intensity = if p.child_named(name).is_some() {
            Color::ONE
        } else {
            self.colour(p, name, 1.0, SpectrumUse::Emission)?
        };
        Ok(DeltaLight { kind, intensity })
    }
}

/// A `gridvolume` plugin: its `.vol` file (`filename`) placed by `to_world` (and
/// `use_grid_bbox`), with Mitsuba's default trilinear filter and clamped edges, the only ones
/// read.
fn grid_volume(v: &Plugin) -> Result<GridVolume, SceneError> {
    v.mark_used();
    if v.tag != "volume" || v.kind != "gridvolume" {
        return Err(v.at.error(format!(
            "<{} type=\"{}\"> is not supported here: expected a <volume type=\"gridvolume\">",
            v.tag, v.kind
        )));
    }
    for (name, only) in [("filter_type", "trilinear"), ("wrap_mode", "clamp")] {
        if let Some((value, at)) = v.string(name)? {
            if value != only {
                return Err(at.error(format!(
                    "{name} \"{value}\" is not supported: expected {only}"
                )));
            }
        }
    }
    let Some((file, at)) = v.file("filename")? else {
        return Err(v.at.error("a gridvolume needs its \"filename\""));
    };
    let grid =
        read_volume_grid(&file).map_err(|why| at.error(format!("cannot read the grid: {why}")))?;
    let to_world = v.transform("to_world")?;
    let use_grid_bbox = v.boolean("use_grid_bbox", false)?;
    GridVolume::new(grid, to_world, use_grid_bbox).ok_or_else(|| {
        v.at.error("the grid's to_world (or, with use_grid_bbox, its file's box) is degenerate")
    })
}

/// A `bitmap` plugin's image `file` (named at `at`), decoded raw or from sRGB, with its
/// `to_uv` and `filter_type`.
fn bitmap(t: &Plugin, file: &Path, at: &xml::Location, raw: bool) -> Result<Texture, SceneError> {
    let loaded = if raw {
        Texture::load_heights(file)
    } else {
        Texture::load(file)
    };
    let mut texture = loaded.map_err(|why| at.error(format!("cannot read {why}")))?;
    texture.to_uv = to_uv(t)?;
    if let Some((filter, _)) = t.string("filter_type")? {
        texture.nearest = filter == "nearest";
    }
    Ok(texture)
}

/// A texture's `to_uv` as trilux's textures take it: Mitsuba's 2D affine map (the upper
/// left 3×3 of the 4×4 given, as Mitsuba extracts it) applied to Mitsuba's (u, v), whose v
/// runs down the image, expressed on trilux's (s, t) = (u, 1 − v) on both sides.
fn to_uv(t: &Plugin) -> Result<Option<[[f32; 3]; 2]>, SceneError> {
    if t.property("to_uv").is_none() {
        return Ok(None);
    }
    let m = t.transform("to_uv")?;
    let a = |r: usize, c: usize| m.col(c)[r] as f32;
    Ok(Some([
        [a(0, 0), -a(0, 1), a(0, 1) + a(0, 2)],
        [-a(1, 0), a(1, 1), 1.0 - a(1, 1) - a(1, 2)],
    ]))
}

/// A positive integer property (a film's size, a sample count).
fn positive(p: &Plugin, name: &str, default: i64) -> Result<u32, SceneError> {
    let v = p.integer(name, default)?;
    u32::try_from(v).ok().filter(|&v| v > 0).ok_or_else(|| {
        p.at.error(format!("\"{name}\" {v}: expected a positive integer"))
    })
}

/// The reflectance of a conductor of complex index η + ik at normal incidence:
/// ((η − 1)² + k²) / ((η + 1)² + k²).
fn conductor_reflectance(eta: Color, k: Color) -> Color {
    let k2 = k * k;
    ((eta - Color::ONE) * (eta - Color::ONE) + k2) / ((eta + Color::ONE) * (eta + Color::ONE) + k2)
}

/// Mitsuba's `cylinder`: the open tube of `radius` from `p0` to `p1`, `segments` around.
fn cylinder(p0: DVec3, p1: DVec3, radius: f64, segments: u32) -> Option<Mesh> {
    let axis = p1 - p0;
    if axis.length_squared() == 0.0 || radius.is_nan() || radius <= 0.0 {
        return None;
    }
    let (u, v) = axis.normalize().any_orthonormal_pair();
    let mut mesh = Mesh::default();
    for k in 0..segments {
        let phi = std::f64::consts::TAU * k as f64 / segments as f64;
        let n = u * phi.cos() + v * phi.sin();
        for (end, t) in [(p0, 0.0f32), (p1, 1.0)] {
            mesh.positions.push((end + n * radius).as_vec3());
            mesh.normals.push(n.as_vec3());
            mesh.tex_coords
                .push(crate::geometry::vec2(k as f32 / segments as f32, 1.0 - t));
        }
        let (a, b) = (2 * k, 2 * ((k + 1) % segments));
        mesh.indices.push([a, b, b + 1]);
        mesh.indices.push([a, b + 1, a + 1]);
    }
    Some(mesh)
}
