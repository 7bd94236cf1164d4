//! `render farm … --submit --wait` through a real Slurm cluster: the local single-node one of
//! `scripts/slurm-local.sh up`, which `.ci/run` starts (and stops) around the tests and points
//! `SLURM_CONF` at. The oracle is the single render of the same scene and flags, as in
//! `farm.rs`.
//!
//! Without a cluster (no `sinfo` answering) the trials are reported as ignored, by name, with
//! the reason; where one must be there (CI sets `TRILUX_REQUIRE_SLURM=1`) they fail instead.

mod common;

use std::path::Path;
use std::process::Command;

use libtest_mimic::{Arguments, Failed, Trial};

fn main() {
    let args = Arguments::from_args();
    let available = cluster();
    let trial = |name, body| slurm_trial(name, body, &available);
    let trials = vec![
        trial(
            "farm_tiles_through_slurm_equal_the_single_render",
            farm_tiles_equal_the_single_render,
        ),
        trial(
            "farm_sample_batches_with_a_photon_pre_pass",
            farm_sample_batches_with_a_photon_pre_pass,
        ),
        trial(
            "farm_with_indirect_radiosity_solves_once",
            farm_with_indirect_radiosity_solves_once,
        ),
        trial(
            "a_failed_task_stops_the_merge_and_is_named",
            a_failed_task_stops_the_merge_and_is_named,
        ),
    ];
    libtest_mimic::run(&args, trials).exit();
}

