//! The reference inputs beside the checkout, in `../shared/`: the course's scenes,
//! RenderPark's MGF scenes and Mitsuba 3's render-test scenes with its reference images. Every other test reads the project's own `scenes/` (or builds its
//! scene in code); these check that the course's files are what `scenes/` copies, that the
//! course's command lines run on them verbatim, and the measured figures of the MGF scenes
//! the project does not ship.
//!
//! A trial whose input is missing is reported as ignored, by name, with the path it looked
//! for: a user's clone has no `../shared/`. Where the inputs must be present (CI sets
//! `TRILUX_REQUIRE_SHARED=1`), a missing input fails the trial instead.

mod common;
// Beside this file rather than in `tests/`, where Cargo would build each as a test of its own.
#[path = "shared_inputs/json.rs"]
mod json;
#[path = "shared_inputs/mitsuba_loader.rs"]
mod mitsuba_loader;

use std::path::{Path, PathBuf};

use common::references::{
    hierarchical, path_traced_patches, per_input_patch_difference, per_input_patch_difference_over,
    seen_by_the_reference, solve,
};
use libtest_mimic::{Arguments, Failed, Trial};
use trilux::engines::radiosity::Solution;
use trilux::film::Film;
use trilux::scene::Scene;

fn main() {
    let args = Arguments::from_args();
    let trials = vec![
        shared_input_trial(
            "course_scenes_match_ours_and_run_verbatim",
            "course-scenes",
            course_compatibility,
        ),
        shared_input_trial(
            "shipped_mgf_scenes_load_with_renderparks_patch_counts",
            "mgf-scenes",
            shipped_mgf_scenes_load_with_renderparks_patch_counts,
        ),
        shared_input_trial(
            "mitsuba_render_tests_against_mitsubas_references",
            "mitsuba-tests/tests/scenes",
            mitsuba_render_tests_against_mitsubas_references,
        ),
        shared_input_trial(
            "mitsuba_z_test_fails_on_a_ggx_roughness_off_by_5_percent",
            GGX_SCENE,
            mitsuba_z_test_fails_on_a_ggx_roughness_off_by_5_percent,
        ),
        mitsuba_loader_trial(),
        shared_input_trial(
            "office3_against_path_traced_references",
            "mgf-scenes/office3/office.mgf",
            office3_against_path_traced_references,
        ),
    ];
    libtest_mimic::run(&args, trials).exit();
}

/// A trial that runs `body` on `../shared/<input>`: ignored, saying why, when that is missing
/// (failed instead when `TRILUX_REQUIRE_SHARED` is set).
fn shared_input_trial(name: &'static str, input: &str, body: fn(&Path)) -> Trial {
    let path = shared(input);
    let missing = (!path.exists()).then(|| not_found(&path));
    trial_needing(name, missing, &["TRILUX_REQUIRE_SHARED"], move || {
        body(&path)
    })
}

/// Our Mitsuba reader against Mitsuba's own loader (`mitsuba_loader.rs`): ignored, saying
/// why, without `../shared/mitsuba-tests` or without Mitsuba in `python3` (failed instead
/// when `TRILUX_REQUIRE_MITSUBA` is set, or `TRILUX_REQUIRE_SHARED` for the scenes).
fn mitsuba_loader_trial() -> Trial {
    let name = "mitsuba_reader_against_mitsubas_loader";
    let dir = shared("mitsuba-tests/tests/scenes");
    let mut required = vec!["TRILUX_REQUIRE_MITSUBA"];
    let missing = if !dir.exists() {
        required.push("TRILUX_REQUIRE_SHARED");
        Some(not_found(&dir))
    } else {
        let import = std::process::Command::new("python3")
            .args(["-c", "import mitsuba"])
            .output();
        match import {
            Ok(out) if out.status.success() => None,
            _ => Some("python3 cannot import mitsuba (pip install mitsuba)".to_string()),
        }
    };
    trial_needing(name, missing, &required, move || {
        mitsuba_loader::our_reader_against_mitsubas_loader(&dir)
    })
}

fn not_found(path: &Path) -> String {
    format!(
        "{} not found (reference inputs beside the checkout)",
        path.display()
    )
}

fn shared(input: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared")
        .join(input)
}

