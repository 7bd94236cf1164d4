//! Our Mitsuba reader against Mitsuba's own loader: what `mi.load_file` and `mi.traverse`
//! make of each of Mitsuba's render-test scenes (`scripts/mitsuba_scene_params.py`) beside
//! what `Scene::load` makes of it — the camera, every shape's world bounding box, its BSDF's
//! plain parameters (RGB values, IORs, roughness) and its area emitter's radiance, and the
//! other emitters. Mitsuba turns named IORs (`bk7`, `water`) and spectra into RGB as its
//! RGB variants do; our reader must store the same numbers.

use std::path::{Path, PathBuf};

use super::json::{Fields, Json};
use trilux::geometry::{Bounds3, Shape};
use trilux::scene::bsdf::{Bsdf, Microfacet};
use trilux::scene::sky::Sky;
use trilux::scene::{DeltaKind, Material, Projection, Scene, ShadingTilt};

/// Camera directions, fov (radians), RGB values and IORs: f32 values both sides, which
/// differ only by rounding where the reader agrees with Mitsuba.
const VALUE_TOLERANCE: f64 = 1e-4;
/// Bounding boxes and positions, relative to the scene's size (the diagonal of Mitsuba's
/// scene box): the meshes are placed in f32 by both, in different orders of operations.
const PLACE_TOLERANCE: f64 = 1e-3;

/// Mitsuba's parameters that have no counterpart in our scene, so are not compared: each
/// with why.
const NOT_COMPARED: [(&str, &str); 4] = [
    (
        "sampling_weight",
        "an emitter's share of light samples: trilux picks lights its own way",
    ),
    (
        "opacity",
        "a mask's opacity texture (its data is not plain)",
    ),
    (
        "normalmap",
        "a normal map's texture (a rawconstant's value is a texture too)",
    ),
    (
        "texture",
        "a spot's projected texture (Mitsuba's is a constant 1 here)",
    ),
];

/// What Mitsuba makes of `files`, one JSON object per file.
fn mitsuba_params(files: &[PathBuf]) -> Vec<Json> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/mitsuba_scene_params.py");
    let run = std::process::Command::new("python3")
        .arg(script)
        .args(files)
        .output()
        .expect("python3 runs");
    assert!(
        run.status.success(),
        "mitsuba_scene_params.py: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8(run.stdout).expect("UTF-8");
    let parsed: Json = serde_json::from_str(&text).unwrap_or_else(|e| panic!("its JSON: {e}"));
    parsed.items().to_vec()
}

/// The comparisons of one scene: each difference found, and how many values agreed.
struct Compare<'a> {
    scene: &'a str,
    differences: Vec<(String, String, Vec<f64>, Vec<f64>)>,
    compared: usize,
}

impl Compare<'_> {
    /// Mitsuba's `theirs` against `ours`, element by element within `tolerance`; a single
    /// value of Mitsuba's stands for a grey colour.
    fn values(&mut self, what: &str, theirs: &[f64], ours: &[f32], tolerance: f64) {
        let ours: Vec<f64> = ours.iter().map(|&x| x as f64).collect();
        let theirs = match (theirs.len(), ours.len()) {
            (1, n) => vec![theirs[0]; n],
            _ => theirs.to_vec(),
        };
        self.compared += 1;
        let agree = theirs.len() == ours.len()
            && theirs
                .iter()
                .zip(&ours)
                .all(|(a, b)| (a - b).abs() <= tolerance);
        if !agree {
            self.differences
                .push((self.scene.to_string(), what.to_string(), theirs, ours));
        }
    }
}

