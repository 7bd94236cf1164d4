//! Split renders (`--crop-window`, `--pixel-samples`, `render merge`) and shared pre-passes
//! (`--save-radiosity` / `--load-radiosity`, `--pre-pass-only`), run as a user runs them: the
//! `render` program. The oracle is the single render of the same scene and flags: every
//! random number is a function of (seed, pixel, sample), so tiles must merge into its very
//! bytes and sample batches into its values up to f32 rounding of the sums. The same through
//! Slurm is in `farm_slurm.rs`.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use trilux::film::{read_pfm, Film};

fn render(dir: &Path, args: &[String]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_render"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("render runs")
}

/// Runs `render` and insists that it succeeds.
fn ok(dir: &Path, args: &[String]) -> Output {
    let out = render(dir, args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `render` and insists that it fails; its stderr.
fn fails(dir: &Path, args: &[String]) -> String {
    let out = render(dir, args);
    assert!(!out.status.success(), "{args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn words(line: &str) -> Vec<String> {
    line.split_whitespace().map(str::to_string).collect()
}

fn scene(name: &str) -> String {
    common::own_scene_dir()
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// The linear pixels of an EXR (the merge's output).
fn read_exr(path: &Path) -> Vec<[f32; 3]> {
    let image = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb32f();
    image.pixels().map(|p| [p[0], p[1], p[2]]).collect()
}

/// The largest relative difference between two images' values.
fn worst_relative(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    a.iter()
        .zip(b)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c], b[c])))
        .map(|(a, b)| (a - b).abs() / a.abs().max(1e-30))
        .fold(0.0f32, f32::max)
}

/// Tiles of uneven sizes (edges at ⌈48 × 0.3⌉ = 15 and ⌈48 × 0.6⌉ = 29) and sample batches
/// of uneven lengths.
const TILES: [&str; 4] = ["0 0.3 0 0.6", "0.3 1 0 0.6", "0 0.3 0.6 1", "0.3 1 0.6 1"];
const BATCHES: [&str; 4] = ["0 1", "1 3", "3 6", "6 8"];

/// For the ray tracer, the path tracer and the photon engine on two course scenes: four tiles
/// merged give the single render's bytes (PFM), four sample batches its values to 1e-6
/// relative in every pixel (EXR; measured: identical).
#[test]
fn tiles_and_sample_batches_merge_into_the_single_render() {
    let dir = common::temp_dir("farm-merge");
    let engines = [
        "--engine raytrace -num_shadow_samples 4 -num_bounces 2",
        "--engine path",
        "-num_photons_to_shoot 20000 -num_shadow_samples 4 -num_bounces 2",
    ];
    for scene_name in ["cornell_box_diffuse_sphere.obj", "reflective_spheres.obj"] {
        for flags in engines {
            let mut base = words(&format!(
                "-input {} -size 48 48 -num_antialias_samples 8 --quiet {flags}",
                scene(scene_name)
            ));
            base.push("--seed".into());
            base.push("7".into());
            let with =
                |extra: &str| -> Vec<String> { base.iter().cloned().chain(words(extra)).collect() };
            ok(&dir, &with("-o single.pfm"));
            ok(&dir, &with("-o single.exr"));
            let mut tiles = Vec::new();
            for (k, t) in TILES.iter().enumerate() {
                let part = format!("tile{k}.exr");
                ok(&dir, &with(&format!("--crop-window {t} -o {part}")));
                tiles.push(part);
            }
            let mut merge = vec!["merge".to_string()];
            merge.extend(tiles.iter().rev().cloned());
            merge.extend(words("-o tiles.pfm"));
            ok(&dir, &merge);
            let single = std::fs::read(dir.join("single.pfm")).expect("single");
            let merged = std::fs::read(dir.join("tiles.pfm")).expect("merged");
            assert!(
                single == merged,
                "{scene_name} {flags}: the merged tiles differ from the single render"
            );

            let mut batches = Vec::new();
            for (k, b) in BATCHES.iter().enumerate() {
                let part = format!("batch{k}.exr");
                ok(&dir, &with(&format!("--pixel-samples {b} -o {part}")));
                batches.push(part);
            }
            let mut merge = vec!["merge".to_string()];
            merge.extend(batches);
            merge.extend(words("-o batches.exr"));
            ok(&dir, &merge);
            let single = read_exr(&dir.join("single.exr"));
            let merged = read_exr(&dir.join("batches.exr"));
            let worst = worst_relative(&single, &merged);
            println!("{scene_name} {flags}: batches within {worst:.1e} of the single render");
            assert!(
                worst <= 1e-6,
                "{scene_name} {flags}: merged batches {worst:e} from the single render"
            );
        }
    }
}

