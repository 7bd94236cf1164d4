//! The scene: plain data (materials, primitives, camera, background) read from a course-dialect
//! file or a standard OBJ/MTL file. Nothing here knows about any acceleration structure.

pub mod bsdf;
pub mod bsdf_support;
pub mod bsdf_texture;
mod dialect;
mod error;
pub mod instance;
pub mod medium;
mod mgf;
mod mitsuba;
mod obj;
pub mod procedural;
pub mod range;
pub mod sky;
mod surface;
pub mod texture;
pub mod volume_grid;

use std::path::{Path, PathBuf};

pub use crate::camera::{Camera, Projection, View};
pub use error::SceneError;
pub use instance::{Group, Instance, Instancing};
pub use surface::{bilinear, PrimHit, QuadNeighbours, SurfaceHit};
pub use texture::Texture;

use crate::geometry::{faces_ray, quad_normal, AnalyticShape, Bounds3, Shape, Vec2, Vec3};
use glam::Mat3;

pub use crate::color::Color;

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Lambertian albedo (used when there is no texture).
    pub diffuse: Color,
    /// Index into `Scene::textures` once decoded; the file it comes from is `texture_file`.
    pub texture: Option<usize>,
    pub texture_file: Option<PathBuf>,
    /// The texture file's coordinates mapped by this affine map (`Texture::to_uv`; default
    /// none).
    pub texture_to_uv: Option<[[f32; 3]; 2]>,
    /// The texture file looked up at its nearest texel (`Texture::nearest`; default false).
    pub texture_nearest: bool,
    /// Perfect-mirror reflectance.
    pub reflective: Color,
    /// Emitted radiance (W·sr⁻¹·m⁻²); with an `emission_texture`, its mean.
    pub emitted: Color,
    /// Index into `Scene::textures` of the emitted radiance across the surface (Mitsuba's
    /// textured `radiance`, on triangles; default none: `emitted` everywhere). The path
    /// tracer reads it where a path meets the surface and where it samples it; the other
    /// engines emit its mean, `emitted`.
    pub emission_texture: Option<usize>,
    /// Specular transmittance.
    pub transmitted: Color,
    /// Index of refraction for `transmitted`; default 1.5.
    pub ior: f32,
    /// Glossy lobe width for `reflective`; 0 is a perfect mirror.
    pub roughness: f32,
    /// The medium that fills the inside of the closed objects of this material
    /// (`interior_medium K`, default none): light refracted into them travels in it.
    pub interior_medium: Option<usize>,
    /// The medium outside the closed objects of this material (Mitsuba's `exterior`; default
    /// none: the fog), which a ray leaving them through their back travels in.
    pub exterior_medium: Option<usize>,
    /// A pattern that gives the albedo in place of `diffuse` (`texture_procedural`).
    pub procedural: Option<procedural::ProceduralTexture>,
    /// A bump map that tilts the shading normal (`bump_procedural`, `bump_file`).
    pub bump: Option<procedural::Bump>,
    /// A Mitsuba BSDF the course's lobes above only approximate (`scene::bsdf`): the path
    /// tracer scatters by it; the other engines by the approximation (default none).
    pub bsdf: Option<bsdf::Bsdf>,
    /// `bsdf` reflects on both sides (Mitsuba's `twosided`; default false: a one-sided
    /// BSDF's back is black).
    pub two_sided: bool,
    /// `bsdf`'s parameters that textures give (default none).
    pub bsdf_textures: Vec<bsdf_texture::TexturedParameter>,
    /// The texture whose first channel is the surface's opacity (Mitsuba's `mask`): where
    /// it is below 1, light passes straight through the rest of the time (default none:
    /// opaque).
    pub opacity: Option<usize>,
    /// What tilts `bsdf`'s shading frame: a normal map or a bump map (default none).
    pub tilt: Option<ShadingTilt>,
    /// Line of the file where the material starts (0 for materials not from a file).
    pub line: u32,
}

/// A texture that tilts a BSDF's shading frame, as Mitsuba's wrapping BSDFs do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadingTilt {
    /// Tangent-space normals, 2·texel − 1 (Mitsuba's `normalmap`): the texture's index.
    NormalMap(usize),
    /// Heights whose gradient, times `scale`, tilts the surface's tangents (Mitsuba's
    /// `bumpmap`): the texture's index.
    BumpMap { heights: usize, scale: f32 },
}