/// Reads `dir`'s Mitsuba scenes with our reader and with Mitsuba's, and compares them (see
/// the module's comment). Every difference fails the test, all of them listed together.
pub fn our_reader_against_mitsubas_loader(dir: &Path) {
    let files = super::mitsuba_test_scenes(dir);
    assert_eq!(files.len(), 23, "Mitsuba's 23 render-test scenes");
    let params = mitsuba_params(&files);
    let mut differences = Vec::new();
    let mut compared = 0;
    for (file, theirs) in files.iter().zip(&params) {
        let name = file.file_stem().unwrap().to_string_lossy().to_string();
        let ours = Scene::load(file).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut c = Compare {
            scene: &name,
            differences: Vec::new(),
            compared: 0,
        };
        let [lo, hi] = corners(theirs.field("bbox"));
        let size = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
        camera(&mut c, &ours, theirs.field("sensor"), size);
        shapes(&mut c, &ours, theirs.field("shapes").items(), size);
        emitters(&mut c, &ours, theirs.field("emitters").items(), size);
        println!(
            "{name}: {} values compared, {} differ",
            c.compared,
            c.differences.len()
        );
        compared += c.compared;
        differences.extend(c.differences);
    }
    println!("{} scenes, {compared} values compared", files.len());
    let failures: Vec<String> = differences
        .iter()
        .map(|(scene, what, theirs, ours)| {
            format!("{scene}: {what}: Mitsuba {theirs:?}, ours {ours:?}")
        })
        .collect();
    assert!(
        failures.is_empty(),
        "our reader and Mitsuba's loader differ:\n{}",
        failures.join("\n")
    );
}

fn corners(b: &Json) -> [Vec<f64>; 2] {
    [b.items()[0].numbers(), b.items()[1].numbers()]
}

/// A 4×4 matrix's column `k` as a 3-vector (rows of the JSON are the matrix's rows).
fn column(m: &Json, k: usize) -> Vec<f64> {
    m.items()[..3]
        .iter()
        .map(|row| row.items()[k].number())
        .collect()
}

fn normalized(v: Vec<f64>) -> Vec<f64> {
    let length = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.into_iter().map(|x| x / length).collect()
}

/// The sensor's place, view direction and up (Mitsuba's camera looks along its +z, up its
/// +y), its film's size, and its field of view: Mitsuba gives it along x, ours spans the
/// larger side.
fn camera(c: &mut Compare, ours: &Scene, sensor: &Json, size: f64) {
    let camera = ours.camera.expect("the scene's camera");
    let to_world = sensor.field("to_world");
    c.values(
        "camera position",
        &column(to_world, 3),
        &camera.position.to_array(),
        PLACE_TOLERANCE * size,
    );
    let forward = (camera.point_of_interest - camera.position).normalize();
    c.values(
        "camera direction",
        &normalized(column(to_world, 2)),
        &forward.to_array(),
        VALUE_TOLERANCE,
    );
    c.values(
        "camera up",
        &normalized(column(to_world, 1)),
        &camera.up.to_array(),
        VALUE_TOLERANCE,
    );
    let [w, h] = [0, 1].map(|i| sensor.field("film_size").numbers()[i]);
    let (ow, oh) = ours.render_hints.size.expect("the film's size");
    c.values("film size", &[w, h], &[ow as f32, oh as f32], 0.0);
    let half_x = (sensor.field("x_fov").number().to_radians() / 2.0).tan();
    let larger = if w >= h { half_x } else { half_x * h / w };
    match camera.projection {
        Projection::Perspective { angle } => c.values(
            "camera fov (radians, larger side)",
            &[2.0 * larger.atan()],
            &[angle],
            VALUE_TOLERANCE,
        ),
        Projection::Orthographic { .. } => c.differences.push((
            c.scene.to_string(),
            "camera: ours orthographic, Mitsuba's perspective".into(),
            vec![],
            vec![],
        )),
    }
}

