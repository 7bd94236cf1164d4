//! `render farm SCENE [render flags] --tiles N | --sample-batches N …`: checks the render as
//! `render` would (flags, scene, plan), writes the farm's Slurm scripts (`crate::farm`), and
//! with `--submit` submits them, with `--wait` waits and reports which job failed.

use std::path::{Path, PathBuf};

use clap::Args;

use super::{normalize_args, Cli};
use crate::engines;
use crate::farm::{self, Farm, Split};
use crate::plan::Plan;
use crate::scene::Scene;

/// The farm's own flags; the scene and the render flags (`words`) may be mixed with them in
/// any order, as `render farm SCENE [render flags] --tiles 4 --submit`.
#[derive(Args, Clone, Debug, Default)]
pub struct FarmArgs {
    /// Split the image into a grid of N tiles (--crop-window per task).
    #[arg(long, value_name = "N")]
    pub tiles: Option<u32>,
    /// Split each pixel's samples into N batches (--pixel-samples per task).
    #[arg(long, value_name = "N")]
    pub sample_batches: Option<u32>,
    /// Slurm partition to submit to [default: the cluster's default].
    #[arg(long, value_name = "P")]
    pub partition: Option<String>,
    /// Time limit of each job, in minutes [default: the partition's].
    #[arg(long, value_name = "MIN")]
    pub time: Option<u32>,
    /// CPUs per job (each job renders with as many threads).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub cpus_per_task: u32,
    /// The farm's folder (scripts, parts, logs) [default: the scene's name with .farm, e.g. cornell_box.farm].
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// Submit the jobs with sbatch and print their ids.
    #[arg(long)]
    pub submit: bool,
    /// With --submit: wait until the jobs end, and report which failed.
    #[arg(long)]
    pub wait: bool,
    /// The scene file, then render flags as for `render -input SCENE` (the output -o is the
    /// merged image).
    #[arg(
        required = true,
        trailing_var_arg = true,
        allow_hyphen_values = true,
        value_name = "SCENE [RENDER FLAGS]"
    )]
    pub words: Vec<String>,
}

/// Flags of the render that the farm sets itself, per part or per job, with their value
/// counts: given by the user they are refused (the output is taken as the merged image).
const FARM_SETS: [(&str, &str); 6] = [
    ("--crop-window", "the farm gives each task its tile"),
    ("--pixel-samples", "the farm gives each task its samples"),
    (
        "--pre-pass-only",
        "the farm runs the pre-pass as a job of its own",
    ),
    (
        "--save-photons",
        "the farm saves the photon maps in its folder",
    ),
    (
        "--save-radiosity",
        "the farm saves the solution in its folder",
    ),
    ("--plan", "run `render --plan` for the plan"),
];

/// Render flags whose files every task would write over each other's.
const ONE_WRITER: [&str; 3] = ["--ray-tree", "--export-radiosity", "--log-convergence"];

/// The farm's own flags found among the words: (name, whether it takes a value).
const OWN: [(&str, bool); 8] = [
    ("--tiles", true),
    ("--sample-batches", true),
    ("--partition", true),
    ("--time", true),
    ("--cpus-per-task", true),
    ("--dir", true),
    ("--submit", false),
    ("--wait", false),
];

impl FarmArgs {
    /// Moves the farm's own flags out of `words` (where clap leaves those given after the
    /// scene) into their fields.
    fn take_own_flags(&mut self) -> Result<(), String> {
        let mut rest = Vec::new();
        let mut words = std::mem::take(&mut self.words).into_iter();
        while let Some(word) = words.next() {
            let (name, inline) = match word.split_once('=') {
                Some((n, v)) if n.starts_with("--") => (n.to_string(), Some(v.to_string())),
                _ => (word.clone(), None),
            };
            let Some(&(_, takes_value)) = OWN.iter().find(|(n, _)| *n == name) else {
                rest.push(word);
                continue;
            };
            let value = if takes_value {
                inline
                    .or_else(|| words.next())
                    .ok_or_else(|| format!("{name}: expected a value"))?
            } else {
                String::new()
            };
            let number = |v: &str| {
                v.parse::<u32>()
                    .map_err(|_| format!("{name} {v}: expected a whole number"))
            };
            match name.as_str() {
                "--tiles" => self.tiles = Some(number(&value)?),
                "--sample-batches" => self.sample_batches = Some(number(&value)?),
                "--partition" => self.partition = Some(value),
                "--time" => self.time = Some(number(&value)?),
                "--cpus-per-task" => self.cpus_per_task = number(&value)?,
                "--dir" => self.dir = Some(PathBuf::from(value)),
                "--submit" => self.submit = true,
                _ => self.wait = true,
            }
        }
        self.words = rest;
        Ok(())
    }
}

/// Removes a file flag (`NAME FILE` or `NAME=FILE`, under any of `names`) from the words:
/// its file, the last given.
fn take_file_flag(words: &mut Vec<String>, names: &[&str]) -> Option<PathBuf> {
    let mut file = None;
    let mut k = 0;
    while k < words.len() {
        let w = &words[k];
        if names.contains(&w.as_str()) && k + 1 < words.len() {
            file = Some(PathBuf::from(words.remove(k + 1)));
            words.remove(k);
        } else if let Some(v) = names
            .iter()
            .find_map(|n| w.strip_prefix(n).and_then(|v| v.strip_prefix('=')))
        {
            file = Some(PathBuf::from(v));
            words.remove(k);
        } else {
            k += 1;
        }
    }
    file
}