impl Default for Material {
    fn default() -> Self {
        Material {
            diffuse: Vec3::ZERO,
            texture: None,
            texture_file: None,
            texture_to_uv: None,
            texture_nearest: false,
            reflective: Vec3::ZERO,
            emitted: Vec3::ZERO,
            emission_texture: None,
            transmitted: Vec3::ZERO,
            ior: 1.5,
            roughness: 0.0,
            interior_medium: None,
            exterior_medium: None,
            procedural: None,
            bump: None,
            bsdf: None,
            two_sided: false,
            bsdf_textures: Vec::new(),
            opacity: None,
            tilt: None,
            line: 0,
        }
    }
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emitted.max_element() > 0.0
    }
    /// Whether the surface's back reflects and emits nothing: a one-sided Mitsuba BSDF that
    /// lets nothing through (`bsdf::Bsdf::front_only`), not made `twosided`. The course's
    /// materials reflect on both sides.
    pub fn black_behind(&self) -> bool {
        self.bsdf.as_ref().is_some_and(bsdf::Bsdf::front_only) && !self.two_sided
    }
    /// Whether the surface changes nothing that crosses it: clear glass of index 1, which
    /// neither reflects nor bends (Mitsuba's `null`, a medium's boundary). A thin sheet of
    /// glass (`thindielectric`) bends nothing either but reflects: its BSDF says so.
    pub fn is_index_matched(&self) -> bool {
        self.bsdf.is_none()
            && self.transmitted == Vec3::ONE
            && self.ior == 1.0
            && self.diffuse == Vec3::ZERO
            && self.reflective == Vec3::ZERO
            && self.emitted == Vec3::ZERO
            && self.texture.is_none()
            && self.procedural.is_none()
    }

    /// The part of the light meeting the surface at `cos_theta` that goes straight through
    /// it, as a shadow ray sees it: all of it for an index-matched boundary, a thin sheet's
    /// transmission (`Bsdf::null_lobe`), none for every other surface.
    pub fn straight_transmission(&self, cos_theta: f32) -> Color {
        if self.is_index_matched() {
            return Color::ONE;
        }
        match self.bsdf.as_ref().and_then(|b| b.null_lobe(cos_theta)) {
            Some((pass, colour)) => colour * pass,
            None => Color::ZERO,
        }
    }

    pub fn is_specular(&self) -> bool {
        self.reflective.max_element() > 0.0 || self.transmitted.max_element() > 0.0
    }
}

/// A planar quad of the course dialect: one-sided, counter-clockwise around `normal`.
#[derive(Clone, Debug, PartialEq)]
pub struct Quad {
    pub vertices: [Vec3; 4],
    /// Texture coordinates of the four vertices, when the file gives them.
    pub tex_coords: Option<[Vec2; 4]>,
    pub material: u32,
    /// Unit front normal.
    pub normal: Vec3,
}

impl Quad {
    pub fn new(vertices: [Vec3; 4], tex_coords: Option<[Vec2; 4]>, material: u32) -> Quad {
        Quad {
            vertices,
            tex_coords,
            material,
            normal: quad_normal(&vertices).normalize_or_zero(),
        }
    }
    pub fn area(&self) -> f32 {
        0.5 * quad_normal(&self.vertices).length()
    }
}

/// Triangles from standard OBJ files, indexed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex texture coordinates: empty, or one per position.
    pub tex_coords: Vec<Vec2>,
    /// Per-vertex shading normals: empty, or one per position.
    pub normals: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    /// Material of each triangle.
    pub materials: Vec<u32>,
}

impl TriangleMesh {
    pub fn len(&self) -> usize {
        self.indices.len()
    }
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
}

/// An analytic shape (sphere, ring) with its material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapePrim {
    pub shape: AnalyticShape,
    pub material: u32,
}

/// The kinds of primitive a ray can hit, ordered as a scene lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PrimKind {
    Quad,
    Triangle,
    /// One of `Scene::shapes`: whichever analytic kind it is, the `Shape` trait answers.
    Shape,
    /// A triangle of an instanced group, placed by its instance: the index runs over all
    /// instances' triangles (`scene::instance`).
    Instanced,
}

impl PrimKind {
    /// Every kind, in the order of their discriminants (`kind as u32` indexes this).
    pub const ALL: [PrimKind; 4] = [
        PrimKind::Quad,
        PrimKind::Triangle,
        PrimKind::Shape,
        PrimKind::Instanced,
    ];
}

/// One primitive of a scene: its kind and its index in that kind's list (ordered by both).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PrimRef {
    pub kind: PrimKind,
    pub index: u32,
}

/// Which polygons a ray passes through from behind (`Scene::culled_backs`): every Accel, and
/// every test of one polygon, apply it alike.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CulledBacks {
    pub quads: bool,
    pub triangles: bool,
}