/// Whether a Slurm cluster answers (its node is up).
fn cluster() -> Result<(), String> {
    let out = Command::new("sinfo")
        .args(["-h", "-o", "%T"])
        .output()
        .map_err(|e| format!("sinfo: {e} (apt-get install slurm-wlm munge)"))?;
    let states = String::from_utf8_lossy(&out.stdout);
    if out.status.success()
        && states
            .lines()
            .any(|s| ["idle", "mixed", "allocated"].contains(&s.trim()))
    {
        Ok(())
    } else {
        Err(format!(
            "no Slurm node answers (start one: eval \"$(scripts/slurm-local.sh up)\"): {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// A trial that needs the cluster: ignored with the reason when there is none (failed
/// instead when `TRILUX_REQUIRE_SLURM` is set).
fn slurm_trial(name: &'static str, body: fn(&Path), available: &Result<(), String>) -> Trial {
    let available = available.clone();
    let required = std::env::var_os("TRILUX_REQUIRE_SLURM").is_some();
    if let (Err(why), false) = (&available, required) {
        eprintln!("{name}: skipped: {why}");
    }
    let ignored = available.is_err() && !required;
    Trial::test(name, move || {
        if let Err(why) = available {
            return Err(Failed::from(format!(
                "{why} (TRILUX_REQUIRE_SLURM is set, or the trial was run with --ignored)"
            )));
        }
        body(&common::temp_dir(name));
        Ok(())
    })
    .with_ignored_flag(ignored)
}

/// Runs `render` with the words of `line` in `dir`: its status and stderr.
fn render(dir: &Path, line: &str) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_render"))
        .args(line.split_whitespace())
        .current_dir(dir)
        .output()
        .expect("render runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(dir: &Path, line: &str) -> String {
    let (success, stderr) = render(dir, line);
    assert!(success, "{line}: {stderr}");
    stderr
}

fn scene(name: &str) -> String {
    common::own_scene_dir()
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn same_bytes(dir: &Path, a: &str, b: &str) -> bool {
    std::fs::read(dir.join(a)).expect(a) == std::fs::read(dir.join(b)).expect(b)
}

/// Ray tracer and path tracer, four tiles each through the cluster: the merged image is the
/// single render's bytes.
fn farm_tiles_equal_the_single_render(dir: &Path) {
    for (k, flags) in [
        "-num_shadow_samples 4 -num_bounces 2 -num_antialias_samples 4",
        "--engine path -num_antialias_samples 8",
    ]
    .iter()
    .enumerate()
    {
        let base = format!(
            "-input {} -size 64 64 {flags}",
            scene("cornell_box_reflective_sphere.obj")
        );
        ok(dir, &format!("{base} --quiet -o single{k}.pfm"));
        let farm = format!(
            "farm {} -size 64 64 {flags}",
            scene("cornell_box_reflective_sphere.obj")
        );
        let stderr = ok(
            dir,
            &format!("{farm} --tiles 4 -o farmed{k}.pfm --dir f{k} --submit --wait"),
        );
        assert!(stderr.contains("merged 4 parts"), "{stderr}");
        assert!(
            same_bytes(dir, &format!("single{k}.pfm"), &format!("farmed{k}.pfm")),
            "{flags}: the farmed image differs from the single render"
        );
    }
}

/// The photon engine in four sample batches: one pre-pass job traces the maps, every task
/// loads them; the merge is within 1e-6 of the single render (measured: the same bytes).
fn farm_sample_batches_with_a_photon_pre_pass(dir: &Path) {
    let flags =
        "-size 48 48 -num_photons_to_shoot 20000 -num_shadow_samples 4 -num_antialias_samples 8";
    let cornell = scene("cornell_box_diffuse_sphere.obj");
    ok(
        dir,
        &format!("-input {cornell} {flags} --quiet -o single.pfm"),
    );
    ok(
        dir,
        &format!("farm {cornell} {flags} --sample-batches 4 -o farmed.pfm --dir f --submit --wait"),
    );
    let single = trilux::film::read_pfm(&dir.join("single.pfm")).expect("single");
    let farmed = trilux::film::read_pfm(&dir.join("farmed.pfm")).expect("farmed");
    let worst = single
        .pixels
        .iter()
        .zip(&farmed.pixels)
        .map(|(a, b)| {
            ((*a - *b).abs() / a.abs().max(trilux::geometry::Vec3::splat(1e-30))).max_element()
        })
        .fold(0.0f32, f32::max);
    assert!(worst <= 1e-6, "batches {worst:e} from the single render");
    let tasks = (0..4)
        .map(|k| std::fs::read_to_string(dir.join(format!("f/logs/part-{k}.log"))).expect("log"))
        .filter(|log| log.contains("wrote"))
        .count();
    assert_eq!(tasks, 4, "every task wrote its part");
}

/// `--indirect radiosity`: the solution is solved once, by the pre-pass job (its log has the
/// solver's summary), and loaded by every task (their logs say so); the image equals the
/// single render's bytes.
fn farm_with_indirect_radiosity_solves_once(dir: &Path) {
    let flags = "-size 48 48 --indirect radiosity --subdivide 2 -num_shadow_samples 4 -num_antialias_samples 4";
    let cornell = scene("cornell_box_diffuse_sphere.obj");
    ok(
        dir,
        &format!("-input {cornell} {flags} --quiet -o single.pfm"),
    );
    ok(
        dir,
        &format!("farm {cornell} {flags} --tiles 4 -o farmed.pfm --dir f --submit --wait"),
    );
    assert!(same_bytes(dir, "single.pfm", "farmed.pfm"));
    let read = |name: &str| std::fs::read_to_string(dir.join("f").join(name)).expect(name);
    let (script, prepass) = (read("prepass.sbatch"), read("logs/prepass.log"));
    assert!(
        script.contains("--pre-pass-only --save-radiosity"),
        "{script}"
    );
    assert!(
        prepass.contains("radiosity:")
            && prepass.contains("progressive solver")
            && !prepass.contains("loaded from"),
        "the pre-pass solves: {prepass}"
    );
    for k in 0..4 {
        let log = read(&format!("logs/part-{k}.log"));
        assert!(
            log.contains("loaded from"),
            "task {k} loads the solution: {log}"
        );
    }
}

/// A task that fails (its part cannot be written: a folder stands in its way) keeps the
/// merge job from running, and `render farm --wait` exits non-zero naming the task and its
/// log; no merged image is written.
fn a_failed_task_stops_the_merge_and_is_named(dir: &Path) {
    let blocker = dir.join("f/parts/part-2.exr");
    std::fs::create_dir_all(&blocker).expect("mkdir");
    std::fs::write(blocker.join("keep"), b"").expect("write");
    let (success, stderr) = render(
        dir,
        &format!(
            "farm {} -size 32 32 --tiles 4 -o farmed.png --dir f --submit --wait",
            scene("cornell_box.obj")
        ),
    );
    assert!(!success, "{stderr}");
    assert!(
        stderr.contains("1 of 4 tasks failed, so the merge job did not run")
            && stderr.contains("task 2, tile 2 of 4")
            && stderr.contains("logs/part-2.log"),
        "{stderr}"
    );
    assert!(!dir.join("farmed.png").exists());
}
