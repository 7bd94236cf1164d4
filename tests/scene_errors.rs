//! Every error class of docs/scene-format.md names the file and the line, and no input —
//! however malformed — panics the parser (a bounded proptest over token soup).

mod common;

use std::path::Path;

use proptest::prelude::*;
use trilux::scene::{Scene, SceneError};

const MATERIAL: &str = "material\ndiffuse 0.5 0.5 0.5\nreflective 0 0 0\nemitted 0 0 0\n";
const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse_dialect(Path::new("bad.obj"), text)
}

/// Asserts the text fails on `line` with a message containing each of `words`.
fn fails_at(text: &str, line: u32, words: &[&str]) {
    let err = parse(text).expect_err("malformed scene must be rejected");
    let message = err.to_string();
    assert_eq!(err.line(), Some(line), "wrong line in: {message}");
    assert!(
        message.starts_with(&format!("bad.obj:{line}:")),
        "no file:line in: {message}"
    );
    for w in words {
        assert!(message.contains(w), "`{w}` missing from: {message}");
    }
}

#[test]
fn unknown_token() {
    fails_at(
        &format!("{MATERIAL}m 0\nbogus 1 2\n"),
        6,
        &["expected a scene token", "`bogus`"],
    );
}

#[test]
fn bad_media() {
    fails_at("medium\nsigma_a 0.1 -0.2 0\n", 2, &["sigma_a must be ≥ 0"]);
    fails_at("medium\nsigma_s 1 1 1\ng 1\n", 3, &["must lie in (−1, 1)"]);
    fails_at(
        "medium\nsigma_s 1 1 1\nfog 1\n",
        3,
        &["fog 1: no such medium", "1 medium block)"],
    );
    // An interior medium needs a refracting boundary and an existing medium.
    fails_at(
        "medium\nsigma_s 1 1 1\nmaterial\ndiffuse 1 1 1\ninterior_medium 0\n",
        5,
        &["interior_medium needs `transmitted`", "index-matched"],
    );
    fails_at(
        "medium\nsigma_s 1 1 1\nmaterial\ndiffuse 0 0 0\ntransmitted 1 1 1\ninterior_medium 2\n",
        6,
        &["interior_medium 2: no such medium", "1 medium block)"],
    );
}

#[test]
fn bad_skies() {
    fails_at(
        "sky_color 1 1 1\nsky_gradient 1 1 1 1 1 1 1 1 1\n",
        2,
        &["a second sky (the first at line 1)"],
    );
    fails_at(
        "sky_color 1 -1 1\n",
        1,
        &["sky_color: radiance must be ≥ 0"],
    );
    fails_at(
        "sky_texture\n",
        1,
        &["expected a file name (sky_texture f)"],
    );
    fails_at(
        "sky_color 1 1 1\nsky_scale -2\n",
        2,
        &["sky_scale must be ≥ 0"],
    );
}

#[test]
fn missing_argument() {
    fails_at(
        "material\ndiffuse 0.5 0.5\n",
        2,
        &["expected a real number", "the end of the file"],
    );
}

#[test]
fn non_numeric_argument() {
    fails_at(
        &format!("{MATERIAL}v 1 two 3\n"),
        5,
        &["expected a real number", "`two`"],
    );
    fails_at(
        &format!("{MATERIAL}v 1 nan 3\n"),
        5,
        &["expected a real number", "`nan`"],
    );
}

#[test]
fn face_index_out_of_range() {
    fails_at(
        &format!("{MATERIAL}m 0\n{QUAD}f 1 2 3 9\n"),
        10,
        &["face index 9 out of range", "4 vertices"],
    );
    fails_at(
        &format!("{MATERIAL}m 0\n{QUAD}f 0 1 2 3\n"),
        10,
        &["face index 0 out of range"],
    );
}

#[test]
fn selecting_a_missing_material() {
    fails_at(
        &format!("{MATERIAL}m 3\n{QUAD}f 1 2 3 4\n"),
        5,
        &["m 3: no such material", "1 defined"],
    );
}

#[test]
fn face_before_any_material() {
    fails_at(
        &format!("{MATERIAL}{QUAD}f 1 2 3 4\n"),
        9,
        &["`f` before any `m`"],
    );
}

#[test]
fn non_planar_quad() {
    fails_at(
        &format!("{MATERIAL}m 0\nv 0 0 0\nv 1 0 0\nv 1 1 0.5\nv 0 1 0\nf 1 2 3 4\n"),
        10,
        &["non-planar quad"],
    );
}

#[test]
fn degenerate_quad() {
    fails_at(
        &format!("{MATERIAL}m 0\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n"),
        10,
        &["degenerate quad"],
    );
}