/// Mitsuba's shapes in its order (the file's, includes in place, as ours): a mesh's faces
/// are the next as many of our triangles, a sphere our next analytic shape. Compared: the
/// world bounding box, the material (which must be one for the whole shape). Shapes taken
/// in another order than Mitsuba's, or a mesh read with other faces, show as boxes that
/// differ.
fn shapes(c: &mut Compare, ours: &Scene, shapes: &[Json], size: f64) {
    let (mut triangle, mut analytic) = (0, 0);
    for (k, shape) in shapes.iter().enumerate() {
        let class = shape.field("class").string();
        let what = format!("shape {k} ({class})");
        let (bounds, materials): (Bounds3, Vec<u32>) = match shape.field("faces").as_f64() {
            Some(faces) => {
                let range = triangle..triangle + faces as usize;
                triangle = range.end;
                if range.end > ours.triangles.len() {
                    c.values(
                        &format!("{what}: triangles"),
                        &[range.end as f64],
                        &[ours.triangles.len() as f32],
                        0.0,
                    );
                    return;
                }
                let mut b = Bounds3::EMPTY;
                for i in range.clone() {
                    b = b.union(Bounds3::from_points(&ours.triangles.vertices(i)));
                }
                (b, ours.triangles.materials[range].to_vec())
            }
            _ if class == "Sphere" => {
                let s = ours
                    .shapes
                    .get(analytic)
                    .expect("an analytic shape per sphere");
                analytic += 1;
                (s.shape.bounds(), vec![s.material])
            }
            _ => panic!("{}: {what}: a shape kind this test does not match", c.scene),
        };
        let [lo, hi] = corners(shape.field("bbox"));
        let tolerance = PLACE_TOLERANCE * size;
        c.values(
            &format!("{what}: bbox min"),
            &lo,
            &bounds.min.to_array(),
            tolerance,
        );
        c.values(
            &format!("{what}: bbox max"),
            &hi,
            &bounds.max.to_array(),
            tolerance,
        );
        let material = materials[0];
        assert!(
            materials.iter().all(|&m| m == material),
            "{}: {what}: one material over the shape",
            c.scene
        );
        let m = &ours.materials[material as usize];
        let classes: Vec<&str> = shape
            .field("bsdf")
            .items()
            .iter()
            .map(Fields::string)
            .collect();
        bsdf(c, &what, m, &classes, shape.field("bsdf_params"));
        if let Some(emitter) = shape.get("area_emitter").filter(|e| !e.is_null()) {
            c.values(
                &format!("{what}: area radiance"),
                &emitter.field("radiance").numbers(),
                &m.emitted.to_array(),
                VALUE_TOLERANCE,
            );
        }
    }
    c.values(
        "triangles",
        &[triangle as f64],
        &[ours.triangles.len() as f32],
        0.0,
    );
    c.values(
        "spheres",
        &[analytic as f64],
        &[ours.shapes.len() as f32],
        0.0,
    );
}

/// A BSDF's parameters (its plugin `classes`, outermost first; `params` named as the
/// innermost has them) against material `m`. A checkerboard's two values (`X.color0`,
/// `X.color1`) are compared as their mean, which is what our reader keeps beside the
/// texture; the texture itself is not compared.
fn bsdf(c: &mut Compare, what: &str, m: &Material, classes: &[&str], params: &Json) {
    let inner = *classes.last().expect("a BSDF class");
    for (key, value) in params.members() {
        let (name, theirs) = match key.strip_suffix(".color0") {
            Some(name) => {
                let other = params.field(&format!("{name}.color1")).numbers();
                let mean = value.numbers().into_iter().zip(other);
                (name, mean.map(|(a, b)| 0.5 * (a + b)).collect())
            }
            None if key.ends_with(".color1") => continue,
            None => (key.as_str(), value.numbers()),
        };
        if NOT_COMPARED.iter().any(|(k, _)| *k == name) {
            continue;
        }
        let ours = parameter(m, inner, name).unwrap_or_else(|| {
            panic!(
                "{}: {what}: {} parameter \"{name}\": not compared by this test",
                c.scene,
                classes.join("/")
            )
        });
        c.values(
            &format!("{what}: {inner} {name}"),
            &theirs,
            &ours,
            VALUE_TOLERANCE,
        );
    }
}