/// A trial that runs `body`, unless what it needs is `missing`: then it is ignored, saying
/// why, or failed when one of the `required` variables is set (CI sets them).
fn trial_needing(
    name: &'static str,
    missing: Option<String>,
    required: &[&str],
    body: impl FnOnce() + Send + 'static,
) -> Trial {
    let required = required.iter().any(|v| std::env::var_os(v).is_some());
    if let (Some(why), false) = (&missing, required) {
        eprintln!("{name}: skipped: {why}");
    }
    let ignored = missing.is_some() && !required;
    Trial::test(name, move || {
        if let Some(why) = missing {
            return Err(Failed::from(format!(
                "{why} (a TRILUX_REQUIRE_ variable is set, or the trial was run with --ignored)"
            )));
        }
        body();
        Ok(())
    })
    .with_ignored_flag(ignored)
}

/// The course's command lines, one or more per engine and every course scene (the photon
/// lines at 48×48, as the course's own images would take minutes each).
const COURSE_LINES: [&str; 8] = [
    "-input reflective_spheres.obj -num_bounces 3 -num_shadow_samples 1",
    "-input textured_plane_reflective_sphere.obj -num_bounces 1 -num_shadow_samples 4",
    "-input cornell_box_diffuse_sphere.obj -ambient_light 0.2 0.2 0.2 -num_shadow_samples 10",
    "-input cornell_box.obj",
    "-size 300 150 -input l.obj -num_form_factor_samples 10 -num_shadow_samples 1",
    "-input cornell_box_diffuse_sphere.obj -sphere_rasterization 16 12 -num_shadow_samples 1",
    "-input reflective_ring.obj -num_photons_to_shoot 10000 -num_bounces 2 -num_shadow_samples 10 -size 48 48",
    "-input cornell_box_reflective_sphere.obj -num_photons_to_shoot 500000 -num_shadow_samples 500 -num_photons_to_collect 500 -num_bounces 1 -size 48 48",
];

/// The course's scenes are the ones `scenes/` holds (`own_scenes_match_the_course_scenes`),
/// and each course command line runs verbatim on the course's file and writes the very bytes
/// it writes from ours — but for the two scenes with textures, whose images are our own.
fn course_compatibility(course: &Path) {
    own_scenes_match_the_course_scenes(course);
    let out = common::temp_dir("course-compat");
    for line in COURSE_LINES {
        let images: Vec<Vec<u8>> = [course.to_path_buf(), common::own_scene_dir()]
            .iter()
            .enumerate()
            .map(|(k, dir)| {
                let cwd = out.join(k.to_string());
                std::fs::create_dir_all(&cwd).expect("temp dir");
                let run = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
                    .args(common::scene_args(dir, line))
                    .arg("--quiet")
                    .current_dir(&cwd)
                    .output()
                    .expect("render runs");
                assert!(
                    run.status.success(),
                    "`{line}` in {}: {}",
                    dir.display(),
                    String::from_utf8_lossy(&run.stderr)
                );
                let stem = line.split(' ').find(|a| a.ends_with(".obj")).unwrap();
                std::fs::read(cwd.join(stem.replace(".obj", ".png"))).expect("<stem>.png written")
            })
            .collect();
        if !line.contains("textured_plane") && !line.contains("reflective_ring") {
            assert!(
                images[0] == images[1],
                "`{line}`: the course's file and ours give different images"
            );
        }
    }
    std::fs::remove_dir_all(&out).ok();
}

/// trilux's own versions of the course scenes (in `scenes/`) have the course's geometry,
/// materials, camera and background; only the texture images are our own.
fn own_scenes_match_the_course_scenes(course: &Path) {
    let theirs = common::obj_files(course);
    assert!(theirs.len() >= 7, "the course has its seven scenes");
    for theirs_path in theirs {
        let path = common::own_scene_dir().join(theirs_path.file_name().unwrap());
        assert!(
            path.is_file(),
            "{}: scenes/ has no version",
            theirs_path.display()
        );
        let ours = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let theirs = Scene::load(&theirs_path).unwrap_or_else(|e| panic!("{e}"));
        let what = path.display();
        assert_eq!(ours.quads, theirs.quads, "{what}: quads");
        assert_eq!(ours.shapes, theirs.shapes, "{what}: spheres and rings");
        assert_eq!(ours.camera, theirs.camera, "{what}: camera");
        assert_eq!(ours.background, theirs.background, "{what}: background");
        assert_eq!(
            ours.materials.len(),
            theirs.materials.len(),
            "{what}: materials"
        );
        for (a, b) in ours.materials.iter().zip(&theirs.materials) {
            assert_eq!(
                (a.diffuse, a.reflective, a.emitted),
                (b.diffuse, b.reflective, b.emitted),
                "{what}"
            );
            assert_eq!(a.texture_file, b.texture_file, "{what}: texture name");
        }
    }
}