#[test]
fn nearly_degenerate_quad_is_loaded() {
    let scene = parse(&format!(
        "{MATERIAL}m 0\nv 0 0 0\nv 1 0 0\nv 1 1e-5 0\nv 0 1e-5 0\nf 1 2 3 4\n"
    ))
    .expect("a thin quad is valid");
    assert_eq!(scene.quads.len(), 1);
}

#[test]
fn negative_radius() {
    fails_at(
        &format!("{MATERIAL}m 0\ns 0 0 0 -1\n"),
        6,
        &["sphere radius must be > 0"],
    );
}

#[test]
fn ring_radii_out_of_order() {
    fails_at(
        &format!("{MATERIAL}m 0\nr 0 0 0 2 4 4\n"),
        6,
        &["0 < r_in < r_out"],
    );
    fails_at(
        &format!("{MATERIAL}m 0\nr 0 0 0 2 5 4\n"),
        6,
        &["0 < r_in < r_out"],
    );
    fails_at(
        &format!("{MATERIAL}m 0\nr 0 0 0 0 1 2\n"),
        6,
        &["ring height must be > 0"],
    );
}

#[test]
fn unreadable_texture() {
    let dir = std::env::temp_dir().join(format!("trilux-texture-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("scene.obj");
    // The scene `text` fails to load at `line`, saying `why`.
    let fails_to_load = |text: String, line: u32, why: &str| {
        std::fs::write(&path, text).expect("write");
        let err = Scene::load(&path).expect_err("an unreadable image must be rejected");
        assert_eq!(err.line(), Some(line), "{err}");
        assert!(err.to_string().contains(why), "{err}");
    };
    fails_to_load(
        format!("\n\nmaterial\ntexture_file missing.ppm\n\nm 0\n{QUAD}f 1 2 3 4\n"),
        3,
        "cannot read texture",
    );
    // A height image and a sky map likewise, at the material's and the key's line.
    fails_to_load(
        format!("\nmaterial\ndiffuse 1 1 1\nbump_file missing.png\nm 0\n{QUAD}f 1 2 3 4\n"),
        2,
        "cannot read bump_file",
    );
    fails_to_load(
        format!("{MATERIAL}m 0\n{QUAD}f 1 2 3 4\n\nsky_texture missing.exr\n"),
        12,
        "cannot read sky_texture",
    );
    // A texture no primitive uses is not decoded, so it cannot fail the load.
    std::fs::write(
        &path,
        format!(
            "material\ndiffuse 1 1 1\nmaterial\ntexture_file missing.ppm\nm 0\n{QUAD}f 1 2 3 4\n"
        ),
    )
    .expect("write");
    let scene = Scene::load(&path).expect("unused texture is not read");
    assert!(scene.textures.is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unreadable_file() {
    let err = Scene::load(Path::new("/nonexistent/scene.obj")).expect_err("missing file");
    assert!(err.to_string().contains("/nonexistent/scene.obj"), "{err}");
}

#[test]
fn energy_violation_is_a_warning_naming_the_material() {
    let dir = std::env::temp_dir().join(format!("trilux-energy-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("scene.obj");
    std::fs::write(
        &path,
        format!(
            "{MATERIAL}material\ndiffuse 0.8 0.8 0.8\nreflective 0.5 0 0\nm 1\n{QUAD}f 1 2 3 4\n"
        ),
    )
    .expect("write");
    let scene = Scene::load(&path).expect("loads with a warning");
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains(":5: material 1"),
        "{}",
        scene.warnings[0]
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn every_course_scene_loads() {
    for path in common::own_scenes() {
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.primitive_count() > 0, "{}", path.display());
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }
}

#[test]
fn standard_obj_is_read_by_content() {
    let dir = std::env::temp_dir().join(format!("trilux-obj-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("mesh.txt");
    std::fs::write(
        dir.join("mesh.mtl"),
        "newmtl lamp\nKd 0.2 0.3 0.4\nKe 5 5 5\n",
    )
    .expect("write mtl");
    std::fs::write(
        &path,
        "mtllib mesh.mtl\ns off\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl lamp\nf 1 2 3 4\n",
    )
    .expect("write");
    let scene = Scene::load(&path).expect("standard OBJ loads");
    assert_eq!(scene.triangles.len(), 2, "the polygon is triangulated");
    let m = &scene.materials[scene.triangles.materials[0] as usize];
    assert_eq!(m.emitted.x, 5.0);
    assert_eq!(m.diffuse.z, 0.4);
    std::fs::remove_dir_all(&dir).ok();
}

fn token() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("material".to_string()),
        Just("diffuse".to_string()),
        Just("reflective".to_string()),
        Just("emitted".to_string()),
        Just("transmitted".to_string()),
        Just("ior".to_string()),
        Just("roughness".to_string()),
        Just("texture_file".to_string()),
        Just("m".to_string()),
        Just("v".to_string()),
        Just("vt".to_string()),
        Just("f".to_string()),
        Just("s".to_string()),
        Just("r".to_string()),
        Just("background_color".to_string()),
        Just("PerspectiveCamera".to_string()),
        Just("OrthographicCamera".to_string()),
        Just("{".to_string()),
        Just("}".to_string()),
        Just("camera_position".to_string()),
        Just("angle".to_string()),
        Just("#".to_string()),
        Just("\n".to_string()),
        (-5i64..20).prop_map(|k| k.to_string()),
        any::<f32>().prop_map(|x| x.to_string()),
        "[ -~]{0,6}",
        "\\PC{0,3}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    /// Any token soup parses or fails with an error that names a line; it never panics.
    #[test]
    fn parser_never_panics(tokens in proptest::collection::vec(token(), 0..60)) {
        let text = tokens.join(" ");
        if let Err(e) = parse(&text) {
            prop_assert!(e.to_string().starts_with("bad.obj"));
        }
    }

    /// Mutating a valid course file byte by byte never panics the parser.
    #[test]
    fn mutated_course_text_never_panics(pos in 0usize..400, byte in any::<u8>()) {
        let mut text = format!("{MATERIAL}m 0\n{QUAD}f 1 2 3 4\ns 0 0 1 0.5\nr 0 0 0 1 0.5 0.6\nPerspectiveCamera {{\ncamera_position 0 0 5\npoint_of_interest 0 0 0\nup 0 1 0\nangle 0.5\n}}\n").into_bytes();
        let k = pos % text.len();
        text[k] = byte;
        let _ = parse(&String::from_utf8_lossy(&text));
    }
}

#[test]
fn reflectance_outside_zero_one_is_clamped_with_a_warning() {
    let dir = std::env::temp_dir().join(format!("trilux-clamp-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("scene.obj");
    std::fs::write(
        &path,
        format!("material\ndiffuse 1.5 0.5 -0.2\nm 0\n{QUAD}f 1 2 3 4\n"),
    )
    .expect("write");
    let scene = Scene::load(&path).expect("loads with a warning");
    let d = scene.materials[0].diffuse;
    assert_eq!((d.x, d.y, d.z), (1.0, 0.5, 0.0));
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains(":1: material 0: diffuse") && w.contains("clamped")),
        "{:?}",
        scene.warnings
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Procedural textures and bump maps: unknown patterns, keys without the key they modify,
/// and two sources of one thing are refused at the key's line.
#[test]
fn bad_procedural_textures_and_bumps() {
    fails_at(
        "material\ntexture_procedural plaid\n",
        2,
        &[
            "expected a pattern",
            "wood | marble | noise | crackle | checker",
            "`plaid`",
        ],
    );
    fails_at(
        "material\ndiffuse 1 1 1\nbump_procedural checker\n",
        3,
        &["expected a pattern", "noise | crackle | wood", "`checker`"],
    );
    fails_at(
        "material\ndiffuse 1 1 1\ntexture_scale 2\n",
        3,
        &["texture_scale needs texture_procedural"],
    );
    fails_at(
        "material\ntexture_procedural wood\ntexture_scale 0\n",
        3,
        &["texture_scale must be > 0"],
    );
    fails_at(
        "material\ntexture_procedural wood\ntexture_colors 1 1 1 0 2 0\n",
        3,
        &["texture_colors are albedos", "[0, 1]"],
    );
    fails_at(
        "material\ntexture_file a.ppm\ntexture_procedural wood\n",
        3,
        &["texture_procedural or texture_file, not both"],
    );
    fails_at(
        "material\ndiffuse 1 1 1\nbump_procedural noise\nbump_file h.png\n",
        4,
        &["bump_procedural or bump_file, not both"],
    );
    fails_at(
        "material\ndiffuse 1 1 1\nbump_file h.png\nbump_scale 2\n",
        4,
        &["bump_scale needs bump_procedural"],
    );
    fails_at(
        "material\ndiffuse 1 1 1\nbump_amplitude 0.1\n",
        3,
        &["bump_amplitude needs bump_procedural or bump_file"],
    );
    // A procedural texture is the material's albedo: no `diffuse` needed.
    let scene = parse(&format!(
        "material\ntexture_procedural checker\nbump_procedural wood\nm 0\n{QUAD}f 1 2 3 4\n"
    ))
    .expect("parses");
    assert!(scene.materials[0].procedural.is_some() && scene.materials[0].bump.is_some());
}

/// Runs the built `render` with `args`, in `dir`.
fn run_render(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_render"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("render runs")
}

/// A scene with nothing that emits and no sky (a component file, such as the hospital's desk):
/// every engine writes a black image (the ray tracer's ambient term set to 0), says so in one
/// warning and exits 0. SPPM picked its photons' light from the empty list of lights and
/// panicked.
#[test]
fn scene_without_light_renders_black_with_one_warning() {
    let dir = common::temp_dir("no-light");
    std::fs::write(
        dir.join("dark.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
    )
    .expect("scene written");
    for engine in ["raytrace", "path", "radiosity", "photon", "sppm"] {
        let image = format!("dark-{engine}.pfm");
        let mut args = vec![
            "--input", "dark.obj", "--engine", engine, "--size", "8", "8", "--quiet", "-o", &image,
        ];
        if engine == "raytrace" {
            args.extend(["--ambient-light", "0", "0", "0"]);
        }
        let out = run_render(&dir, &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{engine}: {stderr}");
        let warnings: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("warning:"))
            .collect();
        assert_eq!(warnings.len(), 1, "{engine}: one warning in: {stderr}");
        assert!(warnings[0].contains("emits light"), "{engine}: {stderr}");
        let film = trilux::film::read_pfm(&dir.join(&image)).expect("image read");
        assert!(
            film.pixels.iter().all(|p| *p == trilux::scene::Color::ZERO),
            "{engine}: the image is not black"
        );
    }
}

/// A scene lit only by a light without area (a Mitsuba point light) is lit: the path tracer
/// renders it with no warning that nothing emits, and the floor under the light is not black.
#[test]
fn a_scene_lit_by_a_point_light_alone_is_not_called_dark() {
    let dir = common::temp_dir("point-light-only");
    std::fs::write(
        dir.join("point.xml"),
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    </sensor>
    <emitter type="point"><point name="position" x="0" y="0" z="2"/></emitter>
    <shape type="rectangle"/>
</scene>"#,
    )
    .expect("scene written");
    let args = [
        "--input",
        "point.xml",
        "--engine",
        "path",
        "--size",
        "8",
        "8",
        "--quiet",
        "-o",
        "p.pfm",
    ];
    let out = run_render(&dir, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("emits light"), "{stderr}");
    let film = trilux::film::read_pfm(&dir.join("p.pfm")).expect("image read");
    assert!(
        film.pixels.iter().any(|p| p.x > 0.0),
        "the lit rectangle is black"
    );
}

const CAMERA: &str =
    "PerspectiveCamera {\ncamera_position 0 0 5\npoint_of_interest 0 0 0\nup 0 1 0\nangle 0.5\n}\n";

/// A value outside the range of scene values (finite, within ±1e8) in a vertex, a sphere's
/// centre or radius, a camera's position or point of interest is refused at its line, the
/// range named: such values made rays of inf and NaN, which Embree aborts on and the BVH
/// followed without end.
#[test]
fn coordinates_out_of_range_are_refused_at_their_line() {
    for huge in ["1e38", "18446744073709551616", "inf", "-1e9"] {
        fails_at(
            &format!("{MATERIAL}m 0\nv 0 0 0\nv {huge} 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"),
            7,
            &[&format!("`{huge}` is out of range"), "±1e8"],
        );
        fails_at(
            &format!("{MATERIAL}m 0\ns 0 0 {huge} 1\n"),
            6,
            &["out of range", "±1e8"],
        );
        fails_at(
            &format!("{MATERIAL}m 0\ns 0 0 0 {huge}\n"),
            6,
            &["out of range", "±1e8"],
        );
        for (line, key) in [
            (12, "camera_position 0 0 5"),
            (13, "point_of_interest 0 0 0"),
        ] {
            let camera = CAMERA.replace(key, &format!("{} {huge}", &key[..key.len() - 2]));
            fails_at(
                &format!("{MATERIAL}m 0\n{QUAD}f 1 2 3 4\n{camera}"),
                line,
                &["out of range"],
            );
        }
    }
    // The stiff cases of the stability tests stay inside the range.
    let stiff = format!(
        "{MATERIAL}m 0\nv 10000 0 0\nv 10001 0 0\nv 10001 1 0\nv 10000 1 0\nf 1 2 3 4\n\
         v 0 0 0\nv 1e-4 0 0\nv 1e-4 1e-4 0\nv 0 1e-4 0\nf 5 6 7 8\ns 1e4 1e4 1e4 1e-4\n"
    );
    if let Err(e) = parse(&stiff) {
        panic!("the stiff cases are refused: {e}");
    }
}

/// The scene `text` written to `name` in a fresh folder, loaded.
fn load_text(name: &str, text: &str) -> Result<Scene, SceneError> {
    let dir = common::temp_dir(&format!("range-{}", name.replace('.', "-")));
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    Scene::load(&path)
}

/// Asserts `text`, written to `name`, fails to load at `line` with each of `words`.
fn file_fails_at(name: &str, text: &str, line: u32, words: &[&str]) {
    let err = load_text(name, text).expect_err("refused");
    let message = err.to_string();
    assert_eq!(err.line(), Some(line), "wrong line in: {message}");
    assert!(
        message.contains(&format!("{name}:{line}:")),
        "no file:line in: {message}"
    );
    for w in words {
        assert!(message.contains(w), "`{w}` missing from: {message}");
    }
}

/// A standard OBJ vertex of `nan`, `inf` or 1e38 is refused at its line (tobj reads them as
/// numbers), as the course dialect and MGF refuse them.
#[test]
fn obj_vertex_out_of_range_is_refused_at_its_line() {
    for bad in ["nan", "inf", "1e38", "18446744073709551616"] {
        file_fails_at(
            "mesh.obj",
            &format!("# a triangle\nv 0 0 0\nv {bad} 0 0\nv 0 1 0\nf 1 2 3\n"),
            3,
            &[&format!("`{bad}` is out of range"), "±1e8"],
        );
    }
    file_fails_at(
        "normals.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 nan\nf 1//1 2//1 3//1\n",
        4,
        &["`nan` is out of range"],
    );
}

/// An MGF sphere of radius 1e38 is refused at its line (it was reported as a scene with no
/// geometry); so is an `xf -t` of 1e38, and a vertex that a transform takes out of the range.
#[test]
fn mgf_values_out_of_range_are_refused_at_their_line() {
    let head = "v c =\n\tp 0 0 0\nm m =\n\tc\n\trd .5\n";
    file_fails_at(
        "sphere.mgf",
        &format!("{head}sph c 1e38\n"),
        6,
        &["`1e38` is out of range", "±1e8"],
    );
    file_fails_at(
        "move.mgf",
        &format!("{head}xf -t 0 0 1e38\nsph c 1\nxf\n"),
        6,
        &["`1e38` is out of range"],
    );
    file_fails_at(
        "scaled.mgf",
        &format!("{head}xf -s 1e7\nsph c 100\nxf\n"),
        7,
        &["transformed", "is out of range", "±1e8"],
    );
}

/// A ray of inf or NaN misses in both Accels (in release builds; debug builds assert that none
/// arrives), single and batched, and the BVH's walk ends: such a ray's slab test entered the
/// empty child slots, whose index is the root's, and the walk grew its stack without end
/// (12 GiB allocations), where Embree aborted the process.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "debug builds assert that no such ray arrives"
)]
fn non_finite_rays_miss_in_both_accels() {
    use trilux::accel::{self, AccelOptions};
    use trilux::geometry::{vec3, Ray};
    let scene = common::own_scene("cornell_box_diffuse_sphere.obj");
    let centre = scene.bounds().centre();
    let (inf, nan) = (f32::INFINITY, f32::NAN);
    let rays = [
        Ray::new(vec3(0.0, 0.0, inf), vec3(0.0, 0.0, -1.0)),
        Ray::new(vec3(nan, 0.0, 0.0), vec3(0.0, 0.0, -1.0)),
        Ray::new(centre, vec3(nan, nan, nan)),
        Ray::new(centre, vec3(0.0, -inf, 0.0)),
        Ray::with_range(centre, vec3(0.0, -1.0, 0.0), 0.0, nan),
    ];
    for kind in common::backends() {
        let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
        for ray in &rays {
            assert!(accel.intersect(ray).is_none(), "{kind}: {ray:?} hit");
            assert!(!accel.occluded(ray), "{kind}: {ray:?} occluded");
        }
        let mut hits = vec![None; rays.len()];
        accel.intersect_batch(&rays, &mut hits);
        assert!(
            hits.iter().all(Option::is_none),
            "{kind}: a batched ray hit"
        );
        // A finite ray among them is still answered.
        let mut mixed = rays.to_vec();
        mixed.push(Ray::new(centre, vec3(0.0, -1.0, 0.0)));
        let mut occluded = vec![false; mixed.len()];
        accel.occluded_batch(&mixed, &mut occluded);
        assert!(
            occluded.last() == Some(&true),
            "{kind}: the floor is not below the centre"
        );
    }
}