impl CulledBacks {
    /// Whether a ray along `dir` meets a polygon of kind `kind` (Quad or Triangle) whose front
    /// normal (vertices counter-clockwise round it, unnormalized) is `normal`.
    #[inline(always)]
    pub fn meets(self, kind: PrimKind, normal: Vec3, dir: Vec3) -> bool {
        let culled = match kind {
            PrimKind::Quad => self.quads,
            PrimKind::Triangle => self.triangles,
            PrimKind::Shape | PrimKind::Instanced => false,
        };
        !culled || faces_ray(normal, dir)
    }
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The file the scene came from (textures are relative to it).
    pub path: PathBuf,
    pub materials: Vec<Material>,
    /// Decoded textures, only those some primitive's material uses.
    pub textures: Vec<Texture>,
    /// Decoded height images of `bump_file`s, only those some primitive's material uses.
    pub height_maps: Vec<Texture>,
    /// How wide a pixel is where (what procedural textures and bumps are averaged over):
    /// zero until `filter_textures_for` is told the image's size.
    pub footprint: procedural::Footprint,
    pub quads: Vec<Quad>,
    pub triangles: TriangleMesh,
    /// Triangles stored once per group and placed by instances (Mitsuba's `shapegroup` and
    /// `instance`; default none).
    pub instancing: Instancing,
    /// Spheres and rings, in the order of the scene file.
    pub shapes: Vec<ShapePrim>,
    pub camera: Option<Camera>,
    /// Linear radiance of rays that leave the scene.
    pub background: Color,
    /// The media of `medium` blocks, in order.
    pub media: Vec<medium::Medium>,
    /// The medium that fills the space outside closed objects, where the camera is (`fog K`).
    pub fog: Option<usize>,
    /// The medium the camera is in where it is not the fog (Mitsuba's sensor `medium`;
    /// default none: the fog).
    pub camera_medium: Option<usize>,
    /// The sky that lights the scene (`sky_color`, `sky_gradient`; None: the background,
    /// which lights nothing).
    pub sky: Option<sky::Sky>,
    /// Lights without area (a Mitsuba scene's `point`, `spot` and `directional` emitters),
    /// which only next-event estimation finds: the path tracer's.
    pub delta_lights: Vec<DeltaLight>,
    /// Quads are opaque from both sides (`--two-sided`); by default they are one-sided for
    /// every query, as in the course program.
    pub two_sided_quads: bool,
    /// Triangles are one-sided as quads are: missed from behind by every query unless
    /// `--two-sided` (MGF scenes, as RenderPark culls their backs; default false: a triangle is
    /// opaque from both sides, as in the course program and Mitsuba).
    pub one_sided_triangles: bool,
    /// For each quad, the quads that share a vertex position with it (built on first use; it
    /// settles hits on shared edges the same way whichever backend reported them).
    pub quad_neighbours: QuadNeighbours,
    /// Triangles are shaded with their vertex normals interpolated (Mitsuba scenes); the
    /// course's formats shade them flat, as the course program does.
    pub smooth_normals: bool,
    /// What emits is not seen straight from the camera (Mitsuba's `hide_emitters`; default
    /// false): the path tracer's camera rays pass through emitting surfaces and show no sky
    /// until they have scattered. The other engines show emitters.
    pub hide_emitters: bool,
    /// What the scene file asks of the render (a Mitsuba scene's film, sampler and
    /// integrator), which the command line's own flags override.
    pub render_hints: RenderHints,
    /// Problems that did not stop loading (e.g. a material that does not conserve energy).
    pub warnings: Vec<String>,
    /// The Mitsuba BSDF each material (by index) was made of and what the engines render of
    /// it, for the materials of a Mitsuba scene that have one. Not light transport (the
    /// material's own fields are), so not part of `content_hash`.
    pub mitsuba_bsdfs: std::collections::BTreeMap<u32, bsdf_support::MitsubaBsdf>,
}

/// A light without area: a point (`intensity` in W·sr⁻¹, per colour channel), a spot (the
/// same, within a cone), or a directional light (`intensity` the irradiance, W·m⁻², on a
/// surface facing it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltaLight {
    pub kind: DeltaKind,
    pub intensity: Color,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeltaKind {
    Point {
        position: Vec3,
    },
    /// Full intensity within `beam` of `axis` (unit), falling linearly in the angle to
    /// zero at `cutoff` (radians) — Mitsuba's `spot`.
    Spot {
        position: Vec3,
        axis: Vec3,
        beam: f32,
        cutoff: f32,
        /// The texture the spot projects (Mitsuba's `texture`; default none), and the map
        /// from world directions to the spot's frame (its `to_world` inverted), in which a
        /// direction d falls on the image at (½ + ½·dx/(dz·tan cutoff), ½ + ½·dy/(dz·tan
        /// cutoff)), v running down.
        projects: Option<(usize, Mat3)>,
    },
    /// Light travelling along the unit `direction`.
    Directional {
        direction: Vec3,
    },
}

