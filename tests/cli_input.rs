//! Bad input at the command line: each class of bad flag is refused with the flag's name and
//! what is allowed, bad output paths are refused before any work, an empty scene says so, and
//! the photon-map fingerprint covers everything that changes the maps. Uses the project's own
//! scenes only.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn scene(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// Runs `render` in `dir`; fails the test if it takes longer than `limit` (a check that
/// should come before the render would otherwise let it run).
fn render_within(dir: &Path, args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_render"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("render runs");
    let start = Instant::now();
    while child.try_wait().expect("waits").is_none() {
        if start.elapsed() > limit {
            child.kill().ok();
            panic!("render {args:?} still running after {limit:?}: the check did not come first");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

fn render(dir: &Path, args: &[&str]) -> Output {
    render_within(dir, args, Duration::from_secs(120))
}

/// `render -input scenes/cornell_box.obj FLAGS…` in `dir`, within `limit`.
fn cornell_box(dir: &Path, flags: &[&str], limit: Duration) -> Output {
    let input = scene("cornell_box.obj");
    let args: Vec<&str> = ["-input", input.as_str()]
        .into_iter()
        .chain(flags.iter().copied())
        .collect();
    render_within(dir, &args, limit)
}

/// Time enough for any of these renders of refused flags (they stop before the work).
const REFUSED: Duration = Duration::from_secs(120);

/// The command failed, and its message names `flag` and contains `expected`.
fn refused(out: &Output, flag: &str, expected: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "accepted; stderr: {err}");
    assert!(err.contains(flag), "message does not name {flag}: {err}");
    assert!(
        err.contains(expected),
        "message does not say {expected:?}: {err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// A render that would take minutes: a check that must come before the work shows by
/// returning at once.
const HEAVY: [&str; 5] = ["-size", "1024", "1024", "-num_antialias_samples", "4096"];
/// Far less than the heavy render would take (hours), far more than loading the scene.
const BEFORE_WORK: Duration = Duration::from_secs(20);

#[test]
fn non_finite_ambient_light_names_the_flag() {
    let dir = common::temp_dir("ambient");
    let out = cornell_box(&dir, &["-ambient_light", "nan", "nan", "nan"], REFUSED);
    refused(&out, "-ambient_light", "finite numbers ≥ 0");
    let out = cornell_box(&dir, &["-ambient_light", "0.1", "-1", "0.1"], REFUSED);
    refused(&out, "-ambient_light", "finite numbers ≥ 0");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn thread_count_out_of_range_names_the_flag_and_the_range() {
    let dir = common::temp_dir("threads");
    let out = cornell_box(&dir, &["--threads", "100000"], REFUSED);
    refused(&out, "--threads", "from 0 to 1024");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn zero_samples_per_pixel_names_the_flag() {
    let dir = common::temp_dir("spp");
    let out = cornell_box(&dir, &["-num_antialias_samples", "0"], REFUSED);
    refused(&out, "-num_antialias_samples", "from 1 to");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn negative_or_non_finite_lens_names_the_flag() {
    let dir = common::temp_dir("lens");
    let out = cornell_box(&dir, &["--aperture", "-0.5"], REFUSED);
    refused(&out, "--aperture", "finite number ≥ 0");
    let out = cornell_box(&dir, &["--focus-distance", "inf"], REFUSED);
    refused(&out, "--focus-distance", "finite number > 0");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn out_of_range_engine_numbers_name_the_flag() {
    let dir = common::temp_dir("engine-numbers");
    let cases: [(&[&str], &str); 7] = [
        (&["-size", "0", "10"], "-size"),
        (&["--link-error", "0"], "--link-error"),
        (&["--min-element-area", "-1"], "--min-element-area"),
        (&["--photon-max-radius", "-1"], "--photon-max-radius"),
        (&["--radiosity-tolerance", "nan"], "--radiosity-tolerance"),
        (
            &["-num_form_factor_samples", "0"],
            "-num_form_factor_samples",
        ),
        (&["--ray-tree", "300", "1"], "--ray-tree"),
    ];
    for (flags, name) in cases {
        refused(&cornell_box(&dir, flags, REFUSED), name, "");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_output_whose_folder_is_missing_is_refused_before_the_render() {
    let dir = common::temp_dir("no-folder");
    let flags: Vec<&str> = ["-o", "missing/out.png"].into_iter().chain(HEAVY).collect();
    let out = cornell_box(&dir, &flags, BEFORE_WORK);
    refused(&out, "missing/out.png", "does not exist");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_output_of_unknown_format_is_refused_before_the_render() {
    let dir = common::temp_dir("format");
    let flags: Vec<&str> = ["-o", "out.gif"].into_iter().chain(HEAVY).collect();
    let out = cornell_box(&dir, &flags, BEFORE_WORK);
    refused(
        &out,
        "out.gif",
        "unknown image format (use .png, .jpg, .exr or .pfm)",
    );
    assert!(!dir.join("out.gif").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_scene_without_geometry_is_an_error_that_says_so() {
    let dir = common::temp_dir("empty");
    let path = dir.join("empty.obj");
    std::fs::write(&path, "# nothing but a comment\n").unwrap();
    let out = render(&dir, &["-input", path.to_str().unwrap()]);
    refused(&out, "empty.obj", "the scene has no geometry");
    std::fs::remove_dir_all(&dir).ok();
}

/// A standard OBJ/MTL scene with a texture: a textured floor under a square light.
fn write_textured_scene(dir: &Path, albedo: &str, texel: u8) {
    std::fs::write(
        dir.join("floor.obj"),
        "mtllib floor.mtl\n\
         v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n\
         v -0.2 1 -0.2\nv 0.2 1 -0.2\nv 0.2 1 0.2\nv -0.2 1 0.2\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl floor\nf 1/1 4/4 3/3 2/2\n\
         usemtl light\nf 5 6 7 8\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("floor.mtl"),
        format!("newmtl floor\nKd {albedo}\nmap_Kd floor.ppm\nnewmtl light\nKd 0 0 0\nKe 5 5 5\n"),
    )
    .unwrap();
    let mut ppm = b"P6\n2 2\n255\n".to_vec();
    ppm.extend([texel; 12]);
    std::fs::write(dir.join("floor.ppm"), ppm).unwrap();
}

/// The maps of `--save-photons` are refused by `--load-photons` when anything that shaped
/// them changed, though the scene file itself did not: `--two-sided`, the `.mtl` file, the
/// texture. The same files and flags load.
#[test]
fn loading_photons_refuses_maps_made_with_another_mtl_texture_or_sidedness() {
    let dir = common::temp_dir("fingerprint");
    write_textured_scene(&dir, "0.5 0.5 0.5", 128);
    let base = [
        "-input",
        "floor.obj",
        "-num_photons_to_shoot",
        "2000",
        "-size",
        "8",
        "8",
        "--quiet",
    ];
    let with =
        |extra: &[&'static str]| -> Vec<&str> { base.iter().chain(extra).copied().collect() };
    let run = |args: Vec<&str>| render(&dir, &args);
    let saved = run(with(&["--save-photons", "maps.photons"]));
    assert!(
        saved.status.success(),
        "{}",
        String::from_utf8_lossy(&saved.stderr)
    );
    let loaded = run(with(&["--load-photons", "maps.photons"]));
    assert!(
        loaded.status.success(),
        "{}",
        String::from_utf8_lossy(&loaded.stderr)
    );

    let stale = |out: Output, what: &str| {
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{what}: stale maps accepted");
        assert!(
            err.contains("maps.photons") && err.contains("made for another scene"),
            "{what}: {err}"
        );
    };
    stale(
        run(with(&["--load-photons", "maps.photons", "--two-sided"])),
        "--two-sided",
    );
    write_textured_scene(&dir, "0.8 0.5 0.5", 128);
    stale(
        run(with(&["--load-photons", "maps.photons"])),
        "edited .mtl",
    );
    write_textured_scene(&dir, "0.5 0.5 0.5", 200);
    stale(
        run(with(&["--load-photons", "maps.photons"])),
        "edited texture",
    );
    write_textured_scene(&dir, "0.5 0.5 0.5", 128);
    let again = run(with(&["--load-photons", "maps.photons"]));
    assert!(
        again.status.success(),
        "restored files: {}",
        String::from_utf8_lossy(&again.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The camera flags: naming the scene's own camera gives its image byte for byte (the
/// oracle: the camera in the file); moving it changes the image; a camera that cannot be
/// made is refused naming the flag.
#[test]
fn camera_flags_override_the_scenes_camera() {
    let dir = common::temp_dir("camera");
    let input = scene("glass_sphere_caustic.obj");
    let base = ["-input", input.as_str(), "-size", "24", "24", "--quiet"];
    let run = |extra: &[&str], out: &str| {
        let args: Vec<&str> = base
            .iter()
            .chain(extra)
            .chain(&["-o", out])
            .copied()
            .collect();
        let o = render(&dir, &args);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        std::fs::read(dir.join(out)).unwrap()
    };
    let own = run(&[], "own.png");
    // The file's PerspectiveCamera: position 0 4.5 7, point of interest 0 0.6 0, up 0 1 0,
    // angle 0.7 rad.
    let fov = 0.7f32.to_degrees().to_string();
    let same = run(
        &[
            "--camera-position",
            "0",
            "4.5",
            "7",
            "--look-at",
            "0",
            "0.6",
            "0",
            "--up",
            "0",
            "1",
            "0",
            "--fov",
            &fov,
        ],
        "same.png",
    );
    assert_eq!(own, same, "the scene's own camera given as flags");
    let moved = run(&["--camera-position", "3", "4.5", "7"], "moved.png");
    assert_ne!(own, moved, "a moved camera sees another image");
    for (flags, name) in [
        (&["--fov", "0"][..], "--fov"),
        (&["--fov", "180"][..], "--fov"),
        (&["--up", "0", "0", "0"][..], "--up"),
        (
            &["--camera-position", "nan", "0", "0"][..],
            "--camera-position",
        ),
    ] {
        let args: Vec<&str> = base.iter().chain(flags).copied().collect();
        refused(&render(&dir, &args), name, "expected");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The command failed with status 1 within a second, naming each of `words`, with no panic
/// and no path of the machine that built the program in its message.
fn refused_at_once(args: &[&str], hide_display: bool, words: &[&str]) {
    let dir = common::temp_dir("last-bad-inputs");
    let mut command = Command::new(env!("CARGO_BIN_EXE_render"));
    command.args(args).current_dir(&dir);
    if hide_display {
        for v in ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"] {
            command.env_remove(v);
        }
    }
    let start = Instant::now();
    let out = command.output().expect("render runs");
    let took = start.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(took < Duration::from_secs(1), "{args:?} took {took:?}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(
        !err.contains(".cargo") && !err.contains("/registry/") && !err.contains(".rs:"),
        "{args:?}: a path of the build machine in: {err}"
    );
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` missing from: {err}");
    }
}

/// The last bad inputs that got through: each is refused up front, with status 1, within a
/// second. `--time-limit 1e30` panicked making its `Duration`, an OBJ vertex `nan` was
/// rendered, `gen-room 1000000000000` wrote without end, `view` without a display printed a
/// path inside the cargo registry, and an MGF sphere of radius 1e38 was "no geometry".
#[test]
fn last_bad_inputs_are_refused_at_once() {
    let dir = common::temp_dir("last-bad-inputs");
    let nan = dir.join("nan.obj");
    std::fs::write(&nan, "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("write");
    let sphere = dir.join("sphere.mgf");
    std::fs::write(
        &sphere,
        "v c =\n\tp 0 0 0\nm m =\n\tc\n\trd .5\nsph c 1e38\n",
    )
    .expect("write");
    let cornell = scene("cornell_box.obj");
    refused_at_once(
        &["-input", &cornell, "--time-limit", "1e30", "-o", "x.png"],
        false,
        &["--time-limit", "at most 1e9"],
    );
    refused_at_once(
        &["-input", &nan.to_string_lossy(), "-o", "x.png"],
        false,
        &["nan.obj:1:3:", "out of range"],
    );
    refused_at_once(
        &["gen-room", "1000000000000", "-o", "room.obj"],
        false,
        &["gen-room 1000000000000", "50000000"],
    );
    refused_at_once(&["view", &cornell], true, &["render view: no display"]);
    refused_at_once(
        &["-input", &sphere.to_string_lossy(), "-o", "x.png"],
        false,
        &["sphere.mgf:6:7:", "`1e38` is out of range"],
    );
}

use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 40,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Numeric flags at their types' extremes, and beyond: each is refused (status 1, or 2
    /// where the command-line parser refuses the text), or renders a 4×4 image to its end,
    /// or is still rendering when the test stops it — never a panic or an abort. The render
    /// runs under a 4 GiB address-space limit, so a runaway allocation aborts it and shows.
    #[test]
    fn numeric_flags_at_extremes_never_panic(
        flag in prop::sample::select(vec![
            "--time-limit", "--max-memory", "--size", "--radiosity-iterations",
            "--num-photons-to-shoot", "--sppm-photons", "--threads", "--num-antialias-samples",
            "--tiles",
        ]),
        value in prop_oneof![
            prop::sample::select(vec![
                "0", "1", "-1", "4294967295", "4294967296", "18446744073709551615",
                "18446744073709551616", "1e30", "-1e30", "1e-30", "nan", "inf", "-inf", "1e9",
            ]).prop_map(String::from),
            any::<u64>().prop_map(|v| v.to_string()),
        ],
    ) {
        let dir = common::temp_dir("extreme-flags");
        let cornell = scene("cornell_box.obj");
        let mut args: Vec<String> = vec!["timeout".into(), "-s".into(), "KILL".into(), "3".into(),
            "prlimit".into(), "--as=4294967296".into(), env!("CARGO_BIN_EXE_render").into()];
        let values: Vec<String> = match flag {
            "--size" => vec![value.clone(), "4".into()],
            _ => vec![value.clone()],
        };
        if flag == "--tiles" {
            args.extend(["farm".into(), cornell.clone(), "--size".into(), "4".into(), "4".into(),
                "--dir".into(), dir.join("farm").to_string_lossy().into_owned()]);
        } else {
            args.extend(["-input".into(), cornell.clone(), "-o".into(), "x.pfm".into(), "--quiet".into()]);
            if flag != "--size" {
                args.extend(["--size".into(), "4".into(), "4".into()]);
            }
        }
        args.push(flag.into());
        args.extend(values);
        let out = Command::new(&args[0]).args(&args[1..]).current_dir(&dir).output().expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        let code = out.status.code();
        prop_assert!(!err.contains("panicked"), "{flag} {value}: {err}");
        // Stopped by the test's KILL: `timeout` reports 137, or, as it signals its whole
        // process group, is killed by it too (no status, signal 9). An abort is signal 6.
        let killed = std::os::unix::process::ExitStatusExt::signal(&out.status) == Some(9);
        prop_assert!(
            matches!(code, Some(0 | 1 | 2 | 137)) || killed,
            "{flag} {value}: status {:?}: {err}",
            out.status
        );
        if code == Some(1) {
            prop_assert!(!err.contains(".cargo"), "{flag} {value}: {err}");
            // The flag is named (as `--size`, or in the course's style, `-size`,
            // `-num_antialias_samples`), or the memory it would take is refused by --max-memory.
            let course = format!("-{}", flag[2..].replace('-', "_"));
            prop_assert!(
                err.contains(&flag[1..]) || err.contains(&course) || err.contains("--max-memory"),
                "{flag} {value}: the flag is not named in: {err}"
            );
        }
    }
}