/// More samples a pixel than one batch of camera rays holds (`CHUNK_SAMPLES`, 4096): the
/// render cuts inside a pixel, and the pieces must add up to exactly the pixel's samples,
/// none twice, none left out. Two sample batches cut elsewhere merge into its values.
#[test]
fn a_pixel_cut_into_batches_of_camera_rays_keeps_every_sample_once() {
    let dir = common::temp_dir("farm-chunks");
    let spp = trilux::render::CHUNK_SAMPLES + 904;
    let base = words(&format!(
        "-input {} --engine path -size 2 2 -num_antialias_samples {spp} --seed 3 --quiet",
        scene("cornell_box_diffuse_sphere.obj")
    ));
    let with = |extra: &str| -> Vec<String> { base.iter().cloned().chain(words(extra)).collect() };
    ok(&dir, &with("-o single.exr"));
    ok(&dir, &with("--pixel-samples 0 1000 -o a.exr"));
    ok(&dir, &with(&format!("--pixel-samples 1000 {spp} -o b.exr")));
    ok(&dir, &words("merge a.exr b.exr -o merged.exr"));
    let worst = worst_relative(
        &read_exr(&dir.join("single.exr")),
        &read_exr(&dir.join("merged.exr")),
    );
    assert!(
        worst <= 1e-6,
        "merged batches {worst:e} from the single render"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--variance` writes the variance of one sample in each pixel. Two checks it did not
/// produce itself: four sample batches merged with `render merge --variance` give the single
/// render's variance to f64 rounding of the sums (1e-4 relative: the sums are f32 per batch),
/// and the variance predicts how far apart two renders of other seeds are: with independent
/// samples, over the pixels, the mean of (a − b)² is 2 var / spp, within 15% at 32×32 pixels.
/// (The default sobol sampler's means vary less than that: 0.76 of it on this scene.)
#[test]
fn the_variance_predicts_the_spread_between_seeds_and_survives_the_merge() {
    let dir = common::temp_dir("farm-variance");
    let spp = 8;
    let base = words(&format!(
        "-input {} --engine path --sampler independent -size 32 32 -num_antialias_samples {spp} --quiet",
        scene("cornell_box_diffuse_sphere.obj")
    ));
    let with = |extra: &str| -> Vec<String> { base.iter().cloned().chain(words(extra)).collect() };
    ok(&dir, &with("--seed 1 -o a.pfm --variance a-var.pfm"));
    ok(&dir, &with("--seed 2 -o b.pfm"));
    let pixels = |name: &str| read_pfm(&dir.join(name)).expect("a PFM").pixels;
    let (a, b, variance) = (pixels("a.pfm"), pixels("b.pfm"), pixels("a-var.pfm"));
    let mut spread = 0.0f64;
    let mut predicted = 0.0f64;
    for ((a, b), v) in a.iter().zip(&b).zip(&variance) {
        for c in 0..3 {
            spread += ((a[c] - b[c]) as f64).powi(2);
            predicted += 2.0 * v[c] as f64 / spp as f64;
        }
    }
    let ratio = spread / predicted;
    println!("mean (a − b)² / (2 var / spp) = {ratio:.3}");
    assert!(
        (ratio - 1.0).abs() <= 0.15,
        "two seeds are {ratio:.3}× as far apart as the variance says"
    );

    let mut merge = vec!["merge".to_string()];
    for (k, batch) in ["0 1", "1 3", "3 6", "6 8"].iter().enumerate() {
        let part = format!("batch{k}.exr");
        ok(
            &dir,
            &with(&format!("--seed 1 --pixel-samples {batch} -o {part}")),
        );
        merge.push(part);
    }
    merge.extend(words("-o merged.exr --variance merged-var.pfm"));
    ok(&dir, &merge);
    let merged = pixels("merged-var.pfm");
    let worst = variance
        .iter()
        .zip(&merged)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / a[c].abs().max(1e-6)))
        .fold(0.0f32, f32::max);
    assert!(
        worst <= 1e-4,
        "the merged variance is {worst:e} from the single render's"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The merge refuses parts of another seed or scene, a set with a tile missing (naming the
/// pixels and samples) or with parts overlapping, a part whose render was interrupted, and an
/// EXR that is not a part.
#[test]
fn merge_refuses_parts_that_do_not_make_one_render() {
    let dir = common::temp_dir("farm-refuse");
    let part = |name: &str, scene_name: &str, extra: &str| {
        ok(
            &dir,
            &words(&format!(
                "-input {} -size 32 32 -num_antialias_samples 4 --quiet {extra} -o {name}",
                scene(scene_name)
            )),
        );
        name.to_string()
    };
    let left = part("left.exr", "cornell_box.obj", "--crop-window 0 0.5 0 1");
    let right = part("right.exr", "cornell_box.obj", "--crop-window 0.5 1 0 1");
    let other_seed = part(
        "seed.exr",
        "cornell_box.obj",
        "--crop-window 0.5 1 0 1 --seed 9",
    );
    let other_scene = part("scene.exr", "l.obj", "--crop-window 0.5 1 0 1");
    let merge = |parts: &[&str]| {
        let mut args = vec!["merge".to_string()];
        args.extend(parts.iter().map(|p| p.to_string()));
        args.extend(words("-o merged.png"));
        fails(&dir, &args)
    };
    for other in [&other_seed, &other_scene] {
        let e = merge(&[&left, other]);
        assert!(
            e.contains("fingerprint differs") && e.contains(other.as_str()),
            "{e}"
        );
    }
    let e = merge(&[&left]);
    assert!(
        e.contains("missing samples 0..4 of 512 pixels within columns 16..32, rows 0..32"),
        "{e}"
    );
    let e = merge(&[&left, &right, &left]);
    assert!(e.contains("in another part too"), "{e}");
    ok(
        &dir,
        &words(&format!(
            "-input {} -size 8 8 --quiet -o plain.exr",
            scene("l.obj")
        )),
    );
    let e = merge(&[&left, "plain.exr"]);
    assert!(e.contains("not a part of a split render"), "{e}");

    // A part Ctrl-C cut short is written (a valid, partial image) but marked incomplete.
    let slow = words(&format!(
        "-input {} --engine path -size 64 64 -num_antialias_samples 4000 --crop-window 0.5 1 0 1 --quiet -o cut.exr",
        scene("cornell_box.obj")
    ));
    let slow: Vec<&str> = slow.iter().map(String::as_str).collect();
    let (status, stderr, _) = common::interrupted(&dir, &slow, &[1500]);
    assert!(!status.success(), "{stderr}");
    assert!(stderr.contains("marked incomplete"), "{stderr}");
    let e = merge(&["cut.exr"]);
    assert!(e.contains("was interrupted"), "{e}");
}

/// A crop written to PNG or PFM is the window's pixels alone (as pbrt writes a cropped image),
/// the same as those pixels of the whole render.
#[test]
fn a_crop_written_as_pfm_is_the_windows_pixels() {
    let dir = common::temp_dir("farm-crop");
    let base = format!(
        "-input {} -size 40 30 -num_shadow_samples 2 --quiet",
        scene("cornell_box_diffuse_sphere.obj")
    );
    ok(&dir, &words(&format!("{base} -o whole.pfm")));
    ok(
        &dir,
        &words(&format!(
            "{base} --crop-window 0.25 0.75 0.1 0.5 -o crop.pfm"
        )),
    );
    let whole = read_pfm(&dir.join("whole.pfm")).expect("whole");
    let crop: Film = read_pfm(&dir.join("crop.pfm")).expect("crop");
    // Columns ⌈10⌉..⌈30⌉ = 10..30, rows ⌈3⌉..⌈15⌉ = 3..15.
    assert_eq!((crop.width, crop.height), (20, 12));
    for row in 0..12 {
        for x in 0..20 {
            assert_eq!(crop.get(x, row), whole.get(x + 10, row + 3), "({x}, {row})");
        }
    }
}

/// `--save-radiosity` then `--load-radiosity` gives the same image for both solvers and after
/// adaptive subdivision (whose splits the file keeps); a file made with another seed, or cut
/// short, is refused; `--pre-pass-only` saves without rendering, and is refused where there
/// is nothing to save.
#[test]
fn a_saved_radiosity_solution_renders_the_same_image() {
    let dir = common::temp_dir("farm-radiosity");
    let cases = [
        "--engine radiosity --subdivide 2 -num_shadow_samples 1 -interpolate",
        "--engine radiosity --radiosity-solver hierarchical -num_shadow_samples 1",
        "--engine radiosity -num_shadow_samples 1 --adaptive-subdivide 0.05",
        "--indirect radiosity --subdivide 1 -num_shadow_samples 4",
    ];
    for (k, flags) in cases.iter().enumerate() {
        let base = format!(
            "-input {} -size 32 32 --quiet {flags}",
            scene("cornell_box_diffuse_sphere.obj")
        );
        let file = format!("solution{k}.bin");
        ok(
            &dir,
            &words(&format!("{base} --save-radiosity {file} -o solved.pfm")),
        );
        let out = render(
            &dir,
            &words(&format!(
                "-input {} -size 32 32 {flags} --load-radiosity {file} -o loaded.pfm",
                scene("cornell_box_diffuse_sphere.obj")
            )),
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            String::from_utf8_lossy(&out.stderr).contains("loaded from"),
            "{flags}: the summary says where the solution came from"
        );
        let solved = std::fs::read(dir.join("solved.pfm")).expect("solved");
        let loaded = std::fs::read(dir.join("loaded.pfm")).expect("loaded");
        assert!(
            solved == loaded,
            "{flags}: the loaded solution renders differently"
        );

        let e = fails(
            &dir,
            &words(&format!("{base} --seed 3 --load-radiosity {file} -o x.pfm")),
        );
        assert!(e.contains("another scene or other settings"), "{e}");
    }
    // A Mitsuba scene lit by a point light: its mesh split where the light falls unevenly,
    // which the file keeps as rounds of splits (not `--adaptive-subdivide`'s), for both
    // solvers.
    std::fs::write(
        dir.join("point.xml"),
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0,6,-6" target="0,0,0" up="0,1,0"/></transform>
    </sensor>
    <emitter type="point"><point name="position" x="-1" y="2" z="0"/><rgb name="intensity" value="10"/></emitter>
    <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate y="0.5"/></transform></shape>
</scene>"#,
    )
    .expect("scene written");
    for solver in ["hierarchical", "progressive"] {
        let base =
            format!("-input point.xml -size 32 32 --engine radiosity --radiosity-solver {solver}");
        let saved = ok(
            &dir,
            &words(&format!("{base} --save-radiosity point.bin -o a.pfm")),
        );
        let loaded = ok(
            &dir,
            &words(&format!("{base} --load-radiosity point.bin -o b.pfm")),
        );
        let [saved, loaded] =
            [saved, loaded].map(|o| String::from_utf8_lossy(&o.stderr).into_owned());
        assert!(loaded.contains("loaded from"), "{loaded}");
        assert!(
            !saved.contains("adaptive") && !loaded.contains("adaptive"),
            "{saved}{loaded}"
        );
        assert_eq!(
            std::fs::read(dir.join("a.pfm")).expect("a"),
            std::fs::read(dir.join("b.pfm")).expect("b"),
            "{solver}: the loaded solution renders differently"
        );
    }
    // A level chosen from `--time-limit` is the file's: loading rebuilds that mesh (the
    // images differ by the samples each run had time for).
    let base = format!(
        "-input {} -size 32 32 --engine radiosity --time-limit 1",
        scene("cornell_box_diffuse_sphere.obj")
    );
    let patches = |stderr: &str| -> String {
        let line = stderr
            .lines()
            .find(|l| l.starts_with("radiosity: "))
            .unwrap_or_else(|| panic!("no summary: {stderr}"));
        line.split(" patches").next().unwrap().to_string()
    };
    let out = render(
        &dir,
        &words(&format!("{base} --save-radiosity timed.bin -o timed.pfm")),
    );
    let saved = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{saved}");
    assert!(saved.contains("as far as the time allowed"), "{saved}");
    let out = render(
        &dir,
        &words(&format!("{base} --load-radiosity timed.bin -o timed.pfm")),
    );
    let loaded = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{loaded}");
    assert!(loaded.contains("loaded from"), "{loaded}");
    assert_eq!(patches(&saved), patches(&loaded));
    // 54 patches unsubdivided: the level-0 solve takes milliseconds, so 1 s goes finer.
    assert_ne!(patches(&saved), "radiosity: 54", "{saved}");

    let bytes = std::fs::read(dir.join("solution0.bin")).expect("file");
    std::fs::write(dir.join("cut.bin"), &bytes[..bytes.len() / 2]).expect("write");
    let base = format!(
        "-input {} -size 32 32 --quiet --engine radiosity --subdivide 2 -num_shadow_samples 1 -interpolate",
        scene("cornell_box_diffuse_sphere.obj")
    );
    let e = fails(&dir, &words(&format!("{base} --load-radiosity cut.bin")));
    assert!(e.contains("truncated"), "{e}");

    std::fs::remove_file(dir.join("pre.bin")).ok();
    let out = ok(
        &dir,
        &words(&format!(
            "{base} --pre-pass-only --save-radiosity pre.bin -o none.png"
        )),
    );
    assert!(dir.join("pre.bin").exists() && !dir.join("none.png").exists());
    assert!(out.stdout.is_empty());
    let e = fails(&dir, &words(&format!("{base} --pre-pass-only")));
    assert!(e.contains("give --save-radiosity FILE"), "{e}");
    let e = fails(
        &dir,
        &words(&format!(
            "-input {} --engine path --pre-pass-only",
            scene("cornell_box.obj")
        )),
    );
    assert!(e.contains("the path engine has no pre-pass"), "{e}");
}

/// `--pixel-samples` is refused, before any work, where the image is not a mean of samples;
/// bad windows and ranges name the flag.
#[test]
fn split_flags_are_checked_before_the_work() {
    let dir = common::temp_dir("farm-flags");
    let cornell = scene("cornell_box.obj");
    for (line, expected) in [
        (
            "--engine raycast --pixel-samples 0 1",
            "--pixel-samples: the raycast engine",
        ),
        (
            "--engine radiosity --wireframe --pixel-samples 0 1",
            "--pixel-samples: the radiosity engine",
        ),
        (
            "-num_antialias_samples 4 --pixel-samples 2 5",
            "expected A < B ≤ -num_antialias_samples (4)",
        ),
        ("--crop-window 0.5 0.4 0 1", "expected fractions X0 < X1"),
        ("--crop-window 0 1 0 1.5", "expected fractions X0 < X1"),
        (
            "-size 4 4 --crop-window 0.3 0.4 0 1",
            "holds no pixel of the 4×4 image",
        ),
    ] {
        let mut args = vec!["-input".to_string(), cornell.clone()];
        args.extend(words(line));
        let e = fails(&dir, &args);
        assert!(e.contains(expected), "{line}: {e}");
    }
}

/// `render farm` without `--submit` writes the scripts: a pre-pass where the engine has one,
/// the array with one line per part, the merge after it; its refusals name the flag.
#[test]
fn farm_writes_its_scripts() {
    let dir = common::temp_dir("farm-scripts");
    let cornell = scene("cornell_box_diffuse_sphere.obj");
    let farm_dir: PathBuf = dir.join("f");
    ok(
        &dir,
        &words(&format!(
            "farm {cornell} -num_photons_to_shoot 1000 --tiles 6 -o out.png --variance v.exr --dir {}",
            farm_dir.display()
        )),
    );
    let parts = std::fs::read_to_string(farm_dir.join("parts.sbatch")).expect("parts");
    let pre = std::fs::read_to_string(farm_dir.join("prepass.sbatch")).expect("prepass");
    let submit = std::fs::read_to_string(farm_dir.join("submit.sh")).expect("submit");
    let merge = std::fs::read_to_string(farm_dir.join("merge.sbatch")).expect("merge");
    assert!(parts.contains("#SBATCH --array=0-5"), "{parts}");
    // The variance is the merge's to write; a part refuses it.
    assert!(!parts.contains("--variance"), "{parts}");
    assert!(
        merge.contains(&format!("--variance '{}'", dir.join("v.exr").display())),
        "{merge}"
    );
    assert_eq!(parts.matches("--crop-window").count(), 6, "{parts}");
    assert!(parts.contains("--load-photons"), "{parts}");
    assert!(pre.contains("--pre-pass-only --save-photons"), "{pre}");
    assert!(
        submit.contains("--dependency=afterok:$prepass")
            && submit.contains("--dependency=afterok:$parts"),
        "{submit}"
    );
    for (line, expected) in [
        (
            "--tiles 4 --pixel-samples 0 1",
            "--pixel-samples: not with render farm",
        ),
        (
            "--tiles 4 --sample-batches 2",
            "give one of --tiles N and --sample-batches N",
        ),
        (
            "--sample-batches 3",
            "expected 1 to -num_antialias_samples (1) batches",
        ),
        ("--engine raycast --sample-batches 1", "use --tiles"),
        ("--tiles 4 --wait", "--wait: only with --submit"),
        (
            "--engine raycast --tiles 2 --variance v.exr",
            "--variance: the raycast engine's image",
        ),
        ("--tiles 2 --variance v.png", "v.png: expected .exr or .pfm"),
    ] {
        let mut args = vec!["farm".to_string(), cornell.clone()];
        args.extend(words(line));
        args.extend(words(&format!("--dir {}", dir.join("g").display())));
        let e = fails(&dir, &args);
        assert!(e.contains(expected), "{line}: {e}");
    }
}
