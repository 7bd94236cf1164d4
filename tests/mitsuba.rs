//! Mitsuba 3 scenes (`.xml`): the reader against what Mitsuba's format defines (parameters,
//! includes, transforms composed in Mitsuba's order, its camera), a render against a closed
//! form (a diffuse sphere under a uniform environment: ρ·L wherever it is seen), and every
//! class of malformed file an error that names the file and the line.

mod common;

use std::path::{Path, PathBuf};

use common::{backends, temp_dir};
use trilux::accel::{self, AccelKind, AccelOptions};
use trilux::engines::{path, RenderSettings};
use trilux::geometry::vec3;
use trilux::scene::Scene;

/// Writes `files` (name, text) into a fresh folder; returns the path of the first.
fn write(test: &str, files: &[(&str, &[u8])]) -> PathBuf {
    let dir = temp_dir(&format!("mitsuba-{test}"));
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).expect("writes");
    }
    dir.join(files[0].0)
}

/// A scene of one unit sphere, scaled by 2 and then moved to x = 3 (Mitsuba applies a
/// transform's operations in order), seen from 5 units away along +z through a narrow lens
/// that the sphere fills, under a uniform environment of radiance 2.
const SPHERE: &str = r#"<scene version="3.0.0">
    <default name="rho" value="0.25"/>
    <integrator type="moment">
        <integrator type="path"><integer name="max_depth" value="-1"/></integrator>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="10"/>
        <transform name="to_world">
            <lookat origin="3, 0, 7" target="3, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="24"/>
            <integer name="height" value="16"/>
        </film>
        <sampler type="independent"><integer name="sample_count" value="32"/></sampler>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="2"/></emitter>
    <shape type="sphere">
        <transform name="to_world">
            <scale value="2"/>
            <translate x="3"/>
        </transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="$rho"/></bsdf>
    </shape>
</scene>"#;

#[test]
fn reads_parameters_transforms_camera_and_film() {
    let file = write("sphere", &[("sphere.xml", SPHERE.as_bytes())]);
    let scene = Scene::load(&file).expect("loads");
    assert_eq!(scene.shapes.len(), 1);
    let shape = format!("{:?}", scene.shapes[0].shape);
    assert!(
        shape.contains("centre: Vec3(3.0, 0.0, 0.0)") && shape.contains("radius: 2.0"),
        "scale, then translate: {shape}"
    );
    assert_eq!(scene.materials[0].diffuse, vec3(0.25, 0.25, 0.25));
    let camera = scene.camera.expect("a camera");
    assert_eq!(camera.position, vec3(3.0, 0.0, 7.0));
    assert!((camera.point_of_interest - vec3(3.0, 0.0, 6.0)).length() < 1e-6);
    let hints = &scene.render_hints;
    assert_eq!(hints.size, Some((24, 16)));
    assert_eq!(hints.samples, Some(32));
    assert_eq!(hints.max_depth, None, "max_depth -1 is no limit");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);

    // --define wins over <default>.
    let defined = Scene::load_with(&file, &[("rho".into(), "0.5".into())]).expect("loads");
    assert_eq!(defined.materials[0].diffuse, vec3(0.5, 0.5, 0.5));
}

