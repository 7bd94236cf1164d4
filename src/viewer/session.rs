//! What `render view SCENE [render flags]` starts from: the flags read as `render` reads them,
//! the scene loaded and checked (every error before a window opens), and the offline command
//! line that reproduces what the viewer shows.

use std::path::{Path, PathBuf};

use super::worker::Job;
use crate::cli::{normalize_args, Cli, RenderArgs};
use crate::engines::{EngineKind, RenderSettings};
use crate::scene::{Camera, Projection, RenderHints, Scene};

/// Render flags that have no meaning in the viewer, and why.
const NOT_IN_VIEWER: [(&str, &str); 7] = [
    (
        "--output",
        "'o' writes the image on screen to <scene stem>.view.png",
    ),
    ("--crop-window", "the viewer renders the whole image"),
    (
        "--pixel-samples",
        "the viewer takes every sample of a pixel",
    ),
    ("--pre-pass-only", "use `render --pre-pass-only`"),
    ("--plan", "use `render --plan`"),
    (
        "--ray-tree",
        "'t' draws the ray tree of the pixel under the pointer",
    ),
    ("--farm", "use `render farm`"),
];

/// The flags the viewer writes into the offline command line in place of those given, with
/// the number of values each takes: the camera's and `--engine` always, the others when the
/// image on screen sets them (a radiosity view's shots and mode).
const REPLACED: [(&str, usize); 11] = [
    ("--two-sided", 0),
    ("--camera-position", 3),
    ("--look-at", 3),
    ("--up", 3),
    ("--fov", 1),
    ("--engine", 1),
    ("--radiosity-iterations", 1),
    ("--visualize", 1),
    ("--subdivide", 1),
    ("--interpolate", 0),
    ("--wireframe", 0),
];

/// The flags replaced in every offline command line.
const ALWAYS_REPLACED: [&str; 5] = [
    "--camera-position",
    "--look-at",
    "--up",
    "--fov",
    "--engine",
];

/// A viewer's starting point.
pub struct Session {
    /// The scene file as given.
    pub input: PathBuf,
    /// The render flags as given (course spellings normalized), without the scene.
    pub flags: Vec<String>,
    pub args: RenderArgs,
    pub settings: RenderSettings,
    /// The engine 'r' renders with (`--engine`, or the one the flags imply).
    pub engine: EngineKind,
    /// The camera as the viewer keeps it: the scene's (with the flags applied), its field of
    /// view held in degrees as `--fov` gives it, so that the printed command line makes the
    /// very same camera.
    pub camera: Camera,
    pub fov_degrees: Option<f32>,
    /// What the scene file chose of the settings, for the jobs of other engines than the
    /// session's (`engine_defaults`).
    hints: RenderHints,
}

impl Session {
    /// Reads `SCENE [render flags]`: the flags checked as `render` checks them, then the
    /// scene loaded and checked. Returns the session and the scene.
    pub fn start(words: &[String]) -> Result<(Session, Scene), String> {
        let mut words = normalize_args(words.iter().cloned());
        if words.is_empty() {
            return Err("render view: expected a scene file, then render flags".into());
        }
        let input = words.remove(0);
        if input.starts_with('-') {
            return Err(format!(
                "render view {input}: expected the scene file first, then render flags"
            ));
        }
        for word in &words {
            let name = word.split('=').next().unwrap_or(word);
            let name = if name == "-o" { "--output" } else { name };
            if let Some((flag, why)) = NOT_IN_VIEWER.iter().find(|(f, _)| *f == name) {
                return Err(format!("{flag}: not with render view: {why}"));
            }
        }
        let cli = Cli::parse_from_iter(
            ["render".to_string(), "--input".into(), input.clone()]
                .into_iter()
                .chain(words.iter().cloned()),
        );
        let args = cli.render;
        let mut settings = crate::cli::render::checked_settings(&args)?;
        // The window shows the progress; no bars on the terminal.
        settings.quiet = true;
        let engine = args.engine();
        let input = PathBuf::from(input);
        let mut scene = crate::cli::render::load_scene(&args, &input, engine)?;
        // What the scene file chooses, as `render` takes it, so that the offline command
        // renders what the window shows.
        crate::cli::render::apply_scene_hints(&args, &mut scene, &mut settings);
        // As `render` plans: refused above --max-memory, and the hierarchical solver bounded
        // by what the limit leaves.
        let plan = crate::plan::Plan::new(&scene, engine, args.accel_kind(&scene), &settings);
        settings.radiosity.memory_budget = crate::cli::render::check_memory(&plan, &args)?;
        let mut camera = scene.camera();
        let fov_degrees = match camera.projection {
            Projection::Perspective { angle } => {
                let degrees = angle.to_degrees();
                camera.projection = Projection::Perspective {
                    angle: degrees.to_radians(),
                };
                Some(degrees)
            }
            Projection::Orthographic { .. } => None,
        };
        let session = Session {
            input,
            flags: words,
            args,
            settings,
            engine,
            camera,
            fov_degrees,
            hints: scene.render_hints.clone(),
        };
        Ok((session, scene))
    }