impl DeltaLight {
    /// What the light sends to point `x`: the unit direction towards it, the distance
    /// (infinite for a directional light) and the irradiance on a surface facing it; None
    /// where it sends nothing.
    pub fn towards(&self, x: Vec3, textures: &[Texture]) -> Option<(Vec3, f32, Color)> {
        match self.kind {
            DeltaKind::Directional { direction } => {
                Some((-direction, f32::INFINITY, self.intensity))
            }
            DeltaKind::Point { position } | DeltaKind::Spot { position, .. } => {
                let to = position - x;
                let d2 = to.length_squared();
                if d2.is_nan() || d2 <= 0.0 {
                    return None;
                }
                let d = d2.sqrt();
                let dir = to / d;
                let falloff = match self.kind {
                    DeltaKind::Spot {
                        axis,
                        beam,
                        cutoff,
                        projects,
                        ..
                    } => {
                        let angle = (-dir).dot(axis).clamp(-1.0, 1.0).acos();
                        if angle >= cutoff {
                            return None;
                        }
                        let ramp = if angle <= beam {
                            1.0
                        } else {
                            (cutoff - angle) / (cutoff - beam)
                        };
                        match projects {
                            None => Color::splat(ramp),
                            Some((k, to_local)) => {
                                let local = to_local * -dir;
                                let scale = 0.5 / (local.z * cutoff.tan());
                                let (u, v) = (0.5 + local.x * scale, 0.5 + local.y * scale);
                                textures[k].lookup(Vec2::new(u, 1.0 - v)) * ramp
                            }
                        }
                    }
                    _ => Color::ONE,
                };
                Some((dir, d, self.intensity * falloff / d2))
            }
        }
    }
}

/// The largest image side a render takes (`-size`, a scene's film): the EXR and PNG
/// encoders' own limits are higher; `--max-memory` bounds the area.
pub const MAX_IMAGE_SIDE: u32 = 1 << 16;

/// Render settings a scene file gives (Mitsuba's film, sampler and integrator), used where
/// the command line gives none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderHints {
    /// The image's width and height (`-size`).
    pub size: Option<(u32, u32)>,
    /// Samples per pixel (`-num_antialias_samples`).
    pub samples: Option<u32>,
    /// Scatterings a path may take (`--max-depth`); None: no limit.
    pub max_depth: Option<u32>,
    /// A thin lens: its radius and focus distance (`--aperture`, `--focus-distance`).
    pub lens: Option<(f32, f32)>,
    /// Mirror and refraction depth of the ray tracer and the engines built on it
    /// (`--num-bounces`), where the format has its own: MGF's (`mgf::NUM_BOUNCES`).
    pub num_bounces: Option<u32>,
    /// Shadow rays a light, which also turn on visibility in radiosity's form factors
    /// (`-num_shadow_samples`), where the format has its own: MGF's
    /// (`mgf::SHADOW_SAMPLES`).
    pub num_shadow_samples: Option<u32>,
    /// The hierarchical radiosity solver whatever the number of faces (`--radiosity-solver
    /// hierarchical`), for formats whose faces are too large to be one flat patch each: MGF's.
    pub hierarchical_radiosity: bool,
    /// The ray tracer's constant indirect radiance (`-ambient_light`), where the format has
    /// no such term: Mitsuba's, whose lights are all the light there is (the course's 0.1,
    /// in a Mitsuba scene's own units, made a lamp over a floor 8× too bright).
    pub ambient_light: Option<Color>,
}