/// What our material `m` holds for parameter `name` of Mitsuba's BSDF class `inner` (the
/// innermost plugin); None for a parameter this test does not know.
fn parameter(m: &Material, inner: &str, name: &str) -> Option<Vec<f32>> {
    let alpha = |d: &Option<Microfacet>, i: usize| {
        d.map(|d| {
            let (u, v) = d.alpha();
            vec![[u, v][i]]
        })
    };
    let one = |x: f32| Some(vec![x]);
    if name == "scale" {
        return match m.tilt {
            Some(ShadingTilt::BumpMap { scale, .. }) => one(scale),
            _ => Some(vec![]),
        };
    }
    match (&m.bsdf, inner, name) {
        // `twosided(diffuse)` is the course's diffuse material, no BSDF of its own.
        (None, "SmoothDiffuse", "reflectance") => Some(m.diffuse.to_array().to_vec()),
        (Some(Bsdf::Diffuse { reflectance }), _, "reflectance") => {
            Some(reflectance.to_array().to_vec())
        }
        // A smooth dielectric with plain factors is the course's glass: its index is `ior`.
        (None, "SmoothDielectric", "eta") => one(m.ior),
        (
            Some(Bsdf::Conductor {
                eta,
                k,
                specular,
                distribution,
            }),
            _,
            _,
        ) => match name {
            "eta" => Some(eta.to_array().to_vec()),
            "k" => Some(k.to_array().to_vec()),
            "specular_reflectance" => Some(specular.to_array().to_vec()),
            "alpha" | "alpha_u" => alpha(distribution, 0),
            "alpha_v" => alpha(distribution, 1),
            _ => None,
        },
        (
            Some(Bsdf::Dielectric {
                eta,
                reflectance,
                transmittance,
                distribution,
            }),
            _,
            _,
        ) => match name {
            "eta" => one(*eta),
            "specular_reflectance" => Some(reflectance.to_array().to_vec()),
            "specular_transmittance" => Some(transmittance.to_array().to_vec()),
            "alpha" | "alpha_u" => alpha(distribution, 0),
            "alpha_v" => alpha(distribution, 1),
            _ => None,
        },
        (Some(Bsdf::ThinDielectric { eta, .. }), _, "eta") => one(*eta),
        (Some(Bsdf::Plastic(p)), _, _) => match name {
            "eta" => one(p.eta()),
            "diffuse_reflectance" => Some(p.diffuse().to_array().to_vec()),
            "specular_reflectance" => Some(p.specular().to_array().to_vec()),
            "alpha" => alpha(&p.distribution(), 0),
            _ => None,
        },
        (Some(Bsdf::Principled(p)), _, _) => match name {
            "base_color" => Some(p.base_color.to_array().to_vec()),
            "roughness" => one(p.roughness),
            "anisotropic" => one(p.anisotropic),
            "metallic" => one(p.metallic),
            "spec_trans" => one(p.spec_trans),
            "specular" => one(p.specular),
            "eta" => Some(p.eta.into_iter().collect()),
            "spec_tint" => one(p.spec_tint),
            "sheen" => one(p.sheen),
            "sheen_tint" => one(p.sheen_tint),
            "flatness" => one(p.flatness),
            "clearcoat" => one(p.clearcoat),
            "clearcoat_gloss" => one(p.clearcoat_gloss),
            "main_specular_sampling_rate" => one(p.main_specular_sampling_rate),
            "clearcoat_sampling_rate" => one(p.clearcoat_sampling_rate),
            "diffuse_reflectance_sampling_rate" => one(p.diffuse_reflectance_sampling_rate),
            _ => None,
        },
        (Some(Bsdf::PrincipledThin(p)), _, _) => match name {
            "base_color" => Some(p.base_color.to_array().to_vec()),
            "roughness" => one(p.roughness),
            "anisotropic" => one(p.anisotropic),
            "spec_trans" => one(p.spec_trans),
            "eta" => one(p.eta),
            "spec_tint" => one(p.spec_tint),
            "sheen" => one(p.sheen),
            "sheen_tint" => one(p.sheen_tint),
            "flatness" => one(p.flatness),
            "diff_trans" => one(p.diff_trans),
            "specular_reflectance_sampling_rate" => one(p.specular_reflectance_sampling_rate),
            "specular_transmittance_sampling_rate" => one(p.specular_transmittance_sampling_rate),
            "diffuse_reflectance_sampling_rate" => one(p.diffuse_reflectance_sampling_rate),
            "diffuse_transmittance_sampling_rate" => one(p.diffuse_transmittance_sampling_rate),
            _ => None,
        },
        _ => None,
    }
}