/// The shipped MGF scenes: every entry file loads, and the patch counts mgf.md gives.
fn shipped_mgf_scenes_load_with_renderparks_patch_counts(dir: &Path) {
    let patches = |file: &str| -> usize {
        let scene = Scene::load(&dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        scene.quads.len() + scene.triangles.len()
    };
    for file in [
        "corridor.mgf",
        "hospital/main.mgf",
        "office2/office2.mgf",
        "office3/office.mgf",
        "salon/classroom.mgf",
        "soda.mgf",
        "floor_gloss.mgf",
        "examp1.mgf",
    ] {
        assert!(patches(file) > 0, "{file}");
    }
    assert_eq!(patches("cube.mgf"), 66);
    // RenderPark: 24,982 for the hospital, 13,948 for graz (one-sided). Graz matches exactly;
    // the hospital gives 25,099, 117 more (+0.47%, not yet traced to a cause; 25,083 before
    // polygons whose holes are joined by seams were triangulated round the holes), so its
    // bound is 1%, twice that.
    let hospital = patches("hospital/hosp.mgf") as f64;
    assert!(
        (hospital / 24_982.0 - 1.0).abs() < 0.01,
        "hospital: {hospital}"
    );
    let graz = patches("office1/graz.mgf") as f64;
    assert_eq!(graz, 13_948.0, "graz");
    // What `--plan` prints as the radiosity mesh's patches; `--two-sided` gives each face a
    // back (RenderPark: 27,896 for graz two-sided).
    let planned = |file: &str, flags: &[&str]| -> f64 {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
            .arg("--input")
            .arg(dir.join(file))
            .args(["--engine", "radiosity", "--plan"])
            .args(flags)
            .output()
            .expect("render runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let line = stdout
            .lines()
            .find_map(|l| l.strip_prefix("radiosity mesh: yes ("))
            .unwrap_or_else(|| panic!("{file} {flags:?}: no mesh line in\n{stdout}"));
        line.split(' ').next().unwrap().parse().unwrap()
    };
    assert_eq!(planned("cube.mgf", &[]), 66.0);
    let hospital = planned("hospital/hosp.mgf", &[]);
    assert!(
        (hospital / 24_982.0 - 1.0).abs() < 0.01,
        "plan, hospital: {hospital}"
    );
    assert_eq!(planned("office1/graz.mgf", &[]), graz);
    let two_sided = planned("office1/graz.mgf", &["--two-sided"]);
    assert_eq!(two_sided, 27_896.0, "plan, graz two-sided");
}

/// office3 (RenderPark's office: 12,629 input patches, one 21 m² floor), hierarchical,
/// against the path tracer averaged per input patch: 16 M paths (`reference_paths`), traced
/// twice with different seeds, so that the L1 between the two traces — the reference's own
/// noise — is measured beside the solver's.
fn office3_against_path_traced_references(path: &Path) {
    let scene = Scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut settings = hierarchical(0);
    settings.radiosity.tolerance = 1e-4;
    settings.num_shadow_samples = 1;
    let solution = solve(&scene, &settings);
    let total_area: f64 = solution.patches.iter().map(|p| p.area as f64).sum();
    let paths = reference_paths(&solution, 16e6);
    let mut traced = solution.clone();
    traced.state.radiance = path_traced_patches(&scene, &solution, &paths, 7);
    let mut again = solution.clone();
    again.state.radiance = path_traced_patches(&scene, &solution, &paths, 8);
    let (l1, power_error) = per_input_patch_difference(&traced, &solution);
    let (noise, noise_power) = per_input_patch_difference(&traced, &again);
    let seen = seen_by_the_reference(&scene, &solution, &paths);
    let unseen_area: f64 = (solution.patches.iter().zip(&seen))
        .filter(|(_, &seen)| !seen)
        .map(|(p, _)| p.area as f64)
        .sum();
    let (l1_seen, _) = per_input_patch_difference_over(&traced, &solution, &seen);
    println!(
        "office3: {}; the two traces apart by L1 {:.2}% and power {:+.2}%; the solution \
         against the first: relative L1 {:.2}%, reflected power {:+.2}%; over the patches the \
         reference sees ({} of {} unseen, {:.2} m² of {:.1}), L1 {:.2}%",
        solution.solver_report,
        100.0 * noise,
        100.0 * noise_power,
        100.0 * l1,
        100.0 * power_error,
        seen.iter().filter(|&&s| !s).count(),
        seen.len(),
        unseen_area,
        total_area,
        100.0 * l1_seen
    );
    // Measured against the diffuse-only trace (`diffuse_only`): the traces 0.83% apart, the
    // solution L1 1.90%, power -0.65%; over the patches seen 1.86%. 2.07% / -0.82% (2.03%
    // seen) while every leaf's links were taken at its centre, and each link's visibility
    // multiplied its mean form factor rather than each point's (`update_leaf_scales`,
    // `Hierarchical::links`): the desk lamp's shade, whose tube above the bulb is lit
    // through its lower end, got 0.45 of the light the trace finds there, now 0.68. 2.27%
    // (2.23% seen) while a leaf kept all the light the clusters above it handed down,
    // however much of its hemisphere its element links covered (`share_of_clusters`).
    // Before MGF polygons with a seam to a hole were triangulated round the hole, office3's
    // window wall was a fan of 20.9 m² folded over itself and over the window, where its
    // doubled light lit the room (walls +3.7%): 5.94% / +0.24% (4.55% seen), its traces
    // shared by area alone 1.71% apart. Before clusters holding an emitter were split as
    // sources and clusters sent the light of the patches facing the receiver
    // (`holds_emitter`, `sent`): 8.95% / +3.7%. Of what is left, 0.44 points are the lamp's
    // shade (0.29 its tube), 0.38 the walls, 0.19 the ceiling (BENCHMARKS.md). The L1
    // bounds are the measured figures and about a tenth, within 2%; the power bound is 1%.
    assert!(noise < 0.012, "the references disagree: L1 {noise}");
    assert!(power_error.abs() < 0.01, "reflected power {power_error}");
    assert!(l1 < 0.02, "relative L1 {l1}");
    assert!(
        l1_seen < 0.02,
        "relative L1 over the patches seen {l1_seen}"
    );
}

/// How many of `total` paths the reference traces to each patch of `solution`, at least 16:
/// half shared by area, half by the solution's reflected power. The L1 weighs each patch by
/// its area times its radiance, so a bright patch's noise counts for more: by area alone,
/// office3's lamp shades (0.04 m², a hundred times the walls' radiance) got 64 paths a patch,
/// and the two traces came 1.79% apart, half of that on the shades.
fn reference_paths(solution: &Solution, total: f64) -> Vec<u32> {
    let (area, reflected): (Vec<f64>, Vec<f64>) = (solution.patches.iter())
        .zip(&solution.state.radiance)
        .map(|(p, b)| {
            let a = p.area as f64;
            (a, a * (*b - p.emitted).element_sum().max(0.0) as f64)
        })
        .unzip();
    let (area_sum, power): (f64, f64) = (area.iter().sum(), reflected.iter().sum());
    area.iter()
        .zip(&reflected)
        .map(|(a, r)| ((total * (0.5 * a / area_sum + 0.5 * r / power)) as u32).max(16))
        .collect()
}

/// Mitsuba 3's render tests that our path tracer passes today: each must keep passing.
const MITSUBA_TESTS_PASSING: [&str; 23] = [
    "test_arealight_path",
    "test_bumpmap_path",
    "test_constant_path",
    "test_envmap_path",
    "test_normalmap_identity_roughconductor_path",
    "test_normalmap_path",
    "test_normalmap_roughconductor_path",
    "test_roughdielectric_path",
    "test_roughplastic_linear_path",
    "test_roughplastic_nonlinear_path",
    "test_textured_diffuse_path",
    "test_textured_roughconductor_path",
    "test_texturedprincipled1_path",
    "test_texturedprincipled2_path",
    "test_texturedprincipledthin_path",
    "test_hetero_sigmat_albedo_volpath",
    "test_hetero_sigmat_volpath",
    "test_homo_area_light_volpath",
    "test_homo_dielectric_envmap_volpath",
    "test_homo_emitter_inside_medium_volpath",
    "test_homo_null_envmap_volpath",
    "test_homo_roughdielectric_spot_volpath",
    "test_surf_area_light_volpath",
];

/// Samples per pixel of the relMSE comparison (the acceptance figure's).
const MITSUBA_TEST_SPP: u32 = 256;

/// Samples per pixel of the z-test's render of each scene: as many as the relMSE comparison
/// takes (Mitsuba's own test takes 2,000,000 over the image's pixels, 868 at 48×48).
const Z_TEST_SPP: u32 = 256;

/// The scenes of `MITSUBA_TESTS_PASSING` that our path tracer does not yet pass the z-test of
/// at `Z_TEST_SPP`; every other one must pass it.
const MITSUBA_Z_TESTS_NOT_YET: [&str; 4] = [
    "test_roughdielectric_path",
    "test_homo_area_light_volpath",
    "test_homo_dielectric_envmap_volpath",
    "test_homo_roughdielectric_spot_volpath",
];

/// Mitsuba renders its references at this many samples per pixel (`test_renders.py` run as a
/// script, `--spp` 32000), and their variance images are of one sample (the `moment`
/// integrator's E[x²] − E[x]²): the reference's mean has that variance over 32000.
const MITSUBA_REFERENCE_SPP: f64 = 32000.0;

/// The floor of a per-sample variance (`test_renders.py`'s `max(var, 1e-4)`): where every
/// sample agrees (a constant background), the images are not judged on rounding.
const Z_TEST_VARIANCE_FLOOR: f64 = 1e-4;

/// The chance that the whole image fails although both estimators agree, before Šidák's
/// correction spreads it over the pixels, and the share of pixel channels that must pass:
/// Mitsuba's.
const Z_TEST_SIGNIFICANCE: f64 = 0.01;
const Z_TEST_PASSING_SHARE: f64 = 0.9975;

/// Mitsuba's GGX test scene, whose roughness the z-test must see off by 5%: an anisotropic
/// GGX conductor (αu 0.25, αv 0.05) under an area light, a point light and an environment.
const GGX_SCENE: &str =
    "mitsuba-tests/tests/scenes/bsdf_spheres/test_normalmap_identity_roughconductor_path.xml";

/// Samples per pixel of the GGX trial's renders: Mitsuba's own budget, 2,000,000 samples
/// over the 48×48 image.
const GGX_Z_TEST_SPP: u32 = 868;

/// The Mitsuba test scenes of `dir` (`tests/scenes`): every `<group>/test_*.xml`, sorted.
fn mitsuba_test_scenes(dir: &Path) -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("the scene groups")
        .flat_map(|group| std::fs::read_dir(group.expect("a group").path()).expect("a group"))
        .map(|e| e.expect("an entry").path())
        .filter(|p| {
            let name = p.file_name().unwrap_or_default().to_string_lossy();
            name.starts_with("test_") && name.ends_with(".xml")
        })
        .collect();
    scenes.sort();
    scenes
}

/// Every scene of Mitsuba 3's render tests rendered by our path tracer at 256 samples a
/// pixel, against Mitsuba's reference image, by two rules:
/// - relMSE: a scene passes when its relMSE is at most 1.5× the relMSE Mitsuba's own
///   estimator has at 256 samples (its per-sample variance, which the suite ships, over 256)
///   plus 2e-4, and its mean is within 2% of the reference's (`RelMse`);
/// - Mitsuba's z-test with both images' noise, on a render of `Z_TEST_SPP` samples with
///   independent numbers (`z_test`).
///
/// The table of every scene is printed; the scenes of `MITSUBA_TESTS_PASSING` must pass the
/// relMSE rule, those of `MITSUBA_Z_TESTS_NOT_YET` the z-test too. A scene that holds what
/// trilux does not read must be refused with its file and line. Both Accels must give the
/// same image of every scene.
fn mitsuba_render_tests_against_mitsubas_references(dir: &Path) {
    use trilux::accel::{self, AccelOptions};
    use trilux::engines::{path, RenderSettings};

    let scenes = mitsuba_test_scenes(dir);
    assert!(
        scenes.len() >= 23,
        "{} scenes in {}",
        scenes.len(),
        dir.display()
    );
    let mut passed = Vec::new();
    let mut z_passed = Vec::new();
    let mut differ = Vec::new();
    for file in &scenes {
        let name = file
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let scene = match Scene::load(file) {
            Ok(scene) => scene,
            Err(e) => {
                let message = e.to_string();
                assert!(
                    message.contains(&format!("{}:", file.display())) && e.line().is_some(),
                    "{name}: refused without its file and line: {message}"
                );
                println!("{name:48} refused: {message}");
                continue;
            }
        };
        let (width, height) = scene.render_hints.size.expect("a film");
        let settings = |spp| RenderSettings {
            width,
            height,
            num_antialias_samples: spp,
            max_depth: scene.render_hints.max_depth,
            quiet: true,
            ..RenderSettings::default()
        };
        let mut images = Vec::new();
        for kind in common::backends() {
            let accel = accel::build(&scene, kind, &AccelOptions::default()).expect("builds");
            images.push(path::render(&scene, accel.as_ref(), &settings(8)).0.pixels);
        }
        let largest_difference = images
            .windows(2)
            .flat_map(|w| {
                w[0].iter()
                    .zip(&w[1])
                    .map(|(a, b)| (*a - *b).abs().max_element())
            })
            .fold(0.0f32, f32::max);
        if largest_difference > 0.0 {
            println!("{name:48} the Accels differ by up to {largest_difference:e}");
            differ.push(name.clone());
        }
        let accel =
            accel::build(&scene, common::backends()[0], &AccelOptions::default()).expect("builds");
        let (film, _) = path::render(&scene, accel.as_ref(), &settings(MITSUBA_TEST_SPP));
        let (reference, reference_variance) = mitsuba_reference(file);
        let relmse = RelMse::of(&film, &reference, &reference_variance);
        let (image, variance) = path_traced_with_variance(&scene, Z_TEST_SPP, 0);
        let z = z_test(
            &Estimate {
                image: &image,
                variance: &variance,
                spp: Z_TEST_SPP as f64,
            },
            &Estimate {
                image: &reference,
                variance: &reference_variance,
                spp: MITSUBA_REFERENCE_SPP,
            },
        );
        println!("{name:48} {relmse}; {z}");
        if relmse.passes() {
            passed.push(name.clone());
        }
        if z.passes() {
            z_passed.push(name);
        }
    }
    println!(
        "{} of {} scenes pass the relMSE rule, {} the z-test at {Z_TEST_SPP} spp: {z_passed:?}",
        passed.len(),
        scenes.len(),
        z_passed.len()
    );
    assert!(
        differ.is_empty(),
        "the Accels give different images of {differ:?}"
    );
    for name in MITSUBA_TESTS_PASSING {
        assert!(passed.iter().any(|p| p == name), "{name} no longer passes");
    }
    for name in MITSUBA_TESTS_PASSING
        .iter()
        .filter(|name| !MITSUBA_Z_TESTS_NOT_YET.contains(name))
    {
        assert!(
            z_passed.iter().any(|p| p == name),
            "{name} no longer passes the z-test"
        );
    }
}

/// The GGX conductor of Mitsuba's test scene and a copy whose roughness (αu and αv) is 5%
/// larger, rendered by our path tracer at `GGX_Z_TEST_SPP`: against Mitsuba's reference the
/// z-test must pass the scene as shipped and fail the rougher copy; two renders of the scene
/// as shipped (two seeds) must be alike, and the copy unlike the scene. The relMSE rule's
/// verdicts (at its 256 samples) are printed: it passes both.
fn mitsuba_z_test_fails_on_a_ggx_roughness_off_by_5_percent(file: &Path) {
    use trilux::accel::{self, AccelOptions};
    use trilux::engines::{path, RenderSettings};

    // The normal distribution's tail against its values to 15 digits (Python's math.erfc).
    for (x, truth) in [
        (0.0, 1.0),
        (1.0, 0.157_299_207_050_285_13),
        (3.0, 2.209_049_699_858_543_8e-5),
        (4.5, 1.966_160_441_542_887_3e-10),
    ] {
        assert!(
            (erfc(x) / truth - 1.0).abs() < 2e-7,
            "erfc({x}) = {:e}, not {truth:e}",
            erfc(x)
        );
    }
    let (reference, reference_variance) = mitsuba_reference(file);
    let folder = file.parent().expect("a folder");
    // The copy lives in a temporary folder: its `<path>` names the suite's `common/` and the
    // scene's own folder (for `fragments/`) by absolute paths, where Mitsuba's resolver (and
    // ours) looks first.
    let common_dir = folder.join("../../../common");
    let text = std::fs::read_to_string(file).expect("the scene");
    let path_element = "<path value=\"../../../common\"/>";
    assert!(
        text.contains(path_element),
        "{}: no {path_element}",
        file.display()
    );
    let mut copy = text.replace(
        path_element,
        &format!(
            "<path value=\"{}\"/><path value=\"{}\"/>",
            common_dir.display(),
            folder.display()
        ),
    );
    for alpha in ["alpha_u", "alpha_v"] {
        let key = format!("name=\"{alpha}\" value=\"");
        let start = copy.find(&key).expect("a roughness") + key.len();
        let end = start + copy[start..].find('"').expect("a closing quote");
        let value: f64 = copy[start..end].parse().expect("a number");
        copy.replace_range(start..end, &format!("{}", value * 1.05));
    }
    let dir = common::temp_dir("ggx-roughness");
    let rougher = dir.join(file.file_name().expect("a name"));
    std::fs::write(&rougher, copy).expect("writes the copy");

    let shipped = Scene::load(file).expect("loads");
    let rougher_scene = Scene::load(&rougher).expect("loads the copy");
    std::fs::remove_dir_all(&dir).expect("removes the copy");
    let renders = [
        path_traced_with_variance(&shipped, GGX_Z_TEST_SPP, 0),
        path_traced_with_variance(&shipped, GGX_Z_TEST_SPP, 1),
        path_traced_with_variance(&rougher_scene, GGX_Z_TEST_SPP, 1),
    ];
    let estimate = |k: usize| Estimate {
        image: &renders[k].0,
        variance: &renders[k].1,
        spp: GGX_Z_TEST_SPP as f64,
    };
    let mitsuba = Estimate {
        image: &reference,
        variance: &reference_variance,
        spp: MITSUBA_REFERENCE_SPP,
    };
    let mut against_mitsuba = Vec::new();
    for (what, scene, k) in [
        ("as shipped", &shipped, 0),
        ("roughness ×1.05", &rougher_scene, 2),
    ] {
        let (width, height) = scene.render_hints.size.expect("a film");
        let accel =
            accel::build(scene, common::backends()[0], &AccelOptions::default()).expect("builds");
        let settings = RenderSettings {
            width,
            height,
            num_antialias_samples: MITSUBA_TEST_SPP,
            max_depth: scene.render_hints.max_depth,
            quiet: true,
            ..RenderSettings::default()
        };
        let (film, _) = path::render(scene, accel.as_ref(), &settings);
        let relmse = RelMse::of(&film, &reference, &reference_variance);
        let z = z_test(&estimate(k), &mitsuba);
        println!(
            "{what:16} against Mitsuba's reference: at {GGX_Z_TEST_SPP} spp {z}; at {MITSUBA_TEST_SPP} spp {relmse}"
        );
        against_mitsuba.push(z);
    }
    assert!(
        against_mitsuba[0].passes(),
        "the scene as shipped against Mitsuba's reference: {}",
        against_mitsuba[0]
    );
    assert!(
        !against_mitsuba[1].passes(),
        "a roughness 5% larger against Mitsuba's reference: {}",
        against_mitsuba[1]
    );
    let alike = z_test(&estimate(0), &estimate(1));
    let unlike = z_test(&estimate(0), &estimate(2));
    println!("as shipped, seeds 0 and 1: {alike}\nas shipped against roughness ×1.05: {unlike}");
    assert!(alike.passes(), "two seeds of one scene: {alike}");
    assert!(!unlike.passes(), "a roughness 5% larger: {unlike}");
}

/// Mitsuba's reference image of a test scene and the variance of one of its samples, from
/// the suite's `refs/` (`refs/<test>_ref_rgb.exr`, `…_ref_rgb_var.exr`).
fn mitsuba_reference(file: &Path) -> (Film, Film) {
    use trilux::film::metrics::read_image;
    let name = file.file_stem().unwrap_or_default().to_string_lossy();
    let stem = name.rsplit_once('_').map_or(&*name, |(t, _)| t);
    let refs = file.parent().expect("a folder").join("refs");
    let read = |suffix: &str| {
        read_image(&refs.join(format!("{stem}_ref_rgb{suffix}.exr"))).expect("a reference")
    };
    (read(""), read("_var"))
}

/// Our path tracer's image of a Mitsuba test scene at `spp` samples a pixel from `seed`, and the variance
/// of its samples (what `--variance` writes). Independent numbers (Mitsuba's sampler), so
/// that the samples' variance over their count is the variance of the pixel's mean; only the
/// camera's jittered pixel strata make it a little less, which errs towards passing.
fn path_traced_with_variance(scene: &Scene, spp: u32, seed: u64) -> (Film, Film) {
    use trilux::accel::{self, AccelOptions};
    use trilux::engines::{path, RenderSettings};
    use trilux::sampling::PathSampler;

    let (width, height) = scene.render_hints.size.expect("a film");
    let settings = RenderSettings {
        width,
        height,
        num_antialias_samples: spp,
        max_depth: scene.render_hints.max_depth,
        path_sampler: PathSampler::Independent,
        variance: true,
        seed,
        quiet: true,
        ..RenderSettings::default()
    };
    let accel =
        accel::build(scene, common::backends()[0], &AccelOptions::default()).expect("builds");
    let (film, _) = path::render(scene, accel.as_ref(), &settings);
    let variance = film
        .samples
        .as_ref()
        .expect("the render kept its sums")
        .variance(width, height);
    (film, variance)
}

/// The relMSE rule: our relMSE against the reference, Mitsuba's own at `MITSUBA_TEST_SPP`
/// (its per-sample variance over that count), and the ratio of the means.
struct RelMse {
    ours: f64,
    mitsuba: f64,
    mean_ratio: f64,
}

impl RelMse {
    fn of(film: &Film, reference: &Film, variance: &Film) -> RelMse {
        use trilux::film::metrics::{compare, RELMSE_EPSILON};
        let n = (reference.pixels.len() * 3) as f64;
        let mitsuba = reference
            .pixels
            .iter()
            .zip(&variance.pixels)
            .flat_map(|(r, v)| r.to_array().into_iter().zip(v.to_array()))
            .map(|(r, v)| {
                let r = r as f64;
                (v as f64).max(0.0) / MITSUBA_TEST_SPP as f64 / (r * r + RELMSE_EPSILON)
            })
            .sum::<f64>()
            / n;
        let mean = |f: &Film| f.pixels.iter().map(|p| p.element_sum() as f64).sum::<f64>() / n;
        RelMse {
            ours: compare(film, reference).expect("same size").relmse,
            mitsuba,
            mean_ratio: mean(film) / mean(reference),
        }
    }

    fn passes(&self) -> bool {
        self.ours <= 1.5 * self.mitsuba + 2e-4 && (self.mean_ratio - 1.0).abs() <= 0.02
    }
}

impl std::fmt::Display for RelMse {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "mean {:.3}× Mitsuba's, relMSE {:.2e} (Mitsuba's at {MITSUBA_TEST_SPP} spp: {:.2e}) {}",
            self.mean_ratio,
            self.ours,
            self.mitsuba,
            if self.passes() { "pass" } else { "FAIL" }
        )
    }
}