fn absolute(path: &Path) -> Result<PathBuf, String> {
    std::path::absolute(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// `render farm …`.
pub fn run(args: &FarmArgs) -> Result<(), String> {
    let mut args = args.clone();
    args.take_own_flags()?;
    let split = match (args.tiles, args.sample_batches) {
        (Some(n), None) => Split::Tiles(n),
        (None, Some(n)) => Split::SampleBatches(n),
        _ => return Err("render farm: give one of --tiles N and --sample-batches N".into()),
    };
    if args.wait && !args.submit {
        return Err("--wait: only with --submit".into());
    }
    if args.cpus_per_task == 0 {
        return Err("--cpus-per-task 0: expected at least 1".into());
    }
    let mut words = normalize_args(args.words.iter().cloned());
    let scene_arg = words.remove(0);
    let output = take_file_flag(&mut words, &["-o", "--output"]);
    // The variance is the merge's: each part keeps its sums and squares.
    let variance = take_file_flag(&mut words, &["--variance"])
        .map(|v| absolute(&v))
        .transpose()?;
    if let Some(path) = &variance {
        super::args::check_variance_output(path).map_err(|e| format!("--variance: {e}"))?;
    }
    for word in &words {
        let name = word.split('=').next().unwrap_or(word);
        if let Some((flag, why)) = FARM_SETS.iter().find(|(f, _)| *f == name) {
            return Err(format!("{flag}: not with render farm: {why}"));
        }
        if ONE_WRITER.contains(&name) {
            return Err(format!(
                "{name}: not with render farm (every task would write the same file); use a single render"
            ));
        }
    }
    // The render as `render` would take it: the flags checked, the scene read, the plan made.
    let cli = Cli::parse_from_iter(
        ["render".to_string(), "--input".into(), scene_arg.clone()]
            .into_iter()
            .chain(words.iter().cloned()),
    );
    let render = &cli.render;
    render.validate()?;
    let mut settings = render.settings();
    let scene_path = absolute(Path::new(&scene_arg))?;
    let mut scene = Scene::load(&scene_path).map_err(|e| e.to_string())?;
    let engine = render.engine();
    super::render::engine_defaults(render, &scene.render_hints, engine, &mut settings);
    scene.two_sided_quads = render.common.two_sided;
    if render.camera.overrides() {
        scene.camera = Some(render.camera(scene.camera())?);
    }
    scene.filter_textures_for(settings.width, settings.height);
    let engine_impl = engines::engine(engine);
    if matches!(split, Split::SampleBatches(_)) && !engine_impl.samples_pixels(&settings) {
        return Err(format!(
            "--sample-batches: the {engine} engine's image with these flags is not a mean of pixel samples; use --tiles"
        ));
    }
    if variance.is_some() && !engine_impl.samples_pixels(&settings) {
        return Err(format!(
            "--variance: the {engine} engine's image with these flags is not a mean of pixel samples, so it has no variance of samples"
        ));
    }
    let loads_pre_pass = settings.photon.load.is_some() || settings.radiosity.load.is_some();
    let pre_pass = engine_impl.pre_pass(&settings).filter(|_| !loads_pre_pass);
    let accel = render.accel_kind(&scene);
    let plan = Plan::new(&scene, engine, accel, &settings);
    let stem = scene_path
        .file_stem()
        .map_or("render".into(), |s| s.to_string_lossy().into_owned());
    let output = absolute(&output.unwrap_or_else(|| PathBuf::from(format!("{stem}.png"))))?;
    crate::film::ImageFormat::check_output(&output).map_err(|e| e.to_string())?;
    let dir = absolute(
        &args
            .dir
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("{stem}.farm"))),
    )?;
    let farm = Farm {
        parts: farm::parts(
            split,
            settings.width,
            settings.height,
            settings.num_antialias_samples.max(1),
        )?,
        dir,
        program: std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?,
        scene: scene_path,
        threads_given: render.given.iter().any(|(_, id)| id == "threads"),
        flags: words,
        output,
        variance,
        pre_pass,
        partition: args.partition.clone(),
        time_minutes: args.time,
        cpus_per_task: args.cpus_per_task,
        // The plan's estimate and room for the program itself.
        memory_mib: plan.memory.div_ceil(1 << 20) + 256,
        name: stem,
    };
    farm.write()?;
    let summary = format!(
        "farm: {} parts ({}){} in {}; submit with bash {}",
        farm.parts.len(),
        match split {
            Split::Tiles(_) => "tiles",
            Split::SampleBatches(_) => "sample batches",
        },
        match pre_pass {
            Some(p) => format!(" after a pre-pass ({})", p.name),
            None => String::new(),
        },
        farm.dir.display(),
        farm.dir.join("submit.sh").display()
    );
    eprintln!("{summary}");
    if !args.submit {
        return Ok(());
    }
    let ids = farm.submit()?;
    for (job, id) in &ids {
        println!("{job} {id}");
    }
    if !args.wait {
        return Ok(());
    }
    crate::interrupt::install();
    farm.wait(&ids)?;
    let done = farm.outcome()?;
    eprintln!("{done}");
    Ok(())
}