impl Scene {
    /// Loads a scene file: MGF by its `.mgf` extension, Mitsuba 3 by `.xml`, else the course
    /// dialect or standard OBJ/MTL, decided by content.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with(path, &[])
    }

    /// `load`, with the values of a Mitsuba scene's `$name` parameters (`--define`), which
    /// win over its `<default>`s; other formats have no parameters.
    pub fn load_with(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
        let is = |ext: &str| {
            path.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case(ext))
        };
        let mgf = is("mgf");
        let text = if mgf || is("xml") {
            String::new()
        } else {
            let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
                file: path.to_path_buf(),
                source,
            })?;
            String::from_utf8_lossy(&bytes).into_owned()
        };
        let mut scene = if mgf {
            mgf::load(path)?
        } else if is("xml") {
            mitsuba::load(path, defines)?
        } else if dialect::is_dialect(&text) {
            dialect::parse(path, &text)?
        } else {
            obj::load(path)?
        };
        // Before any work: a value out of range makes rays of inf or NaN later.
        range::check_scene(&scene)?;
        scene.check_energy();
        scene.decode_used_textures()?;
        scene.decode_sky()?;
        Ok(scene)
    }

    /// Parses course-dialect text as if read from `path` (textures are not decoded).
    pub fn parse_dialect(path: &Path, text: &str) -> Result<Scene, SceneError> {
        dialect::parse(path, text)
    }

    /// The same scene scaled by `scale` about the origin, then moved by `offset` (camera
    /// included): for checking that results do not depend on units or position.
    pub fn transformed(&self, scale: f32, offset: Vec3) -> Scene {
        let map = |p: Vec3| p * scale + offset;
        let mut s = self.clone();
        for q in &mut s.quads {
            *q = Quad::new(q.vertices.map(map), q.tex_coords, q.material);
        }
        s.triangles.positions.iter_mut().for_each(|p| *p = map(*p));
        let placed = glam::DMat4::from_scale_rotation_translation(
            glam::DVec3::splat(scale as f64),
            glam::DQuat::IDENTITY,
            offset.as_dvec3(),
        );
        s.instancing.instances.clear();
        for i in &self.instancing.instances {
            s.instancing
                .add_instance(i.group, placed * i.to_world)
                .expect("a scaled invertible transform stays invertible");
        }
        for sp in &mut s.shapes {
            sp.shape = sp.shape.scaled(scale, offset);
        }
        let camera = self.camera();
        s.camera = Some(Camera {
            position: map(camera.position),
            point_of_interest: map(camera.point_of_interest),
            projection: match camera.projection {
                Projection::Orthographic { size } => {
                    Projection::Orthographic { size: size * scale }
                }
                p => p,
            },
            ..camera
        });
        // Coefficients are per scene unit: a medium scaled with the scene keeps its optical
        // depths, and the image.
        for m in &mut s.media {
            m.sigma_a /= scale;
            m.sigma_s /= scale;
            if let Some(h) = &mut m.heterogeneous {
                **h = h.transformed(scale, offset);
            }
        }
        // Patterns are laid out in scene units from their origin: both move with the scene.
        for m in &mut s.materials {
            if let Some(p) = &mut m.procedural {
                p.origin = map(p.origin);
                p.scale *= scale;
            }
            if let Some(b) = &mut m.bump {
                b.amplitude *= scale;
                if let procedural::BumpSource::Procedural {
                    scale: size,
                    origin,
                    ..
                } = &mut b.source
                {
                    *origin = map(*origin);
                    *size *= scale;
                }
            }
        }
        s.footprint = self.footprint.transformed(scale, offset);
        s.quad_neighbours = Default::default();
        s
    }

    /// The camera of the file, or the default camera for the scene's bounds.
    pub fn camera(&self) -> Camera {
        self.camera
            .unwrap_or_else(|| Camera::default_for(&self.bounds()))
    }

    /// A hash of the scene file's bytes (0 bytes if it cannot be read): what caches made for
    /// this scene are keyed by.
    pub fn file_hash(&self) -> u64 {
        let bytes = std::fs::read(&self.path).unwrap_or_default();
        let mut h = crate::sampling::mix64(bytes.len() as u64);
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            h = crate::sampling::mix64(h ^ u64::from_le_bytes(word));
        }
        h
    }

    /// A hash of everything loaded that light transport depends on: the materials, every
    /// primitive, the decoded texels of the textures used, and whether quads are two-sided —
    /// not the camera, and not the file's bytes (an `.mtl` file, a texture or `--two-sided`
    /// change the light without changing the scene file). What the photon maps saved by
    /// `--save-photons` are keyed by.
    pub fn content_hash(&self) -> u64 {
        use std::fmt::Write;
        let mut h = ContentHasher::default();
        // Debug prints every field, floats in their shortest exact form: equal text, equal
        // values.
        let _ = write!(
            h,
            "{:?}{:?}{:?}{:?}{}",
            self.materials, self.quads, self.triangles, self.shapes, self.two_sided_quads
        );
        // Only scenes with one-sided triangles hash the rule, keeping the other scenes' hashes.
        if self.one_sided_triangles {
            let _ = write!(h, "one-sided triangles");
        }
        // Only scenes with instances hash them, keeping the other scenes' hashes.
        if !self.instancing.instances.is_empty() {
            let groups: Vec<_> = self.instancing.groups.iter().map(|g| &g.mesh).collect();
            let placements: Vec<_> = self
                .instancing
                .instances
                .iter()
                .map(|i| (i.group, i.to_world))
                .collect();
            let _ = write!(h, "{groups:?}{placements:?}");
        }
        // Only scenes with media or a sky hash them: the other scenes keep the hash (and the
        // saved solutions and photon maps) they had before there were either.
        if self.fog.is_some() || self.sky.is_some() || !self.media.is_empty() {
            let _ = write!(
                h,
                "{:?}{:?}{:?}{:?}",
                self.media, self.fog, self.camera_medium, self.sky
            );
        }
        for t in self.textures.iter().chain(&self.height_maps) {
            let _ = write!(h, "texture {}x{}", t.width, t.height);
            for texel in &t.texels {
                for c in texel.to_array() {
                    h.word(c.to_bits() as u64);
                }
            }
        }
        h.finish()
    }

    /// The medium a ray travels in after passing through a boundary of material `m`: into
    /// its closed objects from the front (their `interior_medium`), or out of them from the
    /// back (their `exterior_medium`, else the fog); None for empty space.
    pub fn medium_beyond(&self, m: &Material, into_front: bool) -> Option<&medium::Medium> {
        let k = if into_front {
            m.interior_medium
        } else {
            m.exterior_medium.or(self.fog)
        };
        k.map(|k| &self.media[k])
    }

    /// The medium the camera's rays start in: `camera_medium`, else the fog.
    pub fn camera_medium(&self) -> Option<&medium::Medium> {
        self.camera_medium.or(self.fog).map(|k| &self.media[k])
    }

    /// What a ray leaving the scene along `direction` shows: the sky where the scene has one,
    /// else the background colour.
    pub fn sky_or_background(&self, direction: Vec3) -> Color {
        match &self.sky {
            Some(sky) => sky.radiance(direction.normalize_or_zero()),
            None => self.background,
        }
    }

    /// Whether anything lights the scene: a primitive whose material emits, a sky, or a light
    /// without area.
    pub fn emits_light(&self) -> bool {
        let used = self.used_materials();
        self.sky.is_some()
            || !self.delta_lights.is_empty()
            || self
                .materials
                .iter()
                .zip(used)
                .any(|(m, used)| used && m.is_emissive())
    }

    /// Whether light travels through a medium anywhere: fog, a material's interior or
    /// exterior, or the camera's.
    pub fn has_media(&self) -> bool {
        self.fog.is_some()
            || self.camera_medium.is_some()
            || self
                .materials
                .iter()
                .any(|m| m.interior_medium.is_some() || m.exterior_medium.is_some())
    }

    pub fn bounds(&self) -> Bounds3 {
        self.bounds_of(|_| true)
    }

    /// The bounds of the primitives whose material mirrors or transmits light (what caustic
    /// photons are aimed at), or None when there are none.
    pub fn specular_bounds(&self) -> Option<Bounds3> {
        let specular: Vec<bool> = self.materials.iter().map(Material::is_specular).collect();
        let b = self.bounds_of(|m| specular.get(m as usize).copied().unwrap_or(false));
        (!b.is_empty()).then_some(b)
    }

    /// The bounds of the primitives whose material index passes `keep`.
    fn bounds_of(&self, keep: impl Fn(u32) -> bool) -> Bounds3 {
        let mut b = Bounds3::EMPTY;
        for q in self.quads.iter().filter(|q| keep(q.material)) {
            b = b.union(Bounds3::from_points(&q.vertices));
        }
        for i in (0..self.triangles.len()).filter(|&i| keep(self.triangles.materials[i])) {
            b = b.union(Bounds3::from_points(&self.triangles.vertices(i)));
        }
        for s in self.shapes.iter().filter(|s| keep(s.material)) {
            b = b.union(s.shape.bounds());
        }
        // Instanced triangles: each group's kept triangles' box in the group's space, found
        // once, then placed by each instance (`Instance::place_box`: exact where instances do
        // not turn their group, a box around the triangles where they do). Placing every
        // instanced triangle made `render bench-accel` of 1,024 instances of a 69k-triangle
        // mesh take 8.7 s in all, against 0.15 s placing each instance's group box.
        let kept: Vec<Bounds3> = self
            .instancing
            .groups
            .iter()
            .map(|g| {
                (0..g.mesh.len())
                    .filter(|&j| keep(g.mesh.materials[j]))
                    .fold(Bounds3::EMPTY, |b, j| {
                        b.union(Bounds3::from_points(&g.mesh.vertices(j)))
                    })
            })
            .collect();
        for instance in &self.instancing.instances {
            let group_box = kept[instance.group as usize];
            if !group_box.is_empty() {
                b = b.union(instance.place_box(group_box));
            }
        }
        b
    }

    /// The primitives a ray may hit, instanced triangles counted once per instance.
    pub fn primitive_count(&self) -> usize {
        self.quads.len()
            + self.triangles.len()
            + self.shapes.len()
            + self.instancing.triangle_count()
    }

    /// The world vertices of instanced triangle `index` (`PrimKind::Instanced`): what the
    /// surface, the lights and the engines that need world triangles take it as.
    #[inline]
    pub fn instanced_vertices(&self, index: u32) -> [Vec3; 3] {
        self.instancing.world_vertices(index)
    }

    /// Whether a polygon of `material` is two surfaces, its back lit on its own: every
    /// polygon with `--two-sided`, and one whose Mitsuba BSDF is `twosided` (whose winding
    /// says nothing of the side the light comes from). A course polygon without `--two-sided`
    /// shows one surface from both sides, and a one-sided Mitsuba BSDF's back is black.
    pub fn lit_behind(&self, material: u32) -> bool {
        self.two_sided_quads || self.materials[material as usize].two_sided
    }

    /// Which polygons every query misses from behind (the scene's rule, `--two-sided`
    /// applied). Instanced triangles are always opaque from both sides (Mitsuba's rule).
    pub fn culled_backs(&self) -> CulledBacks {
        CulledBacks {
            quads: !self.two_sided_quads,
            triangles: self.one_sided_triangles && !self.two_sided_quads,
        }
    }

    pub fn material_of(&self, prim: PrimRef) -> u32 {
        let i = prim.index as usize;
        match prim.kind {
            PrimKind::Quad => self.quads[i].material,
            PrimKind::Triangle => self.triangles.materials[i],
            PrimKind::Shape => self.shapes[i].material,
            PrimKind::Instanced => self.instancing.material(prim.index),
        }
    }

    /// The albedo at a hit: the material's image or procedural texture when it has one (the
    /// pattern averaged over the pixel's footprint there), else its `diffuse`.
    ///
    /// Always inlined: as a call it cost the path tracer 1% of its time, where an untextured
    /// material's albedo is one load.
    #[inline(always)]
    pub fn albedo(&self, hit: &SurfaceHit) -> Color {
        let m = &self.materials[hit.material as usize];
        match (m.texture, &m.procedural) {
            (Some(t), _) => self.textures[t].lookup(self.tex_coords(hit)),
            (None, Some(p)) => p.albedo(
                hit.point,
                self.footprint.half_widths(hit.point, hit.geometric_normal),
            ),
            (None, None) => m.diffuse,
        }
    }

    /// Sets the footprint procedural textures and bumps are averaged over to a pixel of a
    /// `width`×`height` image through the scene's camera.
    pub fn filter_textures_for(&mut self, width: u32, height: u32) {
        self.footprint = procedural::Footprint::of_pixels(&self.camera(), width, height);
    }

    /// Indices of the materials some primitive uses.
    pub fn used_materials(&self) -> Vec<bool> {
        let mut used = vec![false; self.materials.len()];
        let mut mark = |m: u32| {
            if let Some(u) = used.get_mut(m as usize) {
                *u = true;
            }
        };
        self.quads.iter().for_each(|q| mark(q.material));
        self.triangles.materials.iter().for_each(|&m| mark(m));
        self.shapes.iter().for_each(|s| mark(s.material));
        // Every group is placed: the reader makes one where an instance first refers to it.
        for g in &self.instancing.groups {
            g.mesh.materials.iter().for_each(|&m| mark(m));
        }
        used
    }

    /// Clamps reflectances to [0, 1] and warns of materials that reflect more than they
    /// receive: each warning names the file, the material's line and its number.
    fn check_energy(&mut self) {
        for (i, m) in self.materials.iter_mut().enumerate() {
            for (name, value) in [
                ("diffuse", &mut m.diffuse),
                ("reflective", &mut m.reflective),
                ("transmitted", &mut m.transmitted),
            ] {
                let clamped = value.max(Vec3::ZERO).min(Vec3::ONE);
                if clamped != *value {
                    self.warnings.push(format!(
                        "{}:{}: material {i}: {name} {:.3} {:.3} {:.3} is outside [0, 1]; clamped to {:.3} {:.3} {:.3}",
                        self.path.display(),
                        m.line,
                        value.x,
                        value.y,
                        value.z,
                        clamped.x,
                        clamped.y,
                        clamped.z
                    ));
                    *value = clamped;
                }
            }
            let sum = m.diffuse + m.reflective + m.transmitted;
            if sum.max_element() > 1.0 + 1e-6 {
                self.warnings.push(format!(
                    "{}:{}: material {i}: diffuse + reflective + transmitted exceeds 1 ({:.3} {:.3} {:.3}): it does not conserve energy",
                    self.path.display(),
                    m.line,
                    sum.x,
                    sum.y,
                    sum.z
                ));
            }
        }
    }

    /// Decodes the sky's image, if the sky is one (`sky_texture`).
    fn decode_sky(&mut self) -> Result<(), SceneError> {
        let Some(sky::Sky::Map(map)) = &mut self.sky else {
            return Ok(());
        };
        let dir = self
            .path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let map = std::sync::Arc::make_mut(map);
        map.decode(&dir).map_err(|why| SceneError::Invalid {
            file: self.path.clone(),
            line: map.line,
            column: 1,
            message: format!("cannot read sky_texture: {why}"),
        })
    }

    /// Decodes the textures of the materials in use ("pay only for what the scene uses").
    fn decode_used_textures(&mut self) -> Result<(), SceneError> {
        let used = self.used_materials();
        let dir = self
            .path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        for (i, m) in self.materials.iter_mut().enumerate() {
            let Some(file) = &m.texture_file else {
                continue;
            };
            if !used[i] {
                continue;
            }
            let full = dir.join(file);
            let texture = Texture::load(&full).map_err(|why| SceneError::Invalid {
                file: self.path.clone(),
                line: m.line,
                column: 1,
                message: format!("material {i}: cannot read texture {why}"),
            })?;
            m.texture = Some(self.textures.len());
            self.textures.push(Texture {
                to_uv: m.texture_to_uv,
                nearest: m.texture_nearest,
                ..texture
            });
        }
        for (i, m) in self.materials.iter_mut().enumerate() {
            let Some(procedural::Bump {
                source: procedural::BumpSource::File { file, map },
                ..
            }) = &mut m.bump
            else {
                continue;
            };
            if !used[i] {
                continue;
            }
            let full = dir.join(&*file);
            let heights = Texture::load_heights(&full).map_err(|why| SceneError::Invalid {
                file: self.path.clone(),
                line: m.line,
                column: 1,
                message: format!("material {i}: cannot read bump_file {why}"),
            })?;
            *map = Some(self.height_maps.len());
            self.height_maps.push(heights);
        }
        Ok(())
    }
}