/// A z-test's result: the share of pixel channels whose p-value is above the Šidák-corrected
/// level, and the smallest p-value.
struct ZTest {
    share: f64,
    min_p: f64,
}

impl ZTest {
    fn passes(&self) -> bool {
        self.share >= Z_TEST_PASSING_SHARE
    }
}

impl std::fmt::Display for ZTest {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "z-test {:.2}% of pixel channels p > α (min p {:.1e}) {}",
            100.0 * self.share,
            self.min_p,
            if self.passes() { "pass" } else { "FAIL" }
        )
    }
}

/// An image, the variance of one of its samples per pixel and channel, and its samples per
/// pixel: what the z-test compares.
struct Estimate<'a> {
    image: &'a Film,
    variance: &'a Film,
    spp: f64,
}

/// Mitsuba's render test (`test_renders.py`) with both images' noise, per pixel and channel:
/// z = |a − b| / √(var_a / spp_a + var_b / spp_b), each variance that of one sample floored
/// at 1e-4 as Mitsuba floors its; p = erfc(z / √2) against α = 1 − 0.99^(1 / pixels) (Šidák:
/// 1% for the whole image); the images agree when 99.75% of the pixel channels have p > α.
/// Mitsuba's own test takes the reference's variance for its image's, in XYZ; the suite's
/// RGB variance file is that XYZ variance through the XYZ→RGB matrix (negative in places), so
/// against a reference it stands only for the reference's own noise (32000 samples), which is
/// 1/125 of ours at 256 samples.
fn z_test(a: &Estimate, b: &Estimate) -> ZTest {
    let alpha = 1.0 - (1.0 - Z_TEST_SIGNIFICANCE).powf(1.0 / a.image.pixels.len() as f64);
    let channels = |f: &Film| -> Vec<f64> {
        f.pixels
            .iter()
            .flat_map(|c| c.to_array())
            .map(f64::from)
            .collect()
    };
    let (xa, va) = (channels(a.image), channels(a.variance));
    let (xb, vb) = (channels(b.image), channels(b.variance));
    assert_eq!(xa.len(), xb.len(), "the images differ in size");
    let mut passing = 0usize;
    let mut min_p = 1.0f64;
    for k in 0..xa.len() {
        let sd = (va[k].max(Z_TEST_VARIANCE_FLOOR) / a.spp
            + vb[k].max(Z_TEST_VARIANCE_FLOOR) / b.spp)
            .sqrt();
        let p = erfc((xa[k] - xb[k]).abs() / sd / std::f64::consts::SQRT_2);
        min_p = min_p.min(p);
        passing += usize::from(p > alpha);
    }
    ZTest {
        share: passing as f64 / xa.len() as f64,
        min_p,
    }
}

/// erfc(x) for x ≥ 0 by Numerical Recipes' Chebyshev fit (relative error below 1.2e-7):
/// p-values near Šidák's α (4.4e-6 at 48×48) need no more.
fn erfc(x: f64) -> f64 {
    const C: [f64; 10] = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let t = 1.0 / (1.0 + 0.5 * x);
    let poly = C.iter().rev().fold(0.0, |acc, c| acc * t + c);
    t * (poly - x * x).exp()
}