/// The emitters that are not area lights: an environment (`constant`, `envmap`) is our
/// sky, a `point` or `spot` the next of our delta lights.
fn emitters(c: &mut Compare, ours: &Scene, emitters: &[Json], size: f64) {
    let mut delta = ours.delta_lights.iter();
    for e in emitters {
        let class = e.field("class").string();
        let params = e.field("params");
        let number = |name: &str| params.field(name).numbers();
        match class {
            "ConstantBackgroundEmitter" => match &ours.sky {
                Some(Sky::Uniform(radiance)) => c.values(
                    "constant radiance",
                    &number("radiance"),
                    &radiance.to_array(),
                    VALUE_TOLERANCE,
                ),
                other => panic!("{}: a constant emitter, ours {other:?}", c.scene),
            },
            "EnvironmentMapEmitter" => match &ours.sky {
                Some(Sky::Map(map)) => {
                    c.values(
                        "envmap scale",
                        &number("scale"),
                        &[map.scale],
                        VALUE_TOLERANCE,
                    );
                    // Our map keeps the inverse of the envmap's rotation (its transpose).
                    let frame = map.mitsuba_frame.expect("the envmap's frame").transpose();
                    for k in 0..3 {
                        c.values(
                            &format!("envmap to_world column {k}"),
                            &column(params.field("to_world"), k),
                            &frame.col(k).to_array(),
                            VALUE_TOLERANCE,
                        );
                    }
                }
                other => panic!("{}: an envmap, ours {other:?}", c.scene),
            },
            "PointLight" | "SpotLight" => {
                let light = delta.next().expect("a delta light per point or spot");
                c.values(
                    &format!("{class} intensity"),
                    &number("intensity"),
                    &light.intensity.to_array(),
                    VALUE_TOLERANCE,
                );
                match light.kind {
                    DeltaKind::Point { position } => c.values(
                        "point position",
                        &number("position"),
                        &position.to_array(),
                        PLACE_TOLERANCE * size,
                    ),
                    DeltaKind::Spot {
                        position,
                        axis,
                        beam,
                        cutoff,
                        ..
                    } => {
                        let to_world = params.field("to_world");
                        c.values(
                            "spot position",
                            &column(to_world, 3),
                            &position.to_array(),
                            PLACE_TOLERANCE * size,
                        );
                        c.values(
                            "spot axis",
                            &normalized(column(to_world, 2)),
                            &axis.to_array(),
                            VALUE_TOLERANCE,
                        );
                        c.values(
                            "spot cutoff (degrees)",
                            &number("cutoff_angle"),
                            &[cutoff.to_degrees()],
                            VALUE_TOLERANCE,
                        );
                        c.values(
                            "spot beam width (degrees)",
                            &number("beam_width"),
                            &[beam.to_degrees()],
                            VALUE_TOLERANCE,
                        );
                    }
                    DeltaKind::Directional { .. } => {
                        panic!("{}: a {class}, ours directional", c.scene)
                    }
                }
            }
            other => panic!("{}: emitter {other}: not compared by this test", c.scene),
        }
    }
    c.values(
        "delta lights",
        &[(ours.delta_lights.len() - delta.len()) as f64],
        &[ours.delta_lights.len() as f32],
        0.0,
    );
}
