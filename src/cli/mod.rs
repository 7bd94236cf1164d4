//! The `render` command line: the course's single-dash flags, the render command's flag
//! groups (`args`), the render command itself (`render`) and the other subcommands (`tools`).
//! `main.rs` parses and dispatches; everything it calls is here, in the library, so that a
//! viewer or a test runs the same code.

pub mod args;
pub mod farm;
pub mod render;
pub mod tools;

use std::path::PathBuf;

use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use crate::accel::AccelKind;
use crate::engines::EngineKind;
pub use args::RenderArgs;

/// The course program's flags, accepted with one dash and underscores (`-num_bounces 3`) as
/// well as in their `--kebab-case` form.
const COURSE_FLAGS: [&str; 15] = [
    "input",
    "output",
    "size",
    "num_bounces",
    "num_shadow_samples",
    "num_antialias_samples",
    "ambient_light",
    "num_form_factor_samples",
    "sphere_rasterization",
    "cylinder_ring_rasterization",
    "num_photons_to_shoot",
    "num_photons_to_collect",
    "gather_indirect",
    "interpolate",
    "two_sided",
];

/// Rewrites `-num_bounces` and `--num_bounces` to `--num-bounces` (and
/// `-gather_indirect=false` to `--gather-indirect=false`); everything else as it is.
pub(crate) fn normalize_args(args: impl Iterator<Item = String>) -> Vec<String> {
    args.map(|a| {
        let name = a.strip_prefix("--").or_else(|| a.strip_prefix('-'));
        let (name, value) = match name.map(|n| n.split_once('=')) {
            Some(Some((n, v))) => (Some(n), Some(v)),
            _ => (name, None),
        };
        match name {
            Some(n) if COURSE_FLAGS.contains(&n) => {
                let flag = format!("--{}", n.replace('_', "-"));
                value.map_or(flag.clone(), |v| format!("{flag}={v}"))
            }
            _ => a,
        }
    })
    .collect()
}

/// A flag as the user would type it, from its argument id: the course's flags with one dash
/// and underscores (`-num_bounces`), the others in kebab case (`--aperture`).
pub fn flag_name(id: &str) -> String {
    if COURSE_FLAGS.contains(&id) {
        format!("-{id}")
    } else {
        format!("--{}", id.replace('_', "-"))
    }
}