    /// `settings`, made from the session's, as `engine` takes them: its own shadow rays and
    /// bounces where nothing chose them (`render::engine_defaults`), as the offline command
    /// of a job of that engine renders.
    pub fn engine_defaults(&self, engine: EngineKind, settings: &mut RenderSettings) {
        crate::cli::render::engine_defaults(&self.args, &self.hints, engine, settings);
    }

    /// `<scene stem>.<suffix>` in the current folder.
    pub fn beside_stem(&self, suffix: &str) -> PathBuf {
        let stem = self
            .input
            .file_stem()
            .map_or("render".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}.{suffix}"))
    }

    /// The `render` command line that renders, offline, the image of `job`, written to
    /// `output`: the session's flags without those the job sets, then the job's engine, its
    /// flags and its camera.
    pub fn offline_command(&self, job: &Job, output: &Path) -> String {
        let mut words = vec![
            "render".to_string(),
            "-input".into(),
            shell_word(&self.input.to_string_lossy()),
        ];
        let replaced: Vec<&str> = ALWAYS_REPLACED
            .iter()
            .chain(job.controls)
            .copied()
            .collect();
        words.extend(
            without(&self.flags, &replaced)
                .iter()
                .map(|w| shell_word(w)),
        );
        words.push(format!("--engine {}", job.engine));
        if job.two_sided {
            words.push("--two-sided".into());
        }
        words.extend(job.flags.iter().map(|w| shell_word(w)));
        let camera = &job.camera;
        let v = |v: crate::geometry::Vec3| format!("{} {} {}", v.x, v.y, v.z);
        words.push(format!("--camera-position {}", v(camera.position)));
        words.push(format!("--look-at {}", v(camera.point_of_interest)));
        words.push(format!("--up {}", v(camera.up)));
        if let Some(fov) = self.fov_degrees {
            words.push(format!("--fov {fov}"));
        }
        words.push(format!("-o {}", shell_word(&output.to_string_lossy())));
        words.join(" ")
    }
}

/// The flags without those named in `replaced` and their values (the viewer prints its
/// own).
fn without(flags: &[String], replaced: &[&str]) -> Vec<String> {
    let mut kept = Vec::new();
    let mut skip = 0;
    for word in flags {
        if skip > 0 {
            skip -= 1;
            continue;
        }
        let name = word.split('=').next().unwrap_or(word);
        if !replaced.contains(&name) {
            kept.push(word.clone());
        } else if name == word {
            skip = REPLACED.iter().find(|(f, _)| *f == name).map_or(0, |r| r.1);
        }
    }
    kept
}

/// A word as bash reads it: as it is when it holds no character bash treats specially,
/// single-quoted otherwise.
fn shell_word(word: &str) -> String {
    let plain = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./:,+=@%".contains(c));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn the_viewer_replaces_the_camera_flags_and_the_engine() {
        let given = words(
            "--num-bounces 2 --fov 30 --camera-position 1 2 3 --engine path --look-at=0,0,0 --seed 4 --interpolate --subdivide 2",
        );
        assert_eq!(
            without(&given, &ALWAYS_REPLACED),
            words("--num-bounces 2 --seed 4 --interpolate --subdivide 2")
        );
        assert_eq!(
            without(&given, &["--interpolate", "--subdivide"]),
            words("--num-bounces 2 --fov 30 --camera-position 1 2 3 --engine path --look-at=0,0,0 --seed 4")
        );
    }

    #[test]
    fn words_bash_would_split_are_quoted() {
        assert_eq!(shell_word("scenes/a.obj"), "scenes/a.obj");
        assert_eq!(shell_word("my scene.obj"), "'my scene.obj'");
        assert_eq!(shell_word("it's"), r"'it'\''s'");
        assert_eq!(shell_word("-0.5"), "-0.5");
    }
}