/// A stable 64-bit hash of `text`: the same in every build and on every machine.
pub fn hash_text(text: &str) -> u64 {
    use std::fmt::Write;
    let mut h = ContentHasher::default();
    let _ = h.write_str(text);
    h.finish()
}

/// A stable 64-bit hash of a stream of text and words (the same in every build, unlike the
/// standard library's hasher), for `Scene::content_hash` and `hash_text`.
#[derive(Default)]
struct ContentHasher {
    state: u64,
    pending: [u8; 8],
    len: usize,
}

impl ContentHasher {
    fn word(&mut self, w: u64) {
        self.state = crate::sampling::mix64(self.state ^ w);
    }

    fn finish(mut self) -> u64 {
        let mut tail = [0u8; 8];
        let rest = self.len % 8;
        tail[..rest].copy_from_slice(&self.pending[..rest]);
        self.word(u64::from_le_bytes(tail));
        self.word(self.len as u64);
        self.state
    }
}

impl std::fmt::Write for ContentHasher {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for &b in s.as_bytes() {
            self.pending[self.len % 8] = b;
            self.len += 1;
            if self.len.is_multiple_of(8) {
                let w = u64::from_le_bytes(self.pending);
                self.word(w);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    /// A spot at the origin looking along +z (its frame the world's), cutoff 45°, projecting
    /// an image of four texels, one colour a quadrant, u along +x and v along +y (down the
    /// image), as Mitsuba's `spot` maps a direction d to (½ + ½·dx/(dz·tan 45°), ½ + ½·dy/dz). A
    /// point one unit ahead and 0.1 aside in each quadrant gets that quadrant's colour, times
    /// the intensity over the squared distance (inside the beam, no ramp).
    #[test]
    fn a_spot_projects_its_texture_as_mitsuba_maps_it() {
        let (top_left, top_right) = (vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0));
        let (bottom_left, bottom_right) = (vec3(0.0, 0.0, 1.0), vec3(1.0, 1.0, 0.0));
        let image = Texture {
            width: 2,
            height: 2,
            texels: vec![top_left, top_right, bottom_left, bottom_right],
            to_uv: None,
            nearest: true,
        };
        let spot = DeltaLight {
            kind: DeltaKind::Spot {
                position: Vec3::ZERO,
                axis: Vec3::Z,
                beam: 40f32.to_radians(),
                cutoff: 45f32.to_radians(),
                projects: Some((0, Mat3::IDENTITY)),
            },
            intensity: Color::splat(2.0),
        };
        for (x, y, colour) in [
            (-0.1, -0.1, top_left),
            (0.1, -0.1, top_right),
            (-0.1, 0.1, bottom_left),
            (0.1, 0.1, bottom_right),
        ] {
            let p = vec3(x, y, 1.0);
            let (dir, distance, irradiance) = spot
                .towards(p, std::slice::from_ref(&image))
                .expect("inside the cone");
            assert!((dir + p.normalize()).length() < 1e-6);
            assert!((distance - p.length()).abs() < 1e-6);
            let expected = colour * 2.0 / p.length_squared();
            assert!(
                (irradiance - expected).length() < 1e-5,
                "at {p}: {irradiance} ≠ {expected}"
            );
        }
    }
}