/// Mitsuba's `max_depth` counts the camera's segment: 2 is direct light, one scattering.
#[test]
fn max_depth_counts_the_camera_segment() {
    let text = SPHERE.replace(r#"value="-1""#, r#"value="2""#);
    let file = write("depth", &[("depth.xml", text.as_bytes())]);
    assert_eq!(
        Scene::load(&file).expect("loads").render_hints.max_depth,
        Some(1)
    );
}

/// A convex diffuse object under a uniform environment L sees only the environment from
/// every point, so it reflects ρ·L whatever its shape: the image of the sphere that fills the
/// view is ρ·L, with both Accels.
#[test]
fn a_diffuse_sphere_under_a_uniform_sky_reflects_rho_times_the_sky() {
    let file = write("furnace", &[("furnace.xml", SPHERE.as_bytes())]);
    for mean in path_means(&file, 64) {
        assert!(
            (mean - 0.5).abs() < 0.005,
            "mean {mean}, expected ρ·L = 0.25 × 2"
        );
    }
}

/// `scene` rendered by the path tracer at `width`×`height` and `spp`, with each of `kinds`.
fn path_films(
    scene: &Scene,
    kinds: &[AccelKind],
    (width, height): (u32, u32),
    spp: u32,
) -> Vec<trilux::film::Film> {
    kinds
        .iter()
        .map(|&kind| {
            let accel = accel::build(scene, kind, &AccelOptions::default()).expect("builds");
            let settings = RenderSettings {
                width,
                height,
                num_antialias_samples: spp,
                quiet: true,
                ..RenderSettings::default()
            };
            path::render(scene, accel.as_ref(), &settings).0
        })
        .collect()
}

/// The mean of the first channel of `file` rendered by the path tracer at 24×16 and `spp`,
/// with each Accel.
fn path_means(file: &Path, spp: u32) -> Vec<f64> {
    let scene = Scene::load(file).expect("loads");
    path_films(&scene, &backends(), (24, 16), spp)
        .iter()
        .map(|film| film.pixels.iter().map(|p| p.x as f64).sum::<f64>() / film.pixels.len() as f64)
        .collect()
}

/// A `thindielectric` pane of bk7 (η = 1.5046) seen face on against a uniform environment of
/// radiance 2, with its transmission halved and its reflection off: what comes through is
/// 2 × 0.5 × (1 − R′), R′ = 2R/(1 + R), R = ((η − 1)/(η + 1))², whatever the engine does with
/// the pane's other lobe. Then a lossless pane (both factors 1) closed around a white
/// diffuse sphere: a furnace, L everywhere, which holds only if shadow rays through the pane
/// carry its transmission (1 − R′) and paths reflected by it the rest.
#[test]
fn a_thin_dielectric_lets_through_what_it_does_not_reflect() {
    let sphere = &SPHERE[SPHERE.find("    <shape").unwrap()..SPHERE.find("</scene>").unwrap()];
    let pane = SPHERE
        .replace(
            sphere,
            r#"<shape type="rectangle">
        <bsdf type="thindielectric">
            <rgb name="specular_transmittance" value="0.5"/>
            <rgb name="specular_reflectance" value="0"/>
        </bsdf>
    </shape>
"#,
        )
        .replace(
            r#"<lookat origin="3, 0, 7" target="3, 0, 0" up="0, 1, 0"/>"#,
            r#"<lookat origin="0, 0, 7" target="0, 0, 0" up="0, 1, 0"/>"#,
        )
        .replace(r#"<default name="rho" value="0.25"/>"#, "");
    let r = (0.5046f64 / 2.5046).powi(2);
    let expected = 2.0 * 0.5 * (1.0 - 2.0 * r / (1.0 + r));
    let file = write("pane", &[("pane.xml", pane.as_bytes())]);
    for mean in path_means(&file, 256) {
        // The lens's 10° spans cos θ ≥ 0.996 at the pane, where R changes by under 1e-4; a
        // sample passes or not, so the mean of 98,304 has a standard deviation of 9e-4.
        assert!(
            (mean - expected).abs() < 4e-3,
            "mean {mean}, expected {expected}"
        );
    }

    let furnace = SPHERE.replace(r#"value="0.25""#, r#"value="1""#).replace(
        r#"<shape type="sphere">"#,
        r#"<shape type="sphere">
        <transform name="to_world"><scale value="4"/><translate x="3"/></transform>
        <bsdf type="thindielectric"/>
    </shape>
    <shape type="sphere">"#,
    );
    let file = write("sheet-furnace", &[("furnace.xml", furnace.as_bytes())]);
    for mean in path_means(&file, 256) {
        assert!((mean - 2.0).abs() < 0.02, "mean {mean}, expected L = 2");
    }
}

/// `hide_emitters`: the uniform environment (radiance 2) is not seen straight from the camera,
/// and a glowing rectangle between the camera and the sphere is seen through, while the
/// sphere it does not hide is still lit by both: ρ·L = 0.5 in the image's middle (the
/// rectangle's own light, 1, adds ρ/π·E there: a little more), 0 in its corners.
#[test]
fn hidden_emitters_are_seen_through_and_still_light() {
    let text = SPHERE
        .replace(
            r#"<integrator type="path">"#,
            r#"<integrator type="path"><boolean name="hide_emitters" value="true"/>"#,
        )
        .replace(r#"<float name="fov" value="10"/>"#, r#"<float name="fov" value="40"/>"#)
        .replace(
            "</scene>",
            r#"<shape type="rectangle">
        <transform name="to_world"><scale value="0.3"/><rotate y="1" angle="180"/><translate x="3" z="5"/></transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
</scene>"#,
        );
    let file = write("hide", &[("hide.xml", text.as_bytes())]);
    let scene = Scene::load(&file).expect("loads");
    assert!(
        scene.hide_emitters && scene.warnings.is_empty(),
        "{:?}",
        scene.warnings
    );
    for film in path_films(&scene, &backends(), (24, 16), 64) {
        let at = |x: usize, y: usize| film.pixels[y * 24 + x].x;
        assert_eq!(at(0, 0), 0.0, "the sky is hidden");
        assert_eq!(at(23, 15), 0.0, "the sky is hidden");
        let middle = at(12, 8);
        assert!(
            (0.5..0.6).contains(&middle),
            "the sphere through the rectangle: {middle}"
        );
    }
}

/// A mesh read through `<include>` and `<path>`, placed by a 4×4 matrix, with its own
/// shading normals; a `rectangle` emitter with a spectrum converted as Mitsuba converts it.
#[test]
fn meshes_includes_paths_and_spectra() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n";
    let main = r#"<scene version="3.0.0">
        <path value="meshes"/>
        <include filename="part.xml"/>
        <shape type="rectangle">
            <emitter type="area">
                <spectrum name="radiance" value="400:1, 700:1"/>
            </emitter>
        </shape>
    </scene>"#;
    let part = r#"<scene version="3.0.0">
        <shape type="obj" id="tri">
            <string name="filename" value="tri.obj"/>
            <transform name="to_world">
                <matrix value="1 0 0 10  0 1 0 20  0 0 1 30  0 0 0 1"/>
            </transform>
        </shape>
    </scene>"#;
    let file = write(
        "include",
        &[("main.xml", main.as_bytes()), ("part.xml", part.as_bytes())],
    );
    let dir = file.parent().unwrap();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(dir.join("meshes/tri.obj"), obj).unwrap();
    let scene = Scene::load(&file).expect("loads");
    let t = &scene.triangles;
    assert_eq!(t.len(), 3, "one triangle and the rectangle's two");
    assert_eq!(t.positions[1], vec3(11.0, 20.0, 30.0), "row-major matrix");
    assert_eq!(t.normals.len(), t.positions.len());
    let light = &scene.materials[t.materials[1] as usize];
    // A flat spectrum over 400–700 nm: near-white, a little less than the full range gives.
    let e = light.emitted;
    assert!(e.min_element() > 0.6 && e.max_element() < 1.2, "{e}");
}

/// A shapegroup of one rectangle (moved by 1 along x inside the group) instanced twice: the
/// group alone makes nothing, its triangles are stored once, and each instance places them by
/// its own transform after theirs (Mitsuba's order), with the group's one material.
#[test]
fn instances_place_their_group_after_its_own_transforms() {
    let text = r#"<scene version="3.0.0">
        <shape type="shapegroup" id="group">
            <shape type="rectangle">
                <transform name="to_world"><translate x="1"/></transform>
                <bsdf type="diffuse"/>
            </shape>
        </shape>
        <shape type="instance"><ref id="group"/></shape>
        <shape type="instance">
            <ref id="group"/>
            <transform name="to_world"><scale value="2"/><translate z="5"/></transform>
        </shape>
    </scene>"#;
    let file = write("instances", &[("instances.xml", text.as_bytes())]);
    let scene = Scene::load(&file).expect("loads");
    assert!(scene.triangles.is_empty());
    let instancing = &scene.instancing;
    assert_eq!(
        instancing.stored_triangle_count(),
        2,
        "one rectangle stored"
    );
    assert_eq!(instancing.triangle_count(), 4, "two rectangles placed");
    let world: Vec<[trilux::geometry::Vec3; 3]> =
        (0..4).map(|i| scene.instanced_vertices(i)).collect();
    // A rectangle's centre: the middle of its first triangle's long edge (its diagonal).
    let centre = |k: usize| {
        let [a, b, c] = world[2 * k];
        let (ab, bc, ca) = ((a - b).length(), (b - c).length(), (c - a).length());
        if ab >= bc && ab >= ca {
            (a + b) / 2.0
        } else if bc >= ca {
            (b + c) / 2.0
        } else {
            (c + a) / 2.0
        }
    };
    assert_eq!(centre(0), vec3(1.0, 0.0, 0.0));
    assert_eq!(
        centre(1),
        vec3(2.0, 0.0, 5.0),
        "translated by 1, then scaled by 2, then moved"
    );
    assert_eq!(
        world[2][0].x - world[2][1].x,
        2.0 * (world[0][0].x - world[0][1].x)
    );
    let materials: Vec<u32> = (0..4).map(|i| instancing.material(i)).collect();
    assert!(materials.iter().all(|&m| m == materials[0]));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// The members of the shapegroup of `instanced_scene`, each with its own transform.
const GROUP_MEMBERS: [(&str, &str); 3] = [
    (
        r#"<shape type="cube"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf>"#,
        r#"<scale x="0.4" y="0.6" z="0.3"/>"#,
    ),
    (
        r#"<shape type="cylinder"><float name="radius" value="0.3"/><bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>"#,
        r#"<rotate x="1" angle="30"/><translate x="0.8"/>"#,
    ),
    (
        r#"<shape type="disk"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/></bsdf>"#,
        r#"<scale value="0.5"/><translate y="0.9"/>"#,
    ),
];

/// Where `instanced_scene` places its group: as it is, rotated, scaled unevenly, mirrored.
const PLACEMENTS: [&str; 4] = [
    r#"<translate x="-1.5" y="-1"/>"#,
    r#"<rotate y="1" angle="70"/><translate x="1.2" y="-0.8" z="0.3"/>"#,
    r#"<scale x="1.6" y="0.7" z="1.2"/><translate x="-1" y="1.2"/>"#,
    r#"<scale x="-1"/><rotate z="1" angle="25"/><translate x="1.3" y="1.1"/>"#,
];

/// A scene of the group of `GROUP_MEMBERS` (a box, a cylinder, a disk) placed at each of
/// `PLACEMENTS` — through a shapegroup and instances when `instanced`, else each member written
/// out at every placement, its own transform then the instance's (Mitsuba's order) — on a
/// floor, lit by a rectangle and a dim environment, seen from above.
fn instanced_scene(instanced: bool) -> String {
    let mut shapes = String::new();
    if instanced {
        shapes += r#"<shape type="shapegroup" id="g">"#;
        for (shape, own) in GROUP_MEMBERS {
            shapes += &format!("{shape}<transform name=\"to_world\">{own}</transform></shape>\n");
        }
        shapes += "</shape>\n";
        for place in PLACEMENTS {
            shapes += &format!(
                "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">{place}</transform></shape>\n"
            );
        }
    } else {
        for place in PLACEMENTS {
            for (shape, own) in GROUP_MEMBERS {
                shapes += &format!(
                    "{shape}<transform name=\"to_world\">{own}{place}</transform></shape>\n"
                );
            }
        }
    }
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="5"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="55"/>
        <transform name="to_world"><lookat origin="0.5, -3, 6" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.8"/><rotate x="1" angle="180"/><translate x="0.5" y="-0.5" z="4"/></transform>
        <emitter type="area"><rgb name="radiance" value="12"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5"/><translate z="-0.7"/></transform>
        <bsdf type="diffuse"/>
    </shape>
    {shapes}
</scene>"#
    )
}

/// The path tracer renders the instanced scene as it renders the same shapes placed directly,
/// with both Accels; and the group is stored once. The images are not identical: an
/// instanced triangle is tested in its group's space, on a ray rounded there, so a hit's point
/// and normals differ from the flattened ones in their last bits, and a path whose random
/// decision (Russian roulette, a light sample at the rim of a BSDF lobe) lies within those
/// bits of its threshold turns elsewhere. So nearly every pixel agrees to float precision (here
/// all of them, the worst by 7e-6 of its value), a few may differ as two samples of the same
/// pixel differ, and the image means agree within their noise. The two Accels' instanced
/// images are identical: they hit the same triangle at the same t, u and v.
#[test]
fn an_instanced_scene_renders_as_its_shapes_placed_directly() {
    let instanced = write(
        "instanced",
        &[("instanced.xml", instanced_scene(true).as_bytes())],
    );
    let flattened = write(
        "flattened",
        &[("flattened.xml", instanced_scene(false).as_bytes())],
    );
    let (scene, flat) = (
        Scene::load(&instanced).expect("loads"),
        Scene::load(&flattened).expect("loads"),
    );
    let floor_and_light = 4;
    assert_eq!(scene.triangles.len(), floor_and_light);
    let per_group = (flat.triangles.len() - floor_and_light) / PLACEMENTS.len();
    assert_eq!(
        scene.instancing.stored_triangle_count(),
        per_group,
        "the group's triangles stored once"
    );
    assert_eq!(
        scene.instancing.triangle_count(),
        PLACEMENTS.len() * per_group
    );
    assert_eq!(scene.instancing.instances.len(), PLACEMENTS.len());
    // Every instanced triangle where the flattened scene has it (to float precision: the
    // flattened vertex is placed by the composed transform).
    for i in 0..scene.instancing.triangle_count() {
        let placed = scene.instanced_vertices(i as u32);
        let direct = flat.triangles.vertices(floor_and_light + i);
        for (a, b) in placed.iter().zip(direct) {
            assert!((*a - b).abs().max_element() <= 1e-6 * (1.0 + b.abs().max_element()));
        }
    }
    let size = (64, 48);
    let spp = 16;
    let kinds = backends();
    let films = path_films(&scene, &kinds, size, spp);
    let direct = path_films(&flat, &kinds[..1], size, spp).remove(0);
    for film in &films[1..] {
        assert!(
            film.pixels == films[0].pixels,
            "the Accels' instanced images are identical"
        );
    }
    let film = &films[0];
    let lum = |c: &trilux::geometry::Vec3| (c.x + c.y + c.z) as f64 / 3.0;
    let close = film
        .pixels
        .iter()
        .zip(&direct.pixels)
        .filter(|(a, b)| (lum(a) - lum(b)).abs() <= 1e-4 * (1.0 + lum(b)))
        .count();
    let n = film.pixels.len();
    let worst = film
        .pixels
        .iter()
        .zip(&direct.pixels)
        .map(|(a, b)| (lum(a) - lum(b)).abs() / (1.0 + lum(b)))
        .fold(0.0, f64::max);
    let mean = |f: &trilux::film::Film| f.pixels.iter().map(lum).sum::<f64>() / n as f64;
    let (m_inst, m_flat) = (mean(film), mean(&direct));
    // The noise of the mean: the pixels' spread over √n (each pixel an independent estimate).
    let spread = (direct
        .pixels
        .iter()
        .map(|p| (lum(p) - m_flat).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    println!(
        "{close} of {n} pixels agree to 1e-4 (the worst by {worst:.2e}); means {m_inst:.6} (instanced) and {m_flat:.6} (placed directly), pixel spread {spread:.4}"
    );
    assert!(m_flat > 0.05, "the scene is lit: {m_flat}");
    assert!(close >= n - n / 100, "{close} of {n} pixels agree");
    assert!(
        (m_inst - m_flat).abs() <= 3.0 * spread / (n as f64).sqrt(),
        "means {m_inst} and {m_flat}"
    );
}

/// The other engines take instanced triangles as world triangles where they need them (the
/// radiosity mesh a patch per instanced triangle, the lights, the plan): each renders the
/// instanced scene as the shapes placed directly, to float precision (the radiosity mesh's
/// patches are the same, in the same order), and `--plan` says how many triangles are stored
/// and how many instanced.
#[test]
fn every_engine_renders_instances_as_shapes_placed_directly() {
    use trilux::engines::{render, EngineKind};
    let load = |name: &str, instanced: bool| {
        let text = instanced_scene(instanced);
        Scene::load(&write(name, &[(&format!("{name}.xml"), text.as_bytes())])).expect("loads")
    };
    let (scene, flat) = (
        load("engines-instanced", true),
        load("engines-flattened", false),
    );
    let settings = RenderSettings {
        width: 32,
        height: 24,
        num_antialias_samples: 4,
        quiet: true,
        ..RenderSettings::default()
    };
    let per_group = scene.instancing.stored_triangle_count();
    let plan = trilux::plan::Plan::new(&scene, EngineKind::Radiosity, AccelKind::Bvh, &settings);
    let expected = format!(
        "instancing: 4 instances of 1 shapegroup: {per_group} triangles stored, {} triangles instanced",
        4 * per_group
    );
    assert!(plan.to_string().contains(&expected), "{plan}");
    for kind in [
        EngineKind::Raycast,
        EngineKind::Raytrace,
        EngineKind::Radiosity,
    ] {
        let mean = |scene: &Scene| {
            let accel = accel::build(scene, AccelKind::Bvh, &AccelOptions::default()).unwrap();
            let film = render(kind, scene, accel.as_ref(), &settings)
                .expect("renders")
                .film;
            film.pixels
                .iter()
                .map(|p| p.x as f64 + p.y as f64 + p.z as f64)
                .sum::<f64>()
                / film.pixels.len() as f64
        };
        let (a, b) = (mean(&scene), mean(&flat));
        println!("{kind:?}: {a:.6} instanced, {b:.6} placed directly");
        assert!(b > 0.01, "{kind:?} renders something: {b}");
        assert!((a - b).abs() <= 1e-4 * b, "{kind:?}: {a} against {b}");
    }
}

/// Mitsuba refuses emitters in a shapegroup, and nested instancing: so does trilux, naming
/// the file and line.
#[test]
fn emitters_and_instances_inside_a_shapegroup_are_refused() {
    let group = |inner: &str| {
        format!(
            "{HEAD}<shape type=\"shapegroup\" id=\"g\">\n{inner}\n</shape>\n<shape type=\"instance\"><ref id=\"g\"/></shape>\n</scene>\n"
        )
    };
    let emitter = group("<shape type=\"rectangle\">\n<emitter type=\"area\"/>\n</shape>");
    let file = write("group-emitter", &[("emitter.xml", emitter.as_bytes())]);
    fails(&file, "emitter.xml", 4, &["emitter", "shapegroup"]);
    let nested = format!(
        "{HEAD}<shape type=\"shapegroup\" id=\"h\"><shape type=\"cube\"/></shape>\n{}",
        &group("<shape type=\"instance\"><ref id=\"h\"/></shape>")[HEAD.len()..]
    );
    let file = write("group-nested", &[("nested.xml", nested.as_bytes())]);
    fails(&file, "nested.xml", 4, &["instance", "shapegroup"]);
}

/// Asserts that loading `file` fails with a message naming `file_name` at `line` and
/// containing each of `words`.
fn fails(file: &Path, file_name: &str, line: u32, words: &[&str]) {
    let err = Scene::load(file).expect_err("a malformed scene is refused");
    let message = err.to_string();
    assert!(
        message.contains(&format!("{file_name}:{line}:")),
        "no {file_name}:{line}: in: {message}"
    );
    for w in words {
        assert!(message.contains(w), "`{w}` missing from: {message}");
    }
}

const HEAD: &str = "<scene version=\"3.0.0\">\n";

#[test]
fn malformed_xml_unknown_plugins_and_bad_values_name_the_file_and_line() {
    let cases: [(&str, String, u32, &[&str]); 6] = [
        ("unclosed", format!("{HEAD}<shape type=\"sphere\">\n</scene>\n"), 3, &["malformed XML"]),
        (
            "unknown",
            format!("{HEAD}<shape type=\"sphere\">\n<bsdf type=\"velvet\"/>\n</shape>\n</scene>\n"),
            3,
            &["\"velvet\"", "diffuse"],
        ),
        (
            "number",
            format!("{HEAD}<shape type=\"sphere\">\n<float name=\"radius\" value=\"2,5x\"/>\n</shape>\n</scene>\n"),
            3,
            &["not a finite number"],
        ),
        (
            "nan",
            format!("{HEAD}<shape type=\"sphere\">\n<point name=\"center\" x=\"nan\"/>\n</shape>\n</scene>\n"),
            3,
            &["not a finite number"],
        ),
        (
            "ref",
            format!("{HEAD}<shape type=\"sphere\">\n<ref id=\"nowhere\"/>\n</shape>\n</scene>\n"),
            3,
            &["nowhere"],
        ),
        (
            "huge",
            format!("{HEAD}<sensor type=\"perspective\">\n<film type=\"hdrfilm\">\n<integer name=\"width\" value=\"1000000\"/>\n<integer name=\"height\" value=\"1000000\"/>\n</film>\n</sensor>\n</scene>\n"),
            2,
            &["1000000", "at most"],
        ),
    ];
    for (name, text, line, words) in cases {
        let file_name = format!("{name}.xml");
        let file = write(name, &[(&file_name, text.as_bytes())]);
        fails(&file, &file_name, line, words);
    }
}

#[test]
fn include_cycles_missing_and_broken_meshes_name_the_file_and_line() {
    let a = format!("{HEAD}<include filename=\"b.xml\"/>\n</scene>\n");
    let b = format!("{HEAD}\n<include filename=\"a.xml\"/>\n</scene>\n");
    let file = write("cycle", &[("a.xml", a.as_bytes()), ("b.xml", b.as_bytes())]);
    fails(&file, "b.xml", 3, &["cycle"]);

    let mesh = |name: &str| {
        format!("{HEAD}<shape type=\"ply\">\n<string name=\"filename\" value=\"{name}\"/>\n</shape>\n</scene>\n")
    };
    let file = write(
        "missing",
        &[("missing.xml", mesh("nowhere.ply").as_bytes())],
    );
    fails(&file, "missing.xml", 3, &["nowhere.ply"]);

    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let mut truncated = header.as_bytes().to_vec();
    truncated.extend_from_slice(&[0u8; 20]);
    let file = write(
        "truncated",
        &[
            ("truncated.xml", mesh("cut.ply").as_bytes()),
            ("cut.ply", &truncated),
        ],
    );
    fails(&file, "truncated.xml", 3, &["cut.ply"]);

    let mut past = header.as_bytes().to_vec();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        past.extend_from_slice(&v.to_le_bytes());
    }
    past.push(3);
    for k in [0i32, 1, 7] {
        past.extend_from_slice(&k.to_le_bytes());
    }
    let file = write(
        "past",
        &[
            ("past.xml", mesh("past.ply").as_bytes()),
            ("past.ply", &past),
        ],
    );
    fails(&file, "past.xml", 3, &["past.ply", "vertex 7"]);

    let undefined = format!("{HEAD}<shape type=\"$kind\"/>\n</scene>\n");
    let file = write("undefined", &[("undefined.xml", undefined.as_bytes())]);
    fails(&file, "undefined.xml", 2, &["$kind", "--define"]);
}

/// The bytes of a Mitsuba `.vol` grid of `size` cells of `channels` channels (unit box).
fn vol(size: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
    let mut bytes = b"VOL\x03".to_vec();
    for v in [1, size[0], size[1], size[2], channels] {
        bytes.extend(v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(values) {
        bytes.extend(v.to_le_bytes());
    }
    bytes
}

/// A cube [−1, 1]³ of `medium` bounded by a `null` BSDF, filling the view from z = 5, under
/// a uniform environment of radiance 1; the grid files are `sigmat.vol` and `albedo.vol`.
fn medium_cube(medium: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="-1"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="20"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    {medium}
    <shape type="cube">
        <bsdf type="null"/>
        <ref id="inside" name="interior"/>
    </shape>
</scene>"#
    )
}

/// A `gridvolume` of `file` over the cube [−1, 1]³ (its unit cube scaled by 2, then moved).
fn grid(name: &str, file: &str) -> String {
    format!(
        r#"<volume name="{name}" type="gridvolume">
            <string name="filename" value="{file}"/>
            <transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform>
        </volume>"#
    )
}

/// The mean of each channel of a path-traced image of `scene` at `spp` paths a pixel.
fn mean_colour(scene: &Scene, spp: u32) -> [f64; 3] {
    let film = &path_films(scene, &backends()[..1], (12, 12), spp)[0];
    let n = film.pixels.len() as f64;
    [0, 1, 2].map(|c| film.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n)
}

/// A heterogeneous medium against closed forms: a medium that only scatters (albedo 1),
/// under a uniform environment, is a furnace, radiance 1 everywhere whatever its density, so
/// a coloured ramp of σt renders 1 in every channel (delta tracking, ratio tracking and
/// next-event estimation together unbiased); and a grid of one value renders what the
/// homogeneous medium of that σt and albedo does.
#[test]
fn heterogeneous_media_render_a_furnace_and_match_a_homogeneous_medium() {
    // σt 0 at x ≤ −0.5 rising to (8, 4, 2) at x ≥ 0.5.
    let ramp = vol([2, 1, 1], 3, &[0.0, 0.0, 0.0, 8.0, 4.0, 2.0]);
    let albedo = vol([1, 1, 1], 3, &[1.0, 1.0, 1.0]);
    let furnace = medium_cube(&format!(
        r#"<medium id="inside" type="heterogeneous">{}{}</medium>"#,
        grid("sigma_t", "sigmat.vol"),
        grid("albedo", "albedo.vol")
    ));
    let file = write(
        "furnace-medium",
        &[
            ("furnace.xml", furnace.as_bytes()),
            ("sigmat.vol", &ramp),
            ("albedo.vol", &albedo),
        ],
    );
    let scene = Scene::load(&file).expect("loads");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mean = mean_colour(&scene, 256);
    assert!(
        mean.iter().all(|m| (m - 1.0).abs() < 0.01),
        "the furnace: {mean:?}, expected 1"
    );

    let constant = vol([2, 2, 2], 1, &[0.6; 8]);
    let heterogeneous = medium_cube(&format!(
        r#"<medium id="inside" type="heterogeneous"><float name="scale" value="2"/>{}<rgb name="albedo" value="0.9, 0.5, 0.2"/></medium>"#,
        grid("sigma_t", "sigmat.vol")
    ));
    let homogeneous = medium_cube(
        r#"<medium id="inside" type="homogeneous"><rgb name="sigma_t" value="1.2"/><rgb name="albedo" value="0.9, 0.5, 0.2"/></medium>"#,
    );
    let file = write(
        "constant-medium",
        &[
            ("heterogeneous.xml", heterogeneous.as_bytes()),
            ("homogeneous.xml", homogeneous.as_bytes()),
            ("sigmat.vol", &constant),
        ],
    );
    let ours = mean_colour(&Scene::load(&file).expect("loads"), 256);
    let reference = mean_colour(
        &Scene::load(&file.with_file_name("homogeneous.xml")).expect("loads"),
        256,
    );
    for c in 0..3 {
        assert!(
            (ours[c] / reference[c] - 1.0).abs() < 0.015,
            "channel {c}: {ours:?} against the homogeneous {reference:?}"
        );
    }
}

/// A grid file that is cut short, or a `sigma_t` that is not a grid, is refused with the
/// scene's file and line (and the grid file's name and what it expected).
#[test]
fn bad_heterogeneous_media_name_the_file_and_line() {
    let medium = |sigma_t: &str| {
        medium_cube(&format!(
            "<medium id=\"inside\" type=\"heterogeneous\">\n{sigma_t}\n</medium>"
        ))
    };
    let cut = vol([4, 4, 4], 1, &[1.0; 60]);
    let text = medium(&grid("sigma_t", "cut.vol"));
    let file = write(
        "cut-grid",
        &[("cut.xml", text.as_bytes()), ("cut.vol", &cut)],
    );
    fails(&file, "cut.xml", 11, &["cut.vol", "expected 304", "4×4×4"]);

    let text = medium(r#"<rgb name="sigma_t" value="1"/>"#);
    let file = write("rgb-sigma-t", &[("rgb.xml", text.as_bytes())]);
    fails(&file, "rgb.xml", 10, &["sigma_t", "gridvolume"]);
}

/// The engines that do not render heterogeneous media refuse a scene with one, naming the
/// scene's file and the medium's line, before any work; the path tracer renders it.
#[test]
fn engines_other_than_the_path_tracer_refuse_a_heterogeneous_medium() {
    let text = medium_cube(&format!(
        "<medium id=\"inside\" type=\"heterogeneous\">\n{}\n</medium>",
        grid("sigma_t", "sigmat.vol")
    ));
    let density = vol([1, 1, 1], 1, &[1.0]);
    let file = write(
        "refused-medium",
        &[("refused.xml", text.as_bytes()), ("sigmat.vol", &density)],
    );
    only_the_path_tracer_renders(&file, "refused.xml:9: the scene has a heterogeneous medium");
}

/// The path tracer renders `file` at 8×8, and every other engine refuses it with a message
/// that contains `message`, before any image is written.
fn only_the_path_tracer_renders(file: &Path, message: &str) {
    for engine in ["path", "raytrace", "photon", "radiosity", "sppm"] {
        let image = file.with_file_name(format!("{engine}.png"));
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
            .args([
                "-input",
                file.to_str().unwrap(),
                "-size",
                "8",
                "8",
                "--quiet",
            ])
            .args(["--engine", engine, "-num_antialias_samples", "4", "-o"])
            .arg(&image)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        if engine == "path" {
            assert!(out.status.success(), "{engine}: {stderr}");
            continue;
        }
        assert!(!out.status.success(), "{engine}: {stderr}");
        assert!(stderr.contains(message), "{engine}: {stderr}");
        assert!(!image.exists(), "{engine}: an image was written");
    }
}

/// Media outside shapes, against closed-form transmittance. Under a uniform environment of
/// radiance 1, an orthographic camera on the z axis looks through a purely absorbing medium
/// of σt `sigma` (albedo 0) and a `null` sphere of radius ½ at the origin that holds empty
/// space (no `interior`) inside that medium (its `exterior`); the medium fills `box`, a
/// `null` cube [−s, s]³. The view is 0.04 wide, so every ray crosses the sphere within 0.2%
/// of its diameter, and sees exp(−σ·ℓ) with ℓ its length in the medium.
fn medium_around_a_hollow_sphere(sigma: f64, box_half: f64, camera_medium: bool) -> String {
    let sensor_medium = if camera_medium {
        r#"<ref id="fog"/>"#
    } else {
        ""
    };
    format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="-1"/></integrator>
    <medium id="fog" type="homogeneous">
        <rgb name="sigma_t" value="{sigma}"/><rgb name="albedo" value="0"/>
    </medium>
    <sensor type="orthographic">
        <transform name="to_world"><scale value="0.02"/><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        {sensor_medium}
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="cube">
        <transform name="to_world"><scale value="{box_half}"/></transform>
        <bsdf type="null"/>
        <ref id="fog" name="interior"/>
    </shape>
    <shape type="sphere">
        <float name="radius" value="0.5"/>
        <bsdf type="null"/>
        <ref id="fog" name="exterior"/>
    </shape>
</scene>"#
    )
}

/// A shape's `exterior` medium is what a ray leaving it through its back travels in, and a
/// sensor's medium is what its rays start in (the path tracer's, in both Accels): the camera
/// outside the unit box sees exp(−σ·(2 − 1)) through the box of medium with the hollow sphere
/// in it (exp(−σ·½) if leaving the sphere were taken as empty space); the camera inside a
/// box [−10, 10]³ of medium sees exp(−σ·(15 − 1)) (exp(−σ·9.5) if it started in empty space).
/// `--plan` says which medium is on which side of which boundary, and where the camera is.
/// The other engines refuse such a scene, naming the medium's line.
#[test]
fn exterior_and_sensor_media_attenuate_by_the_length_travelled_in_them() {
    for (name, sigma, box_half, camera_medium, length) in [
        ("outside", 0.5, 1.0, false, 1.0),
        ("inside", 0.1, 10.0, true, 14.0),
    ] {
        let text = medium_around_a_hollow_sphere(sigma, box_half, camera_medium);
        let file = write(
            &format!("exterior-{name}"),
            &[("exterior.xml", text.as_bytes())],
        );
        let scene = Scene::load(&file).expect("loads");
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let plan = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
            .args(["-input", file.to_str().unwrap(), "--plan"])
            .output()
            .expect("runs");
        let camera = if camera_medium {
            "; the camera in medium 0"
        } else {
            ""
        };
        let media = format!(
            "media at boundaries: material 0: medium 0 inside; material 1: medium 0 outside{camera}\n"
        );
        assert!(
            String::from_utf8_lossy(&plan.stdout).contains(&media),
            "{name}: --plan does not say {media:?}"
        );
        let expected = (-sigma * length).exp();
        for mean in path_means(&file, 256) {
            // Each path survives the absorption or not: 98,304 of them give a standard
            // deviation under 0.3% of the mean; the sphere's curvature across the view adds
            // at most 0.2%.
            assert!(
                (mean / expected - 1.0).abs() < 0.015,
                "{name}: mean {mean}, expected exp(-{sigma}·{length}) = {expected}"
            );
        }
    }

    let text = medium_around_a_hollow_sphere(0.5, 1.0, false);
    let file = write("exterior-refused", &[("refused.xml", text.as_bytes())]);
    only_the_path_tracer_renders(
        &file,
        "refused.xml:3: the scene has a medium around the camera or outside a shape",
    );
}

/// A rectangle emitter whose `radiance` is a `checkerboard` (red 1 and 0.1, `to_uv` doubling
/// u), as Mitsuba defines it on its `rectangle` (u = (x + 1)/2, v = (y + 1)/2 in the shape's
/// own coordinates; `color0` where u mod ½ and v mod ½ fall in the same half), placed by
/// `to_world`, with `extra` shapes beside it, seen by an orthographic camera from z = 5 over
/// [−`half`, `half`]².
fn checker_emitter(to_world: &str, half: f32, extra: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world"><scale value="{half}"/><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">{to_world}</transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area">
            <texture type="checkerboard" name="radiance">
                <rgb name="color0" value="1, 0.5, 0.25"/>
                <rgb name="color1" value="0.1, 0.1, 0.1"/>
                <transform name="to_uv"><scale x="2" y="1"/></transform>
            </texture>
        </emitter>
    </shape>
    {extra}
</scene>"#
    )
}

/// The red radiance of `checker_emitter`'s checkerboard at the rectangle's own (x, y).
fn checker_red(x: f64, y: f64) -> f64 {
    let (u, v) = (2.0 * (x + 1.0) / 2.0, (y + 1.0) / 2.0);
    let upper = |t: f64| t - t.floor() > 0.5;
    if upper(u) == upper(v) {
        1.0
    } else {
        0.1
    }
}

/// A textured area light (Mitsuba's `area` with a `checkerboard` radiance), in the path
/// tracer with both Accels. Seen face on, each pixel (whose edges the checks' and the
/// rectangle's fall on) shows its check's radiance exactly (Mitsuba 3 renders the same
/// pattern, blurred by its Gaussian pixel filter). Lighting a white floor (ρ = ½) from a
/// height of 1, it gives the floor ρ/π ∫ Le(x, y) / r⁴ dA, integrated here over the
/// rectangle on a 100 × 100 grid and over each pixel at 2 × 2 points. Over the pixels clear
/// of the rectangle, at 1,024 paths a pixel: the mean within 1% of the integral's, and the
/// relMSE against it (measured 7.2e-4, the noise) under an eighth of the relMSE between the
/// integral and the floor a light of the checkerboard's mean radiance gives (1.2e-2).
/// Mitsuba 3's image of the same floor: relMSE 6.8e-5 against ours, means 0.1% apart.
#[test]
fn a_textured_area_light_emits_its_texture_where_it_is_seen_and_sampled() {
    let direct = checker_emitter(r#"<translate x="0.25" y="-0.25"/>"#, 1.0, "");
    let file = write("texture-emitter", &[("direct.xml", direct.as_bytes())]);
    let scene = Scene::load(&file).expect("loads");
    for film in path_films(&scene, &backends(), (16, 16), 16) {
        for row in 0..16 {
            for col in 0..16 {
                let (x, y) = (
                    -1.0 + (col as f64 + 0.5) / 8.0,
                    1.0 - (row as f64 + 0.5) / 8.0,
                );
                let (lx, ly) = (x - 0.25, y + 0.25);
                let expected = if lx.abs() < 1.0 && ly.abs() < 1.0 {
                    checker_red(lx, ly)
                } else {
                    0.0
                };
                let red = film.pixels[row * 16 + col].x as f64;
                assert!(
                    (red - expected).abs() < 1e-6,
                    "pixel ({col}, {row}): {red}, expected {expected}"
                );
            }
        }
    }

    // The rectangle at z = 1 facing down (its y turned over), the floor its light reaches.
    let floor = checker_emitter(
        r#"<rotate x="1" angle="180"/><translate z="1"/>"#,
        3.0,
        r#"<shape type="rectangle">
        <transform name="to_world"><scale value="3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>"#,
    );
    let file = write("texture-emitter-floor", &[("floor.xml", floor.as_bytes())]);
    let scene = Scene::load(&file).expect("loads");
    let cells = 100;
    let h = 2.0 / cells as f64;
    let irradiance = |px: f64, py: f64, le: &dyn Fn(f64, f64) -> f64| {
        let mut sum = 0.0;
        for i in 0..cells {
            for j in 0..cells {
                let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
                // The rectangle's (x, y) is the world's (x, −y) at height 1.
                let r2 = (x - px).powi(2) + (-y - py).powi(2) + 1.0;
                sum += le(x, y) / (r2 * r2);
            }
        }
        sum * h * h
    };
    let pixel = 6.0 / 16.0;
    let radiance = |col: usize, row: usize, le: &dyn Fn(f64, f64) -> f64| {
        let (x0, y0) = (-3.0 + col as f64 * pixel, 3.0 - row as f64 * pixel);
        let mut sum = 0.0;
        for (a, b) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
            sum += irradiance(x0 + a * pixel, y0 - b * pixel, le);
        }
        0.5 / std::f64::consts::PI * sum / 4.0
    };
    let mean_red = (1.0 + 0.1) / 2.0;
    let clear: Vec<(usize, usize)> = (0..16)
        .flat_map(|row| (0..16).map(move |col| (col, row)))
        .filter(|&(col, row)| {
            let (x0, y0) = (-3.0 + col as f64 * pixel, 3.0 - row as f64 * pixel);
            x0 >= 1.0 || x0 + pixel <= -1.0 || y0 <= -1.0 || y0 - pixel >= 1.0
        })
        .collect();
    let truth: Vec<f64> = clear
        .iter()
        .map(|&(c, r)| radiance(c, r, &checker_red))
        .collect();
    let flat: Vec<f64> = clear
        .iter()
        .map(|&(c, r)| radiance(c, r, &|_, _| mean_red))
        .collect();
    // The squared relative difference from `reference`, averaged over the clear pixels.
    let rel_mse = |image: &[f64], reference: &[f64]| {
        image
            .iter()
            .zip(reference)
            .map(|(a, b)| (a / b - 1.0).powi(2))
            .sum::<f64>()
            / image.len() as f64
    };
    let apart = rel_mse(&flat, &truth);
    for film in path_films(&scene, &backends(), (16, 16), 1024) {
        let ours: Vec<f64> = clear
            .iter()
            .map(|&(c, r)| film.pixels[r * 16 + c].x as f64)
            .collect();
        let (to_truth, to_flat) = (rel_mse(&ours, &truth), rel_mse(&ours, &flat));
        let mean = ours.iter().sum::<f64>() / truth.iter().sum::<f64>();
        assert!(
            (mean - 1.0).abs() < 0.01,
            "the floor's mean: {mean} of the integral's"
        );
        assert!(
            to_truth < apart / 8.0 && to_flat > apart / 2.0,
            "relMSE against the integral {to_truth}, against the flat light's {to_flat}, between them {apart}"
        );
    }
}