#[derive(Parser, Debug)]
#[command(
    name = "render",
    version,
    about = "trilux: ray tracing, radiosity and photon mapping on Embree or a built-in BVH"
)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Measures the Accel backends: Mrays/s of closest-hit and occlusion queries.
    BenchAccel(tools::BenchArgs),
    /// Compares an image with a reference: RMSE, relMSE (ε = 1e-2), MAPE, largest error.
    Compare {
        /// The image.
        image: PathBuf,
        /// The reference.
        reference: PathBuf,
        /// Also write a heat map of the per-pixel error.
        #[arg(long)]
        heatmap: Option<PathBuf>,
    },
    /// Splits a render into tiles or sample batches run as a Slurm job array (after a
    /// pre-pass job where the engine has one), then merged: writes the batch scripts into a
    /// folder; --submit submits them, --wait waits for them and reports which job failed.
    /// Usage: render farm SCENE [render flags] --tiles N | --sample-batches N [--partition P]
    /// [--time MIN] [--cpus-per-task N] [--dir DIR] [--submit [--wait]].
    Farm(farm::FarmArgs),
    /// The course's interactive viewer: the scene in a window, ray traced progressively on
    /// 'r', the camera moved with the mouse, 'o' writing the image and the offline command
    /// line that renders it, 'h' listing the keys.
    /// Usage: render view SCENE [render flags].
    View {
        /// The scene file, then render flags as for `render -input SCENE`.
        #[arg(
            required = true,
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "SCENE [RENDER FLAGS]"
        )]
        words: Vec<String>,
    },
    /// Merges the parts of a split render (EXR files written with --crop-window or
    /// --pixel-samples) into the whole image: tiles placed, sample batches added as sums and
    /// divided once. Refuses parts of different renders, interrupted parts, and sets that
    /// leave pixels or samples out.
    Merge {
        /// The parts, in any order.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// The merged image (.png, .jpg, .exr or .pfm).
        #[arg(short, long)]
        output: PathBuf,
        /// Also write the variance of each pixel's samples (of one sample, not of the mean),
        /// per colour channel, to this .exr or .pfm, from the parts' sums and squares, as
        /// `render --variance` writes it [default: none].
        #[arg(long, value_name = "FILE")]
        variance: Option<PathBuf>,
    },
    /// Each engine's error against run time on a scene, and Embree against the BVH: a CSV, a
    /// log-log plot (PNG) and a markdown summary.
    Report(tools::ReportArgs),
    /// Writes the manual page of `render` (roff, for `man -l`), generated from the same
    /// definitions as `render --help`, with a section per subcommand.
    Man {
        /// Where to write it (default: standard output).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Writes a height-field terrain of at least N triangles as standard OBJ.
    GenTerrain {
        /// Number of triangles (at least).
        triangles: usize,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Writes a room of about N quads (walls and boxes, one light) in the course dialect: a
    /// radiosity scene where visibility matters, for scaling runs.
    GenRoom {
        /// Number of quads (about).
        patches: usize,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Writes a procedural texture as PPM (P6).
    GenTexture {
        #[arg(value_enum)]
        kind: crate::generate::TextureKind,
        /// Side in pixels.
        #[arg(long, default_value_t = 256)]
        size: u32,
        #[arg(short, long)]
        output: PathBuf,
    },
}

impl Cli {
    /// Parses the process's arguments (the course's spellings accepted); clap prints its own
    /// errors and exits. Records which render flags were given, by group, from clap's value
    /// sources.
    pub fn parse_args() -> Cli {
        Cli::parse_from_iter(std::env::args())
    }

    /// As `parse_args`, from the given arguments (the first is the program's name).
    pub fn parse_from_iter(args: impl Iterator<Item = String>) -> Cli {
        let command = Cli::command();
        let matches = command.clone().get_matches_from(normalize_args(args));
        let mut cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
        for group in command.get_groups() {
            for id in group.get_args() {
                if matches.try_contains_id(id.as_str()).unwrap_or(false)
                    && matches.value_source(id.as_str()) == Some(ValueSource::CommandLine)
                {
                    cli.render
                        .given
                        .push((group.get_id().to_string(), id.to_string()));
                }
            }
        }
        // Each argument once, under its innermost group (clap also lists the flattened
        // groups' arguments under the enclosing ones).
        cli.render
            .given
            .retain(|(g, _)| g != "RenderArgs" && g != "Cli");
        cli
    }
}

/// The clap group of the render flag of id `id`: its innermost, as `Cli::parse_from_iter`
/// records flags given.
pub fn flag_group(id: &str) -> Option<String> {
    Cli::command()
        .get_groups()
        .filter(|g| g.get_id() != "RenderArgs" && g.get_id() != "Cli")
        .find(|g| g.get_args().any(|a| a == id))
        .map(|g| g.get_id().to_string())
}

/// Backends measured by default: every one this build has.
pub fn default_accels() -> Vec<AccelKind> {
    if cfg!(feature = "embree") {
        vec![AccelKind::Embree, AccelKind::Bvh]
    } else {
        vec![AccelKind::Bvh]
    }
}

/// Engines the report measures by default.
pub fn default_report_engines() -> Vec<EngineKind> {
    vec![
        EngineKind::Raytrace,
        EngineKind::Radiosity,
        EngineKind::Photon,
        EngineKind::Path,
    ]
}

/// Writes to standard output; a closed pipe (`render --plan | head`) is not an error.
pub fn emit(text: &str) -> Result<(), String> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(format!("cannot write to standard output: {e}"))
        }
        _ => Ok(()),
    }
}
